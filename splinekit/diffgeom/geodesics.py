"""Geodesics on parametric surfaces.

A geodesic ``(u(s), v(s))`` satisfies ``x''^k + Gamma^k_ij x'^i x'^j = 0`` with
the Christoffel symbols of the first fundamental form,
``Gamma^k_ij = (I^-1)^kl (S_l . S_ij)``. :func:`trace_geodesic` integrates this
initial value problem by arc length (scipy's DOP853); :func:`geodesic` finds
the shortest path between two points: a shortest path in a graph on a
parameter grid (16-neighbourhood, 3-D chord weights) picks the route, and a
boundary value problem (``scipy.integrate.solve_bvp``) makes it a geodesic;
where collocation fails, a minimum of the discrete path energy replaces it.

A surface closed in ``u`` or ``v`` (its two opposite boundary curves and first
derivatives coincide, as on a revolved sphere's seam) is treated as periodic
there: geodesics cross the seam. Points where the parametrization is singular
(``Su x Sv = 0``, a sphere's poles) cannot be crossed: the equations are
singular there.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import as_float_array, as_int, as_real
from ..errors import ConvergenceError, DomainError, ParameterError
from .protocol import as_surface

__all__ = ["Geodesic", "christoffel_symbols", "geodesic", "trace_geodesic"]


@dataclass(frozen=True)
class Geodesic:
    """A geodesic path sampled at ``m`` points.

    ``uv`` ``(m, 2)`` parameters (inside the domain), ``points`` ``(m, 3)``,
    ``s`` ``(m,)`` arc length from the start, ``length`` (the total), and
    ``stopped`` (``trace_geodesic``: True when the path ran into a domain
    boundary before reaching the requested length).
    """

    uv: np.ndarray
    points: np.ndarray
    s: np.ndarray
    length: float
    stopped: bool = False


def christoffel_symbols(derivatives: np.ndarray) -> np.ndarray:
    """``Gamma[..., k, i, j]`` (``(..., 2, 2, 2)``) from surface partials
    ``(3, 3, ..., dim)`` (as returned by ``surface.derivatives(u, v, 2)``; a
    larger leading ``(order + 1, order + 1)`` block is accepted).

    Raises :class:`ParameterError` for another shape, non-finite partials or a
    singular first fundamental form (``S_u`` and ``S_v`` parallel).
    """
    d = as_float_array(derivatives, "derivatives")
    if d.ndim < 3 or d.shape[0] < 3 or d.shape[1] < 3 or d.shape[-1] < 2:
        raise ParameterError(
            f"derivatives must have shape (3, 3, ..., dim) with dim >= 2 (partials up to order 2), got {d.shape}"
        )
    d = d[:3, :3]
    if not np.isfinite(d).all():
        raise ParameterError("derivatives must be finite")
    J = np.stack([d[1, 0], d[0, 1]], -2)  # (..., 2, dim): rows S_u, S_v
    second = np.stack([np.stack([d[2, 0], d[1, 1]], -2), np.stack([d[1, 1], d[0, 2]], -2)], -3)  # (..., 2, 2, dim)
    first = J @ np.swapaxes(J, -1, -2)  # (..., 2, 2): [[E, F], [F, G]]
    proj = np.einsum("...ld,...ijd->...lij", J, second)  # S_l . S_ij
    det = first[..., 0, 0] * first[..., 1, 1] - first[..., 0, 1] ** 2
    inv = np.stack([np.stack([first[..., 1, 1], -first[..., 0, 1]], -1), np.stack([-first[..., 1, 0], first[..., 0, 0]], -1)], -2)
    bad = ~(det > 0)
    if bad.any():
        index = [int(i) for i in np.argwhere(bad)[0]]
        raise ParameterError(
            f"the first fundamental form is singular at point {index} (S_u and S_v parallel): "
            "the Christoffel symbols are undefined there"
        )
    inv = inv / det[..., None, None]
    return np.einsum("...kl,...lij->...kij", inv, proj)


class _Periodic:
    """Evaluation of a surface with its closed directions unwrapped."""

    def __init__(self, surface):
        self.surface = as_surface(surface)
        (a, b), (c, d) = surface.domain
        if not all(np.isfinite(x) for x in (a, b, c, d)):
            raise ParameterError("geodesics need a surface with a bounded parameter domain")
        self.lo = np.array([a, c])
        self.period = np.array([b - a, d - c])
        self.closed = np.array([self._closed(0), self._closed(1)])

    def _closed(self, axis: int) -> bool:
        """Opposite boundaries coincide with equal first derivatives."""
        t = np.linspace(0.0, 1.0, 17)
        (a, b), (c, d) = self.surface.domain
        other = (c + (d - c) * t) if axis == 0 else (a + (b - a) * t)
        lo = np.full_like(other, a if axis == 0 else c)
        hi = np.full_like(other, b if axis == 0 else d)
        uv0 = (lo, other) if axis == 0 else (other, lo)
        uv1 = (hi, other) if axis == 0 else (other, hi)
        d0 = self.surface.derivatives(*uv0, 1)
        d1 = self.surface.derivatives(*uv1, 1)
        scale = max(1.0, float(np.abs(d0[0, 0]).max()))
        along = (1, 0) if axis == 0 else (0, 1)
        same_point = np.abs(d0[0, 0] - d1[0, 0]).max() <= 1e-9 * scale
        dscale = max(1e-300, float(np.abs(d0[along]).max()))
        same_tangent = np.abs(d0[along] - d1[along]).max() <= 1e-7 * dscale
        return bool(same_point and same_tangent)

    def wrap(self, uv: np.ndarray) -> np.ndarray:
        """Parameters folded into the domain along closed directions."""
        uv = np.array(uv, dtype=np.float64)
        for k in (0, 1):
            if self.closed[k]:
                uv[..., k] = self.lo[k] + np.mod(uv[..., k] - self.lo[k], self.period[k])
        return uv

    def derivatives(self, uv: np.ndarray, order: int) -> np.ndarray:
        w = self.wrap(uv)
        hi = self.lo + self.period
        w = np.clip(w, self.lo, hi)  # rounding at the border
        return self.surface.derivatives(w[..., 0], w[..., 1], order)

    def inside(self, uv: np.ndarray, slack: float = 0.0) -> np.ndarray:
        ok = np.ones(uv.shape[:-1], dtype=bool)
        for k in (0, 1):
            if not self.closed[k]:
                pad = slack * self.period[k]
                ok &= (uv[..., k] >= self.lo[k] - pad) & (uv[..., k] <= self.lo[k] + self.period[k] + pad)
        return ok


def _rhs_acceleration(per: _Periodic, uv: np.ndarray, vel: np.ndarray) -> np.ndarray:
    """``-Gamma(vel, vel)`` for ``uv``, ``vel`` of shape ``(n, 2)``; a singular
    first fundamental form (``EG - F^2`` vanishing: ``Su x Sv = 0``) or a
    diverging state raises :class:`DomainError`."""
    if not (np.isfinite(uv).all() and np.isfinite(vel).all()):
        raise DomainError("the geodesic diverged (non-finite parameters): it ran into a singular point")
    d = per.derivatives(uv, 2)
    E, F, G = (np.einsum("nd,nd->n", x, y) for x, y in ((d[1, 0], d[1, 0]), (d[1, 0], d[0, 1]), (d[0, 1], d[0, 1])))
    weak = E * G - F * F <= 1e-12 * (E + G) ** 2
    if weak.any():
        i = int(np.argmax(weak))
        raise DomainError(
            f"the parametrization is singular at (u, v) = {per.wrap(uv[i]).tolist()} (Su x Sv = 0): "
            "a geodesic cannot pass through it"
        )
    return -np.einsum("nkij,ni,nj->nk", christoffel_symbols(d), vel, vel)


def _boundary_event(axis: int, bound: float):
    """A terminal ``solve_ivp`` event: parameter ``axis`` reaches ``bound``."""

    def event(_s, y):
        return y[axis] - bound

    event.terminal = True
    return event


MAX_SAMPLES = 10**7
"""Most sample points a geodesic result may hold."""

MAX_EVALUATIONS = 200_000
"""Budget of right-hand-side evaluations of :func:`trace_geodesic` (about a minute)."""

MAX_GRID = 1024
"""Largest route-finding grid of :func:`geodesic` (``grid**2`` nodes, 8 edges each)."""

MIN_RTOL = 100 * np.finfo(float).eps
"""Smallest relative tolerance the DOP853 integrator honours."""


def _as_samples(value) -> int:
    n = as_int(value, "samples", minimum=2)
    if n > MAX_SAMPLES:
        raise ParameterError(f"samples = {n} exceeds the largest supported count {MAX_SAMPLES}")
    return n


def _as_uv(value, name):
    uv = as_float_array(value, name).ravel()
    if uv.shape != (2,) or not np.isfinite(uv).all():
        raise ParameterError(f"{name} must be a finite (u, v) pair, got {value!r}")
    return uv


def _check_in_domain(per: _Periodic, uv, name):
    (a, b), (c, d) = per.surface.domain
    if not (a <= uv[0] <= b and c <= uv[1] <= d):
        raise DomainError(f"{name} = {uv.tolist()} lies outside the domain [{a}, {b}] x [{c}, {d}]")


def trace_geodesic(surface, start_uv, direction, length, *, samples: int = 201, rtol: float = 1e-10) -> Geodesic:
    """The geodesic from ``start_uv`` in ``direction``, ``length`` long.

    ``direction`` is a tangent vector in space (3 components, projected onto
    the tangent plane) or in parameters (2 components, ``(du, dv)``); only its
    direction matters. Integrated by arc length with DOP853 at relative
    tolerance ``rtol``; sampled at ``samples`` points equally spaced in arc
    length. At most ``MAX_EVALUATIONS`` (200000) evaluations of the geodesic
    equation are spent (ConvergenceError beyond: a bound, not a hang, for long
    paths on closed surfaces). A path reaching a boundary of the domain that is not closed stops
    there (``stopped=True``, ``length`` then the length travelled).
    """
    per = _Periodic(surface)
    uv0 = _as_uv(start_uv, "start_uv")
    _check_in_domain(per, uv0, "start_uv")
    length = as_real(length, "length")
    if not length > 0:
        raise ParameterError(f"length must be positive, got {length!r}")
    samples = _as_samples(samples)
    rtol = as_real(rtol, "rtol")
    if not MIN_RTOL <= rtol < 1:
        raise ParameterError(f"rtol must lie in [{MIN_RTOL:.3g}, 1) (the integrator's limit), got {rtol!r}")
    from scipy.integrate import solve_ivp  # imported here: keeps `import splinekit` fast

    d = per.derivatives(uv0[None], 1)
    J = np.stack([d[1, 0, 0], d[0, 1, 0]], 1)  # (dim, 2)
    vec = as_float_array(direction, "direction").ravel()
    if vec.shape == (2,):
        w = vec
    elif vec.shape == (J.shape[0],):
        w = np.linalg.lstsq(J, vec, rcond=None)[0]
    else:
        raise ParameterError(f"direction must have 2 (parameter) or {J.shape[0]} (space) components, got {vec.shape}")
    speed = np.linalg.norm(J @ w)
    if not np.isfinite(speed) or speed <= 1e-14 * max(1.0, np.linalg.norm(vec)):
        raise ParameterError(f"direction {vec.tolist()} has no component in the tangent plane at {uv0.tolist()}")
    y0 = np.concatenate([uv0, w / speed])

    calls = [0]

    def rhs(s, y):
        # a bound on the work, not a hang, for a long path on a closed surface
        calls[0] += 1
        if calls[0] > MAX_EVALUATIONS:
            raise ConvergenceError(
                f"trace_geodesic gave up after {MAX_EVALUATIONS} evaluations at arc length {float(s):.6g} of the "
                f"requested length {length!r}; ask for a shorter path or a larger rtol"
            )
        return np.concatenate([y[2:], _rhs_acceleration(per, y[None, :2], y[None, 2:])[0]])

    events = [_boundary_event(k, bound) for k in (0, 1) if not per.closed[k] for bound in (per.lo[k], per.lo[k] + per.period[k])]
    # a start on a non-closed boundary heading inward must not stop at once
    if any(e(0.0, y0) == 0.0 for e in events):
        y0[:2] = y0[:2] + 1e-12 * per.period * np.sign(y0[2:])
    sol = solve_ivp(rhs, (0.0, length), y0, method="DOP853", rtol=rtol, atol=rtol * 1e-2 * per.period.min(),
                    dense_output=True, events=events or None)  # fmt: skip
    if sol.status == -1:
        raise ConvergenceError(f"the geodesic integration failed: {sol.message}")
    end = float(sol.t[-1])
    s = np.linspace(0.0, end, samples)
    uv = sol.sol(s)[:2].T
    uv = per.wrap(uv)
    return Geodesic(uv=uv, points=per.derivatives(uv, 0)[0, 0], s=s, length=end, stopped=sol.status == 1)


def _grid_path(per: _Periodic, a: np.ndarray, b: np.ndarray, n: int) -> np.ndarray:
    """A shortest path from ``a`` to ``b`` in a graph on an ``n x n`` parameter
    grid (16-neighbourhood, weights the 3-D chord lengths): ``(k, 2)`` unwrapped
    parameters from ``a`` to ``b`` (``b`` shifted by whole periods when the
    path crosses a seam)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import dijkstra

    t = np.linspace(0.0, 1.0, n)
    U, V = np.meshgrid(per.lo[0] + per.period[0] * t, per.lo[1] + per.period[1] * t, indexing="ij")
    nodes = np.column_stack([U.ravel(), V.ravel()])
    nodes = np.vstack([nodes, a, b])
    X = per.derivatives(nodes, 0)[0, 0]
    ia, ib = n * n, n * n + 1
    I, Jn = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    src, dst = [], []
    for di, dj in [(1, 0), (0, 1), (1, 1), (1, -1), (2, 1), (1, 2), (2, -1), (1, -2)]:
        i2, j2 = I + di, Jn + dj
        ok = np.ones_like(i2, dtype=bool)
        for idx, k in ((i2, 0), (j2, 1)):
            if per.closed[k]:  # node n-1 coincides with node 0: wrap over n - 1 nodes
                idx[idx > n - 1] -= n - 1
                idx[idx < 0] += n - 1
            ok &= (idx >= 0) & (idx <= n - 1)
        src.append((I * n + Jn)[ok])
        dst.append((i2 * n + j2)[ok])
    # the end points link to the grid nodes of their cell's 4 x 4 neighbourhood
    h = per.period / (n - 1)
    for node, p in ((ia, a), (ib, b)):
        ci = np.clip(np.floor((p - per.lo) / h).astype(int), 0, n - 2)
        ii, jj = np.meshgrid(np.arange(ci[0] - 1, ci[0] + 3), np.arange(ci[1] - 1, ci[1] + 3), indexing="ij")
        ok = (ii >= 0) & (ii < n) & (jj >= 0) & (jj < n)
        src.append(np.full(int(ok.sum()), node))
        dst.append((ii * n + jj)[ok])
    src, dst = np.concatenate(src), np.concatenate(dst)
    w = np.linalg.norm(X[src] - X[dst], axis=1) + 1e-300
    both = np.concatenate([src, dst]), np.concatenate([dst, src])
    graph = coo_matrix((np.concatenate([w, w]), both), shape=(n * n + 2,) * 2).tocsr()
    _, pred = dijkstra(graph, indices=ia, return_predecessors=True)
    if pred[ib] < 0:
        raise ConvergenceError("no path on the parameter grid joins the two points")
    chain = [ib]
    while chain[-1] != ia:
        chain.append(int(pred[chain[-1]]))
    uv = nodes[chain[::-1]]
    # unwrap across seams: a step longer than half a period went the other way
    step = np.diff(uv, axis=0)
    for k in (0, 1):
        if per.closed[k]:
            step[:, k] -= per.period[k] * np.round(step[:, k] / per.period[k])
    uv = np.vstack([uv[:1], uv[:1] + np.cumsum(step, axis=0)])
    return np.array(uv)


