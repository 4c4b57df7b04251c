"""``make bench``: a task runs in a process of its own and reports time, memory and index errors;
SALib runs the same Sobol' design as ours; OpenTURNS gets an environment of its own; make's
targets are timed in fresh clones.  Nothing here is timed."""

import builtins
import json
import subprocess
import sys
import sysconfig
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from mtaccuracy.apps import bench, bench_tasks


def test_a_task_runs_in_its_own_process_and_reports_json():
    out = subprocess.run([sys.executable, "-m", "mtaccuracy.apps.bench", "--task",
                          "pce_interaction_polynomial_omp"], capture_output=True, text=True,
                         check=True)
    r = json.loads(out.stdout.strip().splitlines()[-1])
    assert r["time"] > 0 and r["peak_mb"] >= r["task_mb"] >= 0
    # the polynomial is exact in a degree-2 basis: the PCE gives its indices to rounding
    assert r["err_s1"] < 1e-10 and r["err_st"] < 1e-10 and "degree 2" in r["note"]


def test_the_subprocess_imports_the_library_the_bench_runs_from(monkeypatch):
    seen = {}

    def fake_run(cmd, **kw):
        seen.update(cmd=cmd, env=kw["env"])
        return SimpleNamespace(returncode=0, stdout='{"time": 1.0}\n', stderr="")
    monkeypatch.setattr(bench.subprocess, "run", fake_run)
    monkeypatch.setenv("PYTHONPATH", "/elsewhere")
    assert bench._in_subprocess("zheng_mcs", python="/other/python") == {"time": 1.0}
    assert seen["cmd"] == ["/other/python", "-m", "mtaccuracy.apps.bench", "--task",
                           "zheng_mcs"]
    lib = seen["env"]["PYTHONPATH"].split(":")
    assert Path(lib[0], "mtaccuracy", "apps", "bench.py").samefile(bench.__file__)
    assert lib[1:] == ["/elsewhere"]


def test_salib_and_ours_draw_one_design_and_agree_with_the_closed_form():
    model, sd, exact = bench_tasks.sobol_case("linear")   # linear: the closed form is exact
    n = 2**10
    stages = {}
    s1, st = bench_tasks.salib_sobol(model, sd, n, stages)
    o1, ot = bench_tasks.ours_sobol(model, sd, n)
    assert s1.shape == st.shape == exact.shape == (41, 6)
    assert set(stages) == {"sample", "model", "analyze"}
    # the same Sobol' points and the same estimators: the same numbers, to rounding
    assert np.abs(s1 - o1).max() < 1e-12 and np.abs(st - ot).max() < 1e-12
    # within the sampling error at N = 2^10: over 20 seeds the largest errors were 0.028 (S1)
    # and 0.012 (ST), their mean 0.016 and 0.004
    assert np.abs(s1 - exact).max() < 0.05 and np.abs(st - exact).max() < 0.03
    # and they do depend on the design: another N gives other numbers
    assert np.abs(bench_tasks.ours_sobol(model, sd, 2**9)[0] - o1).max() > 1e-6


def _small_case(case):
    """A linear model of three inputs and two outputs with its exact indices."""
    jac = np.array([[1.0, 2.0, 0.5], [0.0, 1.0, 3.0]])
    sd = np.array([1.0, 0.5, 2.0])
    share = (jac * sd) ** 2
    return (lambda e: e @ jac.T), sd, (share / share.sum(1, keepdims=True)).T


def test_a_sobol_row_reports_errors_indices_and_salib_stages(monkeypatch):
    monkeypatch.setattr(bench_tasks, "sobol_case", _small_case)
    r = bench_tasks.sobol_task(bench_tasks.salib_sobol, "linear", 2**8)
    assert r["time"] > 0 and "one run" in r["note"] and "sample" in r["note"]
    s1, st = (np.asarray(a) for a in r["indices"])
    assert s1.shape == (3, 2) and r["err_st"] == pytest.approx(
        np.abs(st - _small_case("linear")[2]).max())
    ours = bench_tasks.sobol_task(bench_tasks.ours_sobol, "linear", 2**8, 1)
    assert "min of 1" in ours["note"] and "sample" not in ours["note"]


def test_the_memory_task_estimates_the_linear_model():
    r = bench_tasks.TASKS["sobol_memory_n8192"]()    # a linear model: S1 = ST = the closed form
    assert r["err_s1"] < 0.01 and r["err_st"] < 0.01 and r["time"] > 0


