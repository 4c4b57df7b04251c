"""How long a slider move of the explorer takes to show new numbers, measured in Chromium.

``make bench`` (row ``explore_browser``) and ``python -m mtaccuracy.apps.explore_bench``: the
explorer is served in a subprocess (:mod:`mtaccuracy.apps.explore`, its token read from the URL
it prints), headless Chromium (Debian's ``/usr/bin/chromium``, driven by Playwright; nothing is
downloaded) opens it at 1280 x 900, and the pose slider ``x`` of the Machine tab is moved with the
keyboard on its handle (PageUp and PageDown in turn).  A move's time runs from the key's
``keydown`` in the page to the first change of the top-error table in the page (a
``MutationObserver``, both on the page's ``performance.now()`` clock): the websocket message,
the server's update, and the browser's drawing of the new table.  The first moves warm up and
are not counted.
"""

from __future__ import annotations

import contextlib
import queue
import re
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np

#: Debian's Chromium (conftest.py's, .ci/install-browser installs it).
CHROMIUM = Path("/usr/bin/chromium")
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu",
                 "--disable-background-networking"]
#: Moves timed, after :data:`WARMUP` not counted.
MOVES, WARMUP = 21, 3

_ARM = """([el, status]) => {
    const root = el.getRootNode();
    window.__mtKey = null; window.__mtShown = null; window.__mtDone = null;
    if (!window.__mtListening) {
        window.addEventListener("keydown", () => { window.__mtKey = performance.now(); }, true);
        window.__mtListening = true;
    }
    if (window.__mtObserver) window.__mtObserver.disconnect();
    window.__mtObserver = new MutationObserver(() => {
        if (window.__mtKey !== null && window.__mtShown === null)
            window.__mtShown = performance.now();
    });
    window.__mtObserver.observe(root, {childList: true, subtree: true, characterData: true});
    if (window.__mtLast) window.__mtLast.disconnect();
    window.__mtLast = new MutationObserver(() => {
        if (window.__mtKey !== null && window.__mtDone === null)
            window.__mtDone = performance.now();
    });
    window.__mtLast.observe(status.getRootNode(), {childList: true, subtree: true,
                                                   characterData: true});
}"""


class NotStarted(RuntimeError):
    """The explorer did not print its URL in time (:func:`served`)."""


@contextlib.contextmanager
def served(*, timeout_s: float = 60.0, cwd=None, stderr=subprocess.DEVNULL):
    """The explorer in a subprocess on 127.0.0.1 at a free port; yields ``(process, URL)``.

    The URL, with its token, is read from the server's output by a thread, so the wait is
    bounded even when the server prints nothing; the server is terminated (then killed) on
    leaving, whatever happened.  The bench and the browser tests share it.

    Parameters
    ----------
    timeout_s : float
        How long to wait for the URL, s.
    cwd : path, optional
        The server's working folder.
    stderr : file, optional
        Where the server's log goes (default: discarded).
    """
    proc = subprocess.Popen([sys.executable, "-m", "mtaccuracy.apps.explore", "--port", "0",
                             "--no-show"], stdout=subprocess.PIPE, stderr=stderr, text=True,
                            cwd=cwd)
    lines: queue.Queue = queue.Queue()
    threading.Thread(target=lambda: [lines.put(li) for li in proc.stdout], daemon=True).start()
    try:
        deadline, url = time.monotonic() + timeout_s, None
        while url is None and time.monotonic() < deadline and proc.poll() is None:
            try:
                found = re.search(r"http://127\.0\.0\.1:\d+/\?token=[\w-]+",
                                  lines.get(timeout=0.5))
            except queue.Empty:
                continue
            url = found.group(0) if found else None
        if url is None:
            raise NotStarted(f"the explorer did not print its URL within {timeout_s:g} s "
                               f"(exit code {proc.poll()})")
        yield proc, url
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(timeout=10)


def slider_latency(moves: int = MOVES, warmup: int = WARMUP) -> dict:
    """Times (s) of ``moves`` slider moves from the key to the new top-error table.

    Returns ``{"times": [...], "median": s, "server_ms": [...], "last": [...]}`` (the server's
    own update times as the page shows them; until the last message of the move, the status
    line sent after the plots' data), or ``{"skipped": why}`` without Chromium or Playwright.
    """
    if not CHROMIUM.exists():
        return {"skipped": f"{CHROMIUM} is missing (make browser installs it)"}
    try:
        from playwright.sync_api import sync_playwright  # optional: the bench says so
    except ImportError:
        return {"skipped": "Playwright is not installed"}
    with served(timeout_s=90.0) as (_, url):
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_ARGS)
            page = browser.new_page(viewport={"width": 1280, "height": 900})
            page.set_default_timeout(60_000)
            page.goto(url, wait_until="load")
            table = page.locator("table.mt-top")
            table.wait_for()
            handle = page.locator(".pose-x .noUi-handle")
            handle.focus()
            times, server, last = [], [], []
            for i in range(moves + warmup):
                page.evaluate(_ARM, [table.element_handle(),
                                     page.locator('[data-role="timing"]').element_handle()])
                page.keyboard.press("PageUp" if i % 2 == 0 else "PageDown")
                page.wait_for_function("window.__mtShown !== null", polling="raf")
                ms = page.evaluate("window.__mtShown - window.__mtKey")
                page.wait_for_function("window.__mtDone !== null", polling="raf")
                done = page.evaluate("window.__mtDone - window.__mtKey")
                page.wait_for_timeout(150)           # the map and the rest arrive: settle
                shown = page.locator('[data-role="timing"]').text_content() or ""
                found = re.search(r"computed in (\d+) ms", shown)
                if i >= warmup:
                    times.append(ms / 1e3)
                    last.append(done / 1e3)
                    if found:
                        server.append(int(found.group(1)))
            browser.close()
    return {"times": times, "median": float(np.median(times)), "server_ms": server,
            "last": last}


def main() -> int:
    """Print the median and the spread of the slider moves."""
    r = slider_latency()
    if "skipped" in r:
        print(f"explore_bench: skipped: {r['skipped']}")
        return 0
    t = np.array(r["times"]) * 1e3
    print(f"slider move to new numbers in Chromium: median {np.median(t):.1f} ms "
          f"(min {t.min():.1f}, max {t.max():.1f}, {t.size} moves); server update median "
          f"{np.median(r['server_ms']) if r['server_ms'] else float('nan'):.0f} ms; the "
          f"move's last message (after the plots' data) median {np.median(r['last']) * 1e3:.1f} "
          "ms")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
