#!/usr/bin/env python
"""Neural implicit benchmark: single-shape networks on a sphere, a torus and the mug, and one
network for eight vases, measured against the exact surfaces in one run.

Run from the repository root::

    python benchmarks/bench_neural.py               # everything with default settings (tens of minutes)
    python benchmarks/bench_neural.py --single      # sphere, torus, mug only
    python benchmarks/bench_neural.py --encodings   # sine vs Fourier features on the three shapes

Shapes: a sphere of radius 40 and a torus R = 40, r = 14 (the exact implicits, which are their own
signed distances), and the mug (``models/mug.py``, genus 1: 536 bicubic patches, trained on their
tessellation). Each is fitted with ``NeuralSDF.fit(shape)`` at default settings, then meshed with
``to_mesh()`` (128 grid cells across the training cube) and measured:

* training time (wall clock, including sampling and JIT compilation); parameters and bytes;
* query time per point: F at 100,000 random points in the bounds (after a warm-up call);
* Chamfer distance, ``(mean d(mesh -> exact) + mean d(exact -> mesh)) / 2`` over 20,000 area-uniform
  samples each way, as % of the exact shape's bounding-box diagonal. Distances to the exact
  surface: ``|F|`` of the exact SDF (sphere, torus), exact point-to-triangle distance to a
  tessellation at 1e-5 of the model size (mug; its own error is far below the figures);
  distances to the mesh: exact point-to-triangle (MeshDistance);
* normal consistency: mean ``|n_exact . n_mesh|`` at the exact samples (exact normal of the
  implicit or of the patch, normal of the nearest mesh triangle);
* volume error of the mesh (exact: closed forms; the mug: its Gauss-Legendre reference volume);
* genus of the mesh (expected 0, 1, 1).

Multi-shape: eight vases (heights 100-190 mm, walls 4 and 6 mm) in one ``NeuralSDFFamily``,
each against a single-shape network of its own (default settings); a vase and its single network
are meshed at the same edge (128 cells across the single network's cube, the family's default
for that shape). Interpolated shapes (codes at 1/4, 1/2, 3/4 between pairs) must mesh watertight
with the vases' genus 0. ``--cache DIR`` keeps the nine networks to measure again without
training. Targets (from the issue): Chamfer <= 0.5 % of the diagonal (sphere, torus), 1 % (mug),
genus kept, training under 3 minutes per shape; family shapes within 1.5 x their single-shape
Chamfer, in fewer bytes than eight single networks.

What held the family back (measured on the 2-core machine at load 10-17, shared):

* Samples, not capacity: a family step draws its 1024 points from all shapes, so at the former
  250 steps per shape each vase saw a quarter of the samples of its single network's 1000 steps.
  On four vases (h 100/190, w 4/6) at 500 steps per shape, codes at the weights' rate, the two
  short vases came out 5.2x and 4.9x their single Chamfer (0.254 and 0.230 % against 0.049 and
  0.047 %), final loss 0.019; at 1000 steps per shape with codes at 10x the rate the loss fell to
  0.0079. Default now: 1000 steps per shape, codes at 10 x the weights' learning rate (DeepSDF
  also trains codes faster); width 96, latent 16 kept (a 128-wide, latent-32 trial was stopped
  unfinished for CPU and is untested).
* Mesh resolution: the family's cube (190 mm tall vases) at 128 cells is 1.9 mm, under two cells
  across the 2.8 mm floor corner of a 4 mm wall; a single network of a 100 mm vase meshes at
  1.0 mm. The edge alone moved the single h190 w4 network's Chamfer from 0.055 % (1.0 mm) to
  0.068 % (1.9 mm), so family shapes now mesh by default at their own box's edge (equal edges in
  the table). It did not make the handles: the retrained family's two 100 mm vases are genus 0
  also at 1.9 mm; the genus 1 of the 250-step family was the undertrained network. The exact
  vases are genus 0.
* Not changed: sampling (near-surface noise 0.01 and 0.06 of the cube already straddles a 4 mm
  wall, 0.034 of the family's cube) and the eikonal weight; no measurement asked for them.

Result with the defaults (``--family``; family trained at load ~15, singles at 10-15)::

    | shape          | edge_mm | single_chamfer_% | family_chamfer_% | ratio | family_genus | family_volume_% |
    | vase h=100 w=4 |   0.977 |            0.049 |            0.054 |  1.10 |            0 |           0.002 |
    | vase h=100 w=6 |   0.977 |            0.047 |            0.048 |  1.02 |            0 |           0.128 |
    | vase h=130 w=4 |   1.270 |            0.057 |            0.041 |  0.73 |            0 |           0.026 |
    | vase h=130 w=6 |   1.270 |            0.049 |            0.035 |  0.72 |            0 |           0.085 |
    | vase h=160 w=4 |   1.563 |            0.059 |            0.036 |  0.60 |            0 |           0.707 |
    | vase h=160 w=6 |   1.563 |            0.051 |            0.032 |  0.62 |            0 |           0.350 |
    | vase h=190 w=4 |   1.855 |            0.068 |            0.038 |  0.56 |            0 |           1.960 |
    | vase h=190 w=6 |   1.855 |            0.054 |            0.030 |  0.56 |            0 |           0.080 |

    family: 8 shapes, 20,769 parameters, 83,076 bytes, trained in 646 s (81 s per shape);
    eight single networks: 276,512 bytes (3.3 x the family), trained in 915 s.
    Interpolants 0-7, 1-6, 2-5 at t = 1/4, 1/2, 3/4: all nine closed, genus 0.

Every single network is genus 0 too; the family's 96-wide layers make it more accurate than the
64-wide single networks on the taller vases.
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np

import splinekit as sk
import splinekit.implicit as si
from models import build_model
from splinekit.mesh.components import genus
from splinekit.neural import NeuralSDF, NeuralSDFFamily
from splinekit.pointcloud import MeshDistance, sample_mesh, sample_surface

SAMPLES = 20_000
VASE_REFERENCE = 3e-5
"""Relative tessellation tolerance of the vases' reference surfaces."""
VASES = [dict(height=h, wall=w) for h in (100.0, 130.0, 160.0, 190.0) for w in (4.0, 6.0)]


