"""The compendium's book: ``make book`` (``python -m mtaccuracy.compendium.book``).

A Sphinx site with MyST-NB and the book theme (the stack under Jupyter Book 1), built from what
is committed, never re-running a notebook:

* a home page with the verdict x basis overview, one line per paper with its DOI, and links;
* one chapter per notebook: the paper and its DOI, the notebook's own conclusion (its "What we
  conclude" section), the figures in the paper's order with the captions of
  ``book/figures.yml`` (and each figure's provenance), and the scorecard as a table that sorts
  and filters (DataTables, through ``itables``);
* the full scorecard on one page, the executed notebooks as pages (math by MathJax), and the
  library's reference generated from its numpydoc docstrings.

Why Sphinx + MyST-NB and not Jupyter Book 2: Jupyter Book 2 (mystmd) downloads its site theme
and a Node.js runtime when it builds, which neither this project's machines nor a reader
offline can do; Jupyter Book 1 is a command-line wrapper over exactly this stack.  Everything
the pages load is in the built site: MathJax from the ``jupyter-server-mathjax`` package and
DataTables from ``itables``, so the book reads without a network.  Served (GitHub Pages, or
``python -m http.server -d build/book/html -b 127.0.0.1``) every page works; opened straight
from disk, the scorecards stay a static table (browsers load no module script from
``file://``).

Before building, every output shown is checked against its folder's ``provenance.json``
(:func:`mtaccuracy.compendium.provenance.folder_problems`) and every figure against
``book/figures.yml`` (:func:`figure_problems`): a broken, changed or missing output, a figure
without a caption or a caption without a figure is named on standard error and marked in its
chapter, and the command exits with status 1 (the book is still written, so the problem can be
seen).

The site is written to ``build/book/html`` (a fresh build in ``build/book/.html-<pid>`` first,
then moved in place, so a killed build never leaves half a site); its pages' source goes to
``build/book/src``.  Both folders are the build's own (a marker file says so): a folder of that
name without the marker is never deleted or overwritten.

Local imports: Sphinx, itables and MathJax are imported when the book is built, so that
the checks of the outputs against their provenance run without them.
"""

from __future__ import annotations

import argparse
import html
import json
import os
import pkgutil
import re
import shutil
import sys
import time
from pathlib import Path

import pandas as pd
import yaml

import mtaccuracy

from . import parameters, paths, provenance, reproduction
from .plotting import unit_symbol

BOOK = paths.ROOT / "book"
CAPTIONS = BOOK / "figures.yml"
BUILD = paths.ROOT / "build" / "book"
#: A file that marks a folder as written by this module (only such folders are replaced).
MARKER = ".mtaccuracy-book"
#: The scorecard columns shown, in order.
CARD_COLUMNS = ["item", "quantity", "published", "reproduced", "tolerance", "verdict", "basis",
                "note"]
#: Library modules left out of the reference (the compendium's machinery is not an API).
_NOT_API = ("mtaccuracy.compendium",)


class BookError(RuntimeError):
    """The book cannot be built (a folder that is not the build's own, Sphinx failed)."""


# ---------------------------------------------------------------------------- the contents

def captions(path: Path | None = None) -> dict[str, list[dict]]:
    """``book/figures.yml``: per notebook stem, its figures in the paper's order.

    Each figure is ``{"figure": stem of the PNG, "label": "Fig. 4", "caption": text}``.  A malformed
    file is a ``ValueError`` naming the file and the entry."""
    path = Path(path or CAPTIONS)
    if not path.is_file():
        raise ValueError(f"{path} is missing: it holds the figures' captions")
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8")) or {}
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f", line {mark.line + 1}" if mark else ""
        raise ValueError(f"{path}{where}: not valid YAML ({getattr(exc, 'problem', exc)})") \
            from None
    if not isinstance(data, dict):
        raise ValueError(f"{path}: expected a mapping of notebook stems to figure lists")
    for stem, figs in data.items():
        if not isinstance(figs, list):
            raise ValueError(f"{path}: {stem}: expected a list of figures")
        for k, f in enumerate(figs):
            if not isinstance(f, dict) or not {"figure", "label", "caption"} <= set(f):
                raise ValueError(f"{path}: {stem}, entry {k + 1}: needs figure, label and "
                                 f"caption")
    return data


