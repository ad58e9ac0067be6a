"""What a picture's colours mean: the colour modes, the curvature colour scales and the shading.

Everything here works on flat arrays of samples (pixels, faces or corners).
"""

from __future__ import annotations

import numpy as np

COLOR_MODES = ("curvature", "gaussian", "mean", "normal", "patch")
"""What :func:`render_patches` / :func:`render_mesh` can color by:
``curvature`` the RMS of the principal curvatures ``sqrt((k1^2 + k2^2) / 2)``
(unsigned, 1/length), ``gaussian`` K (1/length^2, signed), ``mean`` H
(1/length, signed against the normals as everywhere in splinekit and in OCC:
a sphere with outward normals has H = -1/r), ``normal`` the unit normal as RGB, ``patch`` the patch
(or, for a plain mesh, connected component) index."""

COLOR_SCALES = ("percentile", "symlog")
"""Color scales of the curvature modes: ``percentile`` is linear and clipped
at the 98th percentile of ``|value|`` (so a few extreme values at a crease or
pole do not wash out the rest); ``symlog`` is a symmetric logarithmic scale
up to the 99th percentile of ``|value|``, linear below its 25th percentile: it
shows variation over several decades (a wing's flat top and its leading edge).
Percentiles are of surface area, not of sample count."""

SIGNED = {"gaussian": "Gaussian curvature K", "mean": "mean curvature H"}
NAN_GREY = 0.6  # undefined curvature (a degenerate point) is drawn grey


def unit_rows(n):
    """Rows of ``n`` scaled to unit length; zero rows stay zero."""
    length = np.linalg.norm(n, axis=-1, keepdims=True)
    return np.divide(n, length, out=np.zeros_like(n), where=length > 0)


def rms_curvature(K, H):
    """``sqrt((k1^2 + k2^2) / 2) = sqrt(2 H^2 - K)``, clamped at 0 against rounding."""
    return np.sqrt(np.maximum(2.0 * H * H - K, 0.0))


def curvature_field(color, K, H):
    """The scalar field a curvature colour mode shows, from Gaussian ``K`` and mean ``H``."""
    return {"curvature": lambda: rms_curvature(K, H), "gaussian": lambda: K, "mean": lambda: H}[color]()


def area_quantile(values, weights, q: float) -> float:
    """The value below which a fraction ``q`` of the total weight (surface area) lies."""
    order = np.argsort(values)
    cumulative = np.cumsum(weights[order])
    if not cumulative.size or not cumulative[-1] > 0:
        return float(np.quantile(values, q)) if values.size else 0.0
    return float(values[order][min(np.searchsorted(cumulative, q * cumulative[-1]), values.size - 1)])


def norm_and_cmap(color, values, scale, areas):
    """The matplotlib norm and colormap of a scalar field sampled with ``areas`` weights.
    The limits are area quantiles of ``|value|`` over the finite values, so that a
    fine grid on a small, sharply curved feature, or a singular point, does not set
    the scale for the whole surface."""
    from matplotlib import colormaps
    from matplotlib import colors as mcolors

    ok = np.isfinite(values)
    magnitude, weight = np.abs(values[ok]), areas[ok]
    top = float(magnitude.max()) if magnitude.size else 0.0
    clip = area_quantile(magnitude, weight, 0.98)
    if not clip > 0:
        clip = top if top > 0 else 1.0
    if not top > 0:
        top = 1.0
    signed = color in SIGNED
    if signed:
        cmap = colormaps.get_cmap("coolwarm")
    else:  # plasma without its darkest eighth, which shading would turn black
        cmap = mcolors.ListedColormap(colormaps.get_cmap("plasma")(np.linspace(0.12, 1.0, 256)), name="plasma_light")
    if scale == "percentile":
        norm = mcolors.Normalize(-clip if signed else 0.0, clip, clip=True)
    else:
        high = area_quantile(magnitude, weight, 0.99)
        high = high if high > 0 else top
        linthresh = min(max(area_quantile(magnitude, weight, 0.25), 1e-4 * high), 0.5 * high)
        norm = mcolors.SymLogNorm(linthresh, linscale=0.5, vmin=-high if signed else 0.0, vmax=high, base=10, clip=True)
    return norm, cmap


def symlog_ticks(norm) -> np.ndarray:
    """Colour-bar ticks of a SymLogNorm: 0 and the powers of ten up to its limits, leaving out
    those deep in the squeezed linear part (below a quarter of the linear threshold), where
    their labels would sit on the 0's."""
    high = max(abs(norm.vmin), abs(norm.vmax))
    decades = 10.0 ** np.arange(np.ceil(np.log10(0.25 * norm.linthresh)), np.floor(np.log10(high)) + 1)
    ticks = np.concatenate([-decades[::-1] if norm.vmin < 0 else [], [0.0], decades])
    return ticks


def colorbar_label(color, scale) -> str:
    label = SIGNED.get(color, "RMS curvature √((k1² + k2²)/2)")
    how = "clipped at the 98th area percentile" if scale == "percentile" else "log scale, clipped at the 99th area percentile"
    return f"{label}\n({how})"


def base_colors(color, values=None, normals=None, patch_id=None, norm=None, cmap=None):
    """``(n, 3)`` unshaded RGB of ``n`` samples: by the scalar ``values`` through ``norm`` and
    ``cmap`` (non-finite values grey), by unit ``normals`` as RGB, or by ``patch_id``."""
    if color == "normal":
        return 0.5 + 0.5 * normals
    if color == "patch":
        from matplotlib import colormaps

        return colormaps.get_cmap("tab20")(np.asarray(patch_id) % 20)[:, :3]
    rgb = cmap(norm(np.nan_to_num(values)))[:, :3]
    rgb[~np.isfinite(values)] = NAN_GREY
    return rgb


def shade(base, normals, eye, light):
    """Two-sided Lambert plus a little Blinn-Phong highlight on ``(n, 3)`` base colours,
    for ``(n, 3)`` unit normals seen along ``eye`` and lit along ``light`` (unit ``(3,)``)."""
    half = unit_rows((eye + light)[None, :])[0]
    diffuse = np.abs(normals @ light)
    c = np.abs(normals @ half)
    c2 = c * c
    c8 = (c2 * c2) ** 2
    spec = c8 * c8 * c8 * c8 * c8  # c ** 40 by multiplications: a float power is several times slower
    rgb = base * (0.4 + 0.6 * diffuse)[:, None] + 0.2 * spec[:, None]
    return np.clip(rgb, 0.0, 1.0)
