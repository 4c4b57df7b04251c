"""The compendium's book: ``make book`` (``python -m mtaccuracy.apps.book``).

A Sphinx site (MyST-NB, the book theme: the stack under Jupyter Book 1) built from what is
committed, never re-running a notebook: a home page (verdicts by basis, the papers and their
DOIs); one chapter per notebook with the paper, the notebook's "What we conclude", its figures
in the paper's order (the paper module's ``FIGURES``) with the captions their run recorded in
``provenance.json``, its scorecard as a table that sorts and filters (DataTables, through
``itables``) and, after ``make sweep``, the rows whose verdict changes with the seed, and its
parameters as its declaration (``mtaccuracy.papers.<paper>.Parameters``) gives them; the whole
scorecard on one page, the executed notebooks, and the science layer's reference.

Not Jupyter Book 2: mystmd downloads its theme and a Node.js runtime when it builds, which
neither this project's machines nor a reader offline can do.  Everything the pages load is in
the site (MathJax from ``jupyter-server-mathjax``, DataTables from ``itables``): served (GitHub
Pages, ``python -m http.server -d build/book/html -b 127.0.0.1``) it works offline; opened from
disk, the scorecards stay static tables (browsers load no module script from ``file://``).

Every output shown is first checked against its folder's ``provenance.json``
(:func:`mtaccuracy.compendium.provenance.folder_problems`; a sweep's tables against
``sweep/provenance.json``), and every figure against its caption (:func:`chapter_figures`): a
broken, changed or missing output, a figure whose record has no caption, a caption in
``FIGURES`` whose figure the run did not write is named on standard error and in its chapter,
and the command exits with status 1 (the book is still written, so the problem can be seen).
A file the record does not list (the user's) is neither judged nor shown.

Nothing shown can run script (:mod:`mtaccuracy.apps.book_safety`): every name, caption and
card cell is escaped; an entry of a record that is not a plain file name is named, never
opened; an executed notebook is shown only when its source is the one its run recorded, and
its outputs (which no record covers) without any HTML but a table's.  A record that cannot be
read (a merge conflict, ``[]``), a dangling link under ``data/`` or a place that cannot be
written end ``make book`` in one line naming the file.  The home leads with each paper's
finding (README.md's "What we found" lines, read, not re-typed), its key figure and its
chapter; a figure enlarges to its PNG (its SVG beside it, both shipped in the site) and loads
lazily.

The site goes to ``build/book/html``, its source to ``build/book/src``: each built beside
(``.html-<pid>``) and then moved in place, and only over a folder carrying this module's marker
file.

Local imports: Sphinx, itables and MathJax are imported when the book is built, so that the
checks of the outputs against their provenance run without them.
"""

from __future__ import annotations

import argparse
import errno
import html
import json
import math
import os
import pkgutil
import re
import shutil
import sys
import time
from pathlib import Path
from urllib.parse import quote

import pandas as pd

import mtaccuracy

from ..compendium import provenance, reproduction, scorecard, workflow
from ..compendium.notebook import FIGURES, NOTEBOOKS, ROOT
from ..compendium.plotting import unit_symbol
from ..papers.parameters import literal, type_name
from .book_safety import (
    BookError,
    code,
    dangling_links,
    md_text,
    notebook_problems,
    plain_name,
    record,
    safe_notebook,
)
from .book_site import (
    _copy_outputs,
    _own_folder,
    _replace,
    finish_site,
    site_links,
)

BOOK = ROOT / "book"
BUILD = ROOT / "build" / "book"
#: The scorecard columns shown, in order.
CARD_COLUMNS = ["item", "quantity", "published", "reproduced", "tolerance", "verdict", "basis",
                "kind", "note"]
#: Where ``make sweep`` writes a notebook's sweep, inside its output folder.
SWEEP = "sweep"
#: Library modules left out of the reference (paper code, the workflow, the apps: no API).
_NOT_API = ("mtaccuracy.compendium", "mtaccuracy.papers", "mtaccuracy.apps")


def repository() -> str:
    """The repository's URL: ``CITATION.cff``'s ``repository-code``, the one place it is set.

    The book's repository, source and Binder links follow it (they work once the repository is
    published there, as the README says)."""
    import yaml

    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text(encoding="utf-8"))
    url = str(cff.get("repository-code", "")).rstrip("/")
    if not re.fullmatch(r"https://github\.com/[\w.-]+/[\w.-]+", url):
        raise BookError(f"{ROOT / 'CITATION.cff'}: repository-code {url!r} is not a GitHub "
                        "repository URL (https://github.com/<owner>/<name>)")
    return url


def binder_url(path: str) -> str:
    """Binder's launch link of a file of the repository (JupyterLab at that file)."""
    owner_name = repository().removeprefix("https://github.com/")
    return f"https://mybinder.org/v2/gh/{owner_name}/HEAD?urlpath=lab/tree/{quote(path)}"


def stems() -> list[str]:
    """Every notebook, in notebook order (the workflow's declarations)."""
    return [c.stem for c in workflow.DECLARATIONS]


