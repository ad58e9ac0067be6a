"""``splinekit check``'s genus measure on solids whose topology is known: a sphere (genus 0), a
torus (1) and a box with a through hole (1).

OCC's ``V - E + F`` of these shapes is 0, 0 and 2 (a sphere's and a cylinder wall's faces are
closed on themselves), which the former ``(2 - chi) / 2`` read as genus 1, 1 and 0; the measure
now comes from the watertight tessellation. Each model states its genus as a check, and a wrong
statement must fail, so the measure is seen to be compared.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import pytest

import splinekit as sk
from splinekit.cli.check import check_model
from splinekit.cli.console import Console
from splinekit.mesh import primitives

bd = pytest.importorskip("build123d")
from splinekit.interop.occ_brep_read import brep_from_shape  # noqa: E402  (needs OCP, as build123d)


def _registry(model):
    """A one-model registry in the shape ``check_model`` reads (no parameters)."""
    return SimpleNamespace(get_model=lambda name: SimpleNamespace(PARAMETERS=()),
                           build_model=lambda name, **values: model)


def _model(name, *, solids=(), bodies=(), mesh=None, checks):
    return SimpleNamespace(name=name, params={}, bodies=list(bodies), body_names=[], mesh=mesh, closed=True,
                           checks=checks, solids=list(solids))


def _check(model, capsys) -> tuple[int, str]:
    failed = check_model(_registry(model), model.name, [], Console())
    return failed, capsys.readouterr().out


def _genus_row(out: str) -> str:
    rows = [line for line in out.splitlines() if line.lstrip().startswith("genus")]
    assert len(rows) == 1, out
    return rows[0]


SHAPES = {
    "sphere": (lambda: bd.Sphere(10), 0),
    "torus": (lambda: bd.Torus(10, 3), 1),
    "box with a hole": (lambda: bd.Box(20, 20, 10) - bd.Cylinder(4, 10), 1),
}


@pytest.mark.parametrize("name", SHAPES)
def test_genus_of_occ_solids(capsys, name):
    build, expected = SHAPES[name]
    (solid,) = brep_from_shape(build().wrapped)
    assert solid.genus == expected  # splinekit's B-rep topology agrees: the shape is what it claims
    # only the genus row is judged here: the other rows compare areas and volumes with OCC
    failed, out = _check(_model(name, solids=[solid], checks={"genus": (expected, 0)}), capsys)
    assert "PASS" in _genus_row(out) and "tessellation genus" in _genus_row(out), out
    failed_wrong, out = _check(_model(name, solids=[solid], checks={"genus": (expected + 1, 0)}), capsys)
    assert failed_wrong == failed + 1 and "FAIL" in _genus_row(out), out


def test_genus_of_patch_bodies_sewn_by_occ(capsys):
    """A one-patch NURBS sphere and a revolved torus, sewn by OCC (the bodies path)."""
    sphere = sk.revolve(sk.arc([0, 0, 0], [0, -1, 0], 5.0, -math.pi / 2, math.pi / 2, x_axis=[1, 0, 0]),
                        [0, 0, 0], [0, 0, 1])
    tube = sk.revolve(sk.arc([10, 0, 0], [0, -1, 0], 2.0, 0.0, 2 * math.pi, x_axis=[1, 0, 0]), [0, 0, 0], [0, 0, 1])
    for body, expected in (([sphere], 0), ([tube], 1)):
        _, out = _check(_model("body", bodies=[body], checks={"genus": (expected, 0)}), capsys)
        assert "PASS" in _genus_row(out), out
    # two pieces: handles add up
    _, out = _check(_model("two", bodies=[[sphere], [tube]], checks={"genus": (1, 0)}), capsys)
    assert "PASS" in _genus_row(out), out


def test_genus_of_a_mesh_model(capsys):
    _, out = _check(_model("mesh", mesh=primitives.torus(16, 8), checks={"genus": (1, 0)}), capsys)
    assert "PASS" in _genus_row(out), out
