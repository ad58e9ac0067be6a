"""The shared named tolerances (splinekit.tolerances): their values and units as documented, the
defaults the library reads from them, and the deprecated ``Tolerances`` class."""

from __future__ import annotations

import subprocess
import sys
import warnings

import numpy as np
import pytest

import splinekit
from splinekit import tolerances
from splinekit.errors import ParameterError


def test_named_tolerances_are_the_documented_figures():
    # the table in the module's docstring, written out again here
    assert tolerances.PARAMETRIC_SLACK == 1e-10
    assert tolerances.KNOT_CONFUSION == 1e-12
    assert tolerances.GEOMETRIC_CONFUSION == 1e-9
    assert tolerances.ANGULAR_CONFUSION == 1e-12
    assert tolerances.INTEGRAL_RTOL == 1e-10
    for name in ("PARAMETRIC_SLACK", "KNOT_CONFUSION", "GEOMETRIC_CONFUSION", "ANGULAR_CONFUSION", "INTEGRAL_RTOL"):
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
