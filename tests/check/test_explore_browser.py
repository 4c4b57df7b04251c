"""The explorer served by ``python -m mtaccuracy.apps.explore`` and driven in a browser.

The server runs in a subprocess on 127.0.0.1 at a free port (``--port 0``; the URL is read from
its first line of output) and is always terminated.  Headless Chromium from the Debian package
(``/usr/bin/chromium``, conftest.py's ``browser`` fixture; nothing is ever downloaded) opens
it.  A pose slider is moved with
the keyboard on its handle and the top error's index shown must change; the hover tooltip of
the dominant-error map must show an error and its index; a topology typed in must show the
library's message when it is bad and its machine when it is good; the Spindle tab must list
the harmonics four equally spaced probes cancel; the Thermal tab must show an RMSE.  Every
request must stay on the server (Panel serves its own JavaScript: no CDN, no web font), and
the console must show no error.  A screenshot goes to ``.test-output/explore/explore.png``.
At 400 px (issue 35): without the token the page is refused; no tab scrolls sideways; a half
range typed in the ranges table is applied and an out-of-bounds one refused; a probe file
(written here from a known profile, spindle motion and layout) sets the Spindle tab's layout
and a bad one shows notebook 07's reader's message; the URL then restores the tab, the pose,
the range and the probes in a new page, and a crafted link names its bad parts.
Waits are bounded.
"""

import re

import pytest

from mtaccuracy.apps.explore_bench import NotStarted, served
from mtaccuracy.compendium.notebook import ROOT

playwright = pytest.importorskip("playwright.sync_api")

START_TIMEOUT_S = 60
TIMEOUT_MS = 30_000


@pytest.fixture
def server(tmp_path):
    """The explorer in a subprocess (``explore_bench.served``, as the bench serves it); yields
    its URL; terminated whatever happens; its log must show no traceback."""
    log = tmp_path / "server.log"
    with open(log, "w") as err:
        try:
            with served(timeout_s=START_TIMEOUT_S, cwd=tmp_path, stderr=err) as (_, url):
                yield url
        except NotStarted as exc:
            pytest.fail(f"{exc}: {log.read_text()[-2000:]}")
    text = log.read_text()           # what the page sent, crafted values included: no traceback
    assert "Traceback" not in text and "ERROR" not in text, text[-3000:]


#: Sets the value of the Bokeh model with CSS class %s to %s in the page, as a crafted
#: websocket message would (Bokeh sends the change to the server).
_CRAFT = """() => {
    for (const m of Bokeh.documents[0].all_models) {
        if (m.css_classes && m.css_classes.includes("%s")) { m.value = %s; return true; }
    }
    return false;
}"""


def _tooltip_values(page) -> list[str]:
    rows = page.locator(".bk-tooltip-row-value")
    return [rows.nth(i).text_content().strip() for i in range(rows.count())
            if rows.nth(i).is_visible()]


