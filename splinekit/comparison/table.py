"""A small table of measured figures: :class:`Table` (rows of dicts, Markdown out, no pandas)."""

from __future__ import annotations

import math
import numbers

from ..errors import ParameterError

__all__ = ["Table", "cell_text"]


def cell_text(value) -> str:
    """A value as a table cell: floats to 3 significant digits, None as ``--``, ``|`` escaped."""
    if value is None:
        return "--"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, numbers.Integral):
        return str(int(value))
    if isinstance(value, numbers.Real):
        x = float(value)
        if math.isnan(x):
            return "--"
        if x == int(x) and abs(x) < 1e6:
            return str(int(x))
        return f"{x:.3g}"
    return str(value).replace("|", "\\|").replace("\n", " ")


class Table:
    """Rows of measured figures: a list of dicts with one key per column.

    ``len(table)``, ``table[i]`` (a row dict), ``iter(table)`` (rows), ``table["bytes"]`` (the
    column as a list, ``None`` where a row lacks it), :attr:`columns`, :meth:`where` (the rows
    whose column has a value) and :meth:`to_markdown`. Column names say what they measure;
    units are in :attr:`units` (``column -> text``).
    """

    def __init__(self, rows=(), columns=None, units=None):
        self.rows = [dict(r) for r in rows]
        if columns is None:
            columns = list(dict.fromkeys(k for r in self.rows for k in r))
        self.columns = list(columns)
        self.units = dict(units or {})

    def __len__(self):
        return len(self.rows)

    def __iter__(self):
        return iter(self.rows)

    def __getitem__(self, key):
        if isinstance(key, str):
            if key not in self.columns:
                raise ParameterError(f"the table has no column {key!r}; columns: {', '.join(self.columns)}")
            return [r.get(key) for r in self.rows]
        return self.rows[key]

    def __repr__(self):
        return f"Table({len(self.rows)} rows, columns={self.columns})"

    def where(self, **equal) -> Table:
        """The rows whose columns equal the given values (``table.where(representation="mesh")``)."""
        keep = [r for r in self.rows if all(r.get(k) == v for k, v in equal.items())]
        return Table(keep, self.columns, self.units)

    def to_markdown(self, columns=None) -> str:
        """The table as GitHub Markdown (``columns``: a subset, in order; default all)."""
        cols = list(columns or self.columns)
        unknown = [c for c in cols if c not in self.columns]
        if unknown:
            raise ParameterError(f"the table has no column {unknown[0]!r}; columns: {', '.join(self.columns)}")
        head = [f"{c} ({self.units[c]})" if self.units.get(c) else c for c in cols]
        lines = ["| " + " | ".join(head) + " |", "|" + "|".join("---" for _ in cols) + "|"]
        for r in self.rows:
            lines.append("| " + " | ".join(cell_text(r.get(c)) for c in cols) + " |")
        return "\n".join(lines)