def figure_problems(figures: Path, stems: list[str], caps: dict) -> list[tuple[Path, str]]:
    """Figures without a caption, and captions naming a figure that is not there: ``(path, why)``.

    The figures are the PNGs listed in a folder's ``provenance.json``."""
    out, where = [], paths.relative(CAPTIONS)
    for stem in stems:
        folder = figures / stem
        listed = {Path(n).stem for n in provenance.read(folder).get("files", {})
                  if n.endswith(".png")}
        captioned = [f["figure"] for f in caps.get(stem, [])]
        for name in sorted(listed - set(captioned)):
            out.append((folder / f"{name}.png", f"has no caption in {where}"))
        for name in captioned:
            if name not in listed:
                out.append((folder / f"{name}.png",
                            f"is captioned in {where} but is not one of the folder's outputs"))
        if len(set(captioned)) != len(captioned):
            out.append((folder, f"a figure is captioned twice in {where}"))
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
                   columns: list[str] | None = None) -> str:
    """A scorecard as a DataTables table (sorts by any column, filters by the search box).

    Its script is loaded from ``dt_url`` (inside the book)."""
    import itables

    cols = columns or CARD_COLUMNS
    df = cards.copy()
    for c in ("published", "reproduced"):  # the unit with the number it belongs to
        df[c] = [f"{v} {unit_symbol(u)}".strip() if v else ""
                 for v, u in zip(df[c], df["unit"], strict=True)]
    df = df[cols]
    df["verdict"] = df["verdict"].map(_verdict_html)
    for c in cols:
        if c != "verdict":
            df[c] = df[c].astype(str).map(html.escape)
    table = itables.to_html_datatable(
        df, connected=True, dt_url=dt_url, table_id=table_id, allow_html=True,
        showIndex=False, autoWidth=False, pageLength=25, lengthMenu=[10, 25, 100, -1],
        classes="display compact", display_logo_when_loading=False,
        style="table-layout:fixed;width:100%;margin:auto;caption-side:bottom")
    return f'<div class="scorecard cols-{len(cols)}">\n{table}\n</div>'


#: Relative widths of the scorecard's columns on a wide screen.
_WIDTHS = {"paper": 8, "item": 7, "quantity": 15, "published": 9, "reproduced": 10,
           "tolerance": 9, "verdict": 12, "basis": 10, "note": 28}
def _label_css() -> str:
    """On a phone each scorecard cell is shown with its column's name (one rule per column of
    the two column sets the book shows)."""
    rules, widths = [], []
    for cols in (CARD_COLUMNS, ["paper", *CARD_COLUMNS]):
        total = sum(_WIDTHS[c] for c in cols)
        rules += [f".scorecard.cols-{len(cols)} table.dataTable td:nth-child({k + 1})::before "
                  f'{{ content: "{c}: "; }}' for k, c in enumerate(cols)]
        # DataTables sizes its <col> elements: those are what a fixed layout follows
        widths += [f".scorecard.cols-{len(cols)} table.dataTable col:nth-child({k + 1}), "
                   f".scorecard.cols-{len(cols)} table.dataTable th:nth-child({k + 1}) "
                   f"{{ width: {100 * _WIDTHS[c] / total:.1f}% !important; }}"
                   for k, c in enumerate(cols)]
    return ("@media (max-width: 700px) {\n  " + "\n  ".join(rules) + "\n}\n"
            "@media (min-width: 701px) {\n  " + "\n  ".join(widths) + "\n}\n")


def _fig_alt(label: str, caption: str) -> str:
    first = re.split(r"(?<=\.)\s", caption.strip(), maxsplit=1)[0]
    return f"{label}: {first}".replace('"', "'").replace("\n", " ")


def _provenance_details(png: Path) -> str:
    rec = provenance.from_png(png) or {}
    if not rec:
        return ""
    params = ", ".join(f"{k}={v}" for k, v in rec.get("parameters", {}).items())
    inputs = "".join(f"<li><code>{html.escape(k)}</code> sha256 {html.escape(v[:16])}…</li>"
                     for k, v in rec.get("inputs", {}).items())
    return ("<details class=\"provenance\"><summary>provenance</summary><ul>"
            f"<li>notebook <code>{html.escape(rec.get('notebook', ''))}</code>, source sha256 "
            f"<code>{html.escape(str(rec.get('notebook_sha256', ''))[:16])}…</code></li>"
            f"<li>library sha256 "
            f"<code>{html.escape(str(rec.get('library_sha256', ''))[:16])}…</code></li>"
            f"<li>parameters: {html.escape(params)}</li><li>inputs:<ul>{inputs}</ul></li>"
            "</ul></details>")


