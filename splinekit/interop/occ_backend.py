"""Loading OpenCascade (OCP) and calling it: the one place that imports OCP's modules.

OCP is imported inside these functions, on first use, and cached, so ``import splinekit`` never
loads it; a missing OCP (or build123d / cadquery) raises MissingDependencyError naming the
packages to install, and an OCC exception becomes a BackendError naming what failed.
"""

from __future__ import annotations

from .._signals import reraise_interrupt
from ..errors import BackendError, MissingDependencyError, SplineKitError

__all__ = ["require_ocp"]


_INSTALL_HINT = "pip install 'cadquery==2.8.*' 'build123d>=0.12,<0.13'"


def _missing(what: str, exc: Exception) -> MissingDependencyError:
    """The error for a failed import of ``what``; an import that failed because SIGINT/SIGTERM
    interrupted it (OCP's pybind11 initialisation reports ``ImportError: initialization failed``
    caused by the KeyboardInterrupt) re-raises the interrupt instead: it is no missing package."""
    reraise_interrupt(exc)
    return MissingDependencyError(
        f"{what} is missing: install it with {_INSTALL_HINT} "
        f"(they provide OCP 7.9); the import failed with: {exc}"
    )


_MODULES: dict = {}  # OCP submodules already imported, valid while sys.modules["OCP"] is unchanged


def require_ocp():
    """Import and return the OCP modules used here, or raise MissingDependencyError."""
    Geom, TColgp, TColStd, gp = _ocp("Geom", "TColgp", "TColStd", "gp")
    return Geom, TColgp, TColStd, gp


def _ocp(*names: str):
    """The OCP submodules ``names`` (e.g. ``"BRep"``), or MissingDependencyError.

    Imports are cached: converting many small patches calls this once per patch.
    """
    import sys

    root = sys.modules.get("OCP")
    if root is None or _MODULES.get("") is not root:  # first use, or OCP blocked / reloaded
        _MODULES.clear()
        try:
            import OCP
        except ImportError as exc:  # also covers sys.modules["OCP"] = None
            raise _missing("OpenCascade bindings (OCP)", exc) from None
        _MODULES[""] = OCP
    try:
        return tuple(_MODULES[n] if n in _MODULES else _import_ocp(n) for n in names)
    except ImportError as exc:
        raise _missing("OpenCascade bindings (OCP)", exc) from None


def _import_ocp(name: str):
    import importlib

    module = _MODULES[name] = importlib.import_module(f"OCP.{name}")
    return module


def _occ_call(what: str, fn, *args):
    """``fn(*args)``, with an OpenCascade exception turned into a BackendError naming ``what``."""
    try:
        return fn(*args)
    except SplineKitError:
        raise
    except Exception as exc:  # OCP's Standard_Failure family shares no base class but Exception
        raise BackendError(f"OpenCascade failed to {what}: {type(exc).__name__}: {exc}") from None
