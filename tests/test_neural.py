"""splinekit.neural: a tiny network trained on a sphere, checked against the exact sphere.

One small network (2 x 32 sine units, a few hundred steps: seconds) is trained once per module and
shared. Its error is measured against the exact sphere (closed forms: distance |p| - r, mean
curvature 1/r, Gaussian 1/r^2, volume 4/3 pi r^3), never against its own output. Derivatives are
checked against central differences of the values, which the network computes by another road.
"""

import os
import subprocess
import sys
import zipfile

import numpy as np
import pytest

pytest.importorskip("jax")  # the `test` extra installs it; without it only the import test runs below

import exporters
import splinekit as sk
import splinekit.implicit as si
from splinekit.cli import main
from splinekit.errors import FileFormatError, NotManifoldError, SplineKitError
from splinekit.mesh.components import genus
from splinekit.mesh.primitives import grid, icosphere
from splinekit.neural import NeuralOccupancy, NeuralSDF
from splinekit.neural import load as load_any

R = 1.0
TINY = dict(steps=300, width=32, depth=2, omega=10.0, samples=4000, batch=512, lr=1e-3)
"""A network that trains in seconds; the bounds below hold for it with a margin of about two.
``omega = 10`` (not the default 30): a sphere has no fine detail, and a lower frequency leaves a
two-layer network's gradient without ripples (measured eikonal residual 0.06 against 0.17)."""


@pytest.fixture(scope="module")
def sphere_sdf():
    return NeuralSDF.fit(si.sphere(radius=R), seed=0, **TINY)


def _on_sphere(n, seed=1, radius=R):
    p = np.random.default_rng(seed).normal(size=(n, 3))
    return radius * p / np.linalg.norm(p, axis=1, keepdims=True)


def test_tiny_sphere_surface_error_and_eikonal_residual(sphere_sdf):
    m = sphere_sdf
    surface = _on_sphere(2000)
    # the zero set within 2 % of the radius on average, 6 % at worst
    assert np.abs(m(surface)).mean() < 0.02 * R
    assert np.abs(m(surface)).max() < 0.06 * R
    # |grad F| = 1 within 0.1 on average in the band 0.8 r .. 1.2 r, where the surface is decided
    band = np.concatenate([_on_sphere(500, 2, r) for r in (0.8, 0.9, 1.1, 1.2)])
    residual = np.abs(np.linalg.norm(m.gradient(band), axis=1) - 1.0)
    assert residual.mean() < 0.1
    # a signed distance: values in the band match |p| - r within 5 % of r
    assert np.abs(m(band) - (np.linalg.norm(band, axis=1) - R)).mean() < 0.05 * R
    assert m.info["loss"] < 0.5 * m.info.get("first_loss", np.inf) or m.info["loss"] < 0.05


def test_fit_is_deterministic_given_the_seed(sphere_sdf):
    again = NeuralSDF.fit(si.sphere(radius=R), seed=0, **TINY)
    for a, b in zip(sphere_sdf.params, again.params):
        assert np.array_equal(a["W"], b["W"]) and np.array_equal(a["b"], b["b"])


def test_save_load_round_trip_is_bit_exact(sphere_sdf, tmp_path):
    path = tmp_path / "sphere.nsdf"
    sphere_sdf.save(path)
    loaded = NeuralSDF.load(path)
    for a, b in zip(sphere_sdf.params, loaded.params):
        assert a["W"].dtype == b["W"].dtype == np.float32
        assert a["W"].tobytes() == b["W"].tobytes() and a["b"].tobytes() == b["b"].tobytes()
    p = _on_sphere(300) * 1.1
    assert np.array_equal(sphere_sdf(p), loaded(p))
    assert np.array_equal(sphere_sdf.gradient(p), loaded.gradient(p))
    assert loaded.architecture == sphere_sdf.architecture and loaded.info == sphere_sdf.info
    assert isinstance(load_any(path), NeuralSDF)
    with pytest.raises(FileFormatError, match="not a NeuralOccupancy"):
        NeuralOccupancy.load(path)
    assert not [f for f in os.listdir(tmp_path) if f != "sphere.nsdf"]  # no temporary file left


def _rewrite(src, dst, change):
    with np.load(src) as z:
        arrays = {k: z[k] for k in z.files}
    change(arrays)
    with open(dst, "wb") as fh:
        np.savez(fh, **arrays)


