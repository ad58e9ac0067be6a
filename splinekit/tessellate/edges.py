"""Edges of trimmed faces, sampled once in 3-D and shared by every face that uses them.

A B-rep edge has one *use* per face (:class:`~splinekit.brep.Edge`: a pcurve in the face's
``(u, v)`` plane and, optionally, the 3-D curve with the same parameter). For a watertight mesh
both faces of an edge must meet at the same points, so the uses are first grouped (by their
``key``; uses without a key by geometry: the same 3-D points at 0, 1/4, 1/2, 3/4 and 1 of the
edge, either direction), then each group is sampled once:

* the parameters start from the 3-D curve's adaptive polyline (:func:`.curves.tessellate_curve`,
  the same chordal bounds as every curve) or, without a 3-D curve, from the pcurve's knot spans;
* every segment is then measured, for the 3-D curve and for every use: the distance between the
  exact point at the segment's parametric midpoint and the chord's midpoint (for a use: the
  surface at the midpoint of the two samples' ``(u, v)``, the same yardstick the face triangles
  are measured with), and segments over the tolerance are split, a few rounds;
* each use maps the group's parameters onto its own pcurve (affinely, same or opposite
  direction; Gauss-Newton onto the use's curve where the affine map is off), so both faces carry
  ``(u, v)`` images of the very same 3-D points.

Degenerate uses (a pole: the 3-D image is one point) are not shared: their pcurve is sampled
uniformly at the spacing of the face's interior grid, and every sample is the same 3-D vertex.
"""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from .curves import tessellate_curve

__all__ = ["EdgeUse", "group_uses", "sample_groups"]

EDGE_FRACTIONS = np.array([0.0, 0.25, 0.5, 0.75, 1.0])
"""Where along an edge the geometric pairing compares uses."""
MAX_ROUNDS = 8
"""Largest number of measure-and-split rounds per edge."""
MAX_SEGMENTS = 1 << 16
"""Largest number of segments of one edge."""
MAX_SCALED_STEP = 2.0
"""Longest edge segment in a face's scaled parameter plane (units of the interior grid's step):
longer segments are split so the triangles along a trim are not needle fans."""


class EdgeUse:
    """One face's use of an edge, with where it sits: face ``f``, loop ``loop``, position ``pos``."""

    __slots__ = ("f", "loop", "pos", "edge", "face")

    def __init__(self, f, loop, pos, edge, face):
        self.f, self.loop, self.pos, self.edge, self.face = f, loop, pos, edge, face

    def on_surface(self, t):
        """``((k, 2) uv, (k, 3) points)`` of the pcurve parameters ``t`` on the face's surface."""
        uv = self.edge.pcurve.evaluate(np.asarray(t, dtype=np.float64))
        return uv, self.face.surface.evaluate(uv[:, 0], uv[:, 1])


def _face_name(face, f):
    return f"face {f}" + (f" ({face.name!r})" if face.name else "")


