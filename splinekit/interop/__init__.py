"""Bridges to external kernels. Each module imports its backend inside its
functions, so importing splinekit never loads OCP or manifold3d; :mod:`.occ` (which
loads the B-rep layer) is itself imported on first use."""

import importlib

__all__ = ["occ"]


def __getattr__(name):
    if name == "occ":
        return importlib.import_module(f"{__name__}.occ")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
