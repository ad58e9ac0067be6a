"""Curvature of parametric and implicit surfaces, on whole arrays at once.

Sign convention (one for every representation, and OpenCascade's): curvatures
are measured against the surface's unit normal ``n`` -- ``Su x Sv / |Su x Sv|``
for a parametric surface, ``grad F / |grad F|`` for an implicit one. The second
fundamental form is ``L = Suu . n``, ``M = Suv . n``, ``N = Svv . n``; the shape
operator is ``W = I^-1 II`` (the Weingarten map ``-dn``); the principal
curvatures ``k1 >= k2`` are its eigenvalues, ``K = k1 k2`` and
``H = (k1 + k2) / 2 = -div(n) / 2``. A sphere of radius R has ``K = 1/R^2``
and ``H = -1/R`` with outward normals (``+1/R`` with inward ones); a curve on
the surface bending toward ``n`` has positive normal curvature.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import _kernels
from .._validate import as_float_array
from ..errors import ParameterError
from ..surfaces import SplineSurface
from .protocol import ImplicitSurface, _nonzero_norm, as_surface

__all__ = ["SINGULAR_OFFSET", "ImplicitCurvature", "SurfaceCurvature", "curvature"]

# relative distance (of the domain size) by which curvature at a singular
# parameter (Su x Sv = 0, e.g. a sphere's pole) is taken from inside the domain
SINGULAR_OFFSET = 1e-4


@dataclass(frozen=True)
class SurfaceCurvature:
    """Curvature of a parametric surface at parameters of shape ``s``.

    Attributes: ``points``, ``normal`` ``s + (3,)``; first fundamental form
    ``E, F, G`` and second ``L, M, N``, ``gaussian``, ``mean``, ``k1 >= k2``
    (all ``s``); ``directions`` ``s + (2, 3)``: unit principal directions in
    space (row 0 for ``k1``, row 1 for ``k2``; ``(d1, d2, n)`` right-handed);
    ``directions_uv`` ``s + (2, 2)``: the same directions as ``(du, dv)``
    (mapping to the unit vectors in space); ``shape_operator`` ``s + (2, 2)``:
    ``I^-1 II`` in the ``(u, v)`` basis; ``singular`` ``s``: where
    ``Su x Sv`` vanishes: there the normal and curvatures are limits,
    extrapolated from two parameters :data:`SINGULAR_OFFSET` and twice that
    (relative to the domain size) inside, and the other fields are the values
    at the first of them.
    """

    points: np.ndarray
    normal: np.ndarray
    E: np.ndarray
    F: np.ndarray
    G: np.ndarray
    L: np.ndarray
    M: np.ndarray
    N: np.ndarray
    gaussian: np.ndarray
    mean: np.ndarray
    k1: np.ndarray
    k2: np.ndarray
    directions: np.ndarray
    directions_uv: np.ndarray
    shape_operator: np.ndarray
    singular: np.ndarray

    @property
    def first_form(self) -> np.ndarray:
        """``s + (2, 2)``: ``[[E, F], [F, G]]``."""
        return np.stack([np.stack([self.E, self.F], -1), np.stack([self.F, self.G], -1)], -2)

    @property
    def second_form(self) -> np.ndarray:
        """``s + (2, 2)``: ``[[L, M], [M, N]]``."""
        return np.stack([np.stack([self.L, self.M], -1), np.stack([self.M, self.N], -1)], -2)


@dataclass(frozen=True)
class ImplicitCurvature:
    """Curvature of the level set of ``F`` through each of ``n`` points.

    ``normal`` ``(n, 3)`` = ``grad F / |grad F|``; ``gaussian``, ``mean``,
    ``k1 >= k2`` ``(n,)``; ``directions`` ``(n, 2, 3)`` (rows for k1, k2);
    ``shape_operator`` ``(n, 3, 3)``: ``-P Hess P / |grad F|`` with
    ``P = I - n n^T`` (the Weingarten map on the tangent plane, zero along n).
    """

    points: np.ndarray
    normal: np.ndarray
    gaussian: np.ndarray
    mean: np.ndarray
    k1: np.ndarray
    k2: np.ndarray
    directions: np.ndarray
    shape_operator: np.ndarray


def _dot(a, b):
    return np.einsum("...i,...i->...", a, b)


def _cross(a, b):
    return np.cross(a, b)


def _unit(a):
    return a / np.linalg.norm(a, axis=-1, keepdims=True)


def _sym_eigen(p, q, r):
    """Eigen-decomposition of the symmetric ``[[p, q], [q, r]]`` stacks:
    ``(k1, k2, cos t, sin t)`` with ``k1 >= k2`` and ``(cos t, sin t)`` the unit
    eigenvector of ``k1``. Closed form: no cancellation at umbilics."""
    m = 0.5 * (p + r)
    half = 0.5 * (p - r)
    d = np.hypot(half, q)
    t = 0.5 * np.arctan2(q, half)
    return m + d, m - d, np.cos(t), np.sin(t)


def _singular(Su, Sv, n):
    size = np.linalg.norm(Su, axis=-1) + np.linalg.norm(Sv, axis=-1)
    return np.linalg.norm(n, axis=-1) <= 1e-10 * size**2


def _nudged(surface, u, v, offset):
    """Parameters moved ``offset`` (relative to the domain size) toward the
    domain's centre: a regular point near a singular one."""
    (a, b), (c, d) = surface.domain
    cu, cv = 0.5 * (a + b), 0.5 * (c + d)
    du, dv = cu - u, cv - v
    length = np.hypot(du / (b - a), dv / (d - c))
    length = np.where(length > 0, length, 1.0)
    step = offset / length
    return u + step * du, v + step * dv


