
import pandas as pd
import pytest

from mtaccuracy.compendium import reproduction as R
from mtaccuracy.compendium import scorecard
from mtaccuracy.papers import printed


def _write_card(rows, path):
    """A scorecard written as a notebook's run writes it (``Run.scorecard``): checked rows, the
    ``reproduced`` and ``tolerance`` columns held to the printed precision."""
    df = R.card_frame(rows)
    return R.write_table(df, path, tolerance={"reproduced": R.PRINTED, "tolerance": R.PRINTED})

ROW = dict(item="Fig. 1", quantity="q", published="1.0", reproduced="1.1", unit="",
           tolerance="0.2", verdict="reproduced", basis="independent", kind="number",
           agreement="printed", note="")


@pytest.mark.parametrize("pub, ours", [("nan", 1.0), ("1.0", float("nan")),
                                       ("1.0", float("inf")), ("1.0", "nan")])
def test_a_nan_or_infinite_value_is_never_a_verdict(pub, ours):
    with pytest.raises(R.NonFiniteResult, match="never a verdict|not a number"):
        R.Card().number("T", "q", pub, ours)


@pytest.mark.parametrize("value, verdict", [(float("nan"), "not reproducible"),
                                            (float("inf"), "differs"), ("nan", "differs"),
                                            ("-inf", "close"), ("", "reproduced"),
                                            (None, "differs")])
def test_write_card_refuses_non_finite_results(tmp_path, value, verdict):
    basis = "unchecked" if verdict == "not reproducible" else "independent"
    with pytest.raises(R.NonFiniteResult):
        R.card_frame([dict(ROW, reproduced=value, verdict=verdict, basis=basis)])


def test_an_empty_result_is_kept_when_not_reproducible():
    df = R.card_frame([dict(ROW, reproduced="", verdict="not reproducible", basis="unchecked")])
    assert df.reproduced.tolist() == [""] and df.columns.tolist() == R.COLUMNS


def test_save_table_refuses_infinity_and_unknown_tolerance_columns(tmp_path):
    with pytest.raises(R.NonFiniteResult, match="column\\(s\\) \\['a'\\]"):
        R.write_table(pd.DataFrame({"a": [1.0, float("inf")]}), tmp_path / "t.csv")
    with pytest.raises(ValueError, match="unknown column"):
        R.write_table(pd.DataFrame({"a": [1.0]}), tmp_path / "t.csv",
                      tolerance={"b": R.Tolerance(abs=1.0, why="x")})
    with pytest.raises(ValueError, match="finite and >= 0"):
        R.Tolerance(rel=-1.0, why="x")
    with pytest.raises(ValueError, match="reason"):
        R.Tolerance(abs=1.0, why=" ")


def _pair(tmp_path, a, b, tolerance=None):
    R.write_table(pd.DataFrame(a), tmp_path / "new.csv", tolerance=tolerance)
    tol = R.write_table(pd.DataFrame(b), tmp_path / "old.csv", tolerance=tolerance)
    return scorecard.compare_tables(tmp_path / "new.csv", tmp_path / "old.csv",
                                    tol.get("tolerance"))


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
        R.card_frame([dict(ROW, verdict="ok")])
    with pytest.raises(ValueError, match="unknown basis"):
        R.card_frame([dict(ROW, basis="guessed")])
    with pytest.raises(ValueError, match="'not reproducible' and 'unchecked' go together"):
        R.card_frame([dict(ROW, basis="unchecked")])
    with pytest.raises(ValueError, match="lack column"):
        R.card_frame([{k: v for k, v in ROW.items() if k != "note"}])
    _write_card([ROW], tmp_path / "r.csv")
    assert (tmp_path / "r.csv").read_text().splitlines()[0] == ",".join(R.COLUMNS)


def test_save_table_is_byte_deterministic(tmp_path):
    df = pd.DataFrame({"a": [0.1 + 0.2, 1 / 3], "b": ["x", "y"]})
    entry = R.write_table(df, tmp_path / "t.csv")
    first = (tmp_path / "t.csv").read_bytes()
    assert entry["sha256"] == __import__("hashlib").sha256(first).hexdigest()
    R.write_table(df.copy(), tmp_path / "t.csv")
    assert (tmp_path / "t.csv").read_bytes() == first == b"a,b\n0.3,x\n0.333333,y\n"


