"""The operations of the comparison on one representation: a picture, a boolean with a second
body, a bend, curvature analysis and closest points (:data:`OPERATIONS`, :func:`run_operation`).

Each returns a dict ``{"seconds": float or None, "error": float or None, "note": str}``;
``seconds`` None means the operation does not apply or was not run, and ``note`` says why.
"""

from __future__ import annotations

import os
import time

import numpy as np

from ..brep.primitives import sphere as brep_sphere
from ..implicit import primitives as implicit_primitives
from ..interop.booleans import difference
from ..interop.exact_booleans import cut
from ..plot import render_mesh, render_patches
from .measure import QUERY_POINTS, near_points

__all__ = ["BEND_RADIUS", "EXACT_BOOLEAN_NOTE", "OPERATIONS", "run_operation", "second_body"]

OPERATIONS = ("render", "boolean", "bend", "curvature", "closest point")

BEND_RADIUS = 2.0
"""Radius of the bend, as a multiple of the bounding-box diagonal."""

PICTURE_SIZE = (480, 360)

EXACT_BOOLEAN_NOTE = ("exact B-rep cut in OpenCascade (splinekit.brep.cut) applies; not run by default "
                      "(about 35 s on the mug's 536 patches): compare(..., exact_boolean=True)")


def second_body(reference):
    """The body cut away by the boolean: a sphere of radius 0.15 x diagonal centred on the exact
    surface point farthest along +x (the mug's handle, the torus's outer equator)."""
    centre = reference.points[np.argmax(reference.points[:, 0])]
    return implicit_primitives.sphere(center=centre, radius=0.15 * reference.diagonal)


def _timed(fn):
    t0 = time.perf_counter()
    value = fn()
    return time.perf_counter() - t0, value


def _render(holder, reference, folder):
    path = os.path.join(folder, f"{holder.name.replace(' ', '_')}.png")
    if hasattr(holder, "patches"):
        seconds, _ = _timed(lambda: render_patches(holder.patches, path, size=PICTURE_SIZE, title=holder.name))
        return {"seconds": seconds, "error": None, "note": "exact patches, exact curvature colours", "path": path}
    seconds, _ = _timed(lambda: render_mesh(holder.render_mesh(), path, size=PICTURE_SIZE, title=holder.name))
    note = "zero set meshed first (counted in build)" if hasattr(holder, "f") else "mesh drawn as it is"
    return {"seconds": seconds, "error": None, "note": note, "path": path}


def _boolean(holder, reference, exact_boolean, expected):
    body = second_body(reference)
    if hasattr(holder, "patches"):
        if not exact_boolean:
            return {"seconds": None, "error": None, "note": EXACT_BOOLEAN_NOTE}
        tool = brep_sphere(0.15 * reference.diagonal, center=body.center)
        seconds, result = _timed(lambda: cut(holder.solid, tool))
        volume = result.volume(1e-6)
        return {"seconds": seconds, "error": abs(volume - expected()) / expected(), "note": "exact B-rep cut (OCC)"}
    if hasattr(holder, "f"):
        def csg():
            remaining = holder.f - body
            return remaining.to_mesh(getattr(holder, "spacing", reference.diagonal / 96))

        seconds, mesh = _timed(csg)
        return {"seconds": seconds, "error": abs(mesh.volume - expected()) / expected(),
                "note": "implicit CSG max(F, -G), zero set meshed for the volume"}
    tool = body.to_mesh(0.01 * reference.diagonal)
    seconds, result = _timed(lambda: difference(holder.mesh, tool))
    return {"seconds": seconds, "error": abs(result.volume - expected()) / expected(), "note": "manifold3d mesh boolean"}


def _bend(holder, reference):
    radius = BEND_RADIUS * reference.diagonal
    seconds, d = _timed(lambda: holder.bent_distance(reference.points, radius))
    return {"seconds": seconds, "error": float(d.max()), "note": (holder.bent_distance.__doc__ or "").split(":")[0].strip()}


def _curvature(holder, reference):
    seconds, H = _timed(lambda: holder.mean_curvature(reference.points))
    exact = reference.mean_curvature
    w = reference.weights
    rms = np.sqrt(np.average(exact**2, weights=w))
    error = float(np.sqrt(np.average((H - exact) ** 2, weights=w)) / rms)
    return {"seconds": seconds, "error": error, "note": "RMS error of |H| relative to the RMS of the exact |H|"}


def _closest(holder, reference, rng):
    exact, query = near_points(reference, getattr(holder, "query_points", QUERY_POINTS), rng)
    seconds, got = _timed(lambda: holder.closest(query))
    return {"seconds": seconds / len(query), "error": float(np.linalg.norm(got - exact, axis=1).max()),
            "note": "seconds per point; error: largest distance from the known closest point"}


def run_operation(name, holder, reference, *, folder, rng, exact_boolean=False, expected_cut=None) -> dict:
    """Operation ``name`` (one of :data:`OPERATIONS`) on ``holder``; see the module notes."""
    key = name.split()[0]
    if not holder.applies(key):
        return {"seconds": None, "error": None, "note": f"n/a: {holder.not_applicable[key]}"}
    if key == "render":
        return _render(holder, reference, folder)
    if key == "boolean":
        return _boolean(holder, reference, exact_boolean, expected_cut)
    if key == "bend":
        return _bend(holder, reference)
    if key == "curvature":
        return _curvature(holder, reference)
    return _closest(holder, reference, rng)
