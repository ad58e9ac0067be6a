"""Many shapes in one network: :class:`NeuralSDFFamily`, an auto-decoder (DeepSDF, Park et al. 2019).

One network ``f(x_hat, z)`` and one latent code ``z_i`` per shape, trained together; shape ``i``
is the zero set of ``f(., z_i)``. All shapes share one normalization (their common box mapped
into the cube), so codes can be mixed: :meth:`~NeuralSDFFamily.interpolate` blends two codes
linearly. A new shape gets a code by optimizing only the code against its samples, with the
network held fixed (:meth:`~NeuralSDFFamily.fit_code`).

A shape's ``to_mesh()`` defaults to the edge a network of its own would use (its own box across
``MESH_CELLS``, kept in ``info["mesh_edges"]``), not the family's cube: in a family of vases 100
to 190 mm tall the cube's 128 cells are 1.9 mm, under two cells across the 2.8 mm floor corner of
a 4 mm wall, where a network of the shortest vase alone is meshed at 1.0 mm (the mesh edge alone
moved a vase's Chamfer distance by a quarter: ``benchmarks/bench_neural.py``, which also has the
measured defaults: ``STEPS_PER_SHAPE``, ``CODE_LR``).
"""

from __future__ import annotations

import time

import numpy as np

from .._validate import as_int, as_real
from ..errors import FileFormatError, ParameterError
from . import fileio
from .model import DEFAULT_SAMPLES, MESH_CELLS, NeuralOccupancy, NeuralSDF
from .network import Architecture, parameter_count
from .samples import Normalization, as_target, draw_samples
from .training import Settings, fit_codes, fit_network

__all__ = ["DEFAULT_LATENT", "NeuralSDFFamily", "load"]

DEFAULT_LATENT = 16
"""Length of a shape's latent code."""
STEPS_PER_SHAPE = 1000
"""Default steps of a family fit per shape (at least 2000 in all): a step draws its batch from all
shapes, so this many give each shape as many samples as a single network's default fit sees."""
CODE_LR = 10.0
"""Learning rate of the latent codes while a family trains, as a multiple of the weights' rate."""
CODE_STEPS = 500
"""Default steps of :meth:`NeuralSDFFamily.fit_code`."""


