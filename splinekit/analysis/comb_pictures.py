"""Pictures of curvature combs (the comb itself is computed by
``splinekit.analysis.curvature_comb``; this module only draws).

:func:`render_curvature_comb` takes one comb or a list of them -- anything with ``points``
``(n, dim)``, ``tips`` ``(n, dim)`` (the ends of the teeth) and ``curvature`` ``(n,)``, dim 2
or 3 -- and writes a PNG: each curve in black, its teeth as thin lines coloured by
``|curvature|`` and the outline through the tips, with a colour bar. 3-D combs are projected
orthographically from ``view`` (the convention of ``splinekit render``); 2-D combs are drawn
in their plane.
"""

from __future__ import annotations

import numpy as np

from .._atomic import atomic_write
from ..errors import ParameterError
from ..plot import picture, raster

__all__ = ["render_curvature_comb"]

MAX_TEETH = 400
"""Teeth drawn per comb at most (evenly strided): more only blacken the picture."""


def _combs(combs):
    items = [combs] if hasattr(combs, "tips") else list(combs)
    if not items:
        raise ParameterError("render_curvature_comb got no comb to draw")
    out = []
    for i, c in enumerate(items):
        try:
            P, T, k = (np.asarray(getattr(c, name), dtype=np.float64) for name in ("points", "tips", "curvature"))
        except AttributeError:
            raise ParameterError(f"comb {i} is a {type(c).__name__}: a comb has points, tips and curvature") from None
        if P.ndim != 2 or P.shape[1] not in (2, 3) or T.shape != P.shape or k.shape != (len(P),) or len(P) < 2:
            raise ParameterError(f"comb {i}: points and tips must be (n, 2) or (n, 3) with n >= 2 and curvature (n,); "
                                 f"got {P.shape}, {T.shape}, {k.shape}")
        if not (np.isfinite(P).all() and np.isfinite(T).all()):
            raise ParameterError(f"comb {i} has non-finite points or tips")
        out.append((P, T, k))
    return out


def render_curvature_comb(combs, path, *, size=(1000, 800), view=(28.0, -58.0), title=None) -> str:
    """Write a PNG of one or more curvature combs to ``path`` (atomically); returns the path."""
    items = _combs(combs)
    size, view = picture.check_render_options("normal", "percentile", size, view)
    flat = all(P.shape[1] == 2 for P, _, _ in items)  # plane curves are drawn in their plane
    _, right, up = raster.view_basis(*view)

    def to_screen(X):
        if flat:
            return X
        X3 = X if X.shape[1] == 3 else np.column_stack([X, np.zeros(len(X))])
        return np.column_stack([X3 @ right, X3 @ up])

    plt = picture.pyplot()
    from matplotlib import colormaps
    from matplotlib import colors as mcolors
    from matplotlib.collections import LineCollection

    top = max(float(np.abs(k).max()) for _, _, k in items)
    norm = mcolors.Normalize(0.0, top if top > 0 else 1.0)
    cmap = colormaps.get_cmap("plasma")
    w, h = size
    fig, ax = plt.subplots(figsize=(w / picture.DPI, h / picture.DPI), dpi=picture.DPI)
    try:
        for P, T, k in items:
            p, t = to_screen(P), to_screen(T)
            step = max(1, -(-len(P) // MAX_TEETH))
            teeth = np.stack([p[::step], t[::step]], axis=1)
            ax.add_collection(LineCollection(teeth, colors=cmap(norm(np.abs(k[::step]))), linewidths=0.7))
            ax.plot(t[:, 0], t[:, 1], color="0.35", linewidth=0.8)
            ax.plot(p[:, 0], p[:, 1], color="black", linewidth=1.6)
        ax.set_aspect("equal")
        ax.autoscale_view()
        ax.axis("off")
        bar = fig.colorbar(plt.cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax, fraction=0.035, pad=0.02)
        bar.set_label("|curvature| (1/length)", fontsize=9)
        bar.ax.tick_params(labelsize=8)
        n = len(items)
        ax.set_title(title if title is not None else f"curvature comb{'s' if n > 1 else ''} of {n} curve{'s' if n > 1 else ''}",
                     fontsize=10)
        fig.tight_layout()
        return atomic_write(path, lambda tmp: fig.savefig(tmp, format="png", dpi=picture.DPI, facecolor="white"))
    finally:
        plt.close(fig)
