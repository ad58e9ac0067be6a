"""Deviation (splinekit.analysis.deviation) against OpenCascade, point by point:
GeomAPI_ProjectPointOnSurf on the Utah teapot's patches and BRepExtrema_DistShapeShape on a
trimmed B-rep part (distances to the faces within their trims)."""

from __future__ import annotations

import numpy as np
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex
from OCP.BRepExtrema import BRepExtrema_DistShapeShape
from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf
from OCP.gp import gp_Pnt
from OCP.TopAbs import TopAbs_SHELL
from OCP.TopExp import TopExp_Explorer

from models import build_model
from splinekit.analysis import deviation
from splinekit.brep import primitives
from splinekit.interop.occ import to_occ


def test_teapot_patches_against_geomapi_projection():
    patches = [p for body in build_model("teapot").bodies for p in body]
    rng = np.random.default_rng(2)
    # points near the surface: patch points moved off along random directions by up to 3 % of the size
    pick = rng.integers(len(patches), size=400)
    uv = rng.uniform(0.05, 0.95, size=(400, 2))
    base = np.array([patches[k].evaluate(np.array([u]), np.array([v]))[0] for k, (u, v) in zip(pick, uv)])
    size = float(np.ptp(base, axis=0).max())
    P = base + rng.normal(size=base.shape) * 0.01 * size
    d = deviation(patches, P)
    handles = [to_occ(s) for s in patches]
    occ = np.full(len(P), np.inf)
    for i, q in enumerate(P):  # OCC: the lowest orthogonal foot over every patch
        for h in handles:
            pr = GeomAPI_ProjectPointOnSurf(gp_Pnt(*map(float, q)), h)
            if pr.NbPoints():
                occ[i] = min(occ[i], pr.LowerDistance())
    found = np.isfinite(occ)
    assert found.mean() > 0.9
    magnitude = np.abs(d.distances)
    # never farther than OCC's foot; equal where both found the same minimum (most points)
    assert np.all(magnitude[found] <= occ[found] + 1e-9 * size)
    same = found & (np.abs(magnitude - occ) < 1e-9 * size)
    assert same.mean() > 0.85, same.mean()


def test_a_trimmed_part_against_brepextrema():
    solid = primitives.box_with_hole(4.0, 1.0)
    rng = np.random.default_rng(9)
    P = rng.uniform(-3.0, 3.0, size=(150, 3))
    d = deviation(solid, P)
    explorer = TopExp_Explorer(to_occ(solid), TopAbs_SHELL)
    shell = explorer.Current()
    occ = np.empty(len(P))
    for i, q in enumerate(P):
        dist = BRepExtrema_DistShapeShape(BRepBuilderAPI_MakeVertex(gp_Pnt(*map(float, q))).Vertex(), shell)
        occ[i] = dist.Value()
    assert np.abs(np.abs(d.distances) - occ).max() < 1e-7
    # the sign: inside the solid (OCC's classification by distance to the solid itself: 0 inside)
    inside = np.array([BRepExtrema_DistShapeShape(BRepBuilderAPI_MakeVertex(gp_Pnt(*map(float, q))).Vertex(),
                                                  to_occ(solid)).Value() < 1e-12 for q in P])
    assert np.array_equal(d.distances < 0, inside)
