"""The measures of a built model, as flat scalar columns of a sweep's results table.

Every figure is computed by splinekit without OpenCascade, the same way in a Dask worker as in
the caller's process, so a sweep's measures equal a serial :func:`measure` of
:func:`models.build_model` bit for bit.

Built-in measures (names for ``measures=`` / ``--measure``) and their columns:

* ``area`` (mm^2), ``volume`` (mm^3, NaN for a model that does not bound a solid),
  ``centroid`` (``centroid_x``, ``_y``, ``_z``, mm; of the enclosed solid, NaN when open or for a
  mesh-only model): adaptive quadrature of the exact faces
  (:meth:`splinekit.brep.Shell.mass_properties`), or the mesh's own figures;
* ``bbox`` (``bbox_min_x`` ... ``bbox_max_z``, mm): of the tessellation's vertices, which lie on
  the surfaces (the exact box is at most the tessellation's deviation larger);
* ``faces``: exact faces (patches plus trimmed faces), or the mesh's faces;
* ``triangles``: triangles of the tessellation a mesh export writes;
* ``valid``: splinekit's B-rep check finds no problem in any shell or solid (a mesh-only
  model: the mesh is closed when the model says it bounds a solid);
* ``checks``: the model's own reference values (``Model.checks``) against these measures:
  ``checks_ok`` and ``checks_failed`` (the failing names with measured and expected values).

``build_time`` (seconds) is always recorded, by the task that builds the model.
"""

from __future__ import annotations

import math

import numpy as np

from splinekit.brep import Shell, TrimmedFace
from splinekit.errors import ParameterError
from splinekit.tessellation.bodies import model_mesh, solids_of

__all__ = ["MEASURES", "MESH_MEASURES", "measure", "user_columns"]

MEASURES = ("area", "volume", "centroid", "bbox", "faces", "triangles", "valid", "checks")
MESH_MEASURES = frozenset({"bbox", "triangles", "checks"})
"""Measures that need the tessellation (checks: the Euler characteristic is the mesh's)."""
_NAN = float("nan")


def _exact_pieces(model) -> list:
    """The model's closed or open B-rep pieces: one Shell per patch set, then its solids."""
    shells = [Shell([TrimmedFace(p) for p in body]) for body in model.bodies]
    return shells + solids_of(model)


def _mass(model, pieces, mesh) -> dict:
    """Area, volume and centroid columns."""
    if not pieces:  # a mesh-only model
        mesh = model.mesh
        closed = bool(model.closed and mesh.is_closed)
        return {"area": float(mesh.area), "volume": float(mesh.volume) if closed else _NAN,
                "centroid_x": _NAN, "centroid_y": _NAN, "centroid_z": _NAN}
    props = [p.mass_properties() for p in pieces]
    area = math.fsum(m.area for m in props)
    if not model.closed:
        return {"area": area, "volume": _NAN, "centroid_x": _NAN, "centroid_y": _NAN, "centroid_z": _NAN}
    volumes = np.array([m.volume for m in props])
    volume = float(volumes.sum())
    centroid = (volumes @ np.array([m.centroid for m in props])) / volume
    return {"area": area, "volume": volume, "centroid_x": float(centroid[0]),
            "centroid_y": float(centroid[1]), "centroid_z": float(centroid[2])}


def _valid(model, pieces) -> bool:
    if not pieces:
        return bool(model.mesh.is_closed) if model.closed else True
    return all(not piece.check() for piece in pieces)


def _checks(model, measured: dict) -> dict:
    """``checks_ok`` / ``checks_failed`` of ``model.checks`` against the measured values; a check
    whose quantity is not measured here counts as failed, so that a passing row means every
    reference was met."""
    failed = []
    for name, (expected, tol) in (model.checks or {}).items():
        value = measured.get(name)
        if value is None or not np.isfinite(value) or abs(value - expected) > tol:
            failed.append(f"{name} {value!r} vs {expected!r} +- {tol:g}")
    return {"checks_ok": not failed, "checks_failed": "; ".join(failed)}


def measure(model, names=MEASURES, *, tolerance=None, mesh=None) -> dict:
    """The columns of the built-in measures ``names`` of ``model`` (see the module docstring).

    ``tolerance`` is the chordal tolerance of the tessellation (model units; default as
    ``splinekit build``); ``mesh`` is that tessellation when the caller already made it.
    """
    unknown = [n for n in names if n not in MEASURES]
    if unknown:
        raise ParameterError(f"unknown measure {unknown[0]!r}; built-in measures: {', '.join(MEASURES)}")
    wanted = set(names)
    if "checks" in wanted:  # the references are compared with these
        wanted |= {"area", "volume", "faces"}
    pieces = _exact_pieces(model)
    out: dict = {}
    if wanted & {"area", "volume", "centroid"}:
        out.update(_mass(model, pieces, mesh))
    if "faces" in wanted:
        out["faces"] = sum(len(p.faces) for p in pieces) if pieces else int(model.mesh.n_faces)
    if wanted & MESH_MEASURES:
        if mesh is None:
            mesh, _ = model_mesh(model, tolerance)
        if "triangles" in wanted:
            out["triangles"] = int((np.asarray(mesh.topology.face_sizes) - 2).sum())
        if "bbox" in wanted:
            lo, hi = mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)
            out.update({f"bbox_{end}_{axis}": float(v[k]) for end, v in (("min", lo), ("max", hi))
                        for k, axis in enumerate("xyz")})
        out["euler_characteristic"] = int(mesh.euler_characteristic)
    if "valid" in wanted:
        out["valid"] = _valid(model, pieces)
    if "checks" in names:
        out.update(_checks(model, out))
    return {k: v for k, v in out.items() if _asked(k, names)}


def _asked(column: str, names) -> bool:
    """Whether ``column`` belongs to one of the measures ``names`` (helpers computed for the
    checks are dropped unless asked for)."""
    base = column.split("_")[0] if column.startswith(("centroid_", "bbox_", "checks_")) else column
    return base in names


def user_columns(name: str, value) -> dict:
    """The columns of a user measure's result: a number, bool or string is one column ``name``;
    a dict gives one column ``name.key`` per entry. ParameterError for anything else."""
    if isinstance(value, dict):
        out = {}
        for key, item in value.items():
            out.update(user_columns(f"{name}.{key}", item))
        return out
    if isinstance(value, np.generic):
        value = value.item()
    if value is None or isinstance(value, (bool, int, float, str)):
        return {name: value}
    raise ParameterError(f"measure {name!r} returned a {type(value).__name__}; a measure returns a number, "
                         "a bool, a string or a dict of those")
