"""Draw the pictures of docs/gallery with the `splinekit render` command.

Usage (from the repository root, splinekit importable)::

    python docs/gallery/make_gallery.py            # every picture
    python docs/gallery/make_gallery.py wing mug   # some of them
    python docs/gallery/make_gallery.py --out DIR  # somewhere else, to compare

Each picture is one `splinekit render` call, so anyone can draw the same picture
with the command shown in the README. ``plate`` draws the part of the README's
"Real parts" section: it builds that plate with build123d, cuts and fillets it
with splinekit, writes its STL to a temporary folder and renders that file.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
SIZE = "640x480"

# name: (what is drawn, colour mode, view "elevation,azimuth", extra options)
PICTURES = {
    "teapot": ("teapot", "curvature", "28,-58", ["--scale", "symlog"]),
    "vase": ("vase", "gaussian", "28,-58", []),
    "mug": ("mug", "mean", "28,-58", []),
    "bracket": ("bracket", "normal", "28,-58", []),
    "wing": ("wing", "curvature", "40,-120", ["--scale", "symlog"]),
    "block": ("block", "normal", "35,-50", []),
    "plate": ("plate_drilled.stl", "normal", "55,-60", []),
}


def _plate_stl(folder: Path) -> Path:
    """The drilled and filleted plate of the README, tessellated at 0.01 mm, as an STL file."""
    import build123d as bd

    import exporters
    import splinekit as sk
    from splinekit import brep

    part = bd.fillet(bd.Box(40, 30, 10).edges().filter_by(bd.Axis.Z), 5)
    part -= bd.Pos(-10, 0, 0) * bd.Cylinder(3, 10)
    part -= bd.Pos(10, 0, 0) * bd.Cylinder(3, 10)
    bd.export_step(part, str(folder / "plate.step"))
    (item,) = exporters.import_step(folder / "plate.step")
    drilled = brep.cut(item.geometry, brep.cylinder(4, 20, origin=(0, 0, -10)))
    rounded = brep.fillet(drilled, [(0, 15, 5)], 1.0)
    path = folder / "plate_drilled.stl"
    exporters.export_stl(path, sk.tessellate(rounded, 0.01))
    return path


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("names", nargs="*", metavar="NAME", help=f"pictures to draw: {', '.join(PICTURES)} (default: all)")
    parser.add_argument("--out", type=Path, default=HERE, help="folder to write into (default: docs/gallery)")
    args = parser.parse_args(argv)
    unknown = sorted(set(args.names) - set(PICTURES))
    if unknown:
        parser.error(f"unknown picture(s) {', '.join(unknown)}; known: {', '.join(PICTURES)}")
    with tempfile.TemporaryDirectory() as scratch:
        for name in args.names or PICTURES:
            target, color, view, extra = PICTURES[name]
            if name == "plate":
                target = str(_plate_stl(Path(scratch)))
            command = [sys.executable, "-m", "splinekit.cli", "render", target, "-o", str(args.out / f"{name}.png"),
                       "--color", color, "--view", view, "--size", SIZE, *extra]
            shown = [PICTURES[name][0] if word == target else word for word in command[3:]]
            print(" ".join(["splinekit", *shown]), flush=True)
            subprocess.run(command, check=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