# ---------------------------------------------------------------------------- the contents

def captions(stem: str) -> dict:
    """The captions of notebook ``stem``'s figures in the paper's order: its module's FIGURES."""
    return getattr(sys.modules[workflow.declaration(stem).__module__], "FIGURES", {})


def chapter_figures(stem: str, folder: Path, side: dict | None = None
                    ) -> tuple[list[dict], list[tuple[Path, str]]]:
    """The figures a chapter shows, and the problems of their captions.

    The figures are ``{"figure", "label", "caption"}`` as their run recorded them, in the order
    of the paper module's ``FIGURES``, then any other in the run's order; the problems, a PNG
    whose record has no caption and a caption in ``FIGURES`` whose figure the run did not write
    (``side``: the folder's record, read when not given)."""
    side = record(folder)[0] if side is None else side
    pngs = {n[:-4]: e for n, e in side.get("files", {}).items() if n.endswith(".png")}
    order = list(captions(stem))
    where = f"{workflow.declaration(stem).__module__}.FIGURES"
    problems = [(folder / f"{n}.png", f"is captioned in {where} but its run did not write it")
                for n in order if n not in pngs]
    others = sorted((n for n in pngs if n not in order), key=lambda n: (
        o if isinstance(o := pngs[n].get("order"), int | float) else math.inf, n))
    shown = []
    for name in [*(n for n in order if n in pngs), *others]:
        entry = pngs[name]
        if not plain_name(f"{name}.png"):
            problems.append((folder / provenance.SIDECAR,
                             f"lists the figure {name + '.png'!r}, whose name a page cannot "
                             "show (letters, digits, '.', '_' and '-' only)"))
            continue
        if not str(entry.get("caption") or "").strip():
            problems.append((folder / f"{name}.png",
                             f"has no caption in {provenance.SIDECAR} (its run recorded none)"))
            continue
        shown.append({"figure": name, "label": str(entry.get("label", "")).strip(),
                      "caption": " ".join(str(entry["caption"]).split())})
    return shown, problems


def sweep_record(folder: Path, stem: str) -> dict:
    """The ``provenance.json`` of ``make sweep``'s tables in ``folder/sweep`` ({} if none)."""
    side = record(folder / SWEEP)[0]
    ok = (side.get("run", {}).get("notebook") == f"{stem} (sweep)"
          and "verdict_stability.csv" in side.get("files", {}))
    return side if ok else {}


def check(figures: Path, stems: list[str]) -> dict[str, list[tuple[Path, str]]]:
    """Every problem of the outputs shown, per notebook (see the module's docstring)."""
    out: dict[str, list] = {}
    for stem in stems:
        folder = figures / stem
        side, found = record(folder)
        found += provenance.folder_problems(folder, side) + chapter_figures(stem, folder, side)[1]
        found += notebook_problems(stem, side)
        sweep = sweep_record(folder, stem)
        if sweep:
            found += record(folder / SWEEP)[1] + provenance.folder_problems(folder / SWEEP, sweep)
        if found:
            out[stem] = found
    return out


def notebook_parts(nb_path: Path) -> dict:
    """The title and the conclusion of a notebook.

    The title is its first ``#`` heading; the conclusion is the markdown cell whose heading says
    "What we conclude", without that heading."""
    nb = json.loads(Path(nb_path).read_text(encoding="utf-8"))
    md = ["".join(c["source"]) for c in nb["cells"] if c["cell_type"] == "markdown"]
    title = next((m.splitlines()[0].lstrip("# ").strip() for m in md if m.startswith("# ")),
                 Path(nb_path).stem)
    conclusion = ""
    for m in md:
        first, _, rest = m.partition("\n")
        if first.startswith("#") and "what we conclude" in first.lower():
            conclusion = rest.strip()
            break
    return {"title": title, "conclusion": conclusion}


def _verdict_html(v: str) -> str:
    return f'<span class="verdict {v.replace(" ", "-")}">{html.escape(v)}</span>'


