"""The multilayer perceptron behind every neural implicit: its architecture, weights and evaluation.

A network maps a point ``x`` of the *normalized* cube ``[-1, 1]^3`` (the shape scaled into
``[-0.8, 0.8]^3``, see :mod:`.samples`), optionally with a latent code ``z`` of the shape, to one
number: a signed distance in normalized units (:class:`~splinekit.neural.NeuralSDF`) or an
occupancy logit (:class:`~splinekit.neural.NeuralOccupancy`). Two encodings of ``x``:

* ``"sine"`` (SIREN, Sitzmann et al. 2020): every hidden layer is ``sin(omega (W h + b))``, the
  weights initialised so that activations stay distributed alike through the depth;
* ``"fourier"`` (positional encoding, as NeRF): ``x`` followed by ``sin(2^k pi x)``,
  ``cos(2^k pi x)`` for ``k < frequencies``, then softplus layers (smooth, so the Hessian exists).

The latent code, when there is one, is appended to the encoded point at the input (the
auto-decoder of DeepSDF, Park et al. 2019). The default encoding is the one that measured better
(see :data:`DEFAULT_ENCODING`).

Weights are a list of ``{"W": (fan_in, fan_out), "b": (fan_out,)}`` arrays, float32 while
training; evaluation runs on float64 copies (see :class:`Evaluator`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import asdict, dataclass

import numpy as np

from .. import limits
from .._validate import as_int, as_real
from ..errors import ParameterError
from ._backend import jax, jnp

__all__ = ["DEFAULT_ENCODING", "ENCODINGS", "Architecture", "Evaluator", "apply", "init_params", "parameter_count"]

ENCODINGS = ("sine", "fourier")
DEFAULT_ENCODING = "sine"
"""Chosen by measurement: on the unit sphere at equal size (3 x 64), samples (20,000) and steps
(600), the sine network's zero set lay within 8.3e-4 r of the sphere on average (5.6e-3 r at
worst), the positional encoding's (6 octaves, softplus, lr 1e-3) within 1.5e-2 r (0.12 r at worst),
eighteen times farther. ``benchmarks/bench_neural.py --encodings`` repeats the comparison."""

SOFTPLUS_BETA = 10.0
"""Sharpness of the softplus activation of the Fourier network (``softplus(beta x) / beta``)."""


@dataclass(frozen=True)
class Architecture:
    """The shape of a network (everything but its weights).

    Attributes
    ----------
    encoding : "sine" or "fourier"
    width : int
        Units per hidden layer.
    depth : int
        Hidden layers.
    omega : float
        Frequency factor of the sine layers (SIREN's ``omega_0``).
    frequencies : int
        Octaves of the positional encoding (Fourier network).
    latent : int
        Length of the latent code per shape (0: a single-shape network).
    """

    encoding: str = DEFAULT_ENCODING
    width: int = 64
    depth: int = 3
    omega: float = 30.0
    frequencies: int = 6
    latent: int = 0

    def __post_init__(self):
        if self.encoding not in ENCODINGS:
            raise ParameterError(f"encoding must be one of {', '.join(ENCODINGS)}, got {self.encoding!r}")
        object.__setattr__(self, "width", as_int(self.width, "width", minimum=1))
        object.__setattr__(self, "depth", as_int(self.depth, "depth", minimum=1))
        object.__setattr__(self, "frequencies", as_int(self.frequencies, "frequencies", minimum=0))
        object.__setattr__(self, "latent", as_int(self.latent, "latent", minimum=0))
        omega = as_real(self.omega, "omega")
        if not (math.isfinite(omega) and omega > 0):
            raise ParameterError(f"omega must be a finite number > 0, got {self.omega!r}")
        object.__setattr__(self, "omega", omega)
        if self.width > 4096 or self.depth > 64 or self.frequencies > 16 or self.latent > 4096:
            raise ParameterError(f"architecture too large: {self}")

    @property
    def input_size(self) -> int:
        """Inputs of the first layer: the encoded point plus the latent code."""
        encoded = 3 if self.encoding == "sine" else 3 + 6 * self.frequencies
        return encoded + self.latent

    @property
    def layer_sizes(self) -> list[tuple[int, int]]:
        """``(fan_in, fan_out)`` of every layer, the output layer last."""
        sizes = [self.input_size] + [self.width] * self.depth + [1]
        return list(zip(sizes[:-1], sizes[1:]))

    def to_dict(self) -> dict:
        return asdict(self)


def parameter_count(arch: Architecture) -> int:
    """Weights and biases of the network (latent codes not included)."""
    return sum(i * o + o for i, o in arch.layer_sizes)


def init_params(arch: Architecture, key) -> list[dict]:
    """Random float32 weights for ``arch`` from the JAX key ``key`` (SIREN's initialisation for
    sine layers, He's for softplus layers, zeros for biases of the latter)."""
    params = []
    keys = jax.random.split(key, 2 * len(arch.layer_sizes))
    for k, (fan_in, fan_out) in enumerate(arch.layer_sizes):
        kw, kb = keys[2 * k], keys[2 * k + 1]
        if arch.encoding == "sine":
            # first layer spans [-1, 1] x omega; later ones keep sin's input ~ U(-sqrt6, sqrt6)
            bound = 1.0 / fan_in if k == 0 else math.sqrt(6.0 / fan_in) / arch.omega
            W = jax.random.uniform(kw, (fan_in, fan_out), jnp.float32, -bound, bound)
            b = jax.random.uniform(kb, (fan_out,), jnp.float32, -bound, bound)
        else:
            W = jax.random.normal(kw, (fan_in, fan_out), jnp.float32) * math.sqrt(2.0 / fan_in)
            b = jnp.zeros((fan_out,), jnp.float32)
        params.append({"W": W, "b": b})
    return params


def _encode(arch: Architecture, x):
    if arch.encoding == "sine" or arch.frequencies == 0:
        return x
    scales = (2.0 ** jnp.arange(arch.frequencies, dtype=x.dtype)) * jnp.pi  # (L,)
    angles = (x[:, :, None] * scales).reshape(len(x), -1)  # (n, 3 L)
    return jnp.concatenate([x, jnp.sin(angles), jnp.cos(angles)], axis=1)


def apply(arch: Architecture, params, x, z=None):
    """Network output ``(n,)`` at normalized points ``x`` ``(n, 3)`` with latent code ``z``
    ``(latent,)`` (None when ``arch.latent`` is 0)."""
    h = _encode(arch, x)
    if arch.latent:
        h = jnp.concatenate([h, jnp.broadcast_to(z, (len(x), arch.latent)).astype(h.dtype)], axis=1)
    for layer in params[:-1]:
        a = h @ layer["W"] + layer["b"]
        h = jnp.sin(arch.omega * a) if arch.encoding == "sine" else jax.nn.softplus(SOFTPLUS_BETA * a) / SOFTPLUS_BETA
    out = params[-1]
    return (h @ out["W"] + out["b"])[:, 0]


def box_distance(x, half: float = 1.0):
    """Signed distance ``(n,)`` of points ``(n, 3)`` to the cube ``[-half, half]^3``."""
    q = jnp.abs(x) - half
    m = jnp.maximum(q, 0.0)
    sq = jnp.sum(m * m, axis=1)
    # the norm through a guarded square root: its derivatives at 0 would be NaN and, multiplied
    # by the zero weight max() gives this branch inside the cube, still poison the gradient
    outside = jnp.where(sq > 0, jnp.sqrt(jnp.where(sq > 0, sq, 1.0)), 0.0)
    return outside + jnp.minimum(jnp.max(q, axis=1), 0.0)


# -- batched evaluation ---------------------------------------------------------------------------
MIN_BUCKET = 256
"""Smallest padded batch: batches are padded to a power of two so that JAX compiles a handful of
shapes, not one per query size."""
MAX_BUCKET = 1 << 16
"""Largest batch per call (the memory budget may lower it)."""
FLOATS_PER_UNIT = {"value": 4, "gradient": 12, "hessian": 120}
"""Float64 numbers held per point and hidden unit by one evaluation (activations, their
derivatives, the Hessian's forward-over-reverse tangents), for the memory budget."""


@functools.lru_cache(maxsize=64)
def _compiled(arch: Architecture, field):
    """Jitted ``(value, value_grad, hessian)`` of ``(params, x, z)`` for one architecture and field,
    shared by every model of that architecture (the shapes of a family, their blends)."""

    def value(p, x, z):
        return field(x, apply(arch, p, x, z))

    def value_grad(p, x, z):
        f, pull = jax.vjp(lambda y: value(p, y, z), x)
        return f, pull(jnp.ones_like(f))[0]

    def hessian(p, x, z):
        one = lambda y: value(p, y[None], z)[0]  # noqa: E731 - a point -> a number
        return jax.vmap(jax.hessian(one))(x)

    return jax.jit(value), jax.jit(value_grad), jax.jit(hessian)


class Evaluator:
    """Jitted, chunked float64 evaluation of one network at one latent code.

    ``field(x_hat, raw) -> F_hat`` turns the network output into the implicit's value (both in
    normalized units); it is traced with the network, so gradient and Hessian include it.
    """

    def __init__(self, arch: Architecture, params, latent, field):
        self.arch = arch
        self.params = jax.tree_util.tree_map(lambda a: jnp.asarray(np.asarray(a), jnp.float64), params)
        self.latent = None if latent is None else jnp.asarray(np.asarray(latent), jnp.float64)
        self._value, self._value_grad, self._hessian = _compiled(arch, field)

    def _bucket(self, n: int, what: str) -> int:
        per_point = 8.0 * FLOATS_PER_UNIT[what] * self.arch.width * (self.arch.depth + 1)
        cap = MAX_BUCKET
        budget = limits.current_budget()
        while cap > MIN_BUCKET and cap * per_point > budget:
            cap //= 2
        size = MIN_BUCKET
        while size < n and size < cap:  # powers of 4: at most a few compiled shapes per function
            size *= 4
        size = min(size, cap)
        limits.check(size * per_point, f"a neural {what} batch of {size:,} points")
        return size

    def _run(self, fn, x: np.ndarray, what: str, tail: tuple):
        n = len(x)
        out = [np.empty((n,) + t) for t in tail]
        if n == 0:
            return out
        size = self._bucket(n, what)
        for start in range(0, n, size):
            chunk = x[start : start + size]
            m = len(chunk)
            if m < size:  # pad to the bucket with copies of the last point
                chunk = np.concatenate([chunk, np.repeat(chunk[-1:], size - m, axis=0)])
            res = fn(self.params, jnp.asarray(chunk), self.latent)
            res = res if isinstance(res, tuple) else (res,)
            for o, r in zip(out, res):
                o[start : start + m] = np.asarray(r)[:m]
        return out

    def value(self, x: np.ndarray) -> np.ndarray:
        """``(n,)`` at normalized points ``(n, 3)``."""
        return self._run(self._value, x, "value", ((),))[0]

    def value_gradient(self, x: np.ndarray):
        """``((n,), (n, 3))`` at normalized points."""
        return tuple(self._run(self._value_grad, x, "gradient", ((), (3,))))

    def hessian(self, x: np.ndarray) -> np.ndarray:
        """``(n, 3, 3)`` at normalized points (exact: forward over reverse mode)."""
        return self._run(self._hessian, x, "hessian", ((3, 3),))[0]
