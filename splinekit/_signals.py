"""SIGINT and SIGTERM in the ``splinekit`` command: one line, status 130/143, no temporary file.

The command goes through three phases, and a signal is handled by the phase it lands in:

* **starting** (from the first line of ``import splinekit`` until :func:`splinekit.cli.main`
  runs): nothing of ours exists yet, so the handler prints the line and ends the process at once.
  :func:`install_for_command` sets this up, and only when the process *is* the command
  (``splinekit ...``, ``python -m splinekit ...``); importing splinekit anywhere else changes
  no handler.
* **running** (inside ``main``): the handler raises :class:`Interrupted`, a
  ``KeyboardInterrupt``, which unwinds through every ``finally`` -- the atomic writer removes
  its temporary file -- and ``main`` turns it into the line and the status. Inside a
  :class:`deferred` block (the atomic writer's bookkeeping) the signal is held and raised when
  the block ends, so it cannot fall between creating a temporary file and guarding it.
* **finished** (``main`` is done and ends the process): the line and an immediate exit.

Python runs a handler only between bytecodes of the main thread, so a signal that arrives while
OpenCascade's C++ code (or numba's compiler) runs takes effect when control is back in Python.
If that first Python code is a callback from C whose exceptions C discards ("Exception ignored
on calling ctypes callback function", as numba's compiler callbacks do), the discarded interrupt
is caught by our ``sys.unraisablehook`` and raised again a moment later in ordinary code (the
signal is resent until it lands outside the hook, where raising prints no traceback). An
interrupt that a library swallows outright still counts: ``main`` asks :func:`received` when
the command ends. A second signal while the first one is being handled ends the command's
process at once.

``main`` called inside another program (tests call ``main([...])``) installs the running-phase
handler for the duration of the call and restores the previous handlers afterwards.
"""

from __future__ import annotations

import _thread
import os
import signal
import sys
import threading
import time

__all__ = ["Interrupted", "STATUS", "deferred", "finish", "interruptible", "install_for_command", "message",
           "received", "reraise_interrupt", "running"]

STATUS = {signal.SIGINT: 130, signal.SIGTERM: 143}
"""Exit status per handled signal: 128 + the signal number, as a shell reports a killed process."""

_STARTING, _RUNNING, _FINISHED, _OFF = "starting", "running", "finished", "off"
_AGAIN_AFTER = 0.01  # seconds before a discarded interrupt is raised again


class Interrupted(KeyboardInterrupt):
    """SIGINT or SIGTERM arrived while a command ran; ``signum`` says which, ``status`` is 128 + it."""

    def __init__(self, signum: int):
        super().__init__(signal.Signals(signum).name)
        self.signum = int(signum)

    @property
    def status(self) -> int:
        return STATUS.get(self.signum, 128 + self.signum)


class _State:
    phase = _OFF
    own = False  # the process is the command (main was entered from the starting phase)
    received: int | None = None  # the first signal of this run
    in_flight = False  # an Interrupted is unwinding
    pending: int | None = None  # held by a deferred block
    deferred = 0  # depth of deferred blocks (interruptible sets it to 0 inside)
    previous_hook = None  # sys.unraisablehook before running()
    resender = None  # the thread that sends a discarded interrupt again (see _again_soon)


_state = _State()
# the resender's check-and-send against the end of the running phase; reentrant because the
# handler may take it while the main thread holds it (in _again_soon)
_lock = threading.RLock()


def message(signum: int) -> str:
    """The one line printed for ``signum`` (without the newline)."""
    if signum == signal.SIGINT:
        return "splinekit: interrupted"
    return f"splinekit: terminated by {signal.Signals(signum).name}"


def _write_line(text: str) -> None:
    """Flush what the command printed so far, then write ``text`` (if any) as a line on stderr."""
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError, AttributeError):
            pass
    if text:
        try:
            os.write(2, (text + "\n").encode())
        except OSError:
            pass


def _exit_now(signum: int) -> None:
    """Print the line and end the process without unwinding."""
    _write_line(message(signum))
    os._exit(STATUS.get(signum, 128 + signum))


def finish(status: int) -> None:
    """End the command's own process with ``status`` now, output flushed, skipping the
    interpreter's teardown (where a signal would meet default handling, and an extension
    interrupted while it initialised may crash)."""
    _write_line("")
    os._exit(status)


def _raise(signum: int) -> None:
    _state.in_flight = True
    raise Interrupted(signum)


def _handler(signum, frame) -> None:
    if _state.received is None:
        _state.received = signum
    if _state.phase != _RUNNING:
        _exit_now(signum)
    if _in_hook(frame):  # an exception raised here would be printed as a traceback, not raised
        _again_soon()
        return
    if _state.deferred or _state.pending is not None:  # held until the deferred block ends
        if _state.pending is None:
            _state.pending = signum
        return
    if not _state.in_flight:
        _raise(_state.received)
    if _state.own:  # a second signal while the first unwinds: the user insists
        _exit_now(signum)


def _unraisable(unraisable) -> None:
    """sys.unraisablehook while running: an Interrupted that C code discarded (raised inside a
    callback) is raised again shortly, from wherever the main thread is then; anything else
    goes to the previous hook."""
    exc = unraisable.exc_value
    if isinstance(exc, Interrupted) and _state.phase == _RUNNING:
        _state.in_flight = False
        _again_soon()
        return
    (_state.previous_hook or sys.__unraisablehook__)(unraisable)


