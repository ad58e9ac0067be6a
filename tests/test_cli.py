"""The installed ``splinekit`` command, run in a subprocess.

Most tests use a small fake model registry (written to a temporary folder and
selected with ``SPLINEKIT_MODELS``) whose geometry has closed forms: a NURBS
sphere of radius r (volume 4/3 pi r^3, area 4 pi r^2), a box given only as a
mesh, a model that sleeps (for the interrupt test) and one that fails with an
unexpected exception. The real ``models`` registry is exercised at the end
when it is complete.
"""

from __future__ import annotations

import io
import math
import os
import re
import shutil
import signal
import subprocess
import sys
import textwrap
import time
import warnings

import numpy as np
import pytest

import exporters
from splinekit import _progress

FAKE_REGISTRY = textwrap.dedent(
    '''
    """A tiny model registry for the command-line tests."""
    import math, os, time, types
    from dataclasses import dataclass, field

    import splinekit as sk
    from splinekit.errors import ParameterError
    from splinekit.mesh import primitives


    @dataclass(frozen=True)
    class Parameter:
        name: str
        default: float
        unit: str
        minimum: float
        maximum: float
        doc: str
        kind: type = float

        def parse(self, text):
            try:
                value = self.kind(text)
            except ValueError:
                raise ParameterError(f"parameter '{self.name}' = {text!r}: expected a number") from None
            return self.check(value)

        def check(self, value):
            if not (self.minimum <= value <= self.maximum):
                raise ParameterError(f"parameter '{self.name}' = {value}: expected [{self.minimum}, {self.maximum}]")
            return value


    @dataclass
    class Model:
        name: str
        params: dict
        bodies: list = field(default_factory=list)
        body_names: list = field(default_factory=list)
        mesh: object = None
        closed: bool = False
        checks: dict = field(default_factory=dict)


    def _module(name, doc, params, build):
        m = types.ModuleType(name, doc)
        m.PARAMETERS = params
        m.build = build
        return m


    def _values(params, given):
        known = {p.name: p for p in params}
        return {n: p.check(given.get(n, p.default)) for n, p in known.items()}


    BALL = (Parameter("radius", 10.0, "mm", 0.5, 100.0, "sphere radius"),)


    def _ball(name, given, volume_factor=1.0):
        v = _values(BALL, given)
        r = v["radius"]
        profile = sk.arc([0, 0, 0], [0, -1, 0], r, -math.pi / 2, math.pi / 2, x_axis=[1, 0, 0])
        sphere = sk.revolve(profile, [0, 0, 0], [0, 0, 1])
        # closed forms, to 1e-9 relative: the references (OCC's GProp or scipy's cubature) reach 1e-10
        volume, area = 4 / 3 * math.pi * r**3, 4 * math.pi * r**2
        checks = {"volume": (volume_factor * volume, 1e-9 * volume), "area": (area, 1e-9 * area), "faces": (1, 0)}
        return Model(name, v, [[sphere]], [name], None, True, checks)


    CUBE = (Parameter("size", 2.0, "mm", 0.1, 50.0, "edge length"),
            Parameter("count", 1, "", 1, 3, "unused integer", int))


    def build_cube(**given):
        v = _values(CUBE, given)
        return Model("cube", v, [], [], primitives.box(v["size"]), True, {"volume": (v["size"] ** 3, 1e-9)})


    def build_slow(**given):
        with open(os.environ["SPLINEKIT_TEST_MARKER"], "w") as fh:
            fh.write("building")
        time.sleep(60)
        return _ball("slow", {})


    def build_broken(**given):
        raise RuntimeError("a bug in the model")


    MODELS = {
        "ball": _module("ball", "A NURBS sphere (one revolved patch). Units: mm.", BALL, lambda **g: _ball("ball", g)),
        "wrongball": _module("wrongball", "A sphere whose volume check is wrong.", BALL,
                             lambda **g: _ball("wrongball", g, 1.01)),
        "cube": _module("cube", "A box as a quad mesh only. Units: mm.", CUBE, build_cube),
        "slow": _module("slow", "Sleeps, then a ball.", (), build_slow),
        "broken": _module("broken", "Raises an unexpected error.", (), build_broken),
    }
    DEFAULT_MODEL = "ball"


    def get_model(name):
        if name not in MODELS:
            raise ParameterError(f"unknown model {name!r}; available: {', '.join(MODELS)}")
        return MODELS[name]


    def build_model(name, **params):
        return get_model(name).build(**params)
    '''
)


