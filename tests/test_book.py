"""The book (``make book``, :mod:`mtaccuracy.apps.book`).

Fast tests build chapters from synthetic output folders made here (figures drawn with
matplotlib, ``provenance.json`` written by hand as a run writes it): the figures in the paper
module's order with the captions their run recorded, a missing caption and a caption without
its figure named, broken outputs and a user's file, the sweep's sentence, the parameter table.

The whole book is built and opened in Chromium by ``make check`` (tests/check/test_book_build.py).
"""

import re
from pathlib import Path

import matplotlib
import pandas as pd
import pytest

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from mtaccuracy.apps import book  # noqa: E402
from mtaccuracy.compendium import provenance, scorecard, workflow  # noqa: E402
from mtaccuracy.compendium.notebook import NOTEBOOKS, ROOT  # noqa: E402
from mtaccuracy.papers import guo2016, rong  # noqa: E402

TIMEOUT_MS = 30_000
STEMS = book.stems()
PAPERS = [s for s in STEMS if s in scorecard.papers_index()]
WIDTHS = {"desktop": 1280, "phone": 400}
GUO = guo2016.Parameters.stem
SHOTS = ROOT / ".test-output" / "book"


# ------------------------------------------------------------------ synthetic output folders

def _png(path: Path) -> None:
    fig, ax = plt.subplots(figsize=(2, 1.5))
    ax.plot([0, 1], [0, 1])
    fig.savefig(path)
    plt.close(fig)


def _write_run(folder: Path, figures: dict, *, parameters=None, extra=()) -> None:
    """A run's outputs as the workflow leaves them: ``figures`` maps a PNG's stem to its
    record entry (label, caption, order), each with an SVG; a scorecard; ``provenance.json``
    listing every file with its hash."""
    folder.mkdir(parents=True, exist_ok=True)
    files = {}
    for name, entry in figures.items():
        _png(folder / f"{name}.png")
        (folder / f"{name}.svg").write_text('<svg xmlns="http://www.w3.org/2000/svg"/>')
        files[f"{name}.png"] = {"sha256": provenance.sha256(folder / f"{name}.png"), **entry}
        files[f"{name}.svg"] = {"sha256": provenance.sha256(folder / f"{name}.svg")}
    card = pd.DataFrame([dict(item="Fig. 3", quantity="rho", published="0.5", reproduced="0.5",
                              unit="", tolerance="0", verdict="reproduced",
                              basis="independent", kind="number", agreement="printed",
                              note="")])
    card.to_csv(folder / "reproduction.csv", index=False, lineterminator="\n")
    for name in ("reproduction.csv", *extra):
        files[name] = {"sha256": provenance.sha256(folder / name)}
    source = provenance.notebook_source_hash(NOTEBOOKS / f"{folder.name}.ipynb")
    provenance.write_sidecar(folder, {"run": {"notebook": folder.name,
                                              "notebook_sha256": source,
                                              "parameters": parameters or {}},
                                      "files": files})


def _guo_figures(skip=(), uncaptioned=()) -> dict:
    """Notebook 03's figures as its run records them, in the reverse of the paper's order."""
    names = list(guo2016.FIGURES)
    return {n: {"label": guo2016.FIGURES[n].label, "order": len(names) - 1 - k,
                **({} if n in uncaptioned else {"caption": f"Run caption of {n}: n = 500."})}
            for k, n in enumerate(names) if n not in skip}


@pytest.fixture
def guo_folder(tmp_path):
    figures = tmp_path / "figures"
    _write_run(figures / GUO, _guo_figures())
    return figures


def _chapter(figures: Path, stem: str = GUO) -> tuple[str, dict]:
    broken = book.check(figures, [stem])
    return book.chapter(stem, figures, scorecard.papers_index(), broken), broken


def _why(broken: dict, figures: Path, stem: str = GUO) -> list[tuple[str, str]]:
    """The problems of a chapter: (path in its folder, why)."""
    return [(p.relative_to(figures / stem).as_posix(), why) for p, why in broken.get(stem, [])]


