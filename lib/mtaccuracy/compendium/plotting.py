"""One figure style and deterministic saving.

``save(fig, path, stamp=...)`` writes PNG and SVG with no timestamps (SVG ``Date`` removed, a
fixed ``svg.hashsalt`` for element ids), so the same figure gives the same bytes, and stamps the
run's provenance record into each file (PNG text chunk ``mtaccuracy:provenance``, SVG
``Description``); a notebook saves through :meth:`mtaccuracy.compendium.notebook.Run.figure`.

The SVG's clip paths are renamed after what the file prints (:func:`stable_svg_ids`):
matplotlib names each clip path by a hash of its rectangle's floats at full precision, and an
axes laid out by ``tight_layout`` or ``bbox_inches="tight"`` sits where its tick labels put
it, so a change of the plotted data in the 15th digit (another BLAS kernel, an optimiser's
last step) moved the rectangles by 1e-13 pt and renamed every clip path, although no printed
coordinate and no PNG pixel changed.
"""

from __future__ import annotations

import io
import re
from pathlib import Path

import matplotlib as mpl
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import ListedColormap, to_rgb
from scipy import ndimage

from .provenance import write_atomic

STYLE = {
    "figure.dpi": 100,
    "savefig.dpi": 150,
    "font.size": 9,
    "axes.titlesize": 10,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "legend.frameon": False,
    "svg.hashsalt": "mtaccuracy",
    "svg.fonttype": "path",
    "path.simplify": False,
}

#: Colours for the published (paper) and reproduced (ours) series, used by every notebook.
PUBLISHED = "#d95f02"
REPRODUCED = "#1b9e77"

#: The categorical palette of every map or set of lines whose colours name things (Paul Tol's
#: "muted" scheme, https://personal.sron.nl/~pault/): every pair differs by delta-E*ab >= 17
#: under a simulated deuteranopia (Machado et al. 2009), where tab20's red and green differ by 7
#: (``tests/test_palette.py``). More categories than colours repeat them: label the regions
#: directly (:func:`category_map`).
CATEGORICAL = ("#CC6677", "#332288", "#DDCC77", "#117733", "#88CCEE", "#882255", "#44AA99",
               "#999933", "#AA4499")
#: The colour of "no category" (no data, no first-order term): Tol's pale grey.
NO_CATEGORY = "#DDDDDD"
# every figure's default line colours (C0, C1, ...) are the same palette, not matplotlib's tab10
STYLE["axes.prop_cycle"] = mpl.cycler(color=list(CATEGORICAL))
#: Two things highlighted among many (Yang Fig. 21: the paper's layout and the best), from
#: :data:`CATEGORICAL`, and the grey of the rest, drawn as context.
HIGHLIGHT = ("#332288", "#117733")
CONTEXT = "#BBBBBB"


#: Units as a reader writes them; the files and the library name them in ASCII (``rmse_um``,
#: a scorecard's ``unit`` column ``degC``, an axis in ``deg``).
UNIT_SYMBOLS = {"um": "µm", "degC": "°C", "deg": "°", "percent": "%"}


def unit_symbol(unit: str) -> str:
    """``"um/m/degC"`` -> ``"µm/m/°C"``, for labels and tables a reader sees.

    Each part of an ASCII unit is written with its symbol (:data:`UNIT_SYMBOLS`)."""
    return "/".join(UNIT_SYMBOLS.get(part, part) for part in str(unit).split("/"))


def use_style() -> None:
    """Apply the compendium's figure style to matplotlib's global settings."""
    mpl.rcParams.update(STYLE)


#: PNG text key naming the scorecard rows a figure is scored with (for a reader of the file).
SCORED_WITH = "mtaccuracy:scored-with"

#: A clip path as matplotlib's SVG backend writes it (one per line of its ``<defs>``).
_CLIP_PATH = re.compile(r'[ \t]*<clipPath id="([^"]+)">(.*?)</clipPath>\n?', re.S)
#: Prefix of the renamed clip paths (``clip1``, ``clip2``, ... in order of definition).
CLIP_PREFIX = "clip"


