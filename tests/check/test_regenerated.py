"""What nbval's runs of the committed notebooks wrote (``make check``), against what is committed.

``make check`` executes a parameterised copy of every committed notebook through nbval
(``tests/notebook_copies.py``: outputs into ``<check-dir>/figures/<stem>/``); nbval itself
compares the cells marked ``# NBVAL_CHECK_OUTPUT``.  Then, for each notebook:

* it wrote the files that are committed, each listed in its ``provenance.json``;
* every regenerated CSV equals the committed one: text and integer columns exactly, float
  columns within the tolerance declared where the table is written (recorded in the run's
  ``provenance.json``) plus one unit of the last printed digit; tables declared ``measured``
  (wall-clock times) are not compared;
* notebook 03's outputs are byte-identical to the committed ones (exact rationals and
  deterministic arithmetic: on any machine, with any number of BLAS threads).
"""

import pytest

from mtaccuracy.compendium import provenance, scorecard, workflow
from mtaccuracy.compendium.notebook import FIGURES

STEMS = [d.stem for d in workflow.DECLARATIONS]


@pytest.mark.parametrize("stem", STEMS)
def test_regenerated_tables_equal_the_committed_ones(stem, check_dir):
    fresh, committed = check_dir / "figures" / stem, FIGURES / stem
    side = provenance.read(fresh)
    assert side, f"nbval's run of {stem} wrote no provenance.json (did it run?)"
    files = side["files"]
    assert sorted(files) == sorted(provenance.read(committed)["files"])
    assert sorted(p.name for p in fresh.iterdir() if p.is_file()) == \
        sorted([*files, provenance.SIDECAR])
    problems = []
    for name, entry in files.items():
        if name.endswith(".csv") and not entry.get("measured"):
            problems += scorecard.compare_tables(fresh / name, committed / name,
                                                 entry.get("tolerance", {}))
    assert not problems, "\n".join(problems)


def test_notebook_03_is_byte_identical_to_what_is_committed(check_dir):
    stem = "03_guo2016_spearman_21_errors"
    fresh, committed = check_dir / "figures" / stem, FIGURES / stem
    names = sorted(provenance.read(committed)["files"]) + [provenance.SIDECAR]
    assert {".csv", ".png", ".svg"} <= {n[n.rfind("."):] for n in names}
    assert [n for n in names if (fresh / n).read_bytes() != (committed / n).read_bytes()] == []
