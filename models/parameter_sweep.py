"""Parameter sweeps of a model on Dask: every variant built, checked, measured and exported in
its own task (:mod:`splinekit.batch` runs them), the measures gathered into one table.

This is the model-facing half of :func:`splinekit.sweep`: it sits beside the models because it
builds them and writes their files through ``exporters``, which the splinekit library below it
may not import; splinekit finds it through the model registry (:func:`models.sweep`, which looks
a model name up and calls :func:`sweep` here).

Example (in a script, under ``if __name__ == "__main__":``: the local cluster's workers are
spawned processes that import the script's main module again)::

    import splinekit as sk

    table = sk.sweep("vase", {"height": [100, 200, 300], "wall": [2, 3]},
                     measures=["volume", "area"], formats=["step", "stl"], out="sweep")

On a cluster: start ``dask scheduler --port 8786`` on one machine and ``dask worker
tcp://HOST:8786 --nthreads 1 --nworkers N`` on every machine that has splinekit installed, then
pass ``scheduler="tcp://HOST:8786"`` (``--scheduler``) and ``files=`` a folder every worker can
write (a shared one, to collect the files in one place).
"""

from __future__ import annotations

import hashlib
import inspect
import json
import os
import time
from dataclasses import dataclass

import exporters
import splinekit
from splinekit._atomic import checked_path
from splinekit.batch import CONNECT_TIMEOUT, DEFAULT_MAX_VARIANTS, plot_measure, run, variant_key, variants
from splinekit.errors import ParameterError, SplineKitError
from splinekit.tessellation.bodies import model_mesh, solids_of

from ._base import resolve_params
from .measures import MEASURES, MESH_MEASURES, measure, user_columns

__all__ = ["FORMATS", "MEASURES", "VariantTask", "model_version", "sweep"]

FORMATS = ("step", "stl", "3mf", "obj", "glb", "ply")
"""File formats a sweep can write per variant: exact STEP, or the tessellation as a mesh."""


def _model_name(module) -> str:
    """The registry name of a model module: its ``NAME``, else the last part of its module name."""
    return str(getattr(module, "NAME", None) or getattr(module, "__name__", "model").rsplit(".", 1)[-1])


def model_version(module) -> str:
    """What identifies the model's code: its ``VERSION`` if it states one, else splinekit's
    version and a hash of the model module's source, so that editing a model rebuilds its
    variants on resume."""
    stated = getattr(module, "VERSION", None)
    if stated is not None:
        return str(stated)
    try:
        source = inspect.getsource(module)
    except (OSError, TypeError):
        source = repr(getattr(module, "PARAMETERS", ""))
    return f"{splinekit.__version__}+{hashlib.sha256(source.encode()).hexdigest()[:12]}"


def _formats(formats) -> tuple:
    if formats is None:
        return ()
    items = formats.split(",") if isinstance(formats, str) else list(formats)
    wanted = ["step" if f == "stp" else f for f in (str(x).strip().lower().lstrip(".") for x in items) if f]
    for f in wanted:
        if f not in FORMATS:
            raise ParameterError(f"unknown format {f!r}; choose from {', '.join(FORMATS)}")
    return tuple(dict.fromkeys(wanted))


def _measures(measures) -> tuple[tuple, tuple]:
    """``(built-in names, ((name, function), ...))`` from ``measures``: None (every built-in), a
    comma-separated string, a list of names and functions, or a dict name -> function."""
    if measures is None:
        return MEASURES, ()
    if isinstance(measures, str):
        measures = [m.strip() for m in measures.split(",") if m.strip()]
    items = list(measures.items()) if isinstance(measures, dict) else [
        (m, None) if isinstance(m, str) else (getattr(m, "__name__", "measure"), m) for m in measures]
    names, user = [], []
    for name, func in items:
        if func is None:
            if name not in MEASURES:
                raise ParameterError(f"unknown measure {name!r}; built-in measures: {', '.join(MEASURES)} "
                                     "(or pass a function of the built model)")
            names.append(name)
        elif callable(func):
            user.append((str(name), func))
        else:
            raise ParameterError(f"measure {name!r} is a {type(func).__name__}, not a function of the built model")
    return tuple(dict.fromkeys(names)), tuple(user)