def stable_svg_ids(svg: str) -> str:
    """``svg`` with each clip path named after its printed definition, not matplotlib's hash.

    Matplotlib's names hash the unrounded rectangle; these are ``clip1``, ``clip2``, ... in order of
    first definition, clip paths that print the same merged into one.

    The file then depends only on what it prints (coordinates to six decimals), as its PNG
    depends only on pixels: rounding noise in the data behind a figure no longer renames its
    clip paths.

    Parameters
    ----------
    svg : str
        An SVG document written by matplotlib.

    Returns
    -------
    str
        The same document with the clip paths renamed (unchanged when it has none; applied
        twice, the same as once).
    """
    defs = _CLIP_PATH.findall(svg)
    if not defs:
        return svg
    others = set(re.findall(r'\bid="([^"]+)"', svg)) - {old for old, _ in defs}
    clash = sorted(i for i in others if re.fullmatch(rf"{CLIP_PREFIX}\d+", i))
    if clash:
        raise ValueError(f"the SVG has elements other than clip paths with the ids "
                         f"{', '.join(clash)}; cannot give its clip paths those names")
    by_body: dict[str, str] = {}
    rename = {}
    for old, body in defs:
        rename[old] = by_body.setdefault(body, f"{CLIP_PREFIX}{len(by_body) + 1}")
    kept = set()

    def definition(m):
        new = rename[m.group(1)]
        if new in kept:  # prints the same as one already defined: drop it
            return ""
        kept.add(new)
        return m.group(0).replace(f'id="{m.group(1)}"', f'id="{new}"', 1)

    svg = _CLIP_PATH.sub(definition, svg)
    refs = re.compile(r"url\(#(" + "|".join(map(re.escape, rename)) + r")\)")
    return refs.sub(lambda m: f"url(#{rename[m.group(1)]})", svg)


