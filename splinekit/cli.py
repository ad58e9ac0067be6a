"""The ``splinekit`` command line.

Subcommands::

    splinekit list                                   the models and their parameters
    splinekit build [MODEL] [--set k=v ...] [-o DIR] [--format step,stl,...] [--tolerance T]
    splinekit info FILE                              what a STEP, IGES, BREP or mesh file holds
    splinekit render MODEL|FILE -o picture.png [--color ...] [--size WxH]
    splinekit check MODEL                            cross-check a model against OpenCascade
    splinekit demo [-o picture.png]                  a NURBS surface, timed and drawn

``--quiet`` silences everything but errors, ``--verbose`` adds detail and
tracebacks. Errors are one line on stderr (``splinekit: error: ...``) with exit
status 1 (2 for a malformed command line). SIGINT and SIGTERM end a command with
one line and status 130 / 143, leaving no temporary file (see
:mod:`splinekit._signals`); a closed stdout (``splinekit list | head -1``) ends
it silently with status 141, as SIGPIPE ends other Unix tools.

The models come from the ``models`` package; the environment variable
``SPLINEKIT_MODELS`` names another module with the same registry interface
(``MODELS``, ``DEFAULT_MODEL``, ``get_model``, ``build_model``).
Everything heavy (OCP, exporters, matplotlib) is imported inside the commands.
"""

from __future__ import annotations

import argparse
import importlib
import os
import signal
import sys
import time
import warnings

import numpy as np

from . import __version__, _signals
from ._atomic import checked_path
from ._progress import is_enabled, progress, set_enabled
from .errors import (
    FileFormatError,
    MeshTopologyError,
    MissingDependencyError,
    ParameterError,
    SplineKitError,
)


def demo_surface():
    """A bicubic NURBS surface over 8 x 8 control points: a wavy roof with raised weights."""
    from . import NurbsSurface

    n = 8
    x, y = np.meshgrid(np.linspace(-1.0, 1.0, n), np.linspace(-1.0, 1.0, n), indexing="ij")
    z = 0.35 * np.sin(2.2 * x) * np.cos(1.7 * y) + 0.15 * (x**2 - y**2)
    weights = 1.0 + 1.5 * np.exp(-8 * (x**2 + y**2))
    return NurbsSurface.uniform(3, 3, np.stack([x, y, z], axis=-1), weights)


def _area(surface, per_span: int = 6) -> float:
    """Surface area by Gauss-Legendre quadrature on every knot span pair."""
    g, gw = np.polynomial.legendre.leggauss(per_span)
    bu, bv = surface.bezier_breakpoints()

    def nodes(b):
        mid, half = 0.5 * (b[1:] + b[:-1]), 0.5 * (b[1:] - b[:-1])
        return (mid[:, None] + half[:, None] * g).ravel(), (half[:, None] * gw).ravel()

    us, wu = nodes(bu)
    vs, wv = nodes(bv)
    d = surface.derivatives_grid(us, vs, 1)
    jac = np.linalg.norm(np.cross(d[1, 0], d[0, 1]), axis=-1)
    return float(wu @ jac @ wv)


def cmd_demo(args) -> int:
    from .plot import render_surface

    s = demo_surface()
    print(f"surface: {s!r}")
    (a, b), (c, d) = s.domain
    us, vs = np.linspace(a, b, 1000), np.linspace(c, d, 1000)
    t0 = time.perf_counter()
    grid = s.evaluate_grid(us, vs)
    t1 = time.perf_counter()
    print(f"evaluated a 1000 x 1000 grid in {1e3 * (t1 - t0):.1f} ms; bounding box "
          f"{np.round(grid.reshape(-1, 3).min(0), 4).tolist()} .. {np.round(grid.reshape(-1, 3).max(0), 4).tolist()}")
    print(f"area (Gauss-Legendre per span): {_area(s):.10f}")
    patches = s.to_bezier()
    print(f"Bezier decomposition: {len(patches)} x {len(patches[0])} bicubic rational patches")
    rng = np.random.default_rng(0)
    u, v = rng.uniform(a, b, 10000), rng.uniform(c, d, 10000)
    ref = s.evaluate(u, v)
    checks = {
        "knot insertion u=0.3 (x2)": s.insert_knot(0.3, 2, direction="u"),
        "degree elevation v (+2)": s.elevate_degree(2, direction="v"),
        "refinement in u and v": s.refine([0.1, 0.55, 0.9], "u").refine([0.45], "v"),
    }
    for name, other in checks.items():
        print(f"{name}: max deviation {np.abs(other.evaluate(u, v) - ref).max():.2e}")
    n = s.normal(np.array([0.5]), np.array([0.5]))[0]
    print(f"normal at (0.5, 0.5): {np.round(n, 6).tolist()}")
    path = render_surface(s, args.output, title="splinekit demo: bicubic NURBS surface and its control net")
    print(f"wrote {path}")
    return 0


# ---------------------------------------------------------------------------
# output helpers

FORMATS = ("step", "stl", "3mf", "obj", "glb", "ply")
"""File formats ``build`` writes: exact STEP, or a tessellation in a mesh format."""
MESH_FORMATS = FORMATS[1:]
MESH_SUFFIXES = (".stl", ".obj", ".ply", ".3mf", ".glb")
STEP_SUFFIXES = (".step", ".stp")
EXACT_SUFFIXES = STEP_SUFFIXES + (".iges", ".igs", ".brep")  # exact B-rep files `info` reads
DEFAULT_FORMATS = "step,stl"


class _Console:
    """Where the commands write: results to stdout unless quiet, details only when verbose."""

    def __init__(self, quiet: bool = False, verbose: bool = False):
        self.quiet, self.verbose = quiet, verbose

    def out(self, text: str = "") -> None:
        if not self.quiet:
            print(text, flush=True)

    def detail(self, text: str) -> None:
        if self.verbose and not self.quiet:
            print(text, flush=True)


