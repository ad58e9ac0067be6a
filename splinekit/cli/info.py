"""``splinekit info FILE``: what an exact B-rep file (STEP, IGES, OCC .brep) or a mesh file holds.

Exact files are measured twice, independently: by OpenCascade (the file as OCC reads it, GProp
integrals) and by splinekit (the file read into :mod:`splinekit.brep` solids, shells and faces,
mass properties by splinekit's own adaptive quadrature); the two are printed side by side with
their relative difference.
"""

from __future__ import annotations

import os

import numpy as np

import exporters
from exporters.brep import read_brep_shape
from exporters.iges import read_iges_shape
from exporters.step import read_step_shape

from ..brep import Shell, Solid, TrimmedFace
from ..errors import FileFormatError, SplineKitError
from ..interop.gprop import (
    OCC_PRECISION,
    face_kinds,
    is_valid,
    occ_area,
    occ_bbox,
    occ_volume,
    topology_counts,
    trimmed_face_count,
)
from ..mesh.components import face_components, genus
from .console import Console, bbox_text, first_line, measure_text

MESH_SUFFIXES = (".stl", ".obj", ".ply", ".3mf", ".glb")
STEP_SUFFIXES = (".step", ".stp")
EXACT_SUFFIXES = STEP_SUFFIXES + (".iges", ".igs", ".brep")
"""Exact B-rep files ``info`` reads."""

# suffix -> (format name, reader of the OCC shape, reader into splinekit B-rep items)
_EXACT_READERS = {
    ".step": ("STEP", read_step_shape, exporters.import_step),
    ".stp": ("STEP", read_step_shape, exporters.import_step),
    ".iges": ("IGES", read_iges_shape, exporters.import_iges),
    ".igs": ("IGES", read_iges_shape, exporters.import_iges),
    ".brep": ("BREP", read_brep_shape, exporters.import_brep),
}


def read_exact_shape(path):
    """``(format name, OCC shape)`` of a STEP, IGES or OCC .brep file (by its suffix)."""
    fmt, read_shape, _ = _EXACT_READERS[os.path.splitext(path)[1].lower()]
    return fmt, read_shape(path)


def brep_measures(path) -> tuple[float, float | None]:
    """``(area, volume or None)`` of an exact file read into splinekit B-rep objects: the area
    of every solid, shell and face, the volume of the solids (None without a solid)."""
    _, _, read_items = _EXACT_READERS[os.path.splitext(path)[1].lower()]
    geometry = [item.geometry for item in read_items(path)]
    area = sum(g.area() for g in geometry if isinstance(g, (Solid, Shell, TrimmedFace)))
    solids = [g for g in geometry if isinstance(g, Solid)]
    return float(area), (float(sum(s.volume() for s in solids)) if solids else None)


def _difference_text(ours: float, theirs: float) -> str:
    scale = max(abs(ours), abs(theirs))
    relative = abs(ours - theirs) / scale if scale > 0 else 0.0
    return f"splinekit.brep {ours:.10g} (relative difference {relative:.1e})"


def info_exact(path, console: Console) -> int:
    fmt, shape = read_exact_shape(path)
    counts = topology_counts(shape)
    console.out(f"{path}: {fmt}, {counts['SOLID']} solids, {counts['SHELL']} shells, {counts['FACE']} faces, "
                f"{counts['EDGE']} edges, {counts['VERTEX']} vertices")
    trimmed = trimmed_face_count(shape)
    console.out(f"  faces: {trimmed} trimmed, {counts['FACE'] - trimmed} untrimmed; "
                f"valid (OCC BRepCheck): {'yes' if is_valid(shape) else 'NO'}")
    for kind, n in sorted(face_kinds(shape).items(), key=lambda kv: -kv[1]):
        console.out(f"  {n:5d} x {kind}")
    lo, hi = occ_bbox(shape)
    console.out(f"  bounding box {bbox_text(lo, hi)}")
    try:
        ours_area, ours_volume = brep_measures(path)
    except SplineKitError as exc:  # OCC reads it, splinekit's reader refuses a face: say so, keep OCC's figures
        ours_area = ours_volume = None
        console.out(f"  splinekit.brep does not read it: {first_line(exc)}")
    source = f"(OCC GProp {OCC_PRECISION:g})"
    area = occ_area(shape)
    console.out(f"  area   {area:.10g}  {source}" + (f"; {_difference_text(ours_area, area)}" if ours_area is not None else ""))
    if counts["SOLID"]:
        volume = occ_volume(shape)
        console.out(f"  volume {volume:.10g}  {source}"
                    + (f"; {_difference_text(ours_volume, volume)}" if ours_volume is not None else ""))
    else:
        console.out("  volume -- (no solid)")
    return 0


def info_mesh(path, console: Console) -> int:
    mesh = exporters.import_mesh(path)
    V = np.asarray(mesh.vertices)
    closed = bool(mesh.is_closed)
    pieces, _ = face_components(mesh)
    g = genus(mesh)
    kind = "triangles" if mesh.is_triangle_mesh else ("quads" if mesh.is_quad_mesh else "polygons")
    fmt = os.path.splitext(path)[1].lstrip(".").upper()
    console.out(f"{path}: {fmt} mesh, {mesh.n_vertices} vertices, {mesh.n_faces} faces ({kind}), {pieces} component(s)")
    console.out(f"  closed {'yes' if closed else 'no'}, Euler characteristic {mesh.euler_characteristic}"
                + (f", genus {g:g}" if g is not None else ""))
    if len(V):
        console.out(f"  bounding box {bbox_text(V.min(0), V.max(0))}")
    console.out(f"  area   {measure_text(lambda: mesh.area, '.10g')}")
    console.out(f"  volume {measure_text(lambda: mesh.volume, '.10g')}" if closed else "  volume -- (open mesh)")
    return 0


def cmd_info(args, console: Console) -> int:
    path = args.file
    if not os.path.isfile(path):
        raise FileFormatError(f"{path!r} does not exist or is not a file")
    suffix = os.path.splitext(path)[1].lower()
    if suffix in EXACT_SUFFIXES:
        return info_exact(path, console)
    if suffix in MESH_SUFFIXES:
        return info_mesh(path, console)
    raise FileFormatError(f"cannot tell the format of {path!r}; expected a suffix among {', '.join(EXACT_SUFFIXES + MESH_SUFFIXES)}")