def test_timed_keeps_the_fastest_run_after_a_warm_up():
    calls = []

    def fn():
        calls.append(1)
        return len(calls)
    t, out = bench_tasks.timed(fn, repeat=2, number=3)
    assert len(calls) == 9 and out in (6, 9) and t >= 0       # warm-up: calls 1-3, not kept
    calls.clear()
    assert bench_tasks.timed(fn, repeat=0)[1] == 1 and calls == [1]   # one run, no warm-up


def test_the_peer_note_gives_time_and_memory_ratios_and_index_agreement():
    ours = dict(time=2.0, task_mb=100.0, peak_mb=200.0, indices=[[[0.5]], [[0.5]]])
    peer = dict(time=50.0, task_mb=1300.0, peak_mb=1500.0, indices=[[[0.5]], [[0.5 + 3e-15]]])
    note = bench._peer_note(ours, peer, "SALib")
    assert "SALib 25.0x the time" in note and "13.0x the task MB" in note
    assert "7.5x the peak" in note and "agree to 3e-15" in note
    assert bench._peer_note(ours, bench._failed("not run"), "OpenTURNS") == ""
    quicker = bench._peer_note(ours, dict(time=0.05, task_mb=50.0, peak_mb=150.0), "OpenTURNS")
    assert "OpenTURNS 0.025x the time, 0.5x the task MB, 0.75x the peak" in quicker


def test_openturns_rows_are_skipped_with_a_message_when_it_is_absent(monkeypatch):
    real = builtins.__import__

    def no_openturns(name, *a, **k):
        if name == "openturns":
            raise ImportError("no openturns")
        return real(name, *a, **k)
    monkeypatch.setattr(builtins, "__import__", no_openturns)
    r = bench_tasks.pce_openturns("interaction_polynomial")
    assert "--with-openturns" in r["note"] and r["time"] != r["time"]  # NaN time


def test_the_openturns_environment_is_made_once_and_sees_the_project_packages(tmp_path):
    env = tmp_path / "bench-openturns"
    site = env / "lib" / f"python{sys.version_info[0]}.{sys.version_info[1]}" / "site-packages"
    ran = []

    def fake_run(cmd, **kw):          # makes the folders a venv would; installs nothing
        ran.append(cmd)
        if cmd[1:3] == ["-m", "venv"]:
            site.mkdir(parents=True)
            (env / "bin").mkdir()
            (env / "bin" / "python").touch()
        return SimpleNamespace(returncode=0 if installed else 1)
    installed = False
    python = bench.ensure_openturns_env(env, run=fake_run)
    assert python == env / "bin" / "python"
    # the venv by the project's Python (same version, without the base interpreter's
    # packages); then pip as the new environment's Python: openturns lands there alone
    assert ran == [[sys.executable, "-m", "venv", str(env)],
                   [str(python), "-m", "pip", "install", "--quiet",
                    "--disable-pip-version-check", bench.OPENTURNS_REQUIREMENT]]
    assert bench.OPENTURNS_REQUIREMENT.startswith("openturns==")
    pth = (site / bench.PROJECT_PTH).read_text().splitlines()
    assert f"import site; site.addsitedir({sysconfig.get_paths()['purelib']!r})" in pth
    # a second call with openturns importable there runs nothing but that check
    ran.clear()
    installed = True
    assert bench.ensure_openturns_env(env, run=fake_run) == python
    assert ran == [[str(python), "-c", "import openturns"]]
    assert bench.OPENTURNS_ENV.parts[-2:] == ("build", "bench-openturns")


def test_without_the_flag_openturns_rows_say_how_to_get_them(monkeypatch, capsys):
    ran = []

    def fake(name, timeout=None, python=None):
        ran.append((name, python))
        return dict(time=1.0, peak_mb=1.0, task_mb=1.0)
    monkeypatch.setattr(bench, "_in_subprocess", fake)
    monkeypatch.setattr(bench, "ensure_openturns_env",
                        lambda: pytest.fail("no environment without --with-openturns"))
    bench.main(["--only", "pce_ishigami"])
    assert [n for n, _ in ran] == ["pce_ishigami_omp", "pce_ishigami_lars"]
    assert "--with-openturns" in capsys.readouterr().out
    ran.clear()
    monkeypatch.setattr(bench, "ensure_openturns_env", lambda: Path("/ot/bin/python"))
    bench.main(["--only", "pce_ishigami", "--with-openturns"])
    assert sorted(ran) == [("pce_ishigami_lars", None), ("pce_ishigami_omp", None),
                           ("pce_ishigami_openturns", "/ot/bin/python")]
    assert "OpenTURNS 1.0x the time" in capsys.readouterr().out