class Reference:
    """An exact surface to measure against: distances, area-uniform samples and their normals."""

    def __init__(self, name, shape, volume, genus, diagonal, distance, samples):
        self.name, self.shape, self.volume, self.genus, self.diagonal = name, shape, volume, genus, diagonal
        self.distance, self.samples = distance, samples


def implicit_reference(name, implicit, volume, g):
    lo, hi = implicit.bounds
    fine = implicit.to_mesh(float(np.max(hi - lo)) / 200)

    def samples(n, rng):
        p = implicit.closest_points(sample_mesh(fine, n, rng))
        return p, implicit.normal(p)

    return Reference(name, implicit, volume, g, float(np.linalg.norm(hi - lo)), lambda p: np.abs(implicit(p)), samples)


def patch_reference(name, model, g, tolerance=1e-5):
    patches = [p for body in model.bodies for p in body]
    tess = sk.tessellate(patches, tolerance, relative=True)
    md = MeshDistance.of_mesh(tess)
    V = np.asarray(tess.vertices)

    def samples(n, rng):
        p, patch, uv = sample_surface(patches, n, rng, return_parameters=True)
        normals = np.empty_like(p)
        for k in np.unique(patch):
            sel = patch == k
            d = patches[k].derivatives(uv[sel, 0], uv[sel, 1], 1)
            normals[sel] = np.cross(d[1, 0], d[0, 1])
        return p, normals / np.linalg.norm(normals, axis=1, keepdims=True)

    return Reference(name, model, model.checks["volume"][0], g, float(np.linalg.norm(V.max(0) - V.min(0))),
                     lambda p: md.query(p)[0], samples)


def measure_mesh(mesh, ref: Reference, seed=0):
    """Chamfer (% of diagonal), normal consistency, volume error (%), genus of ``mesh``."""
    rng = np.random.default_rng(seed)
    on_mesh = sample_mesh(mesh, SAMPLES, rng)
    exact, normals = ref.samples(SAMPLES, rng)
    d_out = ref.distance(on_mesh)
    d_in, _, tri = MeshDistance.of_mesh(mesh).query(exact)
    chamfer = 0.5 * (d_out.mean() + d_in.mean())
    consistency = float(np.abs(np.einsum("ij,ij->i", normals, np.asarray(mesh.face_normals)[tri])).mean())
    return {"chamfer_%": 100 * chamfer / ref.diagonal, "normals": consistency,
            "volume_%": 100 * abs(mesh.volume - ref.volume) / ref.volume, "genus": genus(mesh)}


