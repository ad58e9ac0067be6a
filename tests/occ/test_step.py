"""Exact STEP export / import (``exporters.step``).

* Round trips splinekit -> STEP -> splinekit keep degrees and knot counts
  exactly and knots, control points and weights to 1e-12 relative: the
  writer prints 16 significant digits, so the only loss is one rounding of
  each number to 16 digits (at most ~5e-16 relative).
* The file is checked with readers other than ``import_step``: build123d's
  ``import_step`` (face, solid and volume counts, BRepCheck validity, volume
  against the closed form) and the file text (units, product names).
* File handling: an existing target survives a failed write byte for byte and
  no temporary file is left; unwritable targets raise ExportError; missing or
  malformed files raise FileFormatError.
"""

from __future__ import annotations

import math
import os
import re

import numpy as np
import pytest
from _geometry import random_curve_data, random_surface_data
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_occ_topology import box_patches, sphere_octants

import splinekit as sk
from exporters import step as step_module
from exporters.step import StepItem, export_step, import_step
from splinekit.errors import ExportError, FileFormatError, ParameterError

ROUND_TRIP_TOL = 1e-12
RATIONAL = pytest.mark.parametrize("rational", [False, True], ids=["poly", "rational"])


def random_surface(rng, rational):
    pu, pv, ku, kv, P, W = random_surface_data(rng, rational)
    return sk.NurbsSurface(pu, pv, ku, kv, P, W) if rational else sk.BSplineSurface(pu, pv, ku, kv, P)


def random_curve(rng, rational):
    p, U, P, W = random_curve_data(rng, rational)
    return sk.NurbsCurve(p, U, P, W) if rational else sk.BSplineCurve(p, U, P)


def assert_same_surface(ours, back, what):
    assert type(back) is type(ours), what
    assert (back.degree_u, back.degree_v) == (ours.degree_u, ours.degree_v), what
    for k0, k1 in ((ours.knots_u, back.knots_u), (ours.knots_v, back.knots_v)):
        assert k0.shape == k1.shape, what
        assert np.abs(k0 - k1).max() <= ROUND_TRIP_TOL * max(1.0, np.abs(k0).max()), what
    net = max(1.0, np.abs(ours.control_points).max())
    assert np.abs(ours.control_points - back.control_points).max() <= ROUND_TRIP_TOL * net, what
    if ours.weights is not None:
        assert np.abs(ours.weights - back.weights).max() <= ROUND_TRIP_TOL * ours.weights.max(), what


def assert_same_curve(ours, back, what):
    assert type(back) is type(ours), what
    assert back.degree == ours.degree, what
    assert back.knots.shape == ours.knots.shape, what
    assert np.abs(back.knots - ours.knots).max() <= ROUND_TRIP_TOL * max(1.0, np.abs(ours.knots).max()), what
    net = max(1.0, np.abs(ours.control_points).max())
    assert np.abs(ours.control_points - back.control_points).max() <= ROUND_TRIP_TOL * net, what
    if ours.weights is not None:
        assert np.abs(ours.weights - back.weights).max() <= ROUND_TRIP_TOL * ours.weights.max(), what


# ----------------------------------------------------------------------------------------
# exact round trips


@RATIONAL
@pytest.mark.parametrize("seed", range(3))
def test_round_trip_is_exact(tmp_path, seed, rational):
    rng = np.random.default_rng([601, seed, rational])
    surfaces = [random_surface(rng, rational) for _ in range(8)]
    curves = [random_curve(rng, rational) for _ in range(8)]
    names = [f"surface {i}" for i in range(8)] + [f"curve {i}" for i in range(8)]
    path = tmp_path / "round.step"
    assert export_step(path, surfaces + curves, names=names) == str(path)
    items = import_step(path, surfaces=True)
    assert all(isinstance(it, StepItem) for it in items)
    assert [it.name for it in items] == names
    for i, (ours, (name, back)) in enumerate(zip(surfaces + curves, items)):
        what = f"seed {seed} object {i} ({name})"
        if i < 8:
            assert_same_surface(ours, back, what)
        else:
            assert_same_curve(ours, back, what)


