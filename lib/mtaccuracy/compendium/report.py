"""The static reproduction report: ``figures/index.html``, opened from disk, no server needed.

Per paper: its citation, the scorecard (published vs reproduced, the verdict by colour and by
word, the note), every regenerated figure captioned with the paper's figure number and what
the scorecard says differs, its provenance (from the PNG itself), links to every CSV table and
to an HTML export of the executed notebook (``figures/html/<stem>.html``).  A top section sums
the verdicts over all papers and gives the last run time and commit of each notebook (recorded
by the runner in ``figures/.runs.json``; the only run-dependent content, and only when present).

Every output is checked against its folder's ``provenance.json``, which lists each file the
run wrote with its SHA-256 (a ``measured`` file, wall-clock times, without one) before it is
shown: a figure (PNG, SVG) that cannot be read (a truncated file from an interrupted run, say),
a figure or table (CSV) whose bytes do not match its hash, one that the sidecar does not list,
and a file that the sidecar lists but that is no longer on disk are marked in the report (a
broken or missing figure is not shown, such a table not linked), and the command exits with
status 1 naming each.  A ``measured`` file is only required to exist (and a measured figure to
be readable).

The report uses no script and no external resource; the notebook exports have their CDN script
tags removed, so they open offline too (LaTeX then shows as source).  ``python -m
mtaccuracy.compendium.report`` builds it; ``make reproduce`` does so at the end.
"""

from __future__ import annotations

import argparse
import fnmatch
import html
import json
import os
import re
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pandas as pd
from PIL import Image

from . import paths, plotting, provenance, reproduction, runner

#: Badge colours, each at least 5:1 against the white badge text (WCAG AA asks 4.5:1).
COLOURS = {"reproduced": "#1a7a40", "close": "#8a6500", "differs": "#b3261e",
           "not reproducible": "#5f5f5f"}
#: Above this many rows a paper's scorecard starts collapsed (its summary line says what is in it).
COLLAPSE_ROWS = 15
CSS = """
body { font-family: system-ui, sans-serif; margin: 2rem auto; max-width: 1200px; color: #222;
       line-height: 1.4; padding: 0 1rem; }
h1 { margin-bottom: 0.2rem; } h2 { border-bottom: 2px solid #ddd; padding-bottom: 0.2rem;
       margin-top: 3rem; }
table { border-collapse: collapse; margin: 0.5rem 0 1rem; font-size: 0.85rem; }
th, td { border: 1px solid #ddd; padding: 0.25rem 0.5rem; vertical-align: top; text-align: left; }
th { background: #f3f3f3; } td.num { text-align: right; }
.verdict { display: inline-block; color: #fff; border-radius: 3px; padding: 0 0.4rem;
           white-space: nowrap; font-weight: 600; }
figure { margin: 1.5rem 0; border: 1px solid #eee; padding: 0.5rem; }
figure img { max-width: 100%; height: auto; }
figcaption { font-size: 0.9rem; } details { font-size: 0.8rem; } code { font-size: 0.8rem; }
details.scorecard { font-size: 0.85rem; } details.scorecard > summary { cursor: pointer;
       font-size: 1rem; margin: 0.5rem 0; } .headline { font-size: 1.1rem; }
.basis { white-space: nowrap; border-bottom: 1px dotted #888; }
.citation { color: #555; } .links a { margin-right: 0.8rem; }
.broken { background: #fde0dd; border-left: 4px solid #d73027; padding: 0.3rem 0.6rem; }
"""


def _e(text) -> str:
    return html.escape(str(text), quote=True)


def _badge(verdict: str) -> str:
    return (f'<span class="verdict" style="background:{COLOURS.get(verdict, "#444")}">'
            f"{_e(verdict)}</span>")


def _basis(basis: str) -> str:
    return (f'<span class="basis" title="{_e(reproduction.BASES.get(basis, ""))}">'
            f"{_e(basis)}</span>")


def _figure_label(name: str) -> str:
    """``fig05_...`` -> "Fig. 5"; ``fig08_09_...`` -> "Figs. 8-9"; ``table2_...`` ->
    "Table 2"; other names as they are."""
    m = re.match(r"(figs?|table)(\d+)(?:_(\d+))?(?:_|$)", name)
    if not m:
        return name
    a, b = int(m.group(2)), m.group(3)
    if m.group(1) == "table":
        return f"Table {a}"
    return f"Figs. {a}-{int(b)}" if b and b.isdigit() and len(b) <= 2 else f"Fig. {a}"


