"""SIGINT and SIGTERM sent to a running ``splinekit build`` at random moments inside the command.

Each try runs ``python -m splinekit build teapot --tolerance 1 --format step,stl`` (imports,
the model, tessellation, OCP's import and the STEP translation, both atomic writes) into a folder
where ``teapot.step`` and ``teapot.stl`` already exist with other contents. The command's span
starts at its marker -- the process catches SIGTERM, which splinekit arranges on the first line
of ``import splinekit`` (``SigCgt`` in /proc/PID/status, polled) -- and ends when the process
does. Each try sends one signal at a random fraction of that span after the marker (the
fractions stratified over ``[0, 1)``), so every signal is meant to land inside the command,
whatever the load. Every try must end with

* exit status 130 (SIGINT) or 143 (SIGTERM) and exactly one line on stderr, no traceback;
* no ``.splinekit-*`` temporary file, nothing but the two targets in the folder;
* each target untouched (its old contents) or complete: byte for byte the uninterrupted build's
  file (the STEP header's time stamp aside).

The span is measured under the load of the tries themselves, not once: the reference builds give
the first value, and a try whose build ended before its signal took effect (status 0: finished
before the delay ran out, or met in its last instant, the exit call under way) is a whole build
run under the current load, so its span becomes the new value; such an attempt must show the
complete output and complete files with status 0, and the try is repeated with a shorter delay
until its signal lands. A run therefore cannot fail because the machine is slower or faster than
when the span was measured. A signal before the marker (while the interpreter starts, before
splinekit exists) meets Python's own handling, which no program can change; no try sends one.
The figures are printed (run with ``-s`` to see them).
"""

from __future__ import annotations

import collections
import concurrent.futures
import ctypes
import os
import re
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
COMMAND = [sys.executable, "-m", "splinekit", "build", "teapot", "--tolerance", "1", "--format", "step,stl"]
TARGETS = ("teapot.step", "teapot.stl")
OLD = b"contents from before the build\n"
MESSAGES = {signal.SIGINT: "splinekit: interrupted", signal.SIGTERM: "splinekit: terminated by SIGTERM"}
WORKERS = 2  # builds at a time
POLL = 0.002  # seconds between looks for the marker
ATTEMPTS = 8  # per try; each repeat at most halves the delay, so the signal lands long before


def _env():
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([REPO] + [p for p in [env.get("PYTHONPATH")] if p])
    env.pop("SPLINEKIT_MODELS", None)
    return env


def _step_body(data: bytes) -> bytes:
    return re.sub(rb"FILE_NAME\([^;]*;", b"FILE_NAME();", data, count=1)


def _catches_sigterm(pid: int) -> bool | None:
    """Whether process ``pid`` has a handler for SIGTERM now (None when /proc cannot tell)."""
    try:
        with open(f"/proc/{pid}/status") as fh:
            for line in fh:
                if line.startswith("SigCgt:"):
                    return bool(int(line.split()[1], 16) >> (signal.SIGTERM - 1) & 1)
    except OSError:
        return None
    return None


def _marker(proc) -> float | None:
    """The moment (time.monotonic) process ``proc`` is seen catching SIGTERM, i.e. inside the
    command; None when it ended first."""
    while proc.poll() is None:
        if _catches_sigterm(proc.pid):
            return time.monotonic()
        time.sleep(POLL)
    return None


