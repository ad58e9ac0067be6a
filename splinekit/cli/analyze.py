"""``splinekit analyze``: surface-quality pictures and numbers of a model or of a STEP or mesh
file -- zebra stripes, isophotes, curvature and draft-angle maps, the continuity of every
shared edge, and the deviation of a scan (a point cloud or mesh file) from the part.

Each analysis asked for writes its PNG(s) into the output folder (atomically) and prints one
line of figures: ``NAME-zebra.png``, ``NAME-isophotes.png``, ``NAME-curvature-KIND.png``,
``NAME-draft.png``, ``NAME-deviation.png`` and ``NAME-deviation-histogram.png``.
"""

from __future__ import annotations

import os
import time

import numpy as np

import exporters

from .. import analysis
from ..brep import Shell, Solid, TrimmedFace
from ..errors import FileFormatError, ParameterError, SplineKitError
from ..mesh import PolyMesh
from .console import Console, count
from .info import MESH_SUFFIXES, STEP_SUFFIXES
from .registry import build_model, patches_of, registry, solids_of
from .render import is_file_target, parse_size, parse_view

POINT_SUFFIXES = (".xyz",)
"""Plain-text point clouds: one point per line, its first three numbers x y z (``#`` comments)."""
SCAN_SUFFIXES = MESH_SUFFIXES + POINT_SUFFIXES
DEFAULT_OUTPUT = "out"


def parse_vector(text, option: str) -> np.ndarray:
    """``X,Y,Z`` as a ``(3,)`` float array; ParameterError naming ``option`` otherwise."""
    try:
        values = [float(x) for x in str(text).split(",")]
    except ValueError:
        values = []
    if len(values) != 3 or not np.isfinite(values).all():
        raise ParameterError(f"{option} must be three finite numbers X,Y,Z (e.g. 0,0,1), got {text!r}")
    if not any(values):
        raise ParameterError(f"{option} {text!r} has zero length: it names no direction")
    return np.array(values)


def parse_degrees(text, option: str, low: float, high: float) -> float:
    try:
        value = float(text)
    except ValueError:
        value = np.nan
    if not (np.isfinite(value) and low <= value < high):
        raise ParameterError(f"{option} must be an angle in [{low:g}, {high:g}) degrees, got {text!r}")
    return value


def read_scan(path):
    """A scan file: a mesh (``.stl``, ``.obj``, ``.ply``, ... with faces) as a PolyMesh, a PLY
    of vertices only or an ``.xyz`` file as an ``(n, 3)`` point array."""
    if not os.path.isfile(path):
        raise FileFormatError(f"the scan {path!r} does not exist or is not a file")
    suffix = os.path.splitext(path)[1].lower()
    if suffix not in SCAN_SUFFIXES:
        raise FileFormatError(f"cannot read the scan {path!r}: scans are {', '.join(SCAN_SUFFIXES)} files")
    if suffix in POINT_SUFFIXES:
        points = _read_xyz(path)
    else:
        mesh = exporters.import_mesh(path)
        if mesh.n_faces:
            return mesh
        points = np.asarray(mesh.vertices)
    if not len(points):
        raise FileFormatError(f"the scan {path!r} is empty: it holds no points")
    bad = ~np.isfinite(points).all(axis=1)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise FileFormatError(f"the scan {path!r}: point {i} = {points[i].tolist()} is not finite")
    return points


def _read_xyz(path):
    rows = []
    with open(path, "r", encoding="utf-8", errors="replace") as fh:
        for number, line in enumerate(fh, 1):
            text = line.split("#", 1)[0].replace(",", " ").split()
            if not text:
                continue
            try:
                point = [float(x) for x in text[:3]]
            except ValueError:
                point = []
            if len(point) != 3:
                raise FileFormatError(f"{path!r} line {number}: expected x y z, got {line.strip()[:60]!r}")
            rows.append(point)
    return np.array(rows, dtype=np.float64).reshape(-1, 3)


def _file_part(target):
    """What a STEP or mesh file holds, as one object the analysis takes."""
    if not os.path.isfile(target):
        raise FileFormatError(f"{target!r} does not exist or is not a file")
    if os.path.splitext(target)[1].lower() in MESH_SUFFIXES:
        mesh = exporters.import_mesh(target)
        if not mesh.n_faces:
            raise FileFormatError(f"{target!r} holds no faces to analyse")
        return mesh
    items = [item.geometry for item in exporters.import_step(target)]
    breps = [g for g in items if isinstance(g, (Shell, Solid, TrimmedFace))]
    if breps:
        return breps
    patches = [g for g in items if hasattr(g, "degree_u")]
    if patches:
        return patches
    raise FileFormatError(f"the STEP file {target!r} holds no faces to analyse")