def test_a_file_that_is_not_a_model_is_refused(sphere_sdf, tmp_path):
    good = tmp_path / "good.nsdf"
    sphere_sdf.save(good)
    junk = tmp_path / "junk.nsdf"
    junk.write_bytes(os.urandom(2000))
    truncated = tmp_path / "truncated.nsdf"
    truncated.write_bytes(good.read_bytes()[:700])
    foreign = tmp_path / "foreign.nsdf"
    np.savez(open(foreign, "wb"), data=np.arange(5.0))
    cases = {junk: "not a NumPy archive", truncated: "not a NumPy archive", foreign: "no header",
             tmp_path / "missing.nsdf": "does not exist"}
    bad_magic = tmp_path / "magic.nsdf"
    _rewrite(good, bad_magic, lambda a: a.__setitem__("header", np.frombuffer(b'{"magic": "x"}', np.uint8)))
    cases[bad_magic] = "wrong magic"
    wrong_shape = tmp_path / "shape.nsdf"
    _rewrite(good, wrong_shape, lambda a: a.__setitem__("W1", a["W1"][:, :-1]))
    cases[wrong_shape] = "layer 1"
    nan = tmp_path / "nan.nsdf"
    _rewrite(good, nan, lambda a: a["b0"].__setitem__(0, np.nan))
    cases[nan] = "non-finite"
    pickled = tmp_path / "pickled.nsdf"  # an object array needs pickle, which is never allowed
    _rewrite(good, pickled, lambda a: a.__setitem__("codes", np.array([{"x": 1}], dtype=object)))
    cases[pickled] = "not a NumPy archive"
    for path, why in cases.items():
        with pytest.raises(FileFormatError, match=why):
            NeuralSDF.load(path)
    assert zipfile.is_zipfile(good)


def test_gradient_and_hessian_match_finite_differences(sphere_sdf):
    m = sphere_sdf
    p = np.random.default_rng(4).uniform(-1.3, 1.3, (40, 3))
    h = 1e-5
    fd = np.stack([(m(p + h * e) - m(p - h * e)) / (2 * h) for e in np.eye(3)], axis=1)
    np.testing.assert_allclose(m.gradient(p), fd, atol=1e-7, rtol=1e-6)
    fd2 = np.stack([(m.gradient(p + h * e) - m.gradient(p - h * e)) / (2 * h) for e in np.eye(3)], axis=1)
    np.testing.assert_allclose(m.hessian(p), 0.5 * (fd2 + np.swapaxes(fd2, 1, 2)), atol=1e-5, rtol=1e-5)
    n = m.normal(p)
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, rtol=1e-12)


def test_curvature_of_the_trained_sphere_is_near_one_over_r(sphere_sdf):
    m = sphere_sdf
    p = m.closest_points(_on_sphere(200, seed=5))
    got = sk.curvature(m, p)
    exact = sk.curvature(si.sphere(radius=R), _on_sphere(200, seed=5))  # same convention, exact sphere
    assert np.allclose(exact.mean, exact.mean[0]) and abs(abs(exact.mean[0]) - 1 / R) < 1e-6
    # loose: a tiny network's Hessian is its least accurate part
    assert abs(np.median(got.mean) - exact.mean[0]) < 0.25 / R
    assert abs(np.median(got.gaussian) - exact.gaussian[0]) < 0.5 / R**2
    mine = m.curvature(p)
    assert np.array_equal(mine.mean, got.mean)


def test_mesh_is_closed_genus_zero_with_the_sphere_volume(sphere_sdf):
    mesh = sphere_sdf.to_mesh(0.08)
    assert mesh.is_closed and genus(mesh) == 0
    assert abs(mesh.volume - 4 / 3 * np.pi * R**3) < 0.08 * 4 / 3 * np.pi * R**3
    assert np.isfinite(mesh.deviation) and mesh.deviation < 0.1 * R


def test_trained_shape_works_in_implicit_csg(sphere_sdf):
    box = si.box(center=(1.0, 0.0, 0.0), size=(1.0, 1.0, 1.0))
    union, cut = sphere_sdf | box, sphere_sdf - box
    p = np.random.default_rng(6).uniform(-1.5, 2.0, (500, 3))
    np.testing.assert_array_equal(union(p), np.minimum(sphere_sdf(p), box(p)))
    np.testing.assert_array_equal(cut(p), np.maximum(sphere_sdf(p), -box(p)))
    mesh = cut.to_mesh(0.08)
    assert mesh.is_closed and genus(mesh) == 0
    assert 0.5 * 4 / 3 * np.pi < mesh.volume < 0.95 * 4 / 3 * np.pi  # a slice of the ball is gone
    moved = sphere_sdf.translate((5.0, 0.0, 0.0))
    np.testing.assert_allclose(moved(p + [5.0, 0.0, 0.0]), sphere_sdf(p))


def test_bounds_hold_the_whole_zero_set(sphere_sdf):
    lo, hi = sphere_sdf.bounds
    far = np.random.default_rng(7).uniform(-1, 1, (1000, 3))
    far = far / np.abs(far).max(axis=1, keepdims=True) * (hi[0] + 0.01)  # on a box just outside
    assert (sphere_sdf(far) > 0).all()


def test_trains_from_a_mesh_and_refuses_open_shapes():
    ball = icosphere(3, radius=2.0)
    m = NeuralSDF.fit(ball, seed=0, **TINY)
    assert np.abs(m(_on_sphere(500, radius=2.0))).mean() < 0.05 * 2.0
    with pytest.raises(NotManifoldError, match="open"):
        NeuralSDF.fit(grid(4, 4), steps=5)
    with pytest.raises(SplineKitError, match="unbounded"):
        NeuralSDF.fit(si.plane(normal=(0, 0, 1)), steps=5)


