"""The fifteen STEP files written by other CAD systems (../shared/data/step, skipped when absent),
read with ``exporters.import_step``: every solid passes splinekit's own checks (``check()``),
tessellates closed, and its volume agrees with OCC's reference figures (reference.json).

OCC calls every one of these files valid, so a problem found here is a defect of the conversion
(or a property of the file OCC's checker does not look at: see ``_ACCEPTED``). Four small files
run by default; the rest with ``-m slow``.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

pytest.importorskip("OCP")

import splinekit as sk  # noqa: E402
from exporters import import_step  # noqa: E402
from splinekit.brep import Solid  # noqa: E402

STEP_DIR = Path(__file__).resolve().parents[2] / ".." / "shared" / "data" / "step"

_QUICK = {"sw2013_two_spheres.stp", "ug19_io1_analytic.stp", "catiav4_4solids_sphere_torus_cone.stp",
          "euclid_screw.step"}

# Problems that are in the file itself, not made by the conversion.
# onshape_abc_0_13: four B-spline faces (3, 4, 13, 65; their surfaces and pcurves are read exactly,
# not re-approximated) are slivers in which two consecutive edges run alongside each other,
# 1e-4 to 5e-4 apart in space over most of their length, while the file gives those edges
# tolerances of 2e-3 to 1e-2: the two edges touch within their own tolerance, and the loop
# "touches itself" at the face's 1e-7 tolerance. OCC's checker does not test that.
# inventor2013_part_11752: four bicubic B-spline faces (492, 555, 769, 837, read exactly) have a
# pcurve that leaves the surface's u-domain by 1.6e-3, 1.16e-2 in space, while the file gives those
# edges a tolerance of 5.5e-3: 2.1 edge tolerances past the face, where the check allows 2. OCC's
# checker does not test it; the integrator takes the polynomial extension there, as OCC does.
_ACCEPTED = {"onshape_abc_0_13.step": {("self-intersecting-loop", 3), ("self-intersecting-loop", 4),
                                       ("self-intersecting-loop", 13), ("self-intersecting-loop", 65)},
             "inventor2013_part_11752.stp": {("trim-outside-domain", 492), ("trim-outside-domain", 555),
                                             ("trim-outside-domain", 769), ("trim-outside-domain", 837)}}
# Every file meshes closed. The Onshape part's sliver faces and the Inventor part's face 504 (edges
# up to 1.7e-2 off it, their tolerance) have trims that cross in (u, v): the tessellator moves them
# apart in (u, v) within their edges' tolerance (splinekit.tessellation.untangle).


# Every file now runs to the end under -m slow (the SolidWorks multibody part, which once grew to
# 15 GB in the check, takes 1.8 GB and about 6 minutes on a loaded 2-core machine).
_UNVERIFIED: dict[str, str] = {}


def _cases():
    path = STEP_DIR / "reference.json"
    if not path.exists():
        return [pytest.param(None, None, marks=pytest.mark.skip(reason=f"{STEP_DIR} is absent"))]
    ref = json.loads(path.read_text())
    return [pytest.param(n, r, id=n, marks=() if n in _QUICK else pytest.mark.slow) for n, r in sorted(ref.items())]


@pytest.fixture(scope="module")
def imported():
    """One import per file, shared by the tests of this module."""
    cache = {}

    def get(name):
        if name not in cache:
            items = import_step(STEP_DIR / name)
            cache[name] = [it.geometry for it in items if isinstance(it.geometry, Solid)]
        return cache[name]

    return get


def _skip_unless_selected(name, request):
    if name in _UNVERIFIED:
        pytest.skip(_UNVERIFIED[name])
    if name not in _QUICK:
        expr = request.config.getoption("markexpr") or ""
        if "slow" not in expr or "not slow" in expr:
            pytest.skip("slow: run with -m slow")


@pytest.mark.parametrize("name, ref", _cases())
def test_foreign_step_solids_pass_native_checks(name, ref, imported, request):
    _skip_unless_selected(name, request)
    solids = imported(name)
    assert len(solids) == ref["solids"]
    assert sum(len(s.faces) for s in solids) == ref["faces"]
    accepted = _ACCEPTED.get(name, set())
    problems = [p for s in solids for p in s.check() if (p.kind, p.face) not in accepted]
    assert not problems, "\n".join(p.message for p in problems[:10])


@pytest.mark.parametrize("name, ref", _cases())
def test_foreign_step_solids_tessellate_closed(name, ref, imported, request):
    _skip_unless_selected(name, request)
    tol = 1e-3
    volume = 0.0
    for i, solid in enumerate(imported(name)):
        mesh = sk.tessellate(solid, tol)
        assert mesh.is_closed, f"solid {i}"
        assert mesh.volume > 0, f"solid {i} faces inward"
        volume += mesh.volume
    # within the bound the tolerance implies (the area times the tolerance) of OCC's volume; where
    # the file's own edge tolerances are larger (NX part: edges up to 3.4e-2 off their faces), the
    # boundary vertices lie that far off and the mesh cannot be closer: area times both
    edge_tol = max(e.tolerance for s in imported(name) for f in s.faces for e in f.edges)
    expected = ref.get("volume_best", ref["volume"])
    bound = ref.get("area_best", ref["area"]) * (tol + (edge_tol if edge_tol > tol else 0.0))
    assert abs(volume - expected) <= bound, (volume, expected, bound)


@pytest.mark.parametrize("name, ref", _cases())
def test_foreign_step_volumes_match_occ(name, ref, imported, request):
    _skip_unless_selected(name, request)
    volume = sum(s.volume(1e-9) for s in imported(name))
    # MANIFEST.md: OCC's raw figure is wrong on the Pro/E part, which carries a `volume_best`;
    # GProp drifts by up to 4e-5 on the unstable files; where the NURBS conversion approximates
    # (revolutions), OCC's own figure on the converted shape moves: allow twice that move
    expected = ref.get("volume_best", ref["volume"])
    rel = 1e-6 if ref.get("gprop_stable") else 1e-4
    moved = abs(ref.get("volume_nurbs_eps1e9", expected) - expected) / abs(expected)
    assert abs(volume - expected) <= (rel + 2 * moved) * abs(expected), (volume, expected)
