"""The model registry the commands build from, and what they need of a built model.

The registry is the ``models`` package, or the module named by the environment variable
``SPLINEKIT_MODELS`` with the same interface (``MODELS``, ``DEFAULT_MODEL``, ``get_model``,
``build_model``). A built model has ``name``, ``params``, ``bodies`` (lists of exact patches),
``body_names``, ``mesh``, ``closed``, ``checks`` and optionally ``solids`` (B-rep solids).
"""

from __future__ import annotations

import importlib
import os
import time

from .. import _signals
from .._progress import progress
from ..errors import MissingDependencyError, ParameterError, SplineKitError
from ..mesh.components import concatenate
from ..tessellation import tessellate
from .console import Console, first_line, number_text

REGISTRY_INTERFACE = ("MODELS", "DEFAULT_MODEL", "get_model", "build_model")


def registry():
    """The model registry module: ``models``, or the module named by ``SPLINEKIT_MODELS``."""
    name = os.environ.get("SPLINEKIT_MODELS", "").strip() or "models"
    try:
        module = importlib.import_module(name)
    except ImportError as exc:
        _signals.reraise_interrupt(exc)
        raise MissingDependencyError(f"cannot import the model registry {name!r}: {exc}") from None
    missing = [attr for attr in REGISTRY_INTERFACE if not hasattr(module, attr)]
    if missing:
        raise MissingDependencyError(f"the model registry {name!r} has no {', '.join(missing)} (its models are not installed yet?)")
    return module


def doc_line(module) -> str:
    """The first line of a model module's docstring, without its final full stop."""
    doc = (module.__doc__ or "").strip()
    return doc.splitlines()[0].rstrip(".") if doc else ""


def parse_sets(reg, name: str, items) -> dict:
    """``--set name=value`` pairs parsed and checked by the model's parameters."""
    module = reg.get_model(name)
    params = {p.name: p for p in module.PARAMETERS}
    values = {}
    for item in items or ():
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise ParameterError(f"--set expects name=value, got {item!r}")
        if key not in params:
            known = ", ".join(params) or "none"
            raise ParameterError(f"model '{name}' has no parameter '{key}'; parameters: {known}")
        try:
            values[key] = params[key].parse(text)
        except SplineKitError:
            raise
        except (ArithmeticError, ValueError, TypeError) as exc:  # a registry's parser that lets one out
            raise ParameterError(f"--set {key}={text!r}: not a value of parameter '{key}' ({first_line(exc)})") from None
    return values


def build_model(reg, name: str, sets, console: Console):
    """Model ``name`` built with the ``--set`` values ``sets``."""
    values = parse_sets(reg, name, sets)
    t0 = time.perf_counter()
    model = reg.build_model(name, **values)
    console.detail(f"built model '{name}' in {time.perf_counter() - t0:.2f} s")
    return model


def model_names(reg, args) -> list:
    """The models a command runs on: every one with ``--all``, else MODEL or the default."""
    if getattr(args, "all", False):
        if args.model or args.set:
            raise ParameterError("--all runs every model with its defaults; give no MODEL and no --set with it")
        return list(reg.MODELS)
    name = args.model or reg.DEFAULT_MODEL
    reg.get_model(name)  # an unknown model fails before any work
    return [name]


def solids_of(model) -> list:
    """The model's exact B-rep solids (none for a model of patches or a mesh)."""
    return list(getattr(model, "solids", None) or [])


def patches_of(model) -> list:
    """Every exact patch of every body of the model."""
    return [p for body in model.bodies for p in body]


def params_text(model) -> str:
    return ", ".join(f"{k}={number_text(v)}" for k, v in (model.params or {}).items())


def model_mesh(model, tolerance=None, label: str = "tessellating"):
    """``(mesh, max_deviation or None)``: the model's own mesh, or its bodies and solids
    tessellated (:func:`splinekit.tessellate`) and joined into one mesh.

    ``tolerance`` is the absolute chordal tolerance (model units); None takes the tolerance a
    B-rep model states in its parameters, else :func:`splinekit.tessellate`'s default (1e-3 of
    the model size). ``max_deviation`` is the largest deviation of any piece's triangles from
    the exact surfaces (None for a model that is only a mesh).
    """
    solids = solids_of(model)
    if not model.bodies and not solids:
        if model.mesh is None:
            raise ParameterError(f"model '{model.name}' has neither exact bodies nor a mesh")
        return model.mesh, None
    if tolerance is None and solids:  # a B-rep model states the tolerance of its meshes
        tolerance = (model.params or {}).get("tolerance")
    meshes = []
    items = [list(body) for body in model.bodies] + solids
    with progress(len(items), label) as bar:
        for item in items:
            meshes.append(tessellate(item, tolerance))
            bar.advance()
    deviation = max(float(getattr(m, "max_deviation", 0.0)) for m in meshes)
    return concatenate(meshes), deviation
