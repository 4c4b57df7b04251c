"""The book (``make book``, :mod:`mtaccuracy.apps.book`).

Fast tests build chapters from synthetic output folders made here (figures drawn with
matplotlib, ``provenance.json`` written by hand as a run writes it): the figures in the paper
module's order with the captions their run recorded, a missing caption and a caption without
its figure named, broken outputs and a user's file, the sweep's sentence, the parameter table.

The whole book is built and opened in Chromium by ``make check`` (tests/check/test_book_build.py).
"""

import re
from pathlib import Path

import matplotlib
import pandas as pd
import pytest

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from mtaccuracy.apps import book, book_safety  # noqa: E402
from mtaccuracy.compendium import provenance, scorecard, workflow  # noqa: E402
from mtaccuracy.compendium.notebook import NOTEBOOKS, ROOT  # noqa: E402
from mtaccuracy.papers import guo2016, rong  # noqa: E402

TIMEOUT_MS = 30_000
STEMS = book.stems()
PAPERS = [s for s in STEMS if s in scorecard.papers_index()]
WIDTHS = {"desktop": 1280, "phone": 400}
GUO = guo2016.Parameters.stem
SHOTS = ROOT / ".test-output" / "book"


# ------------------------------------------------------------------ synthetic output folders

def _png(path: Path) -> None:
    fig, ax = plt.subplots(figsize=(2, 1.5))
    ax.plot([0, 1], [0, 1])
    fig.savefig(path)
    plt.close(fig)


def _write_run(folder: Path, figures: dict, *, parameters=None, extra=()) -> None:
    """A run's outputs as the workflow leaves them: ``figures`` maps a PNG's stem to its
    record entry (label, caption, order), each with an SVG; a scorecard; ``provenance.json``
    listing every file with its hash."""
    folder.mkdir(parents=True, exist_ok=True)
    files = {}
    for name, entry in figures.items():
        _png(folder / f"{name}.png")
        (folder / f"{name}.svg").write_text('<svg xmlns="http://www.w3.org/2000/svg"/>')
        files[f"{name}.png"] = {"sha256": provenance.sha256(folder / f"{name}.png"), **entry}
        files[f"{name}.svg"] = {"sha256": provenance.sha256(folder / f"{name}.svg")}
    card = pd.DataFrame([dict(item="Fig. 3", quantity="rho", published="0.5", reproduced="0.5",
                              unit="", tolerance="0", verdict="reproduced",
                              basis="independent", kind="number", agreement="printed",
                              note="")])
    card.to_csv(folder / "reproduction.csv", index=False, lineterminator="\n")
    for name in ("reproduction.csv", *extra):
        files[name] = {"sha256": provenance.sha256(folder / name)}
    source = provenance.notebook_source_hash(NOTEBOOKS / f"{folder.name}.ipynb")
    provenance.write_sidecar(folder, {"run": {"notebook": folder.name,
                                              "notebook_sha256": source,
                                              "parameters": parameters or {}},
                                      "files": files})


def _guo_figures(skip=(), uncaptioned=()) -> dict:
    """Notebook 03's figures as its run records them, in the reverse of the paper's order."""
    names = list(guo2016.FIGURES)
    return {n: {"label": guo2016.FIGURES[n].label, "order": len(names) - 1 - k,
                **({} if n in uncaptioned else {"caption": f"Run caption of {n}: n = 500."})}
            for k, n in enumerate(names) if n not in skip}


@pytest.fixture
def guo_folder(tmp_path):
    figures = tmp_path / "figures"
    _write_run(figures / GUO, _guo_figures())
    return figures


def _chapter(figures: Path, stem: str = GUO) -> tuple[str, dict]:
    broken = book.check(figures, [stem])
    return book.chapter(stem, figures, scorecard.papers_index(), broken), broken


def _why(broken: dict, figures: Path, stem: str = GUO) -> list[tuple[str, str]]:
    """The problems of a chapter: (path in its folder, why)."""
    return [(book._rel(p, figures / stem), why) for p, why in broken.get(stem, [])]


