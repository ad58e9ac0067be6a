"""Mass properties of trimmed faces, shells and solids: area, volume, centroid, inertia.

Everything is an integral over the faces' trimmed (u, v) domains (:mod:`.integrate`), with the
area element ``|Su x Sv| du dv``. Volume integrals become surface integrals by the divergence
theorem over the oriented faces (outward normal ``sign * Su x Sv``, ``sign = -1`` for a reversed
face), with ``x`` measured from a reference point ``c`` (the centre of the control points'
bounding box, which keeps the sums free of cancellation for parts far from the origin):

- ``V = 1/3 closed integral of x . n dA`` (``div x = 3``),
- ``integral of x_i dV = 1/4 closed integral of x_i (x . n) dA`` (``div(x_i x) = 4 x_i``),
- ``integral of x_i x_j dV = 1/5 closed integral of x_i x_j (x . n) dA`` (``div(x_i x_j x) = 5 x_i x_j``).

Densities are 1: a face's "mass" is its area, a solid's its volume. Inertia tensors are taken
about the centroid: ``I = trace(C) E - C`` with ``C`` the second moments about the centroid.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import as_positive
from .integrate import DEFAULT_TOLERANCE, integrate

__all__ = ["MassProperties", "area", "area_and_volume", "volume", "centroid", "inertia", "mass_properties"]

# second moments in this order: xx, yy, zz, xy, yz, xz
_I, _J = np.array([0, 1, 2, 0, 1, 0]), np.array([0, 1, 2, 1, 2, 2])


@dataclass(frozen=True)
class MassProperties:
    """Mass properties at unit density.

    Attributes
    ----------
    of : str
        ``"volume"`` (shells, solids: centroid and inertia of the enclosed solid) or ``"area"``
        (faces: of the surface as a thin sheet of unit areal density).
    area : float
        Total area of the faces (model units squared).
    volume : float or None
        Enclosed volume by the divergence theorem (None for a face).
    centroid : (3,) ndarray
    inertia : (3, 3) ndarray
        Inertia tensor about the centroid (mass = volume, or area for a face).
    principal_moments : (3,) ndarray
        Eigenvalues of ``inertia``, ascending.
    principal_axes : (3, 3) ndarray
        Unit eigenvectors as columns, matching ``principal_moments``.
    area_error, volume_error : float
        Absolute error estimates (``volume_error`` None for a face).
    centroid_error : float
        Bound on the error of each centroid coordinate.
    inertia_error : float
        Bound on the error of each inertia entry.
    tolerance : float
        The relative tolerance asked for.
    converged : bool
        Whether the adaptive integration met the tolerance everywhere.
    evaluations : int
        Integrand evaluations used.
    """

    of: str
    area: float
    volume: float | None
    centroid: np.ndarray
    inertia: np.ndarray
    principal_moments: np.ndarray
    principal_axes: np.ndarray
    area_error: float
    volume_error: float | None
    centroid_error: float
    inertia_error: float
    tolerance: float
    converged: bool
    evaluations: int

    @property
    def mass(self) -> float:
        """The mass at unit density: the volume for shells and solids, the area for faces."""
        return self.volume if self.of == "volume" else self.area


def _is_face(obj) -> bool:
    """Whether ``obj`` is one face: shells and solids list ``.faces``, a face has none. (Told apart
    by that attribute, so this module needs nothing from :mod:`.face`, whose methods call it.)"""
    return not hasattr(obj, "faces")


def _faces_of(obj) -> list:
    return [obj] if _is_face(obj) else list(obj.faces)


def _reference_point(faces) -> tuple[np.ndarray, float]:
    """``(centre (3,), half diagonal)`` of the bounding box of the faces' control points."""
    pts = np.concatenate([np.asarray(f.surface.control_points).reshape(-1, 3) for f in faces])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    return 0.5 * (lo + hi), max(0.5 * float(np.linalg.norm(hi - lo)), np.finfo(float).tiny)


def _dot(a, b):
    """Row-wise dot product of ``(n, 3)`` arrays (einsum took 6x longer on the integrator's
    4096-row chunks)."""
    return a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1] + a[:, 2] * b[:, 2]


