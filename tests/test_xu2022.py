"""Audit checks of notebook 04 (Xu et al. 2022): can one partition of the sensors produce the
printed per-position sensitive points (Table 3) under the paper's rule of Section 1.1?"""

import itertools

import numpy as np
import pytest

from mtaccuracy.compendium import reproduction, xu2022

SENSORS = [f"T{i}" for i in range(1, 13)]


def _table3():
    t3 = reproduction.published("xu2022_table3_sensitive_points", ["position_mm", "sensors"])
    return t3.position_mm.astype(float).tolist(), [s.split() for s in t3.sensors]


def _fits_by_hand(rows, labels):
    """Independent formulation: a row fits when the set of its sensors' labels is every label."""
    n = len(rows[0])
    return [sorted({labels[s] for s in r}) == list(range(n)) and len(r) == n for r in rows]


def test_partition_fits_agrees_with_a_plain_enumeration():
    rng = np.random.default_rng(7)
    sensors = ["a", "b", "c", "d", "e", "f"]
    rows = [list(rng.choice(sensors, 3, replace=False)) for _ in range(5)]
    fits = xu2022.partition_fits(rows, sensors, 3)
    assert fits.shape == (3 ** 6, 5)
    for a, labels in enumerate(itertools.product(range(3), repeat=6)):
        # assignment a gives sensor s the label (a // 3**s) % 3: itertools varies the last fastest
        by_sensor = dict(zip(sensors, labels[::-1], strict=True))
        assert fits[a].tolist() == _fits_by_hand(rows, by_sensor)


def test_rows_made_from_one_partition_are_all_produced():
    clusters = [["T1", "T2", "T3", "T4", "T5", "T8", "T9", "T10"], ["T6", "T11"], ["T7", "T12"]]
    rows = [list(t) for t in itertools.product(*clusters)][::7]
    out = xu2022.table3_consistency(rows, SENSORS, 3)
    assert out["best"] == len(rows) and out["conflict"] == []
    assert out["best_assignments"] == 6 * out["best_partitions"] >= 6
    assert all(xu2022.rows_fitted_by(rows, clusters))
    assert not any(xu2022.rows_fitted_by(rows, [clusters[0] + clusters[1], clusters[2], []]))


def test_no_partition_produces_the_printed_table3():
    """Hand check: 285 mm {T1 T11 T12} puts T1, T11, T12 in three clusters; 225 mm {T1 T7 T11}
    then puts T7 in T12's; 245 mm {T4 T7 T12} needs T7 and T12 apart. Dropping 245 mm leaves
    T1 T2 T4 | T6 T11 | T7 T12 forced and T3 T5 T8 T9 T10 free: 3**5 partitions."""
    positions, rows = _table3()
    out = xu2022.table3_consistency(rows, SENSORS, 3)
    assert out["assignments"] == 3 ** 12
    assert out["best"] == len(rows) - 1 == 13
    assert out["best_partitions"] == 3 ** 5 and out["best_assignments"] == 6 * 3 ** 5
    missed = [p for p, m in zip(positions, out["missed"], strict=True) if m]
    assert missed == [245.0] and out["missed"][positions.index(245.0)] == out["best_assignments"]
    assert [positions[i] for i in out["conflict"]] == [225.0, 245.0, 285.0]
    assert out["best_partition"][0][:3] == ["T1", "T2", "T4"]
    assert any({"T6", "T11"} <= set(g) for g in out["best_partition"][1:])


def test_table6_partition_for_b_is_one_of_the_best():
    _, rows = _table3()
    b = [["T1", "T2", "T3", "T4", "T5", "T8", "T9", "T10"], ["T6", "T11"], ["T7", "T12"]]
    fitted = xu2022.rows_fitted_by(rows, b)
    assert sum(fitted) == 13 and fitted.index(False) == 3


@pytest.mark.parametrize("rows, match", [([["T1", "T2"]], "needs 3 different"),
                                         ([["T1", "T1", "T2"]], "needs 3 different"),
                                         ([["T1", "T2", "T99"]], "unknown")])
def test_bad_rows_are_refused(rows, match):
    with pytest.raises(ValueError, match=match):
        xu2022.partition_fits(rows, SENSORS, 3)


def test_too_many_assignments_are_refused():
    with pytest.raises(ValueError, match="assignments"):
        xu2022.partition_fits([["a", "b", "c"]], [f"s{i}" for i in range(20)], 3)
