"""Conversions with measured loss (splinekit.convert) against OpenCascade's point projection
(GeomAPI_ProjectPointOnSurf): the fitted surface's reported error is the true largest distance.
"""

from __future__ import annotations

import numpy as np
from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf
from OCP.gp import gp_Pnt

import splinekit as sk
from splinekit import convert


def _occ_distances(surface, points):
    handle = sk.occ.to_occ(surface)
    out = []
    for p in points:
        proj = GeomAPI_ProjectPointOnSurf(gp_Pnt(*map(float, p)), handle)
        out.append(proj.LowerDistance())
    return np.array(out)


def test_points_to_surface_error_matches_occ_projection():
    rng = np.random.default_rng(6)
    xy = rng.uniform(-1, 1, (3000, 2))
    Q = np.column_stack([xy, 0.3 * np.sin(2 * xy[:, 0]) * np.cos(3 * xy[:, 1])])
    c = convert.points_to_surface(Q, 1e-3)
    assert c.error <= 1e-3
    # OCC on the 200 worst points by splinekit's own residual, and on 200 random ones
    res = np.linalg.norm(c.result.evaluate(*sk.fit.scattered.plane_parameters(Q).T) - Q, axis=1)
    pick = np.concatenate([np.argsort(res)[-200:], rng.choice(len(Q), 200, replace=False)])
    occ = _occ_distances(c.result, Q[pick])
    assert occ.max() <= c.error + 1e-9
    assert occ.max() >= 0.99 * c.error or c.error - occ.max() < 1e-6