def scorecard_html(cards: pd.DataFrame, table_id: str, dt_url: str,
                   columns: list[str] | None = None, *, wide: str = "full-width") -> str:
    """A scorecard as a static HTML table that DataTables enhances where it can load.

    Every row is in the page's HTML, so the table reads from a file (``file://``, where a
    browser refuses the module script) and without script; served, DataTables (``dt_url``,
    itables' bundle inside the book, its default export) adds sorting, the search box and
    pages.  Each cell carries its column's name (``data-label``): on a phone a row is a card
    of labelled lines (``mtaccuracy.css``).  On a wide screen it takes the right margin too:
    ``wide="full-width"``, the theme's class, which hides a page's contents sidebar while the
    table is in view; ``"wide"`` on a page without that sidebar (the theme's script fails on
    ``full-width`` there)."""
    cols = columns or CARD_COLUMNS
    total = sum(_WIDTHS[c] for c in cols)
    head = "".join(f'<th style="width:{100 * _WIDTHS[c] / total:.1f}%">{html.escape(c)}</th>'
                   for c in cols)
    body = []
    for _, r in cards.iterrows():
        cells = []
        for c in cols:
            v = str(r[c])
            if c in ("published", "reproduced") and v:   # the unit with its number
                v = f"{v} {unit_symbol(r['unit'])}".strip()
            shown = _verdict_html(v) if c == "verdict" else html.escape(v)
            cells.append(f'<td data-label="{html.escape(c)}">{shown}</td>')
        body.append(f"<tr>{''.join(cells)}</tr>")
    script = ('<script type="module">\n'
              f'import DataTable from "{html.escape(dt_url)}";\n'
              f'new DataTable("#{table_id}", {{autoWidth: false, pageLength: 25, '
              "lengthMenu: [10, 25, 100, -1], order: []});\n</script>")
    css = html.escape(dt_url.removesuffix(".js") + ".css")
    return (f'<link rel="stylesheet" href="{css}">\n'
            f'<div class="scorecard {wide} cols-{len(cols)}">\n'
            f'<table id="{table_id}" class="display compact">'
            f"<thead><tr>{head}</tr></thead>\n<tbody>\n" + "\n".join(body)
            + "\n</tbody></table>\n</div>\n" + script)


#: Relative widths of the scorecard's columns on a wide screen.
_WIDTHS = {"paper": 8, "item": 7, "quantity": 15, "published": 9, "reproduced": 10,
           "tolerance": 9, "verdict": 12, "basis": 10, "kind": 7, "note": 24}


def _fig_alt(label: str, caption: str) -> str:
    """A figure's alternative text (the writer escapes it as an attribute)."""
    first = re.split(r"(?<=\.)\s+(?=[A-Z])", caption.strip(), maxsplit=1)[0]
    return " ".join(f"{label}: {first}".replace('"', "'").replace("`", "").split())


def _rel(path: Path, folder: Path) -> str:
    """``path`` as the book names it: in ``folder``, else in the repository."""
    for base in (folder, ROOT):
        try:
            return Path(path).relative_to(base).as_posix()
        except ValueError:
            pass
    return Path(path).name


def _bad(stem: str, folder: Path, broken: dict) -> set[str]:
    """The names (in ``folder``) of the outputs of ``stem`` with a problem."""
    return {_rel(p, folder) for p, _ in broken.get(stem, [])}


def _provenance_details(png: Path) -> str:
    try:
        rec = provenance.from_png(png) or {}
    except (OSError, ValueError):
        rec = {}
    if not isinstance(rec, dict) or not rec:
        return ""
    params = ", ".join(f"{k}={v}" for k, v in dict(rec.get("parameters") or {}).items())
    inputs = "".join(f"<li><code>{html.escape(str(k))}</code> sha256 "
                     f"{html.escape(str(v)[:16])}…</li>"
                     for k, v in dict(rec.get("inputs") or {}).items())
    return ("<details class=\"provenance\"><summary>provenance</summary><ul>"
            f"<li>notebook <code>{html.escape(str(rec.get('notebook', '')))}</code>, source sha256 "
            f"<code>{html.escape(str(rec.get('notebook_sha256', ''))[:16])}…</code></li>"
            f"<li>library sha256 "
            f"<code>{html.escape(str(rec.get('library_sha256', ''))[:16])}…</code></li>"
            f"<li>parameters: {html.escape(params)}</li><li>inputs:<ul>{inputs}</ul></li>"
            "</ul></details>")


def _cell(text, *, escape: bool = True) -> str:
    """A Markdown table cell's text: escaped (no HTML of its own; ``escape=False`` for a
    literal of the declarations, shown as code), ``|`` and newlines kept from ending it."""
    text = html.escape(str(text), quote=False) if escape else str(text)
    return text.replace("|", "\\|").replace("\n", " ")


def parameter_lines(stem: str, run: dict | None = None) -> list[str]:
    """The notebook's parameters as a Markdown table, from its declaration.

    One row per parameter: its name, default (as the parameters cell writes it), type, what is
    allowed and its help, all read from ``Parameters`` (``Parameters.allowed``); then the
    values of the run shown that are not the defaults (``run``: its record)."""
    decl = workflow.declaration(stem)
    rows = ["| parameter | default | type | allowed | what it sets |",
            "| --- | --- | --- | --- | --- |"]
    for n in decl.names():
        p = decl.param[n]
        rows.append(f"| `{n}` | `{_cell(literal(p.default), escape=False)}` | {type_name(p)} | "
                    f"{_cell(decl.allowed(n))} | {_cell(p.doc)} |")
    given = (run or {}).get("parameters", {})
    given = given if isinstance(given, dict) else {}
    changed = {k: v for k, v in given.items() if k in decl.names() and v != decl.param[k].default}
    used = "" if not given else ("The run shown used the defaults." if not changed else
                                 "The run shown used " + ", ".join(
                                     code(f"{k}={literal(v)}") for k, v in changed.items())
                                 + ", the others at their defaults.")
    module = decl.__module__
    return ["## Parameters", "",
            f"Declared once, in `{module}.Parameters`: the notebook's parameters cell, the "
            f"workflow's checks and this table read that declaration. Run with other values: "
            f'`make reproduce NB={stem[:2]} PARAMS="name=value ..."` (the values are checked '
            f"before any work). {used}".rstrip(), "", *rows, ""]