def test_published_refuses_malformed_files(tmp_path):
    (tmp_path / "t.csv").write_text("output,rank\nEx,\n")
    with pytest.raises(ValueError, match="missing column\\(s\\) \\['symbol'\\]"):
        printed.published("t", ["output", "symbol"], folder=tmp_path)
    with pytest.raises(ValueError, match="column 'rank' is empty in row\\(s\\) \\[2\\]"):
        printed.published("t", ["output", "rank"], folder=tmp_path)
    with pytest.raises(FileNotFoundError, match="available: t"):
        printed.published("nope", folder=tmp_path)
    seen = []
    printed.published("t", ["output"], folder=tmp_path, on_read=seen.append)
    assert seen == [tmp_path / "t.csv"]


def test_gather_fills_the_marked_readme_section(tmp_path):
    figs = tmp_path / "figures"
    _write_card([ROW, dict(ROW, verdict="differs", quantity="p|q")],
                figs / "03_guo2016_spearman_21_errors" / "reproduction.csv")
    readme = tmp_path / "README.md"
    readme.write_text(f"# T\n\n{scorecard.README_START}\nold\n{scorecard.README_END}\n\ntail\n")
    scorecard.gather(figs, readme)
    text = readme.read_text()
    assert "old" not in text and text.endswith("tail\n")
    assert "| Guo et al. 2016 | `03_guo2016_spearman_21_errors` | 1 | 0 | 1 | 0 | 2 | 1 |" in text
    assert "Of the 2 printed numbers scored, 1 were reproduced independently at their printed "\
        "precision" in text
    assert "| `independent` | 1 | 0 | 1 | 0 | 2 |" in text and "- `fitted`: an input" in text
    md = (figs / "REPRODUCTION.md").read_text()
    assert "p\\|q" in md and "| note |" in md and "| note |" not in text
    scorecard.gather(figs, readme)
    assert readme.read_text() == text  # idempotent
    readme.write_text("# no markers\n")
    with pytest.raises(ValueError, match="lacks the scorecard markers"):
        scorecard.gather(figs, readme)


# --- the Card -------------------------------------------------------------------------------

def test_tolerance_policy_takes_the_largest_justified_source():
    assert printed.half_unit("0.0776") == pytest.approx(5e-5)
    assert printed.half_unit("12") == 0.5 and printed.half_unit("1.2e-05") == \
        pytest.approx(5e-7)
    assert R.tolerance_for("0.0776") == (pytest.approx(5e-5), "printed")
    assert R.tolerance_for("0.0776", paper_rel=0.05) == (pytest.approx(0.00388), "paper")
    assert R.tolerance_for("0.0776", paper_rel=0.05, sampling_se=0.003) == \
        (pytest.approx(0.006), "sampling")
    with pytest.raises(R.NonFiniteResult):
        R.tolerance_for("0.1", sampling_se=float("nan"))


def added(method, *args, **kwargs) -> dict:
    """The row that a card's ``method`` adds: the method itself returns nothing, so that a
    notebook cell ending with it echoes no dict as ``Out[]``."""
    rows = method.__self__.rows
    before = len(rows)
    assert method(*args, **kwargs) is None
    assert len(rows) == before + 1
    return rows[-1]


def test_card_number_verdicts_and_conclusions():
    card = R.Card()
    assert added(card.number, "T1", "a", "0.100", 0.1004)["verdict"] == "reproduced"
    assert added(card.number, "T1", "b", "0.100", 0.1006)["verdict"] == "differs"
    row = added(card.number, "T1", "c", "0.10", 0.2, conclusion="largest of the group", holds=True)
    assert row["verdict"] == "close" and "same conclusion: largest of the group" in row["note"]
    assert added(card.number, "T1", "d", "0.10", 0.104, paper_rel=0.05)["verdict"] == "reproduced"
    assert added(card.number, "T1", "e", "0.10", 0.104, paper_rel=0.05)["tolerance"] == \
        "0.005 (paper)"
    with pytest.raises(ValueError, match="needs the conclusion in words"):
        card.number("T1", "f", "0.10", 0.2, holds=True)
    with pytest.raises(ValueError, match="added twice"):
        card.number("T1", "a", "0.100", 0.1)
    with pytest.raises(R.NonFiniteResult):
        card.number("T1", "g", "0.100", float("nan"))
    assert added(card.count, "T2", "n", "12", 12)["verdict"] == "reproduced"
    assert added(card.count, "T2", "m", "12", 11)["verdict"] == "differs"
    assert added(card.statement, "T3", "x rises", "rises", "rises", holds=True)["verdict"] == \
        "reproduced"