def _from_derivatives(S, Su, Sv, Suu, Suv, Svv, singular):
    """Every quantity of :class:`SurfaceCurvature` from flat ``(n, 3)`` partials."""
    nv = _cross(Su, Sv)
    n = _unit(nv)
    E, F, G = _dot(Su, Su), _dot(Su, Sv), _dot(Sv, Sv)
    L, M, N = _dot(Suu, n), _dot(Suv, n), _dot(Svv, n)
    det1 = E * G - F * F
    # orthonormal tangent frame e1 = Su/|Su|, e2 = n x e1; the Jacobian [Su Sv]
    # is B C with C = [[a, b], [0, c]] upper triangular
    a = np.sqrt(E)
    e1 = Su / a[:, None]
    e2 = _cross(n, e1)
    b = _dot(e1, Sv)
    c = _dot(e2, Sv)
    # A = C^-T II C^-1: the shape operator in the orthonormal frame (symmetric)
    p = L / (a * a)
    q = (M - b * p * a) / (a * c)
    r = (N - 2 * b * q * c - b * b * p) / (c * c)
    k1, k2, cos_t, sin_t = _sym_eigen(p, q, r)
    d1 = cos_t[:, None] * e1 + sin_t[:, None] * e2
    d2 = _cross(n, d1)
    # (u, v) components: C^-1 times the frame components
    def to_uv(x, y):
        dv = y / c
        du = (x - b * dv) / a
        return np.stack([du, dv], -1)

    uv1 = to_uv(cos_t, sin_t)
    uv2 = to_uv(-sin_t, cos_t)
    W = np.empty(E.shape + (2, 2))  # I^-1 II
    W[:, 0, 0] = (G * L - F * M) / det1
    W[:, 0, 1] = (G * M - F * N) / det1
    W[:, 1, 0] = (E * M - F * L) / det1
    W[:, 1, 1] = (E * N - F * M) / det1
    return {
        "points": S, "normal": n, "E": E, "F": F, "G": G, "L": L, "M": M, "N": N,
        "gaussian": (L * N - M * M) / det1, "mean": (E * N - 2 * F * M + G * L) / (2 * det1),
        "k1": k1, "k2": k2, "directions": np.stack([d1, d2], -2), "directions_uv": np.stack([uv1, uv2], -2),
        "shape_operator": W, "singular": singular,
    }  # fmt: skip