def test_the_rows_and_their_peers_are_consistent():
    tasks = [r.task for r in bench_tasks.ROWS]
    assert len(set(tasks)) == len(tasks) == len(bench.TASKS)
    for r in bench_tasks.ROWS:
        if r.peer:    # the peer is a row of its own, after ours, and a peer's rows have none
            assert tasks.index(r.peer) > tasks.index(r.task)
            assert bench_tasks.ROWS[tasks.index(r.peer)].peer is None
            # --quick never runs a peer's row without ours beside it
            assert bench_tasks.ROWS[tasks.index(r.peer)].full or not r.full
    assert all(r.peer.endswith("openturns") for r in bench_tasks.ROWS
               if r.peer and r.task.startswith("pce"))
    with pytest.raises(SystemExit):
        bench.main(["--task", "no_such_task"])


def test_memory_rows_go_up_in_n_and_quick_leaves_out_the_largest(monkeypatch):
    ran = []

    def fake(name, timeout=None, python=None):
        ran.append(name)
        return dict(time=1.0, peak_mb=1.0, task_mb=1.0)
    monkeypatch.setattr(bench, "_in_subprocess", fake)
    bench.main(["--quick", "--only", "sobol_memory"])
    assert ran == ["sobol_memory_n8192", "sobol_memory_salib_n8192", "sobol_memory_n131072",
                   "sobol_memory_n1048576"]
    ran.clear()
    bench.main(["--only", "sobol_memory"])
    assert ran[-1] == "sobol_memory_n8388608" and len(ran) == 6
    ran.clear()
    bench.main(["--quick", "--only", "salib"])      # a peer's row brings ours along
    assert ran == ["zheng_sobol_n16384", "zheng_salib_n16384", "sobol_memory_n8192",
                   "sobol_memory_salib_n8192"]
    ran.clear()
    bench.main(["--quick", "--only", "ishigami_openturns"])   # both of ours, OpenTURNS not run
    assert ran == ["pce_ishigami_omp", "pce_ishigami_lars"]


def test_make_runs_in_a_fresh_clone_that_leaves_the_shared_venv_alone():
    ran = []

    def fake_run(cmd, **kw):
        ran.append((cmd, kw))
        if isinstance(cmd, str):            # the checksum naming the venv's stamp
            return SimpleNamespace(stdout="4242 6717\n")
        return SimpleNamespace(stdout="12.5 204800 0\n")
    assert bench.make_in_clone("reproduce", run=fake_run) == (12.5, 200.0, 0)
    (clone_cmd, _), (stamp_cmd, stamp_kw), (make_cmd, _) = ran
    clone = clone_cmd[-1]
    assert clone_cmd == ["git", "clone", "-q", str(bench.ROOT), clone]
    assert not Path(clone).exists()         # removed after the run
    # make must never remake the stamp of the shared .venv (the clone's files are newer):
    # the Makefile names it by the same checksum, taken in the clone
    assert stamp_kw["cwd"] == clone and "cat environment.txt pyproject.toml | cksum" in stamp_cmd
    makefile = (bench.ROOT / "Makefile").read_text()
    assert f"STAMP := $(VENV)/.installed-$(shell {stamp_cmd} | cut -d' ' -f1)" in makefile
    assert make_cmd[-6:] == ["make", "-C", clone, "-o", ".venv/.installed-4242", "reproduce"]


def test_each_timed_make_run_has_a_clone_of_its_own(monkeypatch):
    runs = iter([(80.0, 900.0, 0), (70.0, 950.0, 0), (140.0, 500.0, 0), (130.0, 400.0, 2)])
    targets = []
    monkeypatch.setattr(bench, "make_in_clone", lambda t: targets.append(t) or next(runs))
    (r1, *_, reproduce), (r2, *_, test) = bench._command_rows()
    # a second make reproduce in one clone would have nothing to do: a clone per run
    assert targets == ["reproduce", "reproduce", "test", "test"]
    assert (reproduce["time"], reproduce["peak_mb"], reproduce["note"]) == (70.0, 950.0, "")
    assert (test["time"], test["note"]) == (130.0, "A RUN FAILED")
