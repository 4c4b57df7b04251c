"""The categorical palette stays readable under deuteranopia; a categorical map labels its regions.

Deuteranopia is simulated with Machado, Oliveira and Fernandes (2009), "A physiologically-based
model for simulation of color vision deficiency", IEEE TVCG 15(6), the severity-1.0 matrix of
their Table, applied to linear sRGB; differences are CIE76 delta-E*ab in CIELAB (D65).

The threshold, 10: a delta-E*ab of about 2.3 is a just-noticeable difference between two large
patches side by side (Sharma 2003, Digital Color Imaging Handbook); a map asks more, to match a
region to a legend entry across the figure, and the issue found tab20's red and green, 7.3 apart
under deuteranopia (reproduced here), unreadable. Ten is above that failing pair and over four
just-noticeable differences; the palette's worst pair is 17.
"""

import itertools

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.colors import to_rgb  # noqa: E402

from mtaccuracy.compendium import plotting  # noqa: E402

THRESHOLD = 10.0   # delta-E*ab (module docstring)

#: Machado et al. 2009, deuteranomaly at severity 1.0 (deuteranopia), on linear RGB.
MACHADO_DEUTERANOPIA = np.array([[0.367322, 0.860646, -0.227968],
                                 [0.280085, 0.672501, 0.047413],
                                 [-0.011820, 0.042940, 0.968881]])
#: linear sRGB -> XYZ (IEC 61966-2-1, D65)
SRGB_TO_XYZ = np.array([[0.4124564, 0.3575761, 0.1804375],
                        [0.2126729, 0.7151522, 0.0721750],
                        [0.0193339, 0.1191920, 0.9503041]])


def _linear(rgb):
    rgb = np.asarray(rgb, float)
    return np.where(rgb <= 0.04045, rgb / 12.92, ((rgb + 0.055) / 1.055) ** 2.4)


def _lab(linear_rgb):
    xyz = linear_rgb @ SRGB_TO_XYZ.T / SRGB_TO_XYZ.sum(axis=1)    # relative to the D65 white
    d = 6 / 29
    f = np.where(xyz > d ** 3, np.cbrt(xyz), xyz / (3 * d * d) + 4 / 29)
    return np.stack([116 * f[..., 1] - 16, 500 * (f[..., 0] - f[..., 1]),
                     200 * (f[..., 1] - f[..., 2])], axis=-1)


def lab(colours, *, deuteranopia=False):
    """CIELAB of matplotlib colours (n, 3), as seen by a deuteranope if asked."""
    rgb = _linear([to_rgb(c) for c in colours])
    if deuteranopia:
        rgb = np.clip(rgb @ MACHADO_DEUTERANOPIA.T, 0.0, 1.0)
    return _lab(rgb)


def worst_pair(colours, *, deuteranopia):
    """The smallest delta-E*ab between two of ``colours`` and that pair."""
    L = lab(colours, deuteranopia=deuteranopia)
    return min((float(np.linalg.norm(L[i] - L[j])), colours[i], colours[j])
               for i, j in itertools.combinations(range(len(colours)), 2))


def test_the_simulation_reproduces_the_failing_tab20_pair():
    """The simulation is not a no-op: tab20's red and green, 70 apart to a trichromat, fall to the
    issue's delta-E 7 (it has to be above 6.5 and below 8 to be the same measurement)."""
    red, green = plt.get_cmap("tab20")(6), plt.get_cmap("tab20")(4)
    normal = worst_pair([red, green], deuteranopia=False)[0]
    deut = worst_pair([red, green], deuteranopia=True)[0]
    assert normal > 60
    assert 6.5 < deut < 8
    assert deut < THRESHOLD        # the test below would fail tab20


def test_machado_matrix_keeps_greys_and_the_lab_white_point():
    """Rows sum to 1 (a grey stays that grey) and white is L* = 100, a* = b* = 0."""
    np.testing.assert_allclose(MACHADO_DEUTERANOPIA.sum(axis=1), 1.0, atol=1e-5)
    greys = ["#000000", "#777777", "#DDDDDD", "#FFFFFF"]
    np.testing.assert_allclose(lab(greys, deuteranopia=True), lab(greys), atol=2e-3)
    np.testing.assert_allclose(lab(["#FFFFFF"])[0], [100, 0, 0], atol=1e-4)


