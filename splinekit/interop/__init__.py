"""Bridges to external kernels. Each module imports its backend inside its
functions, so importing splinekit never loads OCP or manifold3d."""

from . import occ

__all__ = ["occ"]
