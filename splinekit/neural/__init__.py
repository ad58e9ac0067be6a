"""Neural implicit surfaces: a network ``F(x, y, z)`` trained as a signed distance or occupancy.

Optional extra: JAX and optax on the CPU (``pip install "splinekit[neural]"``); without them
importing this package raises :class:`~splinekit.errors.MissingDependencyError` naming that
command. ``import splinekit`` never imports it (``splinekit.neural`` loads on first use).

* :class:`NeuralSDF` ``.fit(shape, *, steps, seed)``: a signed distance (eikonal term) learned from
  any closed shape; :class:`NeuralOccupancy`: inside probability (cross-entropy), meshed at 0.5.
* :class:`NeuralSDFFamily` ``.fit(shapes)``: one network and one latent code per shape (an
  auto-decoder, as DeepSDF); ``.shape(i)``, ``.interpolate(i, j, t)``, ``.fit_code(shape)``.
* Every trained shape is a :class:`splinekit.implicit.Implicit`: callable, gradient, normal,
  Hessian and curvature by automatic differentiation, ``to_mesh``, CSG.
* ``.save(path)`` / ``.load(path)`` (and :func:`load` for any kind): one ``.nsdf`` file.
"""

from ._backend import INSTALL
from .family import NeuralSDFFamily, load
from .model import NeuralImplicit, NeuralOccupancy, NeuralSDF
from .network import DEFAULT_ENCODING, ENCODINGS, Architecture

__all__ = ["Architecture", "DEFAULT_ENCODING", "ENCODINGS", "INSTALL", "NeuralImplicit", "NeuralOccupancy",
           "NeuralSDF", "NeuralSDFFamily", "load"]
