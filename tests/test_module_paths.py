"""The module paths of the numeric core that existed before its modules were split stay
importable and name the same objects (old imports and old pickles keep working)."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import splinekit as sk


@pytest.mark.parametrize(
    "module, name, expected",
    [
        ("splinekit.curves.bezier", "BezierCurve", sk.BezierCurve),
        ("splinekit.curves.bspline", "BSplineCurve", sk.BSplineCurve),
        ("splinekit.surfaces.bezier", "BezierSurface", sk.BezierSurface),
        ("splinekit.surfaces.bspline", "NurbsSurface", sk.NurbsSurface),
        ("splinekit.diffgeom.curves", "ParametricCurve", sk.ParametricCurve),
        ("splinekit.diffgeom.curves", "rotation_minimizing_frames", sk.rotation_minimizing_frames),
        ("splinekit.diffgeom.protocol", "ImplicitSurface", sk.ImplicitSurface),
        ("splinekit.closest", "project", sk.project),
        ("splinekit.closest", "Projection", sk.Projection),
        ("splinekit.construct.surfaces", "loft", sk.loft),
    ],
)
def test_old_paths_name_the_same_objects(module, name, expected):
    mod = __import__(module, fromlist=[name])
    assert getattr(mod, name) is expected


def test_arc_length_functions_keep_their_module():
    from splinekit.diffgeom import curves

    assert curves.MAX_PARAMETERS == 10**7
    c = sk.BSplineCurve(1, [0, 0, 1, 1], [[0.0, 0.0], [3.0, 4.0]])
    assert curves.arc_length(c) == pytest.approx(5.0, rel=1e-12)
    np.testing.assert_allclose(curves.equal_arc_length_parameters(c, 3), [0.0, 0.5, 1.0], atol=1e-12)


def test_values_pickle_through_their_classes():
    """A Bézier curve, a Bézier patch and a projection survive pickling."""
    bc = sk.BezierCurve([[0.0, 0.0], [1.0, 2.0], [3.0, 1.0]], weights=[1.0, 2.0, 1.0])
    bs = sk.BezierSurface(np.arange(2 * 3 * 3, dtype=float).reshape(2, 3, 3))
    proj = sk.project(bc, [[1.0, 1.0]])
    for obj in (bc, bs):
        assert pickle.loads(pickle.dumps(obj)) == obj
    again = pickle.loads(pickle.dumps(proj))
    np.testing.assert_array_equal(again.distances, proj.distances)
