"""Differential geometry of curves: tangents, curvature, torsion, frames, arc length.

Every function takes a *curve object* and arrays of parameters. A curve object
is anything with ``.derivatives(u, order)`` returning ``(order + 1,) + u.shape +
(dim,)`` (``C, C', ..., C^(order)``): the splinekit :class:`~splinekit.BezierCurve`,
:class:`~splinekit.BSplineCurve` and :class:`~splinekit.NurbsCurve`, or a
:class:`ParametricCurve` wrapping plain numpy functions. Arc-length functions
also need its ``.domain`` ``(a, b)``.

Units: parameters are in the curve's parameter units; curvature and torsion in
1 / length; arc length in length units. Derivatives are taken with respect to
the curve's own parameter unless stated otherwise.

Conventions at degenerate points (never a NaN):

* *Singular parametrization* (``|C'| = 0``): :func:`tangent` uses the first
  non-vanishing higher derivative (as ``curve.tangent`` does); quantities that
  need ``C'`` itself (curvature, torsion, the Frenet frame) raise
  :class:`~splinekit.errors.DomainError` naming the parameter.
* *Vanishing curvature* (a straight piece or an inflection): the torsion is 0
  and the Frenet normal is carried over from the nearest parameter (of the
  same call) where it is defined, see :func:`frenet_frame`.

"Vanishes" is decided with relative thresholds: a derivative ``C^(k)`` vanishes
when ``|C^(k)| <= 1e-12 * size / length**k`` (``size``: the largest absolute
control-point coordinate, at least 1, or the same measured on 33 samples of a
curve without control points; ``length``: the length of the parameter
domain); the curvature vanishes when ``|C''_perp| <= 1e-10 * max(|C''|,
|C'|**2 / size)``, i.e. when the angle between ``C'`` and ``C''`` is below
1e-10 rad or ``curvature * size`` is below 1e-10.
"""

from __future__ import annotations

import math

import numpy as np

from .._validate import as_float_array, as_int, as_order, as_params, as_real
from ..errors import DomainError, ParameterError

__all__ = [
    "ParametricCurve",
    "arc_length",
    "arc_length_parameters",
    "curvature",
    "equal_arc_length_parameters",
    "frenet_frame",
    "reparametrize_by_arc_length",
    "rotation_minimizing_frames",
    "signed_curvature",
    "tangent",
    "torsion",
]

_EPS = np.finfo(np.float64).eps
_ZERO_DERIVATIVE = 1e-12  # relative size under which a derivative counts as zero
_ZERO_CURVATURE = 1e-10  # relative size under which C''_perp counts as zero
_COINCIDENT = 1e-8  # relative chord length under which two RMF samples count as one point
_GL_X, _GL_W = np.polynomial.legendre.leggauss(8)