@pytest.mark.parametrize("deuteranopia", [False, True])
def test_every_pair_of_the_palette_stays_distinguishable(deuteranopia):
    colours = [*plotting.CATEGORICAL, plotting.NO_CATEGORY]
    d, a, b = worst_pair(colours, deuteranopia=deuteranopia)
    assert d >= THRESHOLD, f"{a} and {b}: delta-E {d:.1f}"


@pytest.mark.parametrize("deuteranopia", [False, True])
def test_the_highlighted_context_and_series_colours_stay_distinguishable(deuteranopia):
    """Fig. 21's two highlighted layouts, its grey context, the published series, ours, black."""
    colours = [*plotting.HIGHLIGHT, plotting.CONTEXT, plotting.PUBLISHED, plotting.REPRODUCED,
               "#000000"]
    d, a, b = worst_pair(colours, deuteranopia=deuteranopia)
    assert d >= THRESHOLD, f"{a} and {b}: delta-E {d:.1f}"


def test_category_colours_order_none_and_repeat():
    cols = plotting.category_colours([-1, 3, 7, 3], none=-1)
    assert cols == {-1: plotting.NO_CATEGORY, 3: plotting.CATEGORICAL[0],
                    7: plotting.CATEGORICAL[1]}
    many = plotting.category_colours(range(11))
    assert many[9] == plotting.CATEGORICAL[0] and many[10] == plotting.CATEGORICAL[1]


def test_text_colour_contrasts():
    assert plotting.text_colour("#332288") == "w"
    assert plotting.text_colour(plotting.NO_CATEGORY) == "k"
    assert plotting.text_colour("#DDCC77") == "k"


def _map():
    """A 40 x 60 grid: a ring of category 1 around a block of 2, category 3 filling the rest, and
    a 2 x 2 speck of 4 too small for any label."""
    rows, cols = np.mgrid[0:40, 0:60]
    codes = np.full((40, 60), 3)
    ring = (abs(rows - 20) <= 14) & (abs(cols - 30) <= 20)
    codes[ring] = 1
    codes[(abs(rows - 20) <= 7) & (abs(cols - 30) <= 10)] = 2
    codes[0:2, 0:2] = 4
    return codes


def test_category_map_labels_each_region_on_itself():
    codes = _map()
    fig, ax = plt.subplots(figsize=(8, 6))
    extent = [-120.0, 120.0, 0.0, 360.0]
    colours = plotting.category_colours([1, 2, 3, 4])
    texts = plotting.category_map(ax, codes, colours, extent=extent,
                                  labels={1: "ring", 2: "block", 3: "outside", 4: "speck"})
    found = {}
    for t in texts:
        x, y = t.get_position()
        j = int((x - extent[0]) / (extent[1] - extent[0]) * codes.shape[1])
        i = int((y - extent[2]) / (extent[3] - extent[2]) * codes.shape[0])
        found.setdefault(t.get_text(), []).append(codes[i, j])
        assert t.get_color() == plotting.text_colour(colours[codes[i, j]])
    # the ring's centroid lies in the block: its label must not
    assert found == {"ring": [1], "block": [2], "outside": [3]}
    # the image shows the palette's colours where the categories are
    rgba = ax.images[0].to_rgba(ax.images[0].get_array())
    np.testing.assert_allclose(rgba[20, 30, :3], to_rgb(colours[2]), atol=1e-9)
    np.testing.assert_allclose(rgba[20, 12, :3], to_rgb(colours[1]), atol=1e-9)
    # the text fits: its drawn box lies inside its region's cells
    fig.canvas.draw()
    to_data = ax.transData.inverted()
    for t in texts:
        (x0, y0), (x1, y1) = to_data.transform(t.get_window_extent())
        j0, j1 = ((np.array([x0, x1]) - extent[0]) / 4.0).astype(int)   # 4 units per column
        i0, i1 = ((np.array([y0, y1]) - extent[2]) / 9.0).astype(int)   # 9 units per row
        assert len(set(codes[i0:i1 + 1, j0:j1 + 1].ravel())) == 1, t.get_text()
    plt.close(fig)


def test_category_map_refuses_a_category_without_a_colour():
    fig, ax = plt.subplots()
    with pytest.raises(ValueError, match=r"no colour for the categories \[4\]"):
        plotting.category_map(ax, _map(), plotting.category_colours([1, 2, 3]),
                              extent=[0, 1, 0, 1])
    plt.close(fig)
