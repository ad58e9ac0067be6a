"""Implicit representations: a signed-distance grid, the analytic implicit (sphere, torus) and a
neural signed distance (``splinekit.neural``, an optional extra). Their surface is the zero set;
it is meshed (marching tetrahedra, :meth:`Implicit.to_mesh`) for volume, genus and pictures."""

from __future__ import annotations

import importlib

import numpy as np

from .._signals import reraise_interrupt
from ..diffgeom import curvature
from ..errors import ConvergenceError
from ..implicit import Implicit, from_mesh
from ..implicit.sampled import BYTES_PER_GRID_POINT
from ..mesh.components import genus
from ..tessellation import tessellate
from .holder import Holder, bend, unbend

__all__ = ["AnalyticImplicit", "NeuralImplicit", "SDFGrid", "neural_module"]

_NO_PARAMETERS = "an implicit surface has no parametrization (points come from root finding)"
CLOSEST_TOLERANCE = 1e-7
"""Residual ``|F|`` (a distance, as a fraction of the diagonal) of the closest-point iteration."""
FALLBACK_STEPS = 20
MESH_FRACTION = 0.02
"""Chordal tolerance of the mesh an SDF grid is sampled from, as a fraction of about its spacing."""
MESH_CELLS = 96
"""Cells along the longest side of the box the analytic and neural zero sets are meshed in."""


class _Callable(Implicit):
    """Any ``f`` callable on ``(n, 3)`` points with ``f.gradient`` as an :class:`Implicit`
    (to mesh it and use it in CSG), bounded by ``bounds``."""

    def __init__(self, f, bounds):
        super().__init__(bounds=bounds, exact=False)
        self._f = f

    def _value(self, p):
        return np.asarray(self._f(p), dtype=float).reshape(-1)

    def _gradient(self, p):
        return np.asarray(self._f.gradient(p), dtype=float).reshape(-1, 3)


class ImplicitHolder(Holder):
    """Queries of ``self.f`` (an :class:`Implicit`: negative inside, with ``gradient``)."""

    not_applicable = {"point": _NO_PARAMETERS}

    def _zero_set(self, edge_length):
        """Mesh the zero set once (volume, genus, pictures, booleans)."""
        self.mesh = self.f.to_mesh(edge_length)
        self.f(self.mesh.vertices[:1])  # any lazy set-up of the function happens in the build

    def inside(self, points):
        return self.f(points) < 0

    def closest(self, points):
        """Newton steps along the gradient to ``|F| <=`` :data:`CLOSEST_TOLERANCE` x diagonal
        (:meth:`Implicit.closest_points`). Where they do not get there (a trilinear grid is
        only C0: the steps can cycle across a cell face), the iterates after
        :data:`FALLBACK_STEPS` plain steps stand as the answer: the measured errors then
        include how far from the zero set they stopped."""
        try:
            return self.f.closest_points(points, tol=CLOSEST_TOLERANCE * self.diagonal)
        except ConvergenceError:
            q = np.array(points, dtype=float)
            for _ in range(FALLBACK_STEPS):
                F, g = self.f(q), self.f.gradient(q)
                q -= (F / np.maximum(np.einsum("nd,nd->n", g, g), 1e-300))[:, None] * g
            return q

    def normal(self, points):
        return self.f.normal(points)

    def distance(self, points):
        """``|p - q|`` with ``q`` the zero-set point Newton steps along the gradient find from
        ``p``: the distance for a true SDF, an upper bound of it otherwise."""
        return np.linalg.norm(points - self.closest(points), axis=1)

    def surface_points(self, n, rng):
        """Vertices of the meshed zero set moved onto the zero set itself."""
        v = np.asarray(self.mesh.vertices)
        v = v if len(v) <= n else v[rng.choice(len(v), n, replace=False)]
        return self.closest(v)

    def mean_curvature(self, points):
        """``|H|`` of the level set through the zero-set point nearest each point (gradient and
        Hessian of the function)."""
        return np.abs(curvature(self._curvature_function(), self.closest(points)).mean)

    def _curvature_function(self):
        return self.f

    def volume(self):
        return float(self.mesh.volume)

    def genus(self):
        return genus(self.mesh)

    def render_mesh(self):
        return self.mesh

    def bent_distance(self, exact_points, radius):
        """A bend of an implicit is a domain warp ``F(unbend(x))``: its zero set is exactly the
        bent zero set, though it is no longer a distance. Measured: the warp evaluated at the
        bent exact points, and ``|bend(p) - bend(q)|`` with ``q`` the zero-set point nearest
        ``p`` (``bend(q)`` lies on the warped zero set: an upper bound of the distance)."""
        x = bend(exact_points, radius)
        self.f(unbend(x, radius))  # what using the bent shape costs: one warped evaluation
        return np.linalg.norm(x - bend(self.closest(exact_points), radius), axis=1)