def _size_text(nbytes: int) -> str:
    for unit in ("B", "kB", "MB"):
        if nbytes < 1000 or unit == "MB":
            return f"{nbytes:.0f} {unit}" if unit == "B" else f"{nbytes:.1f} {unit}"
        nbytes /= 1000.0
    return ""  # pragma: no cover


def _count(n: int, word: str, plural: str | None = None) -> str:
    return f"{n} {word if n == 1 else (plural or word + 's')}"


def _number_text(x) -> str:
    return f"{x:g}" if isinstance(x, float) else str(x)


def _table(rows, header) -> str:
    """Rows of strings as left-aligned columns under ``header``, with a rule below it."""
    rows = [[str(c) for c in r] for r in rows]
    widths = [max(len(h), *(len(r[i]) for r in rows)) if rows else len(h) for i, h in enumerate(header)]
    fmt = "  ".join(f"{{:<{w}}}" for w in widths)
    lines = [fmt.format(*header).rstrip(), "  ".join("-" * w for w in widths)]
    lines += [fmt.format(*r).rstrip() for r in rows]
    return "\n".join(lines)


_BEYOND = "-- (beyond the float range)"


def _bbox_text(lo, hi) -> str:
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    with np.errstate(over="ignore"):  # coordinates near the float limits: a size beyond it is said so
        size = hi - lo
    return (f"[{', '.join(f'{x:.6g}' for x in lo)}] .. [{', '.join(f'{x:.6g}' for x in hi)}] "
            f"(size {' x '.join(f'{x:.6g}' if np.isfinite(x) else 'beyond the float range' for x in size)})")


def _measure(get, fmt: str) -> str:
    """``get()`` (an area or a volume) formatted with ``fmt``, or why there is no number: on a mesh
    near the float limits the measure overflows (MeshTopologyError), which is worth a note in a
    summary, not a failed command after its files are written."""
    try:
        value = float(get())
    except MeshTopologyError as exc:
        return f"-- ({_first_line(exc)})"
    return format(value, fmt) if np.isfinite(value) else _BEYOND


# ---------------------------------------------------------------------------
# the model registry

def _registry():
    """The model registry module: ``models``, or the module named by ``SPLINEKIT_MODELS``."""
    name = os.environ.get("SPLINEKIT_MODELS", "").strip() or "models"
    try:
        module = importlib.import_module(name)
    except ImportError as exc:
        _signals.reraise_interrupt(exc)
        raise MissingDependencyError(f"cannot import the model registry {name!r}: {exc}") from None
    missing = [attr for attr in ("MODELS", "DEFAULT_MODEL", "get_model", "build_model") if not hasattr(module, attr)]
    if missing:
        raise MissingDependencyError(f"the model registry {name!r} has no {', '.join(missing)} (its models are not installed yet?)")
    return module


def _doc_line(module) -> str:
    doc = (module.__doc__ or "").strip()
    return doc.splitlines()[0].rstrip(".") if doc else ""


def _parse_sets(registry, name: str, items) -> dict:
    """``--set name=value`` pairs parsed and checked by the model's parameters."""
    module = registry.get_model(name)
    params = {p.name: p for p in module.PARAMETERS}
    values = {}
    for item in items or ():
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise ParameterError(f"--set expects name=value, got {item!r}")
        if key not in params:
            known = ", ".join(params) or "none"
            raise ParameterError(f"model '{name}' has no parameter '{key}'; parameters: {known}")
        try:
            values[key] = params[key].parse(text)
        except SplineKitError:
            raise
        except (ArithmeticError, ValueError, TypeError) as exc:  # a registry's parser that lets one out
            raise ParameterError(f"--set {key}={text!r}: not a value of parameter '{key}' ({_first_line(exc)})") from None
    return values


def _build_model(registry, name: str, sets, console: _Console):
    values = _parse_sets(registry, name, sets)
    t0 = time.perf_counter()
    model = registry.build_model(name, **values)
    console.detail(f"built model '{name}' in {time.perf_counter() - t0:.2f} s")
    return model


def _patches_of(model) -> list:
    return [p for body in model.bodies for p in body]


def _params_text(model) -> str:
    return ", ".join(f"{k}={_number_text(v)}" for k, v in (model.params or {}).items())


# ---------------------------------------------------------------------------
# list

def cmd_list(args, console: _Console) -> int:
    registry = _registry()
    default = registry.DEFAULT_MODEL
    for name, module in registry.MODELS.items():
        mark = " (default)" if name == default else ""
        console.out(f"{name}{mark}: {_doc_line(module)}")
        rows = []
        for p in module.PARAMETERS:
            unit = p.unit or "-"
            rng = f"{_number_text(p.minimum)} .. {_number_text(p.maximum)}"
            kind = "int" if getattr(p, "kind", float) is int else "float"
            rows.append([p.name, _number_text(p.default), unit, rng, kind, p.doc])
        if rows:
            console.out("  " + _table(rows, ["parameter", "default", "unit", "range", "type", "meaning"]).replace("\n", "\n  "))
        else:
            console.out("  (no parameters)")
        console.out()
    console.out(f"build one with: splinekit build MODEL --set name=value (no MODEL builds '{default}')")
    return 0


# ---------------------------------------------------------------------------
# build

def _formats(text) -> list:
    if text is None:
        text = DEFAULT_FORMATS
    wanted = [f.strip().lower().lstrip(".") for f in str(text).split(",") if f.strip()]
    wanted = ["step" if f == "stp" else f for f in wanted]
    if not wanted:
        raise ParameterError(f"--format needs at least one of {', '.join(FORMATS)}")
    for f in wanted:
        if f not in FORMATS:
            raise ParameterError(f"unknown format {f!r}; choose from {', '.join(FORMATS)}")
    return list(dict.fromkeys(wanted))


