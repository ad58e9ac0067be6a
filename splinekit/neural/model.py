"""Trained single shapes as splinekit implicits: :class:`NeuralSDF` and :class:`NeuralOccupancy`.

Both subclass :class:`splinekit.implicit.Implicit`, so a trained shape is callable on ``(n, 3)``
points, has ``gradient``, ``normal``, ``hessian`` (here from automatic differentiation, exact for
the network: no finite differences), curvature through ``splinekit.curvature(model, points)``,
``closest_points``, ``to_mesh`` (the project's marching-tetrahedra mesher) and the CSG operators.

The value in model units is ``F(x) = scale * max(f(x_hat), box(x_hat))`` with ``x_hat`` the
normalized point (:mod:`.samples`), ``f`` the network and ``box`` the signed distance of the cube
``[-1, 1]^3`` the network was trained in: outside that cube ``F > 0``, so :attr:`bounds` (the
cube) holds the whole zero set, as the Implicit contract requires, and a network's stray zero
crossings outside its training region never reach a mesh. For an occupancy network ``f`` is minus
the logit, so ``F = 0`` is the probability-0.5 surface.
"""

from __future__ import annotations

import time

import numpy as np

from .._validate import as_int
from ..diffgeom.curvature import curvature as _curvature
from ..errors import FileFormatError
from ..implicit.base import Implicit
from ..implicit.meshing import mesh_implicit
from . import fileio
from ._backend import jnp
from .meshing import band_mesh
from .network import Architecture, Evaluator, box_distance, parameter_count
from .samples import Normalization, as_target, draw_samples
from .training import Settings, fit_network

__all__ = ["DEFAULT_SAMPLES", "DEFAULT_STEPS", "MESH_CELLS", "NeuralImplicit", "NeuralOccupancy", "NeuralSDF"]

DEFAULT_STEPS = 1000
DEFAULT_SAMPLES = 100_000
"""Surface points (and as many near points and uniform points) drawn per shape."""
MESH_CELLS = 128
"""Grid cells across the training cube of :meth:`NeuralImplicit.to_mesh` without an edge length."""
OCCUPANCY_BOX = 100.0
"""Slope of the cube term of an occupancy field (logit units per normalized unit)."""