def test_figures_come_in_the_paper_modules_order_with_the_runs_captions(tmp_path):
    figures = tmp_path / "figures"
    extra = {"label": "Beyond the paper", "caption": "A figure FIGURES lacks.", "order": 0}
    _write_run(figures / GUO, {**_guo_figures(), "extra": extra})
    text, broken = _chapter(figures)
    assert broken == {}
    shown = re.findall(r"```\{figure\} \.\./figures/[^/]+/(\w+)\.png", text)
    assert shown == [*guo2016.FIGURES, "extra"]     # the module's order, then the run's
    assert "**Beyond the paper.** A figure FIGURES lacks." in text
    for name, cap in guo2016.FIGURES.items():
        assert f"**{cap.label}.** Run caption of {name}: n = 500." in text
        assert f'<a href="../figures/{GUO}/{name}.svg">SVG</a>' in text
        assert f":target: ../figures/{GUO}/{name}.png" in text     # a click enlarges it


def test_a_figure_without_a_caption_or_a_caption_without_its_figure_is_named(tmp_path):
    figures = tmp_path / "figures"
    gone, bare = list(guo2016.FIGURES)[:2]
    _write_run(figures / GUO, _guo_figures(skip=[gone], uncaptioned=[bare]))
    text, broken = _chapter(figures)
    assert _why(broken, figures) == [
        (f"{gone}.png", "is captioned in mtaccuracy.papers.guo2016.FIGURES but its run did not "
                        "write it"),
        (f"{bare}.png", "has no caption in provenance.json (its run recorded none)")]
    assert f"{{figure}} ../figures/{GUO}/{bare}.png" not in text
    assert text.count('class="broken"') == 2 and f"<code>{GUO}/{bare}.png</code>" in text
    assert re.findall(r"```\{figure\} \.\./figures/[^/]+/(\w+)\.png", text) == \
        list(guo2016.FIGURES)[2:]


def test_make_book_fails_naming_what_is_wrong(tmp_path, monkeypatch, capsys):
    figures = tmp_path / "figures"
    _write_run(figures / GUO, _guo_figures(uncaptioned=[list(guo2016.FIGURES)[0]]))
    site = tmp_path / "html"
    site.mkdir()

    def fake_build(out, figs, quiet):  # the checks, without Sphinx
        return site, book.check(Path(figs), [GUO]), []
    monkeypatch.setattr(book, "build", fake_build)
    assert book.main(["--figures", str(figures)]) == 1
    err = capsys.readouterr().err
    assert f"error: figure {figures / GUO / list(guo2016.FIGURES)[0]}.png has no caption" in err
    _write_run(figures / GUO, _guo_figures())
    assert book.main(["--figures", str(figures)]) == 0