def _tolerance(text):
    if text is None:
        return None
    try:
        value = float(text)
    except ValueError:
        raise ParameterError(f"--tolerance must be a positive number (model units), got {text!r}") from None
    if not (np.isfinite(value) and value > 0):
        raise ParameterError(f"--tolerance must be a positive number (model units), got {text!r}")
    return value


def _tessellator():
    try:
        from .tessellation import tessellate
    except ImportError as exc:
        _signals.reraise_interrupt(exc)
        raise MissingDependencyError(f"mesh output needs splinekit.tessellation, which does not import: {exc}") from None
    return tessellate


def _combined(meshes):
    """One PolyMesh holding the triangles of all ``meshes`` (vertex indices offset)."""
    from .mesh import PolyMesh

    if len(meshes) == 1:
        return meshes[0]
    offsets = np.cumsum([0] + [m.n_vertices for m in meshes[:-1]])
    V = np.concatenate([np.asarray(m.vertices) for m in meshes])
    F = np.concatenate([np.asarray(m.faces).reshape(-1, 3) + o for m, o in zip(meshes, offsets)])
    return PolyMesh(V, F)


def model_mesh(model, tolerance=None, label: str = "tessellating"):
    """``(mesh, max_deviation or None)``: the model's own mesh, or its bodies tessellated.

    ``tolerance`` is the absolute chordal tolerance (model units); None takes
    :func:`splinekit.tessellation.tessellate`'s default (1e-3 of the model size).
    """
    solids = list(getattr(model, "solids", None) or [])
    if not model.bodies and not solids:
        if model.mesh is None:
            raise ParameterError(f"model '{model.name}' has neither exact bodies nor a mesh")
        return model.mesh, None
    if tolerance is None and solids:  # a B-rep model states the tolerance of its meshes
        tolerance = (model.params or {}).get("tolerance")
    tessellate = _tessellator()
    meshes = []
    items = [list(body) for body in model.bodies] + solids
    with progress(len(items), label) as bar:
        for item in items:
            meshes.append(tessellate(item, tolerance))
            bar.advance()
    deviation = max(float(getattr(m, "max_deviation", 0.0)) for m in meshes)
    return _combined(meshes), deviation


def _build_and_export(registry, name, sets, formats, tolerance, out_dir, strict, console: _Console) -> None:
    """Build model ``name``, write it in ``formats`` to ``out_dir`` and print the summary.

    A mesh-only model cannot be STEP: with ``strict`` (formats asked for
    explicitly) that is an error, otherwise STEP is skipped with a note.
    """
    import exporters

    t0 = time.perf_counter()
    model = _build_model(registry, name, sets, console)
    t_build = time.perf_counter() - t0
    formats = list(formats)
    solids = list(getattr(model, "solids", None) or [])
    if not model.bodies and not solids and "step" in formats:
        if strict:
            raise ParameterError(f"model '{name}' exists only as a mesh (no exact surfaces): it cannot be written as STEP")
        formats.remove("step")
        console.out(f"note: model '{name}' exists only as a mesh; no STEP file written")
    mesh = deviation = None
    if any(f in MESH_FORMATS for f in formats):
        t1 = time.perf_counter()
        mesh, deviation = model_mesh(model, tolerance)
        console.detail(f"tessellated in {time.perf_counter() - t1:.2f} s")
    os.makedirs(out_dir, exist_ok=True)
    written = []
    with progress(len(formats), "writing") as bar:
        for fmt in formats:
            path = os.path.join(out_dir, f"{name}.{fmt}")
            t1 = time.perf_counter()
            if fmt == "step":
                names = list(model.body_names) + [s.name or model.name for s in solids]
                exporters.export_step(path, [list(b) for b in model.bodies] + solids, names=names or None)
            else:
                exporters.export_mesh(path, mesh, format=fmt)
            written.append(path)
            console.detail(f"wrote {path} in {time.perf_counter() - t1:.2f} s")
            bar.advance()
    patches = _patches_of(model)
    head = f"{name} ({_params_text(model)})" if model.params else name
    if solids:
        what = [_count(len(solids), "exact solid"), _count(sum(len(s.faces) for s in solids), "trimmed face")]
    elif model.bodies:
        what = [_count(len(model.bodies), "body", "bodies"), _count(len(patches), "exact face")]
    else:
        what = ["mesh only"]
    if mesh is not None:
        tri = _count(mesh.n_faces, "triangle" if mesh.is_triangle_mesh else "mesh face")
        if deviation is not None:
            tri += f" (max deviation {deviation:.3g})"
        what.append(tri)
    console.out(f"{head}: {', '.join(what)}")
    for path in written:
        console.out(f"  wrote {path}  {_size_text(os.path.getsize(path))}")
    if solids and not model.bodies:
        volume, area = sum(s.volume() for s in solids), sum(s.area() for s in solids)
        console.out(f"  volume {volume:.10g}, area {area:.10g} (exact, splinekit.brep mass properties)")
    elif model.bodies and model.closed and "step" in formats:
        from .interop.occ import to_shape

        shapes = [to_shape(list(body)) for body in model.bodies]
        volume = _measure(lambda: sum(occ_volume(s) for s in shapes), ".8g")
        console.out(f"  volume {volume}, area {_measure(lambda: sum(occ_area(s) for s in shapes), '.8g')} (exact, OCC)")
    elif mesh is not None and mesh.is_closed:
        console.out(f"  volume {_measure(lambda: mesh.volume, '.8g')}, area {_measure(lambda: mesh.area, '.8g')} (mesh)")
    elif mesh is not None:
        console.out(f"  area {_measure(lambda: mesh.area, '.8g')} (mesh; open surface, no volume)")
    console.out(f"  built in {t_build:.2f} s, total {time.perf_counter() - t0:.2f} s")