def test_card_sets_count_extra_elements_as_well_as_missing_ones():
    card = R.Card()
    assert added(card.set, "K", "a", ["x", "y"], ["y", "x"])["verdict"] == "reproduced"
    row = added(card.set, "K", "b", list("abcde"), list("abcdef"))
    assert row["verdict"] == "close" and "extra: f" in row["note"]
    assert added(card.set, "K", "c", list("abc"), list("abcdef"))["verdict"] == "differs"
    # Jaccard 0.5
    assert added(card.set, "K", "d", list("abc"), list("abd"))["verdict"] == "differs"
    row = added(card.set, "K", "e", list("abc"), list("acb"), ordered=True)
    assert row["verdict"] == "close" and "other order" in row["note"]


def test_the_basis_follows_the_declared_inputs():
    card = R.Card()
    pose = card.fitted("pose", to=["Table 2"], how="least squares")
    data = card.constructed("thermal data", targets=["Table 7", "Eq. 8: * at 185 mm"],
                            how="built from Tables 1 and 5")
    sim = card.simulated("probe signals", how="set profile plus noise")
    table = card.printed("Table 2 values")
    assert added(card.number, "Table 3", "x", "1", 1.0)["basis"] == "independent"
    assert added(card.number, "Table 2", "y", "1", 1.0, uses=[pose])["basis"] == "fitted"
    assert added(card.number, "Table 7", "RMSE", "1", 1.0, uses=[data])["basis"] == "constructed"
    assert added(card.number, "Eq. 8", "slope at 185 mm", "1", 1.0, uses=[data])["basis"] == \
        "constructed"
    # rule 2: every row using a constructed input is constructed, target or not
    row = added(card.number, "Eq. 8", "slope at 300 mm", "1", 1.0, uses=[data])
    assert row["basis"] == "constructed" and "set to published values" in row["note"]
    assert added(card.number, "Eq. 8", "x", "1", 1.0, uses=[data, sim])["basis"] == "constructed"
    assert added(card.number, "Fig. 9", "roundness", "1", 1.0, uses=[sim])["basis"] == "simulated"
    assert added(card.number, "Table 2", "share", "1", 1.0, uses=[table])["basis"] == "internal"
    assert added(card.number, "Table 2", "mixed", "1", 1.0, uses=[table, pose])["basis"] == "fitted"
    assert added(card.number, "Table 2", "sim", "1", 1.0, uses=[table, sim])["basis"] == \
        "simulated"
    row = added(card.claim, "Fig. 4", "z", "printed", why="the paper does not give the data")
    assert (row["verdict"], row["basis"]) == ("not reproducible", "unchecked")
    row = added(card.claim, "Fig. 5", "z", "printed", why="no data", ours="0.25 (read off)")
    assert row["reproduced"] == "0.25 (read off)" and row["kind"] == "claim"
    # a number of ours is scored, never hidden behind claim()
    with pytest.raises(ValueError, match="our number exists .0.25.: score it with number"):
        card.claim("Fig. 6", "z", "0.3", why="no data", ours=0.25)
    assert "pose fitted to Table 2" in card.rows[1]["note"]
    assert "derived from other" not in card.rows[1]["note"]
    other = R.Card().fitted("pose", to=["Table 9"], how="x")
    with pytest.raises(ValueError, match="not an input of this card"):
        card.number("Table 3", "z", "1", 1.0, uses=[other])
    with pytest.raises(ValueError, match="name the published items"):
        card.fitted("range", to=[], how="x")


def test_a_fitted_reference_scoring_another_published_item_is_internal():
    """Rule 1: an input fitted to one published column, used to score another, compares the
    paper with itself; with simulated data or printed numbers beside it, still internal."""
    card = R.Card()
    pose = card.fitted("pose", to=["Table 2: PCE *"], how="least squares on the PCE column")
    sim = card.simulated("runs", how="Monte Carlo on the model")
    table = card.printed("Table 2")
    row = added(card.number, "Table 2", "PCE S_T of dx", "0.5", 0.5, uses=[pose])
    assert row["basis"] == "fitted"
    for uses in ([pose], [pose, sim], [pose, table], [pose, sim, table]):
        row = added(card.number, "Table 2", f"MCS S_T of dx {len(uses)}{uses[-1].kind}", "0.5",
                    0.5, uses=uses)
        assert row["basis"] == "internal", uses
        assert "derived from other published numbers" in row["note"]
    assert added(card.set, "Table 2", "MCS key set", list("ab"), list("ab"),
                 uses=[pose, sim])["basis"] == "internal"