def _model_part(target, sets, console):
    reg = registry()
    if target not in reg.MODELS and os.path.exists(target):
        raise FileFormatError(f"cannot analyse {target!r}: it is not a model name, and files must end in "
                              f"{', '.join(STEP_SUFFIXES + MESH_SUFFIXES)}")
    model = build_model(reg, target, sets, console)
    if model.bodies:
        return patches_of(model)
    solids = solids_of(model)
    if solids:
        return solids
    if model.mesh is not None:
        return model.mesh
    raise ParameterError(f"model '{target}' has neither exact bodies nor a mesh to analyse")


def _wanted(args) -> list:
    chosen = [name for name, on in (("zebra", args.zebra), ("isophotes", args.isophotes),
                                    ("curvature", args.curvature is not None), ("continuity", args.continuity),
                                    ("draft", args.draft is not None), ("deviation", args.deviation is not None),
                                    ("combs", args.combs)) if on]
    if not chosen:
        raise ParameterError("nothing to analyse: give one or more of --zebra, --isophotes, --curvature KIND, "
                             "--continuity, --draft X,Y,Z, --deviation SCAN, --combs")
    return chosen


def cmd_analyze(args, console: Console) -> int:
    wanted = _wanted(args)
    if "continuity" in wanted and not hasattr(analysis, "shell_continuity"):  # before any work
        raise ParameterError("--continuity needs splinekit.analysis.shell_continuity (edge continuity), "
                             "which this version of splinekit does not have yet")
    size, view = parse_size(args.size), parse_view(args.view)
    if not 1 <= args.stripes <= 180:
        raise ParameterError(f"--stripes must be a whole number from 1 to 180, got {args.stripes}")
    pull = parse_vector(args.draft, "--draft") if args.draft is not None else None
    light = parse_vector(args.light, "--light")
    min_draft = parse_degrees(args.min_draft, "--min-draft", 0.0, 90.0)
    if args.min_draft != "0" and pull is None:
        raise ParameterError("--min-draft applies to --draft; give the pull direction with --draft X,Y,Z")
    tolerance = None if args.tolerance is None else _positive(args.tolerance)
    target = args.target
    file_target = is_file_target(target)
    if file_target and args.set:
        raise ParameterError("--set applies to models; a file is analysed as it is")
    scan = read_scan(args.deviation) if args.deviation is not None else None  # a bad scan fails before any work
    folder = args.output or DEFAULT_OUTPUT
    if os.path.exists(folder) and not os.path.isdir(folder):
        raise FileFormatError(f"cannot write into {folder!r}: it exists and is not a folder")
    stem = os.path.splitext(os.path.basename(target))[0]
    t0 = time.perf_counter()
    obj = _file_part(target) if file_target else _model_part(target, args.set, console)
    sources = analysis.sample_sources(obj, tolerance)
    part = sources.part
    how = "exact normals and curvature" if part.exact else "mesh normals, discrete curvature"
    if part.degenerate.any():
        how += f", {count(int(part.degenerate.sum()), 'degenerate normal')} (limits)"
    console.out(f"{stem}: {count(part.n_vertices, 'sample')} on {count(len(part.triangles), 'triangle')} ({how})")
    os.makedirs(folder, exist_ok=True)

    def out(name):
        return os.path.join(folder, f"{stem}-{name}.png")

    if "zebra" in wanted:
        m = analysis.zebra(part, stripes=args.stripes, view=view)
        console.out(f"zebra: {args.stripes} stripe pairs -> {m.render(out('zebra'), size=size)}")
    if "isophotes" in wanted:
        m = analysis.isophotes(part, light, step=args.step)
        console.out(f"isophotes: light {_vec(light)}, every {args.step:g} deg -> {m.render(out('isophotes'), size=size, view=view)}")
    if "curvature" in wanted:
        m = analysis.curvature_map(part, args.curvature, scale=args.scale)
        finite = m.values[np.isfinite(m.values)]
        rng = f"[{finite.min():.4g}, {finite.max():.4g}]" if finite.size else "(none finite)"
        path = m.render(out(f"curvature-{args.curvature}"), size=size, view=view)
        console.out(f"curvature {args.curvature}: {rng} {m.unit} -> {path}")
    if "draft" in wanted:
        m = analysis.draft_angle(part, pull, min_draft=min_draft)
        path = m.render(out("draft"), size=size, view=view)
        console.out(f"draft for pull {_vec(pull)}: {100 * m.undercut.mean():.1f} % under-cut, "
                    f"{100 * m.insufficient.mean():.1f} % below {min_draft:g} deg (of the samples); "
                    f"range [{m.values.min():.2f}, {m.values.max():.2f}] deg -> {path}")
    if "deviation" in wanted:
        d = analysis.deviation(sources, scan)
        s = d.summary()
        maps = d.render(out("deviation"), size=size, view=view)
        hist = d.histogram(out("deviation-histogram"))
        console.out(f"deviation of {s['count']:,} points: max |d| {s['max']:.4g}, mean {s['mean']:+.4g}, "
                    f"RMS {s['rms']:.4g}, p95 |d| {s['p95']:.4g}, range [{s['max_inside']:+.4g}, {s['max_outside']:+.4g}]"
                    f" ({'exact' if d.exact else 'to the mesh'}) -> {maps}, {hist}")
    if "continuity" in wanted:
        _continuity(obj, console)
    if "combs" in wanted:
        curves, skipped = [], 0
        for curve in edge_curves(obj):  # a collapsed side (a pole) has no curvature: left out
            try:
                analysis.curvature_comb(curve, 8)
            except SplineKitError:
                skipped += 1
                continue
            curves.append(curve)
        if not curves:
            raise ParameterError("--combs found no edge curve with a curvature (all collapse to points)")
        combs = analysis.curvature_combs(curves)
        path = analysis.render_curvature_comb(combs, out("combs"), size=size, view=view,
                                              title=f"curvature combs of {count(len(combs), 'edge curve')}")
        k = max(float(np.abs(c.curvature).max()) for c in combs)
        left = f" ({count(skipped, 'collapsed curve')} left out)" if skipped else ""
        console.out(f"curvature combs: {count(len(combs), 'edge curve')}{left}, largest curvature {k:.4g} -> {path}")
    console.detail(f"analysed in {time.perf_counter() - t0:.2f} s")
    return 0


