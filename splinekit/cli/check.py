"""``splinekit check``: cross-check models against OpenCascade and against their own stated
references, with tolerances no looser than the geometry allows.

- Point evaluation: splinekit and OCC evaluate the same control nets in float64; they agree to
  :data:`POINT_RTOL` of the largest coordinate (a few thousand units in the last place).
- Exact solids: splinekit's mass properties (adaptive quadrature to relative 1e-10, with an error
  estimate) against OCC's GProp (precision 1e-10) on the same solids, within :data:`MASS_RTOL`;
  where a face has a pole or collapsed edge, GProp's drift to a finer precision widens that, up
  to :data:`CATCH_RTOL` (so a 1e-6 error always fails). Patch sets: OCC's GProp where no patch
  has a pole, scipy's cubature where one has (:func:`splinekit.interop.gprop.reference_integrals`).
  Each row's note names the reference used and why.
- Meshes: a tessellation's volume differs from the exact one by at most its area times its
  largest deviation from the surfaces (the tessellation's own bound).
- Model checks (``model.checks``): the tolerance each model states with its reference values.
  The ``genus`` measure is that of the watertight tessellation
  (:func:`splinekit.mesh.components.genus`, handles summed over the pieces). The
  ``euler_characteristic`` of patch sets is that of OCC's sewn topology counted as B-rep topology
  counts it (:func:`splinekit.interop.gprop.occ_euler_characteristic`: degenerate edges at poles
  and collapsed sides are points, a seam is one edge, inner wires are holes), so a sphere is 2
  and a torus 0 whether their faces close on themselves or not.
"""

from __future__ import annotations

import time

import numpy as np

from .._progress import progress
from ..brep.crosscheck import singular_patches
from ..errors import ParameterError, SplineKitError
from ..interop.gprop import (
    OCC_PRECISION,
    is_valid,
    occ_area,
    occ_euler_characteristic,
    occ_volume,
    point_deviation,
    reference_integrals,
    topology_counts,
)
from ..interop.occ import to_occ, to_shape
from ..mesh.components import genus
from ..tessellation import tessellate
from .console import Console, count, table, value_text
from .registry import build_model, model_mesh, model_names, params_text, patches_of, registry, solids_of

POINT_RTOL = 1e-12
"""Largest distance between splinekit's and OCC's points, relative to the largest control-point
coordinate (measured: below 1e-15 on every model)."""

MASS_RTOL = 1e-8
"""Largest relative difference between splinekit's and OCC's area and volume of exact solids.
Both integrate adaptively to 1e-10 relative, but GProp's precision is a stopping threshold, not a
bound: on the block model its volume is 1.4e-9 away from splinekit's (and splinekit's error
estimate is below 1e-10), so 1e-8 is the tightest bound that OCC keeps."""


CATCH_RTOL = 5e-7
"""The loosest relative tolerance an integral comparison may take: a 1e-6 relative error in
splinekit's (or a model's stated) area or volume must still fail."""


def closed_genus(meshes) -> float | None:
    """Handles of the closed ``meshes`` (a sequence of PolyMesh), summed; None when one of
    them is open (the genus of a surface with a boundary is not what a model states)."""
    counts = [genus(m) for m in meshes]
    return None if not counts or any(g is None for g in counts) else float(sum(counts))


class Checks:
    """Rows of the check table: name, measured, expected, tolerance, PASS/FAIL/SKIP, note."""

    def __init__(self):
        self.rows = []

    def compare(self, name, measured, expected, tol, note=""):
        ok = measured is not None and np.isfinite(measured) and abs(measured - expected) <= tol
        self.rows.append([name, value_text(measured), value_text(expected), value_text(tol), "PASS" if ok else "FAIL", note])

    def truth(self, name, ok, note=""):
        self.rows.append([name, "yes" if ok else "no", "yes", "", "PASS" if ok else "FAIL", note])

    def skip(self, name, note):
        self.rows.append([name, "", "", "", "SKIP", note])

    @property
    def failed(self) -> int:
        return sum(r[4] == "FAIL" for r in self.rows)