def geodesic(surface, start_uv, end_uv, *, samples: int = 201, tol: float = 1e-6, grid: int = 48) -> Geodesic:
    """The shortest path on ``surface`` between two parameter pairs.

    A shortest path in a graph on a ``grid x grid`` parameter grid (``4 <= grid <= 1024``) picks the
    route; a boundary value problem on the geodesic equation
    (``solve_bvp``, residual tolerance ``tol``) makes it a geodesic. The length
    integrates ``|S_u u' + S_v v'|`` over the solution (Gauss-Legendre); being
    stationary at a geodesic, it is accurate to about ``tol**2``. Where
    collocation fails (parametrizations that are only C1, such as rational
    splines with double knots, make the residual jump at knot lines), the
    path is the minimum of the discrete path energy on 256 and 512 segments
    instead: points within about ``1e-5`` of the model size of the geodesic,
    the length (Richardson-extrapolated) to about ``1e-10`` relative. Returns
    a :class:`Geodesic` sampled at ``samples`` points equally spaced in arc
    length.
    """
    per = _Periodic(surface)
    a, b = _as_uv(start_uv, "start_uv"), _as_uv(end_uv, "end_uv")
    _check_in_domain(per, a, "start_uv")
    _check_in_domain(per, b, "end_uv")
    samples = _as_samples(samples)
    grid = as_int(grid, "grid", minimum=4)
    if grid > MAX_GRID:
        raise ParameterError(f"grid = {grid} exceeds the largest supported route grid {MAX_GRID} (x {MAX_GRID} nodes)")
    tol = as_real(tol, "tol")
    if not 0 < tol < 1:
        raise ParameterError(f"tol must lie in (0, 1), got {tol!r}")
    pa, pb = per.derivatives(np.array([a, b]), 0)[0, 0]
    size = max(1.0, float(np.abs(per.derivatives(_corners(per), 0)[0, 0]).max()))
    if np.linalg.norm(pa - pb) <= 1e-14 * size:
        uv = np.repeat(a[None], samples, 0)
        return Geodesic(uv=uv, points=np.repeat(pa[None], samples, 0), s=np.zeros(samples), length=0.0)
    path = _grid_path(per, a, b, grid)
    sol, guess = _collocation(per, a, path, tol)
    if sol is not None:
        return _sampled(per, sol, samples)
    return _discrete(per, guess, samples)