def _area_columns(x, N, moments):
    a = np.sqrt(_dot(N, N))[:, None]
    return [a, a * x, a * x[:, _I] * x[:, _J]] if moments else [a]


def _volume_columns(x, N, sign, moments):
    w = (sign * _dot(x, N))[:, None]
    return [w / 3.0, w * x / 4.0, w * x[:, _I] * x[:, _J] / 5.0] if moments else [w / 3.0]


def _cross(a, b):
    """Row-wise cross product of ``(n, 3)`` arrays (np.cross's axis handling cost more than the
    arithmetic on the integrator's batches)."""
    a0, a1, a2 = a[:, 0], a[:, 1], a[:, 2]
    b0, b1, b2 = b[:, 0], b[:, 1], b[:, 2]
    out = np.empty(a.shape)
    out[:, 0] = a1 * b2 - a2 * b1
    out[:, 1] = a2 * b0 - a0 * b2
    out[:, 2] = a0 * b1 - a1 * b0
    return out


def _integrand(center, parts):
    """The integrand of :func:`integrate` for the groups ``parts`` (subset of ``"area"``,
    ``"volume"``, ``"area moments"``, ``"volume moments"``)."""
    area, volume = "area" in parts, "volume" in parts
    area_moments, volume_moments = "area moments" in parts, "volume moments" in parts

    def f(S, Su, Sv, sign):
        N = _cross(Su, Sv)
        if area_moments or volume_moments:
            x = S - center
            cols = (_area_columns(x, N, area_moments) if area else []) + \
                (_volume_columns(x, N, sign, volume_moments) if volume else [])
            return np.concatenate(cols, axis=1)
        # area and/or volume alone (the common case): written into one array
        out = np.empty((len(S), int(area) + int(volume)))
        if area:
            np.sqrt(_dot(N, N), out=out[:, 0])
        if volume:
            np.multiply(_dot(S - center, N), sign / 3.0, out=out[:, -1])
        return out

    f.polynomial_degree = 3  # with Su, Sv constant: at most x_i x_j (x . N), cubic in S
    return f


def _group_scale(value, absval, size, with_moments):
    """Magnitudes of one group's components: mass, mass * size (first moments), mass * size^2.
    The mass is floored at a millionth of the integral of its absolute integrand, so an open
    shell (zero enclosed volume) does not ask for an impossible relative tolerance."""
    mass = max(abs(value[0]), 1e-6 * absval[0], np.finfo(float).tiny)
    if not with_moments:
        return np.array([mass])
    return np.concatenate([[mass], np.full(3, mass * size), np.full(6, mass * size * size)])


def _integrals(obj, tol, parts):
    faces = _faces_of(obj)
    center, size = _reference_point(faces)
    moments = ("area moments" in parts) or ("volume moments" in parts)
    groups = [g for g in ("area", "volume") if g in parts]
    width = 10 if moments else 1

    def scale(value, absval):
        return np.concatenate([_group_scale(value[i * width:(i + 1) * width], absval[i * width:(i + 1) * width],
                                            size, moments) for i in range(len(groups))])

    result = integrate(faces, _integrand(center, parts), tol=tol, scale=scale)
    return center, result


def _cached(obj, key, compute):
    cache = getattr(obj, "_cache", None)
    if cache is None:
        return compute()
    if key not in cache:
        cache[key] = compute()
    return cache[key]


def area(obj, tol: float = DEFAULT_TOLERANCE) -> float:
    """Area of a face, shell or solid (sum over its faces), to relative tolerance ``tol``."""
    return area_with_error(obj, tol)[0]


def area_with_error(obj, tol: float = DEFAULT_TOLERANCE) -> tuple[float, float]:
    """``(area, error estimate)``."""
    tol = as_positive(tol, "tol")

    def compute():
        _, r = _integrals(obj, tol, ("area",))
        return float(r.value[0]), float(r.error[0])

    return _cached(obj, ("area", tol), compute)