def test_the_explorer_in_a_browser(server, browser):
    expect = playwright.expect
    base = server.split("?")[0]
    problems, external = [], []
    context = browser.new_context(viewport={"width": 1500, "height": 1000},
                                  service_workers="block")
    try:
        def route(r):
            if r.request.url.startswith(base):
                r.continue_()
            else:
                external.append(r.request.url)
                r.abort()

        context.route("**/*", route)
        page = context.new_page()
        page.set_default_timeout(TIMEOUT_MS)
        page.on("console", lambda m: m.type == "error" and problems.append(
            f"console error: {m.text}"))
        page.on("pageerror", lambda e: problems.append(f"page error: {e}"))
        page.on("response", lambda r: r.status >= 400 and problems.append(
            f"HTTP {r.status} for {r.url}"))
        response = page.goto(server, wait_until="load")
        assert response is not None and response.status == 200

        # the Machine tab: indices at the starting pose (Zheng et al.'s machine)
        px = page.locator('tr[data-role="top-error"][data-output="Px"]')
        px.wait_for()
        before = px.get_attribute("data-index")
        assert 0 < float(before) <= 1 and px.get_attribute("data-error")
        assert page.locator('tr[data-role="top-error"]').count() == 6

        # move the x slider with the keyboard on its handle: the indices shown change
        handle = page.locator(".pose-x .noUi-handle")
        assert handle.count() == 1
        handle.focus()
        for _ in range(3):
            page.keyboard.press("PageUp")
        expect(px).not_to_have_attribute("data-index", before, timeout=10_000)
        assert float(px.get_attribute("data-index")) != float(before)
        expect(page.locator(".pose-x")).to_contain_text("135")   # 120 mm + 3 x 5 steps of 1

        # hover over the dominant-error map: an error of the machine and its index
        figures = page.locator(".bk-Figure")
        box = figures.nth(1).bounding_box()
        for f in (0.30, 0.35):
            page.mouse.move(box["x"] + box["width"] * f, box["y"] + box["height"] * 0.5,
                            steps=4)
        expect(page.locator(".bk-tooltip-row-value").first).to_be_visible(timeout=5_000)
        values = _tooltip_values(page)
        assert re.fullmatch(r"[a-zA-Z_()]+", values[0]) and 0 <= float(values[1]) <= 1, values

        shot = ROOT / ".test-output" / "explore" / "explore.png"
        shot.parent.mkdir(parents=True, exist_ok=True)
        page.mouse.move(5, 5)
        page.screenshot(path=str(shot), full_page=True)

        # a pose typed in (test point 2: y = -212.5 mm is off the slider's 1 mm steps): Vx
        # shows its eight tied errors; the slider follows the box
        for axis, value in dict(x="-200", y="-212.5", z="-137.5", A="-65", C="90").items():
            box = page.locator(f".pose-{axis}-input input")
            box.fill(value)
            box.press("Enter")
        vx = page.locator('tr[data-role="top-error"][data-output="Vx"]')
        expect(vx).to_have_attribute("data-ties", "8", timeout=10_000)
        expect(vx).to_contain_text("(8 tied)")
        expect(page.locator(".pose-y")).to_contain_text("-212.5")
        # the top-error table downloads as CSV: one row per tied error
        with page.expect_download() as download:
            page.get_by_role("button", name="top errors (CSV)").click()
        rows = download.value.path().read_text().splitlines()
        assert rows[0] == "output,error,index" and sum(r.startswith("Vx,") for r in rows) == 8
        # a cleared box, and values the page would not send (a crafted message: the model's
        # value set in BokehJS): refused by the server with a message, never applied
        box = page.locator(".pose-y-input input")
        box.fill("")
        box.press("Enter")
        refused = page.locator('[data-role="error"]').filter(has_text="axis y")
        expect(refused).to_contain_text("axis y is empty", timeout=10_000)
        for value, why in (("Infinity", "infinite"), ("NaN", "NaN"), ("1e9", "out of bounds")):
            assert page.evaluate(_CRAFT % ("pose-y-input", value)), value
            expect(refused).to_contain_text(why, timeout=10_000)
        expect(vx).to_have_attribute("data-ties", "8")

        # a topology typed in: a bad one shows the library's message, a good one its machine
        topology = page.locator("input[placeholder='w C b X Y Z B t']")
        topology.fill("w C A b Y X Q t")
        topology.press("Enter")
        error = page.locator('[data-role="error"]').filter(has_text="topology")
        expect(error).to_contain_text("unknown axis letter(s) ['Q'] in topology", timeout=10_000)
        assert "Traceback" not in error.text_content()
        topology.fill("w C b X Y Z B t")
        topology.press("Enter")
        expect(page.locator('tr[data-role="top-error"][data-output="Px"]')).to_have_attribute(
            "data-error", "EXC, EXX, EXY, EXZ, EXB", timeout=10_000)
        expect(page.locator('tr[data-role="top-error"][data-output="Vz"]')).to_contain_text(
            "no first-order term")
        expect(error).to_be_hidden()

        # the Spindle tab: four equally spaced probes cancel the odd harmonics
        page.get_by_text("Spindle", exact=True).click()
        page.locator("select", has=page.locator("option", has_text="four probes")) \
            .select_option(label="four probes equally spaced")
        summary = page.locator('[data-role="spindle-summary"]')
        expect(summary).to_contain_text("Cancelled by the layout: 3, 5, 7, 9, 11, 13, 15, 17, "
                                        "19.", timeout=10_000)

        # the Thermal tab: notebook 04's split (train 1 2 3, test 4), the MLR's RMSE
        page.get_by_text("Thermal", exact=True).click()
        rmse = page.locator('[data-role="thermal-summary"]')
        expect(rmse).to_contain_text("trained on experiment(s) 1, 2, 3, predicting experiment 4")
        expect(rmse).to_contain_text("RMSE")
        assert 0 < float(rmse.get_attribute("data-rmse")) < 5
    except AssertionError as exc:          # with what the page reported on the way
        raise AssertionError(f"{exc}\npage problems: {problems}") from None
    finally:
        context.close()
    assert not external, f"requests left 127.0.0.1: {external}"
    assert not problems, problems


def _probe_file(path, angles_deg, n=64):
    """A probe file of a known roundness profile and spindle motion (µm), as notebook 07 reads."""
    import numpy as np

    theta = np.arange(n) * 2 * np.pi / n
    rows = ["revolution,angle_deg," + ",".join(f"probe_{a:g}_um" for a in angles_deg)]
    for r in (1, 2):
        x, y = 0.8 * np.cos(theta + 0.3 * r), 0.6 * np.sin(theta + 0.1)
        for j in range(n):
            vals = [2.0 * np.cos(3 * (theta[j] + a)) + np.sin(5 * (theta[j] + a))
                    + x[j] * np.cos(a) + y[j] * np.sin(a) for a in np.deg2rad(angles_deg)]
            rows.append(f"{r},{float(np.rad2deg(theta[j]))!r}," + ",".join(
                f"{v:.6f}" for v in vals))
    path.write_text("\n".join(rows) + "\n")
    return path