@pytest.mark.parametrize("method", ["number", "statement", "set"])
def test_no_row_using_a_fitted_or_constructed_input_is_independent_or_simulated(method):
    card = R.Card()
    inputs = [card.fitted("f", to=["A*"], how="x"),
              card.constructed("c", targets=["B*"], how="y"),
              card.simulated("s", how="z"), card.printed("p")]
    args = {"number": ("1", 1.0), "statement": ("holds", "holds", True),
            "set": (["a"], ["a"])}[method]
    import itertools
    for n in range(1, 5):
        for uses in itertools.combinations(inputs, n):
            kinds = {u.kind for u in uses}
            for item in ("A1", "B1", "C1"):
                q = f"{method} {n} {'+'.join(sorted(kinds))}"
                if any(r["item"] == item and r["quantity"] == q for r in card.rows):
                    continue
                row = added(getattr(card, method), item, q, *args, uses=list(uses))
                if kinds & {"fitted", "constructed"}:
                    assert row["basis"] not in ("independent", "simulated"), (item, kinds)
                if "constructed" in kinds:
                    assert row["basis"] == "constructed"


def test_an_assumption_that_settles_a_row_never_scores_reproduced():
    card = R.Card()
    same = card.assumed("synchronous error equal at every speed", settles=["Fig. 21: *equal*"],
                        how="the simulation draws one synchronous profile for all speeds")
    sim = card.simulated("runs", how="noise")
    row = added(card.statement, "Fig. 21", "synchronous error equal at every speed", "equal",
                "equal within 0.1 um", True, uses=[same, sim])
    assert (row["verdict"], row["basis"]) == ("not reproducible", "unchecked")
    assert "true by design" in row["note"]
    row = added(card.number, "Fig. 21", "roundness at 600 r/min", "1.0", 1.0, uses=[same, sim])
    assert (row["verdict"], row["basis"]) == ("reproduced", "simulated")
    with pytest.raises(ValueError, match="settles"):
        card.assumed("x", settles=[], how="y")


def test_card_tally_and_write(tmp_path):
    card = R.Card()
    card.number("T", "a", "1.0", 1.0)
    card.number("T", "time", "3", 9.0, measured=True)
    card.claim("F", "b", "x", why="no data")
    t = card.tally()
    assert t.loc["independent", "reproduced"] == 1 and t.loc["total", "total"] == 2
    df = card.frame()
    assert list(df.columns) == R.COLUMNS and list(df.basis) == ["independent", "unchecked"]
    assert card.frame(measured=True).quantity.str.contains(R.MEASURED_MARK, regex=False).sum() == 1


def test_the_tolerance_column_is_compared_by_its_number(tmp_path):
    card = R.Card()
    card.number("T", "a", "1.00", 1.04, sampling_se=0.0251)
    tol = _write_card(card.rows, tmp_path / "new.csv")["tolerance"]
    assert pd.read_csv(tmp_path / "new.csv")["tolerance"][0] == "0.05 (sampling)"
    other = (tmp_path / "new.csv").read_text()
    (tmp_path / "old.csv").write_text(other.replace("0.05 (sampling)", "0.049 (sampling)"))
    assert scorecard.compare_tables(tmp_path / "new.csv", tmp_path / "old.csv", tol) == []
    (tmp_path / "old.csv").write_text(other.replace("0.05 (sampling)", "0.08 (sampling)"))
    assert "column 'tolerance'" in scorecard.compare_tables(tmp_path / "new.csv",
                                                            tmp_path / "old.csv", tol)[0]
    (tmp_path / "old.csv").write_text(other.replace("0.05 (sampling)", "0.05 (paper)"))
    assert "'0.05 (sampling)' != committed '0.05 (paper)'" in \
        scorecard.compare_tables(tmp_path / "new.csv", tmp_path / "old.csv", tol)[0]