def _command() -> list:
    exe = shutil.which("splinekit")
    return [exe] if exe else [sys.executable, "-m", "splinekit.cli"]


@pytest.fixture(scope="module")
def fake_env(tmp_path_factory):
    folder = tmp_path_factory.mktemp("registry")
    (folder / "splinekit_fake_models.py").write_text(FAKE_REGISTRY)
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(folder)] + [p for p in [env.get("PYTHONPATH")] if p])
    env["SPLINEKIT_MODELS"] = "splinekit_fake_models"
    env["SPLINEKIT_TEST_MARKER"] = str(folder / "marker")
    return env


def run(args, env=None, cwd=None, timeout=120):
    return subprocess.run(_command() + [str(a) for a in args], capture_output=True, text=True, env=env, cwd=cwd,
                          timeout=timeout)


def assert_one_line_error(result, *fragments, status=None):
    assert result.returncode != 0 if status is None else result.returncode == status, result
    assert "Traceback" not in result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("splinekit: error: ")
    for fragment in fragments:
        assert fragment in lines[0], lines[0]


def number_after(text: str, label: str) -> float:
    match = re.search(rf"{label}\s+([-+0-9.eE]+)", text)
    assert match, f"no {label!r} in:\n{text}"
    return float(match.group(1))


# -- the basics -------------------------------------------------------------------------------

def test_help_lists_every_subcommand():
    result = run(["--help"])
    assert result.returncode == 0
    for name in ("list", "build", "info", "render", "check", "demo", "--quiet", "--verbose"):
        assert name in result.stdout


def test_python_dash_m_runs_the_same_command():
    result = subprocess.run([sys.executable, "-m", "splinekit.cli", "build", "--help"], capture_output=True, text=True)
    assert result.returncode == 0 and "--tolerance" in result.stdout and "--format" in result.stdout


def test_list_shows_models_parameters_defaults_units_and_ranges(fake_env):
    result = run(["list"], fake_env)
    assert result.returncode == 0, result.stderr
    out = result.stdout
    assert "ball (default)" in out and "cube" in out and "A NURBS sphere" in out
    ball = out[out.index("ball (default)"):out.index("wrongball")]
    row = next(line for line in ball.splitlines() if line.strip().startswith("radius"))
    assert row.split()[:5] == ["radius", "10", "mm", "0.5", ".."] and "100" in row and "sphere radius" in row
    cube = out[out.index("cube:"):]
    assert re.search(r"count\s+1\s+-\s+1 \.\. 3\s+int", cube)


# -- build + info -----------------------------------------------------------------------------

