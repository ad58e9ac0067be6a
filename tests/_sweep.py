"""Sweeps that run a sample by default and in full under ``-m slow``.

``@pytest.mark.parametrize("seed", seeds(40, default=10))`` runs seeds 0..9 in the default run and
all forty with ``-m slow`` (seeds 10..39 carry the ``slow`` marker), so the default run stays fast
while the long sweep keeps the same cases and ids.
"""

from __future__ import annotations

import pytest


def seeds(total: int, default: int):
    """``range(total)`` as parameters, those from ``default`` on marked ``slow``."""
    return [s if s < default else pytest.param(s, marks=pytest.mark.slow) for s in range(total)]
