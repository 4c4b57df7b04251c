"""Provenance stamps, and the checks the book makes before it shows an output (the book
itself: test_book.py)."""

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

from mtaccuracy.compendium import book, paths, plotting, provenance, reproduction, runner  # noqa: E402


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


def _problems(figs, stems, caps=None):
    return {stem: [(p.name, why.split(" (")[0]) for p, why in found]
            for stem, found in book.check(figs, stems, caps or {}).items()}


def _captions(folder):
    return {folder.name: [{"figure": p.stem, "label": "Fig. 2", "caption": "c"}
                          for p in sorted(folder.glob("*.png"))]}


def test_a_broken_figure_is_named_and_not_shown(run_record, tmp_path):
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
    caps = _captions(folder)
    png = folder / "fig03_truncated.png"
    png.write_bytes(png.read_bytes()[: len(png.read_bytes()) // 4])  # an interrupted write
    (folder / "fig04_replaced.svg").write_text((folder / "fig04_replaced.svg").read_text()
                                                .replace("demo", "other"))
    found = book.check(figs, [folder.name], caps)
    assert [(p.name, why.split(" (")[0]) for p, why in found[folder.name]] == [
        ("fig03_truncated.png", "cannot be read"),
        ("fig04_replaced.svg", "does not match the hash in provenance.json")]
    text = book.chapter(folder.name, figs, caps, reproduction.papers_index(), found)
    assert "../figures/02_rong_sobol_21_errors/fig02_good.png" in text
    assert "fig03_truncated.png\n" not in text and "{figure} ../figures/" \
        "02_rong_sobol_21_errors/fig03_truncated.png" not in text
    assert "fig04_replaced.svg\">SVG" not in text
    assert text.count('class="broken"') == 2


def test_every_committed_output_is_sound_and_captioned():
    stems = [p.stem for p in runner.all_notebooks()]
    assert book.check(paths.FIGURES, stems, book.captions()) == {}


ZHENG, RONG, GUO = ("01_zheng2024_pce_sobol_41_errors", "02_rong_sobol_21_errors",
                    "03_guo2016_spearman_21_errors")


def _committed_copy(tmp_path):
    figs = tmp_path / "figures"
    shutil.copytree(paths.FIGURES, figs, ignore=shutil.ignore_patterns("html", "index.html", ".*"))
    return figs


def test_deleted_and_changed_outputs_are_named(tmp_path):
    """A figure or table that provenance.json lists but that is gone, or whose bytes changed,
    is named (and neither shown nor linked); a measured table may change but must exist."""
    figs = _committed_copy(tmp_path)
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
    caps = book.captions()
    assert _problems(figs, [ZHENG, RONG, GUO], caps) == {
        ZHENG: [("fig07_convergence.png", "is missing"), ("table3_timing.csv", "is missing")],
        RONG: [("table3_key_errors.csv", "is missing")],
        GUO: [("pose_search.csv", "does not match the hash in provenance.json")]}
    found = book.check(figs, [ZHENG, GUO], caps)
    text = book.chapter(ZHENG, figs, caps, reproduction.papers_index(), found)
    assert "Not shown:</strong> <code>01_zheng2024_pce_sobol_41_errors/fig07_convergence.png" \
        in text
    assert f"../figures/{ZHENG}/fig07_convergence.png" not in text
    assert f"../figures/{ZHENG}/fig05_position_total_sobol.png" in text  # the rest as before
    assert f"(../figures/{ZHENG}/reproduction_measured.csv)" in text
    guo = book.chapter(GUO, figs, caps, reproduction.papers_index(), found)
    assert f"(../figures/{GUO}/pose_search.csv)" not in guo  # not linked


def test_a_figure_without_a_caption_or_a_caption_without_a_figure_is_named(tmp_path):
    figs = _committed_copy(tmp_path)
    caps = book.captions()
    caps[RONG] = caps[RONG][1:] + [{"figure": "fig99_gone", "label": "Fig. 99", "caption": "c"}]
    missing = book.captions()[RONG][0]["figure"]
    assert _problems(figs, [RONG], caps) == {RONG: [
        (f"{missing}.png", "has no caption in book/figures.yml"),
        ("fig99_gone.png", "is captioned in book/figures.yml but is not one of the folder's "
                           "outputs")]}


def test_outputs_are_checked_against_the_sidecar(run_record):
    """folder_problems: a measured table is only required to exist; a hashed one must keep
    its bytes; a file the sidecar does not list is the user's (an input, notes): not judged,
    named by not_outputs."""
    folder = run_record / "out"
    reproduction.save_table(pd.DataFrame({"a": [1.5]}), folder / "t.csv")
    reproduction.save_table(pd.DataFrame({"s": [0.25]}), folder / "timing.csv", measured=True)
    assert provenance.folder_problems(folder) == [] and provenance.not_outputs(folder) == []
    (folder / "timing.csv").write_text("s\n0.5\n")
    (folder / "my_ranges.csv").write_text("a\n1\n")
    assert provenance.folder_problems(folder) == []
    assert provenance.not_outputs(folder) == ["my_ranges.csv"]
    (folder / "timing.csv").unlink()
    (folder / "t.csv").write_text("a\n1.6\n")
    assert [(p.name, why.split(" (")[0]) for p, why in provenance.folder_problems(folder)] == [
        ("t.csv", "does not match the hash in provenance.json"),
        ("timing.csv", "is missing")]


def test_a_users_file_in_an_output_folder_is_neither_judged_nor_shown(tmp_path):
    """``make reproduce NB=06 PARAMS="ranges_file=figures/06_your_machine/my_ranges.csv"``
    leaves the range file alone; the book neither fails on it nor shows it."""
    figs = _committed_copy(tmp_path)
    folder = figs / "06_your_machine"
    shutil.copy(paths.DATA / "machines" / "swivel_head_ranges.csv", folder / "my_ranges.csv")
    fig, ax = plt.subplots()
    ax.plot([0, 1])
    fig.savefig(folder / "my_sketch.png")  # the user's own figure, not through plotting.save
    plt.close(fig)
    assert _problems(figs, ["06_your_machine"], book.captions()) == {}
    text = book.chapter("06_your_machine", figs, book.captions(), {}, {})
    assert "my_sketch.png" not in text


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


def test_committed_outputs_were_made_by_this_library_and_these_notebooks():
    """Every figure carries the library's hash and the notebook's: a change to either that was
    committed without re-running the notebooks (make reproduce) leaves figures that say they were
    made by other code."""
    for stem in [p.stem for p in runner.all_notebooks()]:
        run = provenance.read(paths.FIGURES / stem)["run"]
        assert run["library_sha256"] == provenance.library_hash(), \
            f"figures/{stem} was made by another version of lib/: run make reproduce"
        assert run["notebook_sha256"] == provenance.notebook_source_hash(
            paths.NOTEBOOKS / f"{stem}.ipynb"), f"notebooks/{stem}.ipynb changed since its run"
