"""Draw the surface-analysis pictures of docs/gallery/analysis with the `splinekit analyze` command.

Usage (from the repository root, splinekit importable)::

    python docs/gallery/make_analysis_gallery.py            # every picture
    python docs/gallery/make_analysis_gallery.py --out DIR  # somewhere else, to compare

Each picture is one `splinekit analyze` call (printed before it runs), so anyone can draw the
same picture. The deviation pictures measure a synthetic scan of the teapot written to a
temporary folder: 200,000 points on its patches, pushed out along the normals by a smooth
0.3 mm bump on the body's front and pulled in by 0.1 mm on the top 15 %, plus 0.02 mm of noise.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent / "analysis"
SIZE = "640x480"

# (model, options); the pictures are named MODEL-ANALYSIS.png by the command
RUNS = [
    ("teapot", ["--zebra"]),
    ("mug", ["--zebra", "--view", "20,-40"]),
    ("vase", ["--isophotes", "--light", "1,0,1", "--step", "10"]),
    ("bracket", ["--draft", "0,0,1", "--min-draft", "1"]),
    ("wing", ["--curvature", "min", "--scale", "symlog", "--view", "40,-120"]),
    ("teapot", ["--deviation", "SCAN"]),
]


def teapot_scan(folder: Path) -> Path:
    """The synthetic scan of the module notes, as an .xyz file."""
    import splinekit as sk
    from models import build_model
    from splinekit.analysis import sample_part

    patches = [p for body in build_model("teapot").bodies for p in body]
    outward = sample_part(patches).patch_sign  # per patch: +1 where Su x Sv points out of the teapot
    rng = np.random.default_rng(18)
    n = 200_000
    pick = rng.integers(len(patches), size=n)
    uv = rng.uniform(0.0, 1.0, size=(n, 2))
    points, normals = np.empty((n, 3)), np.empty((n, 3))
    for k, patch in enumerate(patches):
        rows = np.flatnonzero(pick == k)
        points[rows] = patch.evaluate(uv[rows, 0], uv[rows, 1])
        normals[rows] = outward[k] * sk.curvature(patch, uv[rows, 0], uv[rows, 1]).normal
    # the bump: centred on the body where it faces the default view (azimuth -58 degrees)
    size = float(np.ptp(points, axis=0).max())
    middle = np.abs(points[:, 2] - np.median(points[:, 2])) < 0.02 * size
    facing = points[:, :2] @ [np.cos(np.radians(-58.0)), np.sin(np.radians(-58.0))]
    centre = points[np.flatnonzero(middle)[np.argmax(facing[middle])]]
    bump = 0.3 * np.exp(-np.sum((points - centre) ** 2, axis=1) / (2 * (0.12 * size) ** 2))
    lid = np.where(points[:, 2] > np.percentile(points[:, 2], 85), -0.1, 0.0)
    offset = bump + lid + rng.normal(0.0, 0.02, n)
    path = folder / "teapot_scan.xyz"
    np.savetxt(path, points + offset[:, None] * normals, fmt="%.6f", header="synthetic teapot scan: x y z (mm)")
    return path


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=HERE, help="folder to write into (default: docs/gallery/analysis)")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as scratch:
        for model, options in RUNS:
            options = [str(teapot_scan(Path(scratch))) if word == "SCAN" else word for word in options]
            command = [sys.executable, "-m", "splinekit.cli", "analyze", model, *options, "--size", SIZE,
                       "-o", str(args.out)]
            shown = ["scan.xyz" if word.endswith(".xyz") else word for word in command[3:]]
            print(" ".join(["splinekit", *shown]), flush=True)
            subprocess.run(command, check=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