def sweep_lines(stem: str, folder: Path, bad: set[str]) -> list[str]:
    """What ``make sweep`` found: over how many seeds, and which verdicts change with the seed.

    Nothing when the sweep's tables are missing or broken (``bad``)."""
    side = sweep_record(folder, stem)
    if not side or f"{SWEEP}/verdict_stability.csv" in bad \
            or not (folder / SWEEP / "verdict_stability.csv").is_file():
        return []
    runs = side["run"].get("runs", {})
    runs = {k: g for k, g in runs.items() if isinstance(g, dict)} if isinstance(runs, dict) \
        else {}
    seeds = sorted({g.get("seed") for g in runs.values()} - {None}, key=str)
    settings = sorted({json.dumps({k: v for k, v in g.items() if k != "seed"}, sort_keys=True)
                       for g in runs.values()})
    table = pd.read_csv(folder / SWEEP / "verdict_stability.csv", dtype=str,
                        keep_default_na=False)
    counts = [v.replace(" ", "_") for v in reproduction.VERDICTS]
    keys = ["item", "quantity", *(["setting"] if "setting" in table.columns else [])]
    moving = table[table["changes_with_seed"].str.lower() == "true"]
    span = f" ({seeds[0]} to {seeds[-1]})" if len(seeds) > 1 else ""
    where = f" at each of {len(settings)} settings" if len(settings) > 1 else ""
    links = ", ".join(f"[{n}](../figures/{stem}/{SWEEP}/{n})"
                      for n in ("verdict_stability.csv", "values.csv")
                      if (folder / SWEEP / n).is_file() and f"{SWEEP}/{n}" not in bad)
    span = html.escape(span, quote=False)
    lines = ["### Over seeds", "",
             f"`make sweep NB={stem[:2]}` re-ran the notebook over {len(seeds)} seed"
             f"{'s' if len(seeds) != 1 else ''}{span}{where} and scored every run "
             f"({len(runs)} runs): "
             + (f"the verdict of {len(moving)} of the {len(table)} rows changes with the seed."
                if len(moving) else f"no row's verdict changes with the seed ({len(table)} "
                f"rows).") + (f" Tables: {links}." if links else ""), ""]
    if len(moving):
        lines += ["| " + " | ".join(_cell(k) for k in [*keys, *reproduction.VERDICTS]) + " |",
                  "| " + " | ".join(["---"] * len(keys) + ["---:"] * len(counts)) + " |"]
        lines += ["| " + " | ".join(_cell(r[c]) for c in [*keys, *counts]) + " |"
                  for _, r in moving.iterrows()]
        lines.append("")
    return lines


def figure_label(stem: str, figure: str) -> str:
    """The label of a figure in its chapter (its ``:name:``), for cross-references."""
    return f"{stem[:2]}-{re.sub(r'[^A-Za-z0-9_-]', '-', figure)}"


def evidence_links(text: str, stem: str, shown: set[str]) -> str:
    """A conclusion's evidence links as the chapter shows them.

    The notebook links its run's files (``[Fig. 5](../figures/<stem>/<name>.png)``), which
    resolve in JupyterLab, on GitHub and from the book's pages alike; MyST would make them
    downloads.  In the chapter a figure it shows becomes a cross-reference to that figure (its
    label, :func:`figure_label`) and any other file a plain link to the copy in the site."""
    def link(m):
        label, name = m.group(1), m.group(2)
        fig = name.removesuffix(".png")
        if name.endswith(".png") and fig in shown:
            return f"{{ref}}`{label} <{figure_label(stem, fig)}>`"
        return (f'<a href="../figures/{html.escape(stem)}/{html.escape(name)}">'
                f"{html.escape(label)}</a>")

    return re.sub(rf"\[([^\]]+)\]\(\.\./figures/{re.escape(stem)}/([^)\s]+)\)", link, text)


