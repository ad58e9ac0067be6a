"""``splinekit.occ``: the OpenCascade bridge, :mod:`splinekit.interop.occ` under the name the
design notes use (``import splinekit.occ``, ``from splinekit.occ import to_occ``,
``splinekit.occ.to_shape``). Importing it loads the bridge and the B-rep layer, not OCP."""

import sys

from .interop import occ

sys.modules[__name__] = occ  # the import statement and the package attribute give the bridge itself
