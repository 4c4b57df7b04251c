"""Where things live in the compendium, independent of the current working directory."""

from __future__ import annotations

import os
from pathlib import Path

#: The repository root (``lib/mtaccuracy/paths.py`` -> two levels up from ``lib``).
ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "data"
PAPERS = DATA / "papers"
NOTEBOOKS = ROOT / "notebooks"
FIGURES = ROOT / "figures"

#: Environment variable that redirects relative output folders (used by the tests, so that
#: executing a notebook under test never rewrites the committed figures).
OUTPUT_BASE_ENV = "MTACCURACY_OUTPUT_BASE"


def output_dir(path: str | os.PathLike) -> Path:
    """Resolve a notebook's ``output_dir`` parameter and create the folder.

    A relative path is taken from the repository root, or from ``$MTACCURACY_OUTPUT_BASE``
    when that is set; an absolute path is used as given.
    """
    p = Path(path)
    if not p.is_absolute():
        base = os.environ.get(OUTPUT_BASE_ENV)
        p = (Path(base) if base else ROOT) / p
    p.mkdir(parents=True, exist_ok=True)
    return p
