"""Mass properties of trimmed faces, shells and solids against closed forms.

The bodies (tests/_brep_parts.py) are exact: spheres and tori by revolving rational arcs (poles
and seams included), tubes and a box with a through hole whose planar faces are trimmed by
circles (Green's theorem path), plates with elliptical holes. Every figure is checked against a
hand formula to 1e-10 relative; the error estimates must bracket the true error.
"""

from __future__ import annotations

import numpy as np
import pytest

from splinekit.brep import Shell, Solid, TrimmedFace
from splinekit.brep import integrate as integ
from splinekit.brep.mass import area_with_error, mass_properties, volume_with_error
from splinekit.errors import ParameterError

from _brep_parts import box_with_hole, plate_with_holes, sphere, torus, tube

PI = np.pi
REL = 1e-10


def close(value, exact, rel=REL):
    assert abs(value - exact) <= rel * abs(exact), (value, exact, (value - exact) / exact)


def test_kronrod_rule_is_the_7_15_pair():
    x, wk, wg = integ.kronrod15()
    g, w = np.polynomial.legendre.leggauss(7)
    gauss = wg != 0
    assert np.allclose(x[gauss], g, rtol=0, atol=1e-15) and np.allclose(wg[gauss], w, rtol=0, atol=1e-15)
    for degree in range(23):  # K15 is exact up to degree 3 * 7 + 1 = 22
        exact = 0.0 if degree % 2 else 2.0 / (degree + 1)
        assert abs(wk @ x**degree - exact) < 1e-15
    assert abs(wk @ x**24 - 2 / 25) > 1e-10  # ... and not beyond


def test_sphere_closed_forms():
    R, c = 2.0, np.array([3.0, -2.0, 5.0])
    mp = sphere(R, c).mass_properties()
    V = 4 / 3 * PI * R**3
    close(mp.area, 4 * PI * R**2)
    close(mp.volume, V)
    assert np.abs(mp.centroid - c).max() <= REL * R
    assert np.abs(mp.inertia - 0.4 * V * R**2 * np.eye(3)).max() <= REL * V * R**2
    assert mp.converged and mp.of == "volume" and mp.tolerance == 1e-10


def test_torus_closed_forms():
    R, r = 3.0, 1.0
    body = torus(R, r, center=(1.0, 2.0, -1.0))
    mp = body.mass_properties()
    m = 2 * PI**2 * R * r**2
    close(mp.area, 4 * PI**2 * R * r)
    close(mp.volume, m)
    assert np.abs(mp.centroid - [1.0, 2.0, -1.0]).max() <= REL * R
    expected = np.diag([R**2 / 2 + 5 / 8 * r**2, R**2 / 2 + 5 / 8 * r**2, R**2 + 3 / 4 * r**2]) * m
    assert np.abs(mp.inertia - expected).max() <= REL * m * R**2
    close(mp.principal_moments[2], m * (R**2 + 0.75 * r**2))
    assert abs(abs(mp.principal_axes[2, 2]) - 1.0) < 1e-12  # the z axis carries the largest moment


def test_cylinder_with_through_hole():
    Ro, Ri, h = 3.0, 1.0, 4.0
    body = tube(Ro, Ri, h)
    assert any(f.is_trimmed for f in body.faces)
    mp = body.mass_properties()
    m = PI * (Ro**2 - Ri**2) * h
    close(mp.volume, m)
    close(mp.area, 2 * PI * h * (Ro + Ri) + 2 * PI * (Ro**2 - Ri**2))
    assert np.abs(mp.centroid - [0, 0, h / 2]).max() <= REL * h
    k = Ro**2 + Ri**2
    expected = np.diag([(3 * k + h**2) / 12, (3 * k + h**2) / 12, k / 2]) * m
    assert np.abs(mp.inertia - expected).max() <= REL * m * h**2


def test_box_with_through_hole():
    a, r = 20.0, 4.0
    body = box_with_hole(a, r)
    V = a**3 - PI * r**2 * a
    close(body.volume(), V)
    close(body.area(), 6 * a**2 - 2 * PI * r**2 + 2 * PI * r * a)
    mp = body.mass_properties()
    izz = a**3 * (2 * a**2) / 12 - PI * r**2 * a * r**2 / 2
    ixx = a**3 * (2 * a**2) / 12 - PI * r**2 * a * (3 * r**2 + a**2) / 12
    assert np.abs(mp.inertia - np.diag([ixx, ixx, izz])).max() <= REL * izz
    assert np.abs(mp.centroid - a / 2).max() <= REL * a


