"""The top-level packages shipped beside splinekit (``exporters``, ``models``) and a guard
against another project's package of the same name being imported in their place.

``exporters`` and ``models`` are common names: a ``models.py`` in the folder a script
runs from, or another distribution's top-level ``exporters``, comes first on
``sys.path`` and ``import models`` silently returns it; the first sign would be an
``AttributeError`` far from the cause. Once splinekit is imported, :func:`install`
puts a finder in front of ``sys.meta_path`` that looks where the ordinary path
search would find these two names. When that is not the package beside splinekit:

- an import made by splinekit's own code (the command line, a model importing the
  exporters) raises :class:`ShadowedPackageError`, naming both locations and the fix:
  there our package is certainly the one meant;
- an import made by the user's code warns (:class:`ShadowedPackageWarning`, naming
  both) and goes on: a user's own ``models.py`` keeps working beside splinekit.

It only looks; the import itself is left to the ordinary machinery (including editable
installs). ``SPLINEKIT_ALLOW_SHADOWING=1`` turns the guard off for people who
want the other package and do not use splinekit's.
"""

from __future__ import annotations

import importlib.machinery
import os
import sys
import warnings

from .errors import ShadowedPackageError

SIBLINGS = ("exporters", "models")
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
"""The folder that holds the ``splinekit`` package, and beside it ``exporters`` and ``models``."""

ALLOW_VARIABLE = "SPLINEKIT_ALLOW_SHADOWING"


def _location(spec) -> str:
    """The file or folder a spec would import from (a namespace package has no origin)."""
    if spec.origin and spec.origin not in ("namespace", "built-in", "frozen"):
        return spec.origin
    return next(iter(spec.submodule_search_locations or ()), str(spec.origin))


def _inside(path: str, folder: str) -> bool:
    path, folder = os.path.realpath(path), os.path.realpath(folder)
    return os.path.commonpath([path, folder]) == folder


class ShadowedPackageWarning(UserWarning):
    """A user's ``import models`` / ``import exporters`` loads another project's package,
    not the one beside splinekit."""


OWN_PACKAGES = ("splinekit", *SIBLINGS)


def _importer() -> str:
    """``__name__`` of the module whose code runs the import (the first frame outside the
    import machinery and this module)."""
    frame = sys._getframe(1)
    while frame is not None:
        filename = frame.f_code.co_filename
        if not (filename.startswith("<frozen importlib") or filename == __file__ or "importlib" in filename):
            return str(frame.f_globals.get("__name__", ""))
        frame = frame.f_back
    return ""


class SiblingGuard:
    """A ``sys.meta_path`` finder that finds nothing itself: for ``exporters`` and
    ``models`` it raises when the path search would import another project's package."""

    def find_spec(self, name, path=None, target=None):
        if name not in SIBLINGS or path is not None or os.environ.get(ALLOW_VARIABLE) == "1":
            return None
        ours = os.path.join(ROOT, name)
        if not os.path.isfile(os.path.join(ours, "__init__.py")):
            return None  # not shipped beside this splinekit (a partial install): nothing to protect
        found = importlib.machinery.PathFinder.find_spec(name)
        if found is None or _inside(_location(found), ours):
            return None
        clash = (f"`import {name}` would load {_location(found)}, another package named {name!r} that "
                 f"comes before splinekit's ({ours}) on sys.path.")
        importer = _importer()
        if importer.split(".")[0] in OWN_PACKAGES or importer == "__main__" and _runs_splinekit():
            raise ShadowedPackageError(
                f"{clash} Rename or move the other one, run from a folder without it, or put {ROOT} "
                f"first on sys.path."
            )
        warnings.warn(f"{clash} It is imported; set {ALLOW_VARIABLE}=1 to silence this warning.",
                      ShadowedPackageWarning, stacklevel=2)
        return None


def _runs_splinekit() -> bool:
    """True in the ``splinekit`` command (its console script or ``python -m splinekit``)."""
    main = sys.modules.get("__main__")
    spec = getattr(main, "__spec__", None)
    return os.path.basename(sys.argv[0] if sys.argv else "") == "splinekit" or (
        spec is not None and (spec.name or "").split(".")[0] == "splinekit")


def install() -> None:
    """Put one :class:`SiblingGuard` in front of ``sys.meta_path`` (again on a reload: by class name)."""
    if not any(type(finder).__name__ == SiblingGuard.__name__ for finder in sys.meta_path):
        sys.meta_path.insert(0, SiblingGuard())