def chapter(stem: str, figures: Path, caps: dict, index: dict, broken: dict) -> str:
    """One notebook's chapter (MyST Markdown), written into ``<src>/chapters/``."""
    parts = notebook_parts(paths.NOTEBOOKS / f"{stem}.ipynb")
    paper = index.get(stem, {})
    folder = figures / stem
    lines = [f"# {parts['title']}", ""]
    if paper:
        doi = paper.get("doi", "")
        cite = re.sub(r"\.?\s*doi:\s*\S+$", "", paper.get("citation", "")).rstrip(". ") + "."
        lines += [f"**Paper.** {cite} "
                  + (f"DOI: [{doi}](https://doi.org/{doi})" if doi else "It has no DOI."), ""]
    lines += [f"**Notebook.** [the executed notebook](../notebooks/{stem}.ipynb), "
              f"`notebooks/{stem}.ipynb`; its tables are in `figures/{stem}/`.", ""]
    for path, why in broken.get(stem, []):
        lines += [f'<p class="broken"><strong>Not shown:</strong> <code>{stem}/{path.name}'
                  f"</code> {html.escape(why)}; run <code>make reproduce NB={stem[:2]}</code> "
                  f"again.</p>", ""]
    if parts["conclusion"]:
        lines += ["## What we conclude", "", ":::{container} conclusion", parts["conclusion"],
                  ":::", ""]
    bad = {p.name for p, _ in broken.get(stem, [])}
    figs = [f for f in caps.get(stem, []) if f"{f['figure']}.png" not in bad
            and (folder / f"{f['figure']}.png").is_file()]
    if figs:
        lines += ["## Figures", ""]
    for f in figs:
        png = folder / f"{f['figure']}.png"
        svg = png.with_suffix(".svg")
        label, cap = str(f["label"]).strip(), " ".join(str(f["caption"]).split())
        lines += [f"```{{figure}} ../figures/{stem}/{png.name}",
                  f":alt: {_fig_alt(label, cap)}",
                  f":name: {stem[:2]}-{f['figure']}", "",
                  f"**{label}.** {cap}", "```", ""]
        extra = []
        if svg.is_file() and svg.name not in bad:
            extra.append(f'<a href="../figures/{stem}/{svg.name}">SVG</a>')
        lines += [" ".join(extra) + " " + _provenance_details(png), ""]
    card_path = folder / "reproduction.csv"
    if card_path.is_file() and "reproduction.csv" not in bad:
        cards = pd.read_csv(card_path, dtype=str, keep_default_na=False)
        counts = cards["verdict"].value_counts()
        said = ", ".join(f"{counts[v]} {v}" for v in reproduction.VERDICTS if counts.get(v))
        lines += ["## Scorecard", "",
                  f"{len(cards)} rows: {said}. Type in the search box to filter (a verdict, "
                  "a basis, a table number); click a column's header to sort. Bases: see "
                  "[the overview](../index.md#verdicts-by-basis).", "",
                  "```{raw} html", scorecard_html(cards, f"card-{stem[:2]}",
                                                   "../_static/itables/dt_bundle.js"), "```", ""]
    listed = provenance.read(folder).get("files", {})
    tables = sorted(n for n in listed if n.endswith(".csv") and n not in bad
                    and (folder / n).is_file())
    if tables:
        lines += ["## Tables", "", "Every table the notebook wrote (CSV): "
                  + ", ".join(f"[{t}](../figures/{stem}/{t})" for t in tables) + ".", ""]
    return "\n".join(lines)


def _papers_lines(index: dict, stems: list[str]) -> list[str]:
    out = []
    for stem in stems:
        p = index.get(stem)
        if not p:
            continue
        doi = p.get("doi", "")
        out.append(f"- [{p['paper']}](chapters/{stem}.md): "
                   + notebook_parts(paths.NOTEBOOKS / f"{stem}.ipynb")["title"].split(": ", 1)[-1]
                   + (f" ([doi:{doi}](https://doi.org/{doi}))" if doi else " (no DOI)"))
    return out