def _check_bodies(model, table_: Checks, measures: dict) -> dict:
    """Checks and measures of a model made of exact patch sets, sewn by OCC; returns the note
    on the source of each measure."""
    patches = patches_of(model)
    shapes = []
    with progress(len(model.bodies), "sewing") as bar:
        for i, body in enumerate(model.bodies):
            label = model.body_names[i] if i < len(model.body_names) else f"body {i}"
            try:
                shapes.append(to_shape(list(body)))
                table_.truth(f"{label}: OCC sews a valid shape", True)
            except SplineKitError as exc:
                table_.truth(f"{label}: OCC sews a valid shape", False, str(exc).splitlines()[0][:120])
            bar.advance()
    counts = [topology_counts(s) for s in shapes]
    if model.closed:
        for i, c in enumerate(counts):
            table_.truth(f"body {i} is a closed solid", c["SOLID"] >= 1, f"{c['SOLID']} solid(s)")
    measures["faces"] = sum(c["FACE"] for c in counts)
    # area and volume: an independent reference (OCC's GProp where reliable, else scipy)
    sewn = shapes if len(shapes) == len(model.bodies) else None
    reference = reference_integrals(model.bodies, closed=model.closed, shapes=sewn)
    measures["area"], measures["volume"] = reference.area, reference.volume
    measures["euler_characteristic"] = sum(occ_euler_characteristic(s) for s in shapes)
    measures["genus"] = None
    largest = float(np.abs(np.concatenate([np.asarray(p.control_points).reshape(-1, 3) for p in patches])).max())
    worst, n_points = point_deviation(patches)
    table_.compare(f"point deviation vs OCC ({n_points} points)", worst, 0.0, POINT_RTOL * max(largest, 1.0),
                   "splinekit vs Geom_Surface.Value")
    if model.closed:
        meshes = [tessellate(list(b)) for b in model.bodies]
        closed = all(m.is_closed for m in meshes)
        table_.truth("tessellation is closed", closed)
        measures["genus"] = closed_genus(meshes)
        if closed and reference.volume is not None:
            volume = sum(float(m.volume) for m in meshes)
            bound = sum(float(m.area) * float(m.max_deviation) for m in meshes)
            measures["tessellation"] = (volume, reference.volume, max(bound, 1e-12))
    source = f"{reference.source} ({reference.reason})"
    return {"area": source, "volume": source, "faces": "OCC faces",
            "euler_characteristic": "OCC topology V - E + F - (W - F), degenerate edges left out",
            "genus": "tessellation genus"}


def _solid_reference(shapes, singular) -> tuple[float, float, float, str]:
    """``(area, volume, relative tolerance, note)``: OCC's GProp of the solids' ``shapes`` as the
    reference for splinekit's integrals.

    Where no face has a pole or collapsed edge OCC matches closed forms to ~1e-13 and the tolerance
    is :data:`MASS_RTOL`. Otherwise GProp may drift (see :mod:`splinekit.interop.gprop`) and
    there is no second integrator for trimmed faces: GProp is run again at a precision 100 times
    finer and the tolerance widened by twice the drift between the two runs, but never past
    :data:`CATCH_RTOL` (beyond that the comparison is reported as skipped, naming the drift)."""
    area, volume = sum(occ_area(s) for s in shapes), sum(occ_volume(s) for s in shapes)
    if not singular:
        return area, volume, MASS_RTOL, f"OCC GProp {OCC_PRECISION:g} (no collapsed edges or poles)"
    fine = OCC_PRECISION * 1e-2
    area2, volume2 = sum(occ_area(s, fine) for s in shapes), sum(occ_volume(s, fine) for s in shapes)
    drift = max(abs(area - area2) / max(abs(area2), 1e-300), abs(volume - volume2) / max(abs(volume2), 1e-300))
    i, j, why = singular[0]
    note = (f"OCC GProp {OCC_PRECISION:g}, may drift ({why}: solid {i} face {j}); "
            f"tolerance widened by twice its drift to {fine:g} ({drift:.1e})")
    return area2, volume2, MASS_RTOL + 2.0 * drift, note


