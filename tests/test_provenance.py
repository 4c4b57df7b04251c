"""Provenance: what a run records, what its outputs carry, and the checks made before an output
is shown (the book's own use of them: test_book.py)."""

import io
import json
import re
import xml.etree.ElementTree as ET

import matplotlib
import numpy as np
import pandas as pd
import pytest

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from mtaccuracy.compendium import notebook, plotting, provenance, reproduction, workflow  # noqa: E402
from mtaccuracy.compendium.notebook import FIGURES, NOTEBOOKS, ROOT  # noqa: E402
from mtaccuracy.papers import rong, xu2022  # noqa: E402
from mtaccuracy.papers.figure import Caption  # noqa: E402
from mtaccuracy.papers.parameters import ParameterError  # noqa: E402

RONG = "02_rong_sobol_21_errors"
STEMS = [d.stem for d in workflow.DECLARATIONS]


@pytest.fixture
def run(tmp_path):
    """A run of notebook 02's declaration with its defaults, writing into ``tmp_path/out``."""
    ns = {**rong.Parameters.defaults(), "output_dir": str(tmp_path / "out")}
    r = notebook.start(rong.Parameters, ns)
    r.published("rong_facts", ["quantity", "value"])
    return r


def test_the_record_holds_content_hashes_only(run):
    rec = run.record
    assert set(rec) == {"notebook", "notebook_sha256", "library_sha256", "library_modules",
                        "parameters", "inputs", "packages"}  # no commit, no time
    assert rec["notebook"] == RONG
    assert "output_dir" not in rec["parameters"] and rec["parameters"]["n_base"] == 8192
    assert rec["inputs"]["data/papers/rong_facts.csv"] == provenance.sha256(
        ROOT / "data/papers/rong_facts.csv")
    assert "data/rong/error_ranges.csv" in rec["inputs"]  # a declared input file
    assert "mtaccuracy/papers/rong.py" in rec["library_modules"]
    assert not re.search(r"\d{4}-\d{2}-\d{2}", json.dumps(rec))
    again = provenance.record(RONG, NOTEBOOKS / f"{RONG}.ipynb", rec["parameters"])
    assert {k: v for k, v in again.items() if k != "inputs"} == \
        {k: v for k, v in rec.items() if k != "inputs"}


def test_an_input_outside_the_repository_is_recorded_by_its_absolute_path(tmp_path):
    own = tmp_path / "ranges.csv"
    own.write_bytes((ROOT / "data/rong/error_ranges.csv").read_bytes())
    ns = {**rong.Parameters.defaults(), "output_dir": str(tmp_path / "out"),
          "ranges_file": str(own)}
    rec = notebook.start(rong.Parameters, ns).record
    assert rec["inputs"][own.as_posix()] == provenance.sha256(own)
    folder = notebook.start(xu2022.Parameters, {**xu2022.Parameters.defaults(),
                                                "output_dir": str(tmp_path / "x")}).record
    assert "data/thermal/errors.csv" in folder["inputs"]          # a folder, file by file,
    assert "data/thermal/provenance.json" not in folder["inputs"]  # but not its own record


def test_figures_and_tables_carry_the_record_and_the_folder_lists_them(run):
    fig, ax = plt.subplots()
    ax.plot([0, 1])
    run.figure(fig, Caption("fig01_demo", "Fig. 1", "a demo of {n} points").format(n=2),
               title="demo")
    plt.close(fig)
    run.table(pd.DataFrame({"a": [1.5]}), "t.csv")
    assert provenance.from_png(run.out / "fig01_demo.png") == run.record
    assert RONG in (run.out / "fig01_demo.svg").read_text()
    side = provenance.read(run.out)
    assert side["run"] == run.record
    assert side["files"]["t.csv"]["sha256"] == provenance.sha256(run.out / "t.csv")
    assert side["files"]["fig01_demo.png"]["caption"] == "a demo of 2 points"
    assert set(side["files"]) == {"fig01_demo.png", "fig01_demo.svg", "t.csv"}


def test_a_scorecard_keeps_its_measured_rows_apart(run):
    card = reproduction.Card()
    card.number("Table 3", "time (measured)", "1.0", 1.2, "s")
    card.number("Fig. 2", "an index", "0.50", 0.5)
    df = run.scorecard(card)
    assert len(df) == 2
    assert provenance.read(run.out)["files"]["reproduction_measured.csv"] == {"measured": True}
    assert len(pd.read_csv(run.out / "reproduction.csv")) == 1


def test_the_source_hash_ignores_outputs_and_counts_every_source_change(tmp_path):
    nb = json.loads((NOTEBOOKS / f"{RONG}.ipynb").read_text())
    before = provenance.notebook_source_hash(NOTEBOOKS / f"{RONG}.ipynb")
    for c in nb["cells"]:
        c.pop("outputs", None)
        c["execution_count"] = None
    copy = tmp_path / f"{RONG}.ipynb"
    copy.write_text(json.dumps(nb))
    assert provenance.notebook_source_hash(copy) == before
    nb["cells"][0]["source"] = "changed"
    copy.write_text(json.dumps(nb))
    assert provenance.notebook_source_hash(copy) != before


