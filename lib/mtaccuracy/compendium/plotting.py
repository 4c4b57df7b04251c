"""One figure style and deterministic saving.

``save(fig, folder, name)`` writes PNG and SVG with no timestamps (SVG ``Date`` removed, a
fixed ``svg.hashsalt`` for element ids), so the same figure gives the same bytes, and stamps the
run's provenance into each file (PNG text chunk ``mtaccuracy:provenance``, SVG
``Description``; see :mod:`mtaccuracy.compendium.provenance`).
"""

from __future__ import annotations

from pathlib import Path

import matplotlib as mpl
import matplotlib.pyplot as plt

from . import provenance

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


def use_style() -> None:
    """Apply the compendium's figure style to matplotlib's global settings."""
    mpl.rcParams.update(STYLE)


#: PNG text key naming the scorecard rows a figure is scored with (read by the report).
SCORED_WITH = "mtaccuracy:scored-with"


def save(fig, folder, name: str, formats=("png", "svg"), title: str | None = None,
         scored_with=None) -> None:
    """Save ``fig`` as ``folder/name.<fmt>`` for each format, without timestamps.  Returns
    nothing, so that a notebook cell ending with it shows no machine-specific path.

    ``scored_with``: patterns (:mod:`fnmatch`, on a scorecard row's ``item`` or
    ``"item: quantity"``) of the rows that score what the figure shows, for a figure whose
    name is not the item of its rows (``fig05_...`` drawing what Table 2 scores); the report
    captions the figure with their verdicts."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    stamp = provenance.as_text()
    for fmt in formats:
        path = folder / f"{name}.{fmt}"
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
        with mpl.rc_context(STYLE):
            fig.savefig(path, format=fmt, metadata=meta, bbox_inches="tight")
        provenance.register_output(path)


def close(fig) -> None:
    plt.close(fig)
