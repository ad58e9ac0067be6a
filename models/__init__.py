"""Scripted parametric models: examples, command-line targets and test fixtures.

Every model module has a docstring (what it is; lengths in millimetres),
``PARAMETERS`` (a tuple of :class:`Parameter`) and ``build(**params) -> Model``.
``MODELS`` lists them in a stable order; :func:`build_model` builds one by name.
The default, ``"teapot"``, builds fastest (32 patches from a table) and is
the best-known shape in the set.

Import it beside splinekit, splinekit first::

    import splinekit as sk
    from models import build_model

    vase = build_model("vase", height=200.0)

``models`` is a common name: once splinekit is imported, ``import models``
raises :class:`splinekit.errors.ShadowedPackageError` (an ImportError naming
both folders and the fix) when another project's ``models`` comes first on
``sys.path``, instead of silently importing that one.
"""

from __future__ import annotations

from splinekit.errors import ParameterError

from . import block, bracket, mug, parameter_sweep, teapot, vase, wing
from ._base import INTEGRAL_TOLERANCE, Model, Parameter, resolve_params, surface_integrals

__all__ = [
    "DEFAULT_MODEL",
    "MODELS",
    "Model",
    "Parameter",
    "build_model",
    "get_model",
    "resolve_params",
    "sweep",
    "surface_integrals",
    "INTEGRAL_TOLERANCE",
]

MODELS = {
    "teapot": teapot,
    "vase": vase,
    "mug": mug,
    "bracket": bracket,
    "wing": wing,
    "block": block,
}

DEFAULT_MODEL = "teapot"


def get_model(name: str):
    """The model module registered as ``name``; ParameterError naming the available ones otherwise."""
    module = MODELS.get(name) if isinstance(name, str) else None
    if module is None:
        raise ParameterError(f"unknown model {name!r}; available: {', '.join(MODELS)}")
    return module


def build_model(name: str, **params) -> Model:
    """``get_model(name).build(**params)``."""
    return get_model(name).build(**params)


def sweep(model, parameters, **options):
    """Parameter sweep of model ``model`` (a registry name or a model module) on Dask: see
    :func:`models.parameter_sweep.sweep` for ``parameters`` and the options; returns the results
    as a pandas DataFrame. ``splinekit.sweep(name, parameters, ...)`` comes here."""
    return parameter_sweep.sweep(get_model(model) if isinstance(model, str) else model, parameters, **options)
