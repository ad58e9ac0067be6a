"""The comparison itself: :func:`compare` holds one shape in every representation at several
resolutions, measures each, fits how memory and query time grow, and runs the operations."""

from __future__ import annotations

import math
import os
import tempfile
import time

import numpy as np

from .. import limits
from .._progress import progress
from .._validate import as_int
from ..errors import ParameterError, SplineKitError
from ..interop.booleans import difference
from .holders_implicit import AnalyticImplicit, NeuralImplicit, SDFGrid, neural_module
from .holders_mesh import SubdivisionCage, SubdivisionLimit, TriangleMesh
from .holders_surface import ExactPatches, PointCloud
from .measure import accuracy, query_times
from .operations import OPERATIONS, run_operation, second_body
from .shape import Reference, as_shape, torus
from .table import Table

__all__ = ["COLUMNS", "REPRESENTATIONS", "UNITS", "compare"]

REPRESENTATIONS = {cls.name: cls for cls in (ExactPatches, SubdivisionCage, SubdivisionLimit, TriangleMesh,
                                              PointCloud, SDFGrid, AnalyticImplicit, NeuralImplicit)}
"""Representation name -> holder class, in the order of the table."""

COLUMNS = ("representation", "resolution_name", "resolution", "bytes", "build_s", "query_s", "point_s",
           "inside_s", "closest_s", "normal_s", "inside_correct", "closest_error", "hausdorff", "mean_distance",
           "normal_angle", "volume_error", "genus", "note")
UNITS = {"bytes": "B", "build_s": "s", "query_s": "s/pt", "point_s": "s/pt", "inside_s": "s/pt", "closest_s": "s/pt",
         "normal_s": "s/pt", "closest_error": "units", "hausdorff": "units", "mean_distance": "units",
         "normal_angle": "deg"}


def _skip_reason(cls, shape) -> str | None:
    if cls is AnalyticImplicit and shape.implicit is None:
        return "no analytic implicit is known for this shape (there is one for the sphere and the torus)"
    if cls in (SubdivisionCage, SubdivisionLimit) and shape.subdivision is None:
        return "the shape has no subdivision cage (a cage is authored, not derived from patches)"
    if cls is NeuralImplicit:
        return neural_module()[1]
    return None


def _resolutions(names, given) -> dict:
    given = dict(given or {})
    unknown = [k for k in list(names) + list(given) if k not in REPRESENTATIONS]
    if unknown:
        raise ParameterError(f"unknown representation {unknown[0]!r}; known: {', '.join(REPRESENTATIONS)}")
    out = {}
    for name in names:
        values = given.get(name, REPRESENTATIONS[name].default_resolutions)
        values = [values] if np.isscalar(values) else list(values)
        if not values:
            raise ParameterError(f"representation {name!r} needs at least one resolution")
        smallest = 0 if REPRESENTATIONS[name].resolution_name == "levels" else None  # level 0 is the cage itself
        for v in values:
            number = isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool)
            if not (number and math.isfinite(v) and (v > 0 or v == smallest)):
                raise ParameterError(f"resolution {v!r} of {name!r} must be a finite number > 0 "
                                     f"({REPRESENTATIONS[name].resolution_name})")
        out[name] = values
    return out


def _growth_class(slope: float, fixed: bool) -> str:
    if fixed or abs(slope) < 0.3:
        return "O(parameters)" if fixed else "O(1)"
    half = round(2 * slope) / 2
    return f"O(N^{half:g})" if half != 1 else "O(N)"


def _growth(rows, floor: float) -> list:
    """One row per representation: log-log slopes of bytes and query time against the linear
    resolution N, with the complexity class they indicate, and of bytes against the Hausdorff
    distance (left out when a distance is within twice ``floor``, the reference's tolerance)."""
    out = []
    for name in dict.fromkeys(r["representation"] for r in rows):
        mine = [r for r in rows if r["representation"] == name and r.get("bytes")]
        row = {"representation": name, "rows": len(mine)}
        if len(mine) >= 2:
            N = np.log([r["_linear"] for r in mine])
            fixed = REPRESENTATIONS[name] is NeuralImplicit
            for key, col in (("bytes", "memory"), ("query_s", "query")):
                y = np.log([max(r[key], 1e-300) for r in mine])
                slope = float(np.polyfit(N, y, 1)[0]) if np.ptp(N) > 0 else 0.0
                row[f"{col}_slope"] = slope
                row[f"{col}_class"] = _growth_class(slope, fixed and key == "bytes")
            errs = [r["hausdorff"] for r in mine if r.get("hausdorff")]
            resolved = len(errs) == len(mine) and min(errs) > 2 * floor  # at the floor the error is the reference's
            if resolved and np.ptp(np.log(errs)) > 0:
                row["bytes_per_accuracy_slope"] = float(np.polyfit(np.log(errs), np.log([r["bytes"] for r in mine]), 1)[0])
        else:
            row["memory_class"] = "O(parameters)" if name == AnalyticImplicit.name else None
        out.append(row)
    return out


