"""Zebra, isophote, curvature and draft-angle maps against closed forms.

The expected values come from the vertex *positions* (a cylinder's polar angle, a sphere's
radius, a frustum's taper), never from the normals the maps themselves use, so a wrong normal,
orientation or formula shows up.
"""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

import splinekit as sk
from splinekit.analysis import (
    SampledPart,
    curvature_map,
    draft_angle,
    isophotes,
    render_curvature_comb,
    sample_part,
    zebra,
)
from splinekit.brep import primitives
from splinekit.errors import ParameterError, SplineKitError
from splinekit.mesh import primitives as mesh_primitives


def plane(normal_tilt=0.0):
    """A bilinear plane patch z = tilt * x over [0, 1]^2 (unit normal (-tilt, 0, 1) / norm)."""
    cp = np.array([[[0, 0, 0], [0, 1, 0]], [[1, 0, normal_tilt], [1, 1, normal_tilt]]], dtype=float)
    return sk.BSplineSurface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1], cp)


@pytest.fixture(scope="module")
def cylinder():
    return sample_part(primitives.cylinder(1.5, 2.0))


def side_of(part: SampledPart):
    """Vertices on the curved side of a cylinder or frustum about z (normal not along z)."""
    return np.abs(part.normals[:, 2]) < 1 - 1e-9


def wrapped(a):
    return np.angle(np.exp(1j * a))


# -- zebra -------------------------------------------------------------------------------------------
def test_zebra_on_a_plane_is_constant():
    m = zebra(plane(0.3), view=(40.0, 10.0))
    assert np.ptp(m.values) < 1e-12
    assert len(np.unique(m.options["stripe"])) == 1


def test_zebra_on_a_cylinder_is_twice_the_polar_angle(cylinder):
    # seen from +x (elevation 0, azimuth 0) with bands along the axis z: the view direction
    # (-1, 0, 0) reflected by the normal (cos t, sin t, 0) is (cos 2t, sin 2t, 0)
    m = zebra(cylinder, view=(0.0, 0.0), axis=(0, 0, 1), stripes=12)
    side = side_of(m.part)
    t = np.arctan2(m.part.points[side, 1], m.part.points[side, 0])
    assert np.abs(wrapped(m.values[side] - 2 * t)).max() < 1e-9
    # white stripes are centred on the reflection back to the viewer: round(2t / (pi / 12)) even
    k = np.round(wrapped(2 * t) / (np.pi / 12))
    clear = np.abs(wrapped(2 * t) / (np.pi / 12) - k) < 0.45  # away from stripe borders
    assert np.array_equal(m.options["stripe"][side][clear], (k[clear] % 2 == 0).astype(np.int8))


def test_zebra_does_not_depend_on_the_normals_orientation():
    a = zebra(plane(0.2), view=(30.0, 20.0))
    b = zebra(plane(0.2).reverse("u"), view=(30.0, 20.0))
    assert abs(a.values[0] - b.values[0]) < 1e-12


# -- isophotes ---------------------------------------------------------------------------------------
def test_isophotes_on_a_plane_are_constant():
    m = isophotes(plane(0.5), (0.3, -0.2, 1.0), step=15)
    expected = np.degrees(np.arccos(np.dot([-0.5, 0, 1] / np.sqrt(1.25), np.array([0.3, -0.2, 1.0]) / np.sqrt(1.13))))
    assert np.abs(m.values - expected).max() < 1e-9
    assert len(np.unique(m.options["band"])) == 1


def test_isophotes_on_a_cylinder_are_the_polar_angle(cylinder):
    m = isophotes(cylinder, (1, 0, 0), step=10)
    side = side_of(m.part)
    t = np.arctan2(m.part.points[side, 1], m.part.points[side, 0])
    assert np.abs(m.values[side] - np.degrees(np.abs(t))).max() < 1e-7
    assert np.array_equal(m.options["band"], np.floor(m.values / 10).astype(np.int64))