def test_unnamed_objects_keep_their_order_and_curves(tmp_path):
    # unnamed neighbours share one STEP product; the geometry and its order must not change
    rng = np.random.default_rng(604)
    s0, s1 = random_surface(rng, False), random_surface(rng, True)
    c0, c1 = random_curve(rng, True), random_curve(rng, False)
    path = tmp_path / "mixed.step"
    export_step(path, [s0, c0, box_patches(), s1, c1], names=[None, None, "box", None, None])
    items = import_step(path, surfaces=True)
    assert [it.name for it in items][2:8] == ["box"] * 6
    assert len(items) == 10
    assert_same_surface(s0, items[0].geometry, "s0")
    assert_same_curve(c0, items[1].geometry, "c0")
    assert_same_surface(s1, items[8].geometry, "s1")
    assert_same_curve(c1, items[9].geometry, "c1")


def test_round_trip_keeps_extreme_values(tmp_path):
    # 3-digit exponents and exact zeros go through the writer's fixed-size number buffer
    P = np.array([[[1e-200, -3e150, 0.0], [1.0, 2.0, 3.0]], [[-1e-5, 123456.789, 7e101], [0.1, 0.2, 0.3]]])
    surf = sk.NurbsSurface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1], P, [[1.0, 0.5], [2.0, 1e-3]])
    export_step(tmp_path / "x.step", surf)
    (item,) = import_step(tmp_path / "x.step", surfaces=True)
    rel = np.abs(item.geometry.control_points - P) / np.maximum(np.abs(P), 1e-300)
    assert rel.max() <= 1e-15
    assert np.abs(item.geometry.weights - surf.weights).max() <= 1e-15


def test_bezier_geometry_round_trips_as_the_same_shape(tmp_path):
    rng = np.random.default_rng(602)
    bez = sk.BezierSurface(rng.uniform(-1, 1, (4, 3, 3)), rng.uniform(0.5, 2, (4, 3)))
    export_step(tmp_path / "b.step", [bez])
    (item,) = import_step(tmp_path / "b.step", surfaces=True)
    u, v = rng.uniform(0, 1, (2, 50))
    assert np.abs(item.geometry.evaluate(u, v) - bez.evaluate(u, v)).max() < 1e-13


# ----------------------------------------------------------------------------------------
# the file as other readers see it


def test_closed_bodies_open_in_build123d(tmp_path):
    import build123d as bd

    r = 1.5
    path = tmp_path / "bodies.step"
    rng = np.random.default_rng(603)
    export_step(path, [sphere_octants(r), box_patches(2.0, 1.0, 0.5), random_surface(rng, True)], names=["ball", "brick", "sheet"])
    shape = bd.import_step(str(path))
    assert len(shape.faces()) == 8 + 6 + 1
    solids = shape.solids()
    assert len(solids) == 2 and all(s.is_valid for s in solids)
    volumes = sorted(s.volume for s in solids)
    assert volumes[0] == pytest.approx(1.0, rel=1e-6)
    assert volumes[1] == pytest.approx(4.0 / 3.0 * math.pi * r**3, rel=1e-6)
    # and import_step gives one item per face, named after its body
    names = [it.name for it in import_step(path, surfaces=True)]
    assert names == ["ball"] * 8 + ["brick"] * 6 + ["sheet"]


def test_names_survive_a_round_trip(tmp_path):
    patches = box_patches()[:4]
    names = ["plain", "with 'quotes', commas; (parens)", "Ünï \\ näme", "emoji 😀"]
    path = tmp_path / "names.step"
    export_step(path, patches, names=names)
    text = path.read_bytes()
    assert text.isascii()  # non-ASCII characters are written as STEP \X2\ / \X4\ escapes
    assert b"PRODUCT('plain'" in text
    assert [it.name for it in import_step(path, surfaces=True)] == names


NAME_TEXT = st.text(st.characters(blacklist_categories=("Cc", "Cs")), min_size=1, max_size=40)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(name=NAME_TEXT)
def test_any_printable_name_survives_or_is_refused(tmp_path, name):
    path = tmp_path / "name.step"
    try:
        export_step(path, box_patches()[0], names=[name])
    except ParameterError as exc:
        # only names whose escaped STEP form is too long for one line are refused
        assert len(step_module._step_string(name)) > step_module._MAX_ESCAPED_NAME, str(exc)
        return
    assert [it.name for it in import_step(path, surfaces=True)] == [name]