def _corners(per: _Periodic) -> np.ndarray:
    t = np.linspace(0.0, 1.0, 5)
    U, V = np.meshgrid(per.lo[0] + per.period[0] * t, per.lo[1] + per.period[1] * t, indexing="ij")
    return np.column_stack([U.ravel(), V.ravel()])


def _speed(per, uv, vel):
    d = per.derivatives(uv, 1)
    return np.linalg.norm(d[1, 0] * vel[:, :1] + d[0, 1] * vel[:, 1:2], axis=1)


def _collocation(per: _Periodic, a, path, tol):
    """``solve_bvp`` on the geodesic equation seeded by the graph ``path``
    (unwrapped parameters): ``(solution or None, the seed (2, k))``."""
    from scipy.integrate import solve_bvp

    X = per.derivatives(path, 0)[0, 0]
    seg = np.linalg.norm(np.diff(X, axis=0), axis=1)
    t_nodes = np.concatenate([[0.0], np.cumsum(seg)]) / seg.sum()
    t_nodes, keep = np.unique(t_nodes, return_index=True)
    path = path[keep]
    t = np.linspace(0.0, 1.0, max(2 * len(path), 32))
    # the graph path zigzags: seed with a smooth least-squares polynomial
    # through it (end points kept exactly), whose velocity is smooth too
    deg = int(min(7, len(path) - 1))
    coef = np.polynomial.polynomial.polyfit(t_nodes, path, deg)
    smooth = np.polynomial.polynomial.polyval(t, coef).T  # (k, 2)
    ends = np.polynomial.polynomial.polyval(np.array([0.0, 1.0]), coef).T
    smooth += (path[0] - ends[0]) * (1 - t)[:, None] + (path[-1] - ends[1]) * t[:, None]
    guess = smooth.T
    vel = np.polynomial.polynomial.polyval(t, np.polynomial.polynomial.polyder(coef)) + (path[-1] - ends[1] - path[0] + ends[0])[:, None]
    y_guess = np.vstack([guess, vel])
    b_unwrapped = path[-1]

    def rhs(_t, y):
        return np.vstack([y[2:], _rhs_acceleration(per, y[:2].T, y[2:].T).T])

    def bc(ya, yb):
        return np.concatenate([ya[:2] - a, yb[:2] - b_unwrapped])

    try:
        sol = solve_bvp(rhs, bc, t, y_guess, tol=tol, max_nodes=10000)
    except DomainError:  # an iterate ran into a singular point
        return None, guess
    return (sol if sol.success else None), guess


