"""The shared named tolerances (splinekit.tolerances): their values and units as documented, the
defaults the library reads from them, and the deprecated ``Tolerances`` class."""

from __future__ import annotations

import importlib
import inspect
import math
import subprocess
import sys
import warnings

import numpy as np
import pytest

import splinekit
from splinekit import tolerances
from splinekit.construct.curves import unit_arc
from splinekit.errors import ParameterError


def test_named_tolerances_are_the_documented_figures():
    # the table in the module's docstring, written out again here
    assert tolerances.PARAMETRIC_SLACK == 1e-10
    assert tolerances.KNOT_CONFUSION == 1e-12
    assert tolerances.GEOMETRIC_CONFUSION == 1e-9
    assert tolerances.ANGULAR_CONFUSION == 1e-12
    assert tolerances.INTEGRAL_RTOL == 1e-10
    assert tolerances.ARC_LENGTH_RTOL == 1e-12
    assert tolerances.SAMPLE_COINCIDENCE == 1e-13
    assert tolerances.OCC_CONFUSION == 1e-7
    assert tolerances.WELD == 1e-8
    assert tolerances.DEVIATION_RTOL == 1e-3
    assert tolerances.FD_STEP == 1e-3
    assert tolerances.CONTINUITY_GAP == 1e-6
    assert tolerances.CONTINUITY_ANGLE == 1e-3
    assert tolerances.CONTINUITY_CURVATURE == 1e-2
    assert tolerances.CONTINUITY_MATCH == 1e-3
    constants = [name for name in tolerances.__all__ if name.isupper() and name != "DEFAULT"]
    assert len(constants) == 15
    for name in constants:  # each one has a row in the table: its name, its value, its unit
        assert f"``{name}``" in tolerances.__doc__, name
    # the older short names read the same figures
    d = tolerances.DEFAULT
    assert (d.param, d.knot, d.point) == (1e-10, 1e-12, 1e-9)


def test_parameters_within_the_slack_are_clamped_and_beyond_it_refused():
    c = splinekit.BSplineCurve(1, [0.0, 0.0, 2.0, 2.0], [[0.0], [1.0]])  # domain length 2
    inside = 2.0 + 0.5 * tolerances.PARAMETRIC_SLACK * 2.0
    assert c.evaluate(np.array([inside]))[0, 0] == 1.0
    with pytest.raises(splinekit.SplineKitError):
        c.evaluate(np.array([2.0 + 4 * tolerances.PARAMETRIC_SLACK * 2.0]))


def test_geometric_tolerance_scales_with_the_model_and_checks_its_argument():
    assert tolerances.geometric_tolerance(None, np.array([[0.5, -0.25]])) == 1e-9  # at least 1 unit
    assert tolerances.geometric_tolerance(None, np.array([[3e3, -2e4]])) == pytest.approx(2e-5, rel=1e-15)
    assert tolerances.geometric_tolerance(0.0, np.ones((2, 3))) == 0.0
    assert tolerances.geometric_tolerance("0.25", np.ones((2, 3))) == 0.25
    for bad in (-1e-9, float("nan"), float("inf"), "tight", object()):
        with pytest.raises(ParameterError, match="tol"):
            tolerances.geometric_tolerance(bad, np.ones((2, 3)))


def test_tolerances_class_is_a_deprecated_alias_that_still_works():
    with pytest.warns(DeprecationWarning, match="no function accepts it"):
        t = splinekit.Tolerances(point=1e-6)
    assert (t.param, t.knot, t.point) == (1e-10, 1e-12, 1e-6)
    with pytest.raises(AttributeError):  # still frozen
        t.point = 1.0
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # using the defaults warns nothing
        assert tolerances.DEFAULT.point == 1e-9