def _caption_title(label: str, title: str) -> str:
    """The figure's own title without a leading repetition of its label ("Fig. 5: ...")."""
    t = title.strip()
    for lead in (label, label.replace("Figs.", "Fig."), label.replace(". ", ".")):
        if t.lower().startswith(lead.lower()):
            t = t[len(lead):].lstrip(" :.-\u2013")
            break
    return t


def _numbers(label: str) -> set[int]:
    nums = [int(x) for x in re.findall(r"\d+", label)]
    return set(range(nums[0], nums[-1] + 1)) if len(nums) >= 2 and "-" in label else set(nums)


_REF = re.compile(r"\b(Figs?|Tables?)\.?\s*(\d+)(?:\s*(?:-|\u2013|/|and|,)\s*(\d+))?",
                  re.IGNORECASE)


def _refs(item: str) -> set[tuple[str, int]]:
    """The figures and tables a scorecard item names: ``"Section 1.3, Figs. 6-7"`` ->
    {("fig", 6), ("fig", 7)}; ``"Table 2 PCE"`` -> {("table", 2)}."""
    out = set()
    for m in _REF.finditer(item):
        kind = "fig" if m.group(1).lower().startswith("fig") else "table"
        a = int(m.group(2))
        b = int(m.group(3)) if m.group(3) else a
        out |= {(kind, n) for n in range(a, b + 1)} if 0 <= b - a <= 20 else {(kind, a)}
    return out


def _differs_for(card: pd.DataFrame, label: str, scored_with: str = "") -> str:
    """What the scorecard says about a figure: verdict counts of the rows naming its number,
    or of the rows the figure declares it is scored with (:data:`plotting.SCORED_WITH`)."""
    pats = [p.strip() for p in scored_with.split("|") if p.strip()]
    if card.empty or not (pats or label.startswith(("Fig", "Table"))):
        return ""
    kind = "fig" if label.startswith("Fig") else "table"
    want = {(kind, n) for n in _numbers(label)} if label.startswith(("Fig", "Table")) else set()
    rows = card[[bool(want & _refs(str(i))) or any(
        fnmatch.fnmatchcase(str(i), p) or fnmatch.fnmatchcase(f"{i}: {q}", p) for p in pats)
        for i, q in zip(card["item"], card["quantity"], strict=True)]]
    if rows.empty:
        return ("No scorecard row is tied to this figure: it is regenerated for comparison by "
                "eye with the paper's.")
    counts = rows.groupby(["verdict", "basis"], sort=False).size()
    text = ", ".join(f"{n} {v} ({b})" for (v, b), n in counts.items())
    label = label if want else "this figure"
    bad = rows[rows["verdict"].isin(["differs", "close", "not reproducible"])]
    note = f" First difference: {bad.iloc[0]['quantity']} ({bad.iloc[0]['note']})." \
        if not bad.empty else ""
    return f"Scorecard rows for {label}: {text}.{note}"


def _crosstab_html(t: pd.DataFrame) -> str:
    """Verdict x basis counts as a table (bases as rows)."""
    head = ("<tr><th>basis</th>" + "".join(f"<th>{_badge(v)}</th>"
                                           for v in reproduction.VERDICTS)
            + "<th>total</th></tr>")
    body = "".join(
        "<tr>" + (f"<th>{_e(b)}</th>" if b == "total" else f"<td>{_basis(b)}</td>")
        + "".join(f'<td class="num">{r[v]}</td>' for v in reproduction.VERDICTS)
        + f'<td class="num">{r["total"]}</td></tr>' for b, r in t.iterrows())
    return f'<table class="crosstab">{head}{body}</table>'


def _bases_html() -> str:
    return ("<details><summary>What each basis means</summary><dl>"
            + "".join(f"<dt><strong>{_e(b)}</strong></dt><dd>{_e(d)}</dd>"
                      for b, d in reproduction.BASES.items()) + "</dl></details>")


