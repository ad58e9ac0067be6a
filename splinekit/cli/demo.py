"""``splinekit demo``: one NURBS surface, timed, measured, checked against its own knot algebra
and drawn."""

from __future__ import annotations

import os
import time

import numpy as np

from ..brep import TrimmedFace
from ..plot import render_surface
from ..surfaces import NurbsSurface
from .render import DEFAULT_FOLDER, picture_path, write_picture

DEFAULT_PICTURE = os.path.join(DEFAULT_FOLDER, "splinekit-demo.png")


def demo_surface() -> NurbsSurface:
    """A bicubic NURBS surface over 8 x 8 control points: a wavy roof with raised weights."""
    n = 8
    x, y = np.meshgrid(np.linspace(-1.0, 1.0, n), np.linspace(-1.0, 1.0, n), indexing="ij")
    z = 0.35 * np.sin(2.2 * x) * np.cos(1.7 * y) + 0.15 * (x**2 - y**2)
    weights = 1.0 + 1.5 * np.exp(-8 * (x**2 + y**2))
    return NurbsSurface.uniform(3, 3, np.stack([x, y, z], axis=-1), weights)


def cmd_demo(args, console) -> int:
    out = picture_path(args.output, "splinekit-demo")
    s = demo_surface()
    console.out(f"surface: {s!r}")
    (a, b), (c, d) = s.domain
    us, vs = np.linspace(a, b, 1000), np.linspace(c, d, 1000)
    t0 = time.perf_counter()
    grid = s.evaluate_grid(us, vs)
    t1 = time.perf_counter()
    console.out(f"evaluated a 1000 x 1000 grid in {1e3 * (t1 - t0):.1f} ms; bounding box "
                f"{np.round(grid.reshape(-1, 3).min(0), 4).tolist()} .. {np.round(grid.reshape(-1, 3).max(0), 4).tolist()}")
    console.out(f"area (adaptive Gauss-Kronrod, splinekit.brep): {TrimmedFace(s).area():.10f}")
    patches = s.to_bezier()
    console.out(f"Bezier decomposition: {len(patches)} x {len(patches[0])} bicubic rational patches")
    rng = np.random.default_rng(0)
    u, v = rng.uniform(a, b, 10000), rng.uniform(c, d, 10000)
    ref = s.evaluate(u, v)
    checks = {
        "knot insertion u=0.3 (x2)": s.insert_knot(0.3, 2, direction="u"),
        "degree elevation v (+2)": s.elevate_degree(2, direction="v"),
        "refinement in u and v": s.refine([0.1, 0.55, 0.9], "u").refine([0.45], "v"),
    }
    for name, other in checks.items():
        console.out(f"{name}: max deviation {np.abs(other.evaluate(u, v) - ref).max():.2e}")
    n = s.normal(np.array([0.5]), np.array([0.5]))[0]
    console.out(f"normal at (0.5, 0.5): {np.round(n, 6).tolist()}")
    title = "splinekit demo: bicubic NURBS surface and its control net"
    path = write_picture(out, lambda png: render_surface(s, png, title=title))
    console.out(f"wrote {path}")
    return 0