def test_build_default_model_writes_step_and_stl_and_info_reads_them(fake_env, tmp_path):
    r = 10.0
    result = run(["build", "-o", tmp_path], fake_env)
    assert result.returncode == 0, result.stderr
    assert sorted(os.listdir(tmp_path)) == ["ball.step", "ball.stl"]
    out = result.stdout
    for name in ("ball.step", "ball.stl"):
        size = os.path.getsize(tmp_path / name)
        assert re.search(rf"wrote .*{re.escape(name)}\s+[0-9.]+ (B|kB|MB)", out)
        assert size > 1000
    assert "1 exact face" in out and "triangles" in out and "radius=10" in out
    assert number_after(out, "volume") == pytest.approx(4 / 3 * math.pi * r**3, rel=1e-6)
    assert re.search(r"total [0-9.]+ s", out)

    step = run(["info", tmp_path / "ball.step"], fake_env)
    assert step.returncode == 0, step.stderr
    assert "1 solids" in step.stdout and "1 faces" in step.stdout
    assert "BSplineSurface, degree 2 x 2, rational" in step.stdout
    assert number_after(step.stdout, "volume") == pytest.approx(4 / 3 * math.pi * r**3, rel=1e-6)
    assert number_after(step.stdout, "area") == pytest.approx(4 * math.pi * r**2, rel=1e-6)
    box = re.search(r"bounding box \[([^\]]*)\] \.\. \[([^\]]*)\]", step.stdout)
    lo, hi = (np.array(g.split(","), float) for g in box.groups())
    np.testing.assert_allclose(lo, -r, rtol=1e-6)
    np.testing.assert_allclose(hi, r, rtol=1e-6)



def test_info_on_a_built_mesh(fake_env, in_process, capsys, tmp_path):
    r = 10.0
    assert in_process(["build", "--format", "stl"]) == 0  # into the default folder, out/
    assert os.listdir(tmp_path) == ["out"] and os.listdir(tmp_path / "out") == ["ball.stl"]
    capsys.readouterr()
    assert in_process(["info", "out/ball.stl"]) == 0
    out = capsys.readouterr().out
    mesh = exporters.import_mesh(tmp_path / "out" / "ball.stl")  # the file itself, read independently
    assert f"{mesh.n_vertices} vertices, {mesh.n_faces} faces (triangles)" in out
    assert "closed yes" in out and "genus 0" in out and "Euler characteristic 2" in out
    # an inscribed polyhedron: a little less than the sphere
    volume = number_after(out, "volume")
    assert 0.98 * 4 / 3 * math.pi * r**3 < volume < 4 / 3 * math.pi * r**3
    assert volume == pytest.approx(float(mesh.volume), rel=1e-9)


def test_build_sets_parameters_writes_every_mesh_format(fake_env, tmp_path):
    out_dir = tmp_path / "new" / "folder"  # created on demand
    result = run(["build", "ball", "--set", "radius=2.5", "-o", out_dir, "--format", "stl,obj,3mf,glb,ply",
                  "--tolerance", "0.001"], fake_env)
    assert result.returncode == 0, result.stderr
    assert sorted(os.listdir(out_dir)) == sorted(f"ball.{f}" for f in ("stl", "obj", "3mf", "glb", "ply"))
    for f in ("stl", "obj", "3mf", "glb", "ply"):
        mesh = exporters.import_mesh(out_dir / f"ball.{f}")
        V = np.asarray(mesh.vertices)
        assert np.abs(np.linalg.norm(V, axis=1) - 2.5).max() < 1e-5  # vertices lie on the sphere
        assert mesh.is_closed


def test_a_looser_tolerance_gives_fewer_triangles(in_process, tmp_path):
    counts = []
    for tol in ("0.001", "0.01"):
        assert in_process(["-q", "build", "--set", "radius=2.5", "--format", "stl", "--tolerance", tol, "-o", tol]) == 0
        counts.append(exporters.import_mesh(tmp_path / tol / "ball.stl").n_faces)
    assert counts[1] < counts[0]


def test_mesh_only_model_skips_step_by_default_and_refuses_it_on_request(fake_env, tmp_path):
    result = run(["build", "cube", "--set", "size=3", "-o", tmp_path], fake_env)
    assert result.returncode == 0, result.stderr
    assert os.listdir(tmp_path) == ["cube.stl"]
    assert "no STEP file written" in result.stdout
    assert number_after(result.stdout, "volume") == pytest.approx(27.0)
    info = run(["info", tmp_path / "cube.stl"], fake_env)
    assert "closed yes" in info.stdout and "12 faces" in info.stdout and "genus 0" in info.stdout
    assert_one_line_error(run(["build", "cube", "--format", "step", "-o", tmp_path], fake_env), "only as a mesh", status=1)