def chapter(stem: str, figures: Path, index: dict, broken: dict) -> str:
    """One notebook's chapter (MyST Markdown), written into ``<src>/chapters/``."""
    paper = index.get(stem, {})
    folder = figures / stem
    side = record(folder)[0]
    bad = _bad(stem, folder, broken)
    parts = ({"title": stem, "conclusion": ""} if f"notebooks/{stem}.ipynb" in bad
             else notebook_parts(NOTEBOOKS / f"{stem}.ipynb"))
    lines = [f"# {parts['title']}", ""]
    if paper:
        doi = paper.get("doi", "")
        cite = re.sub(r"\.?\s*doi:\s*\S+$", "", paper.get("citation", "")).rstrip(". ") + "."
        lines += [f"**Paper.** {cite} "
                  + (f"DOI: [{doi}](https://doi.org/{doi})" if doi else "It has no DOI."), ""]
    repo = repository()
    lines += [f"**Notebook.** [the executed notebook](../notebooks/{stem}.ipynb) · "
              f'<a href="../notebooks/{quote(stem)}.ipynb" download>download (.ipynb)</a> · '
              f"[source]({repo}/blob/HEAD/notebooks/{quote(stem)}.ipynb) · "
              f"[launch on Binder]({binder_url(f'notebooks/{stem}.ipynb')}) · "
              f"[repository]({repo}); its tables are in `figures/{stem}/`.", ""]
    for path, why in broken.get(stem, []):
        name = _rel(path, figures)
        again = "sweep" if name.startswith(f"{stem}/{SWEEP}/") else "reproduce"
        lines += [f'<p class="broken"><strong>Not shown:</strong> {code(name)} '
                  f"{html.escape(why)}; run <code>make {again} NB={stem[:2]}</code> again.</p>",
                  ""]
    lines += opening_lines(stem, index, figures, broken)
    figs = [f for f in chapter_figures(stem, folder, side)[0]
            if f"{f['figure']}.png" not in bad and (folder / f"{f['figure']}.png").is_file()]
    if parts["conclusion"]:
        lines += ["## What we conclude", "", ":::{container} conclusion",
                  evidence_links(parts["conclusion"], stem, {f["figure"] for f in figs}),
                  ":::", ""]
    if figs:
        lines += ["## Figures", ""]
    for f in figs:
        png = folder / f"{f['figure']}.png"
        url = f"../figures/{stem}/{quote(png.name)}"
        lines += [f"```{{figure}} {url}", f":alt: {_fig_alt(f['label'], f['caption'])}",
                  f":name: {figure_label(stem, f['figure'])}",
                  f":target: {url}", ":figclass: full-width", "",
                  f"**{md_text(f['label'])}.** {md_text(f['caption'])}", "```", ""]
        svg = png.with_suffix(".svg")
        links = [f'<a href="{html.escape(url)}">full size</a>']
        if svg.is_file() and svg.name in side.get("files", {}) and svg.name not in bad:
            links.append(f'<a href="../figures/{stem}/{html.escape(quote(svg.name))}">SVG</a>')
        lines += [f'<span class="figure-links">{" · ".join(links)}</span> '
                  f"{_provenance_details(png)}", ""]
    if (folder / "reproduction.csv").is_file() and "reproduction.csv" not in bad:
        cards = pd.read_csv(folder / "reproduction.csv", dtype=str, keep_default_na=False)
        counts = cards["verdict"].value_counts()
        said = ", ".join(f"{counts[v]} {v}" for v in reproduction.VERDICTS if counts.get(v))
        lines += ["## Scorecard", "",
                  f"{len(cards)} rows: {said}. Type in the search box to filter (a verdict, "
                  "a basis, a table number); click a column's header to sort. Bases: see "
                  "[the overview](../index.md#verdicts-by-basis).", "",
                  "```{raw} html", scorecard_html(cards, f"card-{stem[:2]}",
                                                   "../_static/itables/dt_bundle.js"), "```", ""]
        lines += sweep_lines(stem, folder, bad)
    lines += parameter_lines(stem, side.get("run"))
    tables = sorted(n for n in side.get("files", {}) if n.endswith(".csv") and n not in bad
                    and (folder / n).is_file())
    if tables:
        lines += ["## Tables", "", "Every table the notebook wrote (CSV): "
                  + ", ".join(f'<a href="../figures/{stem}/{html.escape(quote(t))}">'
                              f"{html.escape(t)}</a>" for t in tables) + ".", ""]
    return "\n".join(lines)


#: The line of README.md under which the papers' one-line findings follow.
FINDINGS = "**What we found**"


def findings(index: dict, readme: Path | None = None) -> dict[str, str]:
    """Each paper's one-line finding, as README.md gives it: notebook stem -> the line.

    The lines are the list that follows the line starting with :data:`FINDINGS`, up to the
    next blank line; a line belongs to the paper whose name (``index``'s ``paper``) starts it.
    A paper without a line is left out (the home then shows its chapter without one)."""
    readme = Path(readme or ROOT / "README.md")
    try:
        lines = readme.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError):
        return {}
    start = next((k for k, li in enumerate(lines) if li.startswith(FINDINGS)), None)
    if start is None:
        return {}
    rest = lines[start + 1:]
    while rest and not rest[0].strip():
        rest = rest[1:]
    block = rest[:next((k for k, li in enumerate(rest) if not li.strip()), len(rest))]
    out = {}
    for stem, row in index.items():
        line = next((li for li in block if li.lstrip("-* ").startswith(row["paper"])), None)
        if line:
            out[stem] = line.lstrip("-* ").strip()
    return out


