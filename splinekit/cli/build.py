"""``splinekit build``: build models and write them as exact STEP and as meshes, then say what
each written file holds (read back from the file for STEP: solids, shells, faces)."""

from __future__ import annotations

import os
import time

import numpy as np

import exporters
from exporters.step import read_step_shape

from .._atomic import checked_path
from .._progress import progress
from ..errors import ParameterError
from ..interop.gprop import occ_area, occ_volume, topology_counts
from .console import Console, count, measure_text, size_text
from .registry import build_model, model_mesh, model_names, params_text, patches_of, registry, solids_of

FORMATS = ("step", "stl", "3mf", "obj", "glb", "ply")
"""File formats ``build`` writes: exact STEP, or a tessellation in a mesh format."""
MESH_FORMATS = FORMATS[1:]
TRIANGLE_FORMATS = ("stl", "3mf", "glb")
"""Mesh formats that hold triangles only: their writers fan-triangulate polygons."""
DEFAULT_FORMATS = "step,stl"
DEFAULT_OUTPUT = "out"
"""Folder ``build`` writes into without ``-o`` (created if missing)."""


def parse_formats(text) -> list:
    """``--format`` as a list of distinct formats among :data:`FORMATS` (``stp`` is ``step``)."""
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


def parse_tolerance(text):
    """``--tolerance`` as a positive finite float, or None when not given."""
    if text is None:
        return None
    try:
        value = float(text)
    except ValueError:
        raise ParameterError(f"--tolerance must be a positive number (model units), got {text!r}") from None
    if not (np.isfinite(value) and value > 0):
        raise ParameterError(f"--tolerance must be a positive number (model units), got {text!r}")
    return value


def mesh_file_text(mesh, fmt: str, deviation) -> str:
    """What the mesh file of format ``fmt`` holds: triangles (polygons fan-triangulated into
    ``k - 2`` triangles in the triangle-only formats) or the mesh's own faces."""
    sizes = np.asarray(mesh.topology.face_sizes)
    if fmt in TRIANGLE_FORMATS or mesh.is_triangle_mesh:
        text = count(int((sizes - 2).sum()), "triangle")
    else:
        text = count(mesh.n_faces, "quad" if mesh.is_quad_mesh else "polygon")
    return text + (f" (max deviation {deviation:.3g})" if deviation is not None else "")


def step_file_text(counts: dict) -> str:
    """What a STEP file holds by OCC's count of its distinct solids, shells and faces."""
    return ", ".join([count(counts["SOLID"], "solid"), count(counts["SHELL"], "shell"), count(counts["FACE"], "face")])


def build_and_export(reg, name, sets, formats, tolerance, out_dir, strict, console: Console) -> None:
    """Build model ``name``, write it in ``formats`` to ``out_dir`` and print the summary.

    A mesh-only model cannot be STEP: with ``strict`` (formats asked for
    explicitly) that is an error, otherwise STEP is skipped with a note.
    """
    t0 = time.perf_counter()
    model = build_model(reg, name, sets, console)
    t_build = time.perf_counter() - t0
    formats = list(formats)
    solids = solids_of(model)
    if not model.bodies and not solids and "step" in formats:
        if strict:
            raise ParameterError(f"model '{name}' exists only as a mesh (no exact surfaces): it cannot be written as STEP")
        formats.remove("step")
        console.out(f"note: model '{name}' exists only as a mesh; no STEP file written")
    mesh = deviation = step_shape = None
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
                # what the file holds, as a reader sees it; the file is ours, so read in-process
                step_shape = read_step_shape(path, isolated=False)
                holds = step_file_text(topology_counts(step_shape))
            else:
                exporters.export_mesh(path, mesh, format=fmt)
                holds = mesh_file_text(mesh, fmt, deviation)
            written.append((path, holds))
            console.detail(f"wrote {path} in {time.perf_counter() - t1:.2f} s")
            bar.advance()
    head = f"{name} ({params_text(model)})" if model.params else name
    if solids:
        what = [count(len(solids), "exact solid"), count(sum(len(s.faces) for s in solids), "trimmed face")]
    elif model.bodies:
        what = [count(len(patches_of(model)), "exact face"), count(len(model.bodies), "patch set")]
    else:
        what = [f"mesh only, {count(model.mesh.n_faces, 'face')}"]
    console.out(f"{head}: {', '.join(what)}")
    for path, holds in written:
        console.out(f"  wrote {path}  {size_text(os.path.getsize(path))}: {holds}")
    if solids and not model.bodies:
        volume, area = sum(s.volume() for s in solids), sum(s.area() for s in solids)
        console.out(f"  volume {volume:.10g}, area {area:.10g} (exact, splinekit.brep mass properties)")
    elif model.bodies and model.closed and step_shape is not None:
        console.out(f"  volume {occ_volume(step_shape):.10g}, area {occ_area(step_shape):.10g} "
                    "(exact, OCC GProp of the written STEP)")
    elif mesh is not None and mesh.is_closed:
        console.out(f"  volume {measure_text(lambda: mesh.volume, '.8g')}, area {measure_text(lambda: mesh.area, '.8g')} (mesh)")
    elif mesh is not None:
        console.out(f"  area {measure_text(lambda: mesh.area, '.8g')} (mesh; open surface, no volume)")
    console.out(f"  built in {t_build:.2f} s, total {time.perf_counter() - t0:.2f} s")


def cmd_build(args, console: Console) -> int:
    reg = registry()
    formats = parse_formats(args.format)
    tolerance = parse_tolerance(args.tolerance)
    names = model_names(reg, args)
    out_dir = checked_path(args.output or DEFAULT_OUTPUT)  # a NUL byte is a ParameterError, not a ValueError from os
    if os.path.exists(out_dir) and not os.path.isdir(out_dir):
        raise ParameterError(f"output folder {out_dir!r} exists and is not a folder")
    strict = args.format is not None and len(names) == 1
    with progress(len(names), "building models", show=len(names) > 1) as bar:
        for name in names:
            build_and_export(reg, name, args.set, formats, tolerance, out_dir, strict, console)
            bar.advance()
    return 0
