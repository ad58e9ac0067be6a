"""Cross-checks against OpenCascade (OCP, build123d, cadquery) live in this folder, so the core's
tests read and run without the kernel. Without OCP installed the whole folder is left out of the
run (the root conftest's settings and fixtures still apply to everything here)."""

import importlib.util

if importlib.util.find_spec("OCP") is None:
    collect_ignore_glob = ["test_*.py"]