def home(cards: pd.DataFrame, index: dict, stems: list[str]) -> str:
    t = reproduction.crosstab(cards)
    table = ["| basis | " + " | ".join(reproduction.VERDICTS) + " | total |",
             "| --- | " + " | ".join("---:" for _ in reproduction.VERDICTS) + " | ---: |"]
    for b, r in t.iterrows():
        table.append(f"| {'**total**' if b == 'total' else b} | "
                     + " | ".join(str(r[v]) for v in reproduction.VERDICTS)
                     + f" | {r['total']} |")
    own = [s for s in stems if s not in index]
    return "\n".join([
        "# mtaccuracy: machine-tool accuracy papers, reproduced", "",
        "A reproducible research compendium: five published studies of machine-tool accuracy "
        "(geometric-error sensitivity, thermal error, spindle error separation), each "
        "re-computed by one notebook from its equations, every printed number scored against "
        "what the code gives, with a verdict and the basis of that verdict. Everything here is "
        "regenerated by `make reproduce`; this book shows what is committed.", "",
        reproduction.headline(cards), "",
        "## Verdicts by basis", "",
        *table, "",
        "What each basis means:", "",
        *[f"- **{b}**: {d}." for b, d in reproduction.BASES.items()], "",
        "Every row, sortable and filterable: [the scorecard](scorecard.md).", "",
        "## The papers", "",
        *_papers_lines(index, stems), "",
        "## Your own data", "",
        *[f"- [{notebook_parts(paths.NOTEBOOKS / f'{s}.ipynb')['title']}](chapters/{s}.md)"
          for s in own], "",
        "```{toctree}", ":hidden:", ":caption: Papers", "",
        *[f"chapters/{s}" for s in stems if s in index], "```", "",
        "```{toctree}", ":hidden:", ":caption: Your own data", "",
        *[f"chapters/{s}" for s in own], "```", "",
        "```{toctree}", ":hidden:", ":caption: Executed notebooks", "",
        *[f"notebooks/{s}" for s in stems], "```", "",
        "```{toctree}", ":hidden:", ":caption: Reference", "",
        "scorecard", "api/index", "```", ""])


def scorecard_page(cards: pd.DataFrame) -> str:
    return "\n".join([
        "# The scorecard", "",
        f"All {len(cards)} scored rows of the five papers. Type in the search box to filter "
        "(a paper, a verdict, a basis, a table number); click a header to sort. The bases are "
        "defined on [the first page](index.md#verdicts-by-basis).", "",
        "```{raw} html",
        scorecard_html(cards, "card-all", "./_static/itables/dt_bundle.js",
                       ["paper", *CARD_COLUMNS]), "```", ""])


def api_modules() -> list[str]:
    """The library's public modules (the science layer), for the reference."""
    mods = []
    for m in pkgutil.walk_packages(mtaccuracy.__path__, "mtaccuracy."):
        name = m.name
        if any(part.startswith("_") for part in name.split(".")) or name.startswith(_NOT_API):
            continue
        mods.append(name)
    return sorted(mods)


def api_pages() -> dict[str, str]:
    mods = api_modules()
    pages = {"index": "\n".join([
        "# Library reference", "",
        "Generated from the numpydoc docstrings of `lib/mtaccuracy` (the science layer; the "
        "compendium's own machinery, `mtaccuracy.compendium`, is not an API).", "",
        "```{toctree}", ":maxdepth: 1", "", *mods, "```", ""])}
    for m in mods:
        pages[m] = "\n".join([f"# `{m}`", "", "```{eval-rst}", f".. automodule:: {m}",
                              "   :members:", "```", ""])
    return pages


# ---------------------------------------------------------------------------- the build

def _own_folder(folder: Path) -> None:
    """Refuse a folder this module did not write (no marker) that is in the way."""
    if folder.exists() and not (folder / MARKER).is_file():
        raise BookError(f"{folder} exists and was not written by make book (no {MARKER}); "
                        f"move it away, nothing was changed")


def _replace(new: Path, final: Path) -> None:
    """Move the freshly built ``new`` to ``final``: the old build (ours) goes last."""
    _own_folder(final)
    (new / MARKER).write_text("written by python -m mtaccuracy.compendium.book\n")
    old = final.with_name(f".{final.name}-old-{os.getpid()}")
    if final.exists():
        os.replace(final, old)
    os.replace(new, final)
    shutil.rmtree(old, ignore_errors=True)