def test_start_refuses_before_any_work(tmp_path, monkeypatch):
    ns = {**rong.Parameters.defaults(), "output_dir": str(tmp_path / "out")}
    with pytest.raises(ParameterError, match="parameter"):
        notebook.start(rong.Parameters, {k: v for k, v in ns.items() if k != "seed"})
    with pytest.raises(ParameterError, match="'n_base' must be at least 64"):
        notebook.start(rong.Parameters, {**ns, "n_base": 2})
    monkeypatch.setattr(notebook, "available_memory", lambda: (1e8, "available memory"))
    with pytest.raises(ParameterError, match=r"0\.1 GB left \(available memory\)"):
        notebook.start(rong.Parameters, ns)
    assert not (tmp_path / "out").exists()


def test_outputs_are_checked_against_the_record(run):
    run.table(pd.DataFrame({"a": [1.5]}), "t.csv")
    run.table(pd.DataFrame({"s": [0.25]}), "timing.csv", measured=True)
    folder = run.out
    assert provenance.folder_problems(folder) == [] and provenance.not_outputs(folder) == []
    (folder / "timing.csv").write_text("s\n0.5\n")          # measured: it may change
    (folder / "my_ranges.csv").write_text("a\n1\n")         # the user's: not judged
    assert provenance.folder_problems(folder) == []
    assert provenance.not_outputs(folder) == ["my_ranges.csv"]
    (folder / "timing.csv").unlink()
    (folder / "t.csv").write_text("a\n1.6\n")
    assert [(p.name, why.split(" (")[0]) for p, why in provenance.folder_problems(folder)] == [
        ("t.csv", "does not match the hash in provenance.json"), ("timing.csv", "is missing")]


def test_a_truncated_figure_cannot_be_read(run):
    fig, ax = plt.subplots()
    ax.plot([0, 1])
    run.figure(fig, Caption("fig02", "Fig. 2", "c"))
    plt.close(fig)
    png = run.out / "fig02.png"
    png.write_bytes(png.read_bytes()[: png.stat().st_size // 4])
    [(path, why)] = provenance.folder_problems(run.out)
    assert path.name == "fig02.png" and why.startswith("cannot be read")


def _convergence_like(noise: float):
    """Laid out as notebook 01's Fig. 7 (log axes, tight_layout): where its axes sit depends
    on its tick labels, so on the data, down to their last digit."""
    n = np.array([100, 200, 500, 1000, 2000])
    r = 10.0 ** np.random.default_rng(5).uniform(-3.5, 2.8, (2, n.size)) * (1 + noise)
    fig, axes = plt.subplots(1, 2, figsize=(6, 2.5))
    for ax, rr in zip(axes, r, strict=True):
        ax.plot(n, rr, "o-")
        ax.set_xscale("log")
        ax.set_yscale("log")
    fig.tight_layout()
    return fig


def test_svg_bytes_do_not_change_with_rounding_noise_in_the_data(tmp_path):
    raw, svg, png = [], [], []
    for k, noise in enumerate((0.0, 1e-15)):
        fig = _convergence_like(noise)
        buf = io.BytesIO()
        with matplotlib.rc_context(plotting.STYLE):
            fig.savefig(buf, format="svg", metadata={"Date": None}, bbox_inches="tight")
        raw.append(buf.getvalue())
        plotting.save(fig, tmp_path / str(k) / "fig07_demo", stamp="{}")
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


# --- what is committed ----------------------------------------------------------------------------

@pytest.mark.parametrize("stem", STEMS)
def test_committed_outputs_were_made_by_this_code_and_this_notebook(stem):
    """Every folder's record names the library modules its notebook imports and their hash, and
    the notebook's source: a change to either committed without re-running the notebook
    (``make reproduce``) leaves outputs that say they were made by other code."""
    run = provenance.read(FIGURES / stem)["run"]
    files = provenance.library_modules(NOTEBOOKS / f"{stem}.ipynb")
    assert run["library_sha256"] == provenance.library_hash(files), \
        f"figures/{stem} was made by other library code: run make reproduce"
    assert run["notebook_sha256"] == provenance.notebook_source_hash(
        NOTEBOOKS / f"{stem}.ipynb"), f"notebooks/{stem}.ipynb changed since its run"


@pytest.mark.parametrize("stem", STEMS)
def test_every_committed_output_is_sound_and_every_figure_captioned(stem):
    folder = FIGURES / stem
    side = provenance.read(folder)
    assert provenance.folder_problems(folder, side) == []
    assert provenance.not_outputs(folder, side) == []
    pngs = [n for n in side["files"] if n.endswith(".png")]
    assert pngs and all(side["files"][n].get("caption") and side["files"][n].get("label")
                        for n in pngs)
    assert all(n.removesuffix(".png") + ".svg" in side["files"] for n in pngs)
