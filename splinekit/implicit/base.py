"""The base class of every implicit surface: :class:`Implicit`.

An implicit surface is the zero set of a function ``F: R^3 -> R``, negative
inside and positive outside (the signed-distance convention). A subclass
implements

* ``_value(points)``: ``(n, 3)`` float64 points (already checked finite) ->
  ``(n,)`` values;
* optionally ``_gradient(points)`` -> ``(n, 3)``, ``_value_gradient(points)``
  -> both at once (when they share work), and ``_hessian(points)`` ->
  ``(n, 3, 3)``. Without them the gradient comes from fourth-order central
  differences of ``_value`` and the Hessian from the same differences of
  ``_gradient``, with step :attr:`Implicit.step` (``RELATIVE_STEP`` times the
  largest extent of :attr:`bounds`, or ``RELATIVE_STEP`` model units when
  unbounded). The truncation error is ``O(h^4)`` and the rounding error
  ``O(eps |F| / h)``: about ``1e-12`` relative for a smooth ``F`` whose
  features are of the size of the bounds. Across a kink of ``F`` (a box edge,
  a CSG seam) within ``2 h`` of the point the difference is a blend of the two
  sides, not a derivative.

and passes ``bounds`` (an axis-aligned box containing the zero set, or None)
and ``exact`` (whether ``F`` is a true signed distance) to ``__init__``.

Everything public validates its input and works on whole arrays: ``F(points)``,
:meth:`~Implicit.gradient`, :meth:`~Implicit.normal`, :meth:`~Implicit.hessian`,
:meth:`~Implicit.closest_points`, :meth:`~Implicit.to_mesh`. Implicits are
immutable; operators and transforms return new ones:

=====================  =================================  =================================
expression             function                           exact signed distance when
=====================  =================================  =================================
``a | b``              ``min(a, b)`` (union)              never claimed: exact outside only
``a & b``              ``max(a, b)`` (intersection)       never claimed: exact inside only
``a - b``              ``max(a, -b)`` (difference)        never claimed
``-a``                 ``-a`` (complement)                ``a`` is
``a.translate(v)``     ``a(p - v)``                       ``a`` is
``a.rotate(R)``        ``a(R^T p)``                       ``a`` is
``a.scale(s)``         ``s a(p / s)``                     ``a`` is
``a.offset(r)``        ``a - r``                          ``a`` is, is convex and ``r >= 0``
``a.shell(t)``         ``|a| - t / 2``                    never claimed: exact outside only
=====================  =================================  =================================

Why ``min`` is not exact inside: a point inside ``A`` only gets ``F = a``, its
depth in ``A``, but the nearest boundary point of ``A ∪ B`` may be farther (the
nearest point of ``∂A`` can lie inside ``B``). ``F`` is then a bound on the
distance (its magnitude is never larger than the distance), which is still
enough for meshing and for :meth:`closest_points` to land on ``F = 0``.

Curvature and projection work through the shared protocol:
``splinekit.curvature(implicit, points)`` and ``splinekit.project(implicit,
points)``.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_int
from ..diffgeom.protocol import ImplicitSurface, _nonzero_norm
from ..errors import ConvergenceError, DomainError, SplineKitError
from ..tolerances import FD_STEP
from ._checks import check_bounds, check_points, positive  # noqa: F401 - also part of this module's names
from .meshing import mesh_implicit

__all__ = ["CLOSEST_MAX_ITER", "RELATIVE_STEP", "Implicit"]

RELATIVE_STEP = FD_STEP
"""Finite-difference step relative to the largest extent of the bounds."""

CLOSEST_MAX_ITER = 50
"""Default iteration budget of :meth:`Implicit.closest_points`."""

# fourth-order central first difference on offsets -2..2 (divide by h)
_D1 = np.array([1.0, -8.0, 0.0, 8.0, -1.0]) / 12.0
_OFFSETS = np.arange(-2, 3, dtype=np.float64)




class Implicit(ImplicitSurface):
    """An implicit surface ``F(p) = 0``, ``F < 0`` inside (see the module notes).

    Parameters (for subclasses)
    ---------------------------
    bounds : (lo (3,), hi (3,)) or None
        An axis-aligned box containing the zero set, such that ``F > 0``
        everywhere outside it (``F`` at least the distance to the box for the
        built-in implicits); None when the zero set is unbounded.
    exact : bool
        Whether ``F`` is a true signed distance (``|grad F| = 1`` off the
        medial axis).
    convex : bool
        Whether the solid ``F <= 0`` is convex (lets :meth:`offset` keep
        exactness).
    growth : float
        For every ``t >= 0`` the set ``F <= t`` lies within ``bounds`` grown
        by ``growth * t`` on every side (1 for a true signed distance, the
        default); offsets and shells grow their boxes by it.
    """

    # defaults for subclasses that do not call __init__
    _bounds = None
    _exact = False
    _convex = False
    _growth = 1.0

    def __init__(self, *, bounds=None, exact: bool = False, convex: bool = False, growth: float = 1.0):
        # ImplicitSurface.__init__ is not called: F, gradient and hessian are
        # methods here, and the step is a property
        self._bounds = check_bounds(bounds)
        self._exact = bool(exact)
        self._convex = bool(convex)
        self._growth = positive(growth, "growth")

    # -- what subclasses provide ------------------------------------------------------------
    def _value(self, p: np.ndarray) -> np.ndarray:
        raise NotImplementedError(f"{type(self).__name__} must implement _value(points) -> (n,)")

    def _gradient(self, p: np.ndarray) -> np.ndarray:
        return self._central(lambda q: self._value(q)[:, None], p)[..., 0]

    def _value_gradient(self, p: np.ndarray):
        """``(_value(p), _gradient(p))``; subclasses that share work between the
        two (CSG trees: one pass instead of re-evaluating every subtree) override it."""
        return self._value(p), self._gradient(p)

    def _hessian(self, p: np.ndarray) -> np.ndarray:
        # [n, axis j, component i] = d(grad_i)/dx_j, symmetrized by the caller
        return self._central(self._gradient, p)

    # -- properties ---------------------------------------------------------------------------
    @property
    def bounds(self):
        """``(lo (3,), hi (3,))``: a box containing the zero set, or None when unbounded."""
        return self._bounds

    @property
    def is_exact_sdf(self) -> bool:
        """True when ``F`` is the signed distance itself (``|grad F| = 1``)."""
        return self._exact

    @property
    def step(self) -> float:
        """Finite-difference step in model units: ``RELATIVE_STEP`` times the
        largest extent of the bounds (1 when unbounded or flat)."""
        if self._bounds is None:
            return RELATIVE_STEP
        size = float(np.max(self._bounds[1] - self._bounds[0]))
        return RELATIVE_STEP * (size if size > 0 else 1.0)

    def __repr__(self):
        return f"{type(self).__name__}(exact={self._exact}, bounds={self._box_text()})"

    def _box_text(self):
        if self._bounds is None:
            return "None"
        return f"({self._bounds[0].tolist()}, {self._bounds[1].tolist()})"

    # -- evaluation -----------------------------------------------------------------------------
    @staticmethod
    def _points(points) -> np.ndarray:
        return check_points(points)

    def _eval(self, fn, p, shape, what):
        """``fn(p)`` checked for shape and finiteness; overflow and invalid
        operations become a DomainError naming the first bad point (not a
        RuntimeWarning and a NaN)."""
        if len(p) == 0:  # no call: numeric differences cannot reshape an empty stencil
            return np.zeros((0,) + shape)
        with np.errstate(all="ignore"):
            out = fn(p)
        return self._checked(out, p, shape, what)

    def _eval_both(self, p):
        """Checked ``(F (n,), grad F (n, 3))`` in one pass."""
        with np.errstate(all="ignore"):
            F, g = self._value_gradient(p)
        return self._checked(F, p, (), "F"), self._checked(g, p, (3,), "gradient")

    def _checked(self, out, p, shape, what):
        out = np.asarray(out, dtype=np.float64)
        if out.shape != (len(p),) + shape:
            raise SplineKitError(f"{type(self).__name__}.{what} returned shape {out.shape}, expected {(len(p),) + shape}")
        if out.size == 0:
            return out
        finite = np.isfinite(out.reshape(len(p), -1)).all(axis=1)
        if not finite.all():
            i = int(np.argmin(finite))
            raise DomainError(f"{what} of {type(self).__name__} is not finite at points[{i}] = {p[i].tolist()}")
        return out

    def __call__(self, points) -> np.ndarray:
        """``F`` at ``(n, 3)`` points: ``(n,)`` (model units for a signed distance)."""
        p = self._points(points)
        return self._eval(self._value, p, (), "F")

    def gradient(self, points) -> np.ndarray:
        """``grad F`` at ``(n, 3)`` points: ``(n, 3)`` (analytic where the subclass
        gives it, else central differences with step :attr:`step`)."""
        p = self._points(points)
        return self._eval(self._gradient, p, (3,), "gradient")

    def hessian(self, points) -> np.ndarray:
        """The (symmetrized) Hessian of ``F`` at ``(n, 3)`` points: ``(n, 3, 3)``."""
        p = self._points(points)
        H = self._eval(self._hessian, p, (3, 3), "hessian")
        return 0.5 * (H + np.swapaxes(H, 1, 2))

    def normal(self, points) -> np.ndarray:
        """Unit normals ``grad F / |grad F|``: ``(n, 3)``, outward. A vanishing
        gradient (a sphere's centre, the medial axis of a box) raises
        :class:`~splinekit.errors.DomainError` naming the point."""
        p = self._points(points)
        g = self._eval(self._gradient, p, (3,), "gradient")
        return g / _nonzero_norm(g, p, "gradient")[:, None]

    def closest_points(self, points, tol=None, max_iter: int = CLOSEST_MAX_ITER) -> np.ndarray:
        """Points of the zero set near each of ``points``: ``(n, 3)``.

        Iterates ``q <- q - F(q) grad F(q) / |grad F(q)|^2`` (Newton along the
        gradient) until ``|F(q)| <= tol`` (times ``|grad F|``, i.e. a distance);
        a step that increases ``|F|`` (overshooting a seam of a CSG tree) is
        retried at half the length.
        For an exact SDF one step lands on the closest point; for other
        implicits the result is a nearby point of ``F = 0``, not necessarily
        the closest one.

        Parameters
        ----------
        points : (n, 3) finite points
        tol : float, optional
            Distance in model units; default ``1e-10`` times the largest
            coordinate magnitude of the bounds (of the points when
            unbounded), at least ``1e-10``.
        max_iter : int
            Iteration budget.

        Raises
        ------
        DomainError
            The gradient vanishes at an iterate (a point on the medial axis:
            the closest point is not unique); the message names the point.
        ConvergenceError
            ``|F|`` did not reach ``tol`` within ``max_iter`` steps.
        """
        p = self._points(points)
        max_iter = as_int(max_iter, "max_iter", minimum=1)
        if tol is None:
            size = 1.0
            if self._bounds is not None:
                size = max(size, float(np.max(np.abs(np.concatenate(self._bounds)))))
            elif p.size:
                size = max(size, float(np.max(np.abs(p))))
            tol = 1e-10 * size
        else:
            tol = positive(tol, "tol")
        q = p.copy()
        active = np.arange(len(p))
        # a step that makes |F| worse (overshooting across a CSG seam, where the gradient
        # jumps) is undone and retried at half the length; a good step restores the length
        alpha = np.ones(len(p))
        prev_q = p.copy()
        prev_F = np.full(len(p), np.inf)
        prev_g = np.zeros_like(p)
        for _ in range(max_iter + 1):
            if active.size == 0:
                break
            qa = q[active]
            F, g = self._eval_both(qa)
            worse = np.abs(F) > np.abs(prev_F[active])
            if worse.any():
                w = active[worse]
                qa[worse], F[worse], g[worse] = prev_q[w], prev_F[w], prev_g[w]
                q[w] = prev_q[w]
                alpha[w] *= 0.5
            alpha[active[~worse]] = np.minimum(1.0, 2.0 * alpha[active[~worse]])
            gg = np.einsum("ij,ij->i", g, g)
            done = np.abs(F) <= tol * np.sqrt(gg)
            keep = ~done
            active, qa, F, g, gg = active[keep], qa[keep], F[keep], g[keep], gg[keep]
            if active.size == 0:
                break
            zero = ~(gg > 1e-28)
            if zero.any():
                i = int(np.argmax(zero))
                raise DomainError(
                    f"the gradient vanishes at {qa[i].tolist()} (iterate of points[{int(active[i])}] = "
                    f"{p[active[i]].tolist()}): the closest point is undefined there"
                )
            step = (F / gg)[:, None] * g
            step = self._crease_step(step, qa, F, g, gg, prev_q[active], prev_F[active], prev_g[active], worse[keep])
            prev_q[active], prev_F[active], prev_g[active] = qa, F, g
            with np.errstate(all="ignore"):
                q[active] = qa - alpha[active][:, None] * step
            bad = ~np.isfinite(q[active]).all(axis=1)
            if bad.any():
                i = int(active[np.argmax(bad)])
                raise ConvergenceError(f"the closest-point iteration of points[{i}] = {p[i].tolist()} diverged")
        else:
            i = int(active[0])
            raise ConvergenceError(
                f"closest point of points[{i}] = {p[i].tolist()} did not reach |F| <= {tol:.3g} in "
                f"{max_iter} steps (|F| = {abs(float(prev_F[i])):.3g})"
            )
        return q

    @staticmethod
    def _crease_step(step, q, F, g, gg, q0, F0, g0, retried):
        """Newton steps near a seam of a CSG tree. Where the gradient turned by
        more than about 25 degrees since the previous iterate, the iterate
        zig-zags between two pieces of ``F`` (a crease): step instead to the
        nearest point where both pieces' linearizations vanish (the
        minimum-norm solution of ``g . d = F``, ``g0 . d = F0 + g0 . (q - q0)``)."""
        g0g0 = np.einsum("ij,ij->i", g0, g0)
        gg0 = np.einsum("ij,ij->i", g, g0)
        det = gg * g0g0 - gg0 * gg0
        use = ~retried & (g0g0 > 0) & (gg0 < 0.9 * np.sqrt(gg * g0g0)) & (det > 1e-6 * gg * g0g0)
        if not use.any():
            return step
        r0 = F0[use] + np.einsum("ij,ij->i", g0[use], q[use] - q0[use])
        a, b, c, d = gg[use], gg0[use], g0g0[use], det[use]
        # d = lam g + mu g0 with [[a, b], [b, c]] [lam, mu] = [F, r0]
        lam = (c * F[use] - b * r0) / d
        mu = (a * r0 - b * F[use]) / d
        step = step.copy()
        step[use] = lam[:, None] * g[use] + mu[:, None] * g0[use]
        return step

    # -- meshing ----------------------------------------------------------------------------------
    def to_mesh(self, edge_length, bounds=None):
        """The zero set as a closed triangle mesh (sampled on a grid, marching tetrahedra).

        Parameters
        ----------
        edge_length : float
            Grid spacing (model units); no triangle edge is longer than a cell
            diagonal, ``sqrt(3) * edge_length``.
        bounds : (lo (3,), hi (3,)), optional
            Box to mesh in; required when :attr:`bounds` is None. The surface
            is clipped (closed off) where it leaves the box.

        Returns
        -------
        ImplicitMesh
            A :class:`~splinekit.mesh.polymesh.PolyMesh` (triangles,
            outward-facing, closed unless empty) with the extra attributes
            ``deviation`` (the measured max distance of the mesh from ``F = 0``)
            and ``edge_length``; see :func:`splinekit.implicit.meshing.mesh_implicit`.
        """
        return mesh_implicit(self, edge_length, bounds)

    # -- operators and transforms ---------------------------------------------------------------
    # They build CSG nodes through the constructors csg.py registers in _CSG (below).
    def __or__(self, other):
        return _CSG["union"](self, other)

    def __and__(self, other):
        return _CSG["intersection"](self, other)

    def __sub__(self, other):
        return _CSG["difference"](self, other)

    def __neg__(self):
        return _CSG["complement"](self)

    def translate(self, vector):
        """This implicit moved by ``vector`` (3,): ``F(p - v)``; exactness kept."""
        return _CSG["transformed"](self, translation=vector)

    def rotate(self, matrix_or_axis, angle=None):
        """This implicit rotated about the origin: ``rotate(R)`` with a proper
        rotation matrix ``R`` (3, 3) (orthogonal, det +1), or ``rotate(axis,
        angle)`` with an axis (3,) and an angle in radians (right-handed).
        ``F(R^T p)``; exactness kept."""
        R = _CSG["rotation_matrix"](matrix_or_axis, angle)
        return _CSG["transformed"](self, rotation=R)

    def scale(self, factor):
        """This implicit scaled by ``factor`` > 0 about the origin: ``s F(p / s)``
        (uniform, so a signed distance stays one)."""
        return _CSG["transformed"](self, scale=factor)

    def offset(self, distance):
        """``F - r``: grown by ``r`` (shrunk for ``r < 0``) in model units.
        Exact when this one is, is convex and ``r >= 0``."""
        return _CSG["offset"](self, distance)

    def shell(self, thickness):
        """``|F| - t / 2``: a hollow shell of thickness ``t`` > 0 centred on the surface."""
        return _CSG["shell"](self, thickness)


_CSG: dict = {}
"""The constructors the operators and transforms call: ``union``, ``intersection``,
``difference``, ``complement``, ``transformed``, ``rotation_matrix``, ``offset``, ``shell``.
CSG nodes subclass :class:`Implicit`, so their module (csg.py) imports this one and not the other
way round; it hands them over through :func:`register_csg` when it is imported, and the package
``__init__`` imports it, so they are in place before any Implicit can be made."""


def register_csg(**constructors) -> None:
    """Register the CSG constructors the operators of :class:`Implicit` call (see ``_CSG``)."""
    _CSG.update(constructors)
