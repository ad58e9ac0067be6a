"""One line per speed ratio a benchmark checks, in the form ``check_ratios.py`` reads::

    ratio: <name> = <peer time / splinekit time> (target >= <target>)

A benchmark calls :func:`report` where it prints its own table; ``check_ratios.py`` runs the
quick version of every benchmark and fails when a reported ratio is below its target. A ratio
above 1 means splinekit is faster than the peer.
"""

from __future__ import annotations

import math

__all__ = ["report", "skipped", "PATTERN"]

PATTERN = r"^ratio: (?P<name>.+?) = (?P<ratio>[-+0-9.eEinfa]+) \(target >= (?P<target>[0-9.eE+-]+)\)$"


def report(name: str, ratio: float, target: float) -> None:
    """Print the line for one ratio (``peer time / splinekit time``, or any figure where more is better)."""
    shown = "nan" if ratio is None or math.isnan(ratio) else f"{ratio:.3g}"
    print(f"ratio: {name} = {shown} (target >= {target:g})", flush=True)


def skipped(peer: str, reason) -> None:
    """Say that a peer was not run, and why (never skip a peer silently)."""
    print(f"skipped peer: {peer}: {reason}", flush=True)
