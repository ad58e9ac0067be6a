"""The ``splinekit`` command's entry point: the argument parser, the table of commands, and the
one place where errors, interrupts and a closed stdout become one line and an exit status."""

from __future__ import annotations

import argparse
import os
import signal
import traceback
import warnings

from .. import __version__, _signals
from .._progress import is_enabled, set_enabled
from ..errors import SplineKitError
from ..plot import COLOR_MODES, COLOR_SCALES
from .analyze import cmd_analyze
from .build import DEFAULT_FORMATS, DEFAULT_OUTPUT, FORMATS, cmd_build
from .check import cmd_check
from .compare import DEFAULT_MODEL as COMPARE_MODEL
from .compare import DEFAULT_OUTPUT as COMPARE_OUTPUT
from .compare import cmd_compare
from .console import Console, error_line, first_line, one_line
from .demo import DEFAULT_PICTURE, cmd_demo
from .info import cmd_info
from .listing import cmd_list
from .neural import add_parser as add_neural_parser
from .neural import cmd_neural
from .render import PICTURE_SUFFIXES, cmd_render
from .sweep import DEFAULT_OUTPUT as SWEEP_OUTPUT
from .sweep import cmd_sweep

COMMANDS = {"list": cmd_list, "build": cmd_build, "info": cmd_info, "render": cmd_render, "check": cmd_check, "demo": cmd_demo,
            "sweep": cmd_sweep, "analyze": cmd_analyze, "compare": cmd_compare, "neural": cmd_neural}
