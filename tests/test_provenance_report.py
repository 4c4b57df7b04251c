"""Provenance stamps and the static report (the browser test is test_report_browser.py)."""

import io
import json
import re
import shutil
import xml.etree.ElementTree as ET

import matplotlib
import numpy as np
import pandas as pd
import pytest

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from mtaccuracy.compendium import paths, plotting, provenance, report, reproduction, runner  # noqa: E402


@pytest.fixture
def run_record(tmp_path):
    ns = {k: p.default for k, p in runner.read_parameters("02").items()}
    runner.check_parameters(ns, "02_rong_sobol_21_errors")
    reproduction.published("rong_facts")
    return tmp_path


def test_record_is_complete_and_deterministic(run_record):
    rec = provenance.record()
    assert rec == provenance.record()
    assert set(rec) == {"library_sha256", "notebook", "notebook_sha256", "parameters", "inputs",
                        "packages"}  # content hashes only: no git commit in figure bytes
    assert rec["notebook"] == "02_rong_sobol_21_errors"
    assert "output_dir" not in rec["parameters"] and rec["parameters"]["n_base"] == 8192
    assert "data/papers/rong_facts.csv" in rec["inputs"]
    assert "data/rong/error_ranges.csv" in rec["inputs"]  # a parameter naming a data file
    provenance.start("04_xu2022_thermal_mlr_svr", {"data_dir": "data/thermal"})
    assert "data/thermal/errors.csv" in provenance.record()["inputs"]  # ... or a folder, but
    assert "data/thermal/provenance.json" not in provenance.record()["inputs"]  # not its record
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


def test_the_record_does_not_change_with_the_commit_or_the_outputs(run_record, tmp_path):
    rec = provenance.record()
    assert provenance.git_commit  # still available for the runner's .runs.json
    nb = json.loads((paths.NOTEBOOKS / "02_rong_sobol_21_errors.ipynb").read_text())
    for c in nb["cells"]:  # outputs and execution counts are not part of the source hash
        c.pop("outputs", None)
        c["execution_count"] = None
    copy = tmp_path / "02_rong_sobol_21_errors.ipynb"
    copy.write_text(json.dumps(nb))
    assert provenance.notebook_source_hash(copy) == rec["notebook_sha256"]
    nb["cells"][0]["source"] = "changed"
    copy.write_text(json.dumps(nb))
    assert provenance.notebook_source_hash(copy) != rec["notebook_sha256"]


def _fig(folder, name):
    fig, ax = plt.subplots()
    ax.plot([0, 1])
    plotting.save(fig, folder, name, title="demo")
    plt.close(fig)