def _provenance_html(rec: dict) -> str:
    if not rec:
        return ""
    params = ", ".join(f"{k}={v}" for k, v in rec.get("parameters", {}).items())
    inputs = "".join(f"<li><code>{_e(k)}</code> sha256 {_e(v[:16])}…</li>"
                     for k, v in rec.get("inputs", {}).items())
    pkgs = ", ".join(f"{k} {v}" for k, v in rec.get("packages", {}).items())
    return (f"<details><summary>provenance</summary><ul>"
            f"<li>library sha256 "
            f"<code>{_e(str(rec.get('library_sha256', ''))[:16])}…</code></li>"
            f"<li>notebook <code>{_e(rec.get('notebook', ''))}</code>, source sha256 "
            f"<code>{_e(str(rec.get('notebook_sha256', ''))[:16])}…</code></li>"
            f"<li>parameters: {_e(params)}</li><li>inputs:<ul>{inputs}</ul></li>"
            f"<li>packages: {_e(pkgs)}</li></ul></details>")


#: Outputs on disk that must be listed in their folder's provenance.json (figures, tables).
CHECKED_SUFFIXES = (".png", ".svg", ".csv")


def output_kind(path: Path) -> str:
    """What an output file is, for the messages: "figure", "table" or "file"."""
    return {".png": "figure", ".svg": "figure", ".csv": "table"}.get(Path(path).suffix, "file")


def output_problem(path: Path, side: dict) -> str | None:
    """Why an output file cannot be shown or linked, or None when it is sound.

    Parameters
    ----------
    path : Path
        The file, in its output folder.
    side : dict
        That folder's ``provenance.json`` (:func:`mtaccuracy.compendium.provenance.read`).

    Returns
    -------
    str or None
        The problem in words, to follow the file's name ("is missing ...", "cannot be read
        ...", "is not listed ...", "does not match the hash ..."): missing though listed, a
        figure that cannot be decoded, not listed, no hash though not ``measured``, or bytes
        that are not the ones the run recorded.  A ``measured`` entry is only required to
        exist (and, for a figure, to be readable).
    """
    path = Path(path)
    entry = side.get("files", {}).get(path.name)
    if not path.is_file():
        return (f"is missing (listed in {provenance.SIDECAR}, not on disk)" if entry is not None
                else "is missing")
    try:
        if path.suffix == ".png":
            with Image.open(path) as im:
                im.load()  # decodes every byte: a truncated file fails here
        elif path.suffix == ".svg":
            ET.parse(path)
    except Exception as exc:  # PIL and expat raise many kinds
        return f"cannot be read ({type(exc).__name__}: {str(exc)[:80]})"
    if entry is None:
        return f"is not listed in {provenance.SIDECAR} (not written by this folder's run)"
    if entry.get("measured"):
        return None  # a measurement of the machine: no hash to check
    if "sha256" not in entry:
        return f"has no hash in {provenance.SIDECAR} and is not declared measured"
    if entry["sha256"] != provenance.sha256(path):
        return f"does not match the hash in {provenance.SIDECAR} (changed after its run)"
    return None


def folder_problems(folder: Path, side: dict | None = None) -> list[tuple[Path, str]]:
    """Every problem (:func:`output_problem`) of the files an output folder's
    ``provenance.json`` lists (its outputs); a file it does not list is not the compendium's
    (:func:`not_outputs`) and is not judged.

    Parameters
    ----------
    folder : Path
        A notebook's output folder (``figures/<stem>``).
    side : dict, optional
        Its ``provenance.json`` (read when not given).

    Returns
    -------
    list of (Path, str)
        ``(path, why)`` for each file with a problem, sorted by name.
    """
    folder = Path(folder)
    side = provenance.read(folder) if side is None else side
    found = ((folder / n, output_problem(folder / n, side)) for n in sorted(side.get("files", {})))
    return [(p, why) for p, why in found if why]


def not_outputs(folder: Path, side: dict | None = None) -> list[str]:
    """The files in an output folder that its ``provenance.json`` does not list: put there by
    someone else (notes, an input file), left alone by every run, never shown or linked as
    results.

    Parameters
    ----------
    folder : Path
        A notebook's output folder.
    side : dict, optional
        Its ``provenance.json`` (read when not given).

    Returns
    -------
    list of str
        Their names, sorted.
    """
    folder = Path(folder)
    side = provenance.read(folder) if side is None else side
    listed = set(side.get("files", {})) | {provenance.SIDECAR}
    return sorted(p.name for p in folder.iterdir() if p.is_file()
                  and not p.name.startswith(".") and p.name not in listed) \
        if folder.is_dir() else []