def test_a_bracket_of_defensible_inputs_is_not_reproducible_inside_and_scored_outside():
    card = R.Card()
    row = added(card.bracket, "C3", "count", "12", 17, 7, why="ranges lost")
    assert (row["verdict"], row["basis"], row["reproduced"]) == ("not reproducible", "unchecked",
                                                                 "7-17")
    assert "lies inside" in row["note"]
    row = added(card.bracket, "F5", "max", "0.35", 0.125, 0.103, "mm", why="scale", digits=3)
    assert (row["verdict"], row["basis"], row["reproduced"]) == ("differs", "independent", 0.125)
    assert "outside 0.103-0.125" in row["note"]
    row = added(card.bracket, "F6", "min", "0.103", 0.125, 0.1034, why="scale")
    assert row["verdict"] == "reproduced" and row["reproduced"] == 0.1034
    with pytest.raises(R.NonFiniteResult):
        card.bracket("F7", "x", "1", float("nan"), 2, why="w")
    with pytest.raises(ValueError, match="what is missing"):
        card.bracket("F8", "x", "1", 0, 2, why=" ")


def test_each_row_says_its_kind_and_what_a_reproduced_number_agrees_within():
    """kind: the Card method that made the row (a bracket scores a number); agreement: the
    printed precision, or only the paper's stated agreement, or only our sampling error."""
    card = R.Card()
    assert added(card.number, "T", "a", "0.50", 0.504)["agreement"] == "printed"
    row = added(card.number, "T", "b", "0.50", 0.52, paper_rel=0.05)
    assert (row["verdict"], row["agreement"], row["kind"]) == ("reproduced", "paper", "number")
    assert added(card.number, "T", "c", "0.50", 0.53, sampling_se=0.02)["agreement"] \
        == "sampling"
    assert added(card.number, "T", "d", "0.50", 0.9)["agreement"] == ""        # differs
    assert added(card.count, "T", "e", "21", 21)["kind"] == "count"
    assert added(card.set, "T", "f", ["a", "b"], ["b", "a"])["kind"] == "set"
    assert added(card.statement, "T", "g", "x", "y", True)["kind"] == "statement"
    inside = added(card.bracket, "T", "h", "5", 1.0, 9.0, why="tool length omitted")
    assert (inside["kind"], inside["verdict"], inside["reproduced"]) == \
        ("number", "not reproducible", "1-9")
    outside = added(card.bracket, "T", "i", "50", 1.0, 9.0, why="tool length omitted")
    assert (outside["kind"], outside["verdict"]) == ("number", "differs")
    # the nearer end's sampling error widens the tolerance as for any number
    wide = added(card.bracket, "T", "j", "10", 1.0, 9.0, why="w", sampling_se=0.6)
    assert (wide["verdict"], wide["agreement"]) == ("reproduced", "sampling")
    assert set(R.card_frame(card.rows)["kind"]) <= set(R.KINDS)


def test_a_check_that_cannot_fail_is_never_an_independent_reproduction():
    card = R.Card()
    rigid = card.tautology("rigid-body chain", settles=["Fig. 6: attitude*"],
                           how="an orientation error depends on angular errors only in every "
                               "rigid-body model")
    row = added(card.statement, "Fig. 6", "attitude: only angular errors matter", "x", "y",
                True, uses=[rigid])
    assert (row["verdict"], row["basis"]) == ("reproduced", "tautological")
    assert "cannot fail: rigid-body chain" in row["note"]
    # a row the tautology does not settle keeps its own basis
    assert added(card.number, "Fig. 6", "S_T of e_x", "0.5", 0.5, uses=[rigid])["basis"] \
        == "independent"
    # and a failing check stays visible as such
    assert added(card.statement, "Fig. 6", "attitude: other", "x", "y", False,
                 uses=[card.tautology("t2", settles=["Fig. 6: attitude: other"], how="h")]
                 )["verdict"] == "differs"
    with pytest.raises(ValueError, match="name the rows it settles"):
        card.tautology("t3", settles=[], how="h")


def test_the_headline_counts_printed_numbers_apart_from_claims_and_counts():
    card = R.Card()
    card.number("T", "a", "0.50", 0.504)                       # printed precision
    card.number("T", "b", "0.50", 0.52, paper_rel=0.05)        # only the stated 5 %
    card.count("T", "c", "21", 21)
    card.statement("T", "d", "x", "y", True)
    card.claim("T", "e", "x", why="no data")
    cards = R.card_frame(card.rows)
    text = scorecard.headline(cards)
    assert text.startswith("Of the 2 printed numbers scored, 1 were reproduced independently "
                           "at their printed precision (2 independently within their tolerance)")
    assert "Of the 3 claims, counts, sets and statements, 2 were reproduced independently" in text
    assert "1 of them only through the paper's stated agreement (1) or our sampling error (0)" \
        in text and "1 cannot be checked" in text