# -- curvature ---------------------------------------------------------------------------------------
def test_curvature_maps_of_a_sphere_and_a_cylinder(cylinder):
    r = 2.5
    sphere = sample_part(primitives.sphere(r))
    K = curvature_map(sphere, "gaussian").values
    H = curvature_map(sphere, "mean").values
    assert np.allclose(K, 1 / r**2, rtol=1e-7, atol=0)
    assert np.allclose(H, -1 / r, rtol=1e-7, atol=0)  # outward normals: H = -1/r
    assert np.allclose(np.linalg.norm(sphere.points, axis=1), r, rtol=1e-12)
    side = side_of(cylinder)
    R = np.hypot(cylinder.points[side, 0], cylinder.points[side, 1])
    assert np.allclose(R, 1.5, rtol=1e-12)
    assert np.abs(curvature_map(cylinder, "gaussian").values[side]).max() < 1e-9
    assert np.allclose(curvature_map(cylinder, "mean").values[side], -1 / (2 * 1.5), rtol=1e-9)
    assert np.abs(curvature_map(cylinder, "max").values[side]).max() < 1e-9
    assert np.allclose(curvature_map(cylinder, "min").values[side], -1 / 1.5, rtol=1e-9)


def test_poles_are_reported_not_nan():
    sphere = sample_part(primitives.sphere(1.0))
    assert sphere.degenerate.any()  # the two poles of the revolved patch
    for field in (sphere.normals, sphere.gaussian, sphere.mean, sphere.k1, sphere.k2):
        assert np.isfinite(field).all()
    poles = sphere.degenerate
    assert np.allclose(np.abs(sphere.normals[poles, 2]), 1.0, atol=1e-6)
    assert np.allclose(sphere.gaussian[poles], 1.0, rtol=1e-4)


def test_a_mesh_uses_its_discrete_curvature():
    mesh = mesh_primitives.icosphere(3, radius=2.0)
    m = curvature_map(mesh, "gaussian")
    assert not m.part.exact
    assert np.median(m.values) == pytest.approx(0.25, rel=0.05)
    assert np.median(curvature_map(mesh, "mean").values) == pytest.approx(-0.5, rel=0.05)


# -- draft -------------------------------------------------------------------------------------------
def test_draft_of_a_box_sides_zero_top_ninety_bottom_undercut():
    m = draft_angle(primitives.box(2, 3, 4), (0, 0, 1), min_draft=1.0)
    z = m.part.points[:, 2]
    n = m.part.normals
    side = np.abs(n[:, 2]) < 0.5
    top = n[:, 2] > 0.5
    bottom = n[:, 2] < -0.5
    assert np.abs(m.values[side]).max() < 1e-9
    assert np.allclose(m.values[top], 90.0) and np.allclose(z[top], 4.0)
    assert np.allclose(m.values[bottom], -90.0) and np.allclose(z[bottom], 0.0)
    assert np.array_equal(m.undercut, bottom)
    assert np.array_equal(m.insufficient, side)  # vertical walls have no draft


@pytest.mark.parametrize("r1, r2", [(2.0, 1.0), (1.0, 2.0)])
def test_draft_of_a_tapered_extrusion_is_its_taper(r1, r2):
    h = 3.0
    taper = np.degrees(np.arctan((r1 - r2) / h))  # from the frustum's dimensions
    m = draft_angle(primitives.cone(r1, r2, h), (0, 0, 1), min_draft=abs(taper) + 1)
    side = side_of(m.part)
    assert np.allclose(m.values[side], taper, atol=1e-9)
    assert m.undercut[side].all() == (taper < 0)
    assert m.insufficient[side].all() == (taper > 0)


def test_draft_with_a_sideways_pull_and_unnormalized_direction():
    m = draft_angle(primitives.box(1, 1, 1), (0, 5, 0))
    n = m.part.normals
    assert np.allclose(m.values[n[:, 1] > 0.5], 90.0)
    assert np.allclose(m.values[n[:, 2] > 0.5], 0.0, atol=1e-9)


def test_an_open_part_with_inward_patches_is_turned_outward():
    # the sphere's revolved patch reversed (inward normals): the part encloses a volume, so it faces out
    sphere = sk.revolve(sk.arc([0, 0, 0], [0, -1, 0], 1.0, -np.pi / 2, np.pi / 2, x_axis=[1, 0, 0]), [0, 0, 0], [0, 0, 1])
    for surface in (sphere, sphere.reverse("u")):
        part = sample_part(surface)
        outward = np.einsum("ij,ij->i", part.normals, part.points)
        assert (outward > 0.99).all()
        assert np.allclose(part.mean, -1.0, rtol=1e-7)


