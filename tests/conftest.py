"""Shared pytest configuration.

Under CI (the ``CI`` environment variable set) hypothesis runs derandomized, so
a submission's test run is reproducible; locally each run explores new examples.
"""

import os

from hypothesis import settings

settings.register_profile("ci", derandomize=True, print_blob=True)
if os.environ.get("CI"):
    settings.load_profile("ci")


def pytest_collection_modifyitems(config, items):
    """Tests marked ``slow`` (long sweeps) run only when ``-m`` names them (``-m slow``)."""
    if "slow" in (config.getoption("markexpr") or ""):
        return
    import pytest

    skip = pytest.mark.skip(reason="slow: run with -m slow")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip)