def _sampled(per: _Periodic, sol, samples) -> Geodesic:
    """The collocation solution as a :class:`Geodesic`: length by Gauss-Legendre
    on every mesh interval, samples equally spaced in arc length."""
    x, wts = np.polynomial.legendre.leggauss(8)
    lo, hi = sol.x[:-1], sol.x[1:]
    tq = (0.5 * (hi - lo)[:, None] * (x[None] + 1) + lo[:, None]).ravel()
    yq = sol.sol(tq)
    speed = _speed(per, yq[:2].T, yq[2:].T).reshape(len(lo), -1)
    pieces = (speed * wts[None]).sum(1) * 0.5 * (hi - lo)
    total = float(pieces.sum())
    # arc length at the mesh nodes, then linear in t within each interval
    # (the parametrization is close to constant speed)
    s_nodes = np.concatenate([[0.0], np.cumsum(pieces)])
    s = np.linspace(0.0, total, samples)
    ts = np.interp(s, s_nodes, sol.x)
    uv = per.wrap(sol.sol(ts)[:2].T)
    return Geodesic(uv=uv, points=per.derivatives(uv, 0)[0, 0], s=s, length=total)


def _discrete(per: _Periodic, guess: np.ndarray, samples: int, n: int = 256) -> Geodesic:
    """The shortest path as a minimum of the discrete energy
    ``sum |X(p_i+1) - X(p_i)|^2`` over ``n + 1`` parameter points with fixed
    ends (Gauss-Newton, banded normal equations; only first derivatives, so
    C1 parametrizations are no obstacle). The minimizer is an equally spaced
    polyline on a geodesic; its length converges as ``n^-2`` and Richardson
    extrapolation over ``n`` and ``2n`` makes it ``O(n^-4)``."""
    lengths = []
    path = guess.T
    for m in (n, 2 * n):
        t = np.linspace(0.0, 1.0, m + 1)
        tg = np.linspace(0.0, 1.0, len(path))
        z = np.column_stack([np.interp(t, tg, path[:, 0]), np.interp(t, tg, path[:, 1])])
        z = _energy_minimum(per, z)
        X = per.derivatives(z, 0)[0, 0]
        lengths.append(float(np.linalg.norm(np.diff(X, axis=0), axis=1).sum()))
        path = z
    total = (4.0 * lengths[1] - lengths[0]) / 3.0
    # the minimizer is (nearly) equally spaced: sample it by index
    idx = np.linspace(0.0, len(path) - 1.0, samples)
    uv = np.column_stack([np.interp(idx, np.arange(len(path)), path[:, k]) for k in (0, 1)])
    uv = per.wrap(uv)
    return Geodesic(uv=uv, points=per.derivatives(uv, 0)[0, 0], s=np.linspace(0.0, total, samples), length=total)