def test_figures_come_in_the_paper_modules_order_with_the_runs_captions(tmp_path):
    figures = tmp_path / "figures"
    extra = {"label": "Beyond the paper", "caption": "A figure FIGURES lacks.", "order": 0}
    _write_run(figures / GUO, {**_guo_figures(), "extra": extra})
    text, broken = _chapter(figures)
    assert broken == {}
    shown = re.findall(r"```\{figure\} \.\./figures/[^/]+/(\w+)\.png", text)
    assert shown == [*guo2016.FIGURES, "extra"]     # the module's order, then the run's
    assert "**Beyond the paper.** A figure FIGURES lacks." in text
    for name, cap in guo2016.FIGURES.items():
        assert f"**{cap.label}.** Run caption of {name}: n = 500." in text
        assert f'<a href="../figures/{GUO}/{name}.svg">SVG</a>' in text
        assert f":target: ../figures/{GUO}/{name}.png" in text     # a click enlarges it


def test_a_figure_without_a_caption_or_a_caption_without_its_figure_is_named(tmp_path):
    figures = tmp_path / "figures"
    gone, bare = list(guo2016.FIGURES)[:2]
    _write_run(figures / GUO, _guo_figures(skip=[gone], uncaptioned=[bare]))
    text, broken = _chapter(figures)
    assert _why(broken, figures) == [
        (f"{gone}.png", "is captioned in mtaccuracy.papers.guo2016.FIGURES but its run did not "
                        "write it"),
        (f"{bare}.png", "has no caption in provenance.json (its run recorded none)")]
    assert f"{{figure}} ../figures/{GUO}/{bare}.png" not in text
    assert text.count('class="broken"') == 2 and f"<code>{GUO}/{bare}.png</code>" in text
    assert re.findall(r"```\{figure\} \.\./figures/[^/]+/(\w+)\.png", text) == \
        list(guo2016.FIGURES)[2:]


def test_make_book_fails_naming_what_is_wrong(tmp_path, monkeypatch, capsys):
    figures = tmp_path / "figures"
    _write_run(figures / GUO, _guo_figures(uncaptioned=[list(guo2016.FIGURES)[0]]))
    site = tmp_path / "html"
    site.mkdir()

    def fake_build(out, figs, quiet):  # the checks, without Sphinx
        return site, book.check(Path(figs), [GUO]), []
    monkeypatch.setattr(book, "build", fake_build)
    assert book.main(["--figures", str(figures)]) == 1
    err = capsys.readouterr().err
    assert f"error: figure {figures / GUO / list(guo2016.FIGURES)[0]}.png has no caption" in err
    _write_run(figures / GUO, _guo_figures())
    assert book.main(["--figures", str(figures)]) == 0


