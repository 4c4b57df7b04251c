"""What the book shows, made safe (:mod:`mtaccuracy.apps.book`): nothing in it can run script.

A folder's ``provenance.json`` read strictly (a failure is one line naming the file), its
entries that are not file names left out; the executed notebooks checked against their run's
record, their outputs (which no record covers) reduced to what cannot carry script; text from a
record or a file written into Markdown escaped.
"""

from __future__ import annotations

import html
import json
import os
import re
from html.parser import HTMLParser
from pathlib import Path

from ..compendium import provenance
from ..compendium.notebook import NOTEBOOKS


class BookError(RuntimeError):
    """The book cannot be built: one line naming the file.

    A record that cannot be read, a folder that is not the build's own, a dangling link,
    Sphinx failed."""


def _conflict_line(text: str) -> int | None:
    """The line (from 1) of the first merge-conflict marker in ``text``, or None."""
    for k, line in enumerate(text.splitlines(), 1):
        if line.startswith(("<<<<<<< ", "=======", ">>>>>>> ")) or line in ("<<<<<<<",
                                                                             ">>>>>>>"):
            return k
    return None


def record(folder: Path) -> tuple[dict, list[tuple[Path, str]]]:
    """An output folder's ``provenance.json``, checked, and the entries the book leaves out.

    Returns ``({}, [])`` when there is none.  An entry whose name is not a file name in the
    folder (a path, ``..``, a control character) is dropped from the record returned and named
    as a problem of the ``provenance.json`` (never opened, copied or linked).

    Raises
    ------
    BookError
        The file cannot be read, is not JSON (a merge conflict's markers: the line), or is not
        the object a run writes (``files`` an object of objects, ``run`` an object): one line
        naming the file and the fix.
    """
    path = Path(folder) / provenance.SIDECAR
    if not path.is_file():
        return {}, []
    again = "resolve it, or run make reproduce again"
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise BookError(f"{path}: cannot be read ({exc}); {again}") from None
    try:
        data = json.loads(text)
    except ValueError as exc:
        line = _conflict_line(text)
        why = (f"line {line} is a merge-conflict marker" if line else f"not JSON ({exc})")
        raise BookError(f"{path}: {why}; {again}") from None
    files = data.get("files", {}) if isinstance(data, dict) else None
    if not isinstance(data, dict) or not isinstance(data.get("run", {}), dict) \
            or not isinstance(files, dict) \
            or not all(isinstance(e, dict) for e in files.values()):
        raise BookError(f"{path}: not a run's record (an object whose 'files' maps each file "
                        f"name to an object); {again}")
    names = [n for n in files if not _file_name(n)]
    problems = [(path, f"lists {n!r}, which is not a file name in its folder (not shown)")
                for n in names]
    return {**data, "files": {n: e for n, e in files.items() if n not in names}}, problems


def plain_name(name: str) -> bool:
    """Whether ``name`` can be a figure's file name in a page: letters, digits, ``._-``."""
    return bool(re.fullmatch(r"[A-Za-z0-9_][A-Za-z0-9_.-]*", name))


def dangling_links(folder: Path) -> None:
    """Refuse a link under ``folder`` to a file that does not exist (the book copies it).

    Raises
    ------
    BookError
        Naming the first such link and where it points."""
    for p in sorted(Path(folder).rglob("*")):
        if p.is_symlink() and not p.exists():
            raise BookError(f"{p} is a link to {os.readlink(p)}, which does not exist; restore "
                            "it (git checkout) or remove the link")


def _file_name(name: str) -> bool:
    """Whether ``name`` is a plain file name (no folder, no ``..``, no control character)."""
    return (bool(name) and name not in (".", "..") and not re.search(r"[/\\\x00-\x1f]", name))


def notebook_problems(stem: str, side: dict, *, notebook: Path | None = None
                      ) -> list[tuple[Path, str]]:
    """The executed notebook's problem, if any: its source is not the one its run recorded.

    Its cells (markdown included) must hash to the ``notebook_sha256`` of the folder's
    ``provenance.json`` (:func:`mtaccuracy.compendium.provenance.notebook_source_hash`); a
    notebook without a record, or edited since its run, is not shown (``notebook``: its
    file, ``notebooks/<stem>.ipynb`` when not given)."""
    nb = Path(notebook or NOTEBOOKS / f"{stem}.ipynb")
    want = side.get("run", {}).get("notebook_sha256")
    if not nb.is_file():
        return [(nb, "is missing")]
    try:
        got = provenance.notebook_source_hash(nb)
    except (OSError, ValueError, AttributeError, TypeError) as exc:
        return [(nb, f"cannot be read ({type(exc).__name__})")]
    if not want:
        return [(nb, f"has no run recorded in {provenance.SIDECAR}")]
    if got != want:
        return [(nb, f"does not match the notebook_sha256 in {provenance.SIDECAR} (edited "
                     "after its run)")]
    return []


