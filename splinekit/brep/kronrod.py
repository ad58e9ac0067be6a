"""The 7-15 point Gauss-Kronrod pair on ``[-1, 1]``, shared by the integration rules of
:mod:`.integrate`: the 7-point Gauss rule is embedded in the 15-point Kronrod rule, so the
difference of the two (the error estimate) costs no extra evaluation."""

from __future__ import annotations

import numpy as np

__all__ = ["kronrod15", "NODES01", "W_KRONROD", "W_GAUSS", "NQ"]

# the non-negative nodes and their weights, computed with 40-digit arithmetic (Stieltjes
# polynomial roots, moment equations); tests check them against numpy's Gauss-Legendre rule and
# the rule's exactness for degree 22.
_XK = np.array([0.0, 0.2077849550078984676, 0.40584515137739716691, 0.58608723546769113029,
                0.74153118559939443986, 0.86486442335976907279, 0.94910791234275852453,
                0.99145537112081263921])
_WK = np.array([0.20948214108472782801, 0.20443294007529889241, 0.19035057806478540991,
                0.16900472663926790283, 0.14065325971552591875, 0.10479001032225018384,
                0.063092092629978553291, 0.022935322010529224964])
_WG = np.array([0.41795918367346938776, 0.0, 0.38183005050511894495, 0.0, 0.2797053914892766679, 0.0,
                0.12948496616886969327, 0.0])


def kronrod15() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The 7-15 Gauss-Kronrod rule on ``[-1, 1]``: ``(nodes (15,), kronrod weights (15,),
    gauss weights (15,))``, nodes ascending; the Gauss weights are zero at the Kronrod-only nodes."""
    x = np.concatenate([-_XK[:0:-1], _XK])
    wk = np.concatenate([_WK[:0:-1], _WK])
    wg = np.concatenate([_WG[:0:-1], _WG])
    return x, wk, wg


_X, W_KRONROD, W_GAUSS = kronrod15()
NODES01 = 0.5 * (_X + 1.0)
"""The 15 nodes mapped to ``[0, 1]`` (weights on ``[-1, 1]``: halve them for ``[0, 1]``)."""
NQ = _X.size