def key_figure(stem: str, folder: Path, bad: set[str]) -> dict | None:
    """A chapter's key figure (None if it shows none).

    The one its ``FIGURES`` marks ``key`` (a caption with a true ``key`` attribute), else the
    first of the paper's order that is shown."""
    shown = [f for f in chapter_figures(stem, folder)[0]
             if f"{f['figure']}.png" not in bad and (folder / f"{f['figure']}.png").is_file()]
    keys = [n for n, c in captions(stem).items() if getattr(c, "key", False)]
    return next((f for f in shown if f["figure"] in keys), shown[0] if shown else None)


def findings_lines(index: dict, stems: list[str], figures: Path, broken: dict) -> list[str]:
    """The home's "What we found": per paper its README line, its key figure and a link."""
    found = findings(index)
    lines = ["## What we found", "",
             "Each paper's outcome in ReScience's terms, from its printed numbers: **[Re]** "
             "every one we can check reproduced or close, **[~Re]** some, **[¬Re]** none.", ""]
    for stem in (s for s in stems if s in index):
        folder = figures / stem
        label = ""
        if (folder / "reproduction.csv").is_file() and "reproduction.csv" not in \
                _bad(stem, folder, broken):
            label = scorecard.outcome(pd.read_csv(folder / "reproduction.csv", dtype=str,
                                                  keep_default_na=False))[0] + " "
        lines += [f"### [{md_text(index[stem]['paper'])}](chapters/{stem}.md)", "",
                  f"**{label.strip()}** " * bool(label) + md_text(found.get(stem, "")), ""]
        lines += key_figure_lines(stem, figures, broken, "")
        lines += [f"[Read the chapter: the figures, the conclusion and every scored row]"
                  f"(chapters/{stem}.md)", ""]
    return lines


#: The width (px) of a key figure's preview on the home and a chapter's opening.
PREVIEW_WIDTH = 800


def preview_name(stem: str, figure: str) -> str:
    """Where a key figure's preview goes in the pages' source (:func:`write_previews`)."""
    return f"previews/{stem}/{figure}-preview.png"


def key_figure_lines(stem: str, figures: Path, broken: dict, up: str) -> list[str]:
    """A key figure as the home and a chapter's opening show it (a preview, to the full PNG).

    The preview is at most :data:`PREVIEW_WIDTH` px wide in 128 colours; a click enlarges it
    to the full PNG.  ``up`` leads from the page to the site's root (``""`` or ``"../"``)."""
    folder = figures / stem
    fig = key_figure(stem, folder, _bad(stem, folder, broken))
    if not fig:
        return []
    url = f"{up}figures/{stem}/{quote(fig['figure'])}.png"
    return [f"```{{figure}} {up}{preview_name(stem, quote(fig['figure']))}",
            f":alt: {_fig_alt(fig['label'], fig['caption'])}", f":target: {url}",
            ":class: key-figure", "",
            f"**{md_text(fig['label'])}.** {md_text(fig['caption'])}", "```", ""]


def write_previews(src: Path, figures: Path, stems: list[str], broken: dict) -> None:
    """The key figures' previews (:func:`key_figure_lines`), made with Pillow."""
    from PIL import Image

    for stem in stems:
        folder = figures / stem
        fig = key_figure(stem, folder, _bad(stem, folder, broken))
        if not fig:
            continue
        out = src / preview_name(stem, quote(fig["figure"]))
        out.parent.mkdir(parents=True, exist_ok=True)
        with Image.open(folder / f"{fig['figure']}.png") as im:
            rgb = im.convert("RGB")
            if rgb.width > PREVIEW_WIDTH:
                rgb = rgb.resize((PREVIEW_WIDTH, round(rgb.height * PREVIEW_WIDTH / rgb.width)),
                                 Image.Resampling.LANCZOS)
            rgb.quantize(128, method=Image.Quantize.MEDIANCUT).save(out, optimize=True)


def opening_lines(stem: str, index: dict, figures: Path, broken: dict) -> list[str]:
    """A paper's chapter's opening: its outcome, its finding and its key figure.

    The outcome is [Re], [~Re] or [¬Re] (:func:`scorecard.outcome`), the finding README.md's
    line."""
    folder = figures / stem
    if stem not in index or "reproduction.csv" in _bad(stem, folder, broken) \
            or not (folder / "reproduction.csv").is_file():
        return []
    cards = pd.read_csv(folder / "reproduction.csv", dtype=str, keep_default_na=False)
    label, counts = scorecard.outcome(cards)
    return [":::{container} opening", f"**{label}** {md_text(findings(index).get(stem, ''))}",
            "", f"{md_text(counts)} Every row: [the scorecard](#scorecard) below; what the labels "
            "mean: [the overview](../index.md#what-we-found).", ":::", "",
            *key_figure_lines(stem, figures, broken, "../")]