# ----------------------------------------------------------------------------------------
# ParametricCurve
# ----------------------------------------------------------------------------------------
class ParametricCurve:
    """A curve given by a numpy function ``x(u)``, usable by every function here.

    Parameters
    ----------
    f : callable
        ``f(u)`` with ``u`` a 1-D float array ``(n,)`` returns the points ``(n, dim)``.
        It is only called with parameters inside ``domain``.
    derivatives : callable, optional
        ``derivatives(u, order)`` returns ``(order + 1, n, dim)``: ``x, x', ...,
        x^(order)``. Without it, derivatives up to order 4 are computed numerically
        (see below).
    domain : (float, float)
        Parameter interval ``[a, b]``, ``a < b``.

    Numeric derivatives
    -------------------
    The ``k``-th derivative (``1 <= k <= 4``) is a finite difference on the
    ``2 r + 1`` equally spaced nodes ``u + (j + s) h``, ``j = -r..r``, with
    ``r = 2 + ceil(k / 2)`` (``r = 3, 3, 4, 4``); the shift ``s`` is 0 (a central difference) unless
    that would leave the domain, in which case the stencil is shifted inside it.
    The step is ``h = 0.3 (b - a) eps**(1 / (2 r + 1))``, which balances the
    truncation error ``O(h**(2 r + 1 - k))`` of the (possibly shifted) stencil
    against the rounding error ``O(eps / h**k)``. Measured against analytic
    derivatives (tests): on one turn of a helix over ``[0, 2 pi]`` the
    relative errors are about 3e-13, 1e-10, 3e-9 and 2e-7 for ``k = 1..4``
    (shifted stencils at the ends included); on two turns over ``[0, 4 pi]``
    2e-11, 4e-9, 2e-7 and 7e-6. The step follows the domain's length, so a
    function that oscillates many times over its domain is differentiated less
    accurately (the truncation error grows like the number of oscillations to
    the power ``2 r + 1``); pass analytic derivatives for such functions.
    """

    MAX_NUMERIC_ORDER = 4

    __slots__ = ("_ders", "_dim", "_domain", "_f")

    def __init__(self, f, derivatives=None, domain=(0.0, 1.0)):
        if not callable(f):
            raise ParameterError(f"f must be callable, got {type(f).__name__}")
        if derivatives is not None and not callable(derivatives):
            raise ParameterError(f"derivatives must be callable or None, got {type(derivatives).__name__}")
        dom = as_float_array(domain, "domain")
        if dom.shape != (2,) or not np.isfinite(dom).all() or not dom[0] < dom[1]:
            raise ParameterError(f"domain must be two finite numbers a < b, got {np.asarray(domain).tolist()!r}")
        for name, value in (("_f", f), ("_ders", derivatives), ("_domain", (float(dom[0]), float(dom[1])))):
            object.__setattr__(self, name, value)
        probe = self._call_f(np.array(self._domain))
        object.__setattr__(self, "_dim", probe.shape[1])

    def __setattr__(self, name, value):
        raise AttributeError("ParametricCurve is immutable")

    @property
    def domain(self) -> tuple[float, float]:
        """Parameter interval ``(a, b)``."""
        return self._domain

    @property
    def dim(self) -> int:
        """Number of coordinates of a point."""
        return self._dim

    def __repr__(self):
        kind = "analytic" if self._ders is not None else "numeric"
        a, b = self._domain
        return f"ParametricCurve(dim={self._dim}, domain=[{a:g}, {b:g}], {kind} derivatives)"

    def _call_f(self, flat: np.ndarray) -> np.ndarray:
        out = as_float_array(self._f(flat), "f(u)")
        if out.ndim != 2 or out.shape[0] != flat.size or out.shape[1] < 1:
            raise ParameterError(f"f(u) must return shape ({flat.size}, dim) for u of shape {flat.shape}, got {out.shape}")
        _require_finite(out, flat, "f(u)")
        return out

    def evaluate(self, u) -> np.ndarray:
        """Points ``u.shape + (dim,)``."""
        u = as_params(u, self._domain)
        return self._call_f(u.ravel()).reshape(u.shape + (-1,))

    __call__ = evaluate

    def derivatives(self, u, order: int = 1) -> np.ndarray:
        """``x, x', ..., x^(order)``: ``(order + 1,) + u.shape + (dim,)``."""
        order = as_order(order)
        u = as_params(u, self._domain)
        flat = u.ravel()
        if self._ders is not None:
            out = as_float_array(self._ders(flat, order), "derivatives(u, order)")
            want = (order + 1, flat.size, self._dim)
            if out.shape != want:
                raise ParameterError(f"derivatives(u, {order}) must return shape {want}, got {out.shape}")
            _require_finite(out, flat, "derivatives(u, order)")
        else:
            if order > self.MAX_NUMERIC_ORDER:
                raise ParameterError(
                    f"order = {order}: numeric derivatives are offered up to order {self.MAX_NUMERIC_ORDER}; "
                    "pass analytic derivatives for more"
                )
            out = np.empty((order + 1, flat.size, self._dim))
            out[0] = self._call_f(flat)
            for k in range(1, order + 1):
                out[k] = self._finite_difference(flat, k)
        return out.reshape((order + 1,) + u.shape + (self._dim,))

    def _finite_difference(self, flat: np.ndarray, k: int) -> np.ndarray:
        """The ``k``-th derivative ``(n, dim)`` by the stencil described in the class docstring."""
        a, b = self._domain
        r = 2 + (k + 1) // 2
        h = 0.3 * (b - a) * _EPS ** (1.0 / (2 * r + 1))
        # shift each stencil just enough to keep its nodes inside [a, b]
        shift = np.maximum(0, np.ceil(r - (flat - a) / h)) - np.maximum(0, np.ceil(r - (b - flat) / h))
        shift = shift.astype(np.int64)
        offsets = np.arange(-r, r + 1)
        out = np.empty((flat.size, self._dim))
        for s in np.unique(shift):
            sel = shift == s
            nodes = offsets + s
            w = _difference_weights(nodes, k) / h**k
            x = np.clip(flat[sel, None] + nodes * h, a, b)
            values = self._call_f(x.ravel()).reshape(x.shape + (self._dim,))
            out[sel] = np.einsum("j,njd->nd", w, values)
        return out


def _difference_weights(nodes: np.ndarray, k: int) -> np.ndarray:
    """Weights ``w`` with ``sum_j w_j f(x + nodes_j) = f^(k)(x) + O(h^(len - k))`` for unit spacing:
    the moment conditions ``sum_j w_j nodes_j**m / m! = [m == k]``, ``m < len(nodes)``."""
    m = np.arange(nodes.size)
    V = nodes[None, :].astype(np.float64) ** m[:, None] / np.array([math.factorial(i) for i in m])[:, None]
    rhs = (m == k).astype(np.float64)
    return np.linalg.solve(V, rhs)


def _require_finite(values: np.ndarray, flat: np.ndarray, what: str):
    bad = ~np.isfinite(values)
    if bad.any():
        where = np.argwhere(bad)[0]
        i = where[-2] if values.ndim >= 2 else where[0]
        raise DomainError(f"{what} is not finite at u = {float(flat[i])!r}")


# ----------------------------------------------------------------------------------------
# shared helpers
# ----------------------------------------------------------------------------------------
def _check_curve(curve):
    if not callable(getattr(curve, "derivatives", None)):
        raise ParameterError(
            f"curve must have a .derivatives(u, order) method (a splinekit curve or a ParametricCurve), "
            f"got {type(curve).__name__}"
        )


