import json

import pandas as pd
import pytest

from mtaccuracy import reproduction as R

ROW = dict(item="Fig. 1", quantity="q", published="1.0", reproduced="1.1", unit="",
           tolerance="0.2", verdict="reproduced", note="")


def test_verdict_rules():
    assert R.verdict(1.0, 1.1, 0.2, False) == "reproduced"
    assert R.verdict(1.0, 1.5, 0.2, True) == "close"
    assert R.verdict(1.0, -1.0, 0.2, False) == "differs"

@pytest.mark.parametrize("pub, ours", [(float("nan"), 1.0), (1.0, float("nan")),
                                       (1.0, float("inf")), (1.0, "nan")])
def test_a_nan_or_infinite_value_is_never_a_verdict(pub, ours):
    with pytest.raises(R.NonFiniteResult, match="never a verdict|not a number"):
        R.verdict(pub, ours, 0.2, True)


@pytest.mark.parametrize("value, verdict", [(float("nan"), "not reproducible"),
                                            (float("inf"), "differs"), ("nan", "differs"),
                                            ("-inf", "close"), ("", "reproduced"),
                                            (None, "differs")])
def test_write_card_refuses_non_finite_results(tmp_path, value, verdict):
    with pytest.raises(R.NonFiniteResult):
        R.write_card([dict(ROW, reproduced=value, verdict=verdict)], tmp_path / "r.csv")
    assert not (tmp_path / "r.csv").exists()


def test_an_empty_result_is_allowed_only_when_not_reproducible(tmp_path):
    R.write_card([dict(ROW, reproduced="", verdict="not reproducible")], tmp_path / "r.csv")


def test_measured_rows_go_to_their_own_card(tmp_path):
    rows = [ROW, dict(ROW, quantity="time, PCE (measured)", reproduced=3.2, verdict="close")]
    R.write_card(rows, tmp_path / "reproduction.csv")
    card = pd.read_csv(tmp_path / "reproduction.csv")
    measured = pd.read_csv(tmp_path / R.MEASURED_CARD)
    assert list(card.quantity) == ["q"] and list(measured.quantity) == ["time, PCE (measured)"]
    side = json.loads((tmp_path / "provenance.json").read_text())
    assert side["files"][R.MEASURED_CARD] == {"measured": True}
    assert side["files"]["reproduction.csv"]["tolerance"]["reproduced"]["rel"] == 0


def test_save_table_refuses_infinity_and_unknown_tolerance_columns(tmp_path):
    with pytest.raises(R.NonFiniteResult, match="column\\(s\\) \\['a'\\]"):
        R.save_table(pd.DataFrame({"a": [1.0, float("inf")]}), tmp_path / "t.csv")
    with pytest.raises(ValueError, match="unknown column"):
        R.save_table(pd.DataFrame({"a": [1.0]}), tmp_path / "t.csv",
                     tolerance={"b": R.Tolerance(abs=1.0, why="x")})
    with pytest.raises(ValueError, match="finite and >= 0"):
        R.Tolerance(rel=-1.0, why="x")
    with pytest.raises(ValueError, match="reason"):
        R.Tolerance(abs=1.0, why=" ")


def _pair(tmp_path, a, b, tolerance=None):
    R.save_table(pd.DataFrame(a), tmp_path / "new.csv", tolerance=tolerance)
    R.save_table(pd.DataFrame(b), tmp_path / "old.csv", tolerance=tolerance)
    tol = json.loads((tmp_path / "provenance.json").read_text())["files"]["old.csv"]
    return R.compare_tables(tmp_path / "new.csv", tmp_path / "old.csv", tol.get("tolerance"))


def test_compare_tables_allows_the_printed_digit_and_the_declared_tolerance(tmp_path):
    # a last-digit rounding flip passes; two units in the last digit do not
    assert _pair(tmp_path, {"x": [0.12345649999]}, {"x": [0.1234565]}) == []
    bad = _pair(tmp_path, {"x": [0.123458]}, {"x": [0.123456]})
    assert len(bad) == 1 and "column 'x' row 2" in bad[0]
    # the declared absolute tolerance widens it, for that column only
    tol = {"x": R.Tolerance(abs=1e-5, why="an optimiser's xatol")}
    assert _pair(tmp_path, {"x": [0.123458], "y": [1.0]}, {"x": [0.123456], "y": [1.0]},
                 tol) == []
    # text and integers are exact, whatever the tolerance
    assert _pair(tmp_path, {"k": ["d_ya"], "n": [3]}, {"k": ["d_yb"], "n": [3]},
                 R.Tolerance(rel=1.0, why="x"))
    assert _pair(tmp_path, {"n": [4]}, {"n": [3]}, R.Tolerance(rel=1.0, why="x"))
    assert _pair(tmp_path, {"x": [1.0, 2.0]}, {"x": [1.0]}) == ["old.csv: shape (2, 1) != "
                                                                "committed (1, 1)"]


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