def test_plate_with_holes_area_centroid_inertia():
    w, h = 10.0, 6.0
    holes = ((0.2, 0.3, 0.1), (0.7, 0.5, 0.15), (0.45, 0.75, 0.05))
    face = plate_with_holes(w, h, holes)
    areas = [w * h] + [-PI * r * w * r * h for _, _, r in holes]  # holes are ellipses in space
    centres = [(w / 2, h / 2)] + [(u * w, v * h) for u, v, _ in holes]
    A = sum(areas)
    mp = face.mass_properties()
    close(mp.area, A)
    assert mp.of == "area" and mp.volume is None
    c = sum(a * np.array(x) for a, x in zip(areas, centres)) / A
    assert np.abs(mp.centroid[:2] - c).max() <= REL * w and abs(mp.centroid[2]) <= REL * w
    # polar moment about the centroid: rectangle w h (w^2 + h^2) / 12 minus ellipses
    # pi a b (a^2 + b^2) / 4, each moved by the parallel axis theorem
    ixx = w * h * h**2 / 12 + w * h * (h / 2 - c[1]) ** 2
    iyy = w * h * w**2 / 12 + w * h * (w / 2 - c[0]) ** 2
    for u, v, r in holes:
        ea, eb = r * w, r * h
        m = PI * ea * eb
        ixx -= m * eb**2 / 4 + m * (v * h - c[1]) ** 2
        iyy -= m * ea**2 / 4 + m * (u * w - c[0]) ** 2
    close(mp.inertia[0, 0], ixx)
    close(mp.inertia[1, 1], iyy)
    close(mp.inertia[2, 2], ixx + iyy)


def test_error_estimate_brackets_the_true_error():
    R = 1.5
    exact_area, exact_volume = 4 * PI * R**2, 4 / 3 * PI * R**3
    for tol in (1e-3, 1e-5, 1e-7, 1e-9):
        body = sphere(R)  # fresh: results are cached per object and tolerance
        a, ea = area_with_error(body, tol)
        v, ev = volume_with_error(body, tol)
        assert abs(a - exact_area) <= ea <= tol * exact_area
        assert abs(v - exact_volume) <= ev <= tol * exact_volume
    face = plate_with_holes()
    for tol in (1e-4, 1e-8):
        a, ea = area_with_error(TrimmedFace(face.surface, face.loops), tol)
        exact = 60.0 - PI * 60.0 * (0.1**2 + 0.15**2 + 0.05**2)
        assert abs(a - exact) <= ea <= tol * exact


def test_orientation_and_voids():
    outer, inner = sphere(2.0), sphere(1.0)
    flipped = Shell([f.flipped() for f in inner.faces])
    assert np.isclose(Shell(inner.faces).volume(), -Shell(flipped.faces).volume(), rtol=1e-14)
    hollow = Solid([outer.outer_shell, flipped])
    close(hollow.volume(), 4 / 3 * PI * (8 - 1))
    close(hollow.area(), 4 * PI * (4 + 1))
    mp = hollow.mass_properties()
    close(mp.inertia[0, 0], 0.4 * 4 / 3 * PI * (2.0**5 - 1.0))


def test_tolerance_is_respected_and_checked():
    body = torus(3.0, 1.0)
    loose = mass_properties(body, 1e-4)
    assert loose.tolerance == 1e-4 and loose.evaluations <= body.mass_properties().evaluations
    assert abs(loose.volume - 2 * PI**2 * 3) <= loose.volume_error
    for bad in (0.0, -1e-6, float("nan"), 1e-20, "x"):
        with pytest.raises(ParameterError):
            body.area(tol=bad)


def test_rigid_motion_invariance():
    rng = np.random.default_rng(7)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    q[:, 0] *= np.sign(np.linalg.det(q))  # a rotation: a reflection would turn the faces inside out
    body = tube(2.0, 0.5, 3.0)
    moved = Solid(Shell([TrimmedFace(f.surface.transform(np.vstack([np.hstack([q, [[5.0], [-3.0], [1e3]]]), [0, 0, 0, 1]])),
                                     f.loops, f.reversed) for f in body.faces]))
    a, b = body.mass_properties(), moved.mass_properties()
    close(b.volume, a.volume, 1e-11)
    close(b.area, a.area, 1e-11)
    assert np.abs(b.principal_moments - a.principal_moments).max() <= 1e-10 * a.principal_moments.max()


