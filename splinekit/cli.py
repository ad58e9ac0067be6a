"""The ``splinekit`` command line."""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np


def demo_surface():
    """A bicubic NURBS surface over 8 x 8 control points: a wavy roof with raised weights."""
    from . import NurbsSurface

    n = 8
    x, y = np.meshgrid(np.linspace(-1.0, 1.0, n), np.linspace(-1.0, 1.0, n), indexing="ij")
    z = 0.35 * np.sin(2.2 * x) * np.cos(1.7 * y) + 0.15 * (x**2 - y**2)
    weights = 1.0 + 1.5 * np.exp(-8 * (x**2 + y**2))
    return NurbsSurface.uniform(3, 3, np.stack([x, y, z], axis=-1), weights)


def _area(surface, per_span: int = 6) -> float:
    """Surface area by Gauss-Legendre quadrature on every knot span pair."""
    g, gw = np.polynomial.legendre.leggauss(per_span)
    bu, bv = surface.bezier_breakpoints()

    def nodes(b):
        mid, half = 0.5 * (b[1:] + b[:-1]), 0.5 * (b[1:] - b[:-1])
        return (mid[:, None] + half[:, None] * g).ravel(), (half[:, None] * gw).ravel()

    us, wu = nodes(bu)
    vs, wv = nodes(bv)
    d = surface.derivatives_grid(us, vs, 1)
    jac = np.linalg.norm(np.cross(d[1, 0], d[0, 1]), axis=-1)
    return float(wu @ jac @ wv)


def cmd_demo(args) -> int:
    from .plot import render_surface

    s = demo_surface()
    print(f"surface: {s!r}")
    (a, b), (c, d) = s.domain
    us, vs = np.linspace(a, b, 1000), np.linspace(c, d, 1000)
    t0 = time.perf_counter()
    grid = s.evaluate_grid(us, vs)
    t1 = time.perf_counter()
    print(f"evaluated a 1000 x 1000 grid in {1e3 * (t1 - t0):.1f} ms; bounding box "
          f"{np.round(grid.reshape(-1, 3).min(0), 4).tolist()} .. {np.round(grid.reshape(-1, 3).max(0), 4).tolist()}")
    print(f"area (Gauss-Legendre per span): {_area(s):.10f}")
    patches = s.to_bezier()
    print(f"Bezier decomposition: {len(patches)} x {len(patches[0])} bicubic rational patches")
    rng = np.random.default_rng(0)
    u, v = rng.uniform(a, b, 10000), rng.uniform(c, d, 10000)
    ref = s.evaluate(u, v)
    checks = {
        "knot insertion u=0.3 (x2)": s.insert_knot(0.3, 2, direction="u"),
        "degree elevation v (+2)": s.elevate_degree(2, direction="v"),
        "refinement in u and v": s.refine([0.1, 0.55, 0.9], "u").refine([0.45], "v"),
    }
    for name, other in checks.items():
        print(f"{name}: max deviation {np.abs(other.evaluate(u, v) - ref).max():.2e}")
    n = s.normal(np.array([0.5]), np.array([0.5]))[0]
    print(f"normal at (0.5, 0.5): {np.round(n, 6).tolist()}")
    path = render_surface(s, args.output, title="splinekit demo: bicubic NURBS surface and its control net")
    print(f"wrote {path}")
    return 0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="splinekit", description="Spline and subdivision modeling toolkit.")
    sub = parser.add_subparsers(dest="command")
    demo = sub.add_parser("demo", help="build a NURBS surface, print what was computed and write a PNG of it")
    demo.add_argument("-o", "--output", default="splinekit-demo.png", help="PNG path (default: %(default)s)")
    args = parser.parse_args(argv)
    if args.command == "demo" or args.command is None:
        if args.command is None:
            args.output = "splinekit-demo.png"
        return cmd_demo(args)
    parser.print_help()
    return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
