"""The book (``make book``), built once per session from the committed notebooks and figures
into the session's folder, then read as files and opened in a real browser.

The browser is headless Chromium from the Debian package (``/usr/bin/chromium``;
``.ci/install-browser`` installs it, nothing is ever downloaded; conftest.py's ``browser``
fixture), driven by Playwright, at a
desktop width and at 400 px.  The book is served on 127.0.0.1 (an ephemeral port); any request
elsewhere is refused and fails the test.  A full-page screenshot of the home page and of one
chapter at each width goes to ``$MTACCURACY_OUTPUT_BASE/book/`` (kept in
``.test-output/book/``).
"""

import contextlib
import functools
import html
import json
import re
import threading
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import pandas as pd
import pytest

from mtaccuracy.compendium import book, paths, reproduction, runner

TIMEOUT_MS = 30_000
STEMS = [p.stem for p in runner.all_notebooks()]
PAPERS = [s for s in STEMS if s in reproduction.papers_index()]
WIDTHS = {"desktop": 1280, "phone": 400}


@pytest.fixture(scope="session")
def built(test_output):
    site, broken, warnings = book.build(test_output / "book-build", paths.FIGURES)
    return site, broken, warnings


def test_the_book_builds_from_what_is_committed_without_a_warning(built):
    site, broken, warnings = built
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


@pytest.mark.parametrize("stem", PAPERS)
def test_each_chapter_opens_with_the_paper_its_doi_and_the_conclusion(built, stem):
    site = built[0]
    page = _text(site / "chapters" / f"{stem}.html")
    article = page[page.index('<article class="bd-article">'):]
    heads = re.findall(r"<h([12])[^>]*>(.*?)</h\1>", article, re.S)
    assert [re.sub(r"<[^>]+>", "", h).strip("¶# \n") for _, h in heads][1:4] == [
        "What we conclude", "Figures", "Scorecard"]
    intro = _visible(article[:article.index("What we conclude")])
    paper = reproduction.papers_index()[stem]
    assert "Paper." in intro
    if paper["doi"]:
        assert f'href="https://doi.org/{paper["doi"]}"' in article
    else:
        assert "It has no DOI." in intro
    conclusion = book.notebook_parts(paths.NOTEBOOKS / f"{stem}.ipynb")["conclusion"]
    first_words = re.sub(r"[*`$]", "", conclusion.split("\n")[0])[2:40].strip()
    assert first_words and first_words in _visible(article)


@pytest.mark.parametrize("stem", STEMS)
def test_figures_come_in_the_papers_order_with_their_captions(built, stem):
    site = built[0]
    page = _text(site / "chapters" / f"{stem}.html")
    caps = book.captions()[stem]
    shown = re.findall(r'src="\.\./_images/([^"]+)\.png"', page)
    assert [re.sub(r"\d*$", "", s) if s not in {c["figure"] for c in caps} else s
            for s in shown] == [c["figure"] for c in caps]
    visible = _visible(page)
    for c in caps:
        words = " ".join(str(c["caption"]).split()[:6])
        assert words in visible, words


def _rows(page: str) -> list[list[str]]:
    """The rows a DataTables table of the page is given (itables' ``data_json``)."""
    return json.loads(json.loads(re.search(r'"data_json": ("(?:[^"\\]|\\.)*")', page).group(1)))


def test_every_scorecard_row_is_in_the_book(built):
    site = built[0]
    cards = reproduction.collect()
    rows = _rows(_text(site / "scorecard.html"))
    assert len(rows) == len(cards)
    assert sorted(r[0] for r in rows) == sorted(cards["paper"])
    for stem in PAPERS:
        card = pd.read_csv(paths.FIGURES / stem / "reproduction.csv", dtype=str,
                           keep_default_na=False)
        rows = _rows(_text(site / "chapters" / f"{stem}.html"))
        assert [r[0] for r in rows] == [html.escape(i) for i in card["item"]]
        assert [re.sub(r"<[^>]+>", "", r[5]) for r in rows] == list(card["verdict"])


def test_nothing_is_loaded_from_outside_the_book(built):
    site = built[0]
    for page in site.rglob("*.html"):
        text = _text(page)
        assert not re.search(r'<(script|link|img)[^>]+(src|href)="(https?:)?//', text), page


def test_a_folder_not_written_by_the_book_is_never_replaced(tmp_path):
    (tmp_path / "html").mkdir()
    (tmp_path / "html" / "mine.txt").write_text("a reader's file")
    with pytest.raises(book.BookError, match="was not written by make book"):
        book.build(tmp_path, paths.FIGURES)
    assert (tmp_path / "html" / "mine.txt").read_text() == "a reader's file"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["html"]


def test_units_are_written_with_their_symbols():
    assert book.unit_symbol("um/m/degC") == "µm/m/°C"
    assert book.unit_symbol("deg") == "°" and book.unit_symbol("mm") == "mm"


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
def test_chapters_fit_the_screen_and_their_scorecards_filter(built, browser, test_output,
                                                             width):
    site, problems = built[0], []
    shots = test_output / "book"
    shots.mkdir(exist_ok=True)
    with _serve(site) as url, _page(browser, width, problems) as page:
        page.goto(url + "index.html")
        assert _no_sideways_scroll(page) <= 0, "the home page scrolls sideways"
        page.screenshot(path=str(shots / f"index-{width}.png"), full_page=True)
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
            verdicts = (pd.read_csv(paths.FIGURES / stem / "reproduction.csv") if stem
                        else reproduction.collect()).verdict
            cells = [c.lower() for c in table.locator("tbody tr").all_inner_texts()]
            if (verdicts == "reproduced").any():
                m = re.search(r"of ([\d,]+) entries \(filtered from ([\d,]+)", info)
                assert m and int(m.group(1)) < n_all == int(m.group(2)), info
                assert all("reproduced" in c for c in cells)
            else:
                assert "No matching records" in " ".join(cells) or "0 to 0" in info, info
            if stem == PAPERS[0]:
                page.screenshot(path=str(shots / f"chapter-{width}.png"), full_page=False)
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
