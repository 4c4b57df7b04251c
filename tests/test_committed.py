"""What is committed of each notebook, checked without running it (nbval's runs are in
``make check``, tests/check/)."""

import json

import pytest

from mtaccuracy.compendium import workflow
from mtaccuracy.compendium.notebook import NOTEBOOKS, ROOT

STEMS = [d.stem for d in workflow.DECLARATIONS]
CHECK = "# NBVAL_CHECK_OUTPUT"


def _printed(cell) -> list[str]:
    out = []
    for o in cell.get("outputs", []):
        if o["output_type"] == "stream":
            out.append("".join(o["text"]))
        elif "data" in o and "text/plain" in o["data"]:
            out.append("".join(o["data"]["text/plain"]))
    return out


def _cells(stem):
    return json.loads((NOTEBOOKS / f"{stem}.ipynb").read_text(encoding="utf-8"))["cells"]


@pytest.mark.parametrize("stem", STEMS)
def test_notebook_marks_cells_for_nbval_visibly(stem):
    """Every notebook has cells nbval compares, each marked by its visible first line (not by a
    hidden tag), and each of them prints something to compare."""
    code = [c for c in _cells(stem) if c["cell_type"] == "code"]
    marked = [c for c in code if "".join(c["source"]).startswith(CHECK)]
    assert marked, f"{stem}: no cell marked {CHECK}"
    assert all(_printed(c) for c in marked), f"{stem}: a marked cell prints nothing"
    for c in code:
        tags = {t.lower() for t in c.get("metadata", {}).get("tags", [])}
        assert not tags & {"nbval-check-output", "nbval-ignore-output", "nbval-skip"}, \
            f"{stem}: a cell is marked for nbval by a hidden tag"


@pytest.mark.parametrize("stem", STEMS)
def test_a_committed_notebook_shows_no_path_of_this_checkout_and_no_measurement(stem):
    """A stored output showing this checkout's path (or the workflow's run folder) would differ
    in every clone; a cell tagged ``measured`` keeps the workflow's note instead of its
    times; the cell papermill injects is stored only when the run had parameters."""
    text = (NOTEBOOKS / f"{stem}.ipynb").read_text(encoding="utf-8")
    assert str(ROOT) not in text and "build/runs" not in text
    for c in _cells(stem):
        tags = c.get("metadata", {}).get("tags", [])
        if "measured" in tags:
            assert _printed(c) == [workflow.MEASURED_NOTE]
        assert "injected-parameters" not in tags, f"{stem} was committed from a run with " \
                                                  f"other parameters"