def test_broken_outputs_are_named_and_a_users_file_is_neither_judged_nor_shown(guo_folder):
    folder = guo_folder / GUO
    first, second = list(guo2016.FIGURES)[:2]
    png = folder / f"{first}.png"
    png.write_bytes(png.read_bytes()[: len(png.read_bytes()) // 4])  # an interrupted write
    (folder / f"{second}.svg").write_text("<svg/>")                   # changed after its run
    _png(folder / "my_sketch.png")                                     # the user's own
    (folder / "my_ranges.csv").write_text("a\n1\n")
    text, broken = _chapter(guo_folder)
    assert sorted((n, why.split(" (")[0]) for n, why in _why(broken, guo_folder)) == sorted([
        (f"{first}.png", "cannot be read"),
        (f"{second}.svg", "does not match the hash in provenance.json")])
    assert f"{{figure}} ../figures/{GUO}/{first}.png" not in text
    assert f"{second}.svg\">SVG" not in text and f"{{figure}} ../figures/{GUO}/{second}.png" \
        in text
    assert "my_sketch" not in text and "my_ranges" not in text


def _sweep(folder: Path, verdicts: dict[int, str], settings=None) -> None:
    """``make sweep``'s tables (:func:`workflow.summarise`) over runs whose scorecard gives
    row ``Fig. 3: rho`` the verdict ``verdicts[seed]`` (and ``Table 1: n`` always
    reproduced)."""
    runs, folders = {}, {}
    for seed, verdict in verdicts.items():
        for s in settings or [None]:
            run = f"{f'setting{s}-' if s else ''}seed{seed}"
            runs[run] = {"seed": seed, **({"n_samples": s} if s else {})}
            folders[run] = folder.parent / "runs" / run
            folders[run].mkdir(parents=True)
            pd.DataFrame([dict(item="Fig. 3", quantity="rho", reproduced="0.5", verdict=verdict),
                          dict(item="Table 1", quantity="n", reproduced="3",
                               verdict="reproduced")]).to_csv(folders[run] / "reproduction.csv",
                                                              index=False)
    workflow.summarise(folder.name, runs, folders, folder / book.SWEEP)


def test_the_chapter_says_which_verdicts_change_with_the_seed(guo_folder):
    folder = guo_folder / GUO
    _sweep(folder, {7: "reproduced", 8: "differs", 9: "reproduced"})
    text, broken = _chapter(guo_folder)
    assert broken == {}                       # the sweep folder is neither the user's nor broken
    assert provenance.not_outputs(folder) == []
    seeds = text[text.index("### Over seeds"):text.index("## Parameters")]
    assert "`make sweep NB=03` re-ran the notebook over 3 seeds (7 to 9)" in seeds
    assert "the verdict of 1 of the 2 rows changes with the seed" in seeds
    assert "| item | quantity | reproduced | close | differs | not reproducible |" in seeds
    assert "| Fig. 3 | rho | 2 | 0 | 1 | 0 |" in seeds and "Table 1" not in seeds
    assert f"(../figures/{GUO}/sweep/verdict_stability.csv)" in seeds


def test_a_stable_sweep_over_settings_says_so_and_an_edited_one_is_named(guo_folder, tmp_path):
    folder = guo_folder / GUO
    _sweep(folder, {1: "reproduced", 2: "reproduced"}, settings=[40, 80])
    text, broken = _chapter(guo_folder)
    assert broken == {}
    assert "over 2 seeds (1 to 2) at each of 2 settings and scored every run (4 runs): no " \
           "row's verdict changes with the seed (4 rows)." in text
    with open(folder / book.SWEEP / "values.csv", "a") as fh:
        fh.write("edited,by,hand,1,2\n")
    text, broken = _chapter(guo_folder)
    assert [n for n, _ in _why(broken, guo_folder)] == ["sweep/values.csv"]
    assert "<code>make sweep NB=03</code>" in text and "sweep/values.csv)" not in text


def test_each_chapter_lists_its_notebooks_declared_parameters():
    for decl in workflow.DECLARATIONS:
        lines = book.parameter_lines(decl.stem)
        rows = [li for li in lines if li.startswith("| `")]
        assert [re.match(r"\| `(\w+)`", r).group(1) for r in rows] == decl.names()
        assert f"`{decl.__module__}.Parameters`" in "\n".join(lines)
    rows = {re.match(r"\| `(\w+)`", r).group(1): r
            for r in book.parameter_lines(rong.Parameters.stem) if r.startswith("| `")}
    assert rows["n_base"] == ("| `n_base` | `8192` | int | [64, 131072] | base sample size N "
                              "of the Saltelli design (paper: 10000) |")
    assert rows["layout"].startswith('| `layout` | `"z/xy"` | str | one of '
                                     'z/xy\\|x/zy\\|zx/y\\|xz/y |')
    text = "\n".join(book.parameter_lines(rong.Parameters.stem,
                                          {"parameters": {"n_base": 4096, "seed": 2022}}))
    assert "The run shown used <code>n_base=4096</code>, the others at their defaults." in text
    assert "used the defaults." in "\n".join(
        book.parameter_lines(GUO, {"parameters": guo2016.Parameters.defaults()}))


def test_a_folder_not_written_by_the_book_is_never_replaced(tmp_path, guo_folder):
    (tmp_path / "html").mkdir()
    (tmp_path / "html" / "mine.txt").write_text("a reader's file")
    with pytest.raises(book.BookError, match="was not written by make book"):
        book.build(tmp_path, guo_folder)
    assert (tmp_path / "html" / "mine.txt").read_text() == "a reader's file"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["figures", "html"]


def test_units_are_written_with_their_symbols():
    assert book.unit_symbol("um/m/degC") == "µm/m/°C"
    assert book.unit_symbol("deg") == "°" and book.unit_symbol("mm") == "mm"


# ---------------------------------------------------------------------- the whole book, once