def test_quiet_prints_nothing_and_no_progress_bar_without_a_terminal(fake_env, tmp_path):
    result = run(["--quiet", "build", "-o", tmp_path, "--format", "stl"], fake_env)
    assert result.returncode == 0
    assert result.stdout == "" and result.stderr == ""
    assert os.listdir(tmp_path) == ["ball.stl"]
    loud = run(["build", "-v", "-o", tmp_path, "--format", "stl"], fake_env)
    assert "built model 'ball'" in loud.stdout and loud.stderr == ""  # no bar: stderr is a pipe


# -- check ------------------------------------------------------------------------------------

def test_check_passes_for_a_sound_model(fake_env):
    result = run(["check", "ball", "--set", "radius=3"], fake_env)
    assert result.returncode == 0, result.stdout + result.stderr
    rows = {line.split("  ")[0].strip(): line for line in result.stdout.splitlines()}
    for name in ("volume", "area", "faces", "body 0 is a closed solid", "tessellation is closed"):
        assert "PASS" in rows[name], result.stdout
    assert any(k.startswith("point deviation vs OCC") and "PASS" in v for k, v in rows.items())
    assert "FAIL" not in result.stdout


def test_check_fails_with_status_1_when_a_reference_is_wrong(in_process, capsys):
    assert in_process(["check", "wrongball"]) == 1
    out = capsys.readouterr().out
    volume = next(line for line in out.splitlines() if line.startswith("volume"))
    assert "FAIL" in volume
    assert "1 failed" in out


def test_check_of_a_mesh_model(fake_env):
    result = run(["check", "cube"], fake_env)
    assert result.returncode == 0, result.stdout
    assert re.search(r"mesh is closed\s+yes\s+yes\s+PASS", result.stdout)


# -- errors -----------------------------------------------------------------------------------

@pytest.mark.parametrize(
    "args, fragments",
    [
        (["build", "nosuchmodel"], ["unknown model", "nosuchmodel"]),
        (["build", "--set", "radius=1000"], ["radius", "1000"]),
        (["build", "--format", "step,dwg"], ["dwg", "stl"]),
        (["info", "README"], ["README"]),
    ],
)
def test_bad_input_is_a_one_line_error(fake_env, tmp_path, args, fragments):
    (tmp_path / "README").write_text("not geometry")
    result = run(args, fake_env, cwd=tmp_path)
    assert_one_line_error(result, *fragments, status=1)
    assert [p for p in os.listdir(tmp_path) if p != "README"] == []  # nothing written


@pytest.fixture
def in_process(fake_env, monkeypatch, tmp_path):
    """``main(argv)`` run in this process (same code as the command, without a
    process start per case) with the fake registry, in an empty folder."""
    from splinekit.cli import main

    folder = fake_env["PYTHONPATH"].split(os.pathsep)[0]
    monkeypatch.syspath_prepend(folder)
    monkeypatch.setenv("SPLINEKIT_MODELS", fake_env["SPLINEKIT_MODELS"])
    monkeypatch.chdir(tmp_path)
    return main


@pytest.mark.parametrize(
    "args, fragments",
    [
        (["build", "--set", "radius=abc"], ["radius", "abc"]),
        (["build", "--set", "colour=3"], ["no parameter 'colour'", "radius"]),
        (["build", "--set", "radius"], ["name=value"]),
        (["build", "--format", ","], ["--format"]),
        (["build", "--tolerance", "-1"], ["--tolerance"]),
        (["build", "--tolerance", "nan"], ["--tolerance"]),
        (["render", "ball", "--size", "10x10"], ["--size"]),
        (["render", "ball", "--size", "wide"], ["--size"]),
        (["render", "ball", "--view", "a,b"], ["--view"]),
        (["render", "no-such-file.stl"], ["no-such-file.stl"]),
        (["render", "no-such-file.stl", "--set", "radius=2"], ["--set"]),
        (["info", "no-such-file.stl"], ["no-such-file.stl"]),
        (["check", "nosuchmodel"], ["unknown model"]),
        (["list"], ["registry"]),
    ],
)
def test_bad_input_is_a_one_line_error_in_process(in_process, capsys, monkeypatch, tmp_path, args, fragments):
    if args == ["list"]:
        monkeypatch.setenv("SPLINEKIT_MODELS", "splinekit_no_such_registry")
    status = in_process(args)
    err = capsys.readouterr().err
    assert status == 1
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1 and err.startswith("splinekit: error: ")
    for fragment in fragments:
        assert fragment in err
    assert os.listdir(tmp_path) == []


