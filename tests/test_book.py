"""The book (``make book``, :mod:`mtaccuracy.apps.book`).

Fast tests build chapters from synthetic output folders made here (figures drawn with
matplotlib, ``provenance.json`` written by hand as a run writes it): the figures in the paper
module's order with the captions their run recorded, a missing caption and a caption without
its figure named, broken outputs and a user's file, the sweep's sentence, the parameter table.

The whole book is built once per session (about 40 s, fixture ``built``) from the folder
fixture ``book_figures`` gives: ``figures/``, or ``$MTACCURACY_BOOK_FIGURES``.  It must show
every output, captioned by the run that drew it, without a Sphinx warning; then it is read as
files and opened in headless Chromium (``/usr/bin/chromium``, conftest.py's ``browser``
fixture: skipped when missing) at a desktop width and at 400 px, served on 127.0.0.1 (any
request elsewhere fails the test).  Screenshots go to ``.test-output/book/``.
"""

import contextlib
import functools
import html
import json
import os
import re
import threading
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import matplotlib
import pandas as pd
import pytest

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from mtaccuracy.apps import book  # noqa: E402
from mtaccuracy.compendium import provenance, scorecard, workflow  # noqa: E402
from mtaccuracy.compendium.notebook import FIGURES, NOTEBOOKS, ROOT  # noqa: E402
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
                              basis="independent", note="")])
    card.to_csv(folder / "reproduction.csv", index=False, lineterminator="\n")
    for name in ("reproduction.csv", *extra):
        files[name] = {"sha256": provenance.sha256(folder / name)}
    provenance.write_sidecar(folder, {"run": {"notebook": folder.name,
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
    return [(p.relative_to(figures / stem).as_posix(), why) for p, why in broken.get(stem, [])]


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
    assert "The run shown used `n_base=4096`, the others at their defaults." in text
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

@pytest.fixture(scope="session")
def book_figures() -> Path:
    """The outputs the whole book is built from: ``figures/`` (committed), or
    ``$MTACCURACY_BOOK_FIGURES``."""
    return Path(os.environ.get("MTACCURACY_BOOK_FIGURES", FIGURES))


@pytest.fixture(scope="session")
def built(tmp_path_factory, book_figures):
    return (*book.build(tmp_path_factory.mktemp("book-build"), book_figures), book_figures)


def test_the_book_builds_from_what_is_committed_without_a_warning(built):
    site, broken, warnings, _ = built
    assert broken == {}, broken
    assert warnings == [], "\n".join(warnings[:20])
    for stem in STEMS:
        assert (site / "chapters" / f"{stem}.html").is_file()
        assert (site / "notebooks" / f"{stem}.html").is_file()
    assert (site / "scorecard.html").is_file() and (site / "api" / "index.html").is_file()
    assert (site / "_static" / "mathjax" / "MathJax.js").is_file()


def _text(path: Path) -> str:
    return path.read_text(encoding="utf-8")


def _visible(html_text: str) -> str:
    """The text a reader sees, with typographic quotes and dashes as typed."""
    text = html.unescape(re.sub(r"<[^>]+>", " ", html_text))
    for typo, typed in {"\u2019": "'", "\u2018": "'", "\u201c": '"', "\u201d": '"',
                        "\u2013": "--", "\u2014": "---"}.items():
        text = text.replace(typo, typed)
    return re.sub(r"\s+", " ", text)


@pytest.mark.parametrize("stem", STEMS)
def test_each_chapter_opens_with_its_paper_and_conclusion_and_shows_its_figures(built, stem):
    site, _, _, figures = built
    page = _text(site / "chapters" / f"{stem}.html")
    article = page[page.index('<article class="bd-article">'):]
    heads = [re.sub(r"<[^>]+>", "", h).strip("¶# \n")
             for _, h in re.findall(r"<h([12])[^>]*>(.*?)</h\1>", article, re.S)]
    assert heads[1:3] == ["What we conclude", "Figures"] and "Parameters" in heads
    intro = _visible(article[:article.index("What we conclude")])
    if stem in PAPERS:
        paper = scorecard.papers_index()[stem]
        assert heads[3] == "Scorecard" and "Paper." in intro
        if paper["doi"]:
            assert f'href="https://doi.org/{paper["doi"]}"' in article
        else:
            assert "It has no DOI." in intro
    conclusion = book.notebook_parts(NOTEBOOKS / f"{stem}.ipynb")["conclusion"]
    first_words = re.sub(r"[*`$]", "", conclusion.split("\n")[0])[2:40].strip()
    assert first_words and first_words in _visible(article)
    shown = [re.sub(r"\d*$", "", s) if s not in book.captions(stem) else s
             for s in re.findall(r'src="\.\./_images/([^"]+)\.png"', page)]
    assert shown == list(book.captions(stem))
    recorded = book.chapter_figures(stem, figures / stem)[0]
    for f in recorded:
        assert " ".join(f["caption"].split()[:6]) in _visible(page)


def _rows(page: str) -> list[list[str]]:
    """The rows a DataTables table of the page is given (itables' ``data_json``)."""
    return json.loads(json.loads(re.search(r'"data_json": ("(?:[^"\\]|\\.)*")', page).group(1)))


def test_every_scorecard_row_is_in_the_book(built):
    site, _, _, figures = built
    cards = scorecard.collect(figures)
    rows = _rows(_text(site / "scorecard.html"))
    assert len(rows) == len(cards)
    assert sorted(r[0] for r in rows) == sorted(cards["paper"])
    for stem in PAPERS:
        card = pd.read_csv(figures / stem / "reproduction.csv", dtype=str,
                           keep_default_na=False)
        rows = _rows(_text(site / "chapters" / f"{stem}.html"))
        assert [r[0] for r in rows] == [html.escape(i) for i in card["item"]]
        assert [re.sub(r"<[^>]+>", "", r[5]) for r in rows] == list(card["verdict"])


def test_nothing_is_loaded_from_outside_the_book(built):
    for page in built[0].rglob("*.html"):
        text = _text(page)
        assert not re.search(r'<(script|link|img)[^>]+(src|href)="(https?:)?//', text), page


# ------------------------------------------------------------------------------- in a browser

class _Quiet(SimpleHTTPRequestHandler):
    def log_message(self, format, *args):
        pass


@contextlib.contextmanager
def _serve(directory: Path):
    server = ThreadingHTTPServer(("127.0.0.1", 0),
                                 functools.partial(_Quiet, directory=str(directory)))
    thread = threading.Thread(target=server.serve_forever, args=(0.05,), daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}/"
    finally:
        server.shutdown()
        server.server_close()


@contextlib.contextmanager
def _page(browser, width: int, problems: list[str]):
    context = browser.new_context(viewport={"width": width, "height": 900})
    page = context.new_page()
    page.set_default_timeout(TIMEOUT_MS)

    def route(r):
        if r.request.url.startswith(("http://127.0.0.1:", "data:", "blob:")):
            r.continue_()
        else:
            problems.append(f"request outside the book: {r.request.url}")
            r.abort()

    page.route("**/*", route)
    blank = []

    def console(m):
        # MathJax 2 tests whether web fonts load with a font at about:blank, which Chromium
        # refuses (a CORS error, then a failed load): one pair per test, harmless
        if m.type != "error" or "favicon" in m.text:
            return
        if "Access to font at 'about:blank'" in m.text:
            blank.append(m.text)
        elif m.text.endswith("net::ERR_FAILED") and blank:
            blank.pop()
        else:
            problems.append(f"console {m.type}: {m.text}")

    page.on("console", console)
    page.on("pageerror", lambda e: problems.append(f"page error: {e}"))
    try:
        yield page
    finally:
        context.close()


def _no_sideways_scroll(page) -> int:
    return page.evaluate("document.documentElement.scrollWidth - "
                         "document.documentElement.clientWidth")


@pytest.mark.parametrize("width", WIDTHS.values(), ids=WIDTHS.keys())
def test_chapters_fit_the_screen_and_their_scorecards_filter(built, browser, width):
    site, _, _, figures = built
    problems = []
    SHOTS.mkdir(parents=True, exist_ok=True)
    with _serve(site) as url, _page(browser, width, problems) as page:
        page.goto(url + "index.html")
        assert _no_sideways_scroll(page) <= 0, "the home page scrolls sideways"
        page.screenshot(path=str(SHOTS / f"index-{width}.png"), full_page=True)
        for stem in [*PAPERS, None]:
            page.goto(url + (f"chapters/{stem}.html" if stem else "scorecard.html"))
            table = page.locator(f"#card-{stem[:2]}" if stem else "#card-all")
            table.locator("tbody tr").first.wait_for()
            assert _no_sideways_scroll(page) <= 0, f"{stem} scrolls sideways at {width} px"
            if stem:
                first = page.locator("article h2").first.inner_text()
                assert "What we conclude" in first, first
            n_all = int(re.search(r"of ([\d,]+) entries",
                                  page.locator(".dt-info").first.inner_text()).group(1))
            page.locator(".dt-search input").first.fill("reproduced")
            page.wait_for_timeout(300)
            info = page.locator(".dt-info").first.inner_text()
            verdicts = (pd.read_csv(figures / stem / "reproduction.csv") if stem
                        else scorecard.collect(figures)).verdict
            cells = [c.lower() for c in table.locator("tbody tr").all_inner_texts()]
            if (verdicts == "reproduced").any():
                m = re.search(r"of ([\d,]+) entries \(filtered from ([\d,]+)", info)
                assert m and int(m.group(1)) < n_all == int(m.group(2)), info
                assert all("reproduced" in c for c in cells)
            else:
                assert "No matching records" in " ".join(cells) or "0 to 0" in info, info
            if stem == PAPERS[0]:
                page.screenshot(path=str(SHOTS / f"chapter-{width}.png"), full_page=False)
    assert not problems, "\n".join(problems[:10])


def test_math_is_typeset_offline(built, browser):
    site, problems = built[0], []
    stem = "05_yang2021_spindle_four_point_ga"
    with _serve(site) as url, _page(browser, WIDTHS["phone"], problems) as page:
        page.goto(url + f"notebooks/{stem}.html")
        page.wait_for_function("window.MathJax && MathJax.Hub", timeout=TIMEOUT_MS)
        page.evaluate("new Promise(r => MathJax.Hub.Queue(r))")
        spans = page.evaluate("document.querySelectorAll('.math.notranslate').length")
        typeset = page.evaluate("document.querySelectorAll('.MathJax, .MathJax_Display').length")
        raw = page.evaluate(r"(document.querySelector('article').innerText.match(/\\\(|\$\$/g)"
                            r" || []).length")
        assert spans > 50 and typeset >= spans and raw == 0, (spans, typeset, raw)
        assert _no_sideways_scroll(page) <= 0
    assert not problems, problems

