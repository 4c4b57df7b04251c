"""The whole book (``make book``, :mod:`mtaccuracy.apps.book`), built as CI builds it.

The whole book is built once per session (about 40 s, fixture ``built``) from the folder
fixture ``book_figures`` gives: ``figures/``, or ``$MTACCURACY_BOOK_FIGURES``.  It must show
every output, captioned by the run that drew it, without a Sphinx warning; then it is read as
files and opened in headless Chromium (``/usr/bin/chromium``, conftest.py's ``browser``
fixture: skipped when missing) at a desktop width and at 400 px, served on 127.0.0.1 (any
request elsewhere fails the test).  Screenshots go to ``.test-output/book/``.
"""

import contextlib
import fcntl
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

from mtaccuracy.apps import book  # noqa: E402
from mtaccuracy.compendium import scorecard  # noqa: E402
from mtaccuracy.compendium.notebook import FIGURES, NOTEBOOKS, ROOT  # noqa: E402
from mtaccuracy.papers import guo2016  # noqa: E402

TIMEOUT_MS = 30_000
STEMS = book.stems()
PAPERS = [s for s in STEMS if s in scorecard.papers_index()]
WIDTHS = {"desktop": 1280, "phone": 400}
GUO = guo2016.Parameters.stem
SHOTS = ROOT / ".test-output" / "book"


@pytest.fixture(scope="session")
def book_figures() -> Path:
    """The outputs the whole book is built from: ``figures/`` (committed), or
    ``$MTACCURACY_BOOK_FIGURES``."""
    return Path(os.environ.get("MTACCURACY_BOOK_FIGURES", FIGURES))


@pytest.fixture(scope="session")
def built(tmp_path_factory, book_figures, worker_id):
    """The book, built once per test run: the first xdist worker to ask builds it (under a file
    lock in the run's shared folder), the others wait and read its result, so that two
    workers do not build the same book side by side on two cores."""
    base = tmp_path_factory.getbasetemp()
    shared = base.parent if worker_id != "master" else base     # this run's, never an old one
    out, result = shared / "book-build", shared / "book-build.json"
    with open(shared / "book-build.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not result.exists():
            site, broken, warnings = book.build(out, book_figures)
            result.write_text(json.dumps({
                "site": str(site), "warnings": warnings,
                "broken": {k: [[str(f), why] for f, why in v] for k, v in broken.items()}}))
    said = json.loads(result.read_text())
    broken = {k: [(Path(f), why) for f, why in v] for k, v in said["broken"].items()}
    return Path(said["site"]), broken, said["warnings"], book_figures


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
             for s in re.findall(r'src="\.\./_images/([^"]+)\.png"', page)
             if not s.endswith("-preview")]                 # the opening's key figure
    assert shown == list(book.captions(stem))
    recorded = book.chapter_figures(stem, figures / stem)[0]
    for f in recorded:
        assert " ".join(f["caption"].split()[:6]) in _visible(page)


def _rows(page: str) -> list[list[str]]:
    """The rows of the page's scorecard (a static table: every row is in the HTML)."""
    body = re.search(r'<table id="card-[^"]+"[^>]*>.*?<tbody>(.*?)</tbody>', page, re.S).group(1)
    return [re.findall(r"<td[^>]*>(.*?)</td>", tr, re.S)
            for tr in re.findall(r"<tr>(.*?)</tr>", body, re.S)]


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



# ------------------------------------------------------------ links, figures, findings (issue 35)

def _local_links(page: Path) -> list[str]:
    """The links and sources of a page that stay in the site (no scheme, no bare fragment)."""
    return [u for u in re.findall(r'(?:href|src)="([^"]+)"', _text(page))
            if not re.match(r"[a-z][a-z0-9+.-]*:|#|//", u)]


def test_no_link_of_any_page_is_a_404(built):
    from urllib.parse import unquote

    site, missing = built[0], []
    pages = [p for p in site.rglob("*.html") if "_static" not in p.parts]
    for page in pages:
        for u in _local_links(page):
            target = unquote(u.split("#")[0].split("?")[0])
            if target and not (page.parent / target).exists():
                missing.append(f"{page.relative_to(site)} -> {u}")
    assert not missing, "\n".join(missing[:20])
    svgs = [u for p in pages for u in _local_links(p) if u.endswith(".svg")]
    assert len(svgs) >= 40                       # the SVG links are there, and resolve


def test_every_figure_loads_lazily_and_enlarges_to_its_file(built):
    site = built[0]
    for stem in STEMS:
        page = _text(site / "chapters" / f"{stem}.html")
        imgs = re.findall(r"<img [^>]*>", page)
        assert imgs and all('loading="lazy"' in i for i in imgs), stem
        for name in book.captions(stem):
            link = f'href="../figures/{stem}/{name}.png"><img '
            assert link in page, (stem, name)
            assert (site / "figures" / stem / f"{name}.png").is_file()


