"""The autodiff backend of :mod:`splinekit.neural`: JAX and optax, an optional extra.

Importing this module imports them, or raises
:class:`~splinekit.errors.MissingDependencyError` (a SplineKitError and an ImportError) that names
the install command. Nothing outside :mod:`splinekit.neural` imports it, so ``import splinekit``
never loads JAX.

JAX runs on the CPU here. Double precision is switched on (``jax_enable_x64``) because a trained
shape is evaluated as a splinekit implicit in float64: Newton closest points stop at
``|F| <= 1e-10`` of the model size, which float32 cannot reach. Training still runs in float32 (its
arrays are created float32 explicitly), which is about twice as fast on the CPU.
"""

from __future__ import annotations

import os

from ..errors import MissingDependencyError

INSTALL = 'pip install "splinekit[neural]"'
"""The command that installs the optional extra (JAX and optax on the CPU)."""

# JAX would otherwise look for accelerators and warn when it finds none
os.environ.setdefault("JAX_PLATFORMS", "cpu")

try:
    import jax
    import jax.numpy as jnp
    import optax
except ImportError as exc:  # the extra is not installed (or a part of it is blocked)
    raise MissingDependencyError(
        f"splinekit.neural needs JAX and optax, which are not installed ({exc}); install them with: {INSTALL}"
    ) from None

jax.config.update("jax_enable_x64", True)

__all__ = ["INSTALL", "jax", "jnp", "optax"]