def group_uses(faces, weld: float):
    """All edge uses of ``faces`` and their groups.

    Returns ``(uses, groups)``: ``uses`` a list of :class:`EdgeUse` (face after face, loop after
    loop), ``groups`` a list of lists of use indices. Uses with equal keys form a group; keyless,
    non-degenerate uses are paired geometrically (the five points of :data:`EDGE_FRACTIONS` within
    ``weld`` of each other, in the same or the opposite direction); degenerate uses stay alone.
    This is the tessellator's own pairing; :mod:`splinekit.brep` topology may supply the pairing
    of a shell instead.
    """
    from .surfaces import _close_pairs, _components

    uses = [EdgeUse(f, l, k, e, face)
            for f, face in enumerate(faces) for l, loop in enumerate(face.boundary_loops()) for k, e in enumerate(loop)]  # fmt: skip
    by_key: dict = {}
    loose = []
    singles = []
    for i, u in enumerate(uses):
        if u.edge.degenerate:
            singles.append([i])
        elif u.edge.key is not None:
            by_key.setdefault(u.edge.key, []).append(i)
        else:
            loose.append(i)
    groups = list(by_key.values()) + singles
    if loose:
        pts = np.stack([_probe(uses[i]) for i in loose])  # (k, 5, 3)
        lab = np.arange(len(loose))
        pairs = _close_pairs(pts[:, 2], weld)
        if len(pairs):
            A, B = pts[pairs[:, 0]], pts[pairs[:, 1]]
            same = (np.linalg.norm(A - B, axis=-1) <= weld).all(axis=1)
            flip = (np.linalg.norm(A - B[:, ::-1], axis=-1) <= weld).all(axis=1)
            ok = pairs[same | flip]
            lab = _components(len(loose), ok[:, 0], ok[:, 1])
        order = np.argsort(lab, kind="stable")
        cuts = np.flatnonzero(np.diff(lab[order])) + 1
        groups += [[loose[j] for j in part] for part in np.split(order, cuts)]
    return uses, groups


def _probe(use):
    """``(5, 3)`` points of a use at :data:`EDGE_FRACTIONS` of its domain."""
    a, b = use.edge.domain
    if use.edge.curve is not None:
        return use.edge.curve.evaluate(a + (b - a) * EDGE_FRACTIONS)
    return use.on_surface(a + (b - a) * EDGE_FRACTIONS)[1]


class SampledGroup:
    """The samples of one edge group.

    Attributes
    ----------
    points : (m + 1, 3) the shared 3-D points (one point for a degenerate use)
    params : dict use index -> (m + 1,) the use's own pcurve parameters, in the use's direction
    uv : dict use index -> (m + 1, 2) the use's ``(u, v)`` at those parameters
    degenerate : bool
    """

    __slots__ = ("points", "params", "uv", "degenerate")


def sample_groups(uses, groups, scales, tol, angle_tol):
    """Sample every group (see the module docstring). ``scales`` ``(F, 2)`` per face: parameter
    units -> interior grid steps in u and v. Returns a list of :class:`SampledGroup`."""
    return [_sample(uses, g, scales, tol, angle_tol) for g in groups]


def _sample(uses, group, scales, tol, angle_tol):
    out = SampledGroup()
    first = uses[group[0]]
    if first.edge.degenerate:
        a, b = first.edge.domain
        uv_ab = first.edge.pcurve.evaluate(np.array([a, b]))
        steps = np.abs(np.diff(uv_ab, axis=0)[0]) * scales[first.f]
        n = int(np.clip(np.ceil(np.hypot(*steps)), 1, MAX_SEGMENTS))
        t = np.linspace(a, b, n + 1)
        uv, X = first.on_surface(t)
        out.points, out.params, out.uv, out.degenerate = X[:1], {group[0]: t}, {group[0]: uv}, True
        return out
    rep_i = next((i for i in group if uses[i].edge.curve is not None), group[0])
    rep = uses[rep_i]
    a, b = rep.edge.domain
    if rep.edge.curve is not None:
        curve = rep.edge.curve

        def exact(t):
            return curve.evaluate(t)

        t = np.asarray(tessellate_curve(curve, tol, angle_tol).params)
    else:

        def exact(t):
            return rep.on_surface(t)[1]

        br = rep.edge.pcurve.bezier_breakpoints()
        br = br[(br >= a) & (br <= b)]
        br = np.unique(np.concatenate([[a], br, [b]]))
        t = np.concatenate([np.linspace(br[:-1], br[1:], 5, endpoint=False, axis=1).ravel(), [b]])
    maps = {i: _param_map(rep, uses[i], a, b) for i in group}
    for _ in range(MAX_ROUNDS):
        X = exact(t)
        tm = 0.5 * (t[:-1] + t[1:])
        factor = np.linalg.norm(exact(tm) - 0.5 * (X[:-1] + X[1:]), axis=1) / tol
        uvs = {}
        for i in group:
            use = uses[i]
            s = maps[i](t, X)
            uv = use.edge.pcurve.evaluate(s)
            uvs[i] = (s, uv)
            mid = 0.5 * (uv[:-1] + uv[1:])
            dev = np.linalg.norm(use.face.surface.evaluate(mid[:, 0], mid[:, 1]) - 0.5 * (X[:-1] + X[1:]), axis=1)
            factor = np.maximum(factor, dev / tol)
            step = np.hypot(*(np.diff(uv, axis=0) * scales[use.f]).T)
            # the scaled-length criterion is linear in the step, the chordal one quadratic
            factor = np.maximum(factor, (step / MAX_SCALED_STEP) ** 2)
        over = factor > 1.0
        if not over.any() or t.size > MAX_SEGMENTS:
            break
        pieces = np.where(over, np.ceil(np.minimum(np.sqrt(factor) * 1.1, 8.0)), 1).astype(np.int64)
        frac = np.arange(pieces.sum()) - np.repeat(np.cumsum(pieces) - pieces, pieces)
        seg = np.repeat(np.arange(pieces.size), pieces)
        t = np.concatenate([t[seg] + (t[seg + 1] - t[seg]) * (frac / pieces[seg]), t[-1:]])
    out.points, out.degenerate = X, False
    out.params = {i: s for i, (s, _) in uvs.items()}
    out.uv = {i: uv for i, (_, uv) in uvs.items()}
    return out


