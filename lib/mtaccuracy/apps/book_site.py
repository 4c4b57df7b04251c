"""The book's site as files: replaced only over a build of ours, outputs copied, pages light.

Split from :mod:`.book`, which writes the pages; :func:`finish_site` does what Sphinx does not."""

from __future__ import annotations

import html
import os
import re
import shutil
from pathlib import Path

from .book_safety import BookError

#: A file that marks a folder as written by the book (only such folders are replaced).
MARKER = ".mtaccuracy-book"


def _own_folder(folder: Path) -> None:
    """Refuse a folder this module did not write (no marker) that is in the way."""
    if folder.exists() and not (folder / MARKER).is_file():
        raise BookError(f"{folder} exists and was not written by make book (no {MARKER}); "
                        f"move it away, nothing was changed")


def _replace(new: Path, final: Path) -> None:
    """Move the freshly built ``new`` to ``final``: the old build (ours) goes last."""
    _own_folder(final)
    (new / MARKER).write_text("written by python -m mtaccuracy.apps.book\n")
    old = final.with_name(f".{final.name}-old-{os.getpid()}")
    if final.exists():
        os.replace(final, old)
    os.replace(new, final)
    shutil.rmtree(old, ignore_errors=True)


def _copy_outputs(folder: Path, side: dict, target: Path, bad: set[str], prefix: str = "") -> None:
    """Copy the figures and tables a record lists (never a file of the user's, nor a broken
    one) into ``target``."""
    target.mkdir(parents=True, exist_ok=True)
    for name in sorted(side.get("files", {})):
        f = folder / name
        if f.is_file() and f.suffix in (".png", ".svg", ".csv") and prefix + name not in bad:
            shutil.copy(f, target / name)


#: A notebook's Markdown link to a file of a run (``[Fig. 5](../figures/<stem>/<file>)``).
_FILE_LINK = re.compile(r"\[([^\]]+)\]\((\.\./figures/[^)\s]+)\)")


def site_links(text: str) -> str:
    """A notebook's links to its run's files as plain links to their copies in the site.

    MyST would make them downloads (a second copy of every figure, opened as a file, not shown
    by the browser)."""
    return _FILE_LINK.sub(lambda m: f'<a href="{html.escape(m.group(2))}">'
                                    f"{html.escape(m.group(1))}</a>", text)


#: What the theme loads on every page and the book does without: its icon script (1.5 MB, "so
#: that users can add custom icons"; its stylesheet draws the icons the book uses with its web
#: font) and the search index (270 kB, for search-as-you-type, which is off: the search box
#: submits to search.html, which loads the index itself).
_HEAVY_SCRIPTS = tuple(re.compile(rf'<script (?:defer )?src="[^"]*{name}\.js[^"]*"></script>\s*')
                      for name in ("_static/scripts/fontawesome", "searchindex"))


def finish_site(src: Path, site: Path) -> None:
    """What Sphinx does not do: ship the files the pages link, load images lazily, stay light.

    The figures (PNG, SVG) and tables the chapters link are copied into the site under
    ``figures/`` (the "full size" and "SVG" links), the notebooks under ``notebooks/`` (the
    "download" links); every ``<img>`` gets ``loading="lazy"``; the theme's icon script and
    the source maps go (:data:`_HEAVY_SCRIPTS`)."""
    if (src / "figures").is_dir():
        shutil.copytree(src / "figures", site / "figures", dirs_exist_ok=True)
    for nb in sorted((src / "notebooks").glob("*.ipynb")):
        shutil.copy(nb, site / "notebooks" / nb.name)
    for page in site.rglob("*.html"):
        text = page.read_text(encoding="utf-8")
        lazy = re.sub(r"<img (?![^>]*\bloading=)", '<img loading="lazy" ', text)
        for heavy in _HEAVY_SCRIPTS[:1 if page == site / "search.html" else 2]:
            lazy = heavy.sub("", lazy)
        if lazy != text:
            page.write_text(lazy, encoding="utf-8")
    for f in {*(site / "_static").rglob("*.map"), *(site / "_static").rglob("fontawesome.js*")}:
        f.unlink()