def _model_names(registry, args) -> list:
    """The models a command runs on: every one with ``--all``, else MODEL or the default."""
    if getattr(args, "all", False):
        if args.model or args.set:
            raise ParameterError("--all runs every model with its defaults; give no MODEL and no --set with it")
        return list(registry.MODELS)
    name = args.model or registry.DEFAULT_MODEL
    registry.get_model(name)  # an unknown model fails before any work
    return [name]


def cmd_build(args, console: _Console) -> int:
    registry = _registry()
    formats = _formats(args.format)
    tolerance = _tolerance(args.tolerance)
    names = _model_names(registry, args)
    out_dir = checked_path(args.output or ".")  # a NUL byte is a ParameterError, not a ValueError from os
    if os.path.exists(out_dir) and not os.path.isdir(out_dir):
        raise ParameterError(f"output folder {out_dir!r} exists and is not a folder")
    strict = args.format is not None and len(names) == 1
    with progress(len(names), "building models", show=len(names) > 1) as bar:
        for name in names:
            _build_and_export(registry, name, args.set, formats, tolerance, out_dir, strict, console)
            bar.advance()
    return 0


# ---------------------------------------------------------------------------
# info

def _occ(*names):
    from .interop.occ import _ocp

    return _ocp(*names)


def read_step_shape(path):
    """The OCC shape of all roots of the STEP file ``path`` (coordinates in millimetres)."""
    IFSelect, STEPControl = _occ("IFSelect", "STEPControl")
    if not os.path.isfile(path):
        raise FileFormatError(f"STEP file {path!r} does not exist or is not a file")
    from exporters._stepscan import scan_step, syntax_errors

    scan_step(path)  # OCC's parser crashes the process on some inputs: refuse them first
    reader = STEPControl.STEPControl_Reader()
    status = reader.ReadFile(path)
    if status != IFSelect.IFSelect_ReturnStatus.IFSelect_RetDone:
        raise FileFormatError(f"{path!r} is not a readable STEP file (OpenCascade: {status.name})")
    syntax_errors(reader, f"STEP file {path!r}")
    if reader.TransferRoots() == 0:
        raise FileFormatError(f"the STEP file {path!r} holds no shapes")
    return reader.OneShape()


def _sub_shapes(shape, kind: str) -> list:
    """The distinct sub-shapes of ``kind`` ("FACE", "EDGE", ...), in OCC's map order."""
    TopAbs, TopExp, TopTools = _occ("TopAbs", "TopExp", "TopTools")
    found = TopTools.TopTools_IndexedMapOfShape()
    TopExp.TopExp.MapShapes_s(shape, getattr(TopAbs.TopAbs_ShapeEnum, f"TopAbs_{kind}"), found)
    return [found.FindKey(i) for i in range(1, found.Extent() + 1)]


def occ_area(shape) -> float:
    """Total face area of ``shape`` by OCC's adaptive Gauss integration (relative error 1e-9)."""
    BRepGProp, GProp = _occ("BRepGProp", "GProp")
    props = GProp.GProp_GProps()
    BRepGProp.BRepGProp.SurfaceProperties_s(shape, props, 1e-9)
    return float(props.Mass())


def occ_volume(shape) -> float:
    """Total volume of the solids of ``shape`` (0 without solids), OCC adaptive integration."""
    BRepGProp, GProp = _occ("BRepGProp", "GProp")
    total = 0.0
    for solid in _sub_shapes(shape, "SOLID"):
        props = GProp.GProp_GProps()
        BRepGProp.BRepGProp.VolumeProperties_s(solid, props, 1e-9)
        total += float(props.Mass())
    return total


def occ_bbox(shape):
    """``(lo, hi)`` of the tight bounding box of ``shape`` (exact geometry, no triangulation)."""
    Bnd, BRepBndLib = _occ("Bnd", "BRepBndLib")
    box = Bnd.Bnd_Box()
    BRepBndLib.BRepBndLib.AddOptimal_s(shape, box, False, False)
    if box.IsVoid():
        return np.zeros(3), np.zeros(3)
    x0, y0, z0, x1, y1, z1 = box.Get()
    return np.array([x0, y0, z0]), np.array([x1, y1, z1])


def _face_kinds(faces) -> dict:
    """``"BSplineSurface, degree 3 x 3" -> count`` over ``faces``."""
    BRepAdaptor, TopoDS = _occ("BRepAdaptor", "TopoDS")
    kinds: dict = {}
    for face in faces:
        surf = BRepAdaptor.BRepAdaptor_Surface(TopoDS.TopoDS.Face_s(face))
        kind = surf.GetType().name.replace("GeomAbs_", "")
        if kind in ("BSplineSurface", "BezierSurface"):
            kind += f", degree {surf.UDegree()} x {surf.VDegree()}"
            if surf.IsURational() or surf.IsVRational():
                kind += ", rational"
        kinds[kind] = kinds.get(kind, 0) + 1
    return kinds


def read_exact_shape(path):
    """``(format name, OCC shape)`` of a STEP, IGES or OCC .brep file."""
    suffix = os.path.splitext(path)[1].lower()
    if suffix in STEP_SUFFIXES:
        return "STEP", read_step_shape(path)
    from exporters.brep import read_brep_shape
    from exporters.iges import read_iges_shape

    return ("BREP", read_brep_shape(path)) if suffix == ".brep" else ("IGES", read_iges_shape(path))


def _trimmed_count(faces) -> int:
    """How many ``faces`` are trimmed: holes, or an outer boundary inside the surface's own domain."""
    BRep, BRepTools, TopoDS = _occ("BRep", "BRepTools", "TopoDS")
    trimmed = 0
    for face in faces:
        face = TopoDS.TopoDS.Face_s(face)
        if len(_sub_shapes(face, "WIRE")) > 1:
            trimmed += 1
            continue
        box = BRepTools.BRepTools.UVBounds_s(face)
        natural = BRep.BRep_Tool.Surface_s(face).Bounds()
        scale = max(1.0, *(abs(x) for x in box))
        trimmed += any(abs(a - b) > 1e-9 * scale for a, b in zip(box, natural))
    return trimmed