@dataclass(frozen=True)
class VariantTask:
    """Build one variant, measure it and write its files: the task each Dask worker runs.

    Picklable by reference: ``build`` is a model module's function. Called with the variant's
    parameters (every one, defaults filled in), returns its columns: ``build_time`` (s), the
    measures, and ``file_<format>`` (path of each file written, in ``files``).
    """

    name: str
    build: object
    version: str
    measures: tuple = MEASURES
    user: tuple = ()
    formats: tuple = ()
    files: str = ""
    tolerance: float | None = None

    def __call__(self, params: dict) -> dict:
        start = time.perf_counter()
        model = self.build(**params)
        figures = {"build_time": time.perf_counter() - start}
        mesh = None
        if any(f != "step" for f in self.formats) or MESH_MEASURES.intersection(self.measures):
            mesh, _ = model_mesh(model, self.tolerance)  # made once, for the measures and the mesh files
        figures.update(measure(model, self.measures, tolerance=self.tolerance, mesh=mesh))
        for name, func in self.user:
            figures.update(user_columns(name, func(model)))
        stem = os.path.join(self.files, f"{self.name}-{variant_key(self.name, self.version, params)}")
        for fmt in self.formats:
            figures[f"file_{fmt}"] = self._write(model, mesh, f"{stem}.{fmt}", fmt)
        return figures

    @staticmethod
    def _write(model, mesh, path, fmt) -> str:
        os.makedirs(os.path.dirname(path), exist_ok=True)
        if fmt != "step":
            return exporters.export_mesh(path, mesh, format=fmt)
        solids = solids_of(model)
        if not model.bodies and not solids:
            raise ParameterError(f"model '{model.name}' exists only as a mesh (no exact surfaces): it cannot be written as STEP")
        names = list(model.body_names) + [s.name or model.name for s in solids]
        return exporters.export_step(path, [list(b) for b in model.bodies] + solids, names=names or None)


def _checked_rows(name, module, rows) -> list:
    """Every row with the model's defaults filled in, checked by the model's parameters before any
    work (unknown name, value out of range: ParameterError naming the variant)."""
    full = []
    for i, row in enumerate(rows):
        try:
            full.append(resolve_params(name, module.PARAMETERS, row))
        except SplineKitError as exc:
            raise type(exc)(f"variant {i} ({_row_text(row)}): {exc}") from None
    return full


def _row_text(row) -> str:
    return ", ".join(f"{k}={v!r}" for k, v in row.items())


