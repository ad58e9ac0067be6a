"""``splinekit compare``: one shape in every representation, measured in one run; prints the
Markdown tables and writes them, a chart of accuracy against bytes and the pictures to a folder."""

from __future__ import annotations

import os
import time

from .._atomic import atomic_write, checked_path
from ..comparison import REPRESENTATIONS, Shape, accuracy_chart, as_shape, compare, sphere, torus
from ..errors import ParameterError
from ..subdiv import SubdivisionSurface
from .console import Console
from .registry import build_model, registry

DEFAULT_MODEL = "mug"
"""The shape compared without MODEL: genus 1, exact B-spline patches and a subdivision cage."""
EXTRA_SHAPES = {"sphere": sphere, "torus": torus}
"""Shapes that are not models but have an analytic implicit."""
DEFAULT_OUTPUT = os.path.join("out", "compare")
TABLE_COLUMNS = ("representation", "resolution", "bytes", "build_s", "query_s", "point_s", "inside_s", "normal_s",
                 "hausdorff", "mean_distance", "normal_angle", "volume_error", "genus", "note")
GROWTH_COLUMNS = ("representation", "rows", "memory_slope", "memory_class", "query_slope", "query_class",
                  "bytes_per_accuracy_slope")


def parse_resolutions(items) -> dict:
    """``--resolutions NAME=v1,v2,...`` pairs (repeatable) as a dict of lists of numbers."""
    out = {}
    for item in items or ():
        name, sep, text = item.partition("=")
        name = name.strip()
        if not sep or name not in REPRESENTATIONS:
            raise ParameterError(f"--resolutions expects NAME=v1,v2,... with NAME one of {', '.join(REPRESENTATIONS)}; got {item!r}")
        try:
            values = [float(v) for v in text.split(",") if v.strip()]
        except ValueError:
            raise ParameterError(f"--resolutions {item!r}: the values must be numbers") from None
        out[name] = [int(v) if v == int(v) and name != "triangle mesh" else v for v in values]
    return out


def quick_resolutions() -> dict:
    """The first two default resolutions of every representation (``--quick``)."""
    return {name: cls.default_resolutions[:2] for name, cls in REPRESENTATIONS.items()}


def shape_of(name: str, sets, console: Console) -> Shape:
    """The shape to compare: a model of the registry built with ``--set`` values (with its
    subdivision cage when the model module offers ``surface(**params)``), or an extra shape."""
    if name in EXTRA_SHAPES:
        if sets:
            raise ParameterError(f"--set applies to models; {name!r} is a fixed shape")
        return EXTRA_SHAPES[name]()
    reg = registry()
    model = build_model(reg, name, sets, console)
    shape = as_shape(model, name)
    make = getattr(reg.get_model(name), "surface", None)
    if callable(make):
        try:
            surface = make(**model.params)
        except TypeError:  # a surface() of other parameters: no cage
            surface = None
        if isinstance(surface, SubdivisionSurface):
            shape = Shape(shape.name, shape.patches, subdivision=surface)
    return shape


def cmd_compare(args, console: Console) -> int:
    t0 = time.perf_counter()
    # steady-state timings: compiled kernels from the first large job, as the benchmarks run,
    # rather than the library's numpy-first warm-up policy (splinekit._kernels)
    os.environ.setdefault("SPLINEKIT_NUMBA", "1")
    name = args.model or DEFAULT_MODEL
    out_dir = checked_path(args.output or DEFAULT_OUTPUT)
    if os.path.exists(out_dir) and not os.path.isdir(out_dir):
        raise ParameterError(f"output folder {out_dir!r} exists and is not a folder")
    resolutions = quick_resolutions() if args.quick else {}
    resolutions.update(parse_resolutions(args.resolutions))
    names = None
    if args.only:
        names = [n.strip() for n in args.only.split(",") if n.strip()]
    shape = shape_of(name, args.set, console)
    os.makedirs(out_dir, exist_ok=True)
    table = compare(shape, representations=names, resolutions=resolutions, samples=args.samples,
                    exact_boolean=args.exact_boolean, folder=os.path.join(out_dir, "pictures"))
    ref = table.reference
    head = (f"# Representations of the {shape.name}\n\nExact reference: {len(shape.patches)} patches; distances to "
            f"the exact surface are measured to their tessellation at {ref.tolerance:.3g} (bounding-box diagonal "
            f"{ref.diagonal:.4g}), exact volume {ref.volume:.6g}, genus {ref.genus:g}.")
    text = "\n\n".join([
        head,
        "## Memory, queries and topology\n\n" + table.to_markdown([c for c in TABLE_COLUMNS if c in table.columns]),
        "## Growth with resolution N (log-log slopes)\n\n" + table.growth.to_markdown(
            [c for c in GROWTH_COLUMNS if c in table.growth.columns]),
        "## Operations (at each representation's middle resolution)\n\n" + table.operations.to_markdown(),
    ]) + "\n"
    console.out(text)
    def write(tmp):
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(text)

    md = atomic_write(os.path.join(out_dir, "compare.md"), write, what="tables")
    chart = accuracy_chart(table, os.path.join(out_dir, "accuracy.png"), title=f"{shape.name}: accuracy against bytes")
    console.out(f"wrote {md} and {chart} in {time.perf_counter() - t0:.1f} s")
    return 0
