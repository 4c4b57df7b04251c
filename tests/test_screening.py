"""Key-error screening (Rong et al.): the 90 % rule, simplification rate, reduced model."""

import numpy as np
import pytest

from mtaccuracy import sensitivity as S

NAMES = ["a", "b", "c", "d"]


def test_rule_on_hand_checkable_cases():
    # cumulative shares 0.5, 0.8, 0.95, 1.0: the smallest top set exceeding 0.9 has 3 errors
    st = [0.15, 0.5, 0.05, 0.3]
    k = S.key_errors(st, names=NAMES, threshold=0.9)
    assert k.names == ("b", "d", "a") and k.index == (1, 3, 0)
    assert k.n_key == 3 and k.share == pytest.approx(0.95) and k.n_total == 4
    assert k.simplification_rate == pytest.approx(0.25)
    assert S.key_errors(st, names=NAMES, threshold=0.7).names == ("b", "d")  # 0.8 > 0.7
    assert S.key_errors(st, names=NAMES, threshold=0.4).names == ("b",)      # 0.5 > 0.4
    assert S.key_errors(st, names=NAMES, threshold=0.99).n_key == 4


def test_share_must_exceed_the_threshold_not_equal_it():
    # 6/10 + 3/10 is 0.9 exactly (to rounding): "exceeds 90 %" needs the third error
    assert S.key_errors([6, 3, 1], threshold=0.9).n_key == 3
    assert S.key_errors([0.6, 0.3, 0.1], threshold=0.9).n_key == 3
    assert S.key_errors([0.6, 0.3, 0.1], threshold=0.89).n_key == 2


def test_shares_are_of_the_sum_so_scale_does_not_matter():
    st = np.array([0.42, 0.31, 0.2, 0.07])
    a, b = S.key_errors(st, names=NAMES), S.key_errors(10 * st, names=NAMES)
    assert a.names == b.names == ("a", "b", "c") and a.share == pytest.approx(b.share)
    # total indices of an interacting model sum to more than 1: shares are still of the sum
    assert S.key_errors(st * 1.7, names=NAMES).names == a.names


def test_ties_are_broken_by_the_original_order_and_zeros_never_count():
    assert S.key_errors([0.25] * 4, names=NAMES, threshold=0.6).names == ("a", "b", "c")
    assert S.key_errors([0.0, 1.0, 0.0, 0.0], names=NAMES, threshold=0.9).names == ("b",)
    assert S.key_errors([0.0, 0.5, 0.5, 0.0], names=NAMES, threshold=0.9).names == ("b", "c")


def test_tie_tolerance_keeps_exchangeable_errors_together():
    st = [0.4, 0.3, 0.1, 0.1, 0.1]
    names = ["a", "b", "c", "d", "e"]
    assert S.key_errors(st, names=names, threshold=0.75).names == ("a", "b", "c")  # 0.8 > 0.75
    k = S.key_errors(st, names=names, threshold=0.75, tie_tol=0.0)
    assert k.names == ("a", "b", "c", "d", "e") and k.share == pytest.approx(1.0)
    near, far = [0.4, 0.3, 0.1, 0.098, 0.05], [0.4, 0.3, 0.1, 0.09, 0.05]
    assert S.key_errors(near, names=names, threshold=0.75, tie_tol=0.05).n_key == 4
    assert S.key_errors(far, names=names, threshold=0.75, tie_tol=0.05).n_key == 3
    assert S.key_errors([1.0, 0.0, 0.0], tie_tol=0.5).n_key == 1          # zeros never join
    with pytest.raises(ValueError, match="tie_tol"):
        S.key_errors(st, names=names, threshold=0.75, tie_tol=1.0)


def test_by_output_and_union():
    st = np.array([[0.7, 0.0], [0.25, 0.05], [0.05, 0.0], [0.0, 0.95]])
    sets = S.key_errors_by_output(st, names=NAMES, outputs=["Ex", "Ey"], threshold=0.9)
    assert sets["Ex"].names == ("a", "b") and sets["Ey"].names == ("d",)
    assert S.union_key_set(sets, NAMES) == ("a", "b", "d")
    assert S.union_key_set(list(sets.values()), NAMES[::-1]) == ("d", "b", "a")