def _params(u, name: str = "u") -> np.ndarray:
    arr = as_float_array(u, name, DomainError)
    if not np.isfinite(arr).all():
        raise DomainError(f"{name} = {float(arr[~np.isfinite(arr)].ravel()[0])!r} is not finite")
    return arr


def _ders(curve, flat: np.ndarray, order: int) -> np.ndarray:
    """``curve.derivatives(flat, order)`` checked to be ``(order + 1, n, dim)`` and finite."""
    _check_curve(curve)
    d = as_float_array(curve.derivatives(flat, order), "curve.derivatives(u, order)")
    if d.ndim != 3 or d.shape[:2] != (order + 1, flat.size):
        raise ParameterError(
            f"curve.derivatives(u, {order}) must return shape ({order + 1}, {flat.size}, dim), got {d.shape}"
        )
    _require_finite(d, flat, "curve.derivatives(u, order)")
    return d


def _domain(curve) -> tuple[float, float]:
    dom = getattr(curve, "domain", None)
    if dom is None:
        raise ParameterError(f"curve must have a .domain (a, b); {type(curve).__name__} has none")
    a, b = (float(x) for x in dom)
    return a, b


def _scales(curve) -> tuple[float, float]:
    """``(size, length)``: the geometric size (at least 1) and the length of the parameter domain."""
    dom = getattr(curve, "domain", None)
    if dom is not None:
        a, b = (float(x) for x in dom)
        length = b - a if b > a else 1.0
    else:
        a = b = None
        length = 1.0
    P = getattr(curve, "control_points", None)
    if P is not None:
        size = float(np.abs(np.asarray(P, dtype=np.float64)).max())
    elif a is not None:
        size = float(np.abs(_ders(curve, np.linspace(a, b, 33), 0)[0]).max())
    else:
        size = 1.0
    return max(size, 1.0), length


