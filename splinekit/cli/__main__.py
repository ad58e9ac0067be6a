"""``python -m splinekit.cli``: the ``splinekit`` command."""

import sys

from . import main

sys.exit(main())
