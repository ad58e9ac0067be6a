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
        for tol in (1e-6, 1e-10):
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
        base = results[1][1]
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
    for name, label, _, ratio, _, _ in rows:  # the lines check_ratios.py reads: the same tolerance on both sides
        if label == "OCC GProp 1e-10":
            report(f"mass properties {name}: OCC GProp 1e-10 / splinekit 1e-10", ratio, 1.0)


if __name__ == "__main__":
    main()