# -- pictures ----------------------------------------------------------------------------------------
def test_pictures_are_written_with_the_asked_size(tmp_path, cylinder):
    maps = [zebra(cylinder, view=(0.0, 0.0), axis=(0, 0, 1)), isophotes(cylinder, (1, 0, 0)),
            curvature_map(cylinder, "mean"), curvature_map(cylinder, "max", scale="symlog"),
            draft_angle(primitives.cone(2.0, 1.0, 3.0), min_draft=20)]
    for i, m in enumerate(maps):
        path = m.render(tmp_path / f"m{i}.png", size=(320, 240))
        with Image.open(path) as image:
            assert image.size == (320, 240)
    # the zebra of a cylinder seen across its axis shows both stripe colours, in quantity
    with Image.open(tmp_path / "m0.png") as image:
        grey = np.asarray(image.convert("L"), dtype=float)
    assert (grey < 40).mean() > 0.05 and (grey > 215).mean() > 0.05


def test_a_zebra_map_refuses_another_view(tmp_path):
    m = zebra(plane(), view=(10.0, 20.0))
    with pytest.raises(ParameterError, match="view"):
        m.render(tmp_path / "z.png", view=(30.0, 20.0))


# -- bad input ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("call, fragment", [
    (lambda: draft_angle(plane(), (0, 0, 0)), "zero length"),
    (lambda: draft_angle(plane(), (0, np.nan, 1)), "not finite"),
    (lambda: draft_angle(plane(), (0, 1)), "three numbers"),
    (lambda: draft_angle(plane(), min_draft=90), "min_draft"),
    (lambda: isophotes(plane(), (0.0, 0.0, 0.0)), "zero length"),
    (lambda: isophotes(plane(), step=0), "step"),
    (lambda: zebra(plane(), axis=(0, 0, 0)), "zero length"),
    (lambda: zebra(plane(), stripes=0), "stripes"),
    (lambda: zebra(plane(), view=(np.inf, 0)), "view"),
    (lambda: curvature_map(plane(), "rainbow"), "kind"),
    (lambda: sample_part("teapot"), "cannot analyse"),
    (lambda: sample_part([]), "cannot analyse"),
])
def test_bad_input_names_the_problem(call, fragment):
    with pytest.raises(SplineKitError, match=fragment):
        call()


def test_a_box_mesh_is_split_at_its_edges():
    # a box given only as a mesh: each face keeps its own normal up to its edges
    m = draft_angle(mesh_primitives.box(2.0), (0, 0, 1))
    assert m.part.n_vertices == 24  # 8 corners x 3 faces
    z = m.part.points[:, 2]
    top, bottom = m.values > 45, m.values < -45
    assert np.allclose(m.values[top], 90) and np.allclose(z[top], 1.0)
    assert np.allclose(m.values[bottom], -90) and np.allclose(z[bottom], -1.0)
    assert np.abs(m.values[~top & ~bottom]).max() < 1e-9
    # a smooth mesh keeps its vertices
    sphere = mesh_primitives.icosphere(3)
    assert sample_part(sphere).n_vertices == sphere.n_vertices


def test_curvature_comb_picture_of_circles(tmp_path):
    # combs given by their closed form: a circle of radius r has curvature 1/r and teeth of
    # length scale/r pointing away from its centre
    from dataclasses import dataclass

    @dataclass
    class Comb:
        points: np.ndarray
        tips: np.ndarray
        curvature: np.ndarray

    t = np.linspace(0, 2 * np.pi, 100)
    combs = []
    for r, dim in ((1.0, 2), (2.0, 3)):
        ring = np.column_stack([r * np.cos(t), r * np.sin(t)] + ([np.zeros_like(t)] if dim == 3 else []))
        combs.append(Comb(ring, ring * (1 + 0.5 / r**2), np.full(len(t), 1 / r)))
    for item in (combs[0], combs):
        path = render_curvature_comb(item, tmp_path / "comb.png", size=(300, 240))
        with Image.open(path) as image:
            assert image.size == (300, 240)
    with pytest.raises(SplineKitError, match="tips"):
        render_curvature_comb([object()], tmp_path / "x.png")


@pytest.mark.parametrize("scheme, exact", [("catmull-clark", True), ("loop", False)])
def test_subdivision_limit_surfaces(scheme, exact):
    cage = mesh_primitives.box(2.0) if scheme == "catmull-clark" else mesh_primitives.icosphere(0)
    part = sample_part(sk.SubdivisionSurface(cage, scheme))
    assert part.exact == exact
    assert np.allclose(np.linalg.norm(part.normals, axis=1), 1.0)
    # a convex limit surface about the origin: outward normals, positive Gaussian curvature
    assert (np.einsum("ij,ij->i", part.normals, part.points) > 0).all()
    assert np.median(part.gaussian) > 0