def test_the_home_leads_with_the_five_findings_their_figures_and_chapters(built):
    site = built[0]
    page = _text(site / "index.html")
    article = page[page.index('<article class="bd-article">'):]
    found = article[article.index('id="what-we-found"'):article.index('id="the-scorecard"')]
    sections = found.split("<h3>")[1:]
    assert len(sections) == len(PAPERS) == 5
    lines = book.findings(scorecard.papers_index())
    for stem, part in zip(PAPERS, sections, strict=True):
        assert f'href="chapters/{stem}.html"' in part
        said = re.sub(r"\s", "", _visible(re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1",
                                                  lines[stem])))
        shown = re.sub(r"\s", "", _visible(part))
        assert said in shown, stem
        img = re.search(r'<a [^>]*href="(figures/[^"]+\.png)"><img [^>]*class="key-figure"', part)
        assert img and (site / img.group(1)).is_file(), stem


# ------------------------------------------------ the scorecard from disk, page weight, 400 px

def test_the_scorecard_reads_from_disk_without_a_server(built, browser):
    site, problems = built[0], []
    with _page(browser, WIDTHS["phone"], problems) as page:
        page.route("**/*", lambda r: r.continue_())          # file:// only here
        page.goto((site / "scorecard.html").as_uri())
        rows = page.locator("#card-all tbody tr")
        assert rows.count() == len(scorecard.collect(built[3]))
        card = rows.first.bounding_box()
        assert card["width"] > 300                         # a card as wide as the phone
        label = rows.first.locator('td[data-label="verdict"]').evaluate(
            "td => getComputedStyle(td, '::before').content")
        assert label == '"verdict: "'                      # each line labelled
        assert _no_sideways_scroll(page) <= 0


def _first_load_bytes(page, url: str) -> int:
    sizes = {}

    def got(r):
        with contextlib.suppress(Exception):
            sizes[r.url] = len(r.body())

    page.on("response", got)
    page.goto(url, wait_until="load")
    page.remove_listener("response", got)
    return sum(sizes.values())


def _pages(site: Path) -> list[str]:
    """The home, the scorecard, every chapter, every executed notebook, every API page."""
    return ["index.html", "scorecard.html", *(f"chapters/{s}.html" for s in STEMS),
            *(f"notebooks/{s}.html" for s in STEMS),
            *sorted(p.relative_to(site).as_posix() for p in (site / "api").glob("*.html"))]


def test_pages_are_light_on_first_load(built, browser):
    """The home under 1 MB and no page over 3 MB on first load (uncompressed, as served from
    disk: what the browser asks for until the page's load event; lazy figures below the fold
    are not asked for)."""
    site, problems, heavy = built[0], [], []
    with _serve(site) as url, _page(browser, WIDTHS["desktop"], problems) as page:
        for name in _pages(site)[:2 + 2 * len(STEMS)]:
            size = _first_load_bytes(page, url + name)
            if size > (1e6 if name == "index.html" else 3e6):
                heavy.append(f"{name}: {size / 1e6:.2f} MB")
    assert not heavy, heavy
    assert not problems, problems[:5]


def test_no_page_scrolls_sideways_at_400_px(built, browser):
    """No page wider than a 400 px phone, the API pages included."""
    site, problems, wide = built[0], [], []
    with _serve(site) as url, _page(browser, WIDTHS["phone"], problems) as page:
        for name in _pages(site):
            page.goto(url + name, wait_until="domcontentloaded")
            if (over := _no_sideways_scroll(page)) > 0:
                wide.append(f"{name}: {over} px")
    assert not wide, wide
    assert not problems, problems[:5]


def test_a_figure_enlarges_to_its_full_png(built, browser):
    site, problems = built[0], []
    stem = PAPERS[0]
    with _serve(site) as url, _page(browser, WIDTHS["phone"], problems) as page:
        page.goto(url + f"chapters/{stem}.html")
        first = page.locator("figure a.image-reference").first
        shown = first.locator("img").evaluate("i => i.getBoundingClientRect().width")
        first.click()
        page.wait_for_load_state()
        assert page.url.endswith(".png") and f"/figures/{stem}/" in page.url
        full = page.evaluate("document.images[0].naturalWidth")
        assert full > 2 * shown                      # the file is larger than what was shown
    assert not problems, problems


def test_a_chapters_figures_take_the_right_margin_on_a_desktop(built, browser):
    """At 1280 px a chapter's figures span the text and the contents column (936 px, against
    688 for the text): their 9 pt labels show at 8 pt or more when the figure is at most 1645 px
    wide (150 dpi); the contents column folds away while a figure is in view, its chevron drawn
    by the theme's own icon font."""
    site, problems = built[0], []
    with _serve(site) as url, _page(browser, WIDTHS["desktop"], problems) as page:
        page.goto(url + f"chapters/{PAPERS[2]}.html")
        text = page.locator("article p").first.bounding_box()["width"]
        fig = page.locator("figure.full-width").first
        fig.scroll_into_view_if_needed()
        page.wait_for_timeout(600)
        assert fig.bounding_box()["width"] > 1.3 * text
        chevron = page.locator(".onthispage").first.evaluate(
            "e => getComputedStyle(e, '::after').fontFamily")
        assert "Font Awesome 7" in chevron
    assert not problems, problems