def home(cards: pd.DataFrame, index: dict, stems: list[str], figures: Path | None = None,
         broken: dict | None = None) -> str:
    """The home page: the findings first, then the scorecard, the papers, the other chapters.

    The findings are README.md's lines (:func:`findings`) with each paper's key figure and a
    link to its chapter; ``figures`` and ``broken`` as :func:`chapter` takes them."""
    own = [s for s in stems if s not in index]
    cards = cards.map(lambda v: html.escape(str(v), quote=False))
    papers = [f"- [{index[s]['paper']}](chapters/{s}.md): "
              + notebook_parts(NOTEBOOKS / f"{s}.ipynb")["title"].split(": ", 1)[-1]
              + (f" ([doi:{d}](https://doi.org/{d}))" if (d := index[s].get("doi")) else
                 " (no DOI)") for s in stems if s in index]
    return "\n".join([
        "# mtaccuracy: machine-tool accuracy papers, reproduced", "",
        "A reproducible research compendium: five published studies of machine-tool accuracy "
        "(geometric-error sensitivity, thermal error, spindle error separation), each "
        "re-computed by one notebook from its equations, every printed number scored against "
        "what the code gives, with a verdict and the basis of that verdict. Everything here is "
        "regenerated by `make reproduce`; this book shows what is committed. The code, the "
        f"notebooks and the data: [the repository]({repository()}) (a link that works once the "
        "repository is published there); each chapter links its notebook's source, a download "
        "and a Binder launch.", "",
        *findings_lines(index, stems, Path(figures or FIGURES), broken or {}),
        "## The scorecard", "",
        scorecard.headline(cards), "",
        "## Verdicts by basis", "",
        scorecard.crosstab_markdown(reproduction.crosstab(cards)),
        "What each basis means:", "", scorecard.bases_markdown(),
        "Every row, sortable and filterable: [the scorecard](scorecard.md).", "",
        "## The papers", "", *papers, "",
        "## Your own data", "",
        *[f"- [{notebook_parts(NOTEBOOKS / f'{s}.ipynb')['title']}](chapters/{s}.md)"
          for s in own], "",
        *[line for caption, pages in (
            ("Papers", [f"chapters/{s}" for s in stems if s in index]),
            ("Your own data", [f"chapters/{s}" for s in own]),
            ("Executed notebooks", [f"notebooks/{s}" for s in stems]),
            ("Reference", ["scorecard", "api/index"]))
          for line in ["```{toctree}", ":hidden:", f":caption: {caption}", "", *pages, "```",
                       ""]]])


def scorecard_page(cards: pd.DataFrame) -> str:
    """Every scored row of the papers on one page."""
    return "\n".join([
        "# The scorecard", "",
        f"All {len(cards)} scored rows of the five papers. Type in the search box to filter "
        "(a paper, a verdict, a basis, a table number); click a header to sort. The bases are "
        "defined on [the first page](index.md#verdicts-by-basis).", "",
        "```{raw} html",
        scorecard_html(cards, "card-all", "./_static/itables/dt_bundle.js",
                       ["paper", *CARD_COLUMNS], wide="wide"), "```", ""])


def api_modules() -> list[str]:
    """The library's public modules (the science layer), for the reference."""
    return sorted(m.name for m in pkgutil.walk_packages(mtaccuracy.__path__, "mtaccuracy.")
                  if not any(part.startswith("_") for part in m.name.split("."))
                  and not m.name.startswith(_NOT_API))


def api_pages() -> dict[str, str]:
    """The reference's pages: an index and one ``automodule`` page per module."""
    mods = api_modules()
    pages = {"index": "\n".join([
        "# Library reference", "",
        "Generated from the numpydoc docstrings of `lib/mtaccuracy` (the science layer; the "
        "paper code, the workflow and the apps are not an API).", "",
        "```{toctree}", ":maxdepth: 1", "", *mods, "```", ""])}
    for m in mods:
        pages[m] = "\n".join([f"# `{m}`", "", "```{eval-rst}", f".. automodule:: {m}",
                              "   :members:", "```", ""])
    return pages


# ---------------------------------------------------------------------------- the build

