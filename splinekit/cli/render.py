"""``splinekit render``: a shaded picture of a model or of a STEP or mesh file, and the picture
writing shared with ``splinekit demo`` (the format the file's suffix names: PNG or JPEG)."""

from __future__ import annotations

import os
import tempfile
import time

import numpy as np

import exporters

from .._atomic import atomic_write
from .._signals import reraise_interrupt
from ..brep import Shell, Solid, TrimmedFace
from ..errors import FileFormatError, MissingDependencyError, ParameterError
from ..mesh.components import concatenate
from ..plot import render_mesh, render_patches
from ..tessellation import tessellate
from .console import Console, count
from .info import MESH_SUFFIXES, STEP_SUFFIXES
from .registry import build_model, model_mesh, params_text, patches_of, registry, solids_of

PICTURE_SUFFIXES = (".png", ".jpg", ".jpeg")
"""Picture formats the commands write, named by the output file's suffix."""
DEFAULT_FOLDER = "out"
"""Folder of a picture written without ``-o`` (created if missing)."""


def picture_path(output, stem: str) -> str:
    """The picture file to write: ``output``, or ``out/STEM.png`` without it (a missing folder
    is created by :func:`write_picture`, once there is something to write).

    Raises FileFormatError for a suffix that is not a picture format the commands write, or when
    a part of the folder of ``output`` exists and is not a folder.
    """
    if output is None:
        return os.path.join(DEFAULT_FOLDER, f"{stem}.png")
    suffix = os.path.splitext(output)[1].lower()
    if suffix not in PICTURE_SUFFIXES:
        raise FileFormatError(f"cannot write {output!r}: pictures are written as "
                              f"{', '.join(PICTURE_SUFFIXES)} (named by the file's suffix), got {suffix or 'no suffix'!r}")
    folder = os.path.dirname(os.path.abspath(output))
    while not os.path.exists(folder):  # the nearest existing ancestor must be a folder
        folder = os.path.dirname(folder)
    if not os.path.isdir(folder):
        raise FileFormatError(f"cannot write {output!r}: {folder!r} is not a folder")
    return output


def write_picture(path: str, draw) -> str:
    """Write the picture ``draw(png_path)`` draws to ``path`` in the format of its suffix.

    ``draw`` writes a PNG (the renderers of :mod:`splinekit.plot` do, atomically). A ``.jpg`` /
    ``.jpeg`` target is that PNG converted by Pillow (which matplotlib depends on) and written
    atomically; the intermediate PNG lives in a private temporary folder, never beside the target.
    A missing folder of ``path`` is created (the default output folder).
    """
    os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    if os.path.splitext(path)[1].lower() == ".png":
        return draw(path)
    try:
        from PIL import Image
    except ImportError as exc:
        reraise_interrupt(exc)
        raise MissingDependencyError(f"writing {path!r} as JPEG needs Pillow: pip install pillow ({exc})") from None
    with tempfile.TemporaryDirectory(prefix="splinekit-render-") as folder:
        png = draw(os.path.join(folder, "picture.png"))
        with Image.open(png) as image:
            rgb = image.convert("RGB")  # JPEG has no alpha channel
        return atomic_write(path, lambda tmp: rgb.save(tmp, format="JPEG", quality=92), what="picture")


def parse_size(text) -> tuple[int, int]:
    w, sep, h = str(text).lower().partition("x")
    try:
        size = (int(w), int(h))
    except ValueError:
        raise ParameterError(f"--size must be WIDTHxHEIGHT in pixels (e.g. 1000x800), got {text!r}") from None
    if not sep or not all(64 <= s <= 8000 for s in size):
        raise ParameterError(f"--size must be WIDTHxHEIGHT with each between 64 and 8000 pixels, got {text!r}")
    return size


def parse_view(text) -> tuple[float, float]:
    try:
        elev, azim = (float(x) for x in str(text).split(","))
    except ValueError:
        raise ParameterError(f"--view must be ELEVATION,AZIMUTH in degrees (e.g. 28,-58), got {text!r}") from None
    if not (np.isfinite(elev) and np.isfinite(azim)):
        raise ParameterError(f"--view angles must be finite, got {text!r}")
    return elev, azim


def is_file_target(target: str) -> bool:
    """A STEP or mesh file by its suffix; anything else is taken for a model name."""
    return os.path.splitext(target)[1].lower() in STEP_SUFFIXES + MESH_SUFFIXES


def _draw_file(target, out, title, options) -> str:
    """Draw a STEP or mesh file; returns what was drawn ("12 faces")."""
    if not os.path.isfile(target):
        raise FileFormatError(f"{target!r} does not exist or is not a file")
    if os.path.splitext(target)[1].lower() in MESH_SUFFIXES:
        mesh = exporters.import_mesh(target)
        write_picture(out, lambda png: render_mesh(mesh, png, title=title, **options))
        return count(mesh.n_faces, "face")
    items = [item.geometry for item in exporters.import_step(target)]
    breps = [g for g in items if isinstance(g, (Shell, Solid, TrimmedFace))]
    patches = [g for g in items if hasattr(g, "degree_u")]
    if breps:  # trimmed faces are drawn as their tessellation
        mesh = concatenate([tessellate(g, None) for g in breps])
        write_picture(out, lambda png: render_mesh(mesh, png, title=title, **options))
        return count(sum(len(getattr(g, "faces", (g,))) for g in breps), "trimmed face")
    if patches:
        write_picture(out, lambda png: render_patches(patches, png, title=title, **options))
        return count(len(patches), "face")
    raise FileFormatError(f"the STEP file {target!r} holds no faces to draw")


def _draw_model(target, sets, out, color, options, console) -> str:
    """Build and draw a model; returns what was drawn."""
    reg = registry()
    if target not in reg.MODELS and os.path.exists(target):
        raise FileFormatError(f"cannot render {target!r}: it is not a model name, and files must end in "
                              f"{', '.join(STEP_SUFFIXES + MESH_SUFFIXES)}")
    model = build_model(reg, target, sets, console)
    title = f"{target} ({params_text(model)}): {color}" if model.params else f"{target}: {color}"
    if model.bodies:
        patches = patches_of(model)
        write_picture(out, lambda png: render_patches(patches, png, title=title, **options))
        return count(len(patches), "exact patch", "exact patches")
    if model.mesh is not None:
        write_picture(out, lambda png: render_mesh(model.mesh, png, title=title, **options))
        return count(model.mesh.n_faces, "mesh face")
    if solids_of(model):
        mesh, _ = model_mesh(model)  # trimmed faces are drawn as their tessellation
        write_picture(out, lambda png: render_mesh(mesh, png, title=title, **options))
        return count(mesh.n_faces, "triangle")
    raise ParameterError(f"model '{target}' has neither exact bodies nor a mesh to draw")


def cmd_render(args, console: Console) -> int:
    size, view = parse_size(args.size), parse_view(args.view)
    target = args.target
    file_target = is_file_target(target)
    if file_target and args.set:
        raise ParameterError("--set applies to models; a file is drawn as it is")
    out = picture_path(args.output, os.path.splitext(os.path.basename(target))[0])
    options = dict(color=args.color, scale=args.scale, size=size, view=view)
    t0 = time.perf_counter()
    if file_target:
        what = _draw_file(target, out, f"{os.path.basename(target)}: {args.color}", options)
    else:
        what = _draw_model(target, args.set, out, args.color, options, console)
    console.out(f"wrote {out} ({what}, colored by {args.color}, {size[0]}x{size[1]}) in {time.perf_counter() - t0:.2f} s")
    return 0