def _check_solids(model, table_: Checks, measures: dict) -> dict:
    """Checks and measures of a model's exact B-rep solids: OCC's validity, splinekit's area and
    volume against OCC's GProp on the same solids (:func:`_solid_reference`), and the
    tessellation (closed, its volume within its bound, its Euler characteristic ``2 - 2 genus``)."""
    solids = solids_of(model)
    shapes = []
    for i, solid in enumerate(solids):
        label = solid.name or f"solid {i}"
        try:
            shape = to_occ(solid)
        except SplineKitError as exc:
            table_.truth(f"{label}: OCC calls it a valid solid", False, str(exc).splitlines()[0][:120])
            continue
        valid = is_valid(shape)
        table_.truth(f"{label}: OCC calls it a valid solid", valid, "BRepCheck_Analyzer")
        if valid:  # GProp of an invalid shape means nothing; the comparison below then fails
            shapes.append(shape)
    measures["faces"] = sum(len(s.faces) for s in solids)
    measures["area"] = sum(s.area() for s in solids)
    measures["volume"] = sum(s.volume() for s in solids)
    singular = [(i, j, why) for i, s in enumerate(solids) for j, why in singular_patches([f.surface for f in s.faces])]
    occ_area_total, occ_volume_total, rtol, note = _solid_reference(shapes, singular)
    for kind, ours, theirs in (("area", measures["area"], occ_area_total), ("volume", measures["volume"], occ_volume_total)):
        if rtol > CATCH_RTOL:
            table_.skip(f"{kind}: splinekit vs OCC", f"{note}: too loose to judge")
        else:
            table_.compare(f"{kind}: splinekit vs OCC", ours, theirs, rtol * abs(theirs), note)
    mesh, deviation = model_mesh(model)
    table_.truth("tessellation is closed", bool(mesh.is_closed))
    measures["euler_characteristic"] = mesh.euler_characteristic
    measures["genus"] = closed_genus([mesh])  # the solids' meshes are joined unwelded: one piece each
    if mesh.is_closed:
        bound = float(mesh.area) * float(deviation or 0.0)
        measures["tessellation"] = (float(mesh.volume), measures["volume"], max(bound, 1e-12))
    return ({key: f"splinekit {key}" for key in ("area", "volume", "faces")}
            | {"euler_characteristic": "tessellation V - E + F", "genus": "tessellation genus"})


def _check_mesh(model, table_: Checks, measures: dict) -> dict:
    mesh = model.mesh
    if mesh is None:
        raise ParameterError(f"model '{model.name}' has neither exact bodies nor a mesh to check")
    if model.closed:
        table_.truth("mesh is closed", bool(mesh.is_closed))
    measures["faces"] = mesh.n_faces
    measures["area"] = float(mesh.area)
    measures["volume"] = float(mesh.volume) if mesh.is_closed else None
    measures["euler_characteristic"] = mesh.euler_characteristic
    measures["genus"] = closed_genus([mesh])
    return {key: f"mesh {key}" for key in measures}


def _model_checks(model, table_: Checks, measures: dict, sources: dict) -> None:
    """The model's own reference values (``model.checks``) against the measures."""
    for key, value in (model.checks or {}).items():
        try:
            expected, tol = value
            expected, tol = float(expected), float(tol)
        except (TypeError, ValueError):
            table_.skip(key, f"malformed check {value!r}; expected (value, tolerance)")
            continue
        measure = next((m for m in measures if key == m or key.startswith(m)), None)
        if measure is None:
            table_.skip(key, "no measure of that name (known: " + ", ".join(measures) + ")")
        elif measures[measure] is None:
            table_.compare(key, None, expected, tol, "no closed solid to measure")
        else:
            table_.compare(key, measures[measure], expected, tol, sources.get(measure, measure))


def check_model(reg, name, sets, console: Console) -> int:
    """Print the check table of model ``name``; returns the number of failed checks."""
    t0 = time.perf_counter()
    model = build_model(reg, name, sets, console)
    table_ = Checks()
    measures = {}
    if model.bodies:
        sources = _check_bodies(model, table_, measures)
    elif solids_of(model):
        sources = _check_solids(model, table_, measures)
    else:
        sources = _check_mesh(model, table_, measures)
    tessellation = measures.pop("tessellation", None)
    _model_checks(model, table_, measures, sources)
    if tessellation is not None:
        reference = "exact" if solids_of(model) and not model.bodies else "reference"
        table_.compare(f"tessellation volume vs {reference}", *tessellation, "within area x max deviation")
    n_faces = len(patches_of(model)) + sum(len(s.faces) for s in solids_of(model))
    console.out(f"check {name}" + (f" ({params_text(model)})" if model.params else "") + f": {count(n_faces, 'exact face')}"
                + (f", mesh of {count(model.mesh.n_faces, 'face')}" if model.mesh is not None else ""))
    console.out(table(table_.rows, ["check", "measured", "expected", "tolerance", "result", "note"]))
    n_fail = table_.failed
    console.out(f"{len(table_.rows) - n_fail} of {len(table_.rows)} passed or skipped, {n_fail} failed "
                f"({time.perf_counter() - t0:.2f} s)")
    console.out()
    return n_fail


def cmd_check(args, console: Console) -> int:
    reg = registry()
    names = model_names(reg, args)
    failed = []
    with progress(len(names), "checking models", show=len(names) > 1) as bar:
        for name in names:
            if check_model(reg, name, args.set, console):
                failed.append(name)
            bar.advance()
    if len(names) > 1:
        console.out(f"{len(names) - len(failed)} of {len(names)} models pass" + (f"; failed: {', '.join(failed)}" if failed else ""))
    return 1 if failed else 0
