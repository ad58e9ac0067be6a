"""Atomic file writes: write a temporary file beside the target, then rename.

Every file splinekit writes (the exporters, STEP through OpenCascade, PNG pictures) goes through
:func:`atomic_write`, so the rules live here once:

* a failed or interrupted write leaves no partial file and never damages an existing one (the
  temporary file ``.splinekit-*`` is removed, the target is untouched or complete);
* only a regular file, or a path that does not exist yet, is a target: a device (``/dev/null``),
  a FIFO, a socket or a folder is refused, since a rename would replace it with a plain file;
* a symbolic link stays: the file it points to is replaced, atomically, in that file's folder;
* an existing file keeps its permission bits (and, where allowed, its owner); a read-only file
  is refused as ``open(path, "w")`` would refuse it;
* errors are :class:`~splinekit.errors.ExportError` naming the target, never the temporary file.
"""

from __future__ import annotations

import os
import stat
import tempfile
from typing import Callable

from ._signals import deferred, interruptible
from ._validate import as_path
from .errors import ExportError

__all__ = ["atomic_write", "checked_path", "write_target"]

TEMP_PREFIX = ".splinekit-"


def checked_path(path) -> str:
    """``path`` (a str, bytes or os.PathLike) as a str; ParameterError if it is not a path, is
    empty or holds a NUL byte (which no file system accepts)."""
    return os.fsdecode(as_path(path))


_KINDS = (
    (stat.S_ISDIR, "a folder"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISFIFO, "a FIFO (named pipe)"),
    (stat.S_ISSOCK, "a socket"),
)


def write_target(path, what: str = "file") -> tuple[str, os.stat_result | None]:
    """``(real, st)``: the file that writing ``path`` replaces and its ``os.stat`` (None if it does
    not exist yet).

    ``real`` is ``path`` with symbolic links resolved, so that a link is kept and the file it points
    to is replaced. ExportError (naming ``what`` and ``path``) if that is not a regular file, is
    read-only, or its folder is missing.
    """
    path = checked_path(path)
    real = os.path.realpath(path)
    try:
        st = os.stat(real)
    except FileNotFoundError:
        st = None
    except OSError as exc:
        raise ExportError(f"cannot write {what} {path!r}: {_reason(exc)}") from None
    shown = f"{path!r} (a link to {real!r})" if os.path.islink(path) else repr(path)
    if st is not None and not stat.S_ISREG(st.st_mode):
        kind = next((name for test, name in _KINDS if test(st.st_mode)), "not a regular file")
        raise ExportError(f"cannot write {what} {shown}: it is {kind}; give the path of a regular file")
    folder = os.path.dirname(real)
    if not os.path.isdir(folder):
        raise ExportError(f"cannot write {what} {shown}: the folder {folder!r} does not exist or is not a folder")
    if st is not None and not os.access(real, os.W_OK):
        raise ExportError(f"cannot write {what} {shown}: the file is read-only")
    return real, st


def _default_mode() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return 0o666 & ~mask


def _reason(exc: OSError) -> str:
    return exc.strerror or str(exc) or type(exc).__name__


def _remove(tmp: str) -> None:
    try:
        os.unlink(tmp)
    except FileNotFoundError:
        pass


def atomic_write(path, write: Callable[[str], None], what: str = "file") -> str:
    """Call ``write(tmp_path)`` and move the result onto ``path``; returns ``path`` as a str.

    ``tmp_path`` is a new empty file in the folder of the file that ``path`` names (after symbolic
    links). A new file gets the permissions an ordinary ``open(path, "w")`` would give (not
    mkstemp's 0600); a replaced file keeps its own. An OSError (from ``write`` too) becomes an
    ExportError naming ``what`` and ``path``; any other exception from ``write`` passes through.
    In every failure, and on SIGINT/SIGTERM in the ``splinekit`` command, the temporary file is
    removed and the target is left as it was.
    """
    path = checked_path(path)
    real, st = write_target(path, what)
    mode = stat.S_IMODE(st.st_mode) if st is not None else _default_mode()
    # The bookkeeping runs with signals held (splinekit._signals): a signal can then not land
    # between creating the temporary file and guarding it, nor in the middle of removing it.
    with deferred():
        try:
            fd, tmp = tempfile.mkstemp(prefix=TEMP_PREFIX, suffix=os.path.splitext(real)[1],
                                       dir=os.path.dirname(real))
        except OSError as exc:
            raise ExportError(f"cannot write {what} {path!r}: {_reason(exc)}") from None
        try:
            os.close(fd)
            with interruptible():
                write(tmp)
            if st is not None and hasattr(os, "chown") and (st.st_uid, st.st_gid) != (os.getuid(), os.getgid()):
                try:  # keep the owner when allowed (root replacing another user's file)
                    os.chown(tmp, st.st_uid, st.st_gid)
                except OSError:
                    pass
            os.chmod(tmp, mode)
            os.replace(tmp, real)
        except BaseException as exc:
            _remove(tmp)
            if isinstance(exc, OSError) and not isinstance(exc, ExportError):
                raise ExportError(f"cannot write {what} {path!r}: {_reason(exc).replace(tmp, path)}") from None
            raise
    return path