def volume(obj, tol: float = DEFAULT_TOLERANCE) -> float:
    """Enclosed volume of a shell or solid by the divergence theorem over its oriented faces
    (a face alone: its signed flux ``1/3 integral of x . n dA`` about the origin is not a volume,
    so faces are refused by the methods; this function accepts them)."""
    return volume_with_error(obj, tol)[0]


def volume_with_error(obj, tol: float = DEFAULT_TOLERANCE) -> tuple[float, float]:
    """``(volume, error estimate)``."""
    tol = as_positive(tol, "tol")

    def compute():
        _, r = _integrals(obj, tol, ("volume",))
        return float(r.value[0]), float(r.error[0])

    return _cached(obj, ("volume", tol), compute)


def area_and_volume(obj, tol: float = DEFAULT_TOLERANCE) -> tuple[float, float, float, float]:
    """``(area, area error, volume, volume error)`` of a face, shell or solid in one adaptive
    integration (the volume is the divergence-theorem flux over the oriented faces)."""
    tol = as_positive(tol, "tol")

    def compute():
        _, r = _integrals(obj, tol, ("area", "volume"))
        return float(r.value[0]), float(r.error[0]), float(r.value[1]), float(r.error[1])

    return _cached(obj, ("area and volume", tol), compute)


def _moments_to_properties(mass, m1, m2, errs, center):
    """Centroid and inertia about it from the mass, first and second moments about ``center``,
    with error bounds from the moments' errors ``(mass error, first error (3,), second error (6,))``."""
    e_mass, e1, e2 = errs
    d = m1 / mass
    second = np.empty((3, 3))
    second[_I, _J] = m2
    second[_J, _I] = m2
    C = second - mass * np.outer(d, d)
    inertia = np.trace(C) * np.eye(3) - C
    e_d = (np.max(e1) + np.max(np.abs(d)) * e_mass) / abs(mass)
    e_C = np.max(e2) + e_mass * float(d @ d) + 2.0 * abs(mass) * np.max(np.abs(d)) * e_d
    return center + d, inertia, float(e_d), float(3.0 * e_C)


def mass_properties(obj, tol: float = DEFAULT_TOLERANCE) -> MassProperties:
    """Area, volume (shells and solids), centroid, inertia about the centroid, principal moments
    and axes of a face, shell or solid, with error estimates, to relative tolerance ``tol``."""
    tol = as_positive(tol, "tol")
    is_face = _is_face(obj)

    def compute():
        parts = ("area", "area moments") if is_face else ("area", "area moments", "volume", "volume moments")
        center, r = _integrals(obj, tol, parts)
        val, err = r.value, r.error
        area_value, area_err = float(val[0]), float(err[0])
        if is_face:
            group, group_err, of, vol, vol_err = val[:10], err[:10], "area", None, None
        else:
            group, group_err, of = val[10:], err[10:], "volume"
            vol, vol_err = float(val[10]), float(err[10])
        c, I, e_c, e_I = _moments_to_properties(group[0], group[1:4], group[4:10],
                                               (group_err[0], group_err[1:4], group_err[4:10]), center)
        moments, axes = np.linalg.eigh(I)
        for a in (c, I, moments, axes):
            a.setflags(write=False)
        return MassProperties(of=of, area=area_value, volume=vol, centroid=c, inertia=I,
                              principal_moments=moments, principal_axes=axes, area_error=area_err,
                              volume_error=vol_err, centroid_error=e_c, inertia_error=e_I, tolerance=tol,
                              converged=bool(r.converged), evaluations=r.evaluations)

    return _cached(obj, ("mass", tol), compute)


def centroid(obj, tol: float = DEFAULT_TOLERANCE) -> np.ndarray:
    """``(3,)`` centroid: of the enclosed solid for shells and solids, of the area for a face."""
    return mass_properties(obj, tol).centroid


def inertia(obj, tol: float = DEFAULT_TOLERANCE) -> np.ndarray:
    """``(3, 3)`` inertia tensor about the centroid at unit density (volume for shells and
    solids, area for a face)."""
    return mass_properties(obj, tol).inertia
