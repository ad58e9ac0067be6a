"""The compiled kernel module a test needs, or the test skipped when numba cannot load it."""

from __future__ import annotations

import pytest

from splinekit import _kernels


def compiled_or_skip(module: str):
    """The loaded kernel module ``module`` (loaded now, whatever the job size), else a skip."""
    kernels = _kernels.load(module)
    if kernels is None:
        pytest.skip("numba kernels unavailable")
    return kernels
