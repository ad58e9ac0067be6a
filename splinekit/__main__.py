"""``python -m splinekit`` and the ``splinekit`` console script: the command line (:mod:`splinekit.cli`).

The command line imports the ``models`` and ``exporters`` packages beside splinekit; when another
project's package of that name comes first on ``sys.path`` (see :mod:`splinekit._siblings`), that
import fails before the command's own error handling exists, so it is reported here, in one line.
"""

import sys

from .errors import ShadowedPackageError

try:
    from .cli import main as _command
except ShadowedPackageError as exc:
    _command, _import_error = None, exc


def main(argv=None) -> int:
    """Run the ``splinekit`` command with ``argv`` (default: ``sys.argv[1:]``); the exit status."""
    if _command is None:
        print(f"splinekit: error: {_import_error}", file=sys.stderr)
        return 1
    return _command(argv)


if __name__ == "__main__":
    sys.exit(main())
