"""Provenance stamps and the static report (the browser test is test_report_browser.py)."""

import json
import re
import shutil

import matplotlib
import pandas as pd
import pytest

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from mtaccuracy import paths, plotting, provenance, report, reproduction, runner  # noqa: E402


@pytest.fixture
def run_record(tmp_path):
    ns = {k: p.default for k, p in runner.read_parameters("02").items()}
    runner.check_parameters(ns, "02_rong_sobol_21_errors")
    reproduction.published("rong_facts")
    return tmp_path


def test_record_is_complete_and_deterministic(run_record):
    rec = provenance.record()
    assert rec == provenance.record()
    assert set(rec) == {"commit", "library_sha256", "notebook", "parameters", "inputs", "packages"}
    assert rec["notebook"] == "02_rong_sobol_21_errors"
    assert "output_dir" not in rec["parameters"] and rec["parameters"]["n_base"] == 8192
    assert "data/papers/rong_facts.csv" in rec["inputs"]
    assert "data/rong/error_ranges.csv" in rec["inputs"]  # a parameter naming a data file
    assert rec["inputs"]["data/papers/rong_facts.csv"] == provenance.sha256(
        paths.PAPERS / "rong_facts.csv")
    assert rec["packages"]["numpy"].count(".") >= 1
    assert not re.search(r"\d{4}-\d{2}-\d{2}", json.dumps(rec))  # no dates or timestamps


def test_figures_and_tables_carry_it(run_record):
    folder = run_record
    fig, ax = plt.subplots()
    ax.plot([0, 1])
    plotting.save(fig, folder, "fig01_demo", title="demo")
    plt.close(fig)
    reproduction.save_table(pd.DataFrame({"a": [1.5]}), folder / "t.csv")
    assert provenance.from_png(folder / "fig01_demo.png") == provenance.record()
    assert "02_rong_sobol_21_errors" in (folder / "fig01_demo.svg").read_text()
    side = provenance.read(folder)
    assert side["run"] == provenance.record()
    assert side["files"]["t.csv"]["sha256"] == provenance.sha256(folder / "t.csv")
    assert set(side["files"]) == {"fig01_demo.png", "fig01_demo.svg", "t.csv"}


def test_report_lists_every_row_and_figure(tmp_path):
    figs = tmp_path / "figures"
    shutil.copytree(paths.FIGURES, figs, ignore=shutil.ignore_patterns("html", "index.html"))
    index = report.build(figs)
    text = index.read_text()
    for card in figs.glob("*/reproduction.csv"):
        stem = card.parent.name
        n = len(pd.read_csv(card))
        assert text.count(f'class="score-row" data-notebook="{stem}"') == n, stem
        for png in card.parent.glob("*.png"):
            assert f'src="{stem}/{png.name}"' in text
        assert (figs / "html" / f"{stem}.html").exists()
    assert "http://" not in text and "https://" not in text and "<script" not in text
    assert not re.search(r'src="https?://', (figs / "html" / f"{stem}.html").read_text())
    assert report.build(figs).read_text() == text  # deterministic


@pytest.mark.parametrize("name, label", [("fig05_position_total_sobol", "Fig. 5"),
                                         ("fig08_09_algorithms_compared", "Figs. 8-9"),
                                         ("fig3_spearman_all", "Fig. 3"),
                                         ("eq06_matrix_eigenvalues", "eq06_matrix_eigenvalues")])
def test_figure_labels(name, label):
    assert report._figure_label(name) == label