"""Command name -> ``function(args, console) -> exit status``."""


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors: ``splinekit: error: ...`` and exit status 2."""

    def error(self, message):
        self.exit(2, one_line(f"{self.prog.split()[0]}: error: {message} (see --help)") + "\n")


def build_parser() -> argparse.ArgumentParser:
    """The parser of the command line, subcommand by subcommand."""
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("-q", "--quiet", action="store_true", default=argparse.SUPPRESS,
                        help="print nothing but errors; no progress bars")
    common.add_argument("-v", "--verbose", action="store_true", default=argparse.SUPPRESS,
                        help="print more detail, and the traceback of an unexpected error")
    parser = _Parser(prog="splinekit", description="Spline and subdivision modeling toolkit.", parents=[common])
    parser.add_argument("--version", action="version", version=f"splinekit {__version__}")
    sub = parser.add_subparsers(dest="command", parser_class=_Parser, metavar="COMMAND")

    sub.add_parser("list", parents=[common], help="the models, their parameters, defaults, units and ranges")

    def model_options(p):
        p.add_argument("--set", action="append", metavar="NAME=VALUE", default=[],
                       help="a model parameter (repeatable); see 'splinekit list'")

    pictures = "/".join(s.lstrip(".") for s in PICTURE_SUFFIXES)
    b = sub.add_parser("build", parents=[common], help="build a model and export it (STEP, STL, 3MF, OBJ, GLB, PLY)")
    b.add_argument("model", nargs="?", help="model name (default: the registry's default model)")
    b.add_argument("--all", action="store_true", help="build every model (with its defaults)")
    model_options(b)
    b.add_argument("-o", "--output", metavar="DIR", help=f"output folder, created if missing (default: {DEFAULT_OUTPUT})")
    b.add_argument("--format", metavar="LIST", help=f"comma-separated formats among {','.join(FORMATS)} (default: {DEFAULT_FORMATS})")
    b.add_argument("--tolerance", metavar="T", help="chordal tolerance of mesh output in model units (default: 1e-3 of the model size)")

    i = sub.add_parser("info", parents=[common], help="what a STEP, IGES, BREP or mesh file holds")
    i.add_argument("file", help="a .step/.stp/.iges/.igs/.brep or .stl/.obj/.ply/.3mf/.glb file")

    r = sub.add_parser("render", parents=[common], help="a shaded picture of a model or a file, colored by curvature")
    r.add_argument("target", metavar="MODEL|FILE", help="a model name, or a STEP or mesh file")
    model_options(r)
    r.add_argument("-o", "--output", metavar="PICTURE",
                   help=f"picture to write, {pictures} by its suffix (default: {DEFAULT_OUTPUT}/NAME.png)")
    r.add_argument("--color", choices=COLOR_MODES, default="curvature",
                   help="curvature (RMS of the principal curvatures), gaussian, mean, normal or patch (default: %(default)s)")
    r.add_argument("--scale", choices=COLOR_SCALES, default="percentile",
                   help="color scale of the curvature modes (default: %(default)s)")
    r.add_argument("--size", default="1000x800", metavar="WxH", help="picture size in pixels (default: %(default)s)")
    r.add_argument("--view", default="28,-58", metavar="ELEV,AZIM", help="view angles in degrees (default: %(default)s)")

    c = sub.add_parser("check", parents=[common], help="cross-check a model against OpenCascade; exit 1 on a failure")
    c.add_argument("model", nargs="?", help="model name (default: the registry's default model)")
    c.add_argument("--all", action="store_true", help="check every model (with its defaults)")
    model_options(c)

    s = sub.add_parser("sweep", parents=[common], help="build, measure and export every variant of a parameter grid on Dask")
    s.add_argument("model", help="model name (see 'splinekit list')")
    s.add_argument("--grid", action="append", metavar="NAME=A:B:N|NAME=V1,V2", default=[],
                   help="a swept parameter: N values from A to B, or a list (repeatable; full factorial)")
    model_options(s)
    s.add_argument("-o", "--output", metavar="DIR", help=f"results folder, created if missing (default: {SWEEP_OUTPUT})")
    s.add_argument("--format", metavar="LIST", help=f"files to write per variant, among {','.join(FORMATS)} (default: none)")
    s.add_argument("--files", metavar="DIR",
                   help="folder the workers write the files into: their own disk or a shared one (default: DIR/files)")
    s.add_argument("--measure", metavar="LIST",
                   help="measures among area,volume,centroid,bbox,faces,triangles,valid,checks (default: all)")
    s.add_argument("--plot", metavar="MEASURE[:X[,Y]]",
                   help="PNG of a measure against one or two parameters, or none (default: the first measure)")
    s.add_argument("--scheduler", metavar="ADDRESS",
                   help="a running Dask scheduler (tcp://host:8786 or a scheduler file); default: a local cluster")
    s.add_argument("--workers", type=int, metavar="N", help="workers of the local cluster (default: one per core)")
    s.add_argument("--timeout", type=float, default=5.0, metavar="S", help="seconds to reach --scheduler (default: %(default)s)")
    s.add_argument("--max-variants", type=int, default=100_000, metavar="N", help="budget of variants (default: %(default)s)")
    s.add_argument("--force", action="store_true", help="rebuild variants already in the results folder")
    a = sub.add_parser("analyze", parents=[common],
                       help="surface quality: zebra, isophotes, curvature, draft, continuity, deviation from a scan")
    a.add_argument("target", metavar="MODEL|FILE", help="a model name, or a STEP or mesh file")
    model_options(a)
    a.add_argument("-o", "--output", metavar="DIR", help=f"folder of the pictures, created if missing (default: {DEFAULT_OUTPUT})")
    a.add_argument("--zebra", action="store_true", help="zebra stripes (reflected parallel light bands)")
    a.add_argument("--stripes", type=int, default=12, metavar="N", help="zebra stripe pairs all around (default: %(default)s)")
    a.add_argument("--isophotes", action="store_true", help="isophotes: lines of constant angle between normal and light")
    a.add_argument("--light", default="0,0,1", metavar="X,Y,Z", help="light direction of --isophotes (default: %(default)s)")
    a.add_argument("--step", type=float, default=10.0, metavar="DEG", help="degrees between isophotes (default: %(default)s)")
    a.add_argument("--curvature", choices=("gaussian", "mean", "max", "min"), help="a curvature map")
    a.add_argument("--scale", choices=COLOR_SCALES, default="percentile", help="colour scale of --curvature (default: %(default)s)")
    a.add_argument("--draft", metavar="X,Y,Z", help="draft-angle map for this pull direction, under-cuts marked")
    a.add_argument("--min-draft", default="0", metavar="DEG", help="least draft a face needs, in degrees (default: 0)")
    a.add_argument("--continuity", action="store_true", help="G0/G1/G2 of every shared edge (printed)")
    a.add_argument("--combs", action="store_true", help="curvature combs of the part's edge curves (one scale for all)")
    a.add_argument("--deviation", metavar="SCAN", help="signed deviation of a scan (.stl/.ply/.obj/... or .xyz points) from the part")
    a.add_argument("--tolerance", metavar="T", help="chordal tolerance of the sampling in model units (default: 1e-3 of the model size)")
    a.add_argument("--size", default="1000x800", metavar="WxH", help="picture size in pixels (default: %(default)s)")
    a.add_argument("--view", default="28,-58", metavar="ELEV,AZIM", help="view angles in degrees (default: %(default)s)")
    m = sub.add_parser("compare", parents=[common],
                       help="one shape in every representation: memory, queries, accuracy, operations")
    m.add_argument("model", nargs="?", help=f"model name, or sphere / torus (default: {COMPARE_MODEL})")
    model_options(m)
    m.add_argument("-o", "--output", metavar="DIR", help=f"folder for compare.md, accuracy.png and pictures/ (default: {COMPARE_OUTPUT})")
    m.add_argument("--resolutions", action="append", metavar="NAME=V1,V2,...", default=[],
                   help="resolutions of one representation (repeatable), e.g. 'SDF grid=24,48,96'")
    m.add_argument("--only", metavar="LIST", help="comma-separated representations to run (default: all)")
    m.add_argument("--samples", type=int, default=2000, help="exact sample points of the accuracy measurement (default: %(default)s)")
    m.add_argument("--quick", action="store_true", help="two resolutions per representation (a fast smoke run)")
    m.add_argument("--exact-boolean", action="store_true", help="also run the exact OCC boolean of the patches (slow)")

    d = sub.add_parser("demo", parents=[common], help="build a NURBS surface, print what was computed and draw it")
    d.add_argument("-o", "--output", metavar="PICTURE", help=f"picture to write, {pictures} (default: {DEFAULT_PICTURE})")

    add_neural_parser(sub, common)
    return parser


def main(argv=None) -> int:
    """Run the command line with ``argv`` (default ``sys.argv[1:]``); returns the exit status.

    SIGINT / SIGTERM end the command with one line on stderr and status 130 / 143. A closed
    stdout ends it silently with status 141. In the ``splinekit`` process itself (the console
    script, ``python -m splinekit``) main does not return: the process ends with the status
    through :func:`splinekit._signals.finish`, after flushing its output, so that no moment is
    left in which a signal meets the interpreter's teardown (default handling, or an extension
    interrupted while it initialised).
    """
    with _signals.running() as own:
        try:
            status = _main(argv)
            signum = _signals.received()  # a signal whose exception a library swallowed still counts
        except KeyboardInterrupt as exc:
            signum = _signals.received() or getattr(exc, "signum", signal.SIGINT)
        except BrokenPipeError:  # the reader of stdout is gone: stop, and say nothing
            signum, status = None, 141
        except SystemExit as exc:  # --help, --version, a malformed command line
            if not own:
                raise
            signum, status = None, exc.code if isinstance(exc.code, int) else int(exc.code is not None)
            if isinstance(exc.code, str):
                error_line(exc.code)
        if signum is not None:
            status = _signals.STATUS.get(signum, 128 + signum)
            error_line(_signals.message(signum), after_echo=signum == signal.SIGINT)
    if own:
        _signals.finish(status)
    return status


def _main(argv) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    quiet, verbose = getattr(args, "quiet", False), getattr(args, "verbose", False)
    if args.command is None:
        parser.print_help()
        return 0
    bars = is_enabled()
    set_enabled(bars and not quiet)
    try:
        return _run(args, Console(quiet, verbose))
    finally:
        set_enabled(bars)  # main() may be called again in the same process


# A RuntimeWarning from numpy in our code means an overflow or an invalid operation on extreme
# input: the command stops with one line instead of printing the warning and an inf result.
_OUR_MODULES = r"(splinekit|exporters|models|numpy|__main__)(\.|$)"


def _run(args, console: Console) -> int:
    """Run the parsed command; errors become one line on stderr and an exit status."""
    verbose = console.verbose
    try:
        with warnings.catch_warnings():
            warnings.filterwarnings("error", category=RuntimeWarning, module=_OUR_MODULES)
            return COMMANDS[args.command](args, console)
    except BrokenPipeError:
        raise  # main() ends quietly
    except (SplineKitError, OSError) as exc:
        _traceback(verbose)
        error_line(f"splinekit: error: {first_line(exc)}")
        return 1
    except RuntimeWarning as exc:
        _traceback(verbose)
        error_line(f"splinekit: error: numerical failure ({first_line(exc)} at {_where(exc)}): "
                   "the input values are too extreme for double precision")
        return 1
    except Exception as exc:  # a bug: still one line, the traceback on request
        cause = exc
        while cause is not None:  # an interrupt wrapped by Python (RuntimeError from __set_name__, ...)
            if isinstance(cause, KeyboardInterrupt):
                raise cause from None
            cause = cause.__cause__ or cause.__context__
        _traceback(verbose)
        hint = "" if verbose else "; run with --verbose for the traceback"
        error_line(f"splinekit: error: unexpected {type(exc).__name__}: {first_line(exc)}{hint}")
        return 1


def _traceback(verbose: bool) -> None:
    if verbose:
        traceback.print_exc()


def _where(exc: BaseException) -> str:
    """``module.py:line`` where ``exc`` was raised."""
    tb = exc.__traceback__
    while tb is not None and tb.tb_next is not None:
        tb = tb.tb_next
    if tb is None:
        return "?"
    return f"{os.path.basename(tb.tb_frame.f_code.co_filename)}:{tb.tb_lineno}"
