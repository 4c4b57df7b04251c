"""The reproduction report (figures/index.html) opened in a real browser.

The report is built from a copy of the committed ``figures/`` in a temporary folder, served on
127.0.0.1 (an ephemeral port) and opened in headless Chromium from the Debian package
(``/usr/bin/chromium``; ``.ci/install-browser`` installs it, nothing is ever downloaded), driven
by Playwright.  The page must show every image (natural width > 0), one ``tr.score-row`` per
row of each ``figures/<stem>/reproduction.csv`` (with the same verdicts), every regenerated PNG,
a ``section.paper`` per notebook and a ``table.summary``; every link must be relative and
resolve (HTTP 200 from the local server); nothing may leave 127.0.0.1 (no CDN, no web font, no
external link); the console must show no error.  A full-page screenshot goes to
``$MTACCURACY_OUTPUT_BASE/report/index.png``.

The checker is itself run on small hand-written pages with one defect each, so that a broken
image, a missing row, a dead or external link or a script error is shown to fail it.
"""

import collections
import contextlib
import functools
import os
import threading
import urllib.error
import urllib.parse
import urllib.request
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import matplotlib.image
import numpy as np
import pandas as pd
import pytest
from playwright.sync_api import sync_playwright

from mtaccuracy.compendium import paths, reproduction, runner

CHROMIUM = Path("/usr/bin/chromium")
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync", "--no-first-run",
                 "--disable-quic"]
TIMEOUT_MS = 30_000
STEMS = [p.stem for p in runner.all_notebooks()]


class _QuietHandler(SimpleHTTPRequestHandler):
    def log_message(self, format, *args):
        pass


@contextlib.contextmanager
def _serve(directory: Path):
    """Serve ``directory`` on 127.0.0.1 at an ephemeral port; yields the root URL."""
    handler = functools.partial(_QuietHandler, directory=str(directory))
    server = ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, args=(0.05,), daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}/"
    finally:
        server.shutdown()
        server.server_close()
        thread.join(timeout=5)


@pytest.fixture(scope="module")
def browser():
    if not CHROMIUM.exists():
        message = (f"{CHROMIUM} is missing: install Debian's chromium and chromium-driver "
                   "packages, run `make browser` (.ci/install-browser) as root")
        if os.environ.get("CI"):
            pytest.fail(message)
        pytest.skip(message)
    with sync_playwright() as p:
        # Playwright gives every launch a fresh, empty profile in a temporary folder.
        b = p.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_ARGS,
                              timeout=TIMEOUT_MS)
        try:
            yield b
        finally:
            b.close()


# Waits (bounded) until every image has loaded or failed; lazy images are made eager first.
_IMAGES_JS = """async (ms) => {
  const imgs = Array.from(document.images);
  for (const i of imgs) if (i.loading === 'lazy') i.loading = 'eager';
  const settled = i => i.complete ? null : new Promise(r => {
    i.addEventListener('load', r, {once: true}); i.addEventListener('error', r, {once: true}); });
  await Promise.race([Promise.all(imgs.map(settled)), new Promise(r => setTimeout(r, ms))]);
  return imgs.map(i => ({src: i.getAttribute('src'), width: i.naturalWidth}));
}"""
_PAGE_JS = """() => ({
  rows: Array.from(document.querySelectorAll('tr.score-row'),
                   r => [r.dataset.notebook ?? null,
                         `${r.dataset.verdict ?? ''}/${r.dataset.basis ?? ''}`]),
  sections: Array.from(document.querySelectorAll('section.paper'), s => s.id),
  summaries: document.querySelectorAll('table.summary').length,
  links: Array.from(document.querySelectorAll('a[href]'),
                    a => ({raw: a.getAttribute('href'), url: a.href})),
})"""


def _is_relative(ref: str) -> bool:
    parts = urllib.parse.urlsplit(ref)
    return not parts.scheme and not parts.netloc and not ref.startswith("/")


def _status(url: str) -> int:
    """HTTP status of a HEAD request (0 when the server cannot be reached)."""
    try:
        with urllib.request.urlopen(urllib.request.Request(url, method="HEAD"),
                                    timeout=10) as response:
            return response.status
    except urllib.error.HTTPError as e:
        return e.code
    except OSError:
        return 0


def _published_verdicts(figures: Path, stem: str) -> collections.Counter | None:
    card = figures / stem / "reproduction.csv"
    if not card.exists():
        return None
    df = pd.read_csv(card, dtype=str, keep_default_na=False)
    basis = df["basis"] if "basis" in df else [""] * len(df)
    return collections.Counter(f"{v}/{b}" for v, b in zip(df["verdict"], basis, strict=True))


def _watch(page, problems: list[str]):
    """Record the page's console errors, uncaught exceptions and HTTP errors in ``problems``."""
    page.set_default_timeout(TIMEOUT_MS)
    page.on("console", lambda m: m.type == "error" and problems.append(
        f"console error: {m.text} (at {m.location.get('url')})"))
    page.on("pageerror", lambda e: problems.append(f"page error: {e} (in {page.url})"))
    page.on("response", lambda r: r.status >= 400 and problems.append(
        f"HTTP {r.status} for {r.url}"))


