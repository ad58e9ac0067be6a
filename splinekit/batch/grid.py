"""The variants of a sweep: a grid, a list of rows or a table turned into one dict per variant,
within a budget, and the key that recognises a variant again when a sweep is resumed."""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import numbers
from collections.abc import Mapping

import numpy as np

from ..errors import ParameterError

__all__ = ["DEFAULT_MAX_VARIANTS", "parse_grid", "variant_key", "variants"]

DEFAULT_MAX_VARIANTS = 100_000
"""Largest number of variants a sweep builds unless ``max_variants`` raises it: a guard against a
grid typed with one value too many per axis (ten axes of ten values are 10^10 builds)."""


def _plain(value):
    """numpy scalars as the Python numbers they hold (JSON, parquet and the models' checks take those)."""
    return value.item() if isinstance(value, np.generic) else value


def _axis(name, values) -> list:
    """The values of one grid axis as a list; a lone number or string is an axis of one value."""
    if isinstance(values, (str, bytes, numbers.Number)) or np.ndim(values) == 0:
        return [_plain(values)]
    try:
        out = [_plain(v) for v in values]
    except TypeError:
        raise ParameterError(f"grid axis {name!r}: expected a list of values, got {type(values).__name__}") from None
    if not out:
        raise ParameterError(f"grid axis {name!r} has no values: the grid is empty, nothing to build")
    return out


def _records(table) -> list | None:
    """Rows of a pandas DataFrame or a pyarrow Table as dicts (None for anything else), told apart
    by their methods so that neither library is imported here."""
    if hasattr(table, "to_pylist") and hasattr(table, "schema"):  # pyarrow.Table
        return table.to_pylist()
    if hasattr(table, "to_dict") and hasattr(table, "columns") and hasattr(table, "iloc"):  # pandas.DataFrame
        return table.to_dict("records")
    return None


def variants(parameters, *, max_variants: int = DEFAULT_MAX_VARIANTS) -> list[dict]:
    """One ``{name: value}`` dict per variant, in order.

    Parameters
    ----------
    parameters : dict of lists, list of dicts, pandas.DataFrame or pyarrow.Table
        A dict is a grid: every combination of its axes' values (full factorial, the last axis
        varying fastest); a lone value is an axis of one. A list of dicts or a table gives the
        variants row by row.
    max_variants : int
        Budget: ParameterError, before any work, when there are more variants than this.

    Raises ParameterError on an empty grid or table, an axis without values, a row that is not a
    mapping, or a count over the budget.
    """
    if isinstance(max_variants, bool) or not isinstance(max_variants, numbers.Integral) or max_variants < 1:
        raise ParameterError(f"max_variants must be a positive integer, got {max_variants!r}")
    if isinstance(parameters, Mapping):
        if not parameters:
            raise ParameterError("the grid has no parameters: give at least one name with a list of values")
        axes = {str(name): _axis(name, values) for name, values in parameters.items()}
        count = math.prod(len(v) for v in axes.values())  # counted before anything is expanded
        _within_budget(count, max_variants)
        names = list(axes)
        return [dict(zip(names, combo)) for combo in itertools.product(*axes.values())]
    rows = _records(parameters)
    if rows is None:
        if isinstance(parameters, (str, bytes)) or not hasattr(parameters, "__len__"):
            raise ParameterError("parameters must be a dict of lists (a grid), a list of dicts or a table "
                                 f"(pandas.DataFrame, pyarrow.Table), got {type(parameters).__name__}")
        rows = list(parameters)
    if not rows:
        raise ParameterError("parameters has no rows: nothing to build")
    _within_budget(len(rows), max_variants)
    for i, row in enumerate(rows):
        if not isinstance(row, Mapping):
            raise ParameterError(f"parameter row {i} is a {type(row).__name__}, expected a dict of name -> value")
    return [{str(k): _plain(v) for k, v in row.items()} for row in rows]


def _within_budget(count: int, max_variants: int) -> None:
    if count > max_variants:
        raise ParameterError(f"the sweep has {count:,} variants, more than the budget of {max_variants:,}; "
                             "raise it with max_variants= (--max-variants) if that many are meant")


def parse_grid(text: str) -> tuple[str, list]:
    """One ``--grid`` option as ``(name, values)``.

    ``name=a:b:n`` is ``n`` equally spaced values from ``a`` to ``b`` (both included);
    ``name=v1,v2,...`` is a list. Values are numbers. ParameterError names the malformed text.
    """
    name, sep, spec = str(text).partition("=")
    name, spec = name.strip(), spec.strip()
    if not sep or not name or not spec:
        raise ParameterError(f"--grid expects name=start:stop:count or name=v1,v2,..., got {text!r}")
    try:
        if ":" in spec:
            parts = spec.split(":")
            if len(parts) != 3:
                raise ValueError
            start, stop, count = float(parts[0]), float(parts[1]), float(parts[2])
            if not (count >= 1 and count == int(count)) or not (math.isfinite(start) and math.isfinite(stop)):
                raise ValueError
            values = np.linspace(start, stop, int(count)).tolist()
        else:
            values = [float(v) for v in spec.split(",")]
    except ValueError:
        raise ParameterError(f"--grid {text!r}: expected name=start:stop:count (count a positive integer) "
                             "or name=v1,v2,... with numbers") from None
    if not all(math.isfinite(v) for v in values):
        raise ParameterError(f"--grid {text!r}: values must be finite numbers")
    return name, values


def variant_key(model: str, version: str, params: Mapping) -> str:
    """16 hex digits naming the variant: the model, its version and every parameter value (exact:
    floats enter by their shortest round-trip text), independent of the order of the names."""
    text = json.dumps([str(model), str(version), sorted((str(k), _plain(v)) for k, v in params.items())])
    return hashlib.sha256(text.encode()).hexdigest()[:16]
