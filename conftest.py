"""Test-session setup shared by the unit tests and the notebook checks.

* Executed notebooks write their figures and tables under ``<tmp>/mtaccuracy-tests/session-<pid>/``
  (through ``$MTACCURACY_OUTPUT_BASE`` and ``--copy-to``, which takes only folders outside the
  repository), never over the committed ``figures/``.
* The committed notebooks are executed by nbval itself (``--nbval-lax`` in pyproject.toml: every
  cell runs, the cells whose first line is ``# NBVAL_CHECK_OUTPUT`` must print what the committed
  notebook prints), after the unit tests, one at a time, each writing under the session folder
  (``$MTACCURACY_OUTPUT_BASE``).  The tests that compare what such a run wrote with the committed
  files (tests/test_notebooks.py, fixture ``nbval_output``) run after all of them.
* When the session includes tests that use the ``notebook_runs`` fixture, the extra runs with
  other parameters or data (notebook 03 with small parameters, notebook 04 on other data) start
  in the background as soon as the tests are collected, two at a time (``python -m
  mtaccuracy.compendium.runner NN --copy-to DIR``), while the unit tests run; those tests wait
  for the run they need.
* A session-wide guard fails the run if anything in the working tree's ``figures/`` or
  ``notebooks/`` changed while the tests ran.
"""

import hashlib
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent
# One folder per test session, outside the repository (a run copies only to folders outside
# it), so that two sessions running at once cannot clear each other's regenerated outputs; it
# is removed when the session ends, except the browser tests' screenshots, kept in
# .test-output/book/ and .test-output/explore/.
TEST_OUTPUT = Path(tempfile.gettempdir()) / "mtaccuracy-tests" / f"session-{os.getpid()}"
KEPT = ROOT / ".test-output"
GUARDED = [ROOT / "figures", ROOT / "notebooks"]
# Ignored by git and written by the runner outside the tests; not part of the guard.
_UNGUARDED = {".runs.json", "index.html", "html", ".running", ".failed", ".backup", ".commits",
              ".ipynb_checkpoints"}
NOTEBOOK_TIMEOUT_S = 1200
#: The extra runs of tests/test_notebooks.py: notebook 03 twice with small parameters, notebook
#: 04 on a reader's own data and on a copy of the reconstruction (:func:`own_data_runs`).
SMALL_03 = ["n_samples=40", "n_repeats=3", "n_search_poses=16", "n_search_samples=100",
            "grid_step_mm=250.0"]


def _snapshot() -> dict:
    out = {}
    for top in GUARDED:
        for p in sorted(top.rglob("*")):
            rel = p.relative_to(ROOT)
            if p.is_file() and not set(rel.parts) & _UNGUARDED and \
                    not any(part.startswith(".staging-") or part.endswith(".tmp")
                            for part in rel.parts):
                out[str(rel)] = hashlib.sha256(p.read_bytes()).hexdigest()
    return out


class NotebookRuns:
    """Notebook executions in the background, ``jobs`` at a time."""

    def __init__(self, base: Path, jobs: int):
        self.base, self.jobs = base, jobs
        self.env = {k: v for k, v in os.environ.items() if k != "MTACCURACY_STAGING"}
        self.queue: list[tuple[str, str, list[str]]] = []
        self.done: dict[str, tuple[int, str, float]] = {}
        self.cond = threading.Condition()
        self.thread: threading.Thread | None = None

    def add(self, name: str, notebook: str, params: list[str]) -> None:
        self.queue.append((name, notebook, params))

    def folder(self, name: str) -> Path:
        return self.base / name

    def start(self) -> None:
        self.thread = threading.Thread(target=self._work, daemon=True)
        self.thread.start()

    def _work(self) -> None:
        active: dict[str, tuple[subprocess.Popen, float, object]] = {}
        pending = list(self.queue)
        while pending or active:
            while pending and len(active) < self.jobs:
                name, nb, params = pending.pop(0)
                log = open(self.base / f"{name}.log", "w+")  # noqa: SIM115 - closed below
                cmd = [sys.executable, "-m", "mtaccuracy.compendium.runner", nb, *params,
                       f"--copy-to={self.folder(name)}"]
                # the environment as the session started (a test may be changing os.environ
                # in the main thread right now)
                active[name] = (subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT,
                                                 cwd=ROOT, env=self.env), time.perf_counter(),
                                log)
            time.sleep(0.1)
            for name, (proc, t0, log) in list(active.items()):
                timed_out = time.perf_counter() - t0 > NOTEBOOK_TIMEOUT_S
                if proc.poll() is None and not timed_out:
                    continue
                if timed_out:
                    proc.kill()
                    proc.wait()
                log.seek(0)
                text = log.read()
                log.close()
                with self.cond:
                    self.done[name] = (proc.returncode if not timed_out else -1, text,
                                       time.perf_counter() - t0)
                    self.cond.notify_all()
                del active[name]

    def result(self, name: str) -> tuple[int, str, float]:
        """Wait for run ``name``: (exit code, its log, seconds)."""
        with self.cond:
            self.cond.wait_for(lambda: name in self.done, timeout=NOTEBOOK_TIMEOUT_S + 60)
        if name not in self.done:
            pytest.fail(f"notebook run {name} did not finish")
        return self.done[name]