class _NaNFar(si.Implicit):
    """A sphere whose F is NaN far from it: training samples there are not finite."""

    def __init__(self):
        super().__init__(bounds=(-np.ones(3), np.ones(3)), exact=True)

    def _value(self, p):
        r = np.linalg.norm(p, axis=1)
        return np.where(r < 1.5, r - 0.8, np.nan)


def test_non_finite_samples_are_refused():
    with pytest.raises(SplineKitError, match="not finite"):
        NeuralSDF.fit(_NaNFar(), steps=5, samples=500)


def test_bad_settings_are_refused():
    for bad in (dict(steps=0), dict(width=0), dict(encoding="relu"), dict(lr=-1.0), dict(seed=-1)):
        with pytest.raises(SplineKitError):
            NeuralSDF.fit(si.sphere(radius=1.0), **{**TINY, **bad})


def test_occupancy_classifies_points_and_is_meshed_at_one_half():
    occ = NeuralOccupancy.fit(si.sphere(radius=R), seed=0, **{**TINY, "lr": 3e-3})
    p = np.random.default_rng(8).uniform(-1.25, 1.25, (4000, 3))
    inside = np.linalg.norm(p, axis=1) < R
    prob = occ.probability(p)
    assert ((prob > 0.5) == inside).mean() > 0.95
    # where it is sure it is right: the band |r - R| > 0.15 R is classified with p < 0.1 or > 0.9
    r = np.linalg.norm(p, axis=1)
    assert (prob[r > 1.15 * R] < 0.1).mean() > 0.97
    assert (prob[(r < 0.85 * R) & (r > 0.4 * R)] > 0.9).mean() > 0.97
    np.testing.assert_allclose(prob, 1.0 / (1.0 + np.exp(occ(p) / occ.normalization.scale)))
    mesh = occ.to_mesh(0.08)  # the 0.5 level
    assert mesh.is_closed and genus(mesh) == 0
    assert abs(mesh.volume - 4 / 3 * np.pi) < 0.15 * 4 / 3 * np.pi


def test_import_splinekit_loads_no_jax_and_a_missing_extra_names_the_install():
    code = (
        "import sys, splinekit\n"
        "print('jax' in sys.modules, 'optax' in sys.modules)\n"
        "sys.modules['jax'] = None\n"
        "try:\n"
        "    splinekit.neural\n"
        "except splinekit.errors.MissingDependencyError as e:\n"
        "    print('missing:', e)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    first, second = out.strip().splitlines()
    assert first == "False False"
    assert second.startswith("missing:") and 'pip install "splinekit[neural]"' in second


# -- the command line ------------------------------------------------------------------------------
def _cli(args, capsys):
    status = main(args)
    out, err = capsys.readouterr()
    return status, out, err


def test_cli_meshes_a_saved_model_to_stl(sphere_sdf, tmp_path, capsys):
    model, stl = tmp_path / "s.nsdf", tmp_path / "s.stl"
    sphere_sdf.save(model)
    status, out, err = _cli(["neural", "mesh", str(model), "-o", str(stl), "--cells", "40"], capsys)
    assert status == 0, err
    assert "genus 0" in out and "wrote" in out
    mesh = exporters.import_stl(str(stl))
    assert mesh.n_faces > 100 and abs(mesh.volume - 4 / 3 * np.pi) < 0.1 * 4 / 3 * np.pi


def test_cli_refuses_bad_files_and_suffixes_in_one_line(tmp_path, capsys):
    junk = tmp_path / "junk.nsdf"
    junk.write_bytes(b"PK\x03\x04 not really a zip")
    cases = [
        (["neural", "mesh", str(junk), "-o", str(tmp_path / "a.stl")], "not a splinekit neural model"),
        (["neural", "mesh", str(tmp_path / "none.nsdf"), "-o", str(tmp_path / "a.stl")], "does not exist"),
        (["neural", "mesh", str(junk), "-o", str(tmp_path / "a.txt")], "must end in"),
        (["neural", "fit", "vase", "-o", str(tmp_path / "a.npz")], "must end in .nsdf"),
        (["neural", "fit", "vase", "-o", str(tmp_path / "a.nsdf"), "--steps", "0"], "--steps"),
    ]
    for args, text in cases:
        status, out, err = _cli(args, capsys)
        assert status == 1 and text in err and len(err.strip().splitlines()) == 1, (args, err)
    assert sorted(os.listdir(tmp_path)) == ["junk.nsdf"]


@pytest.mark.slow
def test_cli_fits_a_model_and_meshes_it(tmp_path, capsys):
    model, stl = tmp_path / "vase.nsdf", tmp_path / "vase.stl"
    status, out, err = _cli(["neural", "fit", "vase", "--set", "wall=6", "-o", str(model), "--steps", "300"], capsys)
    assert status == 0, err
    assert "final loss" in out and NeuralSDF.load(model).info["steps"] == 300
    status, out, err = _cli(["neural", "mesh", str(model), "-o", str(stl)], capsys)
    assert status == 0 and "genus" in out, err
