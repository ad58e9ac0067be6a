"""Differential geometry of curves (splinekit.diffgeom.curves) against OpenCascade's
GeomLProp_CLProps on random NURBS curves: curvature, tangent and principal normal.
"""

from __future__ import annotations

import numpy as np
from OCP.GeomLProp import GeomLProp_CLProps
from OCP.gp import gp_Dir
from test_diffgeom_curves import random_spline

from splinekit.diffgeom.curves import curvature, frenet_frame
from splinekit.interop.occ import to_occ


def test_against_occ_clprops():
    rng = np.random.default_rng(5)
    checked = 0
    for case in range(12):
        c = random_spline(rng, rational=case % 2 == 1, degree=int(rng.integers(2, 6)))
        handle = to_occ(c)
        u = np.concatenate([list(c.domain), rng.uniform(*c.domain, 23)])
        k = curvature(c, u)
        T, N, _ = frenet_frame(c, u)
        size = np.abs(c.control_points).max()
        props = GeomLProp_CLProps(handle, 2, 1e-12)
        for i, ui in enumerate(u):
            props.SetParameter(float(ui))
            ko = props.Curvature()
            assert abs(k[i] - ko) <= 1e-10 * max(ko, 1 / size), (case, ui)
            if props.IsTangentDefined():
                d = gp_Dir()
                props.Tangent(d)
                assert np.abs(T[i] - [d.X(), d.Y(), d.Z()]).max() < 1e-11
            if ko * size > 1e-6:
                d = gp_Dir()
                props.Normal(d)
                assert np.abs(N[i] - [d.X(), d.Y(), d.Z()]).max() < 1e-10
                checked += 1
    assert checked >= 290  # of 300: normals at (near) inflections are skipped