def query_time(model, n=100_000):
    lo, hi = model.bounds
    p = np.random.default_rng(3).uniform(lo, hi, (n, 3))
    model(p)  # compile for this batch size first
    t0 = time.perf_counter()
    model(p)
    return (time.perf_counter() - t0) / n


def references(names=("sphere", "torus", "mug")):
    make = {"sphere": lambda: implicit_reference("sphere", si.sphere(radius=40.0), 4 / 3 * np.pi * 40.0**3, 0),
            "torus": lambda: implicit_reference("torus", si.torus(major=40.0, minor=14.0), 2 * np.pi**2 * 40.0 * 14.0**2, 1),
            "mug": lambda: patch_reference("mug", build_model("mug"), 1)}
    return [make[name]() for name in names]


def fit_and_measure(ref, **options):
    t0 = time.perf_counter()
    model = NeuralSDF.fit(ref.shape, **options)
    seconds = time.perf_counter() - t0
    row = {"shape": ref.name, "train_s": seconds, "params": model.parameter_count, "bytes": model.nbytes,
           "query_us": 1e6 * query_time(model)}
    row.update(measure_mesh(model.to_mesh(), ref))
    return row, model


def print_table(rows, columns):
    fmt = {"train_s": "{:.0f}", "query_us": "{:.2f}", "chamfer_%": "{:.3f}", "normals": "{:.4f}",
           "volume_%": "{:.2f}", "params": "{:,}", "bytes": "{:,}", "genus": "{:g}", "ratio": "{:.2f}"}
    text = [[fmt.get(c, "{}").format(r[c]) if r.get(c) is not None else "-" for c in columns] for r in rows]
    widths = [max(len(c), *(len(t[i]) for t in text)) for i, c in enumerate(columns)]
    print("| " + " | ".join(c.ljust(w) for c, w in zip(columns, widths)) + " |")
    print("|" + "|".join("-" * (w + 2) for w in widths) + "|")
    for t in text:
        print("| " + " | ".join(x.rjust(w) for x, w in zip(t, widths)) + " |")


SINGLE_COLUMNS = ["shape", "train_s", "params", "bytes", "query_us", "chamfer_%", "normals", "volume_%", "genus"]


def bench_single(refs):
    print("\n## Single shapes (NeuralSDF.fit with default settings)\n")
    rows = []
    for ref in refs:
        row, _ = fit_and_measure(ref)
        rows.append(row)
        print(f"  {ref.name}: {row['train_s']:.0f} s, Chamfer {row['chamfer_%']:.3f} % of diagonal, genus {row['genus']:g} "
              f"(exact {ref.genus}), load {os.getloadavg()[0]:.1f}", flush=True)
    print()
    print_table(rows, SINGLE_COLUMNS)
    return rows


def bench_encodings(refs, steps):
    print(f"\n## Encodings at equal size and steps ({steps} steps, 3 x 64)\n")
    rows = []
    for ref in refs:
        for encoding in ("sine", "fourier"):
            row, _ = fit_and_measure(ref, encoding=encoding, steps=steps)
            row["shape"] = f"{ref.name} {encoding}"
            rows.append(row)
            print(f"  {row['shape']}: Chamfer {row['chamfer_%']:.3f} %", flush=True)
    print()
    print_table(rows, SINGLE_COLUMNS)


def cached(cache, name, cls, fit):
    """``cls.load(cache/name)`` when it is there, else ``fit()`` (saved there when ``cache``);
    its training seconds are the model's own record (``info["seconds"]``)."""
    path = None if cache is None else os.path.join(cache, name)
    if path is not None and os.path.exists(path):
        model = cls.load(path)
        print(f"  {name}: loaded from the cache (trained in {model.info['seconds']:.0f} s)", flush=True)
        return model
    model = fit()
    if path is not None:
        os.makedirs(cache, exist_ok=True)
        model.save(path)
    return model