def test_units_are_declared_and_converted(tmp_path):
    patch = box_patches(1.0, 2.0, 3.0)[1]
    export_step(tmp_path / "mm.step", patch)
    export_step(tmp_path / "m.step", patch, unit="m")
    assert "SI_UNIT(.MILLI.,.METRE.)" in (tmp_path / "mm.step").read_text()
    m_text = (tmp_path / "m.step").read_text()
    assert "SI_UNIT($,.METRE.)" in m_text and ".MILLI." not in m_text
    P = patch.control_points
    # coordinates are written as given, in the declared unit
    assert np.array_equal(import_step(tmp_path / "mm.step", surfaces=True)[0].geometry.control_points, P)
    assert np.array_equal(import_step(tmp_path / "m.step", unit="m", surfaces=True)[0].geometry.control_points, P)
    # and converted when read in another unit
    assert np.allclose(import_step(tmp_path / "m.step", surfaces=True)[0].geometry.control_points, 1000 * P, rtol=1e-15, atol=0)
    assert np.allclose(import_step(tmp_path / "mm.step", unit="m", surfaces=True)[0].geometry.control_points, P / 1000, rtol=1e-15, atol=0)


def test_occ_and_build123d_shapes_export_as_they_are(tmp_path):
    import build123d as bd

    path = tmp_path / "mixed.step"
    export_step(path, [bd.Box(1, 2, 3), sk.occ.to_shape(box_patches()[0])], names=["b123d box", "face"])
    items = import_step(path, surfaces=True)
    assert [it.name for it in items] == ["b123d box"] * 6 + ["face"]
    box = bd.import_step(str(path)).solids()
    assert len(box) == 1 and box[0].volume == pytest.approx(6.0, rel=1e-9)


def test_import_walks_assemblies_with_their_placements(tmp_path):
    import build123d as bd

    cube = bd.Box(1, 1, 1)
    cube.label = "cube"
    ball = bd.Pos(10, 0, 0) * bd.Sphere(1)
    ball.label = "ball"
    lifted = bd.Pos(0, 0, 5) * bd.Compound(children=[bd.Box(1, 1, 1)], label="lifted")
    top = bd.Compound(children=[bd.Compound(children=[cube, ball], label="inner"), lifted], label="top")
    path = tmp_path / "assembly.step"
    bd.export_step(top, str(path))
    items = import_step(path, surfaces=True)
    by_name = {}
    for name, g in items:
        by_name.setdefault(name, []).append(g)
    assert sorted((k, len(v)) for k, v in by_name.items()) == [("ball", 1), ("cube", 6), ("lifted", 6)]
    t = np.linspace(0, 1, 7)

    def sample(g):
        (u0, u1), (v0, v1) = g.domain
        uu, vv = np.meshgrid(u0 + t * (u1 - u0), v0 + t * (v1 - v0))
        return g.evaluate(uu.ravel(), vv.ravel())

    ball_pts = sample(by_name["ball"][0])
    assert np.abs(np.linalg.norm(ball_pts - [10, 0, 0], axis=1) - 1).max() < 1e-9
    for name, z in (("cube", 0.0), ("lifted", 5.0)):
        pts = np.concatenate([sample(g) for g in by_name[name]])
        assert np.allclose(pts.min(axis=0), [-0.5, -0.5, z - 0.5], atol=1e-9)
        assert np.allclose(pts.max(axis=0), [0.5, 0.5, z + 0.5], atol=1e-9)


def test_export_does_not_print_or_leak_settings(tmp_path, capfd):
    from OCP.Interface import Interface_Static

    before = Interface_Static.CVal_s("write.step.unit")
    export_step(tmp_path / "q.step", box_patches()[0], unit="inch")
    assert Interface_Static.CVal_s("write.step.unit") == before
    out, _ = capfd.readouterr()
    assert out == ""


# ----------------------------------------------------------------------------------------
# atomic writes and errors


def _only(path):
    return sorted(os.listdir(path))


@pytest.mark.parametrize("failure", ["status", "exception"])
def test_failed_write_leaves_the_target_untouched(tmp_path, monkeypatch, failure):
    from OCP.IFSelect import IFSelect_ReturnStatus

    target = tmp_path / "model.step"
    target.write_bytes(b"previous contents\n")

    def broken(writer, path):
        with open(path, "wb") as f:  # a partial file that must not survive
            f.write(b"ISO-10303-21;\nHEADER;")
        if failure == "exception":
            raise RuntimeError("disk on fire")
        return IFSelect_ReturnStatus.IFSelect_RetFail

    monkeypatch.setattr(step_module, "_write_step_file", broken)
    with pytest.raises(ExportError, match="model.step"):
        export_step(target, box_patches())
    assert target.read_bytes() == b"previous contents\n"
    assert _only(tmp_path) == ["model.step"]