def _info_step(path, console: _Console) -> int:
    fmt, shape = read_exact_shape(path)
    faces = _sub_shapes(shape, "FACE")
    counts = {k: len(_sub_shapes(shape, k)) for k in ("SOLID", "SHELL", "FACE", "EDGE", "VERTEX")}
    console.out(f"{path}: {fmt}, {counts['SOLID']} solids, {counts['SHELL']} shells, {counts['FACE']} faces, "
                f"{counts['EDGE']} edges, {counts['VERTEX']} vertices")
    (BRepCheck,) = _occ("BRepCheck")
    trimmed = _trimmed_count(faces)
    console.out(f"  faces: {trimmed} trimmed, {counts['FACE'] - trimmed} untrimmed; "
                f"valid (OCC BRepCheck): {'yes' if BRepCheck.BRepCheck_Analyzer(shape).IsValid() else 'NO'}")
    for kind, n in sorted(_face_kinds(faces).items(), key=lambda kv: -kv[1]):
        console.out(f"  {n:5d} x {kind}")
    lo, hi = occ_bbox(shape)
    console.out(f"  bounding box {_bbox_text(lo, hi)}")
    console.out(f"  area   {occ_area(shape):.10g}  (OCC GProp)")
    if counts["SOLID"]:
        console.out(f"  volume {occ_volume(shape):.10g}  (OCC GProp)")
    else:
        console.out("  volume -- (no solid)")
    return 0


