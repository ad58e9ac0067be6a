"""The B-rep tessellator's scattered surface evaluator (tessellation.batch.SurfaceBatch) on both
paths (numpy and the compiled kernel) against the surfaces' own public evaluators."""

from __future__ import annotations

import numpy as np
import pytest

from splinekit import _kernels
from splinekit.brep import primitives
from splinekit.tessellation.batch import SurfaceBatch


@pytest.fixture(params=["0", "1"], ids=["numpy", "numba"])
def kernel_path(request, monkeypatch):
    if request.param == "1":
        pytest.importorskip("numba")
        monkeypatch.delenv("SPLINEKIT_NUMBA", raising=False)
        assert _kernels.load("splinekit.tessellation._batch_kernels") is not None
    else:
        monkeypatch.setenv("SPLINEKIT_NUMBA", "0")
    return request.param


def test_points_and_partials_match_the_surfaces_own_evaluators(kernel_path):
    # planes (degree 1), a cylinder (2 x 1), a sphere and a torus (rational 2 x 2), several cells each
    faces = (primitives.torus(2.0, 0.6).faces + primitives.sphere(1.5, center=(1, 2, 3)).faces
             + primitives.box_with_hole(20.0, 4.0).faces)  # fmt: skip
    surfaces = [f.surface for f in faces]
    batch = SurfaceBatch(surfaces)
    rng = np.random.default_rng(5)
    n = 3000
    k = rng.integers(0, len(surfaces), n)
    dom = np.array([[*s.domain[0], *s.domain[1]] for s in surfaces])[k]
    u = dom[:, 0] + (dom[:, 1] - dom[:, 0]) * rng.random(n)
    v = dom[:, 2] + (dom[:, 3] - dom[:, 2]) * rng.random(n)
    u[:50] = dom[:50, 1]  # the domain's far ends (the last cell's closed side)
    v[50:100] = dom[50:100, 3]
    S, Su, Sv = batch.partials(k, u, v)
    assert np.array_equal(batch.evaluate(k, u, v), S)
    for j, s in enumerate(surfaces):
        sel = np.flatnonzero(k == j)
        D = s.derivatives(u[sel], v[sel], 1)
        scale = np.abs(s.control_points).max()
        assert np.allclose(S[sel], D[0, 0], rtol=0, atol=1e-13 * scale)
        assert np.allclose(Su[sel], D[1, 0], rtol=0, atol=1e-11 * scale)
        assert np.allclose(Sv[sel], D[0, 1], rtol=0, atol=1e-11 * scale)


def test_cell_location_is_the_same_on_both_paths(monkeypatch):
    pytest.importorskip("numba")
    faces = primitives.torus(2.0, 0.6).faces + primitives.plate_with_holes(40.0, 30.0, 5.0, [(10, 10, 4)]).faces
    batch = SurfaceBatch([f.surface for f in faces])
    rng = np.random.default_rng(8)
    n = 2000
    k = rng.integers(0, len(faces), n)
    dom = np.array([[*f.surface.domain[0], *f.surface.domain[1]] for f in faces])[k]
    # inside, on the ends and a little outside the domains (pcurves of CAD files stray)
    u = dom[:, 0] + (dom[:, 1] - dom[:, 0]) * rng.uniform(-0.01, 1.01, n)
    v = dom[:, 2] + (dom[:, 3] - dom[:, 2]) * rng.uniform(-0.01, 1.01, n)
    u[:40], v[40:80] = dom[:40, 1], dom[40:80, 2]
    got = []
    for env in ("0", "1"):
        monkeypatch.setenv("SPLINEKIT_NUMBA", env)
        if env == "1":
            assert _kernels.load("splinekit.tessellation._batch_kernels") is not None
        got.append(batch._cells(k, u, v))
    for a, b in zip(*got):
        assert np.array_equal(a, b)