def _energy_minimum(per: _Periodic, z: np.ndarray, iterations: int = 50) -> np.ndarray:
    """Gauss-Newton on the discrete path energy; ``z`` ``(m + 1, 2)`` with the
    two ends fixed."""
    from scipy.sparse import csr_matrix
    from scipy.sparse.linalg import spsolve

    m = len(z) - 1
    z = z.copy()

    def energy_parts(z):
        d = per.derivatives(z, 1)
        X, J = d[0, 0], np.stack([d[1, 0], d[0, 1]], -1)  # (m+1, dim), (m+1, dim, 2)
        return X, J, np.diff(X, axis=0)

    X, J, r = energy_parts(z)
    energy = float((r * r).sum())
    dim = X.shape[1]
    rows = np.arange(m)[:, None, None] * dim + np.arange(dim)[None, :, None]
    for _ in range(iterations):
        # r_i = X_{i+1} - X_i; unknowns: interior points 1..m-1
        blocks_hi = J[1:]  # d r_i / d z_{i+1}
        blocks_lo = -J[:-1]  # d r_i / d z_i
        data, ri, ci = [], [], []
        for blocks, col_of in ((blocks_hi, np.arange(1, m + 1)), (blocks_lo, np.arange(0, m))):
            keep = (col_of >= 1) & (col_of <= m - 1)
            cols = (col_of[keep] - 1)[:, None, None] * 2 + np.arange(2)[None, None, :]
            data.append(blocks[keep].ravel())
            ri.append(np.broadcast_to(rows[keep], blocks[keep].shape).ravel())
            ci.append(np.broadcast_to(cols, blocks[keep].shape).ravel())
        A = csr_matrix((np.concatenate(data), (np.concatenate(ri), np.concatenate(ci))), shape=(m * dim, 2 * (m - 1)))
        step = spsolve((A.T @ A).tocsc(), -(A.T @ r.ravel()))
        if not np.isfinite(step).all():
            break
        step = step.reshape(m - 1, 2)
        scale = 1.0
        while scale > 1e-4:
            trial = z.copy()
            trial[1:-1] += scale * step
            Xt, Jt, rt = energy_parts(trial)
            e = float((rt * rt).sum())
            if e <= energy:
                break
            scale *= 0.5
        else:
            break
        z, X, J, r = trial, Xt, Jt, rt
        done = energy - e <= 1e-15 * energy
        energy = e
        if done or np.abs(scale * step).max() <= 1e-13 * per.period.max():
            break
    return z