def _scroll_width(page) -> int:
    return page.evaluate("document.documentElement.scrollWidth")


def test_the_explorer_at_400px_round_trips_its_url_and_reads_a_probe_file(server, browser,
                                                                          tmp_path):
    expect = playwright.expect
    base = server.split("?")[0]
    problems = []
    context = browser.new_context(viewport={"width": 400, "height": 900},
                                  service_workers="block")
    try:
        context.route("**/*", lambda r: r.continue_() if r.request.url.startswith(base)
                      else (problems.append(f"external: {r.request.url}"), r.abort()))
        page = context.new_page()
        page.set_default_timeout(TIMEOUT_MS)
        page.on("pageerror", lambda e: problems.append(f"page error: {e}"))
        # no token, no app: the page says where the token is
        assert page.goto(base).status == 403
        assert "needs its token" in page.content()
        page.goto(server, wait_until="load")
        px = page.locator('tr[data-role="top-error"][data-output="Px"]')
        px.wait_for()
        assert _scroll_width(page) <= 400, "the Machine tab scrolls sideways at 400 px"

        # a typed pose, one error's range typed in the table: both go into the URL
        box = page.locator(".pose-y-input input")
        box.fill("-212.5")
        box.press("Enter")
        expect(page.locator(".pose-y")).to_contain_text("-212.5", timeout=10_000)
        cell = page.locator('.error-ranges .tabulator-row').nth(2).locator(
            '[tabulator-field="half_range"]')
        cell.scroll_into_view_if_needed()
        page.wait_for_timeout(300)                     # the table settles after scrolling
        cell.click()
        page.locator(".error-ranges input").wait_for(state="attached")
        page.keyboard.press("Control+A")
        page.keyboard.type("25")
        page.keyboard.press("Enter")
        expect(cell).to_contain_text("25.0000", timeout=10_000)
        page.wait_for_timeout(300)
        cell.click()                                   # a value out of bounds: refused
        page.locator(".error-ranges input").wait_for(state="attached")
        page.keyboard.press("Control+A")
        page.keyboard.type("99999")
        page.keyboard.press("Enter")
        expect(cell).to_contain_text("25.0000", timeout=10_000)

        # the Spindle tab at 400 px: a probe file through notebook 07's reader
        page.get_by_text("Spindle", exact=True).click()
        expect(page.locator('[data-role="spindle-summary"]')).to_be_visible()
        assert _scroll_width(page) <= 400, "the Spindle tab scrolls sideways at 400 px"
        upload = page.locator(".probe-file input[type=file]")
        bad = _probe_file(tmp_path / "bad.csv", [0.0, 50.0, 190.0, 300.0])
        bad.write_text(bad.read_text().replace("probe_50_um", "probe_50_mm"))
        upload.set_input_files(str(bad))
        error = page.locator('[data-role="error"]').filter(has_text="bad.csv")
        expect(error).to_contain_text("line 1", timeout=10_000)
        assert "/tmp" not in error.text_content()
        upload.set_input_files(str(_probe_file(tmp_path / "mine.csv",
                                               [10.0, 50.0, 190.0, 300.0])))
        expect(page.locator('[data-role="file-read"]')).to_contain_text(
            "mine.csv: probes at 10, 50, 190, 300 deg", timeout=10_000)
        expect(page.locator(".probe-3-input input")).to_have_value("180", timeout=10_000)
        expect(page.get_by_role("link", name="07_your_spindle")).to_be_visible()

        page.get_by_text("Thermal", exact=True).click()
        expect(page.locator('[data-role="thermal-summary"]')).to_be_visible()
        assert _scroll_width(page) <= 400, "the Thermal tab scrolls sideways at 400 px"
        page.get_by_text("Spindle", exact=True).click()

        # the URL holds the state: a reload restores the tab, the pose, the range, the probes
        page.wait_for_function("location.search.includes('tab=spindle')")
        link = page.url
        assert "token=" in link and "tab=spindle" in link and "ranges=" in link
        again = context.new_page()
        again.set_default_timeout(TIMEOUT_MS)
        again.goto(link, wait_until="load")
        expect(again.locator(".probe-3-input input")).to_have_value("180")
        expect(again.locator(".probe-2-input input")).to_have_value("40")
        again.get_by_text("Machine", exact=True).click()
        expect(again.locator(".pose-y-input input")).to_have_value(re.compile(r"-212\.50*$"))
        expect(again.locator('.error-ranges .tabulator-row').nth(2).locator(
            '[tabulator-field="half_range"]')).to_contain_text("25.0000")
        # a crafted link: its bad part named, the rest applied, no traceback
        again.goto(link.replace("probes=", "probes=1e9%2C") + "&pose=x%3Anan",
                   wait_until="load")
        refused = again.locator('[data-role="error"]').filter(has_text="link's state")
        expect(refused).to_contain_text("probes:")
        expect(refused).to_contain_text("pose:")
    except AssertionError as exc:
        raise AssertionError(f"{exc}\npage problems: {problems}") from None
    finally:
        context.close()
    assert not problems, problems
