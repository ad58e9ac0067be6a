"""The model registry the commands build from, and what they need of a built model.

The registry is the ``models`` package, or the module named by the environment variable
``SPLINEKIT_MODELS`` with the same interface (``MODELS``, ``DEFAULT_MODEL``, ``get_model``,
``build_model``). A built model has ``name``, ``params``, ``bodies`` (lists of exact patches),
``body_names``, ``mesh``, ``closed``, ``checks`` and optionally ``solids`` (B-rep solids).
"""

from __future__ import annotations

import time

from .._registry import REGISTRY_INTERFACE, registry
from ..errors import ParameterError, SplineKitError
from ..tessellation.bodies import model_mesh, patches_of, solids_of
from .console import Console, first_line, number_text

__all__ = ["REGISTRY_INTERFACE", "build_model", "doc_line", "model_mesh", "model_names", "params_text",
           "parse_sets", "patches_of", "registry", "solids_of"]


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


def params_text(model) -> str:
    return ", ".join(f"{k}={number_text(v)}" for k, v in (model.params or {}).items())