def test_report_marks_a_broken_figure_and_fails(run_record, tmp_path, capsys):
    figs = tmp_path / "figures"
    folder = figs / "02_rong_sobol_21_errors"
    folder.mkdir(parents=True)
    reproduction.write_card([dict(item="Fig. 2", quantity="q", published="1", reproduced="1",
                                  unit="", tolerance="0", verdict="reproduced", basis="independent",
                                  note="")],
                            folder / "reproduction.csv")
    _fig(folder, "fig02_good")
    _fig(folder, "fig03_truncated")
    _fig(folder, "fig04_replaced")
    png = folder / "fig03_truncated.png"
    png.write_bytes(png.read_bytes()[: len(png.read_bytes()) // 4])  # an interrupted write
    (folder / "fig04_replaced.svg").write_text((folder / "fig04_replaced.svg").read_text()
                                                .replace("demo", "other"))
    assert report.main(["--figures", str(figs)]) == 1
    err = capsys.readouterr().err
    assert "fig03_truncated.png cannot be read" in err
    assert "fig04_replaced.svg does not match the hash" in err
    assert "fig02_good" not in err
    text = (figs / "index.html").read_text()
    assert 'src="02_rong_sobol_21_errors/fig02_good.png"' in text
    assert 'src="02_rong_sobol_21_errors/fig03_truncated.png"' not in text
    assert text.count('class="broken"') == 2


def test_report_lists_every_row_and_figure(committed_report):
    figs = committed_report
    text = (figs / "index.html").read_text()
    for card in figs.glob("*/reproduction.csv"):
        stem = card.parent.name
        n = len(pd.read_csv(card))
        assert text.count(f'class="score-row" data-notebook="{stem}"') == n, stem
        for png in card.parent.glob("*.png"):
            assert f'src="{stem}/{png.name}"' in text
        assert (figs / "html" / f"{stem}.html").exists()
    assert "http://" not in text and "https://" not in text and "<script" not in text
    assert not re.search(r'src="https?://', (figs / "html" / f"{stem}.html").read_text())
    broken = []
    assert report.build(figs, export=False, broken=broken).read_text() == text  # deterministic
    assert broken == [] and 'class="broken"' not in text  # every committed output as recorded


ZHENG, RONG, GUO = ("01_zheng2024_pce_sobol_41_errors", "02_rong_sobol_21_errors",
                    "03_guo2016_spearman_21_errors")


def test_report_marks_deleted_and_changed_outputs_and_fails(committed_report, tmp_path, capsys):
    """A figure or table that provenance.json lists but that is gone, or whose bytes changed,
    is marked (not shown, not linked) and fails the command; a measured table may change but
    must exist."""
    figs = tmp_path / "figures"
    shutil.copytree(committed_report, figs)  # with its notebook exports: none is redone
    side = provenance.read(figs / ZHENG)["files"]
    assert side["table3_timing.csv"] == {"measured": True}
    assert side["reproduction_measured.csv"] == {"measured": True}
    (figs / ZHENG / "fig07_convergence.png").unlink()
    (figs / RONG / "table3_key_errors.csv").unlink()
    (figs / ZHENG / "table3_timing.csv").unlink()                   # measured, but listed
    with open(figs / GUO / "pose_search.csv", "a") as fh:           # changed after its run
        fh.write("edited,by,hand\n")
    with open(figs / ZHENG / "reproduction_measured.csv", "a") as fh:  # measured: may change
        fh.write("\n")
    assert report.main(["--figures", str(figs)]) == 1
    err = capsys.readouterr().err
    assert f"figure {figs / ZHENG / 'fig07_convergence.png'} is missing" in err
    assert f"table {figs / RONG / 'table3_key_errors.csv'} is missing" in err
    assert f"table {figs / ZHENG / 'table3_timing.csv'} is missing" in err
    assert f"table {figs / GUO / 'pose_search.csv'} does not match the hash" in err
    assert "reproduction_measured.csv" not in err and err.count("error:") == 4
    text = (figs / "index.html").read_text()
    assert text.count('class="broken"') == 4
    assert (f"<strong>Missing figure</strong> <code>{ZHENG}/fig07_convergence.png</code>"
            in text)
    assert f'src="{ZHENG}/fig07_convergence.png"' not in text
    assert f'href="{ZHENG}/fig07_convergence.svg"' not in text  # its SVG only with its PNG
    assert f"<strong>Missing table</strong> <code>{RONG}/table3_key_errors.csv</code>" in text
    assert f"<strong>Broken table</strong> <code>{GUO}/pose_search.csv</code>" in text
    assert f'href="{GUO}/pose_search.csv"' not in text  # not linked
    assert f'href="{ZHENG}/reproduction_measured.csv"' in text
    assert f'src="{ZHENG}/fig05_position_total_sobol.png"' in text  # the rest as before


def test_a_paper_folder_that_lost_its_scorecard_is_still_reported(run_record, tmp_path,
                                                                   capsys):
    figs = tmp_path / "figures"
    folder = figs / RONG
    card = reproduction.Card()
    card.number("Fig. 2", "q", "1.0", 1.0)
    card.write(folder / "reproduction.csv")
    _fig(folder, "fig02_good")
    (folder / "reproduction.csv").unlink()
    assert report.main(["--figures", str(figs)]) == 1
    assert f"table {folder / 'reproduction.csv'} is missing" in capsys.readouterr().err
    text = (figs / "index.html").read_text()
    assert f'<section class="paper" id="{RONG}">' in text
    assert f'src="{RONG}/fig02_good.png"' in text


def test_outputs_are_checked_against_the_sidecar(run_record):
    """folder_problems: a measured table is only required to exist; a hashed one must keep
    its bytes; a file the sidecar does not list is the user's (an input, notes): not judged,
    named by not_outputs."""
    folder = run_record / "out"
    reproduction.save_table(pd.DataFrame({"a": [1.5]}), folder / "t.csv")
    reproduction.save_table(pd.DataFrame({"s": [0.25]}), folder / "timing.csv", measured=True)
    assert report.folder_problems(folder) == [] and report.not_outputs(folder) == []
    (folder / "timing.csv").write_text("s\n0.5\n")
    (folder / "my_ranges.csv").write_text("a\n1\n")
    assert report.folder_problems(folder) == []
    assert report.not_outputs(folder) == ["my_ranges.csv"]
    (folder / "timing.csv").unlink()
    (folder / "t.csv").write_text("a\n1.6\n")
    assert [(p.name, why.split(" (")[0]) for p, why in report.folder_problems(folder)] == [
        ("t.csv", "does not match the hash in provenance.json"),
        ("timing.csv", "is missing")]


def test_a_users_file_in_an_output_folder_neither_fails_nor_shows_in_the_report(
        committed_report, tmp_path, capsys):
    """``make reproduce NB=06 PARAMS="ranges_file=figures/06_your_machine/my_ranges.csv"``
    left the range file alone, then failed in the report, which called it broken."""
    figs = tmp_path / "figures"
    shutil.copytree(committed_report, figs)
    folder = figs / "06_your_machine"
    shutil.copy(paths.DATA / "machines" / "swivel_head_ranges.csv", folder / "my_ranges.csv")
    fig, ax = plt.subplots()
    ax.plot([0, 1])
    fig.savefig(folder / "my_sketch.png")  # the user's own figure, not through plotting.save
    plt.close(fig)
    assert report.main(["--figures", str(figs)]) == 0, capsys.readouterr().err
    text = (figs / "index.html").read_text()
    assert "my_ranges.csv" in text and 'href="06_your_machine/my_ranges.csv"' not in text
    assert 'src="06_your_machine/my_sketch.png"' not in text


def _convergence_like(noise: float):
    """A figure laid out as Fig. 7 of notebook 01 (log axes, ``tight_layout``): where its
    axes sit depends on its tick labels, so on the data, down to their last digit."""
    n = np.array([100, 200, 500, 1000, 2000])
    r = 10.0 ** np.random.default_rng(5).uniform(-3.5, 2.8, (2, n.size)) * (1 + noise)
    fig, axes = plt.subplots(1, 2, figsize=(6, 2.5))
    for ax, rr in zip(axes, r, strict=True):
        ax.plot(n, rr, "o-")
        ax.set_xscale("log")
        ax.set_yscale("log")
    fig.tight_layout()
    return fig


def test_svg_bytes_do_not_change_with_rounding_noise_in_the_data(run_record, tmp_path):
    """Data that differ in the 15th digit (another BLAS kernel, an optimiser's last step)
    move the clip rectangles by 1e-13 pt: nothing printed changes, and neither may the file.
    Matplotlib's own ids (hashes of the unrounded rectangles) did change: the fig07 churn."""
    raw, svg, png = [], [], []
    for k, noise in enumerate((0.0, 1e-15)):
        fig = _convergence_like(noise)
        buf = io.BytesIO()
        with matplotlib.rc_context(plotting.STYLE):
            fig.savefig(buf, format="svg", metadata={"Date": None}, bbox_inches="tight")
        raw.append(buf.getvalue())
        plotting.save(fig, tmp_path / str(k), "fig07_demo")
        plt.close(fig)
        svg.append((tmp_path / str(k) / "fig07_demo.svg").read_bytes())
        png.append((tmp_path / str(k) / "fig07_demo.png").read_bytes())
    assert raw[0] != raw[1]  # the noise reached matplotlib's ids: the test can fail
    assert svg[0] == svg[1] and png[0] == png[1]
    text = svg[0].decode()
    defined = {e.get("id") for e in ET.fromstring(text).iter() if e.get("id")}
    used = set(re.findall(r"url\(#([^)]+)\)", text))
    assert used and used <= defined and not any(re.fullmatch(r"p[0-9a-f]{10}", u) for u in used)


def test_clip_paths_are_named_after_what_they_print():
    svg = ('<svg><g clip-path="url(#pa)"/><g clip-path="url(#pb)"/><g clip-path="url(#pc)"/>\n'
           ' <defs>\n'
           '  <clipPath id="pb">\n   <rect x="1.5" y="0"/>\n  </clipPath>\n'
           '  <clipPath id="pa">\n   <rect x="0" y="0"/>\n  </clipPath>\n'
           '  <clipPath id="pc">\n   <rect x="1.5" y="0"/>\n  </clipPath>\n'
           ' </defs>\n</svg>\n')
    out = plotting.stable_svg_ids(svg)
    assert out == ('<svg><g clip-path="url(#clip2)"/><g clip-path="url(#clip1)"/>'
                   '<g clip-path="url(#clip1)"/>\n <defs>\n'
                   '  <clipPath id="clip1">\n   <rect x="1.5" y="0"/>\n  </clipPath>\n'
                   '  <clipPath id="clip2">\n   <rect x="0" y="0"/>\n  </clipPath>\n'
                   ' </defs>\n</svg>\n')  # pb and pc print the same: one clip path
    assert plotting.stable_svg_ids(out) == out
    assert plotting.stable_svg_ids("<svg/>") == "<svg/>"
    with pytest.raises(ValueError, match="clip1"):
        plotting.stable_svg_ids(svg.replace("<svg>", '<svg><g id="clip1"/>'))


@pytest.mark.parametrize("name, label", [("fig05_position_total_sobol", "Fig. 5"),
                                         ("fig08_09_algorithms_compared", "Figs. 8-9"),
                                         ("fig3_spearman_all", "Fig. 3"),
                                         ("table2_key_errors", "Table 2"),
                                         ("eq06_matrix_eigenvalues", "eq06_matrix_eigenvalues")])
def test_figure_labels(name, label):
    assert report._figure_label(name) == label


@pytest.mark.parametrize("label, title, shown", [
    ("Fig. 5", "Fig. 5: total Sobol indices", "total Sobol indices"),
    ("Figs. 8-9", "Figs. 8-9 - GA against DE", "GA against DE"),
    ("Fig. 3", "Guo 2016 Fig. 3 regenerated", "Guo 2016 Fig. 3 regenerated"),
])
def test_a_caption_does_not_repeat_its_label(label, title, shown):
    assert report._caption_title(label, title) == shown


@pytest.mark.parametrize("item, refs", [
    ("Section 1.3, Figs. 6-7", {("fig", 6), ("fig", 7)}),
    ("Table 2 PCE", {("table", 2)}),
    ("Abstract / Fig. 7", {("fig", 7)}),
    ("Figs. 8 and 9", {("fig", 8), ("fig", 9)}),
    ("Eq. 13", set()),
])
def test_scorecard_items_name_their_figures_and_tables(item, refs):
    assert report._refs(item) == refs


def _luminance(hex_colour):
    c = [int(hex_colour[i:i + 2], 16) / 255 for i in (1, 3, 5)]
    c = [x / 12.92 if x <= 0.03928 else ((x + 0.055) / 1.055) ** 2.4 for x in c]
    return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]


def test_verdict_badges_are_readable():
    """White badge text on each colour: WCAG AA contrast (4.5:1) at least."""
    for verdict, colour in report.COLOURS.items():
        assert (1.05 / (_luminance(colour) + 0.05)) >= 4.5, verdict


def test_report_shows_verdict_by_basis_and_collapses_long_scorecards(tmp_path):
    figs = tmp_path / "figures"
    card = reproduction.Card()
    pose = card.fitted("pose", to=["Table 2"], how="least squares")
    for i in range(report.COLLAPSE_ROWS + 1):
        card.number("Table 2", f"q{i}", "1.0", 1.0, uses=[pose] if i % 2 else ())
    card.write(figs / "03_guo2016_spearman_21_errors" / "reproduction.csv")
    text = report.build(figs, notebooks=tmp_path, export=False).read_text()
    assert text.count('data-basis="fitted"') == report.COLLAPSE_ROWS // 2 + 1
    assert '<details class="scorecard">' in text  # collapsed: more rows than COLLAPSE_ROWS
    assert "8 reproduced independently" in text and 'class="crosstab"' in text
    assert "8 of the 16 published numbers and claims scored were reproduced independently; " \
        "16 agree in all (the others: 8 fitted)" in text


def test_a_figure_is_captioned_with_the_rows_it_declares(run_record, tmp_path):
    figs = tmp_path / "figures"
    folder = figs / "03_guo2016_spearman_21_errors"
    card = reproduction.Card()
    card.number("Table 2", "index in Px", "0.10", 0.1)
    card.number("Table 2", "index in Vx", "0.10", 0.3)
    card.number("Table 5", "k", "1.0", 1.0)
    card.write(folder / "reproduction.csv")
    for name, rows in (("fig05_position", ["Table 2: * in P?"]), ("fig06_other", None)):
        fig, ax = plt.subplots()
        ax.plot([0, 1])
        plotting.save(fig, folder, name, title="demo", scored_with=rows)
        plt.close(fig)
    text = report.build(figs, notebooks=tmp_path, export=False).read_text()
    assert "Scorecard rows for Fig. 5: 1 reproduced (independent)." in text
    assert "No scorecard row is tied to this figure" in text


def test_a_report_it_cannot_write_is_one_clear_line(run_record, tmp_path, capsys):
    """A read-only checkout crashed with a PermissionError traceback on figures/html; any
    error writing the report now ends in one line (here index.html is a folder)."""
    figs = tmp_path / "figures"
    (figs / "index.html").mkdir(parents=True)
    assert report.main(["--figures", str(figs)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "index.html" in err and "Traceback" not in err