def _problem_html(stem: str, path: Path, why: str, action: str) -> str:
    what = output_kind(path)
    state = "Missing" if not path.exists() else "Broken"
    return (f'<p class="broken"><strong>{state} {what}</strong> '
            f"<code>{_e(stem)}/{_e(path.name)}</code> {_e(why)}: {action}; run "
            f"<code>make reproduce NB={_e(stem[:2])}</code> again.</p>")


_EXPORTER = None
_STAMP = "<!-- mtaccuracy: export of notebook sha256 {} -->\n"


def export_notebook(nb: Path, out: Path) -> Path:
    """HTML export of an executed notebook (no execution), with external scripts removed;
    skipped when ``out`` is already the export of these notebook bytes (the runner exports
    each notebook as soon as its run succeeds, so the report seldom has to).

    The notebooks are the compendium's own, so nbconvert's HTML sanitiser (bleach, most of the
    export time) is not applied to them."""
    global _EXPORTER
    stamp = _STAMP.format(provenance.sha256(nb))
    if out.exists():
        with open(out, encoding="utf-8") as fh:
            if fh.readline() == stamp:
                return out
    from nbconvert import HTMLExporter

    if _EXPORTER is None:
        _EXPORTER = HTMLExporter(template_name="lab", filters={"clean_html": lambda s: s})
    body, _ = _EXPORTER.from_filename(str(nb))
    body = re.sub(r'<script[^>]*src="https?://[^"]*"[^>]*>\s*</script>', "", body)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".{out.name}.{os.getpid()}.tmp")
    tmp.write_text(stamp + body, encoding="utf-8")
    os.replace(tmp, out)
    return out


def _title(nb: Path) -> str:
    """The first heading of a notebook's first cell ("" when there is none)."""
    try:
        first = json.loads(nb.read_text(encoding="utf-8"))["cells"][0]
    except (OSError, ValueError, KeyError, IndexError):
        return ""
    for line in "".join(first.get("source", [])).splitlines():
        if line.startswith("# "):
            return line[2:].strip()
    return ""


