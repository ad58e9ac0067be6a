"""Shared pytest configuration.

Under CI (the ``CI`` environment variable set) hypothesis runs derandomized, so
a submission's test run is reproducible; locally each run explores new examples.
"""

import os

from hypothesis import settings

settings.register_profile("ci", derandomize=True, print_blob=True)
if os.environ.get("CI"):
    settings.load_profile("ci")
