"""``splinekit neural``: train a neural implicit on a model (``fit``) and mesh a trained one (``mesh``).

``splinekit neural fit MODEL -o model.nsdf [--steps N] [--set k=v] [--kind sdf|occupancy]`` builds
the model, trains a network on it with a progress bar showing the loss, and writes one ``.nsdf``
file. ``splinekit neural mesh model.nsdf -o out.stl [--cells N | --edge-length E]`` meshes the
zero set of a trained model (marching tetrahedra) and writes it in the mesh format of the suffix.

:mod:`splinekit.neural` needs the optional extra (JAX); it is loaded through ``splinekit.neural``
when a ``neural`` command runs, so the other commands never import JAX.
"""

from __future__ import annotations

import os
import time

import exporters
import splinekit

from .._atomic import checked_path
from .._progress import progress
from ..errors import FileFormatError, ParameterError
from ..mesh.components import genus
from .console import Console, count, size_text
from .registry import build_model, registry

MESH_SUFFIXES = (".stl", ".obj", ".ply", ".3mf", ".glb")
MODEL_SUFFIX = ".nsdf"


def add_parser(sub, common) -> None:
    """The ``neural`` command and its ``fit`` / ``mesh`` subcommands."""
    n = sub.add_parser("neural", parents=[common], help="train a neural implicit on a model, or mesh a trained one")
    actions = n.add_subparsers(dest="action", metavar="ACTION")  # parser class: that of n (one-line errors)
    actions.required = True
    f = actions.add_parser("fit", parents=[common], help="train a neural SDF (or occupancy) on a model")
    f.add_argument("model", nargs="?", help="model name (default: the registry's default model)")
    f.add_argument("--set", action="append", metavar="NAME=VALUE", default=[], help="a model parameter (repeatable)")
    f.add_argument("-o", "--output", metavar="FILE", required=True, help=f"model file to write ({MODEL_SUFFIX})")
    f.add_argument("--steps", default="2000", metavar="N", help="optimizer steps (default: %(default)s)")
    f.add_argument("--seed", default="0", metavar="S", help="random seed (default: %(default)s)")
    f.add_argument("--kind", choices=("sdf", "occupancy"), default="sdf", help="what the network learns (default: %(default)s)")
    m = actions.add_parser("mesh", parents=[common], help="mesh the zero set of a trained model")
    m.add_argument("file", help=f"a {MODEL_SUFFIX} file written by 'splinekit neural fit'")
    m.add_argument("-o", "--output", metavar="MESH", required=True, help=f"mesh to write ({', '.join(MESH_SUFFIXES)})")
    m.add_argument("--cells", default="128", metavar="N", help="grid cells across the training cube (default: %(default)s)")
    m.add_argument("--edge-length", metavar="E", help="grid spacing in model units (overrides --cells)")
    m.add_argument("--shape", default="0", metavar="I", help="which shape of a family file (default: %(default)s)")


def _number(text, name: str, kind=int, minimum=None):
    """A command-line number: ``kind(text)``, finite and at least ``minimum``; ParameterError else."""
    try:
        value = kind(str(text).strip())
    except ValueError:
        value = None
    if value is None or value != value or value in (float("inf"), float("-inf")) or (minimum is not None and value < minimum):
        what = "an integer" if kind is int else "a number"
        bound = "" if minimum is None else f" >= {minimum}"
        raise ParameterError(f"{name} must be {what}{bound}, got {text!r}")
    return value


def _output(path, suffixes, what) -> str:
    suffix = os.path.splitext(str(path))[1].lower()
    if suffix not in suffixes:
        raise FileFormatError(f"cannot write {path!r}: a {what} file must end in {', '.join(suffixes)}, got {suffix or 'no suffix'!r}")
    return checked_path(path)


def cmd_neural(args, console: Console) -> int:
    return {"fit": _fit, "mesh": _mesh}[args.action](args, console)


def _fit(args, console: Console) -> int:
    steps = _number(args.steps, "--steps", minimum=1)
    seed = _number(args.seed, "--seed", minimum=0)
    out = _output(args.output, (MODEL_SUFFIX,), "neural model")
    neural = splinekit.neural  # loads JAX (or names the install command)
    reg = registry()
    name = args.model or reg.DEFAULT_MODEL
    model = build_model(reg, name, args.set, console)
    cls = neural.NeuralOccupancy if args.kind == "occupancy" else neural.NeuralSDF
    t0 = time.perf_counter()
    with progress(steps, f"training {name}") as bar:
        def report(step, total, loss):
            bar.advance(step - bar.done, label=f"training {name}, loss {loss:.4g}")

        trained = cls.fit(model, steps=steps, seed=seed, callback=report)
    seconds = time.perf_counter() - t0
    trained.save(out)
    a = trained.architecture
    console.out(f"trained a neural {args.kind} of '{name}' ({a.encoding} {a.depth}x{a.width}, "
                f"{trained.parameter_count:,} parameters, {size_text(trained.nbytes)}) in {steps} steps, "
                f"{seconds:.1f} s; final loss {trained.info['loss']:.4g}")
    console.out(f"wrote {out} ({size_text(os.path.getsize(out))})")
    return 0


def _mesh(args, console: Console) -> int:
    out = _output(args.output, MESH_SUFFIXES, "mesh")
    if not os.path.isfile(args.file):
        raise FileFormatError(f"{args.file!r} does not exist or is not a file")
    loaded = splinekit.neural.load(args.file)
    if isinstance(loaded, splinekit.neural.NeuralSDFFamily):
        loaded = loaded.shape(_number(args.shape, "--shape"))
    if args.edge_length is not None:
        edge = _number(args.edge_length, "--edge-length", float, minimum=0.0)
        if not edge > 0:
            raise ParameterError(f"--edge-length must be > 0, got {args.edge_length!r}")
    else:
        cells = _number(args.cells, "--cells", minimum=8)
        edge = 2.0 * loaded.normalization.scale / cells
    t0 = time.perf_counter()
    mesh = loaded.to_mesh(edge)
    seconds = time.perf_counter() - t0
    if mesh.n_faces == 0:
        raise ParameterError(f"the model in {args.file!r} has no surface (no zero crossing on the grid)")
    exporters.export_mesh(out, mesh)
    g = genus(mesh)
    console.out(f"meshed {args.file} at edge length {edge:.4g} in {seconds:.1f} s: {count(mesh.n_faces, 'triangle')}, "
                f"genus {g:g}, volume {mesh.volume:.6g}, deviation {mesh.deviation:.3g}")
    console.out(f"wrote {out} ({size_text(os.path.getsize(out))})")
    return 0