def sweep(model, parameters, *, measures=None, formats=None, out="sweep", client=None, scheduler=None,
          n_workers=None, force=False, max_variants=DEFAULT_MAX_VARIANTS, plot=True, files=None,
          tolerance=None, timeout=CONNECT_TIMEOUT):
    """Build, check, measure and export every variant of ``model`` in Dask tasks; returns the
    results as a pandas DataFrame, also written to ``out/results.parquet`` and ``out/results.csv``.

    Parameters
    ----------
    model : module
        A model module (``PARAMETERS`` and ``build``); :func:`models.sweep` also takes a registry name.
    parameters : dict of lists, list of dicts, pandas.DataFrame or pyarrow.Table
        The variants (:func:`splinekit.batch.variants`): a dict is a full-factorial grid.
        Each value is checked against the model's declared range before anything runs.
    measures : list, str or dict, optional
        Built-in measure names (:data:`models.measures.MEASURES`; default all) and functions
        ``f(built model) -> number | dict`` (a dict maps column names to functions).
    formats : list or str, optional
        Files to write per variant among :data:`FORMATS` (default none), into ``files``
        (default ``out/files``): a folder the workers can write, on their disks or shared. Only
        the paths travel back.
    out : path
        Results folder (created if missing). Earlier results there are reused: a variant with
        the same parameters and model version (:func:`model_version`), asked the same measures
        and formats, is not built again (status ``skipped``) unless ``force``.
    client, scheduler, n_workers, timeout
        A ``distributed.Client`` or scheduler address (``tcp://host:8786``, or a scheduler file)
        used unchanged; without either a local cluster of ``n_workers`` (default: one per core)
        single-threaded worker processes is started and closed. An unreachable scheduler is a
        BackendError naming it after ``timeout`` seconds.
    max_variants : int
        Budget of variants (default 100,000).
    plot : bool, str or tuple
        PNG of a measure against the parameters that vary: True plots the first numeric measure
        when one or two parameters vary, a name picks the measure, ``(measure, x)`` or
        ``(measure, x, y)`` say everything; False for none. Written as ``out/<measure>.png``.
    tolerance : float, optional
        Chordal tolerance of the tessellation (mm) for mesh files, triangles and bbox.

    Every bad input (unknown model, parameter, measure or format, a value out of range, an empty
    grid, one over the budget, an unreachable scheduler) raises a SplineKitError before any
    results file is written. A variant that fails to build or measure is a ``failed`` row with
    its ``error``; the others go on. ``attrs["summary"]`` holds the counts and the wall time,
    ``attrs["plot"]`` the picture's path (or None).
    """
    if not (hasattr(model, "PARAMETERS") and callable(getattr(model, "build", None))):
        raise ParameterError(f"model must be a model name or a model module (with PARAMETERS and build), got {type(model).__name__}")
    module, name = model, _model_name(model)
    out = checked_path(out)
    builtin, user = _measures(measures)
    wanted_formats = _formats(formats)
    rows = _checked_rows(name, module, variants(parameters, max_variants=max_variants))
    plot_spec = _plot_spec(plot, builtin, user, rows)
    version = model_version(module)
    files_dir = os.path.abspath(checked_path(files) if files is not None else os.path.join(out, "files"))
    task = VariantTask(name, module.build, version, builtin, user, wanted_formats, files_dir, tolerance)
    recipe = json.dumps({"measures": builtin, "user": [n for n, _ in user], "formats": wanted_formats,
                         "tolerance": tolerance, "files": files_dir})
    keys = [variant_key(name, version, row) for row in rows]
    frame = run(task, rows, keys=keys, out=out, recipe=recipe, leading={"model": name}, client=client,
                scheduler=scheduler, n_workers=n_workers, force=force, timeout=timeout, label=f"sweep {name}")
    frame.attrs["plot"] = None
    if plot_spec is not None and (frame["status"] != "failed").any():
        picture = os.path.join(out, f"{plot_spec[0]}.png")
        frame.attrs["plot"] = plot_measure(frame, *plot_spec, path=picture)
    return frame


_PLOTTABLE = ("volume", "area", "triangles", "faces", "centroid_z")


def _plot_spec(plot, builtin, user, rows):
    """``(measure, x[, y])`` to draw, or None."""
    if plot is False or plot is None:
        return None
    varying = [k for k in rows[0] if len({repr(r[k]) for r in rows}) > 1]
    if isinstance(plot, (tuple, list)):
        if not 2 <= len(plot) <= 3:
            raise ParameterError(f"plot=(measure, x) or (measure, x, y), got {plot!r}")
        return tuple(str(p) for p in plot)
    if not 1 <= len(varying) <= 2:
        if plot is True:
            return None
        raise ParameterError(f"plot={plot!r} draws against one or two varying parameters; {len(varying)} vary here: "
                             "give plot=(measure, x[, y])")
    if plot is True:
        columns = [m if m != "centroid" else "centroid_z" for m in builtin] + [n for n, _ in user]
        chosen = next((c for c in _PLOTTABLE if c in columns), None)
        return None if chosen is None else (chosen, *varying)
    return (str(plot), *varying)
