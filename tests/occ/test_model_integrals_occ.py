"""The reference integrals of the models (splinekit.interop.gprop.reference_integrals): OCC's GProp where it
is reliable, scipy where OCC drifts (collapsed edges).
"""

from __future__ import annotations

import pytest
from test_model_integrals import TEAPOT_AREA

import models
from models import teapot


def test_reference_choice():
    pytest.importorskip("OCP")
    from splinekit.interop.gprop import reference_integrals

    teapot_ref = reference_integrals(teapot.build().bodies, closed=False)
    assert teapot_ref.source.startswith("scipy") and "collapsed" in teapot_ref.reason
    assert teapot_ref.volume is None and abs(teapot_ref.area - TEAPOT_AREA) <= 1e-9 * TEAPOT_AREA
    mug = models.build_model("mug", levels=0)
    mug_ref = reference_integrals(mug.bodies, closed=True)
    assert mug_ref.source.startswith("OCC")
    for key in ("area", "volume"):
        expected, tol = mug.checks[key]
        assert abs(getattr(mug_ref, key) - expected) <= 0.1 * tol