def build(figures=None, notebooks=None, broken: list | None = None, export: bool = True) -> Path:
    """Write ``<figures>/index.html`` and (with ``export``) ``<figures>/html/<stem>.html``.

    Every figure and table that cannot be trusted (:func:`folder_problems`: unreadable, not
    the bytes its folder's ``provenance.json`` records, not listed there, or listed but
    missing) is marked in the page instead of shown or linked, and appended to ``broken``.

    Parameters
    ----------
    figures : str or Path, optional
        The figures folder (default ``figures/``).
    notebooks : str or Path, optional
        The notebooks folder (default ``notebooks/``).
    broken : list, optional
        Receives ``(path, why)`` for each file marked.
    export : bool
        Also write the HTML export of each executed notebook.

    Returns
    -------
    Path
        ``<figures>/index.html``.
    """
    figures = Path(figures or paths.FIGURES)
    notebooks = Path(notebooks or paths.NOTEBOOKS)
    broken = [] if broken is None else broken
    index = reproduction.papers_index()
    cards = reproduction.collect(figures)
    measured = reproduction.collect(figures, measured=True)
    summary = reproduction.summary(cards)
    runs = runner.last_runs() if figures == paths.FIGURES else {}
    runtimes = {k: v.get("seconds") for k, v in runs.items() if isinstance(v, dict)}
    # the papers' notebooks (a scorecard each; a paper's folder that lost its scorecard is
    # still shown, with what is missing), then any other notebook with outputs (a method for
    # the reader's own machine: figures and tables, nothing to score)
    others = {p.parent.name for p in figures.glob("*/provenance.json")
              if (notebooks / f"{p.parent.name}.ipynb").exists() or p.parent.name in index}
    stems = sorted(set(cards["notebook"]) | others)

    out = ['<!DOCTYPE html><html lang="en"><head><meta charset="utf-8">',
           "<title>mtaccuracy: reproduction report</title>",
           f"<style>{CSS}</style></head><body>",
           "<h1>mtaccuracy: reproduction report</h1>",
           "<p>Every table and figure of five machine-tool accuracy papers, regenerated by "
           "<code>make reproduce</code>, beside the published values. Verdicts: "
           + " ".join(_badge(v) for v in reproduction.VERDICTS)
           + ' (<a href="REPRODUCTION.md">scorecard as Markdown</a>).</p>',
           '<table class="summary"><tr><th>paper</th><th>notebook</th>'
           + "".join(f"<th>{_badge(v)}</th>" for v in reproduction.VERDICTS)
           + "<th>total</th><th>last run here</th></tr>"]
    for _, r in summary.iterrows():
        rt = runtimes.get(r["notebook"])
        commit = str(runs.get(r["notebook"], {}).get("commit", ""))[:10]
        out.append(f'<tr><td><a href="#{_e(r["notebook"])}">{_e(r["paper"])}</a></td>'
                   f"<td><code>{_e(r['notebook'])}</code></td>"
                   + "".join(f'<td class="num">{r[v]}</td>' for v in reproduction.VERDICTS)
                   + f'<td class="num">{r["total"]}</td>'
                   + f'<td class="num">{f"{rt:.0f} s" if rt is not None else "not run here"}'
                   + (f" (commit <code>{_e(commit)}</code>)" if commit else "") + "</td></tr>")
    tot = summary[list(reproduction.VERDICTS) + ["total"]].sum() if not summary.empty else None
    if tot is not None:
        total_rt = f"{sum(v for v in runtimes.values() if v):.0f} s" if runtimes else ""
        out.append("<tr><th>all papers</th><th></th>"
                   + "".join(f'<th class="num">{tot[v]}</th>' for v in reproduction.VERDICTS)
                   + f'<th class="num">{tot["total"]}</th><th class="num">{total_rt}</th></tr>')
    out.append("</table>")
    if not cards.empty:
        out += [f'<p class="headline">{_e(reproduction.headline(cards))}</p>',
                _crosstab_html(reproduction.crosstab(cards)), _bases_html()]

    for stem in stems:
        folder = figures / stem
        meta = index.get(stem, {})
        card = cards[cards["notebook"] == stem]
        nb = notebooks / f"{stem}.ipynb"
        links = ['<a href="' + _e(f"html/{stem}.html") + '">executed notebook (HTML)</a>'] \
            if nb.exists() else []
        if nb.exists() and export:
            export_notebook(nb, figures / "html" / f"{stem}.html")
        side = provenance.read(folder)
        problems = folder_problems(folder, side)
        broken += problems
        bad = {p.name for p, _ in problems} | set(not_outputs(folder, side))
        links += [f'<a href="{_e(stem)}/{_e(p.name)}">{_e(p.name)}</a>'
                  for p in sorted(folder.glob("*.csv")) if p.name not in bad]
        n_rows = len(card)
        counts = ", ".join(f"{n} {v}" for v, n in card["verdict"].value_counts()
                           .reindex(reproduction.VERDICTS).dropna().astype(int).items() if n)
        indep = int(((card["verdict"] == "reproduced")
                     & (card["basis"] == "independent")).sum())
        out += [f'<section class="paper" id="{_e(stem)}">',
                f"<h2>{_e(meta.get('paper', _title(nb) or stem))}</h2>",
                f'<p class="citation">{_e(meta.get("citation", ""))}</p>',
                f'<p class="links">{" ".join(links)}</p>']
        out += [_problem_html(stem, p, why, "not linked") for p, why in problems
                if output_kind(p) != "figure"]
        theirs = not_outputs(folder, side)
        if theirs:
            out.append(f"<p>Not written by this notebook's run, so neither shown nor linked "
                       f"here (runs leave them alone): {_e(', '.join(theirs))}.</p>")
        rows = [("score-row", r) for _, r in card.iterrows()]
        rows += [("measured-row", r) for _, r in measured[measured["notebook"] == stem].iterrows()]
        if not rows and stem in index:  # a paper's folder without its scorecard
            out.append("<p>No scorecard rows to show.</p><h3>Figures</h3>")
        elif not rows:
            out.append("<p>No paper: no published value to score. The notebook's own checks are "
                       "its tables above.</p><h3>Figures</h3>")
        else:
            out += [f'<details class="scorecard"{"" if n_rows > COLLAPSE_ROWS else " open"}>'
                    f"<summary><strong>Scorecard</strong>: {n_rows} rows ({_e(counts)}); "
                    f"{indep} reproduced independently</summary>",
                    _crosstab_html(reproduction.crosstab(card)),
                    "<table><tr><th>item</th><th>quantity</th><th>published</th>"
                    "<th>reproduced</th><th>unit</th><th>tolerance</th><th>verdict</th>"
                    "<th>basis</th><th>note</th></tr>"]
        for cls, r in rows:
            out.append(f'<tr class="{cls}" data-notebook="{_e(stem)}" '
                       f'data-verdict="{_e(r["verdict"])}" data-basis="{_e(r["basis"])}">'
                       f"<td>{_e(r['item'])}</td>"
                       f"<td>{_e(r['quantity'])}</td><td>{_e(r['published'])}</td>"
                       f"<td>{_e(r['reproduced'])}</td><td>{_e(r['unit'])}</td>"
                       f"<td>{_e(r['tolerance'])}</td><td>{_badge(r['verdict'])}</td>"
                       f"<td>{_basis(r['basis'])}</td><td>{_e(r['note'])}"
                       + (" <em>(measured on the machine that ran it: changes from run to "
                          "run; not counted in the summary)</em>" if cls == "measured-row" else "")
                       + "</td></tr>")
        if rows:
            out.append("</table></details><h3>Figures</h3>")
        out += [_problem_html(stem, p, why, "not shown") for p, why in problems
                if output_kind(p) == "figure"]
        for png in sorted(folder.glob("*.png")):
            if png.name in bad:
                continue
            label = _figure_label(png.stem)
            with Image.open(png) as im:
                title = im.info.get("Title", "")
                scored_with = im.info.get(plotting.SCORED_WITH, "")
            svg = png.with_suffix(".svg")
            if svg.name in bad:
                svg = Path("/nonexistent")
            out.append(
                f'<figure id="{_e(stem)}-{_e(png.stem)}"><img class="figure" '
                f'src="{_e(stem)}/{_e(png.name)}" alt="{_e(label)}: {_e(title or png.stem)}">'
                f"<figcaption><strong>{_e(label)}</strong>"
                f"{': ' + _e(_caption_title(label, title)) if title else ''}. "
                f"{_e(_differs_for(card, label, scored_with))} "
                + (f'<a href="{_e(stem)}/{_e(svg.name)}">SVG</a>' if svg.exists() else "")
                + f"{_provenance_html(provenance.from_png(png))}</figcaption></figure>")
        out.append("</section>")
    out.append("</body></html>")
    path = figures / "index.html"
    text = "\n".join(out) + "\n"
    if not path.exists() or path.read_text(encoding="utf-8") != text:
        tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")  # whole or not at all
        tmp.write_text(text, encoding="utf-8")
        os.replace(tmp, path)
    return path


