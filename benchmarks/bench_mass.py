#!/usr/bin/env python
"""Mass-property benchmark: splinekit's adaptive integration against OCC's GProp and scipy's
adaptive cubature, in one run: time and achieved error against closed forms.

Run from the repository root::

    python benchmarks/bench_mass.py            # every case, several repeats (about a minute)
    python benchmarks/bench_mass.py --quick    # one repeat, no scipy

Cases (the same exact NURBS geometry for every integrator: splinekit's B-rep, and its OCC
conversion by ``splinekit.occ.to_shape``):

* sphere (radius 10): one trimmed face with two poles and a seam;
* torus (10, 3): one periodic face;
* box with hole: 20 mm cube minus a radius-4 through hole: planar faces trimmed by circles;
* teapot: Newell's 32 bicubic patches, area only (an open surface); eight patches have a
  collapsed edge. Reference 21153.3212370 mm^2 (scipy's dblquad on every patch at 1e-12).

Figures: volume and area together per call (GProp: one VolumeProperties_s and one
SurfaceProperties_s call), median wall time of the repeats, and the relative errors against the
closed forms. The ratio column is the integrator's time over splinekit's at tolerance 1e-10.

Two ratio lines per case: at the same requested tolerance (GProp 1e-10 over splinekit 1e-10),
and at equal achieved accuracy: GProp 1e-10 over splinekit at its loosest tolerance of the table
(1e-4 ... 1e-10) whose achieved error (the larger of area and volume) is at most GProp 1e-10's.

Profile (cProfile plus counts of passes, cells, inner intervals and evaluations, 2026-11-26)
before the rework, at 1e-10: the cost was numpy's per-call overhead more than arithmetic. Every
face was its own rule and every pass evaluated each face separately (the teapot: 137 face
evaluations of a few cells each, 81k integrand evaluations, 60 ms); the box's two holed planes
spent 40% of the time setting up Green's rule (sampling the trims, their total variation) and
most of the rest in the inner K15 integrals, whose integrand is a cubic polynomial on a plane;
the 7-15 estimate (the 7-point rule's error) made the sphere bisect to 46 cells in three passes
while the 15-point values were exact to 4e-16. Once the faces were batched, einsum's generic
loop on the second tensor contraction took 25 ms for 300 cells (a batched matmul: 4.5 ms), and
temporaries over 128 KiB were mapped afresh by glibc at every call (3300 page faults and 15.5 ms
CPU per evaluation of 192 teapot cells; 9.4 ms in chunks that stay under the threshold).

What changed: one tensor rule per degree group evaluates every face's Bézier-patch cells in
one batched product per pass, in chunks of 4000 nodes; the 10-21 pair below tol 1e-8 (the
sphere: 8 cells, one pass); planes take Green's inner integral with a 2-point Gauss rule, exact
for the cubic integrand; the trims are evaluated as one batch of Bézier segments; the trims'
and patches' set-up is cached on the immutable faces (the warm-up call fills it, as it fills
the surfaces' Bézier nets). The teapot still needs 79k evaluations at 1e-10: the 10-point
estimate on whole patches is 5e-6 relative (true error 4e-8) and halving a cell cuts it only
50x, so it refines honestly (the true error after two of its five passes is already 3e-11,
but no estimate tested, QUADPACK's scaled one included, knew it); what is left is about 0.07 us
of numpy per evaluation (integrand 40%, derivatives 25%, sums 20%).
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

import numpy as np

sys.path.insert(0, os.path.abspath(os.path.join(os.path.dirname(__file__), os.pardir)))

import splinekit as sk  # noqa: E402
from _ratios import report  # noqa: E402
from models import teapot  # noqa: E402
from splinekit.brep import Shell, TrimmedFace, primitives  # noqa: E402
from splinekit.brep.crosscheck import scipy_integrals  # noqa: E402
from splinekit.brep.mass import area_and_volume  # noqa: E402

PI = np.pi
TEAPOT_AREA = 21153.3212370


def cases():
    """``name -> (faces, exact volume or None, exact area)``."""
    sphere = primitives.sphere(10.0)
    torus = primitives.torus(10.0, 3.0)
    box = primitives.box_with_hole(20.0, 4.0)
    pot = [TrimmedFace(sk.BezierSurface(net)) for net in teapot.control_nets(20.0)]
    return {
        "sphere": (list(sphere.faces), 4 / 3 * PI * 1000, 4 * PI * 100),
        "torus": (list(torus.faces), 2 * PI**2 * 10 * 9, 4 * PI**2 * 30),
        "box with hole": (list(box.faces), 8000 - PI * 16 * 20, 2400 - 2 * PI * 16 + 2 * PI * 4 * 20),
        "teapot": (pot, None, TEAPOT_AREA),
    }


def timed(fn, repeats):
    fn()  # warm-up (imports, caches of the surfaces' Bézier data)
    times, out = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def occ_shape(faces, closed):
    if closed:
        return sk.occ.to_shape(sk.brep.Solid(Shell(faces)))
    return sk.occ.to_shape([f.surface for f in faces])


def occ_measure(shape, precision, closed):
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    sp = GProp_GProps()
    BRepGProp.SurfaceProperties_s(shape, sp, precision)
    volume = None
    if closed:
        vp = GProp_GProps()
        BRepGProp.VolumeProperties_s(shape, vp, precision)
        volume = vp.Mass()
    return sp.Mass(), volume


SPLINEKIT_TOLERANCES = (1e-4, 1e-6, 1e-8, 1e-10)


def achieved(row):
    """The larger of a table row's area and volume errors (the area's alone for an open shell)."""
    return max(e for e in row[4:6] if not np.isnan(e))


def rel(value, exact):
    return float("nan") if value is None or exact is None else abs(value - exact) / abs(exact)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="one repeat, no scipy")
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args(argv)
    repeats = 1 if args.quick else args.repeats
    rows = []
    for name, (faces, volume, area) in cases().items():
        closed = volume is not None
        results = []
        for tol in SPLINEKIT_TOLERANCES:
            t, (a, _, v, _) = timed(lambda: area_and_volume(Shell(faces), tol), repeats)
            results.append((f"splinekit tol {tol:g}", t, a, v if closed else None))
        shape = occ_shape(faces, closed)
        for precision in (1e-4, 1e-8, 1e-10, 1e-11):
            t, (a, v) = timed(lambda: occ_measure(shape, precision, closed), repeats)
            results.append((f"OCC GProp {precision:g}", t, a, v))
        if not args.quick and all(not f.is_trimmed or name in ("sphere", "torus") for f in faces):
            # scipy on the full domains: right for the untrimmed teapot and for the sphere and
            # torus, whose trims are their domains' boundaries
            t, (a, v, _) = timed(lambda: scipy_integrals([f.surface for f in faces], 1e-10), 1)
            sign = -1.0 if faces[0].reversed else 1.0
            results.append(("scipy cubature 1e-10", t, a, sign * v if closed else None))
        base = next(t for label, t, _, _ in results if label == "splinekit tol 1e-10")
        for label, t, a, v in results:
            rows.append((name, label, t, t / base, rel(a, area), rel(v, volume)))
    header = ("case", "integrator", "time s", "vs splinekit 1e-10", "area rel. error", "volume rel. error")
    widths = [14, 22, 10, 18, 16, 17]
    print("  ".join(h.ljust(w) for h, w in zip(header, widths)))
    print("  ".join("-" * w for w in widths))
    for name, label, t, ratio, ea, ev in rows:
        cells = (name, label, f"{t:.4f}", f"{ratio:.2f}", f"{ea:.1e}", "--" if np.isnan(ev) else f"{ev:.1e}")
        print("  ".join(c.ljust(w) for c, w in zip(cells, widths)))
    print()
    for name in dict.fromkeys(r[0] for r in rows):  # the lines check_ratios.py reads
        case = [r for r in rows if r[0] == name]
        occ = next(r for r in case if r[1] == "OCC GProp 1e-10")
        report(f"mass properties {name}: OCC GProp 1e-10 / splinekit 1e-10", occ[3], 1.0)
        occ_error = achieved(occ)
        equal = [r for r in case if r[1].startswith("splinekit") and achieved(r) <= occ_error]
        if equal:  # the loosest tolerance (the table lists them loosest first)
            r = equal[0]
            report(f"mass properties {name}: OCC GProp 1e-10 / splinekit at equal accuracy ({r[1]})", occ[2] / r[2], 1.0)


if __name__ == "__main__":
    main()
