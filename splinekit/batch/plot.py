"""A PNG of one measure of a sweep against one or two of its parameters."""

from __future__ import annotations

import numpy as np

from .._atomic import atomic_write
from ..errors import ParameterError
from ..plot.picture import pyplot
from .results import DONE

__all__ = ["plot_measure"]


def _numbers(frame, column: str) -> np.ndarray:
    try:
        return frame[column].to_numpy(dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"column {column!r} does not hold numbers; plot a numeric measure") from None


def plot_measure(frame, measure: str, x: str, y: str | None = None, *, path) -> str:
    """Write a PNG of ``measure`` against parameter ``x`` (one line), or against ``x`` with one
    line per value of parameter ``y``, from the finished rows of a results table; returns the path.

    ParameterError when a column is missing or not numeric, or no finished row has the measure.
    """
    for column in (measure, x, y):
        if column is not None and column not in frame.columns:
            raise ParameterError(f"cannot plot {column!r}: the results have no such column; columns: {', '.join(map(str, frame.columns))}")
    done = frame[frame["status"].isin(DONE)]
    done = done[np.isfinite(_numbers(done, measure))]
    if done.empty:
        raise ParameterError(f"cannot plot {measure!r}: no finished variant has a value for it")
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.4), dpi=100)
    try:
        groups = [(None, done)] if y is None else list(done.groupby(y, sort=True))
        for value, part in groups:
            part = part.sort_values(x)
            label = None if y is None else f"{y} = {value:g}" if isinstance(value, float) else f"{y} = {value}"
            ax.plot(_numbers(part, x), _numbers(part, measure), marker="o", markersize=3, label=label)
        ax.set_xlabel(x)
        ax.set_ylabel(measure)
        ax.set_title(f"{measure} against {x}" + (f" and {y}" if y else ""), fontsize=10)
        ax.grid(True, alpha=0.3)
        if y is not None:
            ax.legend(fontsize=8)
        fig.tight_layout()
        return atomic_write(path, lambda tmp: fig.savefig(tmp, format="png", facecolor="white"), "plot")
    finally:
        plt.close(fig)
