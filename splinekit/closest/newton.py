"""Batch Newton search for closest points: every seed of every point at once,
inside the parameter box of its smooth piece, crossing creases while the
distance keeps decreasing (see :mod:`splinekit.closest`)."""

from __future__ import annotations

import numpy as np

MAX_ITERATIONS = 60
"""Newton iterations (rejected steps included) per seed before giving up."""

MAX_PIECE_CROSSINGS = 4
"""How many creases (C0 knot lines) a seed's search may cross."""


def _newton_step(H, G, g, fixed):
    """Newton step ``(m, k)`` for gradient ``g`` with the variables in ``fixed`` held.

    ``H`` is the Hessian of ``|S - P|^2 / 2`` and ``G = J^T J`` its Gauss-Newton
    part. Where the free block of ``H`` is not positive definite (far points,
    strongly curved geometry) it is shifted by twice its most negative
    eigenvalue, which keeps a descent direction of sensible length along the
    direction of negative curvature (plain Gauss-Newton overshoots there).
    """
    free = ~fixed
    g = np.where(free, g, 0.0)
    if g.shape[1] == 1:
        h, gn = H[:, 0, 0], G[:, 0, 0]
        h = np.where(h > 1e-10 * gn, h, np.maximum(gn, -h) + 1e-12 * gn)
        step = -np.divide(g[:, 0], h, out=np.zeros_like(h), where=h > 0)
        return step[:, None]
    a = np.where(free[:, 0], H[:, 0, 0], 1.0)
    c = np.where(free[:, 1], H[:, 1, 1], 1.0)
    b = np.where(free[:, 0] & free[:, 1], H[:, 0, 1], 0.0)
    pd = (a > 0) & (c > 0) & (a * c - b * b > 1e-10 * a * c)
    lam_min = 0.5 * (a + c) - np.sqrt(0.25 * (a - c) ** 2 + b * b)
    shift = np.where(pd, 0.0, 2.0 * np.maximum(-lam_min, 0.0) + 1e-9 * (np.abs(a) + np.abs(c)))
    a, c = a + shift, c + shift
    det = a * c - b * b
    ok = det > 0
    s0 = -np.divide(c * g[:, 0] - b * g[:, 1], det, out=np.zeros_like(det), where=ok)
    s1 = -np.divide(a * g[:, 1] - b * g[:, 0], det, out=np.zeros_like(det), where=ok)
    return np.column_stack([s0, s1])


def _gradients(S, J, H2, P):
    r = S - P
    g = np.einsum("mdk,md->mk", J, r)
    G = np.einsum("mdk,mdl->mkl", J, J)
    H = G + np.einsum("md,mdkl->mkl", r, H2)
    return r, g, G, H


def _derivs_inside(target, x, hi, rows=None):
    """``target.derivs(x)`` with the derivatives of the piece ``x`` belongs to.

    At a crease the derivatives jump, and evaluation takes the piece on the
    right of a knot; a point on the upper end of its box is evaluated one ulp
    to the left so that it gets the derivatives of its own piece. ``rows``: see
    :func:`newton_search`."""
    inner = (x >= hi) & (hi < (target.hi if rows is None else target.hi[rows]))
    if inner.any():
        x = np.where(inner, np.nextafter(hi, -np.inf), x)
    return target.derivs(x) if rows is None else target.derivs(x, rows)