class NeuralImplicit(Implicit):
    """A trained network as an implicit (module notes); made by ``fit`` or ``load``.

    Attributes: ``architecture`` (:class:`~.network.Architecture`), ``params`` (float32 weight
    arrays), ``latent`` (the shape's code or None), ``normalization``, ``info`` (training record:
    steps, seed, final loss, seconds).
    """

    KIND = ""

    def __init__(self, architecture: Architecture, params, normalization: Normalization, latent=None, info=None):
        self.architecture = architecture
        self.params = [{k: np.array(v, dtype=np.float32) for k, v in layer.items()} for layer in params]
        for layer in self.params:
            for arr in layer.values():
                arr.setflags(write=False)
        self.latent = None if latent is None else np.array(latent, dtype=np.float32).reshape(architecture.latent)
        self.normalization = normalization
        self.info = dict(info or {})
        self._network = Evaluator(architecture, self.params, self.latent, self._field)
        super().__init__(bounds=normalization.bounds, exact=False)

    # -- the field -------------------------------------------------------------------------------
    @staticmethod
    def _field(x, raw):
        return jnp.maximum(raw, box_distance(x))

    def _value(self, p):
        n = self.normalization
        return n.scale * self._network.value(n.to_unit(p))

    def _value_gradient(self, p):
        n = self.normalization
        f, g = self._network.value_gradient(n.to_unit(p))
        return n.scale * f, g

    def _gradient(self, p):
        return self._value_gradient(p)[1]

    def _hessian(self, p):
        n = self.normalization
        return self._network.hessian(n.to_unit(p)) / n.scale

    # -- what it costs ---------------------------------------------------------------------------
    @property
    def parameter_count(self) -> int:
        """Weights and biases of the network, plus the latent code if there is one."""
        return parameter_count(self.architecture) + (0 if self.latent is None else self.latent.size)

    @property
    def nbytes(self) -> int:
        """Bytes of the numbers that define the shape (float32 weights and code)."""
        return 4 * self.parameter_count

    def __repr__(self):
        a = self.architecture
        return (f"{type(self).__name__}({a.encoding}, {a.depth}x{a.width}, {self.parameter_count:,} parameters, "
                f"bounds={self._box_text()})")

    # -- use -------------------------------------------------------------------------------------
    def curvature(self, points):
        """Mean and Gaussian curvature (and principal values, directions) at ``(n, 3)`` points
        from the exact Hessian of the network: :func:`splinekit.curvature` of this implicit."""
        return _curvature(self, points)

    def to_mesh(self, edge_length=None, bounds=None):
        """The zero set as a closed triangle mesh (:func:`~splinekit.implicit.mesh_implicit`);
        default edge length :meth:`default_edge`."""
        return mesh_implicit(self, self.default_edge() if edge_length is None else edge_length, bounds)

    def default_edge(self) -> float:
        """Edge length of :meth:`to_mesh` without one (model units): the training cube /
        ``MESH_CELLS``, or ``info["mesh_edge"]`` when the model says (a family's shape occupies
        part of its cube and is meshed as finely as a network of its own would be)."""
        edge = self.info.get("mesh_edge")
        return float(edge) if edge is not None else 2.0 * self.normalization.scale / MESH_CELLS

    def save(self, path) -> str:
        """Write weights, code and configuration to one file (:mod:`.fileio`), atomically."""
        codes = None if self.latent is None else self.latent[None, :]
        n = self.normalization
        return fileio.write(path, self.KIND, self.architecture, self.params, codes, n.center, n.scale, self.info)

    @classmethod
    def load(cls, path):
        """The model saved at ``path``; FileFormatError for anything else (or another kind)."""
        kind, arch, params, codes, center, scale, info = fileio.read(path)
        if kind != cls.KIND:
            raise FileFormatError(f"{path!r} holds a neural {kind} model, not a {cls.__name__} ({cls.KIND})")
        if codes is not None and len(codes) != 1:
            raise FileFormatError(f"{path!r} holds {len(codes)} latent codes; a single shape has one")
        return cls(arch, params, Normalization(center, scale), None if codes is None else codes[0], info)

    # -- training --------------------------------------------------------------------------------
    @classmethod
    def fit(cls, shape, *, steps: int = DEFAULT_STEPS, seed: int = 0, encoding: str | None = None,
            width: int = 64, depth: int = 3, omega: float = 30.0, samples: int = DEFAULT_SAMPLES, batch: int = 1024,
            lr: float | None = None, tolerance=None, callback=None):
        """Train a network on a closed shape and return it.

        Parameters
        ----------
        shape
            A closed PolyMesh, B-rep Solid, SubdivisionSurface, patch list, built model or bounded
            Implicit (:func:`~splinekit.neural.samples.as_target`); an open one raises
            NotManifoldError.
        steps, batch, lr
            Adam steps, surface and space points per step, initial learning rate
            (:class:`~splinekit.neural.training.Settings`).
        seed : int
            Seeds the samples, the initial weights and the minibatches: equal inputs and seed
            give equal weights.
        encoding, width, depth, omega
            The network (:class:`~splinekit.neural.network.Architecture`; default encoding
            :data:`~splinekit.neural.network.DEFAULT_ENCODING`).
        samples : int
            Surface samples drawn from the shape (plus as many near and half as many uniform).
        tolerance
            Tessellation tolerance of exact shapes (model units).
        callback
            ``callback(step, steps, loss)`` after every block of steps (progress bars).
        """
        seed = as_int(seed, "seed", minimum=0)
        arch = Architecture(**({} if encoding is None else {"encoding": encoding}), width=width, depth=depth, omega=omega)
        settings = Settings(steps=steps, batch=batch, lr=lr)
        t0 = time.perf_counter()
        target = as_target(shape, tolerance)
        norm = Normalization.of_box(*target.box)
        pool = draw_samples(target, norm, samples, seed)
        params, _, losses = fit_network(arch, cls.KIND, [pool], settings, seed, callback)
        info = {"steps": settings.steps, "seed": seed, "first_loss": losses[0][1], "loss": losses[-1][1], "seconds": time.perf_counter() - t0}
        return cls(arch, params, norm, None, info)


class NeuralSDF(NeuralImplicit):
    """A network trained as a signed distance: ``|grad F|`` is about 1 (the eikonal term)."""

    KIND = "sdf"

    def to_mesh(self, edge_length=None, bounds=None):
        """The zero set as a closed triangle mesh; default edge length :meth:`default_edge`. Over
        its own bounds the network is sampled in a narrow band around the surface only
        (:func:`~splinekit.neural.meshing.band_mesh`); with ``bounds`` on the full grid."""
        if bounds is not None:
            return super().to_mesh(edge_length, bounds)
        return band_mesh(self, self.default_edge() if edge_length is None else edge_length)


class NeuralOccupancy(NeuralImplicit):
    """A network trained as inside/outside probability with cross-entropy; ``F = 0`` at 0.5."""

    KIND = "occupancy"

    @staticmethod
    def _field(x, raw):
        return jnp.maximum(-raw, OCCUPANCY_BOX * box_distance(x))

    def probability(self, points) -> np.ndarray:
        """Inside probability ``(n,)`` at ``(n, 3)`` points (``sigmoid(-F / scale)``)."""
        F = self(points) / self.normalization.scale
        return 1.0 / (1.0 + np.exp(np.clip(F, -500.0, 500.0)))
