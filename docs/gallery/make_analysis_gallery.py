"""Draw the surface-analysis pictures of docs/gallery/analysis with the `splinekit analyze` command.

Usage (from the repository root, splinekit importable)::

    python docs/gallery/make_analysis_gallery.py            # every picture
    python docs/gallery/make_analysis_gallery.py --out DIR  # somewhere else, to compare

Each picture is one `splinekit analyze` call (printed before it runs), so anyone can draw the
same picture. The deviation pictures measure a synthetic scan of the teapot written to a
temporary folder: 200,000 points on its patches, pushed out along the normals by a smooth
0.3 mm bump on the body and pulled in by 0.1 mm on the lid, plus 0.02 mm of noise.
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
    ("wing", ["--curvature", "max", "--scale", "symlog", "--view", "40,-120"]),
    ("teapot", ["--deviation", "SCAN"]),
]


def teapot_scan(folder: Path) -> Path:
    """The synthetic scan of the module notes, as an .xyz file."""
    import splinekit as sk
    from models import build_model

    patches = [p for body in build_model("teapot").bodies for p in body]
    rng = np.random.default_rng(18)
    n = 200_000
    pick = rng.integers(len(patches), size=n)
    uv = rng.uniform(0.0, 1.0, size=(n, 2))
    points = np.empty((n, 3))
    for k, patch in enumerate(patches):
        rows = np.flatnonzero(pick == k)
        S = patch.evaluate(uv[rows, 0], uv[rows, 1])
        N = sk.curvature(patch, uv[rows, 0], uv[rows, 1]).normal
        points[rows] = S
        outward = np.sign(np.einsum("ij,ij->i", N, S - np.array([0.0, 0.0, 15.0])))
        z, y = S[:, 2], S[:, 1]
        bump = 0.3 * np.exp(-((z - 12.0) ** 2 + (y - 10.0) ** 2) / 40.0) - 0.1 * (z > 30.0)
        points[rows] += (outward * (bump + rng.normal(0.0, 0.02, len(rows))))[:, None] * N
    path = folder / "teapot_scan.xyz"
    np.savetxt(path, points, fmt="%.6f", header="synthetic teapot scan: x y z (mm)")
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
