"""The chart of a comparison: accuracy against bytes, log-log, one line per representation."""

from __future__ import annotations

from .._atomic import atomic_write
from ..errors import ParameterError

__all__ = ["accuracy_chart"]


def accuracy_chart(table, path: str, title: str | None = None) -> str:
    """Write a PNG of ``hausdorff`` against ``bytes`` (both log scale), one line per
    representation (a single row is a marker), to ``path`` atomically; returns the path."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7.5, 5.0), dpi=110)
    ax = fig.add_subplot()
    drawn = 0
    for name in dict.fromkeys(table["representation"]):
        rows = [r for r in table.where(representation=name) if r.get("bytes") and r.get("hausdorff")]
        if not rows:
            continue
        rows.sort(key=lambda r: r["bytes"])
        ax.plot([r["bytes"] for r in rows], [r["hausdorff"] for r in rows], marker="o", label=name)
        drawn += 1
    if not drawn:
        raise ParameterError("the table has no row with both bytes and hausdorff to draw")
    reference = getattr(table, "reference", None)
    if reference is not None:  # distances below the reference tessellation's tolerance are not resolved
        ax.axhline(reference.tolerance, color="0.5", linestyle="--", linewidth=0.8)
        ax.annotate("measurement floor (reference tessellation)", (0.01, reference.tolerance), xycoords=("axes fraction", "data"),
                    xytext=(0, 3), textcoords="offset points", fontsize=7, color="0.4")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("bytes held")
    ax.set_ylabel("Hausdorff distance to the exact surface (model units)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(title or "accuracy against memory")
    return atomic_write(path, lambda tmp: fig.savefig(tmp, format="png", bbox_inches="tight"), what="chart")
