"""OCC's mass properties of a shape with its precision raised: the reference the OCC tests
compare splinekit's integrals and round trips with."""

from __future__ import annotations


def volume_area(shape, eps: float = 1e-10) -> tuple:
    """``(volume, area)`` of an OCC shape by ``BRepGProp`` at precision ``eps``."""
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    v, s = GProp_GProps(), GProp_GProps()
    BRepGProp.VolumeProperties_s(shape, v, eps)
    BRepGProp.SurfaceProperties_s(shape, s, eps)
    return v.Mass(), s.Mass()