def _flat_partials(ders):
    """``(S, Su, Sv, Suu, Suv, Svv)`` flattened to ``(n, 3)`` from a
    ``(3, 3, ..., 3)`` derivative array."""
    dim = ders.shape[-1]
    if dim != 3:
        raise ParameterError(f"curvature needs a surface in 3-D space, this one has dim={dim}")
    f = lambda k, l: ders[k, l].reshape(-1, 3)
    return f(0, 0), f(1, 0), f(0, 1), f(2, 0), f(1, 1), f(0, 2)


def curvature(surface, u, v=None, *, grid: bool = False):
    """Curvature of a surface.

    Parametric surfaces (splines, Bézier patches, :class:`ParametricSurface`,
    :class:`ExplicitSurface`, :class:`SubdivisionPatch`, anything following the
    protocol): ``curvature(surface, u, v)`` at the pairs ``(u, v)`` (arrays of
    one shape ``s``), or with ``grid=True`` on the tensor grid of the 1-D
    arrays ``u`` x ``v`` (``s = (len(u), len(v))``; uses the surface's
    ``derivatives_grid`` when it has one). Returns :class:`SurfaceCurvature`.

    Implicit surfaces (:class:`ImplicitSurface`): ``curvature(surface, points)``
    of the level sets through ``(n, 3)`` points, from the gradient and Hessian.
    Returns :class:`ImplicitCurvature`.

    Sign convention: see the module docstring (OpenCascade's).
    """
    if isinstance(surface, ImplicitSurface):
        if v is not None or grid:
            raise ParameterError("an implicit surface takes curvature(surface, points) with (n, 3) points")
        return _implicit_curvature(surface, u)
    as_surface(surface)
    if grid:
        if v is None:
            raise ParameterError("curvature(surface, u, v, grid=True) needs both u and v")
        us = as_float_array(u, "u").ravel()
        vs = as_float_array(v, "v").ravel()
        fast = _compiled_grid(surface, us, vs)
        if fast is not None:
            return fast
        if hasattr(surface, "derivatives_grid"):
            ders = surface.derivatives_grid(us, vs, 2)
            U, V = np.meshgrid(us, vs, indexing="ij")
        else:
            U, V = np.meshgrid(us, vs, indexing="ij")
            ders = surface.derivatives(U, V, 2)
    else:
        if v is None:
            raise ParameterError("curvature(surface, u, v) needs both u and v for a parametric surface")
        u_arr, v_arr = as_float_array(u, "u"), as_float_array(v, "v")
        try:
            U, V = np.broadcast_arrays(u_arr, v_arr)
        except ValueError:
            raise ParameterError(
                f"u and v must have one shape (or broadcast to one), got {u_arr.shape} and {v_arr.shape}"
            ) from None
        ders = surface.derivatives(U, V, 2)
    shape = U.shape
    S, Su, Sv, Suu, Suv, Svv = _flat_partials(ders)
    singular = _singular(Su, Sv, _cross(Su, Sv))
    regular = ~singular
    out = _from_derivatives(S[regular], Su[regular], Sv[regular], Suu[regular], Suv[regular], Svv[regular], singular[regular])
    if singular.any():
        out = _with_limits(surface, out, U.ravel(), V.ravel(), S, singular)
    return SurfaceCurvature(**{k: a.reshape(shape + a.shape[1:]) for k, a in out.items()})


# quantities with a limit at a singular parameter, extrapolated there
_EXTRAPOLATED = ("normal", "gaussian", "mean", "k1", "k2")


