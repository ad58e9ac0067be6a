"""Adaptive quadrature over trimmed faces: integrals of smooth integrands over a face's (u, v)
domain to a requested relative tolerance, with an error estimate.

Two rules, both built on a Gauss-Kronrod pair (:mod:`.kronrod`: 7-15, or 10-21 for tolerances
below :data:`HIGHER_ORDER_BELOW`):

- **Untrimmed faces** (natural domain, or one loop around an axis-parallel rectangle):
  :class:`.tensor_rule.TensorRule`, the pair in both directions on cells of the surfaces' Bézier
  patches, every face of the same degrees in one rule.
- **Trimmed faces**: :class:`.green_rule.GreenRule`, Green's theorem along the pcurves with an
  adaptive inner integral across the face.

Both are *globally* adaptive over every face passed at once: each pass evaluates the new pieces
(cells or pcurve intervals) of every rule (one vectorized evaluation per rule), sums values and
error estimates, and bisects the pieces carrying the largest share of the error until the total
error of every component is below ``tol`` times that component's scale. The estimate
``|K - G|`` is the error of the embedded Gauss rule, an upper bound in practice for the Kronrod
value returned: it brackets the true error on smooth integrands (tests check it on closed forms
at every tolerance).

An integrand is a callable ``f(S, Su, Sv, sign) -> (n, k)`` given the points ``S`` ``(n, 3)``,
the partial derivatives ``Su``, ``Sv`` ``(n, 3)`` and the faces' orientations ``sign`` (+1, or -1
for a reversed face: a float, or an ``(n,)`` array when the points come from several faces);
``k`` integrals are computed at once. An integrand may declare ``f.polynomial_degree = d``: when
``Su`` and ``Sv`` are constant (a plane), ``f`` is a polynomial of degree at most ``d`` in ``S``;
Green's rule then integrates across planar faces with a Gauss rule exact for that degree.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import as_positive
from ..errors import ParameterError
from ..tolerances import INTEGRAL_RTOL
from .green_rule import MAX_PIECES, GreenRule
from .kronrod import K15, K21, kronrod15
from .tensor_rule import TensorRule, group_key
from .trim_domain import layout

__all__ = ["Integral", "integrate", "integrate_face", "kronrod15", "DEFAULT_TOLERANCE"]

DEFAULT_TOLERANCE = INTEGRAL_RTOL
"""Default relative tolerance of the integrals."""

HIGHER_ORDER_BELOW = 1e-8
"""Tolerances below this use the 10-21 Gauss-Kronrod pair, above it the 7-15 pair. The estimate is
the Gauss rule's error, so near the limits of double precision the 7-point rule's estimate made
the loop bisect cells whose 15-point values were already exact (the sphere at 1e-10: 46 cells
in three passes with 7-15, eight cells in one pass with 10-21)."""

MAX_PASSES = 80
"""Passes of the outer adaptive loop before it gives up (and reports ``converged=False``)."""


@dataclass(frozen=True)
class Integral:
    """Result of an adaptive integration.

    Attributes
    ----------
    value : (k,) ndarray
        The integrals.
    error : (k,) ndarray
        Error estimates (absolute, same units as ``value``).
    evaluations : int
        Integrand evaluations used.
    converged : bool
        Whether every component met its tolerance.
    """

    value: np.ndarray
    error: np.ndarray
    evaluations: int
    converged: bool


def _rules(faces, integrand, gk, inner_gk):
    """The rules over ``faces``: one :class:`.GreenRule` per face trimmed by anything but an
    axis-parallel rectangle, one :class:`.TensorRule` per group of the other faces' surfaces
    (same degrees and rationality), which evaluates the whole group in one call per pass."""
    rules, groups = [], {}
    for face in faces:
        kind, rect = layout(face)
        if kind == "trimmed":
            rules.append(GreenRule(face, integrand, gk, inner_gk))
        else:
            groups.setdefault(group_key(face.surface), []).append((face, rect))
    rules += [TensorRule([f for f, _ in g], [r for _, r in g], integrand, gk) for g in groups.values()]
    return rules


# ---------------------------------------------------------------------------
# the globally adaptive loop

def integrate(faces, integrand, *, tol: float = DEFAULT_TOLERANCE, scale=None) -> Integral:
    """Integrals of ``integrand`` over the trimmed domains of ``faces``, summed.

    Parameters
    ----------
    faces : sequence of TrimmedFace
    integrand : callable ``f(S, Su, Sv, sign) -> (n, k)``
        ``S``, ``Su``, ``Sv``: ``(n, 3)`` points and partial derivatives; ``sign``: -1.0 for a
        reversed face, else 1.0 (a float, or ``(n,)`` per point). Integrated with respect to
        ``du dv``. Optional attribute ``polynomial_degree`` (see the module's docstring).
    tol : float
        Relative tolerance: the loop stops when every component's error estimate is at most
        ``tol * scale`` of that component.
    scale : callable ``(value (k,), abs_value (k,)) -> (k,)``, optional
        The magnitude each component's error is measured against, from the current estimates of
        the integrals and of the integrals of their absolute values. Default: the integral of
        ``|f|`` (QUADPACK's choice), which is the integral itself for a positive integrand.

    Returns
    -------
    Integral
        ``value`` and ``error`` ``(k,)``, evaluation count, convergence flag.
    """
    tol = as_positive(tol, "tol")
    if tol < 1e-15:
        raise ParameterError(f"tol = {tol!r} is below what double precision can deliver (1e-15)")
    faces = list(faces)
    if not faces:
        raise ParameterError("nothing to integrate: no faces")
    gk = K15 if tol >= HIGHER_ORDER_BELOW else K21
    rules = _rules(faces, integrand, gk, gk)
    new = [r.initial() for r in rules]
    # accepted pieces per rule: pieces, values, errors, absolute values, split info
    pieces = [n[:0] for n in new]
    vals, errs, abss, infos = [None] * len(rules), [None] * len(rules), [None] * len(rules), [None] * len(rules)
    n_eval = 0
    targets = None
    converged = False
    for _pass in range(MAX_PASSES):
        for i, r in enumerate(rules):
            if len(new[i]) == 0:
                continue
            val, err, absval, info, used = r.evaluate(new[i], targets)
            n_eval += used
            if vals[i] is None:
                pieces[i], vals[i], errs[i], abss[i], infos[i] = new[i], val, err, absval, info
            else:
                pieces[i] = np.concatenate([pieces[i], new[i]])
                vals[i] = np.concatenate([vals[i], val])
                errs[i] = np.concatenate([errs[i], err])
                abss[i] = np.concatenate([abss[i], absval])
                if info is not None:
                    infos[i] = tuple(np.concatenate([a, b]) for a, b in zip(infos[i], info))
        total = sum(v.sum(axis=0) for v in vals)
        total_err = sum(e.sum(axis=0) for e in errs)
        total_abs = sum(a.sum(axis=0) for a in abss)
        magnitude = total_abs if scale is None else np.asarray(scale(total, total_abs), dtype=float)
        tiny = np.finfo(float).tiny
        targets = np.maximum(tol * np.abs(magnitude), 1e3 * np.finfo(float).eps * tol * total_abs + tiny)
        if np.all(total_err <= targets):
            converged = True
            break
        if sum(len(p) for p in pieces) > MAX_PIECES:
            break
        # bisect the pieces that carry the largest share of the error: keep (unsplit) the
        # smallest-error pieces whose errors add up to at most half the budget
        scores = [np.max(e / targets, axis=1) for e in errs]
        flat = np.concatenate(scores)
        order = np.argsort(flat)
        keep_flat = np.zeros(flat.size, bool)
        keep_flat[order[np.cumsum(flat[order]) <= 0.5]] = True
        start = 0
        for i, r in enumerate(rules):
            m = len(scores[i])
            split = ~keep_flat[start:start + m]
            start += m
            if not split.any():
                new[i] = pieces[i][:0]
                continue
            info_split = None if infos[i] is None else tuple(a[split] for a in infos[i])
            new[i] = r.split(pieces[i][split], info_split, targets)
            keep = ~split
            pieces[i], vals[i], errs[i], abss[i] = pieces[i][keep], vals[i][keep], errs[i][keep], abss[i][keep]
            if infos[i] is not None:
                infos[i] = tuple(a[keep] for a in infos[i])
    return Integral(np.asarray(total, float), np.asarray(total_err, float), int(n_eval), converged)


def integrate_face(face, integrand, *, tol: float = DEFAULT_TOLERANCE, scale=None) -> Integral:
    """:func:`integrate` over one face."""
    return integrate([face], integrand, tol=tol, scale=scale)