def test_simplification_rate_and_the_papers_numbers():
    assert S.simplification_rate(12, 21) == pytest.approx(9 / 21)   # 42.9 %, not 48 %
    assert S.simplification_rate(11, 21) == pytest.approx(10 / 21)  # 47.6 %: the paper's 48 %
    assert S.simplification_rate(0, 5) == 1.0 and S.simplification_rate(5, 5) == 0.0


def test_pooled_indices_weight_by_variance():
    s = np.array([[1.0, 0.0], [0.0, 1.0]])        # error 0 explains output 0, error 1 output 1
    assert np.allclose(S.pooled_indices(s, [3.0, 1.0]), [0.75, 0.25])
    stacked = np.stack([s, s[::-1]])              # leading axis (e.g. two cases)
    assert np.allclose(S.pooled_indices(stacked, [[3.0, 1.0], [1.0, 1.0]]),
                       [[0.75, 0.25], [0.5, 0.5]])


def test_zero_non_key_and_reduced_model():
    x = np.arange(12.0).reshape(3, 4) + 1
    z = S.zero_non_key(x, ["b", "d"], NAMES)
    assert np.array_equal(z[:, [1, 3]], x[:, [1, 3]]) and not z[:, [0, 2]].any()
    assert np.array_equal(S.zero_non_key(x, [3, 1]), z)
    assert np.array_equal(S.zero_non_key(x, S.key_errors([0, 1, 0, 1.0], names=NAMES)), z)
    assert x[0, 0] == 1  # the input is not modified
    f = S.reduced_model(lambda v: v.sum(1), ["a"], NAMES)
    assert np.array_equal(f(x), x[:, 0])


def test_reduced_additive_model_leaves_the_dropped_variance():
    """y = sum c_i x_i with uniform x: the residual RMS ratio is sqrt(1 - kept share)."""
    rng = np.random.default_rng(0)
    c = np.array([4.0, 2.0, 1.0, 0.5])
    x = rng.uniform(-1, 1, size=(200_000, 4))
    model = lambda v: (v @ c)[:, None]  # noqa: E731
    st = (c**2 / (c**2).sum())[:, None]
    k = S.key_errors(st[:, 0], names=NAMES, threshold=0.9)
    assert k.names == ("a", "b")
    summ = S.residual_summary(model(x), S.reduced_model(model, k)(x), ["y"])
    assert summ.rms_ratio.iloc[0] == pytest.approx(S.expected_rms_ratio(k.share), rel=0.01)
    assert summ.residual_max.iloc[0] == pytest.approx(1.5, abs=0.01)  # |x_c| + 0.5 |x_d| <= 1.5


def test_threshold_sweep_is_monotone():
    rng = np.random.default_rng(1)
    c = np.array([[4.0, 0.1], [2.0, 3.0], [1.0, 0.2], [0.5, 1.0]])
    x = rng.uniform(-1, 1, size=(5000, 4))
    model = lambda v: v @ c  # noqa: E731
    st = c**2 / (c**2).sum(0)
    sweep = S.threshold_sweep(st, x, model, thresholds=np.arange(0.5, 0.995, 0.05),
                              names=NAMES, outputs=["y0", "y1"])
    assert len(sweep) == 2 * 10 and set(sweep.output) == {"y0", "y1"}
    for _, d in sweep.groupby("output"):
        assert np.all(np.diff(d.n_key) >= 0) and np.all(np.diff(d.residual_rms) <= 1e-15)
    last = sweep[sweep.threshold == sweep.threshold.max()]
    assert (last.n_key == 4).all() and np.allclose(last.residual_rms, 0)


def test_key_set_bootstrap_is_stable_for_a_clear_case():
    ua, ub = S.base_samples(512, 4, method="sobol", seed=3)
    model = lambda v: (v - 0.5) @ np.array([[4.0], [2.0], [0.3], [0.1]])  # noqa: E731
    _, st_boot = S.sobol_bootstrap_samples(*S.sobol_evaluate(model, ua, ub), n_boot=50,
                                           seed=3)
    freq, counts = S.key_set_bootstrap(st_boot, names=NAMES, outputs=["y"])
    assert list(freq.y) == [1.0, 1.0, 0.0, 0.0] and (counts.union == 2).all()
    assert list(freq.columns) == ["symbol", "y", "union"] and len(counts) == 50