_RUNS: NotebookRuns | None = None


def pytest_configure(config):
    shutil.rmtree(TEST_OUTPUT, ignore_errors=True)
    try:
        TEST_OUTPUT.mkdir(parents=True)
    except OSError as exc:
        raise pytest.UsageError(f"cannot create the tests' scratch folder {TEST_OUTPUT}: "
                                f"{exc.strerror or exc}") from None
    os.environ["MTACCURACY_OUTPUT_BASE"] = str(TEST_OUTPUT)
    config._mtaccuracy_guard = _snapshot()


def _is_nbval(item) -> bool:
    return item.nodeid.startswith("notebooks/") and item.nodeid.split("::")[0].endswith(".ipynb")


def _needs_runs(item) -> bool:
    return bool({"notebook_runs", "nbval_output"} & set(getattr(item, "fixturenames", ())))


def pytest_addoption(parser):
    group = parser.getgroup("mtaccuracy")
    group.addoption("--part", choices=("all", "unit", "notebooks"), default="all",
                    help="unit: every test but nbval's notebook cells and the tests of what "
                         "they wrote; notebooks: only those (make test runs the two parts at "
                         "once, tests/parallel.py); all (default): everything, one after another")
    group.addoption("--notebooks", default="",
                    help="comma-separated notebook numbers (01,03): nbval runs only these, and "
                         "the tests of what nbval wrote only for these")


def _notebook_side(item) -> bool:
    return _is_nbval(item) or "nbval_output" in getattr(item, "fixturenames", ())


def _stem(item) -> str | None:
    """The notebook an nbval cell or a test parametrized by ``stem`` is about."""
    if _is_nbval(item):
        return Path(item.nodeid.split("::")[0]).stem
    return getattr(getattr(item, "callspec", None), "params", {}).get("stem")


def _select(config, items) -> None:
    """Deselect what ``--part`` and ``--notebooks`` leave out (reported as deselected)."""
    part, numbers = config.getoption("--part"), config.getoption("--notebooks")
    wanted = {n.strip() for n in numbers.split(",") if n.strip()}

    def keep(item) -> bool:
        if part != "all" and _notebook_side(item) != (part == "notebooks"):
            return False
        stem = _stem(item)
        return not (wanted and _notebook_side(item) and stem is not None
                    and stem.split("_")[0] not in wanted)

    kept = [i for i in items if keep(i)]
    if len(kept) < len(items):
        ids = {id(i) for i in kept}
        config.hook.pytest_deselected(items=[i for i in items if id(i) not in ids])
        items[:] = kept


def pytest_collection_modifyitems(config, items):
    _select(config, items)
    # the unit tests first (the extra runs execute in the background meanwhile), then nbval's
    # cells notebook by notebook, then the tests of what the runs wrote
    nbval = [i for i in items if _is_nbval(i)]
    late = [i for i in items if _needs_runs(i)]
    rest = [i for i in items if i not in nbval and i not in late]
    items[:] = rest + nbval + late
    config._mtaccuracy_nbval = {i.nodeid.split("::")[0] for i in nbval}


#: Per notebook file executed by nbval in this session: the outcomes of its cells.
_NBVAL_OUTCOMES: dict[str, list[str]] = {}


def pytest_runtest_logreport(report):
    nodeid = report.nodeid.split("::")[0]
    if nodeid.startswith("notebooks/") and nodeid.endswith(".ipynb") and \
            (report.when == "call" or report.outcome != "passed"):
        _NBVAL_OUTCOMES.setdefault(Path(nodeid).stem, []).append(report.outcome)