def bench_family(cache=None):
    print(f"\n## Eight vases in one network (NeuralSDFFamily) against eight single networks\n")
    models = [build_model("vase", **v) for v in VASES]
    family = cached(cache, "family-8-vases.nsdf", NeuralSDFFamily, lambda: NeuralSDFFamily.fit(models))
    family_s = family.info["seconds"]
    print(f"  family trained in {family_s:.0f} s, load {os.getloadavg()[0]:.1f}", flush=True)
    rows, single_bytes, single_s = [], 0, 0.0
    for i, v in enumerate(VASES):
        # one reference at a time, at 3e-5 of the size: eight at 1e-5 held ~10 GB
        ref = patch_reference(f"vase h={v['height']:g} w={v['wall']:g}", models[i], 0, VASE_REFERENCE)
        shape = family.shape(i)
        fam = measure_mesh(shape.to_mesh(), ref)  # default edge: the one its single network uses
        single = cached(cache, f"vase-h{v['height']:g}-w{v['wall']:g}.nsdf", NeuralSDF, lambda: NeuralSDF.fit(models[i]))
        s_seconds = single.info["seconds"]
        single_bytes += single.nbytes
        single_s += s_seconds
        one = measure_mesh(single.to_mesh(), ref)
        rows.append({"shape": ref.name, "edge_mm": shape.default_edge(), "single_chamfer_%": one["chamfer_%"],
                     "family_chamfer_%": fam["chamfer_%"], "ratio": fam["chamfer_%"] / one["chamfer_%"],
                     "single_genus": one["genus"], "family_genus": fam["genus"], "family_volume_%": fam["volume_%"]})
        print(f"  {ref.name}: single {one['chamfer_%']:.3f} % ({s_seconds:.0f} s), family {fam['chamfer_%']:.3f} %, "
              f"load {os.getloadavg()[0]:.1f}", flush=True)
    print()
    for r in rows:
        for c in ("single_chamfer_%", "family_chamfer_%", "family_volume_%", "edge_mm"):
            r[c] = f"{r[c]:.3f}"
    print_table(rows, ["shape", "edge_mm", "single_chamfer_%", "family_chamfer_%", "ratio", "single_genus",
                       "family_genus", "family_volume_%"])
    print(f"\nfamily: {len(family)} shapes, {family.parameter_count:,} parameters, {family.nbytes:,} bytes, "
          f"trained in {family_s:.0f} s; eight single networks: {single_bytes:,} bytes "
          f"({single_bytes / family.nbytes:.1f} x the family), trained in {single_s:.0f} s")
    for i, j in ((0, 7), (1, 6), (2, 5)):
        for t in (0.25, 0.5, 0.75):
            mesh = family.interpolate(i, j, t).to_mesh()
            print(f"interpolated {i}-{j} at t = {t}: {mesh.n_faces:,} triangles, closed {mesh.is_closed}, "
                  f"genus {genus(mesh):g}", flush=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--single", action="store_true", help="only the sphere, torus and mug")
    parser.add_argument("--family", action="store_true", help="only the eight vases")
    parser.add_argument("--encodings", action="store_true", help="sine vs Fourier features at equal steps")
    parser.add_argument("--steps", type=int, default=1000, help="steps of the --encodings comparison")
    parser.add_argument("--shapes", default="sphere,torus,mug", help="single shapes to run (comma-separated)")
    parser.add_argument("--quick", action="store_true", help="the sphere alone (no family)")
    parser.add_argument("--cache", default=None, help="directory to keep the family's and single vase networks in "
                        "(loaded from there when present: measure again without training again)")
    args = parser.parse_args()
    if args.quick:
        args.shapes, args.single = "sphere", True
    load0 = os.getloadavg()[0]
    t0 = time.perf_counter()
    import jax

    print(f"splinekit neural benchmark: jax {jax.__version__}, numpy {np.__version__}, Python {platform.python_version()}, "
          f"{platform.machine()}, {os.cpu_count()} CPUs")
    if args.encodings:
        bench_encodings(references(args.shapes.split(",")), args.steps)
    else:
        if not args.family:
            bench_single(references(args.shapes.split(",")))
        if not args.single:
            bench_family(args.cache)
    print(f"\nload average at start {load0:.2f}, at end {os.getloadavg()[0]:.2f} (other processes share the "
          f"{os.cpu_count()} CPUs and slow every timing); total {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