def test_broken_outputs_are_named_and_a_users_file_is_neither_judged_nor_shown(guo_folder):
    folder = guo_folder / GUO
    first, second = list(guo2016.FIGURES)[:2]
    png = folder / f"{first}.png"
    png.write_bytes(png.read_bytes()[: len(png.read_bytes()) // 4])  # an interrupted write
    (folder / f"{second}.svg").write_text("<svg/>")                   # changed after its run
    _png(folder / "my_sketch.png")                                     # the user's own
    (folder / "my_ranges.csv").write_text("a\n1\n")
    text, broken = _chapter(guo_folder)
    assert sorted((n, why.split(" (")[0]) for n, why in _why(broken, guo_folder)) == sorted([
        (f"{first}.png", "cannot be read"),
        (f"{second}.svg", "does not match the hash in provenance.json")])
    assert f"{{figure}} ../figures/{GUO}/{first}.png" not in text
    assert f"{second}.svg\">SVG" not in text and f"{{figure}} ../figures/{GUO}/{second}.png" \
        in text
    assert "my_sketch" not in text and "my_ranges" not in text


def _sweep(folder: Path, verdicts: dict[int, str], settings=None) -> None:
    """``make sweep``'s tables (:func:`workflow.summarise`) over runs whose scorecard gives
    row ``Fig. 3: rho`` the verdict ``verdicts[seed]`` (and ``Table 1: n`` always
    reproduced)."""
    runs, folders = {}, {}
    for seed, verdict in verdicts.items():
        for s in settings or [None]:
            run = f"{f'setting{s}-' if s else ''}seed{seed}"
            runs[run] = {"seed": seed, **({"n_samples": s} if s else {})}
            folders[run] = folder.parent / "runs" / run
            folders[run].mkdir(parents=True)
            pd.DataFrame([dict(item="Fig. 3", quantity="rho", reproduced="0.5", verdict=verdict),
                          dict(item="Table 1", quantity="n", reproduced="3",
                               verdict="reproduced")]).to_csv(folders[run] / "reproduction.csv",
                                                              index=False)
    workflow.summarise(folder.name, runs, folders, folder / book.SWEEP)


def test_the_chapter_says_which_verdicts_change_with_the_seed(guo_folder):
    folder = guo_folder / GUO
    _sweep(folder, {7: "reproduced", 8: "differs", 9: "reproduced"})
    text, broken = _chapter(guo_folder)
    assert broken == {}                       # the sweep folder is neither the user's nor broken
    assert provenance.not_outputs(folder) == []
    seeds = text[text.index("### Over seeds"):text.index("## Parameters")]
    assert "`make sweep NB=03` re-ran the notebook over 3 seeds (7 to 9)" in seeds
    assert "the verdict of 1 of the 2 rows changes with the seed" in seeds
    assert "| item | quantity | reproduced | close | differs | not reproducible |" in seeds
    assert "| Fig. 3 | rho | 2 | 0 | 1 | 0 |" in seeds and "Table 1" not in seeds
    assert f"(../figures/{GUO}/sweep/verdict_stability.csv)" in seeds


def test_a_stable_sweep_over_settings_says_so_and_an_edited_one_is_named(guo_folder, tmp_path):
    folder = guo_folder / GUO
    _sweep(folder, {1: "reproduced", 2: "reproduced"}, settings=[40, 80])
    text, broken = _chapter(guo_folder)
    assert broken == {}
    assert "over 2 seeds (1 to 2) at each of 2 settings and scored every run (4 runs): no " \
           "row's verdict changes with the seed (4 rows)." in text
    with open(folder / book.SWEEP / "values.csv", "a") as fh:
        fh.write("edited,by,hand,1,2\n")
    text, broken = _chapter(guo_folder)
    assert [n for n, _ in _why(broken, guo_folder)] == ["sweep/values.csv"]
    assert "<code>make sweep NB=03</code>" in text and "sweep/values.csv)" not in text


def test_each_chapter_lists_its_notebooks_declared_parameters():
    for decl in workflow.DECLARATIONS:
        lines = book.parameter_lines(decl.stem)
        rows = [li for li in lines if li.startswith("| `")]
        assert [re.match(r"\| `(\w+)`", r).group(1) for r in rows] == decl.names()
        assert f"`{decl.__module__}.Parameters`" in "\n".join(lines)
    rows = {re.match(r"\| `(\w+)`", r).group(1): r
            for r in book.parameter_lines(rong.Parameters.stem) if r.startswith("| `")}
    assert rows["n_base"] == ("| `n_base` | `8192` | int | [64, 131072] | base sample size N "
                              "of the Saltelli design (paper: 10000) |")
    assert rows["layout"].startswith('| `layout` | `"z/xy"` | str | one of '
                                     'z/xy\\|x/zy\\|zx/y\\|xz/y |')
    text = "\n".join(book.parameter_lines(rong.Parameters.stem,
                                          {"parameters": {"n_base": 4096, "seed": 2022}}))
    assert "The run shown used <code>n_base=4096</code>, the others at their defaults." in text
    assert "used the defaults." in "\n".join(
        book.parameter_lines(GUO, {"parameters": guo2016.Parameters.defaults()}))


def test_a_folder_not_written_by_the_book_is_never_replaced(tmp_path, guo_folder):
    (tmp_path / "html").mkdir()
    (tmp_path / "html" / "mine.txt").write_text("a reader's file")
    with pytest.raises(book.BookError, match="was not written by make book"):
        book.build(tmp_path, guo_folder)
    assert (tmp_path / "html" / "mine.txt").read_text() == "a reader's file"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["figures", "html"]


def test_units_are_written_with_their_symbols():
    assert book.unit_symbol("um/m/degC") == "µm/m/°C"
    assert book.unit_symbol("deg") == "°" and book.unit_symbol("mm") == "mm"


# ---------------------------------------------------------------------- the whole book, once


# ------------------------------------------------------- nothing shown can run script (issue 35)

#: Names and texts a crafted record could carry: each would run script if written as HTML.
XSS = "<img src=x onerror=alert(1)>"


def _record_text(folder: Path) -> dict:
    import json
    return json.loads((folder / provenance.SIDECAR).read_text())


def _rewrite(folder: Path, edit) -> None:
    data = _record_text(folder)
    edit(data)
    provenance.write_sidecar(folder, data)


def test_crafted_names_and_captions_are_escaped_and_never_opened(guo_folder, tmp_path):
    folder = guo_folder / GUO
    first = list(guo2016.FIGURES)[0]
    secret = tmp_path / "secret.csv"
    secret.write_text("password\n")
    _png(folder / f"{XSS}.png")                 # a file name no page can carry
    (folder / f"{XSS}.csv").write_text("a\n1\n")

    def edit(d):
        d["files"][first]["label"] = "Fig. <b onmouseover=alert(2)>"
        d["files"][first]["caption"] = "See <script>alert(3)</script> and `a<b` & $x$."
        d["files"][f"{XSS}.png"] = {"sha256": provenance.sha256(folder / f"{XSS}.png"),
                                    "caption": "c", "label": "l"}
        d["files"][f"{XSS}.csv"] = {"sha256": provenance.sha256(folder / f"{XSS}.csv")}
        d["files"]["<script>alert(4)</script>.csv"] = {"sha256": "0"}   # a path: has a '/'
        d["files"]["../../secret.csv"] = {"sha256": provenance.sha256(secret)}
    _rewrite(folder, lambda d: d["files"].update({first: d["files"].pop(f"{first}.png")}))
    _rewrite(folder, edit)
    _rewrite(folder, lambda d: d["files"].update({f"{first}.png": d["files"].pop(first)}))
    text, broken = _chapter(guo_folder)
    page = "\n".join(li for li in text.splitlines() if not li.startswith(":alt: "))
    page = re.sub(r"```\{raw\} html\n.*?```", "", page, flags=re.S)  # the scorecard's own
    for raw in ("<script", "<img", "<b ", "onerror=alert(1)>"):   # the writer escapes :alt:
        assert raw not in page, raw
    assert "&lt;script&gt;alert(3)&lt;/script&gt;" in text and "<code>a&lt;b</code>" in text
    assert "**Fig. &lt;b onmouseover=alert(2)&gt;.**" in text
    whys = [why for _, why in _why(broken, guo_folder)]
    assert any("'../../secret.csv', which is not a file name" in w for w in whys)
    assert any("'<script>alert(4)</script>.csv', which is not a file name" in w for w in whys)
    assert any(f"the figure '{XSS}.png', whose name a page cannot show" in w for w in whys)
    assert "secret" not in text.split("## Tables")[-1]
    # the escaped table link of the crafted (but plain-file) CSV
    assert "&lt;img src=x onerror=alert(1)&gt;.csv</a>" in text
    assert "%3Cimg%20src%3Dx%20onerror%3Dalert%281%29%3E.csv" in text


def test_a_conflicted_or_malformed_record_ends_make_book_in_one_line(tmp_path, capsys):
    figures = tmp_path / "figures"
    _write_run(figures / GUO, _guo_figures())
    side = figures / GUO / provenance.SIDECAR
    good = side.read_text()
    lines = good.splitlines()
    side.write_text("\n".join([*lines[:3], "<<<<<<< HEAD", *lines[3:5], "=======",
                               *lines[3:5], ">>>>>>> other", *lines[5:]]) + "\n")
    out = tmp_path / "out"
    for text, says in [(None, "line 4 is a merge-conflict marker"),
                       ("[]", "not a run's record"), ('{"files": []}', "not a run's record"),
                       ('{"files": {"a.png": 3}}', "not a run's record"),
                       ("{", "not JSON")]:
        if text is not None:
            side.write_text(text)
        assert book.main(["--figures", str(figures), "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and err.startswith(f"error: {side}: {says}"), err
        assert "resolve it, or run make reproduce again" in err
    assert not out.exists() or not any(out.iterdir())     # nothing built


def test_a_dangling_link_and_an_unwritable_place_are_one_line(tmp_path, monkeypatch, capsys):
    data = tmp_path / "data"
    (data / "ranges").mkdir(parents=True)
    (data / "ranges" / "gone.csv").symlink_to(tmp_path / "nowhere.csv")
    with pytest.raises(book.BookError, match=r"gone\.csv is a link to .*nowhere\.csv, which "
                                             r"does not exist"):
        book.dangling_links(data)
    (tmp_path / "nowhere.csv").write_text("x\n")
    book.dangling_links(data)                                        # now sound
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    assert book.main(["--figures", str(tmp_path), "--out", str(blocker / "book")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"error: {blocker}"), err

    def read_only(*a, **k):
        raise OSError(30, "Read-only file system", str(tmp_path / "build"))
    monkeypatch.setattr(book, "build", read_only)
    assert book.main([]) == 2
    err = capsys.readouterr().err
    assert err == (f"error: {tmp_path / 'build'}: Read-only file system; build elsewhere with "
                   "--out DIR\n")


def test_notebook_outputs_are_sanitised_and_an_edited_notebook_is_not_shown(tmp_path):
    import json

    frame = pd.DataFrame({"error": ["EXX", "<b>EYY</b>"], "S_T": [0.5, 0.25]})
    clean = book_safety.safe_html(frame._repr_html_())
    for cell in ("EXX", "&lt;b&gt;EYY&lt;/b&gt;", "0.50", "0.25", "<table", "<td>", "<th>"):
        assert cell in clean, cell
    crafted = ('<table onmouseover="alert(1)"><tr><td>1<script>alert(2)</script></td>'
               '<td><img src=x onerror=alert(3)><a href="javascript:alert(4)">x</a></td></tr>'
               '</table><style>body{display:none}</style><svg onload=alert(5)><text>t</text>'
               '</svg>')
    assert book_safety.safe_html(crafted) == "<table><tr><td>1</td><td>x</td></tr></table>"
    nb_path = NOTEBOOKS / f"{GUO}.ipynb"
    nb = json.loads(nb_path.read_text())
    code_cell = next(c for c in nb["cells"] if c["cell_type"] == "code")
    code_cell["outputs"] = [{"output_type": "display_data", "metadata": {}, "data": {
        "text/html": crafted, "text/plain": "t", "application/javascript": "alert(6)",
        "image/svg+xml": "<svg onload=alert(7)/>", "text/markdown": "<script>8</script>"}}]
    edited = tmp_path / nb_path.name
    edited.write_text(json.dumps(nb))
    side = {"run": {"notebook_sha256": provenance.notebook_source_hash(nb_path)}}
    assert book.notebook_problems(GUO, side, notebook=edited) == []   # outputs are not hashed
    shown = book.safe_notebook(edited, [])
    out = next(c for c in shown["cells"] if c["cell_type"] == "code")["outputs"][0]["data"]
    assert out == {"text/plain": "t", "text/html": book_safety.safe_html(crafted)}
    # a markdown cell edited after the run: the notebook is not shown at all
    md = next(c for c in nb["cells"] if c["cell_type"] == "markdown")
    md["source"] = "# Title\n<script>alert(9)</script>"
    edited.write_text(json.dumps(nb))
    problems = book.notebook_problems(GUO, side, notebook=edited)
    assert [w for _, w in problems] == ["does not match the notebook_sha256 in provenance.json "
                                        "(edited after its run)"]
    page = json.dumps(book.safe_notebook(edited, problems))
    assert "alert" not in page and "Not shown" in page
    assert [w for _, w in book.notebook_problems(GUO, {}, notebook=edited)] == [
        "has no run recorded in provenance.json"]


def test_the_chapter_of_an_edited_notebook_shows_no_conclusion(tmp_path):
    figures = tmp_path / "figures"
    _write_run(figures / GUO, _guo_figures())
    _rewrite(figures / GUO, lambda d: d["run"].update(notebook_sha256="0" * 64))
    text, broken = _chapter(figures)
    assert [n for n, _ in _why(broken, figures)] == [f"notebooks/{GUO}.ipynb"]
    assert "## What we conclude" not in text and f"<code>notebooks/{GUO}.ipynb</code>" in text


# ---------------------------------------------------------------------- findings first

def test_the_findings_are_read_from_the_readme_not_retyped(tmp_path):
    index = scorecard.papers_index()
    found = book.findings(index)
    readme = (ROOT / "README.md").read_text().splitlines()
    assert sorted(found) == sorted(PAPERS)
    for stem, line in found.items():
        assert f"- {line}" in readme and line.startswith(index[stem]["paper"])
    own = tmp_path / "README.md"
    own.write_text("# x\n\n**What we found**, lines:\n\n- Guo et al. 2016: A <b>.\n"
                   "- Nobody: nothing.\n\n- Rong et al.: after the blank line.\n")
    assert book.findings(index, own) == {GUO: "Guo et al. 2016: A <b>."}
    own.write_text("# no findings here\n")
    assert book.findings(index, own) == {}


def test_the_home_leads_with_each_papers_finding_figure_and_chapter(guo_folder, monkeypatch):
    monkeypatch.setattr(book, "findings", lambda index: {GUO: "Guo: `x<y` is <b>false</b>."})
    cards = scorecard.collect(guo_folder)
    text = book.home(cards, scorecard.papers_index(), STEMS, guo_folder, {})
    found, card = text.index("## What we found"), text.index("## The scorecard")
    assert found < card and text.index("## Verdicts by basis") > card
    guo = text[text.index(f"### [Guo et al. 2016](chapters/{GUO}.md)"):card]
    assert "Guo: <code>x&lt;y</code> is &lt;b&gt;false&lt;/b&gt;." in guo
    first = list(guo2016.FIGURES)[0]
    assert f"```{{figure}} {book.preview_name(GUO, first)}\n" in guo   # a light preview ...
    assert f":target: figures/{GUO}/{first}.png" in guo           # ... that enlarges
    assert f"(chapters/{GUO}.md)" in guo.split("```")[-1]
    for stem in PAPERS:                      # every paper, with or without its outputs
        assert f"(chapters/{stem}.md)" in text[found:card]


def test_the_site_gets_the_linked_files_and_lazy_images(tmp_path):
    src, site = tmp_path / "src", tmp_path / "site"
    (src / "figures" / GUO).mkdir(parents=True)
    (src / "figures" / GUO / "a.svg").write_text("<svg/>")
    (site / "chapters").mkdir(parents=True)
    page = site / "chapters" / "x.html"
    page.write_text('<img src="a.png"><img loading="eager" src="b.png">')
    (src / "notebooks").mkdir()
    (src / "notebooks" / "n.ipynb").write_text("{}")
    (site / "notebooks").mkdir()
    heavy = ('<script src="../searchindex.js"></script>\n<script defer src="../_static/scripts/'
             'fontawesome.js?digest=9"></script>\n')
    search = '<script src="searchindex.js"></script>'
    (site / "search.html").write_text(search + heavy.split("\n", 1)[1])
    (site / "_static" / "scripts").mkdir(parents=True)
    for name in ("fontawesome.js", "fontawesome.js.map", "bootstrap.js.map", "bootstrap.js"):
        (site / "_static" / "scripts" / name).write_text("x")
    page.write_text(heavy + '<img src="a.png"><img loading="eager" src="b.png">')
    book.finish_site(src, site)
    assert (site / "figures" / GUO / "a.svg").read_text() == "<svg/>"
    assert (site / "notebooks" / "n.ipynb").read_text() == "{}"        # the download links'
    assert page.read_text() == '<img loading="lazy" src="a.png"><img loading="eager" src="b.png">'
    assert (site / "search.html").read_text() == search      # the index stays where searched
    assert sorted(f.name for f in (site / "_static" / "scripts").iterdir()) == ["bootstrap.js"]


def _cards(rows):
    cols = ["paper", "item", "quantity", "published", "reproduced", "unit", "tolerance",
            "verdict", "basis", "kind", "agreement", "note"]
    return pd.DataFrame([dict(zip(cols, r, strict=True)) for r in rows], dtype=str)


def _row(verdict, kind="number", basis="internal"):
    return ["P", "T1", "q", "1", "1", "um", "0.5", verdict, basis, kind, "printed", ""]


@pytest.mark.parametrize("verdicts, label", [
    (["reproduced", "close", "not reproducible"], "[Re]"),
    (["reproduced", "differs"], "[~Re]"),
    (["differs", "not reproducible"], "[¬Re]"),
    (["not reproducible"], "[¬Re]"),
])
def test_a_papers_outcome_counts_its_printed_numbers_only(verdicts, label):
    claims = [_row("differs", kind="claim")] * 3           # a claim never moves the label
    got, said = scorecard.outcome(_cards([_row(v) for v in verdicts] + claims))
    assert got == label
    assert said.startswith(f"{len(verdicts)} printed numbers scored: "
                           f"{verdicts.count('reproduced')} reproduced (0 independently)")


def test_the_scorecard_is_a_static_table_every_row_escaped_and_labelled():
    cards = _cards([_row("differs"), ["P<script>", "T<2>", "a & b", "", "3", "um", "x",
                                      "reproduced", "independent", "number", "printed", "n"]])
    out = book.scorecard_html(cards, "card-x", "../_static/itables/dt_bundle.js")
    assert out.count("<tr>") == 3 and "data_json" not in out         # header + the two rows
    assert "<td data-label=\"item\">T&lt;2&gt;</td>" in out and "<script>\"" not in out
    assert '<td data-label="reproduced">3 µm</td>' in out and 'data-label="paper"' not in out
    assert 'import DataTable from "../_static/itables/dt_bundle.js"' in out
    assert '<link rel="stylesheet" href="../_static/itables/dt_bundle.css">' in out


def test_a_key_figures_preview_is_light_and_at_most_the_preview_width(guo_folder, tmp_path):
    from PIL import Image

    book.write_previews(tmp_path, guo_folder, [GUO], {})
    first = list(guo2016.FIGURES)[0]
    with Image.open(tmp_path / book.preview_name(GUO, first)) as im:
        assert im.mode == "P" and im.width <= book.PREVIEW_WIDTH


@pytest.mark.parametrize("stem", ["01_zheng2024_pce_sobol_41_errors", "02_rong_sobol_21_errors",
                                  "03_guo2016_spearman_21_errors", "04_xu2022_thermal_mlr_svr",
                                  "05_yang2021_spindle_four_point_ga"])
def test_each_paper_marks_one_key_figure_that_its_run_writes(stem):
    """The home shows each paper's finding beside its key figure: one caption says so, and the
    committed run wrote that figure."""
    keys = [name for name, c in book.captions(stem).items() if c.key]
    assert len(keys) == 1, keys
    assert (ROOT / "figures" / stem / f"{keys[0]}.png").is_file()
    fig = book.key_figure(stem, ROOT / "figures" / stem, set())
    assert fig is not None and fig["figure"] == keys[0]


# ------------------------------------------------------------- conclusions link their evidence

def _bullets_and_links(markdown: str) -> tuple[list[list[str]], list[str]]:
    """The links of each top-level list item of ``markdown`` (a nested item's count as its
    parent's), and every link of the text, as CommonMark (markdown-it, MyST's parser) reads
    them."""
    from markdown_it import MarkdownIt

    bullets, links, depth = [], [], 0
    for tok in MarkdownIt("commonmark").parse(markdown):
        if tok.type == "list_item_open":
            depth += 1
            if depth == 1:
                bullets.append([])
        elif tok.type == "list_item_close":
            depth -= 1
        for child in tok.children or []:
            if child.type == "link_open":
                links.append(child.attrs["href"])
                if depth:
                    bullets[-1].append(child.attrs["href"])
    return bullets, links


def _evidence_problems(stem: str, conclusion: str, folder: Path) -> list[str]:
    """What is wrong with a conclusion's evidence: a bullet without a link, a link that is not
    ``../figures/<stem>/<file>`` of a file the run wrote and its record lists."""
    files = provenance.read(folder).get("files", {})
    bullets, links = _bullets_and_links(conclusion)
    found = [f"bullet {i + 1} links no evidence" for i, b in enumerate(bullets) if not b]
    prefix = f"../figures/{stem}/"
    for href in links:
        name = href.removeprefix(prefix)
        if not href.startswith(prefix) or "/" in name:
            found.append(f"{href}: not a file of figures/{stem}/")
        elif name not in files or not (folder / name).is_file():
            found.append(f"{href}: not written by the run (not in its provenance.json)")
    return found


def test_the_evidence_check_names_a_bare_bullet_and_a_dangling_link(tmp_path):
    """Fault injection for the check below: a bullet without a link, a link outside the
    folder, one to a file the record does not list, one to a listed file that is gone."""
    folder = tmp_path / GUO
    _write_run(folder, _guo_figures())
    (folder / "mine.csv").write_text("a\n1\n")  # the user's: not in the record
    good = f"[rows](../figures/{GUO}/reproduction.csv)"
    assert _evidence_problems(GUO, f"Intro.\n\n* A claim. {good}\n* B\n  * nested {good}\n",
                              folder) == []
    text = (f"* A claim.\n* B [x](../figures/{GUO}/mine.csv)\n* C [y](https://example.org)\n"
            f"* D [z](../figures/{GUO}/gone.png)\n")
    assert _evidence_problems(GUO, text, folder) == [
        "bullet 1 links no evidence",
        f"../figures/{GUO}/mine.csv: not written by the run (not in its provenance.json)",
        "https://example.org: not a file of figures/" + GUO + "/",
        f"../figures/{GUO}/gone.png: not written by the run (not in its provenance.json)"]
    (folder / "reproduction.csv").unlink()
    assert _evidence_problems(GUO, f"* A. {good}", folder) == [
        f"{good[7:-1]}: not written by the run (not in its provenance.json)"]


@pytest.mark.parametrize("stem", STEMS)
def test_every_conclusion_bullet_links_evidence_the_run_wrote(stem):
    """Every bullet of a notebook's "What we conclude" ends with links to the figures or tables
    that support it, each a file of its own ``figures/<stem>/`` that its run recorded: the
    relative link resolves from ``notebooks/`` (JupyterLab, GitHub) and from the book's
    ``chapters/`` alike."""
    conclusion = book.notebook_parts(NOTEBOOKS / f"{stem}.ipynb")["conclusion"]
    bullets, _ = _bullets_and_links(conclusion)
    assert len(bullets) >= 2, f"{stem}: its conclusion has {len(bullets)} bullets"
    assert _evidence_problems(stem, conclusion, ROOT / "figures" / stem) == []


def test_a_conclusions_evidence_cross_references_the_figures_its_chapter_shows():
    text = ("x [Fig. 5](../figures/01_x/fig05_a.png), [t<b>.csv](../figures/01_x/t.csv), "
            "[Fig. 9](../figures/01_x/gone.png), [other](../figures/02_y/f.png)")
    out = book.evidence_links(text, "01_x", {"fig05_a"})
    assert "{ref}`Fig. 5 <01-fig05_a>`" in out                       # the figure shown
    assert '<a href="../figures/01_x/t.csv">t&lt;b&gt;.csv</a>' in out   # a table, escaped
    assert '<a href="../figures/01_x/gone.png">Fig. 9</a>' in out       # not shown: the file
    assert "[other](../figures/02_y/f.png)" in out                      # another chapter's
    assert book.figure_label("03_guo", "fig03 a.b") == "03-fig03-a-b"
    assert book.site_links("see [Fig. <1>](../figures/01_x/a.png) and [w](https://x.org)") == \
        'see <a href="../figures/01_x/a.png">Fig. &lt;1&gt;</a> and [w](https://x.org)'
