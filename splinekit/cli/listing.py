"""``splinekit list``: the models, their parameters, defaults, units and ranges."""

from __future__ import annotations

from .console import Console, number_text, table
from .registry import doc_line, registry


def cmd_list(args, console: Console) -> int:
    reg = registry()
    default = reg.DEFAULT_MODEL
    for name, module in reg.MODELS.items():
        mark = " (default)" if name == default else ""
        console.out(f"{name}{mark}: {doc_line(module)}")
        rows = []
        for p in module.PARAMETERS:
            unit = p.unit or "-"
            rng = f"{number_text(p.minimum)} .. {number_text(p.maximum)}"
            kind = "int" if getattr(p, "kind", float) is int else "float"
            rows.append([p.name, number_text(p.default), unit, rng, kind, p.doc])
        if rows:
            console.out("  " + table(rows, ["parameter", "default", "unit", "range", "type", "meaning"]).replace("\n", "\n  "))
        else:
            console.out("  (no parameters)")
        console.out()
    console.out(f"build one with: splinekit build MODEL --set name=value (no MODEL builds '{default}')")
    return 0