def test_key_set_bootstrap_breaks_rounding_ties_by_catalogue_order():
    """b and c enter the output alike; the rule needs one of them.  Their estimates differ by
    rounding noise whose sign flips between resamples: the key one is b (catalogue order) in
    every resample, never whichever the noise favours (the former key_set_frequencies is gone:
    one function, one tie rule)."""
    assert not hasattr(S, "key_set_frequencies")
    noise = np.array([1e-13, -1e-13, 3e-14, -5e-14])
    st = np.stack([np.array([0.5, 0.2 * (1 + e), 0.2 * (1 - e), 0.1]) for e in noise])[..., None]
    freq, counts = S.key_set_bootstrap(st, names=NAMES, outputs=["y"], threshold=0.6)
    assert list(freq.y) == [1.0, 1.0, 0.0, 0.0] and (counts.y == 2).all()
    # the rule on the raw values follows the noise: this is what the merge prevents
    raw = [S.key_errors(s[:, 0], names=NAMES, threshold=0.6).names for s in st]
    assert {r[1] for r in raw} == {"b", "c"}


def test_cumulative_share_margin():
    st = np.array([[5.0, 4.0, 1.0], [1.0, 1.0, 1.0]]).T
    assert np.allclose(S.cumulative_share_margin(st, 0.85), [0.05, 0.15])
    assert S.cumulative_share_margin(np.array([3.0, 1.0]), 0.5)[0] == pytest.approx(0.25)


@pytest.mark.parametrize("st, threshold, message", [
    ([0.5, -0.1, 0.6], 0.9, ">= 0"),
    ([0.5, np.nan, 0.6], 0.9, "NaN"),
    ([0.0, 0.0, 0.0], 0.9, "sum to zero"),
    ([0.5, 0.5, 0.1], 1.0, "strictly between 0 and 1"),
    ([0.5, 0.5, 0.1], 0.0, "strictly between 0 and 1"),
    ([0.5, 0.5, 0.1], 90, "strictly between 0 and 1"),
    ([[0.5, 0.5]], 0.9, r"shape \(D,\)"),
    ([], 0.9, "non-empty"),
])
def test_bad_inputs_of_the_rule(st, threshold, message):
    with pytest.raises(ValueError, match=message):
        S.key_errors(st, threshold=threshold)


def test_other_bad_inputs():
    with pytest.raises(ValueError, match="3 names for 4"):
        S.key_errors([1, 2, 3, 4], names=["a", "b", "c"])
    with pytest.raises(ValueError, match="unique"):
        S.key_errors([1, 2, 3, 4], names=["a", "a", "c", "d"])
    with pytest.raises(ValueError, match="n_key must be"):
        S.simplification_rate(22, 21)
    with pytest.raises(ValueError, match="n_total must be"):
        S.simplification_rate(0, 0)
    with pytest.raises(ValueError, match="unknown error name"):
        S.zero_non_key(np.ones((2, 4)), ["e"], NAMES)
    with pytest.raises(ValueError, match="need the list of names"):
        S.zero_non_key(np.ones((2, 4)), ["a"])
    with pytest.raises(ValueError, match=r"in \[0, 4\)"):
        S.zero_non_key(np.ones((2, 4)), [4])
    with pytest.raises(ValueError, match="one shape"):
        S.residual_summary(np.ones((5, 2)), np.ones((5, 3)))
    with pytest.raises(ValueError, match="not among the names"):
        S.union_key_set([S.key_errors([1, 0], names=["p", "q"])], NAMES)
    with pytest.raises(ValueError, match="must match"):
        S.pooled_indices(np.ones((3, 2)), np.ones(3))
    with pytest.raises(ValueError, match="share must be"):
        S.expected_rms_ratio(1.5)
    with pytest.raises(ValueError, match=r"shape \(n, 4\)"):
        S.threshold_sweep(np.ones((4, 1)), np.ones((3, 5)), lambda v: v, thresholds=[0.9],
                          names=NAMES)
    with pytest.raises(ValueError, match=r"\(n_boot, D, q\)"):
        S.key_set_bootstrap(np.ones((4, 1)), names=NAMES)
    with pytest.raises(ValueError, match="only 3 inputs"):
        S.key_set_bootstrap(np.ones((2, 3, 1)), names=NAMES)