def mesh_genus(mesh):
    """``(components, genus or None)``: genus of a closed orientable mesh from
    ``chi = sum over components of (2 - 2 g)``, None when the mesh is open."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    idx, off = np.asarray(mesh.face_indices), np.asarray(mesh.face_offsets)
    counts = np.diff(off)
    face = np.repeat(np.arange(counts.size), counts)
    n = mesh.n_vertices + counts.size
    graph = coo_matrix((np.ones(idx.size), (idx, mesh.n_vertices + face)), shape=(n, n))
    _, labels = connected_components(graph, directed=False)
    used = np.zeros(mesh.n_vertices, bool)
    used[idx] = True
    components = np.unique(labels[mesh.n_vertices:]).size
    if not mesh.is_closed:
        return components, None
    chi = mesh.euler_characteristic - int((~used).sum())  # isolated vertices are not part of the surface
    return components, (2 * components - chi) / 2


def _info_mesh(path, console: _Console) -> int:
    import exporters

    mesh = exporters.import_mesh(path)
    V = np.asarray(mesh.vertices)
    closed = bool(mesh.is_closed)
    components, genus = mesh_genus(mesh)
    kind = "triangles" if mesh.is_triangle_mesh else ("quads" if mesh.is_quad_mesh else "polygons")
    fmt = os.path.splitext(path)[1].lstrip(".").upper()
    console.out(f"{path}: {fmt} mesh, {mesh.n_vertices} vertices, {mesh.n_faces} faces ({kind}), {components} component(s)")
    console.out(f"  closed {'yes' if closed else 'no'}, Euler characteristic {mesh.euler_characteristic}"
                + (f", genus {genus:g}" if genus is not None else ""))
    if len(V):
        console.out(f"  bounding box {_bbox_text(V.min(0), V.max(0))}")
    console.out(f"  area   {_measure(lambda: mesh.area, '.10g')}")
    console.out(f"  volume {_measure(lambda: mesh.volume, '.10g')}" if closed else "  volume -- (open mesh)")
    return 0


def cmd_info(args, console: _Console) -> int:
    path = args.file
    if not os.path.isfile(path):
        raise FileFormatError(f"{path!r} does not exist or is not a file")
    suffix = os.path.splitext(path)[1].lower()
    if suffix in EXACT_SUFFIXES:
        return _info_step(path, console)
    if suffix in MESH_SUFFIXES:
        return _info_mesh(path, console)
    raise FileFormatError(f"cannot tell the format of {path!r}; expected a suffix among {', '.join(EXACT_SUFFIXES + MESH_SUFFIXES)}")


# ---------------------------------------------------------------------------
# render

def _size(text):
    w, sep, h = str(text).lower().partition("x")
    try:
        size = (int(w), int(h))
    except ValueError:
        raise ParameterError(f"--size must be WIDTHxHEIGHT in pixels (e.g. 1000x800), got {text!r}") from None
    if not sep or not all(64 <= s <= 8000 for s in size):
        raise ParameterError(f"--size must be WIDTHxHEIGHT with each between 64 and 8000 pixels, got {text!r}")
    return size


def _view(text):
    try:
        elev, azim = (float(x) for x in str(text).split(","))
    except ValueError:
        raise ParameterError(f"--view must be ELEVATION,AZIMUTH in degrees (e.g. 28,-58), got {text!r}") from None
    if not (np.isfinite(elev) and np.isfinite(azim)):
        raise ParameterError(f"--view angles must be finite, got {text!r}")
    return elev, azim


def _is_file_target(target: str) -> bool:
    """A STEP or mesh file by its suffix; anything else is taken for a model name."""
    return os.path.splitext(target)[1].lower() in STEP_SUFFIXES + MESH_SUFFIXES


def cmd_render(args, console: _Console) -> int:
    from .plot import render_mesh, render_patches

    size, view = _size(args.size), _view(args.view)
    target = args.target
    stem = os.path.splitext(os.path.basename(target))[0]
    out = args.output or f"{stem}.png"
    folder = os.path.dirname(os.path.abspath(out))
    if not os.path.isdir(folder):
        raise FileFormatError(f"cannot write {out!r}: the folder {folder!r} does not exist")
    options = dict(color=args.color, scale=args.scale, size=size, view=view)
    t0 = time.perf_counter()
    if _is_file_target(target):
        if args.set:
            raise ParameterError("--set applies to models; a file is drawn as it is")
        if not os.path.isfile(target):
            raise FileFormatError(f"{target!r} does not exist or is not a file")
        suffix = os.path.splitext(target)[1].lower()
        title = f"{os.path.basename(target)}: {args.color}"
        if suffix in STEP_SUFFIXES:
            import exporters

            items = [item.geometry for item in exporters.import_step(target)]
            patches = [g for g in items if hasattr(g, "degree_u")]
            from .brep import Shell, Solid, TrimmedFace

            breps = [g for g in items if isinstance(g, (Shell, Solid, TrimmedFace))]
            if breps:  # trimmed faces are drawn as their tessellation
                tessellate = _tessellator()
                mesh = _combined([tessellate(g, None) for g in breps])
                render_mesh(mesh, out, title=title, **options)
                what = _count(sum(len(getattr(g, "faces", (g,))) for g in breps), "trimmed face")
            elif patches:
                render_patches(patches, out, title=title, **options)
                what = _count(len(patches), "face")
            else:
                raise FileFormatError(f"the STEP file {target!r} holds no faces to draw")
        elif suffix in MESH_SUFFIXES:
            import exporters

            mesh = exporters.import_mesh(target)
            render_mesh(mesh, out, title=title, **options)
            what = _count(mesh.n_faces, "face")
    else:
        registry = _registry()
        if target not in registry.MODELS and os.path.exists(target):
            raise FileFormatError(f"cannot render {target!r}: it is not a model name, and files must end in "
                                  f"{', '.join(STEP_SUFFIXES + MESH_SUFFIXES)}")
        model = _build_model(registry, target, args.set, console)
        title = f"{target} ({_params_text(model)}): {args.color}" if model.params else f"{target}: {args.color}"
        if model.bodies:
            patches = _patches_of(model)
            render_patches(patches, out, title=title, **options)
            what = _count(len(patches), "exact patch", "exact patches")
        elif model.mesh is not None:
            render_mesh(model.mesh, out, title=title, **options)
            what = _count(model.mesh.n_faces, "mesh face")
        elif getattr(model, "solids", None):
            mesh, _ = model_mesh(model)  # trimmed faces are drawn as their tessellation
            render_mesh(mesh, out, title=title, **options)
            what = _count(mesh.n_faces, "triangle")
        else:
            raise ParameterError(f"model '{target}' has neither exact bodies nor a mesh to draw")
    console.out(f"wrote {out} ({what}, colored by {args.color}, {size[0]}x{size[1]}) in {time.perf_counter() - t0:.2f} s")
    return 0


# ---------------------------------------------------------------------------
# check

class _Checks:
    """Rows of the check table: name, measured, expected, tolerance, PASS/FAIL/SKIP."""

    def __init__(self):
        self.rows = []

    def compare(self, name, measured, expected, tol, note=""):
        ok = measured is not None and np.isfinite(measured) and abs(measured - expected) <= tol
        self.rows.append([name, _fmt(measured), _fmt(expected), _fmt(tol), "PASS" if ok else "FAIL", note])

    def truth(self, name, ok, note=""):
        self.rows.append([name, "yes" if ok else "no", "yes", "", "PASS" if ok else "FAIL", note])

    def skip(self, name, note):
        self.rows.append([name, "", "", "", "SKIP", note])

    @property
    def failed(self) -> int:
        return sum(r[4] == "FAIL" for r in self.rows)


def _fmt(x) -> str:
    if x is None:
        return "--"
    if isinstance(x, (int, np.integer)):
        return str(int(x))
    return f"{x:.10g}"


def point_deviation(patches, samples: int = 9) -> tuple[float, int]:
    """``(max distance, points)`` between splinekit and OCC at a ``samples x samples``
    parameter grid of every patch; OCC evaluates the surface of the face that
    :func:`splinekit.occ.to_shape` builds from the patch (one call per point:
    OCC has no batch evaluator)."""
    from .interop.occ import to_shape

    (BRep,) = _occ("BRep")
    worst, count = 0.0, 0
    with progress(len(patches), "comparing points") as bar:
        for s in patches:
            (a, b), (c, d) = s.domain
            us, vs = np.linspace(a, b, samples), np.linspace(c, d, samples)
            ours = s.evaluate_grid(us, vs).reshape(-1, 3)
            surface = BRep.BRep_Tool.Surface_s(to_shape(s))
            U, V = np.meshgrid(us, vs, indexing="ij")
            theirs = np.array([[p.X(), p.Y(), p.Z()] for p in map(surface.Value, U.ravel(), V.ravel())])
            worst = max(worst, float(np.linalg.norm(ours - theirs, axis=1).max()))
            count += ours.shape[0]
            bar.advance()
    return worst, count


def _euler_characteristic(shape) -> int:
    return len(_sub_shapes(shape, "VERTEX")) - len(_sub_shapes(shape, "EDGE")) + len(_sub_shapes(shape, "FACE"))


def cmd_check(args, console: _Console) -> int:
    registry = _registry()
    names = _model_names(registry, args)
    failed = []
    with progress(len(names), "checking models", show=len(names) > 1) as bar:
        for name in names:
            if _check_model(registry, name, args.set, console):
                failed.append(name)
            bar.advance()
    if len(names) > 1:
        console.out(f"{len(names) - len(failed)} of {len(names)} models pass" + (f"; failed: {', '.join(failed)}" if failed else ""))
    return 1 if failed else 0


def _check_solids(model, table: _Checks, measures: dict) -> str:
    """Checks and measures of a model's exact B-rep solids; returns the measures' source.

    Area and volume are splinekit's adaptive integrals (relative tolerance 1e-10), cross-checked
    against OCC's GProp at precision 1e-10 on the same solids; the Euler characteristic is the
    tessellation's (a closed mesh: 2 - 2 genus), which also has to be closed with a volume within
    area x max deviation of the exact one.
    """
    from .interop.exact_booleans import occ_solid
    from .interop.occ import _check_valid

    BRepGProp, GProp = _occ("BRepGProp", "GProp")
    solids = list(model.solids)
    occ_area_total = occ_volume_total = 0.0
    for i, solid in enumerate(solids):
        label = solid.name or f"solid {i}"
        try:
            shape = occ_solid(solid)
            _check_valid(shape, label)
        except SplineKitError as exc:
            table.truth(f"{label}: OCC calls it a valid solid", False, str(exc).splitlines()[0][:120])
            continue
        table.truth(f"{label}: OCC calls it a valid solid", True, "BRepCheck_Analyzer")
        for kind, fn in (("area", BRepGProp.BRepGProp.SurfaceProperties_s), ("volume", BRepGProp.BRepGProp.VolumeProperties_s)):
            props = GProp.GProp_GProps()
            fn(shape, props, 1e-10)
            if kind == "area":
                occ_area_total += props.Mass()
            else:
                occ_volume_total += props.Mass()
    measures["faces"] = sum(len(s.faces) for s in solids)
    measures["area"] = sum(s.area() for s in solids)
    measures["volume"] = sum(s.volume() for s in solids)
    for kind, ours, theirs in (("area", measures["area"], occ_area_total), ("volume", measures["volume"], occ_volume_total)):
        table.compare(f"{kind}: splinekit vs OCC", ours, theirs, 1e-8 * abs(theirs), "OCC GProp at precision 1e-10")
    mesh, deviation = model_mesh(model)
    table.truth("tessellation is closed", bool(mesh.is_closed))
    measures["euler_characteristic"] = mesh.euler_characteristic
    if mesh.is_closed:
        bound = float(mesh.area) * float(deviation or 0.0)
        table.compare("tessellation volume vs exact", float(mesh.volume), measures["volume"], max(bound, 1e-12),
                      "within area x max deviation")
    return "splinekit"


def _check_model(registry, name, sets, console: _Console) -> int:
    """Print the check table of model ``name``; returns the number of failed checks."""
    from .interop.occ import to_shape

    t0 = time.perf_counter()
    model = _build_model(registry, name, sets, console)
    table = _Checks()
    measures = {}
    patches = _patches_of(model)
    if model.bodies:
        shapes = []
        with progress(len(model.bodies), "sewing") as bar:
            for i, body in enumerate(model.bodies):
                label = model.body_names[i] if i < len(model.body_names) else f"body {i}"
                try:
                    shapes.append(to_shape(list(body)))
                    table.truth(f"{label}: OCC sews a valid shape", True)
                except SplineKitError as exc:
                    table.truth(f"{label}: OCC sews a valid shape", False, str(exc).splitlines()[0][:120])
                bar.advance()
        if model.closed:
            n_solids = [len(_sub_shapes(s, "SOLID")) for s in shapes]
            for i, n in enumerate(n_solids):
                table.truth(f"body {i} is a closed solid", n >= 1, f"{n} solid(s)")
        measures["faces"] = sum(len(_sub_shapes(s, "FACE")) for s in shapes)
        # area and volume: an independent reference (OCC's GProp where reliable, else scipy)
        from .interop.gprop import reference_integrals

        sewn = shapes if len(shapes) == len(model.bodies) else None
        reference = reference_integrals(model.bodies, closed=model.closed, shapes=sewn)
        measures["area"], measures["volume"] = reference.area, reference.volume
        sources = dict.fromkeys(("area", "volume"), f"{reference.source} ({reference.reason})")
        measures["euler_characteristic"] = sum(_euler_characteristic(s) for s in shapes)
        size = np.ptp(np.concatenate([np.asarray(p.control_points).reshape(-1, 3) for p in patches]), axis=0).max()
        worst, count = point_deviation(patches)
        table.compare(f"point deviation vs OCC ({count} points)", worst, 0.0, 1e-9 * max(size, 1.0), "splinekit vs Geom_Surface.Value")
        source = "OCC"
    elif getattr(model, "solids", None):
        source = _check_solids(model, table, measures)
        sources = {}
    else:
        mesh = model.mesh
        if mesh is None:
            raise ParameterError(f"model '{name}' has neither exact bodies nor a mesh to check")
        if model.closed:
            table.truth("mesh is closed", bool(mesh.is_closed))
        measures["faces"] = mesh.n_faces
        measures["area"] = float(mesh.area)
        measures["volume"] = float(mesh.volume) if mesh.is_closed else None
        measures["euler_characteristic"] = mesh.euler_characteristic
        source = "mesh"
        sources = {}
    chi = measures["euler_characteristic"]
    measures["genus"] = (2 - chi) / 2
    for key, value in (model.checks or {}).items():
        try:
            expected, tol = value
            expected, tol = float(expected), float(tol)
        except (TypeError, ValueError):
            table.skip(key, f"malformed check {value!r}; expected (value, tolerance)")
            continue
        measure = next((m for m in measures if key == m or key.startswith(m)), None)
        if measure is None:
            table.skip(key, "no measure of that name (known: " + ", ".join(measures) + ")")
        elif measures[measure] is None:
            table.compare(key, None, expected, tol, f"{source}: no closed solid to measure")
        else:
            table.compare(key, measures[measure], expected, tol, sources.get(measure, f"{source} {measure}"))
    if model.bodies and model.closed:
        try:
            tessellate = _tessellator()
        except MissingDependencyError as exc:
            table.skip("tessellation volume", str(exc))
        else:
            meshes = [tessellate(list(b)) for b in model.bodies]
            closed = all(m.is_closed for m in meshes)
            table.truth("tessellation is closed", closed)
            if closed and measures["volume"] is not None:
                vol = sum(float(m.volume) for m in meshes)
                bound = sum(float(m.area) * float(m.max_deviation) for m in meshes)
                table.compare("tessellation volume vs OCC", vol, measures["volume"], max(bound, 1e-12), "within area x max deviation")
    n_faces = len(patches) + sum(len(s.faces) for s in getattr(model, "solids", None) or [])
    console.out(f"check {name}" + (f" ({_params_text(model)})" if model.params else "") + f": {_count(n_faces, 'exact face')}"
                + (f", mesh of {_count(model.mesh.n_faces, 'face')}" if model.mesh is not None else ""))
    console.out(_table(table.rows, ["check", "measured", "expected", "tolerance", "result", "note"]))
    n_fail = table.failed
    console.out(f"{len(table.rows) - n_fail} of {len(table.rows)} passed or skipped, {n_fail} failed "
                f"({time.perf_counter() - t0:.2f} s)")
    console.out()
    return n_fail


# ---------------------------------------------------------------------------
# main

class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors: ``splinekit: error: ...`` and exit status 2."""

    def error(self, message):
        self.exit(2, _one_line(f"{self.prog.split()[0]}: error: {message} (see --help)") + "\n")