def write_source(src: Path, figures: Path, stems: list[str], broken: dict) -> None:
    """The pages' source: conf.py, generated Markdown, copied notebooks, MathJax and DataTables.

    Copies of ``figures/`` and ``data/`` go with the notebooks, so that their links resolve."""
    import itables
    import jupyter_server_mathjax

    src.mkdir(parents=True)
    shutil.copy(BOOK / "conf.py", src / "conf.py")
    static = src / "_static"
    shutil.copytree(BOOK / "_static", static)
    shutil.copytree(Path(jupyter_server_mathjax.__file__).parent / "static", static / "mathjax",
                    ignore=shutil.ignore_patterns("localization", "*.md"))
    (static / "itables").mkdir()
    for name in ("dt_bundle.js", "dt_bundle.css"):
        shutil.copy(Path(itables.__file__).parent / "html" / name, static / "itables" / name)
    index = scorecard.papers_index()
    cards = scorecard.collect(figures)
    write_previews(src, figures, stems, broken)
    (src / "index.md").write_text(home(cards, index, stems, figures, broken), encoding="utf-8")
    (src / "scorecard.md").write_text(scorecard_page(cards), encoding="utf-8")
    for kind in ("chapters", "notebooks", "api"):
        (src / kind).mkdir()
    for stem in stems:
        (src / "chapters" / f"{stem}.md").write_text(chapter(stem, figures, index, broken),
                                                     encoding="utf-8")
        nb = safe_notebook(NOTEBOOKS / f"{stem}.ipynb", [
            (p, w) for p, w in broken.get(stem, []) if p == NOTEBOOKS / f"{stem}.ipynb"])
        for cell in nb.get("cells", []):     # the run's files open in the site, not as downloads
            if cell.get("cell_type") == "markdown":
                text = "".join(cell["source"]) if isinstance(cell["source"], list) else \
                    cell["source"]
                cell["source"] = site_links(text)
        (src / "notebooks" / f"{stem}.ipynb").write_text(json.dumps(nb, indent=1),
                                                         encoding="utf-8")
    for name, text in api_pages().items():
        (src / "api" / f"{name}.md").write_text(text, encoding="utf-8")
    # the outputs the pages show or link (a broken one neither), and the data the notebooks link
    for stem in stems:
        folder = figures / stem
        bad = _bad(stem, folder, broken)
        _copy_outputs(folder, record(folder)[0], src / "figures" / stem, bad)
        sweep = sweep_record(folder, stem)
        if sweep:
            _copy_outputs(folder / SWEEP, sweep, src / "figures" / stem / SWEEP, bad, f"{SWEEP}/")
    dangling_links(ROOT / "data")
    shutil.copytree(ROOT / "data", src / "data")


def build(out: Path = BUILD, figures: Path | None = None, *, quiet: bool = True
          ) -> tuple[Path, dict, list[str]]:
    """Build the book into ``out/html``.

    Returns (that folder, the problems found per notebook, Sphinx's warnings)."""
    from sphinx.cmd.build import build_main

    figures = Path(figures or FIGURES)
    out = Path(out)
    names = stems()
    broken = check(figures, names)
    out.mkdir(parents=True, exist_ok=True)
    src_final, html_final = out / "src", out / "html"
    _own_folder(src_final)
    _own_folder(html_final)
    pid = os.getpid()
    src, site, doctrees = (out / f".src-{pid}", out / f".html-{pid}", out / f".doctrees-{pid}")
    log = out / f".warnings-{pid}.txt"
    for p in (src, site, doctrees):
        shutil.rmtree(p, ignore_errors=True)  # a stale one of this pid is ours
    try:
        write_source(src, figures, names, broken)
        args = ["-b", "html", "-d", str(doctrees), "-j", "auto", "-w", str(log), str(src),
                str(site)]
        code = build_main((["-q"] if quiet else []) + args)
        warnings = [w for w in log.read_text(encoding="utf-8").splitlines() if w.strip()] \
            if log.is_file() else []
        if code:
            raise BookError(f"sphinx-build failed (exit status {code}); run "
                            f"{sys.executable} -m sphinx {' '.join(args)} to see why")
        finish_site(src, site)
        _replace(src, src_final)
        _replace(site, html_final)
    finally:
        for p in (src, site, doctrees):
            shutil.rmtree(p, ignore_errors=True)
        log.unlink(missing_ok=True)
    return html_final, broken, warnings


def main(argv=None) -> int:
    """``python -m mtaccuracy.apps.book [--out DIR] [--figures DIR] [--verbose]``."""
    ap = argparse.ArgumentParser(prog="python -m mtaccuracy.apps.book",
                                 description="Build the compendium's book from what is "
                                             "committed (nothing is executed).")
    ap.add_argument("--out", type=Path, default=BUILD, help="build folder (default build/book)")
    ap.add_argument("--figures", type=Path, default=None,
                    help="the outputs to show (default figures/)")
    ap.add_argument("--verbose", action="store_true", help="show Sphinx's progress")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    try:
        site, broken, warnings = build(args.out, args.figures, quiet=not args.verbose)
    except (BookError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:  # a read-only checkout, a full disk: the file, not a traceback
        where = exc.filename or args.out
        fix = ("; build elsewhere with --out DIR" if exc.errno in (errno.EACCES, errno.EPERM,
                                                                   errno.EROFS) else "")
        print(f"error: {where}: {exc.strerror or exc}{fix}", file=sys.stderr)
        return 2
    for found in broken.values():
        for path, why in found:
            print(f"error: {provenance.output_kind(path)} {path} {why}", file=sys.stderr)
    size = sum(f.stat().st_size for f in site.rglob("*") if f.is_file())
    print(f"book: {provenance.shown(site / 'index.html')} ({time.perf_counter() - t0:.0f} s, "
          f"{size / 1e6:.1f} MB, {len(warnings)} Sphinx warning(s)); open it in a browser, "
          f"or serve it: python -m http.server -d {provenance.shown(site)} -b 127.0.0.1")
    return 1 if broken else 0


if __name__ == "__main__":
    raise SystemExit(main())