def write_source(src: Path, figures: Path, stems: list[str], caps: dict,
                 broken: dict) -> None:
    """The pages' source: conf.py, generated Markdown, copied notebooks, MathJax and DataTables.

    Copies of ``figures/`` and ``data/`` go with the notebooks, so that their links resolve."""
    import itables
    import jupyter_server_mathjax

    src.mkdir(parents=True)
    shutil.copy(BOOK / "conf.py", src / "conf.py")
    static = src / "_static"
    shutil.copytree(BOOK / "_static", static)
    (static / "scorecard.css").write_text(_label_css(), encoding="utf-8")
    shutil.copytree(Path(jupyter_server_mathjax.__file__).parent / "static", static / "mathjax",
                    ignore=shutil.ignore_patterns("localization", "*.md"))
    dt = Path(itables.__file__).parent / "html"
    (static / "itables").mkdir()
    for name in ("dt_bundle.js", "dt_bundle.css"):
        shutil.copy(dt / name, static / "itables" / name)
    index = reproduction.papers_index()
    cards = reproduction.collect(figures)
    (src / "index.md").write_text(home(cards, index, stems), encoding="utf-8")
    (src / "scorecard.md").write_text(scorecard_page(cards), encoding="utf-8")
    (src / "chapters").mkdir()
    for stem in stems:
        (src / "chapters" / f"{stem}.md").write_text(
            chapter(stem, figures, caps, index, broken), encoding="utf-8")
    (src / "notebooks").mkdir()
    for stem in stems:
        shutil.copy(paths.NOTEBOOKS / f"{stem}.ipynb", src / "notebooks" / f"{stem}.ipynb")
    (src / "api").mkdir()
    for name, text in api_pages().items():
        (src / "api" / f"{name}.md").write_text(text, encoding="utf-8")
    # the outputs the pages show or link (a broken one neither), and the data the notebooks link
    for stem in stems:
        bad = {p.name for p, _ in broken.get(stem, [])}
        target = src / "figures" / stem
        target.mkdir(parents=True)
        for name in sorted(provenance.read(figures / stem).get("files", {})):
            f = figures / stem / name  # only the run's outputs, never a file of the user's
            if f.is_file() and f.suffix in (".png", ".svg", ".csv") and f.name not in bad:
                shutil.copy(f, target / f.name)
    shutil.copytree(paths.DATA, src / "data")


def check(figures: Path, stems: list[str], caps: dict) -> dict[str, list[tuple[Path, str]]]:
    """Every problem of the outputs shown, per notebook (see the module's docstring)."""
    out: dict[str, list] = {}
    for stem in stems:
        found = provenance.folder_problems(figures / stem)
        found += figure_problems(figures, [stem], caps)
        if found:
            out[stem] = found
    return out


def build(out: Path = BUILD, figures: Path | None = None, *, quiet: bool = True
          ) -> tuple[Path, dict, list[str]]:
    """Build the book into ``out/html``.

    Returns (that folder, the problems found per notebook, Sphinx's warnings)."""
    from sphinx.cmd.build import build_main

    figures = Path(figures or paths.FIGURES)
    out = Path(out)
    stems = [p.stem for p in parameters.all_notebooks()]
    caps = captions()
    broken = check(figures, stems, caps)
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
        write_source(src, figures, stems, caps, broken)
        args = ["-b", "html", "-d", str(doctrees), "-j", "auto", "-w", str(log), str(src),
                str(site)]
        code = build_main((["-q"] if quiet else []) + args)
        warnings = [w for w in log.read_text(encoding="utf-8").splitlines() if w.strip()] \
            if log.is_file() else []
        if code:
            raise BookError(f"sphinx-build failed (exit status {code}); run "
                            f"{sys.executable} -m sphinx {' '.join(args)} to see why")
        _replace(src, src_final)
        _replace(site, html_final)
    finally:
        for p in (src, site, doctrees):
            shutil.rmtree(p, ignore_errors=True)
        log.unlink(missing_ok=True)
    return html_final, broken, warnings


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m mtaccuracy.compendium.book",
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
    for found in broken.values():
        for path, why in found:
            print(f"error: {provenance.output_kind(path)} {path} {why}", file=sys.stderr)
    size = sum(f.stat().st_size for f in site.rglob("*") if f.is_file())
    print(f"book: {paths.relative(site / 'index.html')} ({time.perf_counter() - t0:.0f} s, "
          f"{size / 1e6:.1f} MB, {len(warnings)} Sphinx warning(s)); open it in a browser, "
          f"or serve it: python -m http.server -d {paths.relative(site)} -b 127.0.0.1")
    return 1 if broken else 0


if __name__ == "__main__":
    raise SystemExit(main())