def test_native_primitives_closed_forms():
    """The exact primitives of splinekit.brep.primitives (trimmed planar caps, seams, poles,
    an apex) against hand formulas: volume, area, centroid and the axial moment."""
    from splinekit.brep import primitives as P

    axis = np.array([1.0, 2.0, 2.0]) / 3.0
    r1, r2, h = 3.0, 1.0, 5.0
    cases = [
        (P.box(2.0, 3.0, 5.0, origin=(1.0, -1.0, 2.0)), 30.0, 2 * (6 + 15 + 10), [2.0, 0.5, 4.5]),
        (P.cone(r1, r2, h, origin=(1.0, 1.0, 1.0), axis=axis), PI * h * (r1**2 + r1 * r2 + r2**2) / 3,
         PI * (r1**2 + r2**2) + PI * (r1 + r2) * np.hypot(r1 - r2, h),
         np.ones(3) + axis * h * (r1**2 + 2 * r1 * r2 + 3 * r2**2) / (4 * (r1**2 + r1 * r2 + r2**2))),
        (P.cone(2.0, 0.0, 3.0), PI * 4, PI * 4 + PI * 2 * np.hypot(2, 3), [0, 0, 0.75]),  # apex
        (P.cylinder(2.0, 3.0), PI * 12, 2 * PI * 4 + 2 * PI * 6, [0, 0, 1.5]),
        (P.sphere(2.0, (1.0, 0.0, -1.0)), 32 / 3 * PI, 16 * PI, [1.0, 0.0, -1.0]),
        (P.torus(4.0, 1.5), 2 * PI**2 * 4 * 2.25, 4 * PI**2 * 6, [0, 0, 0]),
        (P.box_with_hole(20.0, 4.0), 8000 - PI * 16 * 20, 2400 - 2 * PI * 16 + 2 * PI * 4 * 20, [0, 0, 0]),
        (P.plate_with_holes(10.0, 6.0, 2.0, [(3.0, 3.0, 1.0), (7.0, 2.0, 0.5)]),
         120 - PI * 2 * (1 + 0.25), 2 * (60 + 20 + 12) - 2 * PI * (1 + 0.25) + 2 * PI * 2 * (1 + 0.5),
         (np.array([5, 3, 1]) * 120 - PI * 2 * (np.array([3, 3, 1]) + 0.25 * np.array([7, 2, 1]))) / (120 - PI * 2.5)),
    ]
    for solid, volume, area, centre in cases:
        mp = solid.mass_properties()
        close(mp.volume, volume)
        close(mp.area, area)
        assert np.abs(mp.centroid - centre).max() <= REL * 20, (solid, mp.centroid, centre)
    # axial moment of the frustum: integral of pi r(z)^4 / 2 dz = pi h (r1^5 - r2^5) / (10 (r1 - r2))
    frustum = P.cone(r1, r2, h, axis=axis).inertia()
    close(axis @ frustum @ axis, PI * h * (r1**5 - r2**5) / (10 * (r1 - r2)))


def test_trims_outside_the_domain_are_refused():
    from splinekit.errors import DomainError

    face = plate_with_holes()
    shifted = [[c.transform(np.array([[1.0, 0, 0], [0, 1.0, 1.0], [0, 0, 1]])) for c in (e.pcurve for e in loop)]
               for loop in face.loops]  # every trim moved up by one period in v
    with pytest.raises(DomainError, match="past the surface's domain"):
        TrimmedFace(face.surface, shifted).area()


@pytest.mark.parametrize("edge_tolerance, accepted", [(1e-2, True), (1e-7, False)])
def test_trims_a_little_past_the_domain_within_their_edge_tolerance_are_integrated(edge_tolerance, accepted):
    """CAD exports (the Inventor part of the shared STEP set) give B-spline faces trims that leave
    the surface's domain by 2e-3 of its width, 1.2e-2 in 3-D, with edge tolerances of 5.5e-3. Within
    a few edge tolerances the face is integrated over the surface's polynomial extension (as
    OpenCascade evaluates it); on a plane that extension is the plane itself, so the area is the
    trim polygon's, exactly. Far past the edges' tolerance it is refused."""
    from splinekit.construct import line
    from splinekit.brep import Edge
    from splinekit.errors import DomainError
    from splinekit.surfaces import BSplineSurface

    a = 10.0
    plane = BSplineSurface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1], np.array([[[0, 0, 0], [0, a, 0]], [[a, 0, 0], [a, a, 0]]], float))
    over = 1.002  # 0.02 past u = 1 in 3-D: two edge tolerances of 1e-2
    # a rectangle (the tensor rule) and a pentagon (Green's theorem along the trims)
    for pts in ([(0.1, 0.1), (over, 0.1), (over, 0.9), (0.1, 0.9)], [(0.1, 0.1), (over, 0.1), (over, 0.9), (0.5, 0.95), (0.1, 0.9)]):
        loop = [Edge(line(pts[k], pts[(k + 1) % len(pts)]), tolerance=edge_tolerance) for k in range(len(pts))]
        face = TrimmedFace(plane, [loop], tolerance=min(edge_tolerance, 1e-3))
        x, y = np.array(pts).T
        exact = 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)) * a * a  # shoelace
        if accepted:
            assert face.area() == pytest.approx(exact, rel=1e-13)
        else:
            with pytest.raises(DomainError, match="past the surface's domain"):
                face.area()


@pytest.mark.parametrize("tol", [1e-6, 1e-10, 1e-12])
def test_a_disc_tangent_to_the_domain_sides_has_its_exact_area_at_every_tolerance(tol):
    """The Inventor part's annular plane faces: a circle trim touching all four sides of the
    plane's domain, its extremes between samples. Green's inner integral started at the leftmost
    sample and clipped the nodes beyond it, which cut 6e-6 off the disc, and only at tight
    tolerances (where nodes come near the extremes): the area must be pi R^2 at every tolerance."""
    from splinekit.construct import arc
    from splinekit.surfaces import BSplineSurface

    R = 48.41875
    plane = BSplineSurface(1, 1, [-R, -R, R, R], [-R, -R, R, R],
                           np.array([[[-R, -R, 0], [-R, R, 0]], [[R, -R, 0], [R, R, 0]]], float))
    disc = TrimmedFace(plane, [[arc((0.0, 0.0), None, R, 0.3, 0.3 + 2 * np.pi)]])
    assert disc.area(tol) == pytest.approx(np.pi * R * R, rel=max(tol, 1e-13))
