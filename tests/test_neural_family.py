"""NeuralSDFFamily: two spheres in one network, codes mixed and a third code fitted alone.

Reference values are the exact radii of the spheres and the genus from the Euler characteristic
of the extracted mesh. One tiny family (seconds) runs in the default run; the larger one, tens of
seconds on a loaded 2-core machine, runs with ``-m slow``.
"""

import numpy as np
import pytest

pytest.importorskip("jax")

import splinekit.implicit as si
from splinekit.errors import ParameterError
from splinekit.mesh.components import genus
from splinekit.neural import NeuralSDF, NeuralSDFFamily
from splinekit.neural import load as load_any

RADII = (0.6, 0.9)
SETTINGS = dict(steps=1200, width=48, depth=2, latent=8, samples=4000, batch=512, lr=1e-3)
TINY = dict(steps=400, width=32, depth=2, latent=4, samples=2000, batch=256, lr=1e-3)


@pytest.fixture(scope="module")
def family():
    return NeuralSDFFamily.fit([si.sphere(radius=r) for r in RADII], seed=0, **SETTINGS)


def _on_sphere(r, n=1000):
    p = np.random.default_rng(4).normal(size=(n, 3))
    return r * p / np.linalg.norm(p, axis=1, keepdims=True)


def test_tiny_family_holds_both_spheres_and_meshes_each_at_its_own_resolution():
    fam = NeuralSDFFamily.fit([si.sphere(radius=r) for r in RADII], seed=0, **TINY)
    for i, r in enumerate(RADII):
        shape = fam.shape(i)
        # on its own sphere |F| is small; on the other one it is not (the codes tell them apart)
        assert np.abs(shape(_on_sphere(r))).mean() < 0.04
        assert np.abs(shape(_on_sphere(RADII[1 - i]))).mean() > 0.2
        # default mesh edge: the box of this sphere (side 2 r) filling 0.8 of a cube of 128 cells
        assert shape.default_edge() == pytest.approx(2.0 * (r / 0.8) / 128, rel=1e-3)  # box of a tessellation
        mesh = shape.to_mesh()
        assert mesh.is_closed and genus(mesh) == 0
    mid = fam.interpolate(0, 1, 0.5)
    assert mid.default_edge() == pytest.approx(fam.shape(0).default_edge())
    mesh = mid.to_mesh()
    assert mesh.is_closed and genus(mesh) == 0


def _radius(shape, n=400):
    """Mean distance from the origin of the zero set along random rays (Newton onto F = 0)."""
    d = np.random.default_rng(0).normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return float(np.linalg.norm(shape.closest_points(0.75 * d), axis=1).mean())


@pytest.mark.slow
def test_each_code_holds_its_sphere(family):
    assert len(family) == 2
    for i, r in enumerate(RADII):
        assert abs(_radius(family.shape(i)) - r) < 0.04
    assert isinstance(family.shape(1), NeuralSDF)
    with pytest.raises(ParameterError):
        family.shape(2)


@pytest.mark.slow
def test_interpolated_shape_lies_between_and_is_watertight(family):
    mid = family.interpolate(0, 1, 0.5)
    assert RADII[0] + 0.03 < _radius(mid) < RADII[1] - 0.03
    mesh = mid.to_mesh(0.08)
    assert mesh.is_closed and genus(mesh) == 0


@pytest.mark.slow
def test_fit_code_moves_only_the_code(family):
    new = family.fit_code(si.sphere(radius=0.75), steps=300, seed=1)
    assert abs(_radius(new) - 0.75) < 0.05
    for a, b in zip(family.params, new.params):
        assert np.array_equal(a["W"], b["W"]) and np.array_equal(a["b"], b["b"])


@pytest.mark.slow
def test_family_file_round_trip(family, tmp_path):
    path = tmp_path / "two.nsdf"
    family.save(path)
    back = load_any(path)
    assert isinstance(back, NeuralSDFFamily) and np.array_equal(back.codes, family.codes)
    p = np.random.default_rng(2).uniform(-1, 1, (100, 3))
    assert np.array_equal(back.shape(1)(p), family.shape(1)(p))
    assert family.nbytes == 4 * family.parameter_count