def newton_search(target, P, x0, lo, hi, tol, rows=None):
    """Minimise ``|S(x) - P|`` from each seed ``x0`` ``(m, k)`` inside the boxes ``[lo, hi]`` ``(m, k)``.

    ``target`` is what is searched on, in search units: ``derivs(x)`` -> ``(S (m, dim), J (m,
    dim, k), second derivatives (m, dim, k, k))``, ``evaluate(x)`` -> ``(m, dim)``, ``hi`` (the
    domain's upper ends) and ``size`` (its largest absolute coordinate, for the rounding slack).

    Returns ``(x, S(x), distances, g, converged, stationary)`` with ``g`` the
    gradient of ``|S - P|^2 / 2``; every accepted step does not increase the
    distance, so ``distances`` never exceed the seeds'.

    ``tol`` is one stopping distance or one per seed ``(m,)``. ``rows`` ``(m,)``: for a target
    that holds many geometries (one per row of its own, e.g. the edge uses of a face), the row
    of each seed; it is passed on as ``target.derivs(x, rows)`` / ``target.evaluate(x, rows)``,
    ``target.hi`` is then per row and ``target.size`` per seed.
    """
    tol = np.broadcast_to(np.asarray(tol, dtype=np.float64), x0.shape[:1])
    x = np.clip(x0, lo, hi)
    S, J, H2 = _derivs_inside(target, x, hi, rows)
    dist = np.linalg.norm(S - P, axis=1)
    scale = target.size + np.abs(P).max(axis=1)
    slack = 16 * np.finfo(float).eps * scale  # distances compare equal within rounding
    alpha = np.ones(x.shape[0])
    converged = dist == 0
    active = np.flatnonzero(~converged)
    last, last_x = [], []  # final steps (shorter than tol), checked together after the loop
    for _ in range(MAX_ITERATIONS):
        if active.size == 0:
            break
        xa, Pa, la, ha = x[active], P[active], lo[active], hi[active]
        _, g, G, H = _gradients(S[active], J[active], H2[active], Pa)
        fixed = ((xa <= la) & (g > 0)) | ((xa >= ha) & (g < 0))
        step = _newton_step(H, G, g, fixed) * alpha[active, None]
        xt = np.clip(xa + step, la, ha)
        moved = np.linalg.norm(np.einsum("mdk,mk->md", J[active], xt - xa), axis=1)
        # a step shorter than tol ends the search: it needs the new point only, not its
        # derivatives, so it is evaluated in one batch at the end
        small = moved <= tol[active]
        if small.any():
            converged[active[small]] = True
            last.append(active[small])
            last_x.append(xt[small])
            active, xa, Pa, ha, xt = active[~small], xa[~small], Pa[~small], ha[~small], xt[~small]
            moved = moved[~small]
            if active.size == 0:
                break
        St, Jt, H2t = _derivs_inside(target, xt, ha, None if rows is None else rows[active])
        dt = np.linalg.norm(St - Pa, axis=1)
        accept = dt <= dist[active] + slack[active]
        acc = active[accept]
        x[acc], S[acc], J[acc], H2[acc], dist[acc] = xt[accept], St[accept], Jt[accept], H2t[accept], dt[accept]
        alpha[acc] = np.minimum(1.0, 4.0 * alpha[acc])
        alpha[active[~accept]] *= 0.25
        done = (moved <= tol[active]) | (dt == 0)
        converged[active[done]] = True
        active = active[~done]
    if last:
        idx, xt = np.concatenate(last), np.concatenate(last_x)
        St = target.evaluate(xt) if rows is None else target.evaluate(xt, rows[idx])
        dt = np.linalg.norm(St - P[idx], axis=1)
        ok = dt <= dist[idx] + slack[idx]
        x[idx[ok]], S[idx[ok]], dist[idx[ok]] = xt[ok], St[ok], dt[ok]
    # a seed that ran out of iterations may still sit at a stationary point (slow, linear convergence)
    _, g, G, _ = _gradients(S, J, H2, P)
    fixed = ((x <= lo) & (g > 0)) | ((x >= hi) & (g < 0))
    gfree = np.linalg.norm(np.where(fixed, 0.0, g), axis=1)
    jn = np.sqrt(np.einsum("mkk->m", G))
    stationary = gfree <= 1e-8 * jn * dist + 1e-300
    return x, S, dist, g, converged, stationary


def _search(target, P, owner, x0, tol):
    """Newton from every seed, piece by piece.

    Where the geometry is only C0 (knots of full multiplicity: creases, and
    every knot of degree 1) the distance has a kink and Newton would zigzag, so
    each seed searches inside its smooth piece of the domain. A seed that stops
    on a crease with the gradient pointing across it moves into the
    neighbouring piece and searches on from there (the distance keeps
    decreasing), a few pieces at most.
    """
    left = np.zeros(x0.shape, dtype=bool)
    for j, br in enumerate(target.breaks):
        # a seed on a crease starts in both pieces beside it (samples lie on every knot line)
        on = np.isin(x0[:, j], br[1:-1])
        if on.any():
            flag = left[on]
            flag[:, j] = True
            owner, P, x0 = (np.concatenate([a, a[on]]) for a in (owner, P, x0))
            left = np.concatenate([left, flag])
    piece = np.empty(x0.shape, dtype=np.intp)
    for j, br in enumerate(target.breaks):
        piece[:, j] = np.clip(np.searchsorted(br, x0[:, j], side="right") - 1 - left[:, j], 0, br.size - 2)
    lo, hi = target.boxes(piece)
    x, S, dist, g, converged, stationary = newton_search(target, P, x0, lo, hi, tol)
    rounds = 0
    while rounds < MAX_PIECE_CROSSINGS:
        down = (x <= lo) & (g > 0) & (piece > 0)
        up = (x >= hi) & (g < 0) & (piece < np.array([br.size - 2 for br in target.breaks]))
        move = np.flatnonzero((down | up).any(axis=1))
        if move.size == 0:
            break
        piece[move] += up[move].astype(np.intp) - down[move].astype(np.intp)
        lo, hi = target.boxes(piece)
        res = newton_search(target, P[move], x[move], lo[move], hi[move], tol)
        for arr, new in zip((x, S, dist, g, converged, stationary), res):
            arr[move] = new
        rounds += 1
    return owner, x, S, dist, converged, stationary


def nearest_per_point(owner, dist, n):
    """Index (into the seeds) of the nearest result of each of the ``n`` points."""
    order = np.lexsort((dist, owner))
    first = np.ones(order.size, dtype=bool)
    first[1:] = owner[order[1:]] != owner[order[:-1]]
    best = order[first]
    if best.size != n:  # every point has at least one seed by construction
        raise AssertionError("a point without seeds")
    return best