def _max_fallback_order(curve) -> int:
    """Highest derivative order inspected when ``C'`` vanishes: the degree of a
    splinekit curve (a polynomial span has no non-zero derivative beyond it),
    else 3."""
    degree = getattr(curve, "degree", None)
    if isinstance(degree, (int, np.integer)) and degree >= 1:
        return max(int(degree), 2)
    return 3


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise dot products ``(n,)`` of ``(n, k)`` arrays."""
    return np.einsum("ij,ij->i", a, b)


def _norm(v: np.ndarray) -> np.ndarray:
    """Euclidean norms of the rows of ``v``: ``(n,)`` for ``(n, k)``, or ``(m, n)`` for ``(m, n, k)``."""
    return np.sqrt(np.einsum("...i,...i->...", v, v))


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross products of broadcastable ``(..., 3)`` arrays (cheaper than ``np.cross`` on small rows)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def _unit(v: np.ndarray, norms: np.ndarray | None = None) -> np.ndarray:
    if norms is None:
        norms = _norm(v)
    return np.divide(v, norms[..., None], out=np.zeros_like(v), where=norms[..., None] > 0)


def _tangents(curve, flat: np.ndarray, d1: np.ndarray, size: float, length: float):
    """Unit tangents ``(n, dim)`` and a mask of where one exists."""
    norms = _norm(d1)
    regular = norms > _ZERO_DERIVATIVE * size / length
    T = _unit(d1, np.where(regular, norms, 0.0))
    defined = regular.copy()
    if not regular.all():
        idx = np.flatnonzero(~regular)
        K = _max_fallback_order(curve)
        higher = _ders(curve, flat[idx], K)[2:]  # C'' ... C^(K)
        hn = _norm(higher)
        usable = hn > _ZERO_DERIVATIVE * size / length ** np.arange(2, K + 1)[:, None]
        first = usable.argmax(axis=0)
        found = usable.any(axis=0)
        m = np.arange(idx.size)
        T[idx] = np.where(found[:, None], _unit(higher[first, m], hn[first, m]), 0.0)
        defined[idx] = found
    return T, defined, regular


def _require_regular(regular: np.ndarray, flat: np.ndarray, what: str):
    if not regular.all():
        u0 = float(flat[np.flatnonzero(~regular)[0]])
        raise DomainError(
            f"the first derivative vanishes at u = {u0!r} (a singular parametrization); {what} is undefined there"
        )


def _as_3d(v: np.ndarray, what: str) -> np.ndarray:
    """``(n, 3)``: 3-D vectors as they are, planar ones embedded in the plane z = 0."""
    if v.shape[-1] == 3:
        return v
    if v.shape[-1] == 2:
        return np.concatenate([v, np.zeros(v.shape[:-1] + (1,))], axis=-1)
    raise ParameterError(f"{what} needs a 2-D or 3-D curve, got dim={v.shape[-1]}")


def _perpendicular(T: np.ndarray) -> np.ndarray:
    """A unit vector ``(n, 3)`` orthogonal to each unit ``T``: the coordinate axis
    least aligned with ``T`` (the first such axis on ties), made orthogonal to ``T``."""
    axis = np.abs(T).argmin(axis=-1)
    e = np.zeros_like(T)
    e[np.arange(T.shape[0]), axis] = 1.0
    e -= _dot(e, T)[:, None] * T
    return _unit(e)


# ----------------------------------------------------------------------------------------
# tangent, curvature, torsion
# ----------------------------------------------------------------------------------------
def tangent(curve, u) -> np.ndarray:
    """Unit tangent vectors ``u.shape + (dim,)``.

    Where ``C'`` vanishes the direction of the first non-vanishing higher
    derivative is used (the one-sided limit from larger parameters); where all
    derivatives inspected vanish (a constant curve) the result is the zero vector.
    """
    u = _params(u)
    flat = u.ravel()
    d1 = _ders(curve, flat, 1)[1]
    size, length = _scales(curve)
    T, _, _ = _tangents(curve, flat, d1, size, length)
    return T.reshape(u.shape + (d1.shape[-1],))


def _per_point_unit(d1: np.ndarray) -> np.ndarray:
    """A power of two ``(n,)`` near ``|C'|`` at each point (1 where ``C'`` vanishes).

    Curvature and torsion are homogeneous of degree -1 in the derivatives:
    dividing the derivatives by the same power of two (exactly) before the
    products keeps squared and cubed lengths inside the float range, whatever
    the units; the result is then divided by it.
    """
    peak = np.abs(d1).max(axis=-1)
    exponent = np.frexp(np.where(peak > 0, peak, 1.0))[1]
    return np.ldexp(1.0, exponent)


def _perp_second(d1: np.ndarray, d2: np.ndarray):
    """``C''`` minus its component along ``C'``, and ``|C'|``: ``(n, dim)``, ``(n,)``."""
    speed = _norm(d1)
    T = _unit(d1, speed)
    return d2 - _dot(d2, T)[:, None] * T, speed


def _regular_derivatives(curve, u, order: int, what: str, dim: int | None = None, hint: str = ""):
    """``(u, d, unit, size)``: parameters, the derivatives ``(order + 1, n, dim)``
    at the flattened ``u`` divided point by point by the power of two ``unit``
    (:func:`_per_point_unit`, so products of derivatives cannot overflow), and
    the curve's size. Raises where ``C'`` vanishes (``what`` names the
    quantity) and, with ``dim``, for curves of another dimension."""
    u = _params(u)
    flat = u.ravel()
    d = _ders(curve, flat, order)
    if dim is not None and d.shape[-1] != dim:
        raise ParameterError(f"{what} needs a {dim}-D curve, got dim={d.shape[-1]}{hint}")
    size, length = _scales(curve)
    _require_regular(_norm(d[1]) > _ZERO_DERIVATIVE * size / length, flat, what)
    unit = _per_point_unit(d[1])
    return u, d / unit[:, None], unit, size


def curvature(curve, u) -> np.ndarray:
    """Curvature ``u.shape`` (>= 0, in 1 / length) of a curve of any dimension.

    ``kappa = |C''_perp| / |C'|**2`` with ``C''_perp`` the part of ``C''``
    orthogonal to ``C'``; this equals ``sqrt(Gram(C', C'')) / |C'|**3`` and, in
    3-D, ``|C' x C''| / |C'|**3``, without the cancellation of the Gram
    determinant. Raises :class:`DomainError` where ``C'`` vanishes.
    """
    u, d, unit, _ = _regular_derivatives(curve, u, 2, "the curvature")
    speed = _norm(d[1])
    if d.shape[-1] == 3:
        num = _norm(_cross(d[1], d[2])) / speed
    elif d.shape[-1] == 2:
        num = np.abs(d[1, :, 0] * d[2, :, 1] - d[1, :, 1] * d[2, :, 0]) / speed
    else:
        num = _norm(_perp_second(d[1], d[2])[0])
    return (num / speed**2 / unit).reshape(u.shape)


def signed_curvature(curve, u) -> np.ndarray:
    """Signed curvature ``u.shape`` of a planar (2-D) curve: ``(x' y'' - y' x'') / |C'|**3``,
    positive where the curve turns counter-clockwise."""
    u, d, unit, _ = _regular_derivatives(curve, u, 2, "the signed curvature", dim=2, hint=" (use curvature)")
    speed = _norm(d[1])
    cross = d[1, :, 0] * d[2, :, 1] - d[1, :, 1] * d[2, :, 0]
    return (cross / speed**3 / unit).reshape(u.shape)


def _straight(perp: np.ndarray, d1: np.ndarray, d2: np.ndarray, size: float) -> np.ndarray:
    """Mask of points where the curvature vanishes (see the module docstring)."""
    scale = np.maximum(_norm(d2), _dot(d1, d1) / size)
    return _norm(perp) <= _ZERO_CURVATURE * scale


def torsion(curve, u) -> np.ndarray:
    """Torsion ``u.shape`` (1 / length) of a 3-D curve: ``det(C', C'', C''') / |C' x C''|**2``.

    Positive for a right-handed helix. Where the curvature vanishes (straight
    pieces, inflections) the torsion is defined as 0. Raises
    :class:`DomainError` where ``C'`` vanishes.
    """
    u, d, unit, size = _regular_derivatives(curve, u, 3, "the torsion", dim=3)
    straight = _straight(_perp_second(d[1], d[2])[0], d[1], d[2], size / unit)
    cross = _cross(d[1], d[2])
    c2 = _dot(cross, cross)
    det = _dot(cross, d[3])
    out = np.divide(det, c2, out=np.zeros_like(det), where=~straight & (c2 > 0))
    return (out / unit).reshape(u.shape)


# ----------------------------------------------------------------------------------------
# frames
# ----------------------------------------------------------------------------------------
def frenet_frame(curve, u):
    """Frenet frame ``(T, N, B)``, each ``u.shape + (3,)``, of a 3-D (or planar, embedded at z = 0) curve.

    ``T = C' / |C'|``, ``N`` the unit part of ``C''`` orthogonal to ``T``,
    ``B = T x N``. Where the curvature vanishes ``N`` is undefined; it is then
    the normal of the nearest parameter of this call where it is defined,
    made orthogonal to ``T`` (or, if there is none, or it is parallel to
    ``T``, the coordinate axis least aligned with ``T`` made orthogonal to it).
    So the frame is always orthonormal and right-handed, but at a straight
    piece it depends on the other parameters passed. Raises
    :class:`DomainError` where ``C'`` vanishes.
    """
    u = _params(u)
    flat = u.ravel()
    d = _ders(curve, flat, 2)
    size, length = _scales(curve)
    d1, d2 = _as_3d(d[1], "frenet_frame"), _as_3d(d[2], "frenet_frame")
    _require_regular(_norm(d1) > _ZERO_DERIVATIVE * size / length, flat, "the Frenet frame")
    unit = _per_point_unit(d1)  # the frame is invariant under this scaling; squares stay in range
    d1, d2 = d1 / unit[:, None], d2 / unit[:, None]
    perp, speed = _perp_second(d1, d2)
    T = _unit(d1, speed)
    straight = _straight(perp, d1, d2, size / unit)
    N = _unit(perp)
    if straight.any():
        N[straight] = _carried_normals(flat, T, N, straight)
    B = _cross(T, N)
    shape = u.shape + (3,)
    return T.reshape(shape), N.reshape(shape), B.reshape(shape)


def _carried_normals(flat, T, N, undefined):
    """Normals at the ``undefined`` points: the nearest defined one, projected orthogonal to ``T``."""
    idx = np.flatnonzero(undefined)
    Tu = T[idx]
    out = _perpendicular(Tu)
    good = np.flatnonzero(~undefined)
    if good.size:
        order = good[np.argsort(flat[good], kind="stable")]
        keys = flat[order]
        pos = np.clip(np.searchsorted(keys, flat[idx]), 1, max(keys.size - 1, 1))
        left = order[np.clip(pos - 1, 0, keys.size - 1)]
        right = order[np.clip(pos, 0, keys.size - 1)]
        nearest = np.where(np.abs(flat[left] - flat[idx]) <= np.abs(flat[right] - flat[idx]), left, right)
        cand = N[nearest] - _dot(N[nearest], Tu)[:, None] * Tu
        cn = _norm(cand)
        ok = cn > 1e-6
        out[ok] = cand[ok] / cn[ok, None]
    return out


def rotation_minimizing_frames(curve, u, normal=None):
    """Rotation-minimizing frames ``(T, N, B)``, each ``(n, 3)``, along sorted parameters ``u`` ``(n,)``.

    The double reflection method (Wang, Juettler, Zheng, Liu, *Computation of
    rotation minimizing frames*, ACM TOG 27(1), 2008): the frame at ``u[i+1]``
    is the frame at ``u[i]`` reflected in the bisector plane of the two curve
    points, then in the plane that maps the reflected tangent onto the tangent
    at ``u[i+1]``. Its global error is ``O(h**4)`` in the step ``h``; ``N``
    has no rotation about ``T`` (``dN/ds`` is parallel to ``T``) up to that error.

    Parameters
    ----------
    curve
        A 3-D curve (a planar 2-D one is embedded in the plane z = 0).
    u : array_like, shape (n,)
        Non-decreasing parameters (repeated values give repeated frames).
    normal : array_like, shape (3,), optional
        Start normal; it is projected orthogonal to the start tangent and
        normalized. Default: the coordinate axis least aligned with the start
        tangent (the first on ties), made orthogonal to it.

    Returns
    -------
    T, N, B : ndarray, shape (n, 3)
        Unit tangents (as :func:`tangent`), rotation-minimizing normals and
        ``B = T x N``.

    The reflections are built for all steps at once. A pair of reflections is
    a rotation, kept as a unit quaternion (a lone reflection, where the second
    one is skipped, as minus a half-turn and a sign); their sequential
    composition is a blocked prefix product of the quaternions
    (:func:`_prefix_products`), so no Python loop runs per frame. The normals
    are re-orthogonalized against ``T`` at the end.
    """
    u = _params(u)
    if u.ndim != 1 or u.size == 0:
        raise ParameterError(f"u must be a non-empty 1-D array of parameters, got shape {u.shape}")
    steps = np.diff(u)
    if (steps < 0).any():
        i = int(np.flatnonzero(steps < 0)[0])
        raise ParameterError(
            f"u must be sorted (non-decreasing): u[{i}] = {float(u[i])!r} > u[{i + 1}] = {float(u[i + 1])!r}"
        )
    d = _ders(curve, u, 1)
    size, length = _scales(curve)
    T, defined, _ = _tangents(curve, u, d[1], size, length)
    if not defined.all():
        u0 = float(u[np.flatnonzero(~defined)[0]])
        raise DomainError(f"the curve has no tangent direction at u = {u0!r} (every derivative vanishes)")
    X = _as_3d(d[0], "rotation_minimizing_frames")
    T = _as_3d(T, "rotation_minimizing_frames")
    r0 = _start_normal(T[0], normal)
    R = np.empty((u.size, 3))
    R[0] = r0
    if u.size > 1:
        q, sign = _double_reflections(X, T, size)
        R[1:] = _rotate(_prefix_products(q), r0) * np.cumprod(sign)[:, None]
        # rounding in the long product: put N back exactly orthogonal to T
        R -= _dot(R, T)[:, None] * T
        R = _unit(R)
    return T, R, _cross(T, R)


def _start_normal(t0: np.ndarray, normal) -> np.ndarray:
    if normal is None:
        return _perpendicular(t0[None, :])[0]
    v = as_float_array(normal, "normal")
    if v.shape != (3,) or not np.isfinite(v).all():
        raise ParameterError(f"normal must be 3 finite numbers, got {np.asarray(normal).tolist()!r}")
    peak = float(np.abs(v).max())
    if peak > 0:
        v = v / peak  # only the direction matters; scaled first so that no product overflows
    norm = float(np.linalg.norm(v))
    w = v - float(v @ t0) * t0
    wn = float(np.linalg.norm(w))
    if not wn > 1e-9 * norm:
        raise ParameterError(
            f"normal {v.tolist()} is zero or parallel to the start tangent {t0.tolist()}; "
            "it must have a component orthogonal to it"
        )
    return w / wn


def _double_reflections(X: np.ndarray, T: np.ndarray, size: float):
    """Step maps as quaternions ``(n - 1, 4)`` ``(w, x, y, z)`` and signs ``(n - 1,)``.

    Step ``i`` maps the frame at ``i`` onto the one at ``i + 1`` by ``H2 H1``,
    ``H = I - 2 m m^T`` the reflection in the plane with unit normal ``m``:
    ``m1`` along the chord ``X[i+1] - X[i]``, ``m2`` along ``T[i+1] - H1 T[i]``.
    As ``H = -(half-turn about m)`` and a half-turn is the pure quaternion
    ``(0, m)``, ``H2 H1`` is the quaternion ``(0, m2)(0, m1) = (-m2.m1, m2 x m1)``
    with sign +1. Where two samples coincide (a repeated parameter) the chord's
    direction is rounding noise, so ``T[i]`` stands in for it (the limit of the
    chord direction as the step shrinks) and the step is the smallest rotation
    taking ``T[i]`` to ``T[i+1]``. Where ``T[i+1] - H1 T[i]`` vanishes the second
    reflection is skipped, as in the paper: quaternion ``(0, m1)``, sign -1.
    """
    # chords in units of the curve's size: squares of raw chords overflow beyond ~1e154
    Xs = X / size if size > 0 else X
    v1 = Xs[1:] - Xs[:-1]
    c1 = _dot(v1, v1)
    close = c1 <= _COINCIDENT**2
    m1 = np.where(close[:, None], T[:-1], v1 / np.sqrt(np.where(close, 1.0, c1))[:, None])
    tL = T[:-1] - (2.0 * _dot(m1, T[:-1]))[:, None] * m1
    v2 = T[1:] - tL
    c2 = _dot(v2, v2)
    skip = c2 <= 1e-20
    m2 = v2 / np.sqrt(np.where(skip, 1.0, c2))[:, None]
    q = np.empty((v1.shape[0], 4))
    q[:, 0] = -_dot(m2, m1)
    q[:, 1:] = _cross(m2, m1)
    q[skip, 0] = 0.0
    q[skip, 1:] = m1[skip]
    return q, np.where(skip, -1.0, 1.0)


def _qmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton products ``a b`` of quaternion arrays ``(..., 4)``."""
    aw, ax, ay, az = np.moveaxis(a, -1, 0)
    bw, bx, by, bz = np.moveaxis(b, -1, 0)
    return np.stack(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ],
        axis=-1,
    )


