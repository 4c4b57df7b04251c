"""``make bench``: a task runs in a process of its own and reports time, memory and index errors;
OpenTURNS is optional."""

import builtins
import json
import subprocess
import sys

import pytest

from mtaccuracy.compendium import bench


def test_a_task_runs_in_its_own_process_and_reports_json():
    out = subprocess.run([sys.executable, "-m", "mtaccuracy.compendium.bench", "--task",
                          "pce_interaction_polynomial_omp"], capture_output=True, text=True,
                         check=True)
    r = json.loads(out.stdout.strip().splitlines()[-1])
    assert r["time"] > 0 and r["peak_mb"] >= r["task_mb"] >= 0
    # the polynomial is exact in a degree-2 basis: the PCE gives its indices to rounding
    assert r["err_s1"] < 1e-10 and r["err_st"] < 1e-10 and "degree 2" in r["note"]


def test_openturns_rows_are_skipped_with_a_message_when_it_is_absent(monkeypatch):
    real = builtins.__import__

    def no_openturns(name, *a, **k):
        if name == "openturns":
            raise ImportError("no openturns")
        return real(name, *a, **k)
    monkeypatch.setattr(builtins, "__import__", no_openturns)
    r = bench._task_openturns("interaction_polynomial")
    assert "not installed" in r["note"] and r["time"] != r["time"]  # NaN time


def test_every_row_names_a_task_and_unknown_tasks_are_refused():
    assert all(task in bench.TASKS for _, task, *_ in bench.ROWS)
    with pytest.raises(SystemExit):
        bench.main(["--task", "no_such_task"])


def test_memory_rows_go_up_in_n_and_quick_leaves_out_the_largest(monkeypatch, capsys):
    ran = []

    def fake(name, timeout=None):
        ran.append(name)
        return dict(time=1.0, peak_mb=1.0, task_mb=1.0)
    monkeypatch.setattr(bench, "_in_subprocess", fake)
    bench.main(["--quick", "--only", "sobol_memory"])
    assert ran == ["sobol_memory_1e4", "sobol_memory_1e5", "sobol_memory_1e6"]
    ran.clear()
    bench.main(["--only", "sobol_memory"])
    assert ran[-1] == "sobol_memory_1e7" and len(ran) == 4


def test_the_memory_task_estimates_the_linear_model():
    r = bench._sobol_memory(10_000)      # a linear model: S1 = ST = the closed form
    assert r["err_s1"] < 0.05 and r["err_st"] < 0.05 and r["time"] > 0
