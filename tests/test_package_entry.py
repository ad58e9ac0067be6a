"""A newcomer's first contact with the package: ``help``/``dir`` of splinekit, and
``import models`` / ``import exporters`` when another project's package of that name
comes first on ``sys.path`` (run in subprocesses, so sys.path and sys.modules stay clean)."""

from __future__ import annotations

import doctest
import os
import pydoc
import subprocess
import sys
from pathlib import Path

import pytest

import splinekit as sk
from splinekit.errors import ShadowedPackageError, SplineKitError

ROOT = Path(__file__).resolve().parents[1]
LAZY = ("convert", "implicit", "levelset", "plot", "pointcloud")  # brep comes with the tessellation


def test_docstring_example_runs():
    result = doctest.testmod(sk, verbose=False)
    assert result.attempted >= 3 and result.failed == 0


def test_help_starts_with_the_overview():
    lines = pydoc.render_doc(sk, renderer=pydoc.plaintext).splitlines()
    head = "\n".join(lines[:45])
    assert "Example" in head and "sk.NurbsCurve(" in head and "sk.brep" in head


def test_help_is_a_page_not_a_book():
    """help(splinekit) was 2,708 lines (every public class in full); it is the overview and the
    list of subpackages, and each name's help is one ``help(sk.<name>)`` away."""
    assert len(pydoc.render_doc(sk, renderer=pydoc.plaintext).splitlines()) < 150


def test_star_import_gives_every_public_name():
    namespace = {}
    exec("from splinekit import *", namespace)
    assert set(sk._PUBLIC) <= set(namespace)


def test_dir_lists_lazy_subpackages_without_importing_them():
    code = (
        "import sys, splinekit as sk\n"
        f"names = dir(sk)\n"
        f"print(all(n in names for n in {LAZY!r}), [m for m in {LAZY!r} if 'splinekit.' + m in sys.modules])\n"
        "print(sorted(set(sk._PUBLIC) - set(names)), names == sorted(names))\n"
    )
    out = _run(code, cwd=ROOT)
    assert out.splitlines() == ["True []", "[] True"]


@pytest.mark.parametrize("name", LAZY)
def test_lazy_subpackage_resolves(name):
    module = getattr(sk, name)
    assert module.__name__ == f"splinekit.{name}"


def test_unknown_attribute_still_raises():
    with pytest.raises(AttributeError, match="no_such_thing"):
        sk.no_such_thing  # noqa: B018


def test_shadowed_package_error_is_an_import_error_and_a_splinekit_error():
    assert issubclass(ShadowedPackageError, ImportError)
    assert issubclass(ShadowedPackageError, SplineKitError)


def _run(code: str, cwd, env=None, check=True):
    environment = dict(os.environ, PYTHONPATH=str(ROOT), **(env or {}))
    result = subprocess.run([sys.executable, "-c", code], cwd=cwd, env=environment, capture_output=True, text=True)
    if check:
        assert result.returncode == 0, result.stderr
        return result.stdout.strip()
    return result


def _shadow(folder: Path) -> Path:
    """A folder holding another project's ``models`` package and ``exporters`` module."""
    (folder / "models").mkdir()
    (folder / "models" / "__init__.py").write_text("FOREIGN = True\n")
    (folder / "exporters.py").write_text("FOREIGN = True\n")
    return folder


@pytest.mark.parametrize("name", ["models", "exporters"])
def test_shadowing_package_fails_loudly_in_splinekit(tmp_path, name):
    """splinekit's own code (here the command line, run from a folder holding other ``models`` and
    ``exporters``: ``python -m`` puts that folder first on sys.path) refuses the other package."""
    folder = _shadow(tmp_path)
    code = (
        "import sys, splinekit, splinekit._siblings as s\n"
        "sys.path.insert(0, '')\n"
        "sys.argv = ['splinekit']\n"  # as the command runs
        "try:\n"
        f"    import {name}\n"
        "except ImportError as exc:\n"
        "    print(type(exc).__name__); print(exc)\n"
        "else:\n"
        f"    print('imported', {name}.__file__)\n"
    )
    kind, message = _run(code, cwd=folder).split("\n", 1)
    assert kind == "ShadowedPackageError"
    assert str(folder / name) in message  # the other package's location
    assert str(ROOT / name) in message  # ours
    assert "Rename or move" in message


def test_command_line_names_the_clash(tmp_path):
    folder = _shadow(tmp_path)
    result = subprocess.run([sys.executable, "-m", "splinekit", "list"], cwd=folder, capture_output=True, text=True,
                            env=dict(os.environ, PYTHONPATH=str(ROOT)))
    assert result.returncode != 0
    assert "another package named" in result.stderr and str(folder) in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1  # one line, no traceback


@pytest.mark.parametrize("name", ["models", "exporters"])
def test_users_own_package_of_that_name_imports_with_a_warning(tmp_path, name):
    """A user's own ``models.py`` keeps working beside splinekit: the import warns and goes on."""
    folder = _shadow(tmp_path)
    code = (
        "import sys, warnings; sys.path.insert(0, '')\n"
        "import splinekit\n"
        "with warnings.catch_warnings(record=True) as caught:\n"
        "    warnings.simplefilter('always')\n"
        f"    import {name}\n"
        f"print({name}.FOREIGN); print(caught[0].category.__name__); print(caught[0].message)\n"
    )
    foreign, kind, message = _run(code, cwd=folder).split("\n", 2)
    assert foreign == "True" and kind == "ShadowedPackageWarning"
    assert str(folder / name) in message and str(ROOT / name) in message


def test_shadowing_can_be_allowed(tmp_path):
    folder = _shadow(tmp_path)
    code = "import sys; sys.path.insert(0, ''); import splinekit, models, exporters; print(models.FOREIGN, exporters.FOREIGN)"
    assert _run(code, cwd=folder, env={"SPLINEKIT_ALLOW_SHADOWING": "1"}) == "True True"


def test_our_packages_import_when_nothing_shadows_them(tmp_path):
    code = "import splinekit, models, exporters; print(models.__file__); print(exporters.__file__)"
    out = _run(code, cwd=tmp_path).splitlines()
    assert out == [str(ROOT / "models" / "__init__.py"), str(ROOT / "exporters" / "__init__.py")]


def test_other_top_level_imports_are_left_alone(tmp_path):
    """The guard looks at two names only: a project's own ``mymodels`` still imports."""
    (tmp_path / "mymodels.py").write_text("OK = 1\n")
    assert _run("import sys; sys.path.insert(0, ''); import splinekit, mymodels; print(mymodels.OK)", cwd=tmp_path) == "1"