#: What a notebook output may show: these types as they are, text/html through
#: :func:`safe_html`; any other (SVG, JavaScript, Markdown, widgets) is dropped.
_MIME_KEPT = ("text/plain", "image/png", "image/jpeg", "image/gif", "text/latex")
#: The HTML a notebook output keeps (pandas' tables): tags, and their attributes.
_TAGS = {"div", "table", "thead", "tbody", "tfoot", "tr", "th", "td", "p", "br", "span", "b",
         "i", "em", "strong", "code", "sub", "sup", "caption"}
_ATTRS = {"class", "border", "colspan", "rowspan"}


class _Sanitizer(HTMLParser):
    """Rebuilds HTML from the allowed tags and attributes only, every text escaped; the
    content of ``script``, ``style`` and the like dropped."""

    _SKIP = {"script", "style", "iframe", "object", "embed", "template", "svg", "math",
             "textarea", "noscript", "title"}

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.out, self.skip = [], 0

    def handle_starttag(self, tag, attrs):
        if tag in self._SKIP:
            self.skip += 1
        elif tag in _TAGS and not self.skip:
            kept = "".join(f' {k}="{html.escape(v or "")}"' for k, v in attrs if k in _ATTRS)
            self.out.append(f"<{tag}{kept}>")

    def handle_endtag(self, tag):
        if tag in self._SKIP:
            self.skip = max(0, self.skip - 1)
        elif tag in _TAGS and not self.skip and tag != "br":
            self.out.append(f"</{tag}>")

    def handle_data(self, data):
        if not self.skip:
            self.out.append(html.escape(data, quote=False))


def safe_html(text: str) -> str:
    """What the book shows of a notebook's ``text/html`` output: a table, nothing that runs.

    ``text`` rebuilt with only the tags of a table (``_TAGS``), their harmless attributes
    (``_ATTRS``) and every text escaped; scripts, styles and any other tag dropped."""
    parser = _Sanitizer()
    parser.feed(text)
    parser.close()
    return "".join(parser.out)


def safe_notebook(notebook: Path, problems: list[tuple[Path, str]]) -> dict:
    """The executed notebook as the book shows it.

    Its outputs are not covered by its run's record, so none is trusted: ``text/html`` goes
    through :func:`safe_html`, types that can carry script are dropped.  A notebook with a
    problem (``problems``, :func:`notebook_problems`) is replaced by a page saying so."""
    stem = Path(notebook).stem
    if problems:
        why = "; ".join(w for _, w in problems)
        return {"nbformat": 4, "nbformat_minor": 5, "metadata": {}, "cells": [{
            "cell_type": "markdown", "metadata": {}, "id": "not-shown",
            "source": f"# {stem}\n\n**Not shown:** `notebooks/{stem}.ipynb` "
                      f"{html.escape(why, quote=False)}; run `make reproduce NB={stem[:2]}` "
                      "again."}]}
    nb = json.loads(Path(notebook).read_text(encoding="utf-8"))
    for cell in nb.get("cells", []):
        for out in cell.get("outputs", []):
            data = out.get("data")
            if not isinstance(data, dict):
                continue
            kept = {k: v for k, v in data.items() if k in _MIME_KEPT}
            if "text/html" in data:
                raw = data["text/html"]
                kept["text/html"] = safe_html("".join(raw) if isinstance(raw, list) else raw)
            out["data"] = kept
    return nb


#: A Markdown code span (not after a backslash), for :func:`md_text`.
_CODE_SPAN = re.compile(r"(?<![\\`])(`+)(?!`)(.+?)(?<!`)\1(?!`)")


def md_text(text) -> str:
    """Text from a record or a file (a caption, a finding) as Markdown that carries no HTML.

    ``&``, ``<`` and ``>`` escaped, its code spans written as ``<code>`` here (emphasis and
    links stay Markdown)."""
    text, out, at = str(text), [], 0
    for m in _CODE_SPAN.finditer(text):
        out += [html.escape(text[at:m.start()], quote=False), code(m.group(2).strip())]
        at = m.end()
    return "".join([*out, html.escape(text[at:], quote=False)])


def code(text) -> str:
    """``text`` as inline code, escaped (a backtick in it cannot end the code span)."""
    return f"<code>{html.escape(str(text))}</code>"
