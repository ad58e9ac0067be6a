"""Training: the losses, the optimizer and the loop, for one shape, many shapes or one new code.

Signed distance (all in normalized units, ``f`` the network, ``d`` the target distance, ``n``
the surface normal, means over a minibatch)::

    L = |f(surface)| + |f(space) - d(space)|                     (level set and distance)
        + W_NORMAL (1 - cos(grad f(surface), n))                 (orientation)
        + W_EIKONAL (|grad f| - 1)^2                             (a distance field: |grad f| = 1)
        + W_LATENT |z|^2                                         (auto-decoder codes stay small)

Occupancy: binary cross-entropy of the logit on the space points against ``d < 0``.

Every step draws a minibatch of ``batch`` surface and ``batch`` space points from the sample
pools with a JAX key derived from the seed, so a fit is a function of its inputs and its seed.
Steps run inside ``jax.lax.fori_loop`` in blocks of ``BLOCK`` (one Python call per block); the
learning rate follows a cosine decay from ``lr`` to ``lr * FINAL_LR``.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from .._validate import as_int, as_real
from ..errors import ConvergenceError, ParameterError
from ._backend import jax, jnp, optax
from .network import Architecture, apply, init_params
from .samples import SamplePool

__all__ = ["BLOCK", "Settings", "fit_codes", "fit_network"]

BLOCK = 50
"""Optimizer steps per jitted call (and per progress report)."""
W_NORMAL = 0.1
W_EIKONAL = 0.1
W_LATENT = 1e-3
FINAL_LR = 0.05
LATENT_INIT = 0.01
"""Standard deviation of the initial latent codes (DeepSDF starts them near zero)."""


@dataclass(frozen=True)
class Settings:
    """How long and how hard to train.

    steps : optimizer steps; batch : surface points and space points per step; lr : Adam's
    initial learning rate (default by encoding: ``3e-4`` sine, ``1e-3`` fourier); code_lr : the
    latent codes' learning rate as a multiple of ``lr`` (DeepSDF trains codes and weights at
    different rates)."""

    steps: int = 1000
    batch: int = 1024
    lr: float | None = None
    code_lr: float = 1.0

    def __post_init__(self):
        object.__setattr__(self, "steps", as_int(self.steps, "steps", minimum=1))
        object.__setattr__(self, "batch", as_int(self.batch, "batch", minimum=16))
        if self.steps > 10_000_000 or self.batch > 1 << 20:
            raise ParameterError(f"steps = {self.steps} or batch = {self.batch} is beyond any sensible training")
        if self.lr is not None:
            lr = as_real(self.lr, "lr")
            if not (np.isfinite(lr) and lr > 0):
                raise ParameterError(f"lr must be a finite number > 0, got {self.lr!r}")
        code_lr = as_real(self.code_lr, "code_lr")
        if not (np.isfinite(code_lr) and code_lr > 0):
            raise ParameterError(f"code_lr must be a finite number > 0, got {self.code_lr!r}")
        object.__setattr__(self, "code_lr", code_lr)

    def learning_rate(self, arch: Architecture) -> float:
        if self.lr is not None:
            return float(self.lr)
        return 3e-4 if arch.encoding == "sine" else 1e-3


def _stack(pools: list[SamplePool]):
    """Device arrays of all pools: points, normals, distances and the shape index of each."""
    ids = lambda key: np.concatenate([np.full(len(getattr(p, key)), i, np.int32) for i, p in enumerate(pools)])  # noqa: E731
    cat = lambda key: jnp.asarray(np.concatenate([getattr(p, key) for p in pools]))  # noqa: E731
    return (cat("surface"), cat("normals"), jnp.asarray(ids("surface")),
            cat("space"), cat("distance"), jnp.asarray(ids("space")))


def _loss(arch: Architecture, kind: str, net, codes, batch):
    surf, nrm, sid, space, dist, qid = batch
    zs = codes[sid] if arch.latent else None
    zq = codes[qid] if arch.latent else None
    if kind == "occupancy":
        logit = apply(arch, net, space, zq)
        loss = jnp.mean(optax.sigmoid_binary_cross_entropy(logit, (dist < 0).astype(logit.dtype)))
    else:
        x = jnp.concatenate([surf, space])
        z = None if zs is None else jnp.concatenate([zs, zq])
        f, pull = jax.vjp(lambda y: apply(arch, net, y, z), x)
        g = pull(jnp.ones_like(f))[0]
        ns = len(surf)
        fs, fq, gs = f[:ns], f[ns:], g[:ns]
        gnorm = jnp.sqrt(jnp.sum(g * g, axis=1) + 1e-12)
        cos = jnp.sum(gs * nrm, axis=1) / gnorm[:ns]
        loss = (jnp.mean(jnp.abs(fs)) + jnp.mean(jnp.abs(fq - dist))
                + W_NORMAL * jnp.mean(1.0 - cos) + W_EIKONAL * jnp.mean((gnorm - 1.0) ** 2))
    if arch.latent:
        loss = loss + W_LATENT * jnp.mean(jnp.sum(codes * codes, axis=1))
    return loss


def _draw(data, key, batch: int):
    surf, nrm, sid, space, dist, qid = data
    k1, k2 = jax.random.split(key)
    i = jax.random.randint(k1, (batch,), 0, len(surf))
    j = jax.random.randint(k2, (batch,), 0, len(space))
    return surf[i], nrm[i], sid[i], space[j], dist[j], qid[j]


@functools.lru_cache(maxsize=32)
def _compiled(arch: Architecture, kind: str, mode: str, batch: int, steps: int, lr: float, code_lr: float = 1.0):
    """``(optimizer, block)`` for one training configuration, compiled once per process: a
    second fit with the same settings (a test, a benchmark repeat) skips JAX's compilation.

    ``block(state, opt_state, fixed, data, key, start, count)`` runs ``count`` Adam steps from
    step ``start``; ``mode`` is ``"network"`` (weights and codes train) or ``"codes"`` (only the
    codes train, the weights are ``fixed``); in ``"network"`` mode the codes step at ``code_lr``
    times the weights' rate (Adam's step does not scale with the gradient, so a separate optimizer)."""
    adam = lambda rate: optax.adam(optax.cosine_decay_schedule(rate, steps, alpha=FINAL_LR))  # noqa: E731
    if mode == "network" and arch.latent and code_lr != 1.0:
        opt = optax.multi_transform({"net": adam(lr), "codes": adam(lr * code_lr)},
                                    lambda state: {k: jax.tree_util.tree_map(lambda _: k, v) for k, v in state.items()})
    else:
        opt = adam(lr)

    def loss_of(state, fixed, b):
        net = state["net"] if mode == "network" else fixed
        return _loss(arch, kind, net, state.get("codes"), b)

    @jax.jit
    def block(state, opt_state, fixed, data, key, start, count):
        def step(k, carry):
            state, opt_state, total = carry
            b = _draw(data, jax.random.fold_in(key, start + k), batch)
            loss, grads = jax.value_and_grad(loss_of)(state, fixed, b)
            updates, opt_state = opt.update(grads, opt_state, state)
            return optax.apply_updates(state, updates), opt_state, total + loss

        state, opt_state, total = jax.lax.fori_loop(0, count, step, (state, opt_state, jnp.float32(0.0)))
        return state, opt_state, total / count

    return opt, block


def _run(arch, kind, mode, state, fixed, data, settings: Settings, lr: float, seed: int, callback):
    """Adam for ``settings.steps`` steps from ``state``; ``(state, losses [(step, mean loss)])``."""
    opt, block = _compiled(arch, kind, mode, settings.batch, settings.steps, float(lr), settings.code_lr)
    opt_state = opt.init(state)
    key = jax.random.PRNGKey(seed)
    losses = []
    done = 0
    while done < settings.steps:
        count = min(BLOCK, settings.steps - done)
        state, opt_state, mean = block(state, opt_state, fixed, data, key, done, count)
        loss = float(mean)
        if not np.isfinite(loss):
            raise ConvergenceError(f"the training loss became {loss} at step {done + count}; lower lr (now {lr:g})")
        done += count
        losses.append((done, loss))
        if callback is not None:
            callback(done, settings.steps, loss)
    return state, losses


def fit_network(arch: Architecture, kind: str, pools: list[SamplePool], settings: Settings, seed: int, callback=None):
    """Train weights (and one latent code per pool when ``arch.latent``) from scratch.

    Returns ``(params, codes (len(pools), latent) or None, losses [(step, mean loss)])``, numpy
    float32."""
    key_net, key_codes = jax.random.split(jax.random.PRNGKey(seed))
    state = {"net": init_params(arch, key_net)}
    if arch.latent:
        state["codes"] = LATENT_INIT * jax.random.normal(key_codes, (len(pools), arch.latent), jnp.float32)
    state, losses = _run(arch, kind, "network", state, None, _stack(pools), settings, settings.learning_rate(arch),
                         seed + 1, callback)
    to_np = lambda a: np.asarray(a, dtype=np.float32)  # noqa: E731
    params = [{k: to_np(v) for k, v in layer.items()} for layer in state["net"]]
    codes = to_np(state["codes"]) if arch.latent else None
    return params, codes, losses


def fit_codes(arch: Architecture, params, pool: SamplePool, settings: Settings, seed: int, callback=None):
    """One new latent code ``(latent,)`` for ``pool`` with the weights ``params`` held fixed."""
    net = jax.tree_util.tree_map(lambda a: jnp.asarray(a, jnp.float32), params)
    state = {"codes": LATENT_INIT * jax.random.normal(jax.random.PRNGKey(seed), (1, arch.latent), jnp.float32)}
    lr = 10.0 * settings.learning_rate(arch)  # only a few numbers move: a larger step is safe
    state, losses = _run(arch, "sdf", "codes", state, net, _stack([pool]), settings, lr, seed + 1, callback)
    return np.asarray(state["codes"][0], dtype=np.float32), losses
