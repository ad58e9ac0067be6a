"""NeuralSDFFamily: two spheres in one network, codes mixed and a third code fitted alone.

Reference values are the exact radii of the spheres. The training takes tens of seconds on a
loaded 2-core machine, so the module runs with ``-m slow``.
"""

import numpy as np
import pytest

pytest.importorskip("jax")

import splinekit.implicit as si
from splinekit.errors import ParameterError
from splinekit.mesh.components import genus
from splinekit.neural import NeuralSDF, NeuralSDFFamily
from splinekit.neural import load as load_any

pytestmark = pytest.mark.slow

RADII = (0.6, 0.9)
SETTINGS = dict(steps=1200, width=48, depth=2, latent=8, samples=4000, batch=512, lr=1e-3)


@pytest.fixture(scope="module")
def family():
    return NeuralSDFFamily.fit([si.sphere(radius=r) for r in RADII], seed=0, **SETTINGS)


def _radius(shape, n=400):
    """Mean distance from the origin of the zero set along random rays (Newton onto F = 0)."""
    d = np.random.default_rng(0).normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return float(np.linalg.norm(shape.closest_points(0.75 * d), axis=1).mean())


def test_each_code_holds_its_sphere(family):
    assert len(family) == 2
    for i, r in enumerate(RADII):
        assert abs(_radius(family.shape(i)) - r) < 0.04
    assert isinstance(family.shape(1), NeuralSDF)
    with pytest.raises(ParameterError):
        family.shape(2)


def test_interpolated_shape_lies_between_and_is_watertight(family):
    mid = family.interpolate(0, 1, 0.5)
    assert RADII[0] + 0.03 < _radius(mid) < RADII[1] - 0.03
    mesh = mid.to_mesh(0.08)
    assert mesh.is_closed and genus(mesh) == 0


def test_fit_code_moves_only_the_code(family):
    new = family.fit_code(si.sphere(radius=0.75), steps=300, seed=1)
    assert abs(_radius(new) - 0.75) < 0.05
    for a, b in zip(family.params, new.params):
        assert np.array_equal(a["W"], b["W"]) and np.array_equal(a["b"], b["b"])


def test_family_file_round_trip(family, tmp_path):
    path = tmp_path / "two.nsdf"
    family.save(path)
    back = load_any(path)
    assert isinstance(back, NeuralSDFFamily) and np.array_equal(back.codes, family.codes)
    p = np.random.default_rng(2).uniform(-1, 1, (100, 3))
    assert np.array_equal(back.shape(1)(p), family.shape(1)(p))
    assert family.nbytes == 4 * family.parameter_count