def _in_hook(frame) -> bool:
    """Whether ``frame`` (where the main thread was when a signal came) runs inside
    :func:`_unraisable`, whose exceptions Python prints as "Exception ignored in
    sys.unraisablehook" with a traceback instead of raising them."""
    while frame is not None:
        if frame.f_code is _unraisable.__code__:
            return True
        frame = frame.f_back
    return False


def _again_soon() -> None:
    """Start (once) the thread that sends the first signal to the main thread again until the
    interrupt is raised in ordinary code. A resent signal that lands inside the hook again is
    dropped by the handler and sent once more ``_AGAIN_AFTER`` later, so under any load one of
    them lands where it can be raised."""
    with _lock:
        if _state.resender is not None and _state.resender.is_alive():
            return
        _state.resender = threading.Thread(target=_resend, name="splinekit-signal-again", daemon=True)
        _state.resender.start()


def _resend() -> None:
    """Send the run's first signal to the main thread every ``_AGAIN_AFTER`` seconds until it is
    raised (a real signal, so that a blocking call such as a sleep is interrupted too)."""
    while True:
        time.sleep(_AGAIN_AFTER)
        with _lock:  # running.__exit__ takes it too: no signal is sent after the phase ended
            if _state.phase != _RUNNING or _state.in_flight or _state.received is None:
                return
            if _state.pending is not None:  # a deferred block holds it and raises it at its end
                return
            if hasattr(signal, "pthread_kill"):
                signal.pthread_kill(threading.main_thread().ident, _state.received)
            else:  # pragma: no cover - Windows: the handler runs, a blocking call is not interrupted
                _thread.interrupt_main(_state.received)


def _in_main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


def _install() -> dict:
    """Our handler for SIGINT and SIGTERM; returns the previous handlers."""
    return {s: signal.signal(s, _handler) for s in STATUS}


def _is_command() -> bool:
    """Whether this process is the ``splinekit`` command: its script is named ``splinekit`` or
    it runs ``python -m splinekit`` / ``python -m splinekit.cli``."""
    if sys.argv and os.path.splitext(os.path.basename(sys.argv[0]))[0] == "splinekit":
        return True
    argv = list(getattr(sys, "orig_argv", None) or [])
    if sys.argv and sys.argv[0] == "-m" and "-m" in argv:  # splinekit is being located as a -m target
        index = argv.index("-m")
        return index + 1 < len(argv) and argv[index + 1] in ("splinekit", "splinekit.cli")
    return False


def install_for_command() -> None:
    """Enter the starting phase if this process is the command (see the module docstring)."""
    if _state.phase == _OFF and _in_main_thread() and _is_command():
        _install()
        _state.phase = _STARTING


class running:
    """``with running() as own:`` -- the running phase around one call of ``main``.

    ``own`` is True when this process is the command (the starting phase was entered); then the
    handlers stay installed afterwards (finished phase). Otherwise the previous handlers (and
    ``sys.unraisablehook``) are restored on exit. Outside the main thread, or in a nested call,
    nothing is installed (Python allows handlers only in the main thread).
    """

    def __enter__(self) -> bool:
        self.own = _state.phase == _STARTING
        self.active = _state.phase in (_STARTING, _OFF) and _in_main_thread()
        if not self.active:
            return self.own
        self.previous = None if self.own else _install()
        _state.previous_hook, sys.unraisablehook = sys.unraisablehook, _unraisable
        _state.own, _state.received, _state.in_flight, _state.pending, _state.deferred = self.own, None, False, None, 0
        _state.phase = _RUNNING
        return self.own

    def __exit__(self, *exc) -> None:
        if not self.active:
            return
        _state.in_flight = True  # main has reported any signal by now: one more is not resent
        if self.own:
            with _lock:
                _state.phase = _FINISHED
            return
        with _lock:
            _state.phase, _state.received, _state.in_flight, _state.pending, _state.deferred = _OFF, None, False, None, 0
        sys.unraisablehook = _state.previous_hook
        for signum, handler in self.previous.items():
            signal.signal(signum, handler if handler is not None else signal.SIG_DFL)


def received() -> int | None:
    """The first signal number seen during the current ``running()`` block, or None."""
    return _state.received


class deferred:
    """``with deferred():`` -- a signal arriving inside is held and raised when the block ends."""

    def __enter__(self) -> None:
        _state.deferred += 1

    def __exit__(self, *exc) -> None:
        _state.deferred -= 1
        if _state.deferred == 0 and _state.pending is not None and _state.phase == _RUNNING:
            _state.pending = None
            if not _state.in_flight:
                _raise(_state.received)


class interruptible:
    """``with interruptible():`` inside a :class:`deferred` block -- signals act at once again
    (a held one is raised on entry); the block's hold is back on exit."""

    def __enter__(self) -> None:
        self.saved, _state.deferred = _state.deferred, 0
        if _state.pending is not None and _state.phase == _RUNNING:
            _state.pending = None
            if not _state.in_flight:
                _raise(_state.received)

    def __exit__(self, *exc) -> None:
        _state.deferred = self.saved


def reraise_interrupt(exc: BaseException) -> None:
    """Raise the interrupt behind ``exc`` if there is one, else return.

    An extension module interrupted while it initialises (OCP is a pybind11 module that takes
    about a second to import) reports ``ImportError: initialization failed`` with the
    ``KeyboardInterrupt`` as its cause; code that turns an ImportError into "package missing"
    calls this first so that the interrupt is never reported as a missing package.
    """
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, (KeyboardInterrupt, SystemExit)):
            raise exc
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