def test_rank_with_ties_breaks_near_equal_values_by_the_key_not_by_noise():
    # two candidates equal up to rounding noise: the key decides, whichever is smaller by noise
    for noise in (+1e-13, -1e-13):
        v = [1.0, 1.0 + noise, 2.0]
        keys = [[5.0], [3.0], [0.0]]
        assert list(S.rank_with_ties(v, keys, rtol=1e-9)) == [1, 0, 2]
    # without a tolerance the value decides
    assert list(S.rank_with_ties([1.0, 1.0 + 1e-13, 2.0], [[5.0], [3.0], [0.0]])) == [0, 1, 2]
    # a real difference is not a tie, whatever the key says
    assert list(S.rank_with_ties([1.0, 1.01], [[5.0], [3.0]], rtol=1e-6)) == [0, 1]
    # the group is anchored at its smallest value: 1.0 and 1.0 + 6e-7 tie, 1.0 + 1.2e-6 does not
    order = S.rank_with_ties([1.0 + 1.2e-6, 1.0 + 6e-7, 1.0], [[0.0], [1.0], [2.0]], rtol=1e-6)
    assert list(order) == [1, 2, 0]
    # absolute tolerance, for values near zero
    assert list(S.rank_with_ties([1e-20, 0.0], [[0.0], [1.0]], atol=1e-15)) == [0, 1]


def test_rank_with_ties_compares_keys_with_a_tolerance_then_by_position():
    v = np.zeros(3)
    keys = [[1.0, 9.0], [1.0 + 1e-12, 2.0], [0.5, 0.0]]
    assert list(S.rank_with_ties(v, keys, key_tol=1e-9)) == [2, 1, 0]  # first keys tie: second
    assert list(S.rank_with_ties(v, keys)) == [2, 0, 1]                 # exact: first key decides
    assert list(S.rank_with_ties(v, np.zeros((3, 1)))) == [0, 1, 2]     # all equal: given order
    with pytest.raises(ValueError, match="NaN"):
        S.rank_with_ties([1.0, np.nan])
    with pytest.raises(ValueError, match="3 keys for 2 values"):
        S.rank_with_ties([1.0, 2.0], np.zeros((3, 1)))
    with pytest.raises(ValueError, match="rtol"):
        S.rank_with_ties([1.0], rtol=-1.0)


def test_ties_is_one_symmetric_rule_with_a_relative_and_an_absolute_part():
    # relative part: 1e-9 of the larger magnitude, whichever argument it is
    assert S.ties(1.0, 1.0 + 0.9e-9) and S.ties(1.0 + 0.9e-9, 1.0)
    assert not S.ties(1.0, 1.0 + 1.1e-9) and not S.ties(1.0 + 1.1e-9, 1.0)
    # absolute part decides near zero: TIE_ABS is the floating-point resolution of an index
    assert S.TIE_ABS == S.FLOAT_NOISE and S.ties(0.0, 0.9e-11) and not S.ties(0.0, 1.1e-11)
    assert S.ties([1.0, 2.0], [1.0, 2.5], rtol=0.1).tolist() == [True, False]
    assert not S.ties(1.0, 1.0 + 1e-15, rtol=0.0, atol=0.0) and S.ties(3.0, 3.0, rtol=0, atol=0)
    for bad in (-1.0, np.nan, np.inf, True):
        with pytest.raises(ValueError, match="rtol must be a finite number >= 0"):
            S.ties(1.0, 1.0, rtol=bad)
    with pytest.raises(ValueError, match="atol must be a finite number >= 0"):
        S.merge_ties([1.0], atol=-1e-3)


def test_ties_are_anchored_at_the_first_of_the_group_not_chained():
    """Three values 0.6e-6 apart with a tolerance of 1e-6: the first and last do not tie, so
    they are not one group, although each ties with its neighbour (a chained rule would merge
    all three).  The group starts at the first value in rank order: the largest for
    merge_ties (indices, descending), the smallest for rank_with_ties (misfits, ascending)."""
    v = np.array([1.0, 1.0 + 6e-7, 1.0 + 1.2e-6])
    merged = S.merge_ties(v, rtol=1e-6, atol=0.0)
    assert merged.tolist() == [v[0], v[2], v[2]]          # 1+1.2e-6 and 1+6e-7, then 1 alone
    order = S.rank_with_ties(v, [[2.0], [1.0], [0.0]], rtol=1e-6)
    assert order.tolist() == [1, 0, 2]                     # 1 and 1+6e-7, then 1+1.2e-6 alone