def compare(shape=None, *, representations=None, resolutions=None, samples: int = 2000, operations: bool = True,
            exact_boolean: bool = False, folder=None, seed: int = 0) -> Table:
    """Hold ``shape`` in every representation at several resolutions and measure each.

    Parameters
    ----------
    shape : Shape, list of patches, SubdivisionSurface or built model, optional
        A closed shape (:func:`~splinekit.comparison.as_shape`). Default: the torus of
        :func:`~splinekit.comparison.torus` (genus 1, exact patches and an analytic SDF); the
        ``splinekit compare`` command defaults to the mug model.
    representations : list of str, optional
        Names among :data:`REPRESENTATIONS` (default all); those that do not apply to the
        shape (no cage, no analytic implicit, the neural extra missing) get one row saying why.
    resolutions : dict, optional
        Representation name -> resolutions (each holder's ``default_resolutions`` otherwise).
    samples : int
        Exact sample points (and points per representation) of the accuracy measurement.
    operations : bool
        Also run :data:`OPERATIONS` at each representation's middle resolution.
    exact_boolean : bool
        Run the exact OCC boolean of the patches too (slow).
    folder : str, optional
        Where the pictures of the render operation go (default: a temporary folder, removed).

    Returns
    -------
    Table
        One row per representation and resolution, columns :data:`COLUMNS` (units :data:`UNITS`):
        ``bytes`` (the arrays held), ``build_s``, ``query_s`` (closest point, s per point) and
        the other query times, ``hausdorff``, ``mean_distance``, ``normal_angle``,
        ``volume_error`` (relative), ``genus``, ``note`` (why a row was skipped). Extra
        attributes: ``growth`` (a Table of log-log slopes and complexity classes per
        representation), ``operations`` (a Table: operation x representation),
        ``reference`` (the :class:`Reference`) and ``shape``.

    Raises ParameterError for an unknown representation or a bad resolution,
    ResourceLimitError before a resolution over the memory budget, NotManifoldError for an
    open shape.
    """
    shape = torus() if shape is None else as_shape(shape)
    samples = as_int(samples, "samples", minimum=50)
    names = list(representations) if representations is not None else list(REPRESENTATIONS)
    plan = _resolutions(names, resolutions)
    reference = Reference(shape, samples, seed)
    applicable = {name: _skip_reason(REPRESENTATIONS[name], shape) for name in names}
    for name, values in plan.items():  # every size is checked before any work
        if applicable[name] is None:
            for v in values:
                limits.check(REPRESENTATIONS[name].estimate_bytes(shape, reference, v), f"the {name} at resolution {v:g}")
    rng = np.random.default_rng(seed)
    rows, middle = [], {}
    total = sum(len(v) if applicable[k] is None else 1 for k, v in plan.items())
    with progress(total, "comparing representations") as bar:
        for name, values in plan.items():
            cls = REPRESENTATIONS[name]
            if applicable[name] is not None:
                rows.append({"representation": name, "resolution_name": cls.resolution_name, "note": applicable[name]})
                bar.advance()
                continue
            for i, value in enumerate(values):
                t0 = time.perf_counter()
                holder = cls(shape, reference, value)
                row = {"representation": name, "resolution_name": cls.resolution_name, "resolution": value,
                       "bytes": holder.nbytes, "build_s": time.perf_counter() - t0, "_linear": holder.linear}
                row.update(query_times(holder, reference, rng))
                row["query_s"] = row["closest_s"]
                row.update(accuracy(holder, reference, rng, samples))
                rows.append(row)
                if i == len(values) // 2:
                    middle[name] = holder
                bar.advance()
    table = Table(rows, COLUMNS, UNITS)
    table.growth = Table(_growth(rows, reference.tolerance))
    table.reference, table.shape = reference, shape
    table.operations = _operations(middle, names, applicable, reference, rng, folder, exact_boolean) if operations else None
    for r in table.rows:
        r.pop("_linear", None)
    return table


def _operations(middle, names, applicable, reference, rng, folder, exact_boolean) -> Table:
    cache = {}

    def expected_cut():
        if "v" not in cache:
            body = second_body(reference)
            cache["v"] = difference(reference.mesh, body.to_mesh(0.005 * reference.diagonal)).volume
        return cache["v"]

    cells = {op: {"operation": op} for op in OPERATIONS}
    details = []
    with tempfile.TemporaryDirectory(prefix="splinekit-compare-") as scratch:
        out = folder or scratch
        os.makedirs(out, exist_ok=True)
        for name in names:
            holder = middle.get(name)
            for op in OPERATIONS:
                if holder is None:
                    result = {"seconds": None, "error": None, "note": "n/a: not built (its row says why)"}
                else:
                    try:
                        result = run_operation(op, holder, reference, folder=out, rng=rng,
                                               exact_boolean=exact_boolean, expected_cut=expected_cut)
                    except SplineKitError as exc:  # an operation that fails on this representation says so
                        result = {"seconds": None, "error": None, "note": f"failed: {exc}"}
                cells[op][name] = _cell(result)
                details.append({"operation": op, "representation": name, **result})
    table = Table(cells.values(), ["operation"] + names)
    table.details = Table(details)
    return table


def _cell(result) -> str:
    if result["seconds"] is None:
        return result["note"]
    text = f"{result['seconds']:.3g} s"
    if result.get("error") is not None:
        text += f", error {result['error']:.2g}"
    return text
