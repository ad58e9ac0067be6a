"""``python -m splinekit``: the ``splinekit`` command (:mod:`splinekit.cli`)."""

import sys

from .cli import main

sys.exit(main())
