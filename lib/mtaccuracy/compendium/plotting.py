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


def close(fig) -> None:
    """Close ``fig`` (pyplot forgets it and its memory is freed).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    """
    plt.close(fig)