def _parser() -> argparse.ArgumentParser:
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

    b = sub.add_parser("build", parents=[common], help="build a model and export it (STEP, STL, 3MF, OBJ, GLB, PLY)")
    b.add_argument("model", nargs="?", help="model name (default: the registry's default model)")
    b.add_argument("--all", action="store_true", help="build every model (with its defaults)")
    model_options(b)
    b.add_argument("-o", "--output", metavar="DIR", help="output folder, created if missing (default: current folder)")
    b.add_argument("--format", metavar="LIST", help=f"comma-separated formats among {','.join(FORMATS)} (default: {DEFAULT_FORMATS})")
    b.add_argument("--tolerance", metavar="T", help="chordal tolerance of mesh output in model units (default: 1e-3 of the model size)")

    i = sub.add_parser("info", parents=[common], help="what a STEP, IGES, BREP or mesh file holds")
    i.add_argument("file", help="a .step/.stp/.iges/.igs/.brep or .stl/.obj/.ply/.3mf/.glb file")

    from .plot import COLOR_MODES, COLOR_SCALES

    r = sub.add_parser("render", parents=[common], help="a shaded PNG of a model or a file, colored by curvature")
    r.add_argument("target", metavar="MODEL|FILE", help="a model name, or a STEP or mesh file")
    model_options(r)
    r.add_argument("-o", "--output", metavar="PNG", help="picture to write (default: NAME.png in the current folder)")
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

    d = sub.add_parser("demo", parents=[common], help="build a NURBS surface, print what was computed and write a PNG of it")
    d.add_argument("-o", "--output", default="splinekit-demo.png", help="PNG path (default: %(default)s)")
    return parser