def _param_map(rep, use, a, b):
    """A function ``(t, X) -> s``: the use's pcurve parameters of the representative's
    parameters ``t`` (points ``X``). Affine (same or opposite direction, decided at one third
    of the edge), refined by Gauss-Newton steps onto the use's curve where the affine image
    lies off the representative's points."""
    if use is rep:
        return lambda t, X: t
    c, d = use.edge.domain
    probe = a + (b - a) / 3.0
    ref = rep.edge.curve.evaluate(np.array([probe])) if rep.edge.curve is not None else rep.on_surface([probe])[1]
    fwd = use.on_surface([c + (d - c) / 3.0])[1]
    bwd = use.on_surface([d - (d - c) / 3.0])[1]
    flip = np.linalg.norm(bwd - ref) < np.linalg.norm(fwd - ref)

    def affine(t, X):
        r = (t - a) / (b - a)
        s = d - r * (d - c) if flip else c + r * (d - c)
        return _project(use, s, X, c, d)

    return affine


def _project(use, s, X, c, d, rounds: int = 6):
    """Gauss-Newton steps moving the parameters ``s`` so that the use's surface points approach
    ``X`` (only where the affine guess is off by more than rounding)."""
    uv, P = use.on_surface(s)
    size = np.abs(X).max() + 1.0
    off = np.linalg.norm(P - X, axis=1) > 1e-9 * size
    off[[0, -1]] = False  # the ends are the edge's vertices: keep them on the domain's ends
    if not off.any():
        return s
    s = s.copy()
    idx = np.flatnonzero(off)
    for _ in range(rounds):
        D = use.edge.pcurve.derivatives(s[idx], 1)  # (2, k, 2)
        uv = D[0]
        S = use.face.surface.derivatives(uv[:, 0], uv[:, 1], 1)  # (2, 2, k, 3)
        F1 = S[1, 0] * D[1][:, :1] + S[0, 1] * D[1][:, 1:]
        r = X[idx] - S[0, 0]
        denom = np.einsum("ij,ij->i", F1, F1)
        step = np.einsum("ij,ij->i", F1, r) / np.where(denom > 0, denom, 1.0)
        s[idx] = np.clip(s[idx] + step, min(c, d), max(c, d))
        if np.all(np.abs(step) <= 1e-14 * (abs(d - c) + 1.0)):
            break
    return s