def test_successful_write_replaces_the_target(tmp_path):
    target = tmp_path / "model.step"
    target.write_bytes(b"old")
    export_step(target, box_patches()[0])
    assert target.read_bytes().startswith(b"ISO-10303-21;")
    assert _only(tmp_path) == ["model.step"]


def test_unwritable_targets_raise_export_error(tmp_path):
    patch = box_patches()[0]
    with pytest.raises(ExportError, match="does not exist"):
        export_step(tmp_path / "no such folder" / "x.step", patch)
    (tmp_path / "plain_file").write_text("x")
    with pytest.raises(ExportError, match="plain_file"):
        export_step(tmp_path / "plain_file" / "x.step", patch)
    (tmp_path / "folder.step").mkdir()
    with pytest.raises(ExportError, match="is a folder"):
        export_step(tmp_path / "folder.step", patch)
    assert _only(tmp_path) == ["folder.step", "plain_file"]
    assert _only(tmp_path / "folder.step") == []


def test_bad_export_arguments(tmp_path):
    patch = box_patches()[0]
    with pytest.raises(ParameterError, match="unit must be one of"):
        export_step(tmp_path / "a.step", patch, unit="furlong")
    with pytest.raises(ParameterError, match="names has 1 entries but there are 2"):
        export_step(tmp_path / "a.step", [patch, patch], names=["one"])
    with pytest.raises(ParameterError, match=r"names\[1\]"):
        export_step(tmp_path / "a.step", [patch, patch], names=["one", 2])
    with pytest.raises(ParameterError, match=r"names\[0\] must be a non-empty"):
        export_step(tmp_path / "a.step", [patch], names=[""])
    with pytest.raises(ParameterError, match=r"control character U\+000A at position 3"):
        export_step(tmp_path / "a.step", [patch], names=["two\nlines"])
    with pytest.raises(ParameterError, match=r"names\[0\] = 'ÜÜÜ.* at most 64"):
        export_step(tmp_path / "a.step", [patch], names=["Ü" * 20])
    export_step(tmp_path / "long.step", [patch], names=["a" * 300])  # plain ASCII: any length
    assert import_step(tmp_path / "long.step", surfaces=True)[0].name == "a" * 300
    (tmp_path / "long.step").unlink()
    with pytest.raises(ParameterError, match="empty"):
        export_step(tmp_path / "a.step", [])
    with pytest.raises(ParameterError, match="dict"):
        export_step(tmp_path / "a.step", [{}])
    with pytest.raises(ParameterError, match="names must be a list.*int"):
        export_step(tmp_path / "a.step", [patch], names=3)
    for bad, match in ((None, "path must be a str.*NoneType"), (3, "path must be a str.*int"), ("", "path is empty")):
        with pytest.raises(ParameterError, match=match):
            export_step(bad, patch)
        with pytest.raises(ParameterError, match=match):
            import_step(bad)
    assert _only(tmp_path) == []


def test_bad_files_raise_file_format_error(tmp_path, capfd):
    with pytest.raises(FileFormatError, match="does not exist"):
        import_step(tmp_path / "missing.step")
    with pytest.raises(FileFormatError, match="not a file"):
        import_step(tmp_path)
    for name, content in [
        ("garbage.step", b"hello, I am not a STEP file\n"),
        ("empty.step", b""),
        ("binary.step", bytes(range(256)) * 4),
    ]:
        (tmp_path / name).write_bytes(content)
        with pytest.raises(FileFormatError, match=re.escape(name)):
            import_step(tmp_path / name)
    # a valid file cut in half
    export_step(tmp_path / "whole.step", box_patches())
    text = (tmp_path / "whole.step").read_bytes()
    (tmp_path / "half.step").write_bytes(text[: len(text) // 2])
    with pytest.raises(FileFormatError, match="half.step"):
        import_step(tmp_path / "half.step")
    with pytest.raises(ParameterError, match="unit"):
        import_step(tmp_path / "whole.step", unit="parsec")
    assert capfd.readouterr().out == ""  # OCC's parse errors reach the caller as exceptions, not prints