COMMANDS = {"list": cmd_list, "build": cmd_build, "info": cmd_info, "render": cmd_render, "check": cmd_check, "demo": cmd_demo}


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip()
    return text.splitlines()[0] if text else type(exc).__name__


def _one_line(text: str) -> str:
    """``text`` with every character that ends a line or steers a terminal (newline, carriage
    return, escape, the separators \\x1c-\\x1e, U+2028...) written as its escape: arguments echoed
    in an error message cannot break it into several lines."""
    return "".join(c if c.isprintable() or c == " " else repr(c)[1:-1] for c in text)


def _error_line(text: str, after_echo: bool = False) -> None:
    """``text`` as one line on stderr; a closed stderr is no further error. ``after_echo``: on a
    terminal, start a fresh line first (the terminal has echoed ``^C``)."""
    try:
        sys.stderr.write(("\n" if after_echo and _is_tty(sys.stderr) else "") + _one_line(text) + "\n")
        sys.stderr.flush()
    except (OSError, ValueError):
        pass


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
                _error_line(exc.code)
        if signum is not None:
            status = _signals.STATUS.get(signum, 128 + signum)
            _error_line(_signals.message(signum), after_echo=signum == signal.SIGINT)
    if own:
        _signals.finish(status)
    return status


def _is_tty(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


def _main(argv) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    quiet, verbose = getattr(args, "quiet", False), getattr(args, "verbose", False)
    if args.command is None:
        parser.print_help()
        return 0
    bars = is_enabled()
    set_enabled(bars and not quiet)
    try:
        return _run(args, _Console(quiet, verbose))
    finally:
        set_enabled(bars)  # main() may be called again in the same process


# A RuntimeWarning from numpy in our code means an overflow or an invalid operation on extreme
# input: the command stops with one line instead of printing the warning and an inf result.
_OUR_MODULES = r"(splinekit|exporters|models|numpy|__main__)(\.|$)"


def _run(args, console: _Console) -> int:
    """Run the parsed command; errors become one line on stderr and an exit status."""
    verbose = console.verbose
    try:
        with warnings.catch_warnings():
            warnings.filterwarnings("error", category=RuntimeWarning, module=_OUR_MODULES)
            if args.command == "demo":
                return cmd_demo(args)
            return COMMANDS[args.command](args, console)
    except BrokenPipeError:
        raise  # main() ends quietly
    except (SplineKitError, OSError) as exc:
        _traceback(verbose)
        _error_line(f"splinekit: error: {_first_line(exc)}")
        return 1
    except RuntimeWarning as exc:
        _traceback(verbose)
        _error_line(f"splinekit: error: numerical failure ({_first_line(exc)} at {_where(exc)}): "
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
        _error_line(f"splinekit: error: unexpected {type(exc).__name__}: {_first_line(exc)}{hint}")
        return 1


def _traceback(verbose: bool) -> None:
    if verbose:
        import traceback

        traceback.print_exc()


def _where(exc: BaseException) -> str:
    """``module.py:line`` where ``exc`` was raised."""
    tb = exc.__traceback__
    while tb is not None and tb.tb_next is not None:
        tb = tb.tb_next
    if tb is None:
        return "?"
    return f"{os.path.basename(tb.tb_frame.f_code.co_filename)}:{tb.tb_lineno}"


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