def _run(folder, signum=None, delay=0.0, timeout=120) -> dict:
    """One build into ``folder``; with ``signum``, that signal ``delay`` seconds after the marker.

    Returns status, stdout, stderr, span (seconds from the marker to the end), sent (the signal
    went to a live process) and handled (the process caught SIGTERM just before it was sent)."""
    proc = subprocess.Popen(COMMAND + ["-o", str(folder)], env=_env(), stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    sent = handled = False
    try:
        marker = _marker(proc)
        if signum is not None and marker is not None:
            time.sleep(max(0.0, marker + delay - time.monotonic()))
            if proc.poll() is None:
                handled = _catches_sigterm(proc.pid)
                proc.send_signal(signum)
                sent = True
        out, err = proc.communicate(timeout=timeout)
        span = None if marker is None else time.monotonic() - marker
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    return dict(status=proc.returncode, stdout=out, stderr=err, span=span, sent=sent, handled=handled)


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The uninterrupted build, run WORKERS at a time: its files and its span (the median)."""
    folders = [tmp_path_factory.mktemp("reference") for _ in range(WORKERS)]
    with concurrent.futures.ThreadPoolExecutor(WORKERS) as pool:
        runs = list(pool.map(_run, folders))
    for run in runs:
        assert run["status"] == 0 and run["stderr"] == "" and run["span"] is not None, run
    files = {name: open(folders[0] / name, "rb").read() for name in TARGETS}
    assert files["teapot.stl"] == open(folders[1] / "teapot.stl", "rb").read()  # the build is deterministic
    assert _step_body(files["teapot.step"]) == _step_body(open(folders[1] / "teapot.step", "rb").read())
    return files, float(np.median([run["span"] for run in runs]))


def _state_of(name, data, reference_files) -> str:
    if data == OLD:
        return "untouched"
    ref = reference_files[name]
    if name.endswith(".step"):
        return "complete" if _step_body(data) == _step_body(ref) else "DAMAGED"
    return "complete" if data == ref else "DAMAGED"


def _attempt(folder, signum, delay, reference_files) -> dict:
    folder.mkdir(parents=True)
    for name in TARGETS:
        (folder / name).write_bytes(OLD)
    result = _run(folder, signum, delay)
    names = sorted(os.listdir(folder))
    states = {n: _state_of(n, (folder / n).read_bytes(), reference_files) for n in TARGETS if n in names}
    result.update(signal=signum, delay=delay, names=names, states=states)
    return result


def _describe(result) -> str:
    return (f"{signal.Signals(result['signal']).name} {result['delay']:.3f} s after the marker: "
            f"status {result['status']}, stderr {result['stderr']!r}, folder {result['names']}, {result['states']}")


def _check_ended_first(result) -> None:
    """An attempt whose build ended before its signal took effect: a whole, normal build."""
    where = _describe(result)
    assert result["span"] is not None, f"{where}: the process ended before it caught SIGTERM"
    assert result["status"] == 0 and result["stderr"] == "", where
    assert re.search(r"total [0-9.]+ s\n$", result["stdout"]), where
    assert result["names"] == sorted(TARGETS) and set(result["states"].values()) == {"complete"}, where


def _check_landed(result) -> None:
    """The contract for a signal that landed inside the command."""
    signum, err, where = result["signal"], result["stderr"], _describe(result)
    assert result["handled"] is True, f"{where}: sent before the command caught SIGTERM"
    assert result["status"] == 128 + signum, where
    assert "Traceback" not in err, where
    assert err.splitlines() == [MESSAGES[signum]], where
    assert result["names"] == sorted(TARGETS), where  # no temporary file left
    assert "DAMAGED" not in result["states"].values(), where


def _try(folder, signum, fraction, reference_files, spans) -> tuple[dict, int]:
    """Send ``signum`` at ``fraction`` of the current span after the marker, repeating with a
    shorter delay until it lands; returns the landed attempt and the number of repeats."""
    delay = fraction * spans[-1]
    for repeat in range(ATTEMPTS):
        result = _attempt(folder / f"attempt{repeat}", signum, delay, reference_files)
        if result["sent"] and result["status"] != 0:
            return result, repeat
        _check_ended_first(result)
        spans.append(result["span"])  # a whole build under the current load: the span re-measured
        delay = min(fraction * result["span"], delay / 2)
    raise AssertionError(f"{signal.Signals(signum).name} at {fraction:.3f} of the span did not land in {ATTEMPTS} attempts")


def _sweep(reference, tmp_path, tries_per_signal, seed):
    files, span = reference
    spans = [span]  # the latest value is the current span (appended to by the worker threads)
    rng = np.random.default_rng(seed)
    jobs = []
    for signum in (signal.SIGINT, signal.SIGTERM):
        # stratified: one fraction in each of tries_per_signal equal slices of [0, 1)
        fractions = (np.arange(tries_per_signal) + rng.random(tries_per_signal)) / tries_per_signal
        jobs += [(signum, float(f)) for f in fractions]
    order = rng.permutation(len(jobs))
    with concurrent.futures.ThreadPoolExecutor(WORKERS) as pool:
        futures = [pool.submit(_try, tmp_path / f"try{i}", *jobs[i], files, spans) for i in order]
        results = [f.result() for f in futures]
    figures = collections.Counter()
    for result, repeats in results:
        _check_landed(result)
        name = signal.Signals(result["signal"]).name
        figures[(name, "landed, targets " + "/".join(sorted(set(result["states"].values()))))] += 1
        figures[(name, "attempts repeated (build ended before the signal)")] += repeats
    print(f"\nsignal sweep: {len(results)} tries, span after the marker {spans[0]:.2f} s measured first, "
          f"{min(spans):.2f}-{max(spans):.2f} s over {len(spans)} measurements ({WORKERS} at a time), seed {seed}")
    for (name, outcome), count in sorted(figures.items()):
        print(f"  {name:8s} {count:4d}  {outcome}")
    for signum in (signal.SIGINT, signal.SIGTERM):  # every try landed and kept the contract
        assert sum(result["signal"] == signum for result, _ in results) == tries_per_signal
    return figures


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="signals and /proc as on Linux")
def test_sigint_and_sigterm_at_random_moments(reference, tmp_path):
    _sweep(reference, tmp_path, tries_per_signal=50, seed=13)


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="signals and /proc as on Linux")
def test_sigint_and_sigterm_at_random_moments_long(reference, tmp_path):
    _sweep(reference, tmp_path, tries_per_signal=150, seed=1313)


# -- the mechanism, in process ----------------------------------------------------------------

REGISTRY = '''
"""Models that signal themselves while they build (for the in-process signal tests)."""
import ctypes, os, signal, time
from dataclasses import dataclass, field

from splinekit.errors import ParameterError
from splinekit.mesh import primitives


@dataclass
class Model:
    name: str
    params: dict
    bodies: list = field(default_factory=list)
    body_names: list = field(default_factory=list)
    mesh: object = None
    closed: bool = True
    checks: dict = field(default_factory=dict)


class _Module:
    PARAMETERS = ()

    def __init__(self, build):
        self.__doc__, self.build = "A model.", build


def _signal():
    os.kill(os.getpid(), int(os.environ["SPLINEKIT_TEST_SIGNAL"]))


def plain(**given):
    _signal()
    time.sleep(20)  # interrupted long before
    return Model("plain", {}, mesh=primitives.box())


def swallowed(**given):
    try:
        _signal()
        time.sleep(20)
    except BaseException:  # a library that swallows everything: the command still ends 130/143
        pass
    return Model("swallowed", {}, mesh=primitives.box())


def in_callback(**given):
    # the signal is handled inside a ctypes callback, whose exceptions ctypes discards
    # (numba's compiler calls back into Python this way)
    callback = ctypes.CFUNCTYPE(None)(lambda: (_signal(), sum(range(1000))))
    callback()
    time.sleep(20)  # the discarded interrupt comes again and ends this
    return Model("in_callback", {}, mesh=primitives.box())


MODELS = {"plain": _Module(plain), "swallowed": _Module(swallowed), "in_callback": _Module(in_callback)}
DEFAULT_MODEL = "plain"


def get_model(name):
    if name not in MODELS:
        raise ParameterError(f"unknown model {name!r}")
    return MODELS[name]


def build_model(name, **params):
    return get_model(name).build(**params)
'''


@pytest.fixture
def signalling_registry(tmp_path, monkeypatch, capsys):
    (tmp_path / "splinekit_signal_models.py").write_text(REGISTRY)
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setenv("SPLINEKIT_MODELS", "splinekit_signal_models")
    monkeypatch.chdir(tmp_path)
    return tmp_path


@pytest.mark.parametrize("model", ["plain", "swallowed", "in_callback"])
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_main_in_process_ends_on_a_signal_with_one_line_and_restores_the_handlers(signalling_registry, monkeypatch,
                                                                                   capsys, model, signum):
    from splinekit.cli import main

    monkeypatch.setenv("SPLINEKIT_TEST_SIGNAL", str(int(signum)))
    before = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    hook = sys.unraisablehook
    t0 = time.monotonic()
    status = main(["build", model, "--format", "stl", "-o", "out"])
    err = capsys.readouterr().err
    assert status == 128 + signum
    assert err.splitlines() == [MESSAGES[signum]]
    assert time.monotonic() - t0 < 15  # not the 20 s sleep: interrupted
    assert {s: signal.getsignal(s) for s in before} == before and sys.unraisablehook is hook


def test_a_signal_inside_the_unraisable_hook_is_raised_later_not_printed(monkeypatch, capsys):
    """Under load the resent signal can land while ``sys.unraisablehook`` still runs (it once
    printed "Exception ignored in sys.unraisablehook" and a traceback); here the hook is made to
    meet a signal every time, deterministically: the interrupt must still end the sleep below
    as an Interrupted, and nothing may be printed."""
    from splinekit import _signals

    real, sent = _signals._again_soon, []

    def again_soon_meeting_a_signal():
        if not sent:  # the first call comes from the hook: a signal lands while it runs
            sent.append(True)
            os.kill(os.getpid(), signal.SIGTERM)
            for _ in range(10000):  # many chances for the handler to run inside the hook
                pass
        real()

    monkeypatch.setattr(_signals, "_again_soon", again_soon_meeting_a_signal)
    callback = ctypes.CFUNCTYPE(None)(lambda: (os.kill(os.getpid(), signal.SIGTERM), sum(range(1000))))
    t0 = time.monotonic()
    with _signals.running():
        with pytest.raises(_signals.Interrupted) as info:
            callback()  # ctypes discards the Interrupted raised inside: the hook gets it
            time.sleep(20)
    assert sent and info.value.signum == signal.SIGTERM and time.monotonic() - t0 < 15
    captured = capsys.readouterr()
    assert captured.err == "" and captured.out == ""


def test_a_signal_inside_a_deferred_block_is_raised_when_it_ends(tmp_path):
    from splinekit import _atomic, _signals

    steps = []
    with _signals.running():
        with pytest.raises(_signals.Interrupted) as info:
            with _signals.deferred():
                os.kill(os.getpid(), signal.SIGTERM)
                for _ in range(10000):  # many chances for the handler to run
                    pass
                steps.append("end of block")
        assert steps == ["end of block"] and info.value.signum == signal.SIGTERM and info.value.status == 143

    # the atomic writer: the interrupt lands while write() runs; the temporary file goes, the
    # target stays as it was
    target = tmp_path / "kept.bin"
    target.write_bytes(b"old")

    def write(tmp):
        with open(tmp, "wb") as fh:
            fh.write(b"partial")
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(20)

    with _signals.running():
        with pytest.raises(_signals.Interrupted):
            _atomic.atomic_write(target, write)
    assert target.read_bytes() == b"old" and os.listdir(tmp_path) == ["kept.bin"]


def test_an_interrupted_ocp_import_is_an_interrupt_not_a_missing_package(monkeypatch):
    """pybind11 reports an extension interrupted while it initialises as ``ImportError:
    initialization failed`` caused by the KeyboardInterrupt; that is no missing package."""
    import importlib.abc

    from splinekit.errors import MissingDependencyError
    from splinekit.interop import occ

    class Interrupted(importlib.abc.MetaPathFinder, importlib.abc.Loader):
        def __init__(self, cause):
            self.cause = cause

        def find_spec(self, name, path=None, target=None):
            import importlib.util

            return importlib.util.spec_from_loader(name, self) if name == "OCP" else None

        def create_module(self, spec):
            return None

        def exec_module(self, module):
            raise ImportError("initialization failed") from self.cause

    for name in [m for m in sys.modules if m == "OCP" or m.startswith("OCP.")]:
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setattr(occ, "_MODULES", {})
    monkeypatch.setattr(sys, "meta_path", [Interrupted(KeyboardInterrupt())] + sys.meta_path)
    with pytest.raises(KeyboardInterrupt):
        occ.require_ocp()
    sys.meta_path[0].cause = RuntimeError("a broken build of OCP")  # a real failure stays one
    with pytest.raises(MissingDependencyError, match="OCP"):
        occ.require_ocp()
