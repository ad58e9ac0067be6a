"""Atomic file writes: write a temporary file beside the target, then rename.

A failed or interrupted write leaves no partial file and never damages an
existing one.
"""

from __future__ import annotations

import os
import tempfile
from typing import Callable

from ._validate import as_path


def _default_mode() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return 0o666 & ~mask


def atomic_write(path, write: Callable[[str], None]) -> str:
    """Call ``write(tmp_path)`` and move the result onto ``path``.

    The file gets the permissions an ordinary ``open(path, "w")`` would give
    (not mkstemp's 0600). Returns ``path`` as a string.
    """
    path = as_path(path)
    directory = os.path.dirname(os.path.abspath(path))
    suffix = os.path.splitext(path)[1]
    fd, tmp = tempfile.mkstemp(prefix=".splinekit-", suffix=suffix, dir=directory)
    os.close(fd)
    try:
        write(tmp)
        os.chmod(tmp, _default_mode())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return path
