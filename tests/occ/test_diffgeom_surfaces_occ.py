"""Surface curvature (splinekit.diffgeom.curvature) against OpenCascade's GeomLProp_SLProps on
random B-spline and NURBS surfaces: principal, mean and Gaussian curvature, normal, directions.
Sign convention as in test_diffgeom_surfaces (the unit normal Su x Sv, as in OCC).
"""

from __future__ import annotations

import numpy as np
import pytest
from _geometry import random_surface_data
from OCP.GeomLProp import GeomLProp_SLProps
from OCP.gp import gp_Dir

import splinekit as sk
from splinekit.diffgeom.curvature import curvature


@pytest.mark.parametrize("seed", range(40))
def test_against_occ_slprops(seed):
    rng = np.random.default_rng([41, seed])
    rational = bool(seed % 2)
    pu, pv, ku, kv, P, Wt = random_surface_data(rng, rational, max_degree=5, max_spans=3)
    s = sk.NurbsSurface(pu, pv, ku, kv, P, Wt) if rational else sk.BSplineSurface(pu, pv, ku, kv, P)
    (a, b), (c0, d0) = s.domain
    u, v = rng.uniform(a, b, 12), rng.uniform(c0, d0, 12)
    c = curvature(s, u, v)
    h = sk.occ.to_occ(s)
    for i in range(u.size):
        props = GeomLProp_SLProps(h, float(u[i]), float(v[i]), 2, 1e-12)
        if not props.IsCurvatureDefined():
            continue
        scale = max(abs(props.MaxCurvature()), abs(props.MinCurvature()), 1.0 / np.abs(P).max())
        tol = 1e-7 * scale
        assert c.k1[i] == pytest.approx(props.MaxCurvature(), abs=tol)
        assert c.k2[i] == pytest.approx(props.MinCurvature(), abs=tol)
        assert c.mean[i] == pytest.approx(props.MeanCurvature(), abs=tol)
        assert c.gaussian[i] == pytest.approx(props.GaussianCurvature(), abs=tol * scale)
        n = props.Normal()
        assert np.allclose(c.normal[i], [n.X(), n.Y(), n.Z()], atol=1e-8)
        if props.MaxCurvature() - props.MinCurvature() > 1e-4 * scale:  # not an umbilic
            dmax, dmin = gp_Dir(), gp_Dir()
            props.CurvatureDirections(dmax, dmin)
            assert abs(c.directions[i, 0] @ [dmax.X(), dmax.Y(), dmax.Z()]) == pytest.approx(1, abs=1e-6)
            assert abs(c.directions[i, 1] @ [dmin.X(), dmin.Y(), dmin.Z()]) == pytest.approx(1, abs=1e-6)