def save(fig, path, *, stamp: str, formats=("png", "svg"), title: str | None = None,
         scored_with=None) -> list[Path]:
    """Save ``fig`` as ``<path>.<fmt>`` for each format, without timestamps.

    The SVG's clip paths are named after what it prints (:func:`stable_svg_ids`), so that the
    bytes do not change with rounding noise in the data.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : Path
        Where, without the extension (``<folder>/fig05_position_total_sobol``).
    stamp : str
        The run's provenance record as text: PNG text chunk ``mtaccuracy:provenance``, SVG
        ``Description``.
    formats : tuple of str
        Formats written.
    title : str, optional
        Stored as the file's ``Title``.
    scored_with : list of str, optional
        Patterns (:mod:`fnmatch`, on a scorecard row's ``item`` or ``"item: quantity"``) of the
        rows that score what the figure shows, stored in the PNG's metadata.

    Returns
    -------
    list of Path
        The files written, in the order of ``formats``.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    written = []
    for fmt in formats:
        target = path.with_name(f"{path.name}.{fmt}")
        if fmt == "svg":
            meta = {"Date": None, "Creator": "mtaccuracy", "Description": stamp}
        elif fmt == "png":
            meta = {"Software": "mtaccuracy", "mtaccuracy:provenance": stamp}
        else:
            meta = {}
        if title:
            meta["Title"] = title
        if scored_with and fmt == "png":
            meta[SCORED_WITH] = " | ".join(scored_with)
        buf = io.BytesIO()
        with mpl.rc_context(STYLE):
            fig.savefig(buf, format=fmt, metadata=meta, bbox_inches="tight")
        data = buf.getvalue()
        if fmt == "svg":
            data = stable_svg_ids(data.decode("utf-8")).encode("utf-8")
        write_atomic(target, data)
        written.append(target)
    return written


def category_colours(categories, *, none=None) -> dict:
    """A colour for each category: :data:`CATEGORICAL` in order, :data:`NO_CATEGORY` for ``none``.

    Parameters
    ----------
    categories : iterable
        The categories (hashable), in the order they take the palette's colours; past its nine
        colours they repeat.
    none : optional
        The category meaning "nothing" (e.g. ``-1``), drawn pale grey and taking no colour.

    Returns
    -------
    dict
        Category -> colour (hex string).
    """
    out, k = {}, 0
    for c in categories:
        if c == none:
            out[c] = NO_CATEGORY
        elif c not in out:
            out[c] = CATEGORICAL[k % len(CATEGORICAL)]
            k += 1
    return out


def text_colour(colour) -> str:
    """Black or white, whichever contrasts more with ``colour`` (WCAG relative luminance).

    Parameters
    ----------
    colour : str or tuple
        A matplotlib colour.

    Returns
    -------
    str
        ``"k"`` on a light colour, ``"w"`` on a dark one (luminance below 0.179, where the two
        contrast ratios are equal).
    """
    c = np.asarray(to_rgb(colour))
    lin = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    return "k" if lin @ [0.2126, 0.7152, 0.0722] > 0.179 else "w"


def category_map(ax, codes, colours: dict, *, extent, labels: dict | None = None,
                 fontsize: float = 8.0):
    """Draw a grid of categories in their colours, each region labelled with its name where it fits.

    A region is a connected set of cells (4-neighbours) of one category. Its label is placed at
    the cell farthest from its edge among those where the label's box, estimated from the axes'
    size and ``fontsize``, lies wholly inside the region; a region too small for its label is
    left to the legend. A label of a non-convex region (a ring, an L) thus sits on it, where its
    centroid might not.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Where (its current size sets which labels fit: lay the figure out first).
    codes : array (rows, cols)
        The category of each cell, row 0 at the bottom (``origin="lower"``).
    colours : dict
        Category -> colour (:func:`category_colours`); every category of ``codes`` must be a key.
    extent : sequence of 4 float
        ``[left, right, bottom, top]`` of the grid's outer edges in data units.
    labels : dict, optional
        Category -> label; a category missing here (or with an empty label) is not labelled.
    fontsize : float
        Of the labels, in points.

    Returns
    -------
    list of matplotlib.text.Text
        The labels drawn.
    """
    codes = np.asarray(codes)
    keys = list(colours)
    missing = set(np.unique(codes).tolist()) - set(keys)
    if missing:
        raise ValueError(f"category_map: no colour for the categories {sorted(missing)}")
    index = {k: i for i, k in enumerate(keys)}
    img = np.vectorize(index.get, otypes=[int])(codes)
    cmap = ListedColormap([colours[k] for k in keys])
    ax.imshow(img, origin="lower", aspect="auto", interpolation="nearest", cmap=cmap,
              vmin=-0.5, vmax=len(keys) - 0.5, extent=extent)
    rows, cols = codes.shape
    box = ax.get_position()
    fig_w, fig_h = ax.figure.get_size_inches() * 72.0
    cell_w, cell_h = box.width * fig_w / cols, box.height * fig_h / rows   # points
    texts = []
    for key in keys:
        label = (labels or {}).get(key, "")
        if not label or not (codes == key).any():
            continue
        # the label's half-box in cells (width: ~0.6 em per character), with a half-cell margin
        hw = int(np.ceil((0.3 * fontsize * len(label) + 2) / cell_w))
        hh = int(np.ceil((0.5 * fontsize + 2) / cell_h))
        regions, n = ndimage.label(codes == key)
        for r in range(1, n + 1):
            mask = np.pad(regions == r, 1)          # the grid's edge bounds a region
            fits = ndimage.binary_erosion(mask, np.ones((2 * hh + 1, 2 * hw + 1), bool))
            if not fits.any():
                continue
            depth = np.where(fits, ndimage.distance_transform_edt(mask), -1.0)
            deepest = np.argwhere(depth == depth.max())      # ties: the one nearest their mean
            i, j = deepest[np.argmin(((deepest - deepest.mean(axis=0)) ** 2).sum(axis=1))]
            x = extent[0] + (j - 0.5) * (extent[1] - extent[0]) / cols   # padded: j - 1 + 0.5
            y = extent[2] + (i - 0.5) * (extent[3] - extent[2]) / rows
            texts.append(ax.text(x, y, label, ha="center", va="center", fontsize=fontsize,
                                 color=text_colour(colours[key])))
    return texts


def close(fig) -> None:
    """Close ``fig`` (pyplot forgets it and its memory is freed).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    """
    plt.close(fig)