def check_report(browser, figures: Path, stems: list[str], screenshot: Path | None = None):
    """Open ``figures/index.html`` in ``browser``; return the list of problems found.

    Linked HTML pages (the notebook exports) are opened too, for console errors and external
    requests; other links are only required to resolve.
    """
    problems = []
    with _serve(figures) as root:
        context = browser.new_context(viewport={"width": 1280, "height": 900},
                                      service_workers="block")
        try:
            def route(r):
                if r.request.url.startswith(root):
                    r.continue_()
                else:
                    problems.append(f"external request blocked: {r.request.url}")
                    r.abort()

            context.route("**/*", route)
            page = context.new_page()
            _watch(page, problems)
            response = page.goto(root + "index.html", wait_until="load")
            if response is None or response.status != 200:
                return problems + ["index.html did not load"]
            images = page.evaluate(_IMAGES_JS, TIMEOUT_MS // 2)
            found = page.evaluate(_PAGE_JS)
            if screenshot is not None:
                screenshot.parent.mkdir(parents=True, exist_ok=True)
                page.screenshot(path=str(screenshot), full_page=True)
            page.close()

            # Links: relative and resolving; no external ones; linked pages without errors.
            urls = set()
            for link in found["links"]:
                raw, url = link["raw"].strip(), link["url"]
                if raw.startswith("#") or raw.lower().startswith("mailto:"):
                    continue
                if urllib.parse.urlsplit(raw).scheme.lower() in ("http", "https"):
                    problems.append(f"external link: {raw}")
                elif not _is_relative(raw) or not url.startswith(root):
                    problems.append(f"link is not a relative path: {raw!r}")
                else:
                    urls.add(urllib.parse.urldefrag(url).url)
            for url in sorted(urls):
                status = _status(url)
                if status != 200:
                    problems.append(f"dead link (HTTP {status}): {url.removeprefix(root)}")
                elif urllib.parse.urlsplit(url).path.endswith((".html", ".htm")):
                    linked = context.new_page()
                    _watch(linked, problems)
                    linked.goto(url, wait_until="load")
                    linked.close()
        finally:
            context.close()

    # Images: all loaded, all relative, every regenerated PNG shown.
    shown = set()
    for img in images:
        src = img["src"] or ""
        if not _is_relative(src):
            problems.append(f"image source is not a relative path: {src!r}")
        if img["width"] <= 0:
            problems.append(f"image did not load: {src!r}")
        shown.add(urllib.parse.unquote(src.removeprefix("./")))
    for stem in stems:
        for png in sorted((figures / stem).glob("*.png")):
            if f"{stem}/{png.name}" not in shown:
                problems.append(f"figure not shown in the report: {stem}/{png.name}")

    # Scorecard: one row per reproduction.csv row, same verdicts; a section per notebook.
    rows = collections.defaultdict(collections.Counter)
    for notebook, verdict in found["rows"]:
        rows[notebook][verdict] += 1
    for stem in stems:
        expected = _published_verdicts(figures, stem)
        if expected is None and stem in reproduction.papers_index():
            problems.append(f"{stem}: figures/{stem}/reproduction.csv is missing")
            continue
        if expected is None:       # a notebook with no paper (06): a section, no score rows
            if rows.pop(stem, collections.Counter()).total():
                problems.append(f"{stem}: score rows in the report but no reproduction.csv")
            if found["sections"].count(stem) != 1:
                problems.append(f"{stem}: expected one <section class=\"paper\" id=\"{stem}\">, "
                                f"found {found['sections'].count(stem)}")
            continue
        got = rows.pop(stem, collections.Counter())
        if got.total() != expected.total():
            problems.append(f"{stem}: {got.total()} score rows in the report, "
                            f"{expected.total()} rows in reproduction.csv")
        elif got != expected:
            problems.append(f"{stem}: score-row verdicts/bases {dict(got)} differ from "
                            f"reproduction.csv {dict(expected)}")
        if found["sections"].count(stem) != 1:
            problems.append(f"{stem}: expected one <section class=\"paper\" id=\"{stem}\">, "
                            f"found {found['sections'].count(stem)}")
    for notebook, got in rows.items():
        problems.append(f"{got.total()} score rows with data-notebook={notebook!r}, "
                        "which is not a notebook")
    if found["summaries"] < 1:
        problems.append("no <table class=\"summary\">")
    return problems


def test_report_opens_in_the_browser_with_every_figure_row_and_link(browser, committed_report):
    figures = committed_report
    assert (figures / "index.html").is_file(), "report.build wrote no index.html"
    screenshot = Path(os.environ[paths.OUTPUT_BASE_ENV]) / "report" / "index.png"
    problems = check_report(browser, figures, STEMS, screenshot=screenshot)
    assert not problems, "\n".join(problems)
    assert screenshot.stat().st_size > 0


# --- the checker on hand-written pages, so that it is shown to fail -------------------------

_FIXTURE_STEMS = ["01_alpha", "02_beta"]
_FIXTURE_CARD = """item,quantity,published,reproduced,unit,tolerance,verdict,note
Table 1,a,1.0,1.0,mm,0.1,reproduced,"a note, with a comma"
Fig. 2,b,2.0,2.5,mm,0.1,differs,"a note
on two lines"
Fig. 3,c,,,,,not reproducible,lost
"""


def _fixture(folder: Path, defect: str) -> Path:
    """A report following the HTML contract, with one ``defect`` (or none)."""
    figures = folder / "figures"
    (figures / "html").mkdir(parents=True)
    (figures / "REPRODUCTION.md").write_text("# Reproduction scorecard\n")
    head, body = ["<style>td.differs { color: #a00 }</style>"], []
    body.append('<table class="summary"><tr><th>paper</th><th>rows</th></tr></table>')
    for stem in _FIXTURE_STEMS:
        out = figures / stem
        out.mkdir()
        (out / "reproduction.csv").write_text(_FIXTURE_CARD)
        (out / "table1.csv").write_text("a,b\n1,2\n")
        matplotlib.image.imsave(out / "fig02_curve.png", np.linspace(0, 1, 48).reshape(6, 8))
        export = "<!doctype html><title>nb</title>"
        if defect == "external script in a notebook export" and stem == "02_beta":
            export += '<script src="https://cdn.example.org/require.js"></script>'
        (figures / "html" / f"{stem}.html").write_text(export)
        card = pd.read_csv(out / "reproduction.csv", dtype=str, keep_default_na=False)
        if defect == "missing row" and stem == "02_beta":
            card = card.iloc[:-1]
        if defect == "wrong verdict" and stem == "02_beta":
            card = card.assign(verdict="reproduced")
        rows = "".join(f'<tr class="score-row" data-notebook="{stem}" data-verdict="{v}">'
                       f"<td>{item}</td><td>{v}</td></tr>"
                       for item, v in zip(card["item"], card["verdict"], strict=True))
        broken = defect == "broken image" and stem == "01_alpha"
        png = "missing.png" if broken else "fig02_curve.png"
        img = "" if defect == "figure not shown" and stem == "02_beta" else (
            f'<img class="figure" src="{stem}/{png}" alt="Fig. 2">')
        csv = "table9.csv" if defect == "dead link" and stem == "01_alpha" else "table1.csv"
        section_id = "02-beta" if defect == "missing section" and stem == "02_beta" else stem
        body.append(f'<section class="paper" id="{section_id}"><h2>{stem}</h2>'
                    f"<table>{rows}</table>{img}"
                    f'<a href="{stem}/{csv}">table</a> <a href="html/{stem}.html">notebook</a>'
                    "</section>")
    body.append('<a href="REPRODUCTION.md">scorecard</a> <a href="#01_alpha">top</a> '
                '<a href="mailto:someone@example.org">mail</a>')
    extra = {
        "external link": ('<a href="https://example.org/paper">paper</a>', ""),
        "absolute link": ('<a href="/REPRODUCTION.md">scorecard</a>', ""),
        "external resource": ("", '<link rel="stylesheet" href="https://cdn.example.org/a.css">'),
        "console error": ("<script>console.error('something broke')</script>", ""),
        "script error": ("<script>null.length</script>", ""),
    }
    if defect in extra:
        body.append(extra[defect][0])
        head.append(extra[defect][1])
    (figures / "index.html").write_text(
        '<!doctype html><html lang="en"><head><meta charset="utf-8"><title>report</title>'
        f'<link rel="icon" href="data:,">{"".join(head)}</head>'
        f"<body>{''.join(body)}</body></html>")
    return figures


def test_checker_passes_a_correct_fixture(browser, tmp_path):
    assert check_report(browser, _fixture(tmp_path, "none"), _FIXTURE_STEMS) == []


@pytest.mark.parametrize("defect, expected", [
    ("broken image", "image did not load: '01_alpha/missing.png'"),
    ("figure not shown", "figure not shown in the report: 02_beta/fig02_curve.png"),
    ("missing row", "02_beta: 2 score rows in the report, 3 rows in reproduction.csv"),
    ("wrong verdict", "02_beta: score-row verdicts/bases"),
    ("missing section", 'expected one <section class="paper" id="02_beta">'),
    ("dead link", "dead link (HTTP 404): 01_alpha/table9.csv"),
    ("external link", "external link: https://example.org/paper"),
    ("absolute link", "link is not a relative path: '/REPRODUCTION.md'"),
    ("external resource", "external request blocked: https://cdn.example.org/a.css"),
    ("console error", "console error: something broke"),
    ("script error", "page error:"),
    ("external script in a notebook export",
     "external request blocked: https://cdn.example.org/require.js"),
])
def test_checker_finds_the_defect(browser, tmp_path, defect, expected):
    problems = check_report(browser, _fixture(tmp_path, defect), _FIXTURE_STEMS)
    assert any(expected in p for p in problems), problems
