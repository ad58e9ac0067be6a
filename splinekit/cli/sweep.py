"""``splinekit sweep``: build every variant of a model's parameter grid on Dask, measure it and
write the results table (and each variant's files); see :func:`models.parameter_sweep.sweep`."""

from __future__ import annotations

import os

from ..batch import RESULTS_CSV, RESULTS_PARQUET, parse_grid, summary_text
from ..errors import ParameterError
from .console import Console
from .registry import REGISTRY_INTERFACE, parse_sets, registry

DEFAULT_OUTPUT = "sweep"
"""Folder ``sweep`` writes into without ``-o``."""
FAILED_SHOWN = 5
"""Failed variants listed after the summary (all of them are in the results table)."""


def parse_plot(text):
    """``--plot``: ``none``, ``MEASURE`` (against the varying parameters) or ``MEASURE:X[,Y]``;
    None (not given) draws the first measure when one or two parameters vary."""
    if text is None:
        return True
    text = text.strip()
    if text.lower() == "none":
        return False
    measure, sep, axes = text.partition(":")
    names = [a.strip() for a in axes.split(",") if a.strip()] if sep else []
    if not measure.strip() or (sep and not 1 <= len(names) <= 2):
        raise ParameterError(f"--plot expects MEASURE, MEASURE:X or MEASURE:X,Y (or none), got {text!r}")
    return (measure.strip(), *names) if names else measure.strip()


def sweep_grid(reg, name: str, grids, sets) -> dict:
    """The grid of ``--grid`` options, with each ``--set`` value as an axis of one."""
    grid = {}
    for item in grids or ():
        key, values = parse_grid(item)
        if key in grid:
            raise ParameterError(f"--grid {key} is given twice; give all its values in one --grid")
        grid[key] = values
    for key, value in parse_sets(reg, name, sets).items():
        if key in grid:
            raise ParameterError(f"parameter '{key}' is given by both --grid and --set")
        grid[key] = [value]
    if not grid:
        raise ParameterError("nothing to sweep: give at least one --grid NAME=START:STOP:COUNT or NAME=V1,V2,...")
    return grid


def cmd_sweep(args, console: Console) -> int:
    reg = registry(REGISTRY_INTERFACE + ("sweep",))
    reg.get_model(args.model)  # an unknown model fails before anything else
    grid = sweep_grid(reg, args.model, args.grid, args.set)
    out = args.output or DEFAULT_OUTPUT
    frame = reg.sweep(args.model, grid, measures=args.measure, formats=args.format, out=out,
                      scheduler=args.scheduler, n_workers=args.workers, force=args.force,
                      max_variants=args.max_variants, plot=parse_plot(args.plot), timeout=args.timeout,
                      files=args.files)
    console.out(f"{args.model}: {summary_text(frame.attrs['summary'])}")
    console.out(f"  wrote {os.path.join(out, RESULTS_PARQUET)} and {os.path.join(out, RESULTS_CSV)}")
    if frame.attrs.get("plot"):
        console.out(f"  wrote {frame.attrs['plot']}")
    failed = frame[frame["status"] == "failed"]
    columns = list(frame.columns)
    params = columns[columns.index("key") + 1: columns.index("status")]  # the table's documented order
    for _, row in failed.head(FAILED_SHOWN).iterrows():
        values = ", ".join(f"{p}={row[p]:g}" if isinstance(row[p], float) else f"{p}={row[p]}" for p in params)
        console.out(f"  failed: {values}: {row['error']}")
    if len(failed) > FAILED_SHOWN:
        console.out(f"  ... and {len(failed) - FAILED_SHOWN} more failed variants (see the results table)")
    return 0
