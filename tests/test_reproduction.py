import pandas as pd
import pytest

from mtaccuracy import reproduction as R

ROW = dict(item="Fig. 1", quantity="q", published="1.0", reproduced="1.1", unit="",
           tolerance="0.2", verdict="reproduced", note="")


def test_verdict_rules():
    assert R.verdict(1.0, 1.1, 0.2, False) == "reproduced"
    assert R.verdict(1.0, 1.5, 0.2, True) == "close"
    assert R.verdict(1.0, -1.0, 0.2, False) == "differs"
    assert R.verdict(float("nan"), 1.0, 0.2, True) == "not reproducible"


def test_write_card_checks_columns_and_verdicts(tmp_path):
    with pytest.raises(ValueError, match="unknown verdict"):
        R.write_card([dict(ROW, verdict="ok")], tmp_path / "r.csv")
    with pytest.raises(ValueError, match="lack column"):
        R.write_card([{k: v for k, v in ROW.items() if k != "note"}], tmp_path / "r.csv")
    R.write_card([ROW], tmp_path / "r.csv")
    assert (tmp_path / "r.csv").read_text().splitlines()[0] == ",".join(R.COLUMNS)


def test_save_table_is_byte_deterministic(tmp_path):
    df = pd.DataFrame({"a": [0.1 + 0.2, 1 / 3], "b": ["x", "y"]})
    R.save_table(df, tmp_path / "t.csv")
    first = (tmp_path / "t.csv").read_bytes()
    R.save_table(df.copy(), tmp_path / "t.csv")
    assert (tmp_path / "t.csv").read_bytes() == first == b"a,b\n0.3,x\n0.333333,y\n"


def test_published_refuses_malformed_files(tmp_path):
    (tmp_path / "t.csv").write_text("output,rank\nEx,\n")
    with pytest.raises(ValueError, match="missing column\\(s\\) \\['symbol'\\]"):
        R.published("t", ["output", "symbol"], folder=tmp_path)
    with pytest.raises(ValueError, match="column 'rank' is empty in row\\(s\\) \\[2\\]"):
        R.published("t", ["output", "rank"], folder=tmp_path)
    with pytest.raises(FileNotFoundError, match="available: t"):
        R.published("nope", folder=tmp_path)


def test_gather_fills_the_marked_readme_section(tmp_path):
    figs = tmp_path / "figures"
    R.write_card([ROW, dict(ROW, verdict="differs", quantity="p|q")],
                 figs / "03_guo2016_spearman_21_errors" / "reproduction.csv")
    readme = tmp_path / "README.md"
    readme.write_text(f"# T\n\n{R.README_START}\nold\n{R.README_END}\n\ntail\n")
    R.gather(figs, readme)
    text = readme.read_text()
    assert "old" not in text and text.endswith("tail\n")
    assert "| Guo et al. 2016 | `03_guo2016_spearman_21_errors` | 1 | 0 | 1 | 0 | 2 |" in text
    assert "p\\|q" in (figs / "REPRODUCTION.md").read_text()
    R.gather(figs, readme)
    assert readme.read_text() == text  # idempotent
    readme.write_text("# no markers\n")
    with pytest.raises(ValueError, match="lacks the scorecard markers"):
        R.gather(figs, readme)