class SDFGrid(ImplicitHolder):
    """Exact signed distances of a tessellation sampled on a grid with ``resolution`` samples
    along the longest side (:func:`splinekit.implicit.from_mesh`), trilinear between samples;
    tricubic (Catmull-Rom) for curvature, which needs a Hessian. The tessellation's tolerance is
    :data:`MESH_FRACTION` of the spacing (fewer triangles: from_mesh's cost grows with them)."""

    name = "SDF grid"
    resolution_name = "samples per side"
    default_resolutions = (24, 48, 96)

    def __init__(self, shape, reference, resolution):
        self.resolution = int(resolution)
        self.diagonal = reference.diagonal
        tolerance = max(reference.tolerance, MESH_FRACTION * reference.diagonal / self.resolution)
        self.f = from_mesh(tessellate(list(shape.patches), tolerance), self.resolution)
        self.spacing = float(self.f.spacing.max())
        self.arrays = {"values": self.f.values}
        self._zero_set(self.spacing)
        self.linear = float(max(self.f.shape))  # samples along the longest side, padding included

    @staticmethod
    def estimate_bytes(shape, reference, resolution):
        return (1.2 * int(resolution)) ** 3 * BYTES_PER_GRID_POINT

    def _curvature_function(self):
        return self.f.with_interpolation("cubic")


class AnalyticImplicit(ImplicitHolder):
    """The shape's exact analytic signed distance (sphere, torus): a few numbers, no resolution."""

    name = "analytic implicit"
    resolution_name = "parameters"
    default_resolutions = (1,)

    def __init__(self, shape, reference, resolution):
        self.resolution = 1
        self.diagonal = reference.diagonal
        self.f = shape.implicit
        numbers = [np.asarray(v, dtype=float) for k, v in vars(self.f).items()
                   if not k.startswith("_") and isinstance(v, (float, np.ndarray))]  # centre, axis, radii
        self.arrays = {"parameters": np.concatenate([v.ravel() for v in numbers]) if numbers else np.empty(0)}
        self._zero_set(reference.diagonal / MESH_CELLS)
        self.linear = 1.0


def neural_module():
    """``(splinekit.neural, None)``, or ``(None, why it cannot be used)`` when it is not there or
    its optional extra is missing. Looked up by name: the package is an optional extra."""
    try:
        return importlib.import_module("splinekit.neural"), None
    except ImportError as exc:
        reraise_interrupt(exc)
        return None, f"splinekit.neural does not import ({exc}); install the extra: pip install 'splinekit[neural]'"


class NeuralImplicit(ImplicitHolder):
    """A neural signed distance (``splinekit.neural.NeuralSDF.fit(mesh, steps=resolution,
    seed=0)``) trained on the reference tessellation; holds the network's weights. Its size
    does not grow with training steps: O(parameters)."""

    name = "neural SDF"
    resolution_name = "training steps"
    default_resolutions = (250, 500, 1000)

    def __init__(self, shape, reference, resolution):
        module, why = neural_module()
        if module is None:
            raise RuntimeError(why)
        self.resolution = int(resolution)
        self.diagonal = reference.diagonal
        model = module.NeuralSDF.fit(reference.mesh, steps=self.resolution, seed=0)
        self.model = model
        self.f = model if isinstance(model, Implicit) else _Callable(model, _padded(reference.bounds))
        self.arrays = _weights(model)
        self._zero_set(reference.diagonal / MESH_CELLS)
        self.linear = float(self.resolution)


def _padded(bounds, fraction: float = 0.1):
    lo, hi = (np.asarray(b, dtype=float) for b in bounds)
    pad = fraction * float((hi - lo).max())
    return lo - pad, hi + pad


def _weights(model) -> dict:
    """The network's arrays: ``model.arrays`` (name -> array) when it offers them, else every
    array found in ``model.params`` (nested dicts, lists and tuples)."""
    given = getattr(model, "arrays", None)
    if isinstance(given, dict):
        return {k: np.asarray(v) for k, v in given.items()}
    out, stack = {}, [("params", getattr(model, "params", None))]
    while stack:
        key, item = stack.pop()
        if isinstance(item, dict):
            stack.extend((f"{key}.{k}", v) for k, v in item.items())
        elif isinstance(item, (list, tuple)):
            stack.extend((f"{key}[{i}]", v) for i, v in enumerate(item))
        elif item is not None and hasattr(item, "shape"):
            out[key] = np.asarray(item)
    return out
