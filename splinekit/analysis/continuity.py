"""Continuity across the edge two faces or surfaces share: G0 gap, G1 normal angle, G2 jump of
the normal curvature across the edge, sampled along the edge all at once.

Along an edge with unit tangent ``t``, each side ``s`` has its unit normal ``n_s`` and its
cross-edge direction ``c_s``: the unit tangent of the surface perpendicular to ``t`` pointing into
the face. The two normals are oriented consistently: ``b``'s normal is flipped when needed so that
the two faces run the edge in opposite senses (``c_a x n_a = -(c_b x n_b)``), as in a
consistently oriented shell; ``a``'s normal is its outward one (``-Su x Sv`` on a reversed B-rep
face). Then, per sample,

* ``gap`` = ``|S_a - S_b|`` (model units): the distance from the point of ``a``'s use to the
  closest point of ``b``'s use;
* ``angle`` = the angle between ``n_a`` and ``n_b`` (radians, 0 for a tangent joint, up to pi);
* ``normal_curvature[:, s]`` = the normal curvature of side ``s`` in its direction ``c_s``
  (1 / length; positive when the surface bends toward the oriented normal: the sign convention of
  :func:`splinekit.curvature`), from Euler's formula on the principal curvatures;
  ``curvature_jump`` = ``|k_b - k_a|``; ``curvature_vector_jump`` = ``|k_a n_a - k_b n_b|``, the
  difference of the curvature vectors of the two normal sections across the edge.

A G1 joint whose normal curvatures across the edge agree is G2: the curvatures along the edge and
the twist agree already when the normals agree all along it. The levels, per sample and for the
edge (its worst sample): ``"G2"``, ``"G1"``, ``"G0"``, ``"none"`` under the tolerances
``gap_tol`` (model units), ``angle_tol`` (radians) and ``curvature_tol`` (relative: the jump over
the larger of the two ``|k|`` and ``1 / edge length``).

Where a surface's parametrization degenerates (a pole, a collapsed side: ``Su x Sv = 0``) the
normal and curvatures are the limits :func:`splinekit.curvature` extrapolates and ``singular``
flags the sample; nothing is NaN. At a Catmull-Clark extraordinary vertex the patch's derivatives
shrink to zero without vanishing exactly: the exact limit normal of the vertex replaces the
evaluator's approximate one, and since the curvature there depends on the direction of approach
(the limit surface is G1, not G2, at the vertex) the sample is flagged ``extraordinary`` (and
``singular``) and is at most G1.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validate import as_int
from ..closest import project
from ..diffgeom.curvature import curvature
from ..errors import ParameterError
from ..tolerances import CONTINUITY_ANGLE, CONTINUITY_CURVATURE, CONTINUITY_GAP, CONTINUITY_MATCH, GEOMETRIC_CONFUSION
from .matching import POLYLINE, NoSharedEdgeError, lies_on, polyline, shared_edge
from .sides import SIDE_NAMES, Side, Trace, as_patch, extraordinary_corners, sides_of

__all__ = ["LEVELS", "EdgeContinuity", "Frame", "NoSharedEdgeError", "compare", "edge_continuity", "edge_tangent", "frame",
           "measure", "tolerance_value"]

LEVELS = ("none", "G0", "G1", "G2")
"""Continuity levels from worst to best."""



@dataclass(frozen=True)
class EdgeContinuity:
    """Continuity sampled along one shared edge (arrays ``(n,)`` unless stated).

    ``params``: parameters of the sampled use's pcurve; ``uv`` ``(n, 2, 2)``: the surface
    parameters on side a (``[:, 0]``) and b (``[:, 1]``); ``points`` ``(n, 3)``: the points on a;
    ``normals`` ``(n, 2, 3)``: the oriented unit normals; ``across`` ``(n, 2, 3)``: the unit
    cross-edge directions into each face (those of the normal curvatures); ``gap``, ``angle`` (radians),
    ``normal_curvature`` ``(n, 2)``, ``curvature_jump``, ``curvature_vector_jump`` (module
    docstring); ``singular``: a normal is degenerate there (limit values); ``extraordinary``: at a
    Catmull-Clark extraordinary vertex (also singular; at most G1); ``sample_levels``:
    the level of each sample; ``level``: the edge's (worst sample's). ``sides``: the names of the
    two uses (``"u0"``... for natural sides); ``patches``: indices of the two faces in the caller's
    list; ``flipped``: b's normal was turned to match a's orientation; ``gap_tol``, ``angle_tol``,
    ``curvature_tol``: the tolerances used.
    """

    params: np.ndarray
    uv: np.ndarray
    points: np.ndarray
    normals: np.ndarray
    across: np.ndarray
    gap: np.ndarray
    angle: np.ndarray
    normal_curvature: np.ndarray
    curvature_jump: np.ndarray
    curvature_vector_jump: np.ndarray
    singular: np.ndarray
    extraordinary: np.ndarray
    sample_levels: np.ndarray
    level: str
    sides: tuple
    patches: tuple
    flipped: bool
    gap_tol: float
    angle_tol: float
    curvature_tol: float

    @property
    def max_gap(self) -> float:
        """Largest G0 gap along the edge (model units)."""
        return float(self.gap.max())

    @property
    def max_angle(self) -> float:
        """Largest angle between the normals (radians)."""
        return float(self.angle.max())

    @property
    def max_curvature_jump(self) -> float:
        """Largest jump of the normal curvature across the edge (1 / length)."""
        return float(self.curvature_jump.max())

    def __repr__(self):
        return (f"EdgeContinuity({self.level}, sides {self.sides}, {self.gap.size} samples, max gap {self.max_gap:.3g}, "
                f"max angle {self.max_angle:.3g} rad, max curvature jump {self.max_curvature_jump:.3g})")


def tolerance_value(value, name: str, default: float) -> float:
    """``value`` checked finite and >= 0, or ``default`` for None."""
    if value is None:
        return default
    try:
        value = float(value)
    except (TypeError, ValueError, OverflowError):
        raise ParameterError(f"{name} must be a number, got {value!r}") from None
    if not (np.isfinite(value) and value >= 0):
        raise ParameterError(f"{name} must be finite and >= 0, got {value!r}")
    return value


def _unit(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    length = np.linalg.norm(x, axis=-1)
    return np.divide(x, length[..., None], out=np.zeros_like(x), where=length[..., None] > 0), length


def _finite(values: np.ndarray, side: Side, what: str) -> None:
    bad = ~np.isfinite(values).reshape(len(values), -1).all(axis=1)
    if bad.any():
        raise ParameterError(f"patch {side.patch} gives non-finite {what} along its side {side.name} "
                             f"(sample {int(np.flatnonzero(bad)[0])})")


def _majority_sign(values: np.ndarray) -> float:
    """+1 or -1: the sign of the weighted majority (values near 0 weigh little)."""
    return 1.0 if float(values.sum()) >= 0 else -1.0


@dataclass(frozen=True)
class Frame:
    """One side of an edge at its samples (arrays ``(n, ...)``): the use ``side``, its pcurve
    ``params``, surface parameters ``uv``, ``points``, unit ``normal`` (``Su x Sv``, or the exact
    limit normal at an extraordinary vertex), ``across`` (unit, in the tangent plane,
    perpendicular to the edge, into the face), its curvature ``c``
    (:class:`~splinekit.diffgeom.curvature.SurfaceCurvature`) and the ``extraordinary`` mask."""

    side: Side
    params: np.ndarray
    uv: np.ndarray
    points: np.ndarray
    normal: np.ndarray
    across: np.ndarray
    c: object
    extraordinary: np.ndarray


def frame(side: Side, params, uv, d_uv, ders, c, tangent, extraordinary, corner_normals=None) -> Frame:
    """The :class:`Frame` of a use from its surface's first derivatives ``ders`` ``(2, 2, n, 3)``,
    curvature ``c``, the pcurve's derivative ``d_uv`` ``(n, 2)`` and the edge's unit ``tangent``;
    ``corner_normals`` ``(n, 3)``: exact normals where ``extraordinary``."""
    _finite(c.normal, side, "normals")
    _finite(np.column_stack([c.k1, c.k2]), side, "curvatures")
    normal = np.array(c.normal)
    if corner_normals is not None and extraordinary.any():
        # the evaluator's normal at an extraordinary vertex is approximate; up to sign, the exact one
        ref = corner_normals[extraordinary]
        normal[extraordinary] = ref * np.sign(np.einsum("ij,ij->i", normal[extraordinary], ref))[:, None]
    # into the face: left of the pcurve's direction in (u, v), mapped to space; its sign decides
    # between the two perpendiculars n x t and t x n (robust where the map degenerates at a pole)
    left = np.column_stack([-d_uv[:, 1], d_uv[:, 0]])
    m = ders[1, 0] * left[:, :1] + ders[0, 1] * left[:, 1:]
    across, _ = _unit(np.cross(normal, tangent))
    s = np.einsum("ij,ij->i", m, across)
    sign = np.where(np.abs(s) > 1e-9 * np.linalg.norm(m, axis=1), np.sign(s), _majority_sign(s))
    return Frame(side, params, uv, ders[0, 0], normal, across * sign[:, None], c, extraordinary)


def _side_frame(side: Side, t: np.ndarray, tangent=None) -> tuple[Frame, np.ndarray]:
    """:func:`frame` of a use at its pcurve parameters ``t`` and the edge tangent used
    (``tangent`` None: the use's own)."""
    uv = side.uv(t)
    c = curvature(side.surface, uv[:, 0], uv[:, 1])
    ders = np.asarray(side.surface.derivatives(uv[:, 0], uv[:, 1], 1), dtype=np.float64)
    _finite(ders[0, 0], side, "points")
    d_uv = np.asarray(side.pcurve.derivatives(t, 1), dtype=np.float64).reshape(2, -1, 2)[1]
    if tangent is None:
        tangent = edge_tangent(ders, d_uv)
    extraordinary = np.zeros(len(uv), dtype=bool)
    corner_normals = None
    corners, normals = extraordinary_corners(side.surface)
    if len(corners):
        near = np.all(np.abs(uv[:, None, :] - corners[None]) <= 1e-12, axis=2)  # (n, k)
        extraordinary = near.any(axis=1)
        if normals is not None:
            corner_normals = normals[np.argmax(near, axis=1)]
    return frame(side, t, uv, d_uv, ders, c, tangent, extraordinary, corner_normals), tangent


def edge_tangent(ders: np.ndarray, d_uv: np.ndarray) -> np.ndarray:
    """Unit tangents ``(n, 3)`` of a use, ``Su u' + Sv v'`` normalized; central differences of
    the points where that vanishes (a pole at an end of the edge)."""
    tangent, length = _unit(ders[1, 0] * d_uv[:, :1] + ders[0, 1] * d_uv[:, 1:])
    weak = length <= 1e-9 * max(1e-300, float(length.max()))
    if weak.any():
        fallback, _ = _unit(np.gradient(ders[0, 0], axis=0))
        tangent[weak] = fallback[weak]
    return tangent


def _normal_curvature(c, across: np.ndarray) -> np.ndarray:
    """Euler's formula: normal curvature ``(n,)`` in the unit tangent directions ``across``."""
    a = np.einsum("ij,ij->i", across, c.directions[:, 0])
    b = np.einsum("ij,ij->i", across, c.directions[:, 1])
    return c.k1 * a * a + c.k2 * b * b


def _corresponding(inner: Side, outer: Side, f: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Pcurve parameters ``(n,)`` on ``outer`` of the points ``points`` of ``inner`` at fractions
    ``f``: the same or the reversed fractions when the two uses coincide there (the common case of
    patches sharing their boundary with proportional parametrizations), else the closest points."""
    t = outer.fractions(np.concatenate([f, 1.0 - f]))
    Q = outer.points(t).reshape(2, len(f), -1)
    d = np.linalg.norm(Q - points[None], axis=2).max(axis=1)
    k = int(np.argmin(d))
    if d[k] <= GEOMETRIC_CONFUSION * max(1.0, float(np.abs(points).max())):
        return t.reshape(2, -1)[k]
    return _closest_on(outer, points)


def _closest_on(outer: Side, points: np.ndarray) -> np.ndarray:
    """Pcurve parameters ``(n,)`` of the points of ``outer``'s use closest to ``points``,
    seeded from its polyline (a local search)."""
    poly = polyline(outer)
    nearest = np.argmin(np.linalg.norm(points[:, None] - poly[None], axis=2), axis=1)
    seeds = outer.fractions(nearest / (POLYLINE - 1))
    return np.asarray(project(Trace(outer), points, seeds=seeds).parameters, dtype=np.float64).reshape(-1)


def measure(inner: Side, outer: Side, samples: int, *, gap_tol=None, angle_tol=None, curvature_tol=None,
            swap: bool = False) -> EdgeContinuity:
    """Continuity along ``inner``'s use sampled at ``samples`` equal pcurve steps, against
    ``outer``'s use. ``swap``: report ``outer`` as side a (the caller's first face) and ``inner``
    as side b. Tolerances as in :func:`edge_continuity`."""
    f = np.linspace(0.0, 1.0, samples)
    fi, tangent = _side_frame(inner, inner.fractions(f))
    fo, _ = _side_frame(outer, _corresponding(inner, outer, f, fi.points), tangent)
    return compare(fo, fi, gap_tol, angle_tol, curvature_tol) if swap else compare(fi, fo, gap_tol, angle_tol, curvature_tol)


def compare(fa: Frame, fb: Frame, gap_tol=None, angle_tol=None, curvature_tol=None) -> EdgeContinuity:
    """The :class:`EdgeContinuity` of two frames at corresponding samples (a's normal leads)."""
    A, B = fa.side, fb.side
    extraordinary = fa.extraordinary | fb.extraordinary
    # orientation: the faces run the edge in opposite senses, c x n = -(c' x n')
    runs = np.einsum("ij,ij->i", np.cross(fa.across, fa.normal), np.cross(fb.across, fb.normal))
    relative = -_majority_sign(runs)
    sign_a = -1.0 if A.flip else 1.0
    sign_b = sign_a * relative
    na, nb = sign_a * fa.normal, sign_b * fb.normal
    ka = sign_a * _normal_curvature(fa.c, fa.across)
    kb = sign_b * _normal_curvature(fb.c, fb.across)
    P, Q = fa.points, fb.points
    gap = np.linalg.norm(P - Q, axis=1)
    angle = np.arctan2(np.linalg.norm(np.cross(na, nb), axis=1), np.einsum("ij,ij->i", na, nb))
    jump = np.abs(kb - ka)
    vector_jump = np.linalg.norm(ka[:, None] * na - kb[:, None] * nb, axis=1)

    size = max(1.0, float(np.abs(P).max()))
    length = float(np.linalg.norm(np.diff(P, axis=0), axis=1).sum())
    gap_tol = tolerance_value(gap_tol, "gap_tol", max(CONTINUITY_GAP * size, A.tolerance, B.tolerance))
    angle_tol = tolerance_value(angle_tol, "angle_tol", CONTINUITY_ANGLE)
    curvature_tol = tolerance_value(curvature_tol, "curvature_tol", CONTINUITY_CURVATURE)
    scale = np.maximum(np.maximum(np.abs(ka), np.abs(kb)), 1.0 / length if length > 0 else 0.0)
    g0 = gap <= gap_tol
    g1 = g0 & (angle <= angle_tol)
    g2 = g1 & (jump <= curvature_tol * scale) & ~extraordinary
    index = g0.astype(int) + g1 + g2
    levels = np.array(LEVELS)[index]
    return EdgeContinuity(
        params=fa.params, uv=np.stack([fa.uv, fb.uv], axis=1), points=P, normals=np.stack([na, nb], axis=1),
        across=np.stack([fa.across, fb.across], axis=1), gap=gap, angle=angle,
        normal_curvature=np.column_stack([ka, kb]), curvature_jump=jump, curvature_vector_jump=vector_jump, singular=fa.c.singular | fb.c.singular | extraordinary,
        extraordinary=extraordinary, sample_levels=levels, level=LEVELS[int(index.min())], sides=(A.name, B.name),
        patches=(A.patch, B.patch), flipped=relative < 0, gap_tol=gap_tol, angle_tol=angle_tol,
        curvature_tol=curvature_tol,
    )  # fmt: skip


def _given_side(sides: list, spec, which: str) -> Side:
    """The use named by ``spec``: a side name (``"u0"``, ``"u1"``, ``"v0"``, ``"v1"``), an index into
    the face's edges, or one of its Edge objects."""
    if isinstance(spec, str):
        found = [s for s in sides if s.name == spec]
        if not found:
            names = ", ".join(s.name for s in sides)
            raise ParameterError(f"edge side {spec!r} of {which} is not one of its sides ({names}; natural sides "
                                 f"are named {', '.join(SIDE_NAMES)})")
        return found[0]
    if isinstance(spec, (int, np.integer)) and not isinstance(spec, bool):
        if not 0 <= int(spec) < len(sides):
            raise ParameterError(f"edge index {int(spec)} of {which} is outside 0..{len(sides) - 1}")
        return sides[int(spec)]
    pc = getattr(spec, "pcurve", None)
    found = [s for s in sides if pc is not None and s.pcurve is pc]
    if not found:
        raise ParameterError(f"edge {spec!r} is not an edge of {which}: give a side name, an index or one of its Edges")
    return found[0]


def edge_continuity(a, b, samples: int = 64, *, edge=None, gap_tol=None, angle_tol=None, curvature_tol=None,
                    match_rtol=None) -> EdgeContinuity:
    """G0/G1/G2 continuity along the edge shared by ``a`` and ``b``.

    Parameters
    ----------
    a, b
        B-rep faces (:class:`~splinekit.brep.TrimmedFace`, e.g. faces of a Shell or Solid) or
        parametric surfaces in 3-D (B-spline, NURBS or Bézier patches,
        :class:`~splinekit.SubdivisionPatch`, anything with ``domain``, ``evaluate`` and
        ``derivatives``). ``a`` may be ``b`` (a face meeting itself across a seam).
    samples : int
        Samples along the edge (>= 2), end points included, at equal steps of the sampled use's
        pcurve parameter.
    edge : (side_a, side_b), optional
        The uses that form the edge, each a natural side name (``"u0"``, ``"u1"``, ``"v0"``,
        ``"v1"``: the side ``u = u0``...), an index into the face's edges, or one of its
        :class:`~splinekit.brep.Edge` objects. By default the shared edge is found: uses with one
        B-rep key, else the pair of sides of which one lies on the other (either direction and
        parametrization; one may be part of the other).
    gap_tol : float, optional
        G0 tolerance (model units); default ``CONTINUITY_GAP`` times the model size (largest
        absolute coordinate along the edge, at least 1), at least the faces' own tolerances.
    angle_tol : float, optional
        G1 tolerance on the normals' angle (radians); default ``CONTINUITY_ANGLE``.
    curvature_tol : float, optional
        G2 tolerance on the curvature jump relative to ``max(|k_a|, |k_b|, 1 / edge length)``;
        default ``CONTINUITY_CURVATURE``.
    match_rtol : float, optional
        How close (relative to its length) a use must lie on the other to be the shared edge;
        default ``CONTINUITY_MATCH``.

    Returns
    -------
    EdgeContinuity
        ``.gap``, ``.angle``, ``.curvature_jump``, ``.normal_curvature``, ``.params``,
        ``.points``, ``.level`` ("G2", "G1", "G0" or "none"), per-edge maxima... (module docstring
        for the definitions and the orientation of the normals).

    Raises
    ------
    NoSharedEdgeError
        (a ParameterError) ``a`` and ``b`` share no edge.
    ParameterError
        Not a face or 3-D surface, bad ``samples``, ``edge`` or tolerance, a surface that evaluates
        to non-finite values.
    """
    samples = as_int(samples, "samples", minimum=2)
    match_rtol = tolerance_value(match_rtol, "match_rtol", CONTINUITY_MATCH)
    as_patch(a, "a")
    as_patch(b, "b")
    same = a is b
    sides_a = sides_of(0, a)
    sides_b = sides_a if same else sides_of(1, b)
    if edge is not None:
        if isinstance(edge, (str, bytes)) or not isinstance(edge, (tuple, list)) or len(edge) != 2:
            raise ParameterError(f"edge must be a pair (side of a, side of b), got {edge!r}")
        spec_a, spec_b = edge
        x, y = _given_side(sides_a, spec_a, "a"), _given_side(sides_b, spec_b, "b")
        if x.degenerate or y.degenerate:
            raise ParameterError("the given edge collapses to a point on one face: it has no length to sample")
        px, py = polyline(x), polyline(y)
        from_a = lies_on(px, py) <= lies_on(py, px)
        inner, outer = (x, y) if from_a else (y, x)
    else:
        inner, outer = shared_edge(sides_a, sides_b, match_rtol, same=same)
        from_a = same or any(inner is s for s in sides_a)
    return measure(inner, outer, samples, gap_tol=gap_tol, angle_tol=angle_tol, curvature_tol=curvature_tol,
                   swap=not from_a)