class NeuralSDFFamily:
    """One signed-distance network and ``len(self)`` latent codes (module notes).

    Attributes: ``architecture``, ``params`` (float32 weights), ``codes`` ``(shapes, latent)``
    float32, ``normalization``, ``info``.
    """

    def __init__(self, architecture: Architecture, params, codes, normalization: Normalization, info=None):
        if architecture.latent == 0:
            raise ParameterError("a family needs an architecture with latent > 0")
        self.architecture = architecture
        self.params = [{k: np.array(v, dtype=np.float32) for k, v in layer.items()} for layer in params]
        self.codes = np.array(codes, dtype=np.float32).reshape(-1, architecture.latent)
        self.codes.setflags(write=False)
        self.normalization = normalization
        self.info = dict(info or {})

    def __len__(self) -> int:
        return len(self.codes)

    def __repr__(self):
        a = self.architecture
        return (f"NeuralSDFFamily({len(self)} shapes, {a.encoding}, {a.depth}x{a.width}, latent {a.latent}, "
                f"{self.parameter_count:,} parameters)")

    @property
    def parameter_count(self) -> int:
        """Network weights and biases plus every latent code."""
        return parameter_count(self.architecture) + self.codes.size

    @property
    def nbytes(self) -> int:
        """Bytes of the numbers that define every shape (float32)."""
        return 4 * self.parameter_count

    def _with_code(self, code, mesh_edge=None, **info) -> NeuralSDF:
        info = {k: v for k, v in {**self.info, **info}.items() if k != "mesh_edges"}
        if mesh_edge is not None:
            info["mesh_edge"] = mesh_edge
        return NeuralSDF(self.architecture, self.params, self.normalization, code, info)

    def _mesh_edge(self, i: int):
        """Default mesh edge of shape ``i``: what a network of its own would use (its box, not the
        family's, across ``MESH_CELLS``), so a small shape's thin walls are not meshed coarser
        than they would be alone; None for families saved without the boxes."""
        edges = self.info.get("mesh_edges")
        return None if edges is None or len(edges) != len(self) else float(edges[i])

    def shape(self, i: int) -> NeuralSDF:
        """Shape ``i`` as an implicit (the network with code ``i``)."""
        i = as_int(i, "i")
        if not -len(self) <= i < len(self):
            raise ParameterError(f"shape index {i} out of range for a family of {len(self)}")
        i %= len(self)
        return self._with_code(self.codes[i], self._mesh_edge(i), shape=i)

    def interpolate(self, i: int, j: int, t: float) -> NeuralSDF:
        """The shape of code ``(1 - t) z_i + t z_j`` (``t`` in [0, 1] interpolates); meshed by
        default at the finer of the two shapes' edges."""
        a, b = self.shape(i), self.shape(j)
        t = as_real(t, "t")
        if not np.isfinite(t):
            raise ParameterError(f"t must be finite, got {t!r}")
        edges = [e for e in (a.info.get("mesh_edge"), b.info.get("mesh_edge")) if e is not None]
        return self._with_code((1.0 - t) * a.latent + t * b.latent, min(edges) if edges else None,
                               interpolated=[int(i), int(j), t])

    def fit_code(self, shape, *, steps: int = CODE_STEPS, seed: int = 0, samples: int = DEFAULT_SAMPLES // 4,
                 tolerance=None, callback=None) -> NeuralSDF:
        """A code for a new shape, the network held fixed; returns the shape as an implicit.

        The shape must lie within the family's training cube (ParameterError otherwise)."""
        seed = as_int(seed, "seed", minimum=0)
        target = as_target(shape, tolerance)
        lo, hi = target.box
        cube_lo, cube_hi = self.normalization.bounds
        if (lo < cube_lo).any() or (hi > cube_hi).any():
            raise ParameterError(f"the shape's box {lo.tolist()} .. {hi.tolist()} leaves the family's training cube "
                                 f"{cube_lo.tolist()} .. {cube_hi.tolist()}")
        pool = draw_samples(target, self.normalization, samples, seed)
        t0 = time.perf_counter()
        code, losses = fit_codes(self.architecture, self.params, pool, Settings(steps=steps), seed, callback)
        edge = 2.0 * Normalization.of_box(lo, hi).scale / MESH_CELLS  # as a network of its own
        return self._with_code(code, edge, code_steps=steps, code_loss=losses[-1][1],
                               code_seconds=time.perf_counter() - t0)

    @classmethod
    def fit(cls, shapes, *, steps: int | None = None, seed: int = 0, encoding: str | None = None,
            width: int = 96, depth: int = 3, latent: int = DEFAULT_LATENT, samples: int = DEFAULT_SAMPLES // 2,
            batch: int = 1024, lr: float | None = None, code_lr: float = CODE_LR, tolerance=None, callback=None):
        """Train one network and one code per shape of ``shapes`` (closed shapes, as
        :meth:`NeuralSDF.fit` takes); default ``steps``: ``STEPS_PER_SHAPE`` per shape, at least 2000."""
        shapes = list(shapes)
        if not shapes:
            raise ParameterError("fit needs at least one shape")
        seed = as_int(seed, "seed", minimum=0)
        steps = max(2000, STEPS_PER_SHAPE * len(shapes)) if steps is None else steps
        arch = Architecture(**({} if encoding is None else {"encoding": encoding}), width=width, depth=depth,
                            latent=as_int(latent, "latent", minimum=1))
        settings = Settings(steps=steps, batch=batch, lr=lr, code_lr=code_lr)
        t0 = time.perf_counter()
        targets = [as_target(s, tolerance) for s in shapes]
        lo = np.min([t.box[0] for t in targets], axis=0)
        hi = np.max([t.box[1] for t in targets], axis=0)
        norm = Normalization.of_box(lo, hi)
        pools = [draw_samples(t, norm, samples, seed + k) for k, t in enumerate(targets)]
        params, codes, losses = fit_network(arch, "sdf", pools, settings, seed, callback)
        info = {"steps": settings.steps, "seed": seed, "first_loss": losses[0][1], "loss": losses[-1][1],
                "seconds": time.perf_counter() - t0,
                "mesh_edges": [2.0 * Normalization.of_box(*t.box).scale / MESH_CELLS for t in targets]}
        return cls(arch, params, codes, norm, info)

    def save(self, path) -> str:
        """Write the network, every code and the configuration to one file, atomically."""
        n = self.normalization
        return fileio.write(path, "family", self.architecture, self.params, self.codes, n.center, n.scale, self.info)

    @classmethod
    def load(cls, path) -> "NeuralSDFFamily":
        kind, arch, params, codes, center, scale, info = fileio.read(path)
        if kind != "family":
            raise FileFormatError(f"{path!r} holds a neural {kind} model, not a family")
        return cls(arch, params, codes, Normalization(center, scale), info)


def load(path):
    """Whatever neural model ``path`` holds: NeuralSDF, NeuralOccupancy or NeuralSDFFamily."""
    kind = fileio.read(path)[0]
    return {"sdf": NeuralSDF, "occupancy": NeuralOccupancy, "family": NeuralSDFFamily}[kind].load(path)