@pytest.fixture(scope="session")
def nbval_output(request):
    """``nbval_output(stem)``: the folder under which nbval's run of ``notebooks/<stem>.ipynb``
    in this session wrote (``figures/<stem>/``, and ``data/thermal/`` for notebook 04); fails
    when that run failed, skips when the session did not run it (run ``pytest notebooks
    tests/test_notebooks.py``, as ``make test`` does)."""
    collected = getattr(request.config, "_mtaccuracy_nbval", set())

    def get(stem: str) -> Path:
        if f"notebooks/{stem}.ipynb" not in collected:
            pytest.skip(f"nbval did not run notebooks/{stem}.ipynb in this session: add "
                        f"notebooks/ to the command (make test does)")
        outcomes = _NBVAL_OUTCOMES.get(stem, [])
        if not outcomes or set(outcomes) != {"passed"}:
            pytest.fail(f"nbval's run of notebooks/{stem}.ipynb did not pass "
                        f"({', '.join(sorted(set(outcomes))) or 'no cell ran'}); "
                        f"see its cells' failures above")
        return TEST_OUTPUT
    return get


def pytest_collection_finish(session):
    global _RUNS
    if not any("notebook_runs" in getattr(i, "fixturenames", ()) for i in session.items):
        return
    base = TEST_OUTPUT / "notebooks"
    base.mkdir(parents=True, exist_ok=True)
    _RUNS = NotebookRuns(base, jobs=max(1, min(2, os.cpu_count() or 1)))
    for k in (1, 2):
        _RUNS.add(f"03_small_{k}", "03", SMALL_03)
    for name, params in own_data_runs(TEST_OUTPUT / "own_data").items():
        _RUNS.add(name, name.split("_")[0], params)
    _RUNS.start()


def own_data_runs(base: Path) -> dict[str, list[str]]:
    """Notebook 04 on a reader's own measurements (the tests' own physical model,
    ``tests/thermal_lab.py``: experiments 11-15, 19 measurements, 9 sensors of any name,
    25 targets over 960 mm) and on a byte-identical copy of the reconstruction elsewhere."""
    sys.path.insert(0, str(ROOT / "tests"))
    import thermal_lab

    thermal_lab.write(base / "lab", **thermal_lab.NOTEBOOK_RUN)
    shutil.copytree(ROOT / "data" / "thermal", base / "copy_of_thermal")
    return {"04_own": [f"data_dir={base / 'lab'}", "n_replicates=2"],
            "04_copy": [f"data_dir={base / 'copy_of_thermal'}", "n_replicates=20"]}


@pytest.fixture(scope="session")
def notebook_runs() -> NotebookRuns:
    if _RUNS is None:
        pytest.skip("notebook runs were not started")
    return _RUNS


def pytest_sessionfinish(session, exitstatus):
    before = getattr(session.config, "_mtaccuracy_guard", None)
    if before is None:
        return
    after = _snapshot()
    changed = sorted(k for k in set(before) | set(after) if before.get(k) != after.get(k))
    if changed:
        print(f"\nERROR: the tests changed the working tree's figures/ or notebooks/: "
              f"{', '.join(changed[:10])}", file=sys.stderr)
        session.exitstatus = pytest.ExitCode.TESTS_FAILED


def pytest_unconfigure(config):
    # keep the browser tests' screenshots (.test-output/book/, .test-output/explore/), drop the
    # rest
    for name in ("book", "explore"):
        kept = TEST_OUTPUT / name
        if not kept.is_dir():
            continue
        target = KEPT / name
        try:
            shutil.rmtree(target, ignore_errors=True)
            target.parent.mkdir(exist_ok=True)
            shutil.move(str(kept), target)
        except OSError as exc:  # a read-only checkout: the screenshots are not kept
            print(f"note: the browser tests' screenshots were not kept in {target}: {exc}",
                  file=sys.stderr)
    shutil.rmtree(TEST_OUTPUT, ignore_errors=True)


@pytest.fixture(scope="session")
def test_output() -> Path:
    return TEST_OUTPUT


#: Debian's Chromium (``.ci/install-browser``; never a browser download) and its launch
#: arguments, for the browser tests (tests/test_book.py, tests/test_explore_browser.py).
CHROMIUM = Path("/usr/bin/chromium")
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync", "--no-first-run",
                 "--disable-quic"]
BROWSER_TIMEOUT_MS = 30_000


@pytest.fixture(scope="session")
def browser():
    """Headless Chromium driven by Playwright; a missing Chromium skips the test, or fails it
    under CI (``$CI`` set), which must install it."""
    if not CHROMIUM.exists():
        message = (f"{CHROMIUM} is missing: install Debian's chromium and chromium-driver "
                   "packages (make browser, that is .ci/install-browser, as root)")
        if os.environ.get("CI"):
            pytest.fail(message)
        pytest.skip(message)
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_ARGS,
                              timeout=BROWSER_TIMEOUT_MS)
        try:
            yield b
        finally:
            b.close()

