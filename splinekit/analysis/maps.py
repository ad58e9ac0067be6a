"""Scalar maps over a whole part: zebra stripes, isophotes, curvature and draft angle.

Each function samples the part (:func:`~splinekit.analysis.sampling.sample_part`: exact
normals and curvatures on a tessellation, a mesh's own on a mesh) and returns a
:class:`SurfaceMap`: per-vertex ``values`` (numbers to test and to compute with) and a
``render(path)`` that draws the map as a PNG through :mod:`splinekit.plot`. The pictures
evaluate the same formulas per pixel, on the normal interpolated across each triangle, so
stripes and isophote lines are sharp whatever the triangle size.

The formulas (unit normal ``n``, all on whole arrays):

* zebra: light bands parallel to ``axis`` all around the part, seen in a mirror. The
  view direction ``d`` (from the eye into the scene) reflects to ``r = d - 2 (d.n) n``;
  the value is the angle of ``r`` about ``axis``, measured from the direction back to the
  viewer, in radians in ``(-pi, pi]``. The stripe is white where ``round(angle / (pi /
  stripes))`` is even: ``stripes`` black and white pairs all around, a white one centred on
  the reflection straight back to the viewer. On a plane the angle is constant; on a
  cylinder about ``axis`` seen across it, it is twice the polar angle of the normal.
* isophotes: the angle between ``n`` and the light ``direction``, in degrees in
  ``[0, 180]``; the isophote lines are its multiples of ``step``.
* curvature: Gaussian ``K``, mean ``H`` or principal ``k1`` (max) / ``k2`` (min).
* draft: ``asin(n . pull)`` in degrees in ``[-90, 90]``: 0 on a wall parallel to the pull
  direction, 90 on a face square to it, negative where the normal points against it (an
  under-cut: the mould cannot release the face by moving along ``pull``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .._validate import as_int, as_real
from ..errors import ParameterError
from ..plot import raster
from ..plot.picture import DEFAULT_SIZE, view_angles
from . import pictures
from .fields import VERTICAL_DEGREES, draft_degrees, isophote_angle, zebra_angle, zebra_stripe
from .sampling import SampledPart, freeze, sample_part, unit_direction

__all__ = ["CURVATURE_KINDS", "DraftMap", "SurfaceMap", "curvature_map", "draft_angle", "isophotes", "zebra"]

CURVATURE_KINDS = ("gaussian", "mean", "max", "min")
"""What :func:`curvature_map` shows: Gaussian K, mean H, and the principal curvatures k1 >= k2."""

DEFAULT_VIEW = (28.0, -58.0)
"""(elevation, azimuth) in degrees: the view of ``splinekit render``."""



@dataclass(frozen=True, eq=False)
class SurfaceMap:
    """A scalar field over a sampled part.

    Attributes
    ----------
    kind : str
        ``"zebra"``, ``"isophotes"``, ``"gaussian"``, ``"mean"``, ``"max"``, ``"min"`` or ``"draft"``.
    part : SampledPart
        The sampled part (points, normals, triangles, ``degenerate`` vertices).
    values : (n,) float64
        The field at the part's vertices (see the module notes for formulas and units).
    unit : str
        Unit of ``values``.
    options : dict
        The parameters of the map (directions as unit vectors, counts, angles).
    """

    kind: str
    part: SampledPart
    values: np.ndarray
    unit: str
    options: dict = field(default_factory=dict)

    def __post_init__(self):
        freeze(self)

    def render(self, path, *, size=DEFAULT_SIZE, view=None, title=None) -> str:
        """Write the map as a PNG to ``path`` (atomically); returns the path. ``view`` is
        ``(elevation, azimuth)`` in degrees; a zebra map is drawn from its own view (its
        stripes depend on it) and refuses another."""
        return pictures.render_map(self, path, size=size, view=view, title=title)


@dataclass(frozen=True, eq=False)
class DraftMap(SurfaceMap):
    """A draft-angle map (:func:`draft_angle`): ``values`` in degrees, plus the regions."""

    @property
    def undercut(self) -> np.ndarray:
        """``(n,)`` vertices whose normal points against the pull direction (draft < 0)."""
        return self.values < -VERTICAL_DEGREES

    @property
    def insufficient(self) -> np.ndarray:
        """``(n,)`` vertices with a draft in ``[0, min_draft)``: releasable, but with less draft than asked."""
        return ~self.undercut & (self.values < self.options["min_draft"] - VERTICAL_DEGREES)


# -- the public maps -----------------------------------------------------------------------------------
def zebra(part, *, stripes: int = 12, axis=None, view=DEFAULT_VIEW, tolerance=None) -> SurfaceMap:
    """Zebra stripes of ``part`` seen from ``view`` (module notes).

    ``part``: anything :func:`~splinekit.analysis.sampling.sample_part` takes (or a
    SampledPart). ``stripes``: black-and-white pairs all around (1 to 180). ``axis``: the
    direction the light bands run along (default: the view's screen-up direction, so the
    bands stand upright in the picture). ``view``: ``(elevation, azimuth)`` in degrees, as in
    ``splinekit render``. ``values`` are reflection angles in radians; ``options["stripe"]``
    is the ``(n,)`` 0/1 stripe of each vertex.
    """
    stripes = as_int(stripes, "stripes", minimum=1)
    if stripes > 180:
        raise ParameterError(f"stripes must be at most 180 (one-degree bands), got {stripes}")
    view = view_angles(view)
    eye, _, up = raster.view_basis(*view)
    upright = axis is None
    axis = up if upright else unit_direction(axis, "axis")
    sampled = sample_part(part, tolerance)
    angle = zebra_angle(sampled.normals, eye, axis)
    options = {"stripes": stripes, "axis": axis, "upright": upright, "eye": eye, "view": view,
               "stripe": zebra_stripe(angle, stripes)}
    return SurfaceMap("zebra", sampled, angle, "rad", options)


def isophotes(part, direction=(0.0, 0.0, 1.0), *, step: float = 10.0, tolerance=None) -> SurfaceMap:
    """Isophotes of ``part``: the angle in degrees between the normal and ``direction``, with
    lines every ``step`` degrees (``0 < step <= 90``) in the picture (module notes).
    ``options["band"]`` is the ``(n,)`` band index ``floor(angle / step)`` of each vertex."""
    direction = unit_direction(direction, "direction")
    step = as_real(step, "step")
    if not 0 < step <= 90:
        raise ParameterError(f"step must be an angle in (0, 90] degrees, got {step!r}")
    sampled = sample_part(part, tolerance)
    angle = isophote_angle(sampled.normals, direction)
    band = np.floor(angle / step).astype(np.int64)
    return SurfaceMap("isophotes", sampled, angle, "deg", {"direction": direction, "step": step, "band": band})


def curvature_map(part, kind: str = "mean", *, scale: str = "percentile", tolerance=None) -> SurfaceMap:
    """Curvature of ``part`` at its vertices: ``kind`` one of :data:`CURVATURE_KINDS`
    (Gaussian in 1/length^2, the others in 1/length; signed against the part's normals,
    ``H = -1/r`` on a sphere with outward normals). ``scale`` is the picture's colour scale,
    ``"percentile"`` or ``"symlog"`` (:data:`splinekit.plot.COLOR_SCALES`)."""
    if kind not in CURVATURE_KINDS:
        raise ParameterError(f"kind must be one of {', '.join(CURVATURE_KINDS)}; got {kind!r}")
    if scale not in ("percentile", "symlog"):
        raise ParameterError(f"scale must be 'percentile' or 'symlog'; got {scale!r}")
    sampled = sample_part(part, tolerance)
    values = {"gaussian": sampled.gaussian, "mean": sampled.mean, "max": sampled.k1, "min": sampled.k2}[kind]
    unit = "1/length^2" if kind == "gaussian" else "1/length"
    return SurfaceMap(kind, sampled, np.array(values), unit, {"scale": scale})


def draft_angle(part, pull=(0.0, 0.0, 1.0), *, min_draft: float = 0.0, tolerance=None) -> DraftMap:
    """Draft angles of ``part`` for the pull direction ``pull``, in degrees (module notes).

    ``min_draft`` (degrees, in ``[0, 90)``) is the least draft a face needs; the result's
    ``undercut`` marks vertices with a negative draft, ``insufficient`` those in
    ``[0, min_draft)``. Degenerate normals (``part.degenerate``, e.g. a mesh vertex with
    no area around it) give 0 and are listed there.
    """
    pull = unit_direction(pull, "pull direction")
    min_draft = as_real(min_draft, "min_draft")
    if not 0 <= min_draft < 90:
        raise ParameterError(f"min_draft must be an angle in [0, 90) degrees, got {min_draft!r}")
    sampled = sample_part(part, tolerance)
    values = draft_degrees(sampled.normals, pull)
    return DraftMap("draft", sampled, values, "deg", {"pull": pull, "min_draft": min_draft})