def test_import_splinekit_warns_nothing():
    done = subprocess.run([sys.executable, "-W", "error::DeprecationWarning", "-c", "import splinekit"],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr


# Constants the modules used to type out as numbers, now read from splinekit.tolerances. Identity,
# not equality: a number typed again (``WELD = 1e-8``) is equal to the shared one but a different
# object, so this fails for any module that stops reading the shared value.
MODULE_CONSTANTS = [
    ("splinekit.tessellation.trimmed", "WELD", "WELD"),
    ("splinekit.tessellation.surfaces", "WELD", "WELD"),
    ("splinekit.tessellation.core", "DEFAULT_RELATIVE_TOLERANCE", "DEVIATION_RTOL"),
    ("splinekit.pointcloud.reconstruct", "DEFAULT_RELATIVE_TOLERANCE", "DEVIATION_RTOL"),
    ("splinekit.brep.integrate", "DEFAULT_TOLERANCE", "INTEGRAL_RTOL"),
    ("splinekit.interop.gprop", "OCC_PRECISION", "INTEGRAL_RTOL"),
    ("splinekit.interop.gprop", "SCIPY_TOLERANCE", "INTEGRAL_RTOL"),
    ("splinekit.diffgeom.protocol", "DEFAULT_STEP", "FD_STEP"),
    ("splinekit.implicit.base", "RELATIVE_STEP", "FD_STEP"),
    ("splinekit.fit.parametrize", "COINCIDENT", "SAMPLE_COINCIDENCE"),
    ("splinekit.brep.edge", "DEFAULT_TOLERANCE", "OCC_CONFUSION"),
    ("splinekit.construct.curves", "_ANGLE_SLACK", "ANGULAR_CONFUSION"),
]


@pytest.mark.parametrize("module, name, shared", MODULE_CONSTANTS, ids=lambda v: str(v))
def test_module_constants_are_the_shared_ones(module, name, shared):
    assert getattr(importlib.import_module(module), name) is getattr(tolerances, shared)


# Tolerances written into function defaults, likewise (module, attribute path, argument, shared name).
FUNCTION_DEFAULTS = [
    *[("splinekit.brep.shell", f"{cls}.{m}", "tol", "INTEGRAL_RTOL")
      for cls in ("Shell", "Solid") for m in ("area", "volume", "centroid", "inertia", "mass_properties")],
    *[("splinekit.brep.face", f"TrimmedFace.{m}", "tol", "INTEGRAL_RTOL")
      for m in ("area", "centroid", "inertia", "mass_properties")],
    ("models._base", "surface_integrals", "tol", "INTEGRAL_RTOL"),
    ("splinekit.curves.measures", "CurveMeasures.arc_length", "tol", "ARC_LENGTH_RTOL"),
    ("splinekit.curves.bspline", "BezierCurve.arc_length", "tol", "ARC_LENGTH_RTOL"),
    *[("splinekit.diffgeom.arc_length", f, "tol", "ARC_LENGTH_RTOL")
      for f in ("arc_length", "arc_length_parameters", "equal_arc_length_parameters", "reparametrize_by_arc_length")],
    ("splinekit.diffgeom.implicit_surface", "ImplicitSurface.__init__", "step", "FD_STEP"),
    *[("splinekit.interop.occ", f, "tolerance", "OCC_CONFUSION")
      for f in ("to_occ", "to_shape", "to_build123d", "to_cadquery")],
    *[("splinekit.interop.occ_brep_write", f, "tolerance", "OCC_CONFUSION")
      for f in ("brep_to_shape", "brep_list_to_shape")],
    *[(f"exporters.{m}", f"export_{m}", "tolerance", "OCC_CONFUSION") for m in ("step", "brep", "iges")],
]


@pytest.mark.parametrize("module, path, argument, shared", FUNCTION_DEFAULTS, ids=lambda v: str(v))
def test_function_defaults_are_the_shared_ones(module, path, argument, shared):
    obj = importlib.import_module(module)
    for part in path.split("."):
        obj = getattr(obj, part)
    assert inspect.signature(obj).parameters[argument].default is getattr(tolerances, shared)


def test_an_arc_within_the_angular_confusion_of_a_full_turn_is_the_full_circle():
    full = unit_arc(0.0, 2.0 * math.pi)
    near = unit_arc(0.0, 2.0 * math.pi - 0.5 * tolerances.ANGULAR_CONFUSION)
    for a, b in zip(full, near):
        np.testing.assert_array_equal(a, b)
    # the full circle closes: its last control point is its first (cos 0, sin 0) = (1, 0)
    np.testing.assert_array_equal(full[1][-1], [1.0, 0.0])
    short = unit_arc(0.0, 2.0 * math.pi - 1e3 * tolerances.ANGULAR_CONFUSION)
    assert not np.array_equal(short[1][-1], full[1][-1])
    with pytest.raises(ParameterError, match="full turn"):
        unit_arc(0.0, 2.0 * math.pi + 2.0 * tolerances.ANGULAR_CONFUSION)