def test_malformed_command_line_is_one_line_with_status_2(fake_env):
    assert_one_line_error(run(["render", "ball", "--color", "rainbow"], fake_env), "rainbow", status=2)
    assert_one_line_error(run(["frobnicate"], fake_env), "frobnicate", status=2)


def test_unwritable_output_is_a_one_line_error(fake_env, tmp_path):
    blocker = tmp_path / "a-file"
    blocker.write_text("x")
    assert_one_line_error(run(["build", "-o", blocker], fake_env), "a-file", status=1)
    assert_one_line_error(run(["build", "-o", blocker / "below"], fake_env), status=1)
    assert_one_line_error(run(["render", "ball", "-o", blocker / "pic.png"], fake_env), status=1)
    assert sorted(os.listdir(tmp_path)) == ["a-file"]


def test_corrupt_files_are_a_one_line_error(in_process, capsys, tmp_path):
    (tmp_path / "bad.stl").write_bytes(b"solid x\n facet normal 0 0 1\n outer loop\n vertex 0 0\n")
    (tmp_path / "bad.step").write_text("ISO-10303-21;\nthis is not a step file\n")
    for name in ("bad.stl", "bad.step"):
        for command in (["info", name], ["render", name, "-o", "x.png"]):
            assert in_process(command) == 1
            err = capsys.readouterr().err
            assert err.startswith("splinekit: error: ") and len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert sorted(os.listdir(tmp_path)) == ["bad.step", "bad.stl"]


def test_unexpected_exception_is_one_line_with_a_hint_and_verbose_shows_the_traceback(fake_env):
    result = run(["build", "broken"], fake_env)
    assert_one_line_error(result, "RuntimeError", "a bug in the model", "--verbose", status=1)
    verbose = run(["--verbose", "build", "broken"], fake_env)
    assert verbose.returncode == 1
    assert "Traceback" in verbose.stderr and verbose.stderr.strip().splitlines()[-1].startswith("splinekit: error:")