def _positive(text) -> float:
    try:
        value = float(text)
    except ValueError:
        value = np.nan
    if not (np.isfinite(value) and value > 0):
        raise ParameterError(f"--tolerance must be a positive number (model units), got {text!r}")
    return value


def _vec(v) -> str:
    return ",".join(f"{x:.3g}" for x in v)


def _continuity(obj, console: Console) -> None:
    """The continuity of every shared edge (``splinekit.analysis.shell_continuity``)."""
    shell_continuity = analysis.shell_continuity
    if isinstance(obj, PolyMesh):
        raise ParameterError("--continuity measures edges between exact faces or patches; a mesh has none")
    items = obj if isinstance(obj, list) and all(isinstance(o, (Shell, Solid)) for o in obj) else [obj]
    for item in items:
        result = shell_continuity(item)
        s = result.summary
        console.out(f"continuity: {s['edges']} shared edges (G2 {s['G2']}, G1 {s['G1']}, G0 {s['G0']}, none {s['none']}), "
                    f"{s['free_edges']} free; worst {s['worst']}; max gap {s['max_gap']:.3g}, "
                    f"max angle {np.degrees(s['max_angle']):.3g} deg, max curvature jump {s['max_curvature_jump']:.3g}")
        console.detail(result.table())


def edge_curves(obj) -> list:
    """The 3-D curves a part's edges run along: each B-rep edge once (its first use's curve; poles
    and edges without a 3-D curve left out), or the four boundary curves of every patch. A mesh
    has none (ParameterError)."""
    items = obj if isinstance(obj, (list, tuple)) else [obj]
    curves = []
    for item in items:
        if isinstance(item, PolyMesh):
            raise ParameterError("--combs draws the curvature of exact edge curves; a mesh has none")
        if isinstance(item, TrimmedFace):
            curves += [e.curve for e in item.edges if e.curve is not None and not e.degenerate]
            continue
        shells = item.shells if isinstance(item, Solid) else [item] if isinstance(item, Shell) else None
        if shells is not None:
            for shell in shells:
                for group in shell.edges:
                    f, lp, e = group.uses[0]
                    edge = shell.faces[f].boundary_loops()[lp][e]
                    if edge.curve is not None and not group.degenerate:
                        curves.append(edge.curve)
            continue
        patch = item.to_bspline() if not hasattr(item, "isocurve") else item  # Bézier patches
        (u0, u1), (v0, v1) = patch.domain
        curves += [patch.isocurve(u=u0), patch.isocurve(u=u1), patch.isocurve(v=v0), patch.isocurve(v=v1)]
    if not curves:
        raise ParameterError("--combs found no edge curves in this part")
    return curves
