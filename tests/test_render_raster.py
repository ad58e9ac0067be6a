"""The z-buffer rasterizer of splinekit.plot against pixel counts and depths worked out by hand,
and pictures where drawing order used to decide what is in front."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from matplotlib.image import imread

from splinekit.mesh import PolyMesh
from splinekit.plot import picture, raster, render_mesh


def _square(x0, y0, x1, y1, z=0.0):
    """Two screen triangles sharing the diagonal of an axis-aligned rectangle, at depth z."""
    xy = np.array([[[x0, y0], [x1, y0], [x1, y1]], [[x0, y0], [x1, y1], [x0, y1]]], float)
    return xy, np.full((2, 3), z)


def _centres_inside(lo, hi, n):
    """Pixel indices in [0, n) whose centres i + 0.5 lie in [lo, hi]."""
    i = np.arange(n)
    return (i + 0.5 >= lo) & (i + 0.5 <= hi)


@given(st.floats(0, 30), st.floats(0, 30), st.floats(1, 30), st.floats(1, 30))
@settings(max_examples=40, deadline=None)
def test_rectangle_covers_exactly_the_pixel_centres_inside_it(x0, y0, w, h):
    """A shared diagonal leaves no crack: the covered set is exactly the pixel centres inside
    the rectangle. Centres on its outline (within rounding) may go either way."""
    xy, depth = _square(x0, y0, x0 + w, y0 + h)
    f = raster.rasterize(xy, depth, 64, 48)
    eps = 1e-9
    inside = _centres_inside(y0 + eps, y0 + h - eps, 48)[:, None] & _centres_inside(x0 + eps, x0 + w - eps, 64)[None, :]
    near = _centres_inside(y0 - eps, y0 + h + eps, 48)[:, None] & _centres_inside(x0 - eps, x0 + w + eps, 64)[None, :]
    assert f.covered[inside].all()
    assert not f.covered[~near].any()


def test_barycentric_weights_reproduce_the_pixel_centres():
    rng = np.random.default_rng(7)
    xy = rng.uniform(0, 50, (30, 3, 2))
    f = raster.rasterize(xy, rng.uniform(-1, 1, (30, 3)), 50, 50)
    assert f.covered.sum() > 200
    centres = f.interpolate(xy)
    rows, cols = np.nonzero(f.covered)
    np.testing.assert_allclose(centres, np.column_stack([cols + 0.5, rows + 0.5]), atol=1e-9)
    assert np.all(f.weights[f.covered] >= 0) and np.allclose(f.weights[f.covered].sum(axis=1), 1.0)


def test_nearest_wins_whatever_the_order():
    near, far = _square(5, 5, 30, 30, z=2.0), _square(10, 10, 40, 40, z=1.0)
    for first, second in ((near, far), (far, near)):
        f = raster.rasterize(np.concatenate([first[0], second[0]]), np.concatenate([first[1], second[1]]), 48, 48)
        assert f.depth[20, 20] == 2.0  # the overlap shows the nearer square
        assert f.depth[35, 35] == 1.0  # the far one where it is alone
        assert f.depth[2, 2] == -np.inf and f.triangle[2, 2] == -1


def test_piercing_triangles_switch_at_their_intersection():
    """Two screen-filling squares, one with depth x, the other with depth 40 - x: each is in front
    on its side of x = 20, pixel by pixel (a painter's sort shows one of them whole)."""
    xy = np.concatenate([_square(0, 0, 40, 20)[0]] * 2)
    x = xy[..., 0]
    depth = np.concatenate([x[:2], 40.0 - x[2:]])
    f = raster.rasterize(xy, depth, 40, 20)
    first = f.triangle < 2
    cols = np.arange(40) + 0.5
    np.testing.assert_array_equal(first, np.broadcast_to(cols > 20, (20, 40)))


def test_many_passes_give_the_same_frame(monkeypatch):
    rng = np.random.default_rng(11)
    xy, depth = rng.uniform(-5, 45, (60, 3, 2)), rng.uniform(0, 1, (60, 3))
    whole = raster.rasterize(xy, depth, 40, 40)
    monkeypatch.setattr(raster, "CANDIDATES_PER_PASS", 97)
    pieces = raster.rasterize(xy, depth, 40, 40)
    np.testing.assert_array_equal(whole.depth, pieces.depth)
    np.testing.assert_array_equal(whole.covered, pieces.covered)


def test_edge_on_and_offscreen_triangles_cover_nothing():
    xy = np.array([[[0, 0], [10, 10], [20, 20]], [[-30, -30], [-10, -30], [-10, -10]]], float)
    f = raster.rasterize(xy, np.zeros((2, 3)), 32, 32)
    assert not f.covered.any()


def test_projection_keeps_proportions_and_fills_the_frame():
    cube = np.array([[x, y, z] for x in (0, 2) for y in (0, 2) for z in (0, 2)], float)
    xy, depth, scale = raster.project(cube, (0.0, 0.0), 200, 100, fill=0.9)  # looking along -x: y right, z up
    assert np.isclose(np.ptp(xy[:, 0]), np.ptp(xy[:, 1])) and np.isclose(np.ptp(xy[:, 1]), 90.0) and np.isclose(scale, 45.0)
    np.testing.assert_allclose(depth, cube[:, 0])
    right = xy[cube[:, 1] == 2, 0].min() > xy[cube[:, 1] == 0, 0].max()
    up = xy[cube[:, 2] == 2, 1].max() < xy[cube[:, 2] == 0, 1].min()  # rows grow downwards
    assert right and up


def _crossed_quads():
    """Two 2 x 2 squares through the z axis, crossing at right angles (an X seen from above)."""
    V = np.array([[-1, -1, -1], [1, 1, -1], [1, 1, 1], [-1, -1, 1],
                  [-1, 1, -1], [1, -1, -1], [1, -1, 1], [-1, 1, 1]], float)
    return PolyMesh(V, [[0, 1, 2, 3], [4, 5, 6, 7]])


def test_crossing_surfaces_show_the_nearer_one_per_pixel(tmp_path):
    """The view (0, 0) looks from +x with +y to the right: left of the crossing line (y < 0) the
    square through (1, -1) is nearer, right of it the square through (1, 1). Both have the same
    mean depth, so a per-polygon depth sort draws one of them whole over the other."""
    path = render_mesh(_crossed_quads(), tmp_path / "x.png", color="patch", size=(200, 160), view=(0.0, 0.0))
    img = imread(path)[..., :3]
    left, right = img[80, 40], img[80, 160]
    assert np.abs(left - right).max() > 0.2  # two different patch colours, not one square drawn over the other


def test_through_hole_shows_the_background(tmp_path):
    """A square frame with a square hole, seen from above: the hole is white, the frame is not."""
    outer = np.array([[-3, -3], [3, -3], [3, 3], [-3, 3]], float)
    inner = outer / 3
    ring = np.concatenate([outer, inner])
    V = np.concatenate([np.c_[ring, np.zeros(8)], np.c_[ring, np.ones(8)]])
    faces = []
    for i in range(4):
        j = (i + 1) % 4
        faces += [[i, j, 4 + j, 4 + i], [8 + i, 12 + i, 12 + j, 8 + j]]  # bottom and top rings
        faces += [[i, 8 + i, 8 + j, j], [4 + i, 4 + j, 12 + j, 12 + i]]  # outer and inner walls
    path = render_mesh(PolyMesh(V, faces), tmp_path / "frame.png", color="normal", size=(200, 200), view=(90.0, -90.0))
    img = imread(path)[..., :3]
    assert np.all(img[95:106, 95:106] > 0.99)  # the hole: background
    assert np.all(img[100, 30:40] < 0.95)  # the frame


def test_long_titles_wrap_inside_the_picture(tmp_path):
    title = "bracket (" + ", ".join(f"parameter_{i}={i * 1.5}" for i in range(14)) + "): normal"
    text, height = picture._wrapped_title(title, 480, 400)
    assert len(text.splitlines()) >= 3 and height > 3 * 17
    assert max(len(line) for line in text.splitlines()) * 7.5 <= 480 - 20
    path = render_mesh(_crossed_quads(), tmp_path / "t.png", color="mean", size=(480, 400), title=title)
    img = imread(path)[..., :3]
    assert np.all(img[:, -4:] > 0.99)  # nothing drawn against the right edge: the title did not run off
    ink_rows = np.nonzero((img[:, :300] < 0.5).any(axis=(1, 2)))[0]
    assert ink_rows.min() < 20  # the title starts at the top


@pytest.mark.parametrize("fill", [0.5, 0.92])
def test_object_fills_the_asked_share_of_the_frame(tmp_path, fill):
    xy, _, _ = raster.project(np.random.default_rng(0).normal(size=(500, 3)), (28.0, -58.0), 300, 200, fill=fill)
    assert np.isclose(max(np.ptp(xy[:, 0]) / 300, np.ptp(xy[:, 1]) / 200), fill)


def test_symlog_scale_ignores_a_singular_spike_and_labels_clear_of_zero():
    """99.5 % of the area at curvature 1e-3..1, 0.5 % at 1e4 (a degenerate point): the log scale
    tops out at the 99th area percentile, not at the spike."""
    from splinekit.plot import colors

    values = np.concatenate([np.geomspace(1e-3, 1.0, 995), np.full(5, 1e4)])
    norm, _ = colors.norm_and_cmap("curvature", values, "symlog", np.ones(1000))
    assert 0.9 < norm.vmax <= 1.0 and norm.vmin == 0.0
    ticks = colors.symlog_ticks(norm)
    assert ticks[0] == 0.0 and np.all(ticks[1:] >= 0.25 * norm.linthresh) and ticks[-1] <= norm.vmax
    signed, _ = colors.norm_and_cmap("mean", np.concatenate([-values, values]), "symlog", np.ones(2000))
    both = colors.symlog_ticks(signed)
    np.testing.assert_allclose(both, -both[::-1])  # symmetric about 0


@pytest.mark.parametrize("scale", ["percentile", "symlog"])
def test_colour_bar_names_the_scale_asked_for(tmp_path, monkeypatch, scale):
    from splinekit.plot import colors

    asked = []
    label = colors.colorbar_label
    monkeypatch.setattr(colors, "colorbar_label", lambda color, s: asked.append(s) or label(color, s))
    render_mesh(_crossed_quads(), tmp_path / "s.png", color="mean", scale=scale, size=(300, 200))
    assert asked == [scale]
    assert ("log scale" in label("mean", scale)) == (scale == "symlog")