def test_interrupted_build_exits_130_and_leaves_no_files(fake_env, tmp_path):
    marker = fake_env["SPLINEKIT_TEST_MARKER"]
    if os.path.exists(marker):
        os.unlink(marker)
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    proc = subprocess.Popen(_command() + ["build", "slow", "-o", str(out_dir)], env=fake_env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 60
        while not os.path.exists(marker):  # the model's build has started
            assert proc.poll() is None and time.monotonic() < deadline
            time.sleep(0.05)
        proc.send_signal(signal.SIGINT)
        stdout, stderr = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130
    assert "interrupted" in stderr and "Traceback" not in stderr
    assert os.listdir(out_dir) == []


# -- progress bar -----------------------------------------------------------------------------

class _Terminal(io.StringIO):
    def isatty(self):
        return True


def test_progress_bar_draws_only_on_a_terminal_and_clears_its_line():
    tty, pipe = _Terminal(), io.StringIO()
    with _progress.progress(4, "work", stream=tty) as bar, _progress.progress(4, "work", stream=pipe) as quiet:
        for _ in range(4):
            bar.advance()
            quiet.advance()
        assert bar.line().startswith("work [") and "4/4" in bar.line()
    assert pipe.getvalue() == ""
    text = tty.getvalue()
    assert "work [" in text and "0/4" in text and "4/4" in text and text.endswith("\r\x1b[2K")
    _progress.set_enabled(False)
    try:
        silent = _Terminal()
        with _progress.progress(2, "x", stream=silent) as bar:
            bar.advance(2)
        assert silent.getvalue() == ""
    finally:
        _progress.set_enabled(True)


def test_only_the_outermost_shown_bar_draws():
    outer_tty, inner_tty = _Terminal(), _Terminal()
    with _progress.progress(2, "outer", stream=outer_tty) as outer:
        with _progress.progress(3, "inner", stream=inner_tty) as inner:
            inner.advance(3)
        outer.advance(2)
    assert "outer [" in outer_tty.getvalue() and inner_tty.getvalue() == ""
    hidden_tty = _Terminal()
    with _progress.progress(2, "hidden", stream=hidden_tty, show=False):
        with _progress.progress(1, "inner", stream=inner_tty) as inner:
            inner.advance()
    assert hidden_tty.getvalue() == "" and "inner [" in inner_tty.getvalue()


@pytest.mark.skipif(not hasattr(os, "openpty"), reason="needs a pseudo-terminal")
def test_build_draws_a_progress_bar_on_a_terminal_stderr_only(fake_env, tmp_path):
    master, slave = os.openpty()
    try:
        result = subprocess.run(_command() + ["build", "-o", str(tmp_path), "--format", "stl"], env=fake_env,
                                stdout=subprocess.PIPE, stderr=slave, text=True, timeout=120)
        os.close(slave)
        slave = None
        chunks = []
        while True:
            try:
                data = os.read(master, 4096)
            except OSError:  # EIO once the writer side is closed and drained
                break
            if not data:
                break
            chunks.append(data)
    finally:
        if slave is not None:
            os.close(slave)
        os.close(master)
    err = b"".join(chunks).decode()
    assert result.returncode == 0
    assert "writing [" in err and "\r" in err  # drawn in place on the terminal
    assert "[" not in result.stdout.replace("[-", "").split("wrote")[0]  # stdout carries no bar
    assert "Traceback" not in err


def test_build_all_and_check_all(in_process, capsys, monkeypatch, tmp_path):
    import splinekit_fake_models as registry

    everything = dict(registry.MODELS)
    monkeypatch.setattr(registry, "MODELS", {k: everything[k] for k in ("ball", "cube")})
    assert in_process(["build", "--all", "--format", "stl", "-o", "out"]) == 0
    assert sorted(os.listdir(tmp_path / "out")) == ["ball.stl", "cube.stl"]
    assert in_process(["check", "--all"]) == 0
    assert "2 of 2 models pass" in capsys.readouterr().out
    monkeypatch.setattr(registry, "MODELS", {k: everything[k] for k in ("ball", "wrongball", "cube")})
    assert in_process(["check", "--all"]) == 1
    assert "2 of 3 models pass; failed: wrongball" in capsys.readouterr().out
    assert in_process(["build", "--all", "ball"]) == 1
    assert "--all" in capsys.readouterr().err


# -- the real registry ------------------------------------------------------------------------

def _real_registry():
    """The project's models package: it must import and export the registry (a missing one is a
    failure, not a reason to skip)."""
    import models

    missing = [a for a in ("MODELS", "DEFAULT_MODEL", "get_model", "build_model") if not hasattr(models, a)]
    assert not missing, f"models does not export {missing}"
    assert models.DEFAULT_MODEL in models.MODELS
    return models


def test_real_registry_list_default_build_info_and_check(tmp_path, capsys, monkeypatch):
    models = _real_registry()
    monkeypatch.delenv("SPLINEKIT_MODELS", raising=False)
    env = {k: v for k, v in os.environ.items() if k != "SPLINEKIT_MODELS"}
    from splinekit.cli import main

    assert main(["list"]) == 0
    listing = capsys.readouterr().out
    for name, module in models.MODELS.items():
        assert name in listing
        for p in module.PARAMETERS:
            assert p.name in listing
    result = run(["build"], env, cwd=tmp_path)  # the README's first command: default model, into out/
    assert result.returncode == 0, result.stderr
    default = models.DEFAULT_MODEL
    model = models.build_model(default)
    expected = {f"{default}.step", f"{default}.stl"} if model.bodies else {f"{default}.stl"}
    assert os.listdir(tmp_path) == ["out"] and set(os.listdir(tmp_path / "out")) == expected
    if model.bodies:
        faces = sum(len(b) for b in model.bodies)
        info = run(["info", tmp_path / "out" / f"{default}.step"], env)
        assert info.returncode == 0 and f"{faces} faces" in info.stdout
    check = run(["check"], env)
    assert check.returncode == 0, check.stdout + check.stderr


# -- version, python -m splinekit, closed pipes, extreme values --------------------------------

def test_version_and_python_dash_m_splinekit():
    import splinekit

    for command in (_command(), [sys.executable, "-m", "splinekit"]):
        result = subprocess.run(command + ["--version"], capture_output=True, text=True, timeout=120)
        assert result.returncode == 0 and result.stdout.strip() == f"splinekit {splinekit.__version__}"
    result = subprocess.run([sys.executable, "-m", "splinekit", "build", "--help"], capture_output=True, text=True,
                            timeout=120)
    assert result.returncode == 0 and "--tolerance" in result.stdout


def test_a_closed_stdout_ends_the_command_silently(fake_env):
    """``splinekit list | head -1``: the reader goes away; no 'Broken pipe' error, no traceback,
    status 141 as for a tool that SIGPIPE ended."""
    read, write = os.pipe()
    proc = subprocess.Popen(_command() + ["list"], stdout=write, stderr=subprocess.PIPE, env=fake_env, text=True)
    os.close(write)
    os.close(read)  # before the command prints anything
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 141 and err == ""


def test_a_closed_stdout_in_process(in_process, capsys, monkeypatch):
    class Closed(io.StringIO):
        def write(self, text):
            raise BrokenPipeError(32, "Broken pipe")

    monkeypatch.setattr(sys, "stdout", Closed())
    assert in_process(["list"]) == 141
    assert capsys.readouterr().err == ""


def test_coordinates_near_the_float_limits_are_reported_not_warned(in_process, capsys, tmp_path):
    (tmp_path / "huge.obj").write_text("v 1e308 1e308 1e308\nv -1e308 -1e308 -1e308\nv 1e308 -1e308 0\n"
                                       "v 0 0 1e308\nf 1 2 3\nf 1 3 4\nf 1 4 2\nf 2 4 3\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        status = in_process(["info", "huge.obj"])
    out, err = capsys.readouterr()
    assert status == 0 and err == "", err
    assert "beyond the float range" in out and "inf" not in out.replace("info", "")


def test_a_runtime_warning_in_our_code_is_one_line(in_process, capsys, monkeypatch):
    from splinekit import cli

    scope = {"__name__": "splinekit.fake_module"}  # the warning is attributed to a splinekit module
    exec("import numpy as np\ndef overflow(args, console):\n    return int(np.ones(1)[0] * 1e308 * 10 > 0)\n", scope)
    monkeypatch.setitem(cli.COMMANDS, "list", scope["overflow"])
    assert in_process(["list"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("splinekit: error: numerical failure (overflow") and len(err.splitlines()) == 1


def test_control_characters_in_arguments_stay_on_one_line(in_process, capsys):
    """argparse echoes unknown arguments as they are; the error line escapes them."""
    with pytest.raises(SystemExit):
        in_process(["list", "--x\ny\x1b[2J\x1e\u2028"])
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and "\\n" in err and "\x1b" not in err and "\\u2028" in err
    assert in_process(["build", "--format", "st\nl\x1b[2J"]) == 1
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and "\x1b" not in err
