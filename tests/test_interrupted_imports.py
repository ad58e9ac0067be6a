"""Ctrl-C while an optional backend is being imported is an interrupt, never "package missing".

An extension interrupted while it initialises reports ``ImportError`` with the
``KeyboardInterrupt`` as its cause; every loader that turns an ImportError into a
MissingDependencyError or BackendError must re-raise the interrupt first. A real import failure
(any other cause) must still name the package.
"""

from __future__ import annotations

import importlib.abc
import importlib.util
import sys

import pytest

from splinekit.errors import BackendError, MissingDependencyError
from splinekit.interop import booleans
from splinekit.plot import picture
from splinekit.tessellation import trimmed


class _FailingImport(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Imports of ``name`` fail with ImportError caused by ``cause``."""

    def __init__(self, name, cause):
        self.name, self.cause = name, cause

    def find_spec(self, name, path=None, target=None):
        return importlib.util.spec_from_loader(name, self) if name == self.name else None

    def create_module(self, spec):
        return None

    def exec_module(self, module):
        raise ImportError("initialization failed") from self.cause


LOADERS = [
    ("manifold3d", booleans._require_manifold3d, MissingDependencyError),
    ("matplotlib", picture.pyplot, MissingDependencyError),
    ("triangle", trimmed._triangulator, BackendError),
]


@pytest.mark.parametrize("package, load, error", LOADERS, ids=[p for p, _, _ in LOADERS])
def test_interrupted_backend_import_is_an_interrupt(monkeypatch, package, load, error):
    for name in [m for m in sys.modules if m == package or m.startswith(package + ".")]:
        monkeypatch.delitem(sys.modules, name)
    finder = _FailingImport(package, KeyboardInterrupt())
    monkeypatch.setattr(sys, "meta_path", [finder] + sys.meta_path)
    with pytest.raises(KeyboardInterrupt):
        load()
    finder.cause = RuntimeError(f"a broken build of {package}")  # a real failure stays one
    with pytest.raises(error, match=package):
        load()