def _rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``q v q*`` ``(n, 3)`` for unit quaternions ``q`` ``(n, 4)`` and one vector ``v`` ``(3,)``."""
    w, qv = q[:, :1], q[:, 1:]
    t = 2.0 * _cross(qv, v)
    return v + w * t + _cross(qv, t)


def _prefix_products(q: np.ndarray) -> np.ndarray:
    """``P[k] = q[k] q[k-1] ... q[0]`` for quaternions ``(m, 4)``.

    Blocked scan: the ``m`` quaternions are cut into about ``sqrt(m)`` blocks
    of about ``sqrt(m)``; the running products inside every block advance
    together (one batched product per position in a block), then the block
    totals are scanned the same way (recursively) and applied to every block
    in one batched product: about ``2 m`` products in ``2 sqrt(m)`` Python steps.
    """
    m = q.shape[0]
    if m <= 16:
        P = q.copy()
        for k in range(1, m):
            P[k] = _qmul(P[k], P[k - 1])
        return P
    width = math.ceil(math.sqrt(m))
    blocks = -(-m // width)
    Q = np.zeros((blocks * width, 4))
    Q[:m] = q
    Q[m:, 0] = 1.0  # identity padding
    Q = Q.reshape(blocks, width, 4)
    for j in range(1, width):
        Q[:, j] = _qmul(Q[:, j], Q[:, j - 1])
    before = _prefix_products(Q[:, -1])  # product of blocks 0..b
    Q[1:] = _qmul(Q[1:], before[:-1, None, :])
    return Q.reshape(-1, 4)[:m]


# ----------------------------------------------------------------------------------------
# arc length
# ----------------------------------------------------------------------------------------
class _ArcLengthTable:
    """Cumulative arc length at the edges of a partition of the domain.

    The domain is cut at the curve's breakpoints (its distinct knots, where the
    speed may be non-smooth), and every span into ``2**level`` equal pieces;
    each piece is integrated with 8-point Gauss-Legendre. ``level`` grows until
    every piece's integral agrees with the sum of its two halves to ``tol``
    times the total length (at most ``2**12`` pieces per span). The length from
    the start to any ``u`` is then the table value at the piece's left edge
    plus one more 8-point rule on the remainder.
    """

    MAX_LEVEL = 12

    def __init__(self, curve, tol: float):
        _check_curve(curve)
        self.curve = curve
        self.a, self.b = _domain(curve)
        breaks = getattr(curve, "bezier_breakpoints", None)
        edges = np.asarray(breaks(), dtype=np.float64) if callable(breaks) else np.array([self.a, self.b])
        edges = edges[(edges >= self.a) & (edges <= self.b)]
        edges = np.unique(np.concatenate([[self.a], edges, [self.b]]))
        previous = self._pieces(edges)
        for _ in range(self.MAX_LEVEL):
            mid = 0.5 * (edges[:-1] + edges[1:])
            finer = np.empty(2 * edges.size - 1)
            finer[0::2], finer[1::2] = edges, mid
            pieces = self._pieces(finer)
            total = float(pieces.sum())
            converged = np.abs(pieces[0::2] + pieces[1::2] - previous).max() <= tol * max(total, 1e-300)
            edges, previous = finer, pieces
            if converged:
                break
        self.edges = edges
        self.cumulative = np.concatenate([[0.0], np.cumsum(previous)])
        self.length = float(self.cumulative[-1])

    def _integral(self, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        """Gauss-Legendre (8 points) of the speed over each ``[lo, hi]``."""
        half = 0.5 * (hi - lo)
        x = (0.5 * (lo + hi))[:, None] + half[:, None] * _GL_X
        x = np.clip(x, self.a, self.b)
        d1 = _ders(self.curve, x.ravel(), 1)[1]
        speed = np.sqrt(_dot(d1, d1)).reshape(x.shape)
        return (speed @ _GL_W) * half

    def _pieces(self, edges: np.ndarray) -> np.ndarray:
        return self._integral(edges[:-1], edges[1:])

    def length_at(self, u: np.ndarray) -> np.ndarray:
        """Arc length from the domain start to each ``u`` (1-D, inside the domain)."""
        j = np.clip(np.searchsorted(self.edges, u, side="right") - 1, 0, self.edges.size - 2)
        return self.cumulative[j] + self._integral(self.edges[j], u)

    def parameters_at(self, s: np.ndarray, tol: float) -> np.ndarray:
        """Parameters ``u`` with ``length_at(u) = s`` (1-D, ``0 <= s <= length``).

        Newton's method on ``length_at(u) - s`` inside the piece bracketing
        ``s``, falling back to bisection whenever a Newton step would leave the
        current bracket (or the speed vanishes). Stops when the residual is at
        most ``tol * length`` or the bracket has shrunk to rounding.
        """
        j = np.clip(np.searchsorted(self.cumulative, s, side="right") - 1, 0, self.edges.size - 2)
        lo, hi = self.edges[j].copy(), self.edges[j + 1].copy()
        s_lo, s_hi = self.cumulative[j], self.cumulative[j + 1]
        width = s_hi - s_lo
        frac = np.divide(s - s_lo, width, out=np.full_like(s, 0.5), where=width > 0)
        u = lo + np.clip(frac, 0.0, 1.0) * (hi - lo)
        active = np.arange(s.size)
        goal = tol * max(self.length, 1e-300)
        for _ in range(200):  # bisection alone halves the bracket: 200 steps exhaust a double
            ua, ja = u[active], j[active]
            g = self.cumulative[ja] + self._integral(self.edges[ja], ua) - s[active]
            done = (np.abs(g) <= goal) | (hi[active] - lo[active] <= 4 * _EPS * np.maximum(np.abs(ua), 1.0))
            below = g < 0
            lo[active] = np.where(below, ua, lo[active])
            hi[active] = np.where(below, hi[active], ua)
            d1 = _ders(self.curve, ua, 1)[1]
            speed = np.sqrt(_dot(d1, d1))
            step = np.divide(g, speed, out=np.full_like(g, np.inf), where=speed > 0)
            newton = ua - step
            inside = (newton > lo[active]) & (newton < hi[active])
            u[active] = np.where(done, ua, np.where(inside, newton, 0.5 * (lo[active] + hi[active])))
            active = active[~done]
            if active.size == 0:
                break
        return u


def _tolerance(tol) -> float:
    tol = as_real(tol, "tol")
    if not tol > 0:
        raise ParameterError(f"tol must be > 0, got {tol!r}")
    return tol


def arc_length(curve, u0=None, u1=None, tol: float = 1e-12):
    """Arc length between parameters ``u0`` and ``u1`` (default: the domain ends).

    ``u0`` and ``u1`` broadcast against each other; the result has their
    broadcast shape (a float for scalars) and is negative where ``u1 < u0``.
    Accurate to about ``tol`` relative to the curve's total length (see
    :class:`_ArcLengthTable`); agrees with ``curve.arc_length`` of splinekit curves.
    """
    table = _ArcLengthTable(curve, _tolerance(tol))
    a, b = table.a, table.b
    s = as_params(a if u0 is None else _params(u0, "u0"), (a, b), "u0")
    e = as_params(b if u1 is None else _params(u1, "u1"), (a, b), "u1")
    s, e = np.broadcast_arrays(s, e)
    out = table.length_at(e.ravel()) - table.length_at(s.ravel())
    # identical end points give exactly zero, not a difference of two roundings
    out[e.ravel() == s.ravel()] = 0.0
    out = out.reshape(s.shape)
    return float(out) if out.ndim == 0 else out


def arc_length_parameters(curve, s, tol: float = 1e-12) -> np.ndarray:
    """Parameters ``s.shape`` at which the arc length from the domain start equals ``s``.

    ``s`` must lie in ``[0, L]`` (``L`` the total length; values within
    ``1e-10 L`` outside are clamped). The lengths at the returned parameters
    match ``s`` to about ``tol * L``. Where the curve stands still over an
    interval (zero speed), any parameter of that interval may be returned.
    """
    tol = _tolerance(tol)
    table = _ArcLengthTable(curve, tol)
    s = as_params(_params(s, "s"), (0.0, table.length), "s")
    return table.parameters_at(s.ravel(), tol).reshape(s.shape)


MAX_PARAMETERS = 10**7
"""Most parameters :func:`equal_arc_length_parameters` returns (each costs a Newton solve)."""


def equal_arc_length_parameters(curve, n: int, tol: float = 1e-12) -> np.ndarray:
    """``n >= 2`` parameters ``(n,)`` cutting the curve into ``n - 1`` pieces of equal length,
    starting and ending at the domain ends; ``n <= 10**7``."""
    n = as_int(n, "n", minimum=2)
    if n > MAX_PARAMETERS:
        raise ParameterError(f"n = {n} exceeds the largest supported count {MAX_PARAMETERS}")
    table = _ArcLengthTable(curve, _tolerance(tol))
    u = table.parameters_at(np.linspace(0.0, table.length, n), tol)
    u[0], u[-1] = table.a, table.b
    return u


def reparametrize_by_arc_length(curve, tol: float = 1e-12) -> ParametricCurve:
    """The same curve parametrized by arc length, as a :class:`ParametricCurve` on ``[0, L]``.

    Evaluation inverts the arc-length table (:func:`arc_length_parameters`,
    accurate to ``tol * L`` in the parameter's length); derivatives up to
    order 3 follow from the curve's own by the chain rule, with
    ``du/ds = 1 / |C'|``: the first derivative is the unit tangent and the
    second the curvature vector. Derivatives raise :class:`DomainError` where
    ``C'`` vanishes.
    """
    tol = _tolerance(tol)
    table = _ArcLengthTable(curve, tol)
    if not table.length > 0:
        raise DomainError("the curve has zero length; it has no arc-length parametrization")
    size, length = _scales(curve)

    def points(s):
        return _ders(curve, table.parameters_at(s, tol), 0)[0]

    def derivatives(s, order):
        if order > 3:
            raise ParameterError(f"order = {order}: an arc-length parametrization offers derivatives up to order 3")
        u = table.parameters_at(s, tol)
        d = _ders(curve, u, max(order, 1))
        out = np.empty((order + 1,) + d.shape[1:])
        out[0] = d[0]
        if order == 0:
            return out
        sigma = np.sqrt(_dot(d[1], d[1]))
        _require_regular(sigma > _ZERO_DERIVATIVE * size / length, u, "the arc-length derivative")
        u1 = 1.0 / sigma  # du/ds
        out[1] = d[1] * u1[:, None]
        if order >= 2:
            sigma_u = _dot(d[1], d[2]) / sigma  # d|C'|/du
            u2 = -sigma_u / sigma**3  # d2u/ds2
            out[2] = d[2] * (u1**2)[:, None] + d[1] * u2[:, None]
        if order >= 3:
            sigma_uu = (_dot(d[2], d[2]) + _dot(d[1], d[3]) - sigma_u**2) / sigma
            u3 = u1 * (-sigma_uu / sigma**3 + 3 * sigma_u**2 / sigma**4)
            out[3] = d[3] * (u1**3)[:, None] + 3 * d[2] * (u1 * u2)[:, None] + d[1] * u3[:, None]
        return out

    return ParametricCurve(points, derivatives, domain=(0.0, table.length))