@pytest.mark.parametrize("seed", range(5))
def test_merge_ties_and_rank_with_ties_find_the_same_groups(seed):
    """A cross-check of the two users of the rule: the groups merge_ties forms (sorted
    descending) are the groups rank_with_ties forms on the negated values (sorted ascending)."""
    rng = np.random.default_rng(seed)
    v = np.repeat(rng.uniform(0, 1, 6), 3) * (1 + rng.uniform(-1, 1, 18) * 2e-9)
    groups = {}
    for i, m in enumerate(S.merge_ties(v)):
        groups.setdefault(m, []).append(i)
    order = S.rank_with_ties(-v, np.arange(v.size), rtol=S.TIE_REL, atol=S.TIE_ABS)
    # within a group rank_with_ties orders by the key (the index): the merged groups in order
    want = [i for m in sorted(groups, reverse=True) for i in groups[m]]
    assert order.tolist() == want and len(groups) < v.size


def test_functions_with_more_than_three_parameters_take_keywords_after_the_data():
    with pytest.raises(TypeError):
        S.key_errors([0.5, 0.5], ["a", "b"])
    with pytest.raises(TypeError):
        S.key_errors_by_output(np.ones((2, 1)), ["a", "b"])
    with pytest.raises(TypeError):
        S.key_set_bootstrap(np.ones((1, 2, 1)), ["a", "b"])
    with pytest.raises(TypeError):
        S.threshold_sweep(np.ones((2, 1)), np.ones((3, 2)), lambda v: v, [0.9])
    with pytest.raises(TypeError):
        S.rank_with_ties([1.0, 2.0], None, 0.1)
    with pytest.raises(TypeError):
        S.merge_ties([1.0, 2.0], 0.1)


def test_tie_rule_lives_in_tie_rule_and_sobol_does_not_import_it():
    import mtaccuracy.sensitivity.screening as screening
    import mtaccuracy.sensitivity.sobol as sobol
    import mtaccuracy.sensitivity.tie_rule as tie_rule

    assert S.merge_ties is tie_rule.merge_ties is screening.merge_ties
    assert S.ties is tie_rule.ties and S.rank_with_ties is tie_rule.rank_with_ties
    assert not hasattr(sobol, "merge_ties") and not hasattr(sobol, "TIE_REL")


def test_simplification_rate_checks_through_validate():
    with pytest.raises(ValueError, match=r"n_key must be an integer in \[0, 21\], got 2.5"):
        S.simplification_rate(2.5, 21)
    with pytest.raises(ValueError, match="n_total must be an integer >= 1, got True"):
        S.simplification_rate(0, True)
    assert S.simplification_rate(np.int64(3), 6.0) == 0.5
    with pytest.raises(ValueError, match="threshold must be a share"):
        S.cumulative_share_margin(np.ones(3), 1.0)


# --- one result shape: the key sets and their bootstrap frequencies, labelled --------------------

def test_key_sets_tabulate_with_their_values_and_cumulative_shares():
    st = np.array([[0.15, 0.1], [0.5, 0.2], [0.05, 0.6], [0.3, 0.1]])
    sets = S.key_errors_by_output(st, names=NAMES, outputs=["f", "g"], threshold=0.9)
    assert isinstance(sets, dict) and list(sets) == ["f", "g"]          # a dict, as before
    assert sets.union() == S.union_key_set(sets, NAMES)
    df = sets.to_df()
    assert list(df.columns) == ["output", "rank", "input", "position", "value",
                                "cumulative_share"]
    f = df[df.output == "f"]
    assert f.input.tolist() == ["b", "d", "a"] and f.position.tolist() == [1, 3, 0]
    assert f.value.tolist() == [0.5, 0.3, 0.15]
    # the shares are the cumulative sums of the sorted indices over their total, bitwise
    assert np.array_equal(f.cumulative_share, np.cumsum(st[[1, 3, 0], 0]) / st[:, 0].sum())
    assert f.cumulative_share.iloc[-1] == sets["f"].share


def test_key_set_bootstrap_unpacks_as_before_and_tabulates_its_frequencies():
    rng = np.random.default_rng(3)
    boot = np.abs(np.array([[0.5, 0.3, 0.15, 0.05]]).T[None] + 0.05 * rng.standard_normal(
        (50, 4, 1)))
    res = S.key_set_bootstrap(boot, names=NAMES, threshold=0.9)
    freq, counts = res
    assert res.freq is freq and res.counts is counts and res.to_df().equals(freq)
    assert len(counts) == 50 and freq.symbol.tolist() == NAMES
