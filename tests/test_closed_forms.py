"""Closed-form checks on exact rational geometry: a quarter of the unit sphere
built by hand as a biquadratic NURBS patch (half-circle profile x quarter-circle
sweep). Its points lie at radius 1 and its outward normal equals the position,
also at the collapsed pole edges, where Su x Sv vanishes."""

import math

import numpy as np
import pytest

import splinekit as sk
from splinekit import _kernels
from splinekit.brep import TrimmedFace


def sphere_patch():
    r = math.sqrt(0.5)
    profile = np.array([[0, 0, 1], [1, 0, 1], [1, 0, 0], [1, 0, -1], [0, 0, -1]], float)
    w_profile = np.array([1, r, 1, r, 1])
    arc = [(1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
    w_arc = np.array([1, r, 1])
    P = np.array([[[x * c, x * s, z] for (c, s) in arc] for x, _, z in profile])
    W = np.outer(w_profile, w_arc)
    return sk.NurbsSurface(2, 2, [0, 0, 0, 0.5, 0.5, 1, 1, 1], [0, 0, 0, 1, 1, 1], P, W)


@pytest.fixture(params=["numpy", "compiled"])
def kernel_path(request, monkeypatch):
    """The numpy path (SPLINEKIT_NUMBA=0), or the compiled kernels at every size (thresholds 0)."""
    if request.param == "numpy":
        monkeypatch.setenv("SPLINEKIT_NUMBA", "0")
    else:
        pytest.importorskip("numba")
        monkeypatch.delenv("SPLINEKIT_NUMBA", raising=False)
        monkeypatch.setattr(_kernels, "MIN_WORK", 0)
        monkeypatch.setattr(_kernels, "LOAD_WORK", 0)
    return request.param


@pytest.mark.parametrize("count", [41, 160])
def test_sphere_points_and_normals(count, kernel_path):
    s = sphere_patch()
    g = np.linspace(0, 1, count)
    X = s.evaluate_grid(g, g)
    np.testing.assert_allclose(np.linalg.norm(X, axis=-1), 1.0, rtol=0, atol=1e-14)
    np.testing.assert_allclose(s.normal_grid(g, g), X, rtol=0, atol=1e-13)
    U, V = np.meshgrid(g, g, indexing="ij")
    np.testing.assert_allclose(s.normal(U, V), X, rtol=0, atol=1e-13)


def test_sphere_pole_normals_pointwise():
    s = sphere_patch()
    u = np.array([0.0, 0.0, 1.0, 1.0])
    v = np.array([0.0, 0.7, 0.2, 1.0])
    np.testing.assert_allclose(s.normal(u, v), [[0, 0, 1], [0, 0, 1], [0, 0, -1], [0, 0, -1]], atol=1e-14)


def test_sphere_area_is_a_quarter_of_4pi():
    assert TrimmedFace(sphere_patch()).area() == pytest.approx(math.pi, rel=1e-9)


def test_quarter_circle_arc_length_and_radius():
    r = math.sqrt(0.5)
    c = sk.NurbsCurve(2, [0, 0, 0, 1, 1, 1], [[1, 0], [1, 1], [0, 1]], [1, r, 1])
    u = np.linspace(0, 1, 1001)
    np.testing.assert_allclose(np.linalg.norm(c.evaluate(u), axis=-1), 1.0, rtol=0, atol=1e-15)
    assert c.arc_length() == pytest.approx(math.pi / 2, rel=1e-12)
    # unit tangent is perpendicular to the radius
    np.testing.assert_allclose(np.einsum("ij,ij->i", c.tangent(u), c.evaluate(u)), 0.0, atol=1e-14)
