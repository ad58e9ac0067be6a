"""The mesh of a built model (``models.Model`` or anything with ``bodies``, ``solids`` and
``mesh``): its patch sets and B-rep solids tessellated and joined, or its own mesh. Shared by
the ``splinekit`` commands and parameter sweeps."""

from __future__ import annotations

from .._progress import progress
from ..errors import ParameterError
from ..mesh.components import concatenate
from .core import tessellate

__all__ = ["model_mesh", "patches_of", "solids_of"]


def solids_of(model) -> list:
    """The model's exact B-rep solids (none for a model of patches or a mesh)."""
    return list(getattr(model, "solids", None) or [])


def patches_of(model) -> list:
    """Every exact patch of every body of the model."""
    return [p for body in model.bodies for p in body]


def model_mesh(model, tolerance=None, label: str = "tessellating"):
    """``(mesh, max_deviation or None)``: the model's own mesh, or its bodies and solids
    tessellated (:func:`splinekit.tessellate`) and joined into one mesh.

    ``tolerance`` is the absolute chordal tolerance (model units); None takes the tolerance a
    B-rep model states in its parameters, else :func:`splinekit.tessellate`'s default (1e-3 of
    the model size). ``max_deviation`` is the largest deviation of any piece's triangles from
    the exact surfaces (None for a model that is only a mesh).
    """
    solids = solids_of(model)
    if not model.bodies and not solids:
        if model.mesh is None:
            raise ParameterError(f"model '{model.name}' has neither exact bodies nor a mesh")
        return model.mesh, None
    if tolerance is None and solids:  # a B-rep model states the tolerance of its meshes
        tolerance = (model.params or {}).get("tolerance")
    meshes = []
    items = [list(body) for body in model.bodies] + solids
    with progress(len(items), label) as bar:
        for item in items:
            meshes.append(tessellate(item, tolerance))
            bar.advance()
    deviation = max(float(getattr(m, "max_deviation", 0.0)) for m in meshes)
    return concatenate(meshes), deviation