def main(argv=None) -> int:
    """``python -m mtaccuracy.compendium.report``: build the report and name every file it
    marked (:func:`build`).

    Parameters
    ----------
    argv : list of str, optional
        The command line (default: ``sys.argv[1:]``); ``--figures DIR`` reports on another
        figures folder.

    Returns
    -------
    int
        0, or 1 when a figure or table was marked as broken or missing.
    """
    ap = argparse.ArgumentParser(prog="python -m mtaccuracy.compendium.report")
    ap.add_argument("--figures", default=None, help="figures folder (default: figures/)")
    args = ap.parse_args(argv)
    broken: list = []
    try:
        path = build(args.figures, broken=broken)
    except OSError as exc:  # a read-only checkout, a full disk
        print(f"error: cannot write {exc.filename or 'the report'} ({exc.strerror or exc}); "
              f"the report is built inside figures/, which needs a checkout you can write",
              file=sys.stderr)
        return 2
    shown = path.relative_to(paths.ROOT) if path.is_relative_to(paths.ROOT) else path
    print(f"report: {shown}")
    for bad, why in broken:
        print(f"error: {output_kind(bad)} {bad} {why}; marked in the report", file=sys.stderr)
    return 1 if broken else 0


if __name__ == "__main__":
    raise SystemExit(main())
