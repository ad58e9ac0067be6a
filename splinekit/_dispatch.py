"""``splinekit.sweep``: one public name for two meanings, told apart by the first argument.

``sweep(profile, path)`` (a curve first) is the swept surface of
:func:`splinekit.construct.sweep`; ``sweep(model, parameters, ...)`` (a model name or module
first) is a parameter sweep of that model on Dask, run by the model registry's ``sweep``
(:func:`models.sweep`), which the library finds at run time like the ``splinekit`` command does.
"""

from __future__ import annotations

from . import _registry
from .construct import sweep as sweep_surface

__all__ = ["sweep"]


def _is_model(first) -> bool:
    """A registry name, or a model module (declared parameters and a build function)."""
    return isinstance(first, str) or (hasattr(first, "PARAMETERS") and callable(getattr(first, "build", None)))


def sweep(*args, **kwargs):
    """Sweep a profile along a path, or sweep a model's parameters.

    ``sweep(profile, path, *, n_sections=None, tolerance=None, normal=None, degree=3)``
        The surface of ``profile`` swept along ``path`` in the rotation-minimizing frame: see
        :func:`splinekit.construct.sweep` (returns a BSplineSurface or NurbsSurface).

    ``sweep(model, parameters, *, measures=None, formats=None, out="sweep", client=None, ...)``
        Every variant of ``model`` (a registry name such as ``"vase"``, or a model module) built,
        checked, measured and exported in its own Dask task; returns a pandas DataFrame, written
        as ``out/results.parquet`` and ``out/results.csv``. ``parameters`` is a grid (dict of
        lists, full factorial), a list of dicts, or a pandas/pyarrow table. See
        :func:`models.parameter_sweep.sweep` for every option. Needs the optional extra
        ``sweep`` (dask[distributed], pandas, pyarrow).

    Example::

        surface = sk.sweep(sk.line([0.0, 0.0], [1.0, 0.0]), sk.line([0, 0, 0], [0, 0, 5.0]))
        table = sk.sweep("vase", {"height": [100, 200, 300]}, measures=["volume"], out="sweep")
    """
    first = args[0] if args else kwargs.get("model", kwargs.get("profile"))
    if "profile" not in kwargs and _is_model(first):
        return _registry.registry(_registry.REGISTRY_INTERFACE + ("sweep",)).sweep(*args, **kwargs)
    return sweep_surface(*args, **kwargs)
