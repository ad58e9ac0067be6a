"""The registry contract shared by every model: :class:`Parameter` and :class:`Model`.

A model module has a docstring, ``PARAMETERS: tuple[Parameter, ...]`` and
``build(**params) -> Model``. Lengths are millimetres, angles degrees.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field

import numpy as np

from splinekit.brep import Shell, TrimmedFace
from splinekit.brep.mass import area_and_volume
from splinekit.errors import ParameterError
from splinekit.tolerances import INTEGRAL_RTOL

__all__ = ["INTEGRAL_TOLERANCE", "Model", "Parameter", "gauss_nodes", "resolve_params", "surface_integrals"]


def _number_text(value) -> str:
    return f"{value:g}" if isinstance(value, float) else str(value)


@dataclass(frozen=True)
class Parameter:
    """One scalar input of a model.

    Attributes
    ----------
    name : str
        Keyword of ``build``.
    default : float or int
        Value used when the caller gives none; within ``[minimum, maximum]``.
    unit : str
        ``"mm"``, ``"deg"`` or ``""`` (a pure number).
    minimum, maximum : float or int
        Closed range of allowed values.
    doc : str
        One line saying what it controls.
    kind : type
        ``float`` or ``int``; an ``int`` parameter rejects fractional values.
    """

    name: str
    default: float
    unit: str
    minimum: float
    maximum: float
    doc: str
    kind: type = float

    def _range_text(self) -> str:
        unit = f" {self.unit}" if self.unit else ""
        what = "an integer" if self.kind is int else "a number"
        return f"{what} in [{_number_text(self.minimum)}, {_number_text(self.maximum)}]{unit}"

    def _reject(self, shown) -> ParameterError:
        return ParameterError(f"parameter '{self.name}' = {shown}: expected {self._range_text()}")

    def parse(self, text: str):
        """The value written as ``text`` (e.g. a command-line argument), checked.

        Raises ParameterError (one line naming the parameter, the text and the
        allowed range) when ``text`` is not a number of the right kind or out of range.
        """
        if not isinstance(text, str):
            raise self._reject(repr(text))
        stripped = text.strip()
        try:
            value = int(stripped) if self.kind is int else float(stripped)
        except ValueError:
            if self.kind is int:
                try:  # "3.0" is an acceptable way to write an integer
                    as_float = float(stripped)
                except ValueError:
                    raise self._reject(repr(text)) from None
                if not (math.isfinite(as_float) and as_float == int(as_float)):
                    raise self._reject(repr(text)) from None
                value = int(as_float)
            else:
                raise self._reject(repr(text)) from None
        return self.check(value)

    def check(self, value):
        """``value`` as ``kind`` if it is a real number of that kind within range, else ParameterError."""
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            raise self._reject(repr(value))
        number = float(value)
        if not math.isfinite(number):
            raise self._reject(repr(value))
        if self.kind is int:
            if number != int(number):
                raise self._reject(repr(value))
            out = int(number)
        else:
            out = number
        if not (self.minimum <= out <= self.maximum):
            raise self._reject(_number_text(out))
        return out


@dataclass
class Model:
    """What ``build`` returns.

    Attributes
    ----------
    name : str
        The model's registry name.
    params : dict
        The parameter values used (defaults filled in).
    bodies : list of list of surfaces
        Each body is a list of exact Bézier / B-spline / NURBS patches in
        millimetres (empty for mesh-only models).
    body_names : list of str
        One name per body (STEP product names).
    mesh : PolyMesh or None
        The result of models that only exist as a mesh (booleans); else None.
    solids : list of splinekit.brep.Solid
        Exact B-rep solids of trimmed faces (models made with exact booleans
        and fillets); written to STEP as they are, tessellated for meshes.
    closed : bool
        Whether every body (or the mesh, or every solid) bounds a solid.
    checks : dict
        ``name -> (expected, tolerance)``: reference values computed without
        OCC (closed forms, Green's theorem on profiles, Gauss-Legendre
        quadrature of the exact patches) that the measures of the sewn bodies
        (or of the mesh) must match within ``tolerance`` (absolute, in the
        quantity's unit). Names used: ``"volume"`` (mm^3, the sum over the
        bodies or solids, or the mesh's volume), ``"area"`` (mm^2), ``"faces"`` (face
        count of the sewn bodies), ``"euler_characteristic"`` (V - E + F of the
        sewn topology or of the mesh). Volume and area of exact bodies come
        from adaptive quadrature (:func:`surface_integrals`) with tolerance
        :data:`INTEGRAL_TOLERANCE` (1e-9 relative); ``splinekit check``
        compares them with OCC's GProp at precision 1e-10 where it is
        reliable and with scipy's cubature where it is not (collapsed edges,
        poles: GProp drifts there by up to 1e-4).
    """

    name: str
    params: dict
    bodies: list = field(default_factory=list)
    body_names: list = field(default_factory=list)
    mesh: object = None
    solids: list = field(default_factory=list)
    closed: bool = False
    checks: dict = field(default_factory=dict)


def resolve_params(model: str, parameters: tuple, given: dict) -> dict:
    """The checked value of every parameter: ``given`` over the defaults.

    Raises ParameterError naming an unknown keyword (and the known ones) or a bad value.
    """
    known = {p.name: p for p in parameters}
    for key in given:
        if key not in known:
            raise ParameterError(
                f"model '{model}' has no parameter '{key}'; parameters: {', '.join(known)}"
            )
    return {name: p.check(given.get(name, p.default)) for name, p in known.items()}


def gauss_nodes(breaks, order: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes and weights, ``(len(breaks) - 1) * order`` each, on every interval between consecutive ``breaks``."""
    g, w = np.polynomial.legendre.leggauss(order)
    breaks = np.asarray(breaks, dtype=float)
    mid, half = 0.5 * (breaks[1:] + breaks[:-1]), 0.5 * (breaks[1:] - breaks[:-1])
    return (mid[:, None] + half[:, None] * g).ravel(), (half[:, None] * w).ravel()


INTEGRAL_TOLERANCE = 1e-9
"""Relative tolerance of the models' stated areas and volumes: the adaptive integration
(:mod:`splinekit.brep.integrate`) meets 1e-10 with an error estimate, and the references that
``splinekit check`` compares them with (OCC's GProp at 1e-10 without collapsed edges, scipy's
cubature at 1e-10 with them) agree with it to about 1e-12."""


def surface_integrals(patches, tol: float = INTEGRAL_RTOL) -> tuple[float, float]:
    """``(area, signed volume)`` of a patch set by adaptive Gauss-Kronrod quadrature
    (:func:`splinekit.brep.mass.area_and_volume`) to relative tolerance ``tol``.

    The volume is the divergence-theorem flux ``(1/3) sum of integrals of S . (S_u x S_v) du dv``
    (mm^3): the enclosed volume when the patches close up with their ``S_u x S_v`` normals all
    pointing outward (negative when all point inward). Area in mm^2. Patches with collapsed
    edges (the teapot's lid and bottom) are handled by the adaptive subdivision; a fixed
    8-point Gauss rule is 0.3 % off on the lid knob. Independent of OCC, hence a cross-check of
    its ``BRepGProp`` values.
    """
    area, _, volume, _ = area_and_volume(Shell([TrimmedFace(p) for p in patches]), tol)
    return area, volume
