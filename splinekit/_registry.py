"""Where the model registry is: the ``models`` package, or the module named by the environment
variable ``SPLINEKIT_MODELS`` with the same interface.

The registry sits in a later layer than splinekit (``models`` imports splinekit, never the other
way round), so the library finds it at run time by name, as a plug-in, rather than importing it:
the ``splinekit`` command and :func:`splinekit.sweep` with a model name both look it up here.
"""

from __future__ import annotations

import importlib
import os

from . import _signals
from .errors import MissingDependencyError

__all__ = ["ENV_VAR", "REGISTRY_INTERFACE", "registry"]

ENV_VAR = "SPLINEKIT_MODELS"
REGISTRY_INTERFACE = ("MODELS", "DEFAULT_MODEL", "get_model", "build_model")
"""What every registry module has; parameter sweeps also need its ``sweep``."""


def registry(needs: tuple = REGISTRY_INTERFACE):
    """The model registry module: ``models``, or the module named by ``SPLINEKIT_MODELS``.

    MissingDependencyError when it cannot be imported or lacks one of the names ``needs``.
    """
    name = os.environ.get(ENV_VAR, "").strip() or "models"
    try:
        module = importlib.import_module(name)
    except ImportError as exc:
        _signals.reraise_interrupt(exc)
        raise MissingDependencyError(f"cannot import the model registry {name!r}: {exc}") from None
    missing = [attr for attr in needs if not hasattr(module, attr)]
    if missing:
        raise MissingDependencyError(f"the model registry {name!r} has no {', '.join(missing)} (its models are not installed yet?)")
    return module
