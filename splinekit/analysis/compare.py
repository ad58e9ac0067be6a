"""Comparing the two sides of a shared edge at its samples: G0 gap, G1 normal angle, G2 jump of
the normal curvature across the edge, on whole arrays of samples.

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
from types import SimpleNamespace

import numpy as np

from .._validate import as_positive
from ..errors import ParameterError
from ..tolerances import CONTINUITY_ANGLE, CONTINUITY_CURVATURE, CONTINUITY_GAP
from .sides import Side

__all__ = ["LEVELS", "EdgeContinuity", "Frame", "compare", "curvature_rows", "edge_tangent", "finite_values", "frame",
           "tolerance_value"]

LEVELS = ("none", "G0", "G1", "G2")
"""Continuity levels from worst to best."""


@dataclass(frozen=True)
class EdgeContinuity:
    """Continuity sampled along one shared edge (arrays ``(n,)`` unless stated).

    ``params``: parameters of side a's pcurve (its use of the edge); ``uv`` ``(n, 2, 2)``: the surface
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
    return default if value is None else as_positive(value, name, allow_zero=True)


def _unit(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    length = np.linalg.norm(x, axis=-1)
    return np.divide(x, length[..., None], out=np.zeros_like(x), where=length[..., None] > 0), length


def finite_values(values: np.ndarray, side: Side, what: str) -> None:
    """A ParameterError naming the patch, side and first sample where ``values`` (``(n, ...)``) are not finite."""
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
    finite_values(c.normal, side, "normals")
    finite_values(np.column_stack([c.k1, c.k2]), side, "curvatures")
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


def curvature_rows(c, rows):
    """The fields of a :class:`~splinekit.diffgeom.curvature.SurfaceCurvature` that :func:`frame`
    and :func:`compare` read, at the rows ``rows`` (a slice or index array)."""
    return SimpleNamespace(normal=c.normal[rows], k1=c.k1[rows], k2=c.k2[rows], directions=c.directions[rows],
                           singular=c.singular[rows])