def _with_limits(surface, regular_part, U, V, S, singular):
    """Fill the singular parameters in: every quantity at the regular parameter
    ``d`` inside (:func:`_nudged`); normal and curvatures extrapolated
    linearly from ``d`` and ``2 d``, which cancels the O(d) error of the offset."""
    us, vs = U[singular], V[singular]
    near = []
    for k in (1, 2):
        un, vn = _nudged(surface, us, vs, k * SINGULAR_OFFSET)
        partials = _flat_partials(surface.derivatives(un, vn, 2))
        if _singular(partials[1], partials[2], _cross(partials[1], partials[2])).any():
            i = int(np.flatnonzero(singular)[0])
            raise ParameterError(
                f"the surface is degenerate around (u, v) = ({U[i]!r}, {V[i]!r}): Su x Sv vanishes there "
                "and next to it, so it has no tangent plane"
            )
        near.append(_from_derivatives(S[singular], *partials[1:], np.ones(len(us), dtype=bool)))
    out = {}
    for key, value in regular_part.items():
        arr = np.empty((len(S),) + value.shape[1:], dtype=value.dtype)
        arr[~singular] = value
        arr[singular] = 2.0 * near[0][key] - near[1][key] if key in _EXTRAPOLATED else near[0][key]
        out[key] = arr
    out["normal"][singular] = _unit(out["normal"][singular])
    return out


def _compiled_grid(surface, us, vs):
    """:class:`SurfaceCurvature` on the grid from the fused compiled kernel, for
    large grids of spline surfaces (None otherwise: the numpy path serves)."""
    spline = getattr(surface, "_spline", surface)  # a BezierSurface wraps a spline
    if not isinstance(spline, SplineSurface) or spline.dim != 3:
        return None
    kernels = _kernels.load("splinekit.diffgeom._kernels", work=3 * us.size * vs.size)  # a point with its curvature: 3 curve points
    if kernels is None:
        return None
    (su, Nu), (sv, Nv) = spline._grid_basis(us, vs, 2)
    out = np.empty((kernels.N_FIELDS, us.size, vs.size))
    kernels.grid_curvature(spline._coefs4(), su, np.ascontiguousarray(Nu), spline.degree_u, sv,
                           np.ascontiguousarray(Nv), spline.degree_v, spline.is_rational, out)  # fmt: skip
    fields, start = {}, 0
    for name, width in kernels.FIELDS:
        block = out[start : start + width]  # (width, mu, mv) planes: views, no copies
        start += width
        if name in ("directions", "directions_uv", "shape_operator"):
            block = np.moveaxis(block.reshape((2, width // 2) + block.shape[1:]), (0, 1), (2, 3))
        elif width == 1:
            block = block[0]
        else:
            block = np.moveaxis(block, 0, -1)
        fields[name] = block
    singular = fields["singular"] > 0.5
    fields["singular"] = singular
    if singular.any():
        U, V = np.meshgrid(us, vs, indexing="ij")
        fix = curvature(surface, U[singular], V[singular])
        for name in fields:
            fields[name][singular] = getattr(fix, name)
    return SurfaceCurvature(**fields)


def _implicit_curvature(surface: ImplicitSurface, points) -> ImplicitCurvature:
    p = surface._points(points)
    g = surface.gradient(p)
    Hs = surface.hessian(p)
    length = _nonzero_norm(g, p, "gradient")
    n = g / length[:, None]
    # tangent frame: t1 from the coordinate axis least aligned with n
    axis = np.eye(3)[np.argmin(np.abs(n), axis=1)]
    t1 = _unit(_cross(axis, n))
    t2 = _cross(n, t1)
    Ht1 = np.einsum("nij,nj->ni", Hs, t1)
    Ht2 = np.einsum("nij,nj->ni", Hs, t2)
    p_ = -_dot(t1, Ht1) / length
    q_ = -_dot(t1, Ht2) / length
    r_ = -_dot(t2, Ht2) / length
    k1, k2, cos_t, sin_t = _sym_eigen(p_, q_, r_)
    d1 = cos_t[:, None] * t1 + sin_t[:, None] * t2
    d2 = _cross(n, d1)
    P = np.eye(3) - n[:, :, None] * n[:, None, :]
    W = -np.einsum("nij,njk,nkl->nil", P, Hs, P) / length[:, None, None]
    return ImplicitCurvature(
        points=p, normal=n, gaussian=p_ * r_ - q_ * q_, mean=0.5 * (p_ + r_), k1=k1, k2=k2,
        directions=np.stack([d1, d2], -2), shape_operator=W,
    )  # fmt: skip
