"""The study helpers notebook 05 calls (issue 15 item 4: the maths out of the notebook)."""

from types import SimpleNamespace

import numpy as np
import pytest

from mtaccuracy import spindle as SP


def test_rank_check_of_the_symmetric_layout_finds_the_odd_harmonics_cancelled():
    n = 64
    pos = [0, 16, 32, 48]
    phi = SP.probe_angles(pos, n)
    w = SP.full_weights(phi[1:], 0.5)
    r = np.random.default_rng(0).standard_normal(n)
    rank, sv, s, warned = SP.rank_check(pos, phi[1:], w, r, rtol=1e-9, roundoff=1e-12)
    assert rank == n // 2                               # every odd k vanishes (a3 != +-1)
    assert sv[0] > 0 and np.all(np.diff(sv) <= 1e-12 * sv[0])
    assert list(s.cancelled) == list(range(1, n // 2, 2)) and warned


def test_rank_check_refuses_a_threshold_below_round_off():
    n = 64
    pos = [0, 16, 32, 48]
    phi = SP.probe_angles(pos, n)
    r = np.random.default_rng(0).standard_normal(n)
    with pytest.raises(RuntimeError, match="expected round-off below 1e-30"):
        SP.rank_check(pos, phi[1:], SP.full_weights(phi[1:], 0.5), r, rtol=1e-9,
                      roundoff=1e-30)


def test_convergence_statistics_of_hand_made_histories():
    hist = np.array([[1.0, 1.0, 1.0], [0.5, 1.0, 0.8], [0.3, 0.9, 0.3], [0.3, 0.9, 0.3]])
    res = SimpleNamespace(history=hist, best_h=hist[-1], label="toy", evaluations_per_generation=4)
    st = SP.convergence_statistics(res, name="toy", h_ref=0.3, rel_tol=0.01)
    assert st["reached_fraction"] == pytest.approx(2 / 3)   # runs 0 and 2 reach 0.3 at gen 2
    assert st["reached_median"] == 2.0
    assert st["plateau_median"] == 2.0                      # each run's own final value
    assert st["final_H_best"] == 0.3 and st["final_H_worst"] == 0.9
    never = SP.convergence_statistics(res, name="toy", h_ref=0.01, rel_tol=0.01)
    assert never["reached_fraction"] == 0 and np.isnan(never["reached_median"])


def test_speedup_and_its_bootstrap_standard_error():
    fast, slow = np.full(20, 50.0), np.full(20, 100.0)
    assert SP.speedup(fast, slow) == pytest.approx(50.0)
    rng = np.random.default_rng(1)
    assert SP.bootstrap_se(SP.speedup, fast, slow, rng=rng) == pytest.approx(0.0, abs=1e-12)
    noisy = np.random.default_rng(2).normal(100, 10, 200)
    se = SP.bootstrap_se(lambda x, axis: np.median(x, axis=axis), noisy, rng=rng)
    assert 0.3 < se < 1.5                  # sd of a median ~ 1.25 * 10 / sqrt(200) = 0.9


def test_separation_statistics_of_a_known_circle_and_motion():
    n = 240                         # a multiple of 12: the extremes of cos 3t and sin t are samples
    t = 2 * np.pi * np.arange(n) / n
    profile = np.stack([1e-3 * np.cos(3 * t), 1.1e-3 * np.cos(3 * t)])     # mm, two runs
    sep = SimpleNamespace(profile=profile, dx=np.zeros((2, n)), dy=np.zeros((2, n)))
    st = SP.separation_statistics(sep, lambda dx, dy: dx + 2e-3 * np.sin(t))
    assert st["mz_mean_um"] == pytest.approx(2.1, rel=1e-6)                # peak-to-valley
    assert st["lsc_mean_um"] == pytest.approx(2.1, rel=1e-6)
    assert st["repeatability_percent"] == pytest.approx(100 * np.std([2.0, 2.2], ddof=1) / 2.1)
    assert st["rotation_error_pv_mean_um"] == pytest.approx(4.0, rel=1e-9)
