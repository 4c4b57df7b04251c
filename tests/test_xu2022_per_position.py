"""Table 3 under Section 3.1's per-position reading (xu2022.per_position): each position's error
joins the fuzzy clustering of the temperatures.  Checked against a plain per-position loop over
the library's Eqs. 1-3, an analytic case, the structure every dataset must show, and the
constructive example that reproduces the printed Table 3."""

import numpy as np
import pandas as pd
import pytest

from mtaccuracy import thermal
from mtaccuracy.papers import printed, xu2022

SENSORS = [f"T{i}" for i in range(1, 13)]


def _machine(seed=3, n_pos=6):
    """Our own warm-up model: 12 first-order nodes (time constants 10-200 min, gains 0.5-6 K)
    over three runs of 8 readings, plus a drifting air; the error at each position a
    position-dependent mix of three nodes' expansion and a bow, with 0.2 um noise."""
    rng = np.random.default_rng(seed)
    t = np.tile(np.linspace(0.0, 160.0, 8), 3)
    run = np.repeat(np.arange(3), 8)
    tau = rng.uniform(10.0, 200.0, 12)
    gain = rng.uniform(0.5, 6.0, 12) * (1.0 + 0.3 * run[:, None])
    rises = gain * (1.0 - np.exp(-t[:, None] / tau))
    rises[:, 9] = 0.8 * np.sin(t / 60.0 + run)           # the air: no warm-up
    rises += rng.normal(0.0, 0.02, rises.shape)
    x = np.linspace(0.0, 1.0, n_pos)
    errors = (-4.0 * x[None] * rises[:, [0]] - 1.5 * (1 - x[None]) * rises[:, [10]]
              + 0.8 * x[None] ** 2 * rises[:, [11]] + rng.normal(0.0, 0.2, (len(t), n_pos)))
    return pd.DataFrame(rises, columns=SENSORS), errors


def _by_hand(x, y, n):
    """Independent formulation: the library's Eqs. 1-3 on the 13 columns of one position, then
    the highest level (of the closure's own, merged as cut_levels does) giving the temperatures
    exactly n classes."""
    t, _ = thermal.transitive_closure(thermal.similarity_matrix(np.column_stack([x, y])))
    for lam in thermal.cut_levels(t):                       # highest level first
        labels = thermal.lambda_cut(t[:-1, :-1], lam)
        if labels.max() + 1 == n:
            return lam, labels
    raise AssertionError("no level gives n classes")


def test_batched_clustering_equals_a_loop_over_positions():
    temps, errors = _machine()
    out = xu2022.per_position_clusters(temps.to_numpy(), errors, n_clusters=3)
    assert out["labels"].shape == (errors.shape[1], 12)
    for p in range(errors.shape[1]):
        lam, labels = _by_hand(temps.to_numpy(), errors[:, p], 3)
        assert out["lam"][p] == pytest.approx(lam, rel=1e-12)
        assert out["labels"][p].tolist() == labels.tolist()


def test_an_error_that_copies_a_sensor_leaves_the_shared_partition():
    """Eq. 1 is blind to shift and scale: an error equal to 3 * T5 - 2 duplicates T5 and links
    nothing new, so every position's classes are the shared fuzzy_clusters classes."""
    temps, _ = _machine()
    x = temps.to_numpy()
    errors = np.column_stack([3.0 * x[:, 4] - 2.0, -0.5 * x[:, 0], 7.0 * x[:, 11]])
    out = xu2022.per_position_clusters(x, errors, n_clusters=3)
    shared = thermal.fuzzy_clusters(x, SENSORS, 3)
    for p in range(3):
        assert out["labels"][p].tolist() == shared.labels.tolist()
        assert out["lam"][p] == pytest.approx(shared.lam, rel=1e-12)


def test_every_position_merges_classes_of_the_shared_hierarchy():
    """What must hold on every dataset: at its cut, a position's classes are the temperatures'
    own classes at that level, with those the error touches merged into one."""
    for seed in range(4):
        temps, errors = _machine(seed, n_pos=8)
        x = temps.to_numpy()
        out = xu2022.per_position_clusters(x, errors, n_clusters=3)
        base_t, _ = thermal.transitive_closure(thermal.similarity_matrix(x))
        for p in range(errors.shape[1]):
            base = thermal.lambda_cut(base_t, out["lam"][p] * (1 - thermal.LEVEL_RTOL))
            mine = out["labels"][p]
            # every shared class lies inside one class of the position
            assert all(len(set(mine[base == c])) == 1 for c in set(base))
            # at most one class of the position holds more than one shared class
            assert sum(len(set(base[mine == c])) > 1 for c in set(mine)) <= 1


def test_the_constructed_example_gives_the_printed_table3():
    t3 = printed.published("xu2022_table3_sensitive_points", ["position_mm", "sensors"])
    rows = [s.split() for s in t3.sensors]
    temps, errors = xu2022.witness(rows, SENSORS)
    sel = xu2022.per_position_selections(temps, errors, n_clusters=3)
    assert [sorted(s.selected) for s in sel] == [sorted(r) for r in rows]
    # and one shared partition cannot (the shared reading's check, on the same rows)
    assert xu2022.table3_consistency(rows, SENSORS, 3)["best"] < len(rows)


def test_the_constructed_example_gives_any_rows():
    rng = np.random.default_rng(11)
    names = [f"s{i}" for i in range(7)]
    rows = [list(rng.choice(names, 2, replace=False)) for _ in range(10)]
    temps, errors = xu2022.witness(rows, names, block=3)
    sel = xu2022.per_position_selections(temps, errors, n_clusters=2)
    assert [sorted(s.selected) for s in sel] == [sorted(r) for r in rows]


def test_bad_input_is_refused_with_the_reason():
    temps, errors = _machine()
    x = temps.to_numpy()
    with pytest.raises(ValueError, match="same n"):
        xu2022.per_position_clusters(x, errors[:-1], n_clusters=3)
    flat = errors.copy()
    flat[:, 2] = 1.0
    with pytest.raises(ValueError, match=r"error column\(s\) \[2\] are constant"):
        xu2022.per_position_clusters(x, flat, n_clusters=3)
    with pytest.raises(ValueError, match="n_clusters"):
        xu2022.per_position_clusters(x, errors, n_clusters=13)
    with pytest.raises(ValueError, match="different sensors"):
        xu2022.witness([["T1", "T1", "T2"]], SENSORS)
    with pytest.raises(ValueError, match="at least 5"):
        xu2022.witness([["T1", "T2", "T3"]], SENSORS[:4])
