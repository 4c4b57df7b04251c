"""Four-point separation, transfer function, bound of H, GAs, roundness (Yang et al. 2021)."""

import warnings

import numpy as np
import pytest
import scipy.linalg

from mtaccuracy import spindle as S
from mtaccuracy.optimise import ga

N = 128
POS = [0, 14, 65, 116]


def _layout(rng, n=N):
    """A random layout on the sampling grid with weights from Eq. 15 (well away from degenerate)."""
    while True:
        p = np.r_[0, np.sort(rng.choice(np.arange(1, n), 3, replace=False))]
        phi = S.probe_angles(p, n)
        if abs(np.sin(phi[2] - phi[1])) > 0.2:
            w = S.full_weights(phi, rng.uniform(0.3, 2.0))
            lam = np.abs(S.eigenvalues(phi, w, np.arange(n)))
            lam[[1, n - 1]] = np.inf
            if lam.min() > 1e-3:          # no harmonic but the first cancelled
                return p, phi, w


def _motion_without_fundamental(rng, n=N):
    t = 2 * np.pi * np.arange(n) / n
    z = rng.standard_normal(n) + 1j * rng.standard_normal(n)
    z -= (z * np.exp(1j * t)).mean() * np.exp(-1j * t)
    return z.real, z.imag


def test_weights_cancel_the_first_harmonic_and_match_eq5():
    rng = np.random.default_rng(1)
    phi = rng.uniform(0, 2 * np.pi, (50, 3))
    a3 = rng.uniform(-2, 2, 50)
    w = S.full_weights(phi, a3)
    lam1 = S.eigenvalues(phi, w, [1])[:, 0]
    assert np.abs(lam1).max() < 1e-10
    # Eq. 5 written with sample positions p, for the paper's layout
    p1, p2, p3 = POS[1:]
    a1 = (1.953 * np.sin(2 * np.pi * (p3 - p2) / N) - np.sin(2 * np.pi * p2 / N)) \
        / np.sin(2 * np.pi * (p2 - p1) / N)
    a2 = -(1.953 * np.sin(2 * np.pi * (p3 - p1) / N) - np.sin(2 * np.pi * p1 / N)) \
        / np.sin(2 * np.pi * (p2 - p1) / N)
    assert np.allclose(S.weights(S.probe_angles(POS, N), 1.953), (a1, a2), atol=1e-14)


@pytest.mark.parametrize("trial", range(5))
def test_exact_separation_of_random_profiles_and_motions(trial):
    """Noise-free: profile (all harmonics) and a motion without the workpiece-synchronous
    fundamental come back to round-off, for random layouts, batched."""
    rng = np.random.default_rng(100 + trial)
    p, phi, w = _layout(rng)
    r = rng.standard_normal((3, N))
    dxy = np.array([_motion_without_fundamental(rng) for _ in range(3)])
    y = S.probe_signals(r, dxy[:, 0], dxy[:, 1], p)
    prof, dx, dy = S.separate(y, phi, w)
    scale = np.abs(r).max()
    assert np.abs(prof - r).max() < 1e-10 * scale
    assert np.abs(dx - dxy[:, 0]).max() < 1e-10 * scale
    assert np.abs(dy - dxy[:, 1]).max() < 1e-10 * scale


def test_radial_convention_recovers_a_radial_motion_and_the_first_harmonic():
    rng = np.random.default_rng(7)
    p, phi, w = _layout(rng)
    t = 2 * np.pi * np.arange(N) / N
    r = rng.standard_normal(N) + 1.2 * np.cos(t) - 0.8 * np.sin(t)
    delta = rng.standard_normal(N) + 1.3
    dx, dy, back = S.motion_from_scalar(delta, "radial")
    s = S.separate_details(S.probe_signals(r, dx, dy, p), phi, w, first_harmonic="radial")
    assert np.abs(s.profile - r).max() < 1e-10
    assert np.abs(back(s.dx, s.dy) - delta).max() < 1e-10
    assert np.allclose(S.rotation_error(s.dx, s.dy), delta, atol=1e-10)
    # the eccentricity convention moves the exp(-i theta) part of this motion into the profile,
    # and the sum of what the probes see is unchanged
    e = S.separate_details(S.probe_signals(r, dx, dy, p), phi, w)
    assert np.abs(e.profile - r).max() > 1e-3
    assert np.allclose(S.probe_signals(e.profile, e.dx, e.dy, p),
                       S.probe_signals(r, dx, dy, p), atol=1e-10)


def test_the_matrix_has_rank_n_minus_2_and_lstsq_equals_the_fft_solution():
    phi = S.probe_angles(POS, N)
    w = S.full_weights(phi, 1.953)
    a = S.circulant_matrix(POS, w, N)
    assert np.linalg.matrix_rank(a) == N - 2
    assert np.allclose(np.sort(np.abs(np.linalg.eigvals(a))),
                       np.sort(np.abs(S.eigenvalues(phi, w, np.arange(N)))), atol=1e-9)
    rng = np.random.default_rng(3)
    y = S.probe_signals(rng.standard_normal(N), *_motion_without_fundamental(rng), POS)
    s = S.separate_details(y, phi, w)
    assert s.rank == N - 2 and list(s.cancelled) == [1]
    ls = scipy.linalg.lstsq(a, w @ y, cond=1e-9)[0]
    assert np.abs(ls - s.profile_no_first).max() < 1e-10
    # a symmetric layout cancels every odd harmonic: rank N/2
    sym = S.probe_angles([0, 32, 64, 96], N)
    ws = S.full_weights(sym, 1.3)
    assert np.linalg.matrix_rank(S.circulant_matrix([0, 32, 64, 96], ws, N)) == N // 2
    with pytest.warns(S.CancelledHarmonicsWarning, match="every odd one"):
        ss = S.separate_details(S.probe_signals(rng.standard_normal(N), 0 * y[0], 0 * y[0],
                                                [0, 32, 64, 96]), sym, ws, allow_cancelled=True)
    assert list(ss.cancelled) == list(range(1, N // 2, 2))


def _half_circle_layout():
    """Probe 3 at 180 degrees with a3 = 1: Eq. 15 gives a1 = a2 = 0, and the weights (1, 0, 0, 1)
    cancel every odd harmonic, Lambda_k = 1 + (-1)^k."""
    pos = [0, 20, 50, N // 2]
    phi = S.probe_angles(pos, N)
    w = S.full_weights(phi, 1.0)
    assert np.allclose(w, [1, 0, 0, 1], atol=1e-12)
    return pos, phi, w


def test_separate_refuses_a_layout_that_cancels_more_than_the_first_harmonic():
    pos, phi, w = _half_circle_layout()
    rng = np.random.default_rng(21)
    r = rng.standard_normal(N)
    y = S.probe_signals(r, *_motion_without_fundamental(rng), pos)
    with pytest.raises(ValueError, match=r"cancels harmonic\(s\) 3, 5, 7, 9, .*63 \(31 harmonics; "
                                         r"every odd one\).*allow_cancelled=True"):
        S.separate(y, phi, w)
    with pytest.raises(ValueError, match="cancels harmonic"):
        S.separate_details(y, phi, w, first_harmonic="radial")


def test_separate_proceeds_on_request_with_a_warning_naming_the_cancelled_harmonics():
    pos, phi, w = _half_circle_layout()
    rng = np.random.default_rng(22)
    r = rng.standard_normal(N)
    y = S.probe_signals(r, 0 * r, 0 * r, pos)
    with pytest.warns(S.CancelledHarmonicsWarning, match=r"3, 5, 7, .*63 \(31 harmonics"):
        s = S.separate_details(y, phi, w, allow_cancelled=True)
    assert list(s.cancelled) == list(range(1, N // 2, 2)) and s.rank == N // 2
    spec = np.fft.rfft(r)
    spec[1::2] = 0                                   # what is left: the even harmonics
    assert np.abs(s.profile_no_first - np.fft.irfft(spec, n=N)).max() < 1e-12
    # harmonics above what the signals contain are no loss: a layout cancelling only those is
    # accepted without a word when max_harmonic says so.  With every position even, harmonic
    # N/2 - 1 aliases to -1: Lambda_63 = conj(Lambda_1) = 0 whatever a3.
    p2 = [0, 2, 24, 118]
    ph2 = S.probe_angles(p2, N)
    w2 = S.full_weights(ph2, 1.4173)
    r2 = S.lowpass(rng.standard_normal(N), 50)
    y2 = S.probe_signals(r2, 0 * r2, 0 * r2, p2)
    with pytest.raises(ValueError, match=r"harmonic\(s\) 63 besides the first"):
        S.separate(y2, ph2, w2)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        prof, _, _ = S.separate(y2, ph2, w2, max_harmonic=50)
    assert np.abs(S.lowpass(prof, 50) - r2).max() < 1e-9


def test_transfer_function_predicts_the_noise_of_the_harmonics():
    rng = np.random.default_rng(11)
    phi = S.probe_angles(POS, N)
    w = S.full_weights(phi, 1.953)
    sigma, m = 0.3, 4000
    y = rng.standard_normal((m, 4, N)) * sigma
    s = S.separate_details(y, phi, w)
    ks = np.array([2, 5, 20, 40])
    a_k, b_k = S.harmonic_coefficients(s.profile_no_first, ks)
    pred = 2 * S.transfer(phi, w, ks) * sigma ** 2 / N          # Eq. 18 with its 1/N
    assert np.allclose(a_k.var(axis=0), pred, rtol=0.1)
    assert np.allclose(b_k.var(axis=0), pred, rtol=0.1)
    assert np.isinf(S.transfer(phi, w, [1])[0])


def test_lower_bound_of_h_holds_and_is_reached_at_even_k():
    rng = np.random.default_rng(5)
    x = np.column_stack([rng.uniform(0, 2 * np.pi, (20000, 3)), rng.uniform(-3, 3, 20000)])
    for k in (2, 3, 7, 20, 41):
        assert S.objective_H(x, k).min() >= S.lower_bound_H(4) - 1e-12
    for k in (2, 10, 20, 80):
        assert S.objective_H(S.bound_layout(k), k) == pytest.approx(0.25, abs=1e-12)
    # odd k: the bound is not reached (numerical optimum stays above 1/4)
    h3, _ = S.reference_optimum(3, bounds=S.FULL_BOX, n_starts=1)
    assert h3 > 0.27
    with pytest.raises(ValueError, match="even k"):
        S.bound_layout(7)


def test_weights_only_bound_holds_for_every_angle_and_is_reached_in_phase():
    rng = np.random.default_rng(12)
    w = rng.uniform(-4, 4, (200, 3))                       # a1..a3, any signs, no Eq. 15
    phi = rng.uniform(0, 2 * np.pi, (200, 500, 3))         # 500 random angle sets per weight set
    ks = np.array([2, 3, 10, 20, 41, 80])
    q2 = S.transfer(phi, np.broadcast_to(w[:, None], phi.shape), ks)
    bound = S.weights_bound_H(w)
    assert np.all(q2 >= bound[:, None, None] * (1 - 1e-12))
    assert np.all(bound >= S.lower_bound_H(4) - 1e-15)
    # reached when every a_l exp(i k phi_l) has one phase: k phi_l = 0 (a_l > 0) or pi (a_l < 0)
    k = 20
    phi_eq = (2 * np.pi * rng.integers(1, k, (200, 3)) + np.pi * (w < 0)) / k
    assert np.allclose(S.transfer(phi_eq, w, [k])[:, 0], bound, rtol=1e-9)
    # hand value: a = (1, 1, 1, 2): 7 / 25
    assert S.weights_bound_H([1.0, 1.0, 2.0]) == pytest.approx(7 / 25)
    # a0..a3 given explicitly gives the same; signs do not matter
    assert S.weights_bound_H([1.0, -1.0, 1.0, 2.0]) == pytest.approx(7 / 25)


def test_weights_only_bound_covers_every_weight_within_rounding():
    rng = np.random.default_rng(13)
    centre = np.array([2.430, 3.82, 1.39])
    half = np.array([5e-4, 5e-3, 5e-3])
    box_bound = S.weights_bound_H(centre, half)
    inside = centre + rng.uniform(-1, 1, (20000, 3)) * half
    assert np.all(S.weights_bound_H(inside) >= box_bound)
    assert box_bound < S.weights_bound_H(centre) < box_bound + 0.01
    # an interval containing 0 contributes nothing to sum a^2 (m_l = 0)
    assert S.weights_bound_H([0.001, 1.0, 1.0], [0.01, 0, 0]) == pytest.approx(3 / 3.011 ** 2)
    with pytest.raises(ValueError, match="last axis"):
        S.weights_bound_H([1.0, 2.0])
    with pytest.raises(ValueError, match=">= 0"):
        S.weights_bound_H([1.0, 2.0, 3.0], [-1e-3, 0, 0])


def test_optimal_a3_matches_a_scan():
    rng = np.random.default_rng(2)
    phi = rng.uniform(0, 2 * np.pi, (20, 3))
    a3, h = S.optimal_a3(phi, 12, (0.1, 3.0))
    grid = np.linspace(0.1, 3.0, 20001)
    hs = S.objective_H(np.concatenate([np.repeat(phi[:, None], grid.size, 1),
                                       np.broadcast_to(grid[None, :, None], (20, grid.size, 1))],
                                      -1), 12)
    assert np.all(h <= hs.min(axis=1) + 1e-9)
    assert np.allclose(h, hs.min(axis=1), rtol=1e-4)


def test_worst_case_bound_for_grid_layouts():
    rng = np.random.default_rng(9)
    n = 64
    for _ in range(200):
        p = np.r_[0, rng.choice(np.arange(1, n), 3, replace=False)]
        phi = S.probe_angles(p, n)
        if abs(np.sin(phi[2] - phi[1])) < 1e-6:
            continue
        q2 = S.transfer(phi, S.full_weights(phi, rng.uniform(-2, 2)), np.arange(2, n - 1))
        assert q2.max() >= S.worst_case_bound(n) - 1e-12


#: The paper's bounds of the adaptive rates (Section 2.2), as notebook 05 passes them.
PAPER_RATES = dict(pc_max=S.PC_MAX, pc_min=S.PC_MIN, pm_max=S.PM_MAX, pm_min=S.PM_MIN)


def _rates(f, generation, max_generation=200, **kw):
    return ga.adaptive_rates(f, 1.0, generation=generation, max_generation=max_generation,
                             **PAPER_RATES, **kw)


def test_adaptive_rates_with_the_papers_bounds_follow_eqs_22_23():
    assert (S.PC_MAX, S.PC_MIN, S.PM_MAX, S.PM_MIN) == (0.99, 0.4, 0.09, 0.005)
    f = np.array([0.5, 1.0, 2.0])
    pc, pm = _rates(f, 50)
    assert np.allclose(pc, [0.99, 0.99 - 0.59 * 0.25, 0.99 - 0.59 * 0.25])
    assert np.allclose(pm, [0.005, 0.005 + 0.085 * 0.25, 0.005 + 0.085 * 0.25])
    pc0, pm0 = _rates(f, 0)
    pc1, pm1 = _rates(f, 200)
    assert np.allclose(pc0, 0.99) and np.allclose(pm0, 0.005)
    assert np.allclose(pc1, [0.99, 0.4, 0.4]) and np.allclose(pm1, [0.005, 0.09, 0.09])
    # printed Eq. 23: falls from 0.005, negative for the fit individuals once alpha / alpha_max >
    # 0.005 / 0.085, i.e. from generation 12 of 200 on
    _, pmp = _rates(f, 50, eq23="printed")
    assert pmp[0] == pytest.approx(0.005) and np.all(pmp[1:] < 0)
    assert np.all(_rates(f, 11, eq23="printed")[1] > 0)
    assert np.all(_rates(f, 12, eq23="printed")[1][1:] < 0)


def test_printed_eq23_over_a_whole_run_turns_negative_at_generation_12_as_notebook_05_prints():
    """Notebook 05 evaluates Eq. 23 as printed for an above-average individual at every
    generation in one call (``generation`` an array); it must equal the generation-by-generation
    values exactly, and turn negative where the analytic threshold says."""
    alpha = np.arange(201)
    _, pm = ga.adaptive_rates(1.0, 0.0, generation=alpha, max_generation=200, eq23="printed",
                              **PAPER_RATES)
    one_by_one = [ga.adaptive_rates(1.0, 0.0, generation=int(a), max_generation=200,
                                    eq23="printed", **PAPER_RATES)[1] for a in alpha]
    assert pm.shape == (201,) and np.array_equal(pm, np.array(one_by_one))
    first_negative = int(alpha[pm < 0][0])
    threshold = 200 * S.PM_MIN / (S.PM_MAX - S.PM_MIN)     # alpha / alpha_max > Pm_min / range
    assert first_negative == int(np.floor(threshold)) + 1 == 12
    _, corrected = ga.adaptive_rates(1.0, 0.0, generation=alpha, max_generation=200,
                                     **PAPER_RATES)
    assert np.all(np.diff(corrected) > 0) and corrected[-1] == pytest.approx(S.PM_MAX)


def test_ga_runs_are_batched_reproducible_and_use_the_probabilities():
    kw = dict(n_runs=6, pop_size=20, generations=30, seed=4)
    a = S.run_ga(20, **kw)
    b = S.run_ga(20, **kw)
    assert np.array_equal(a.history, b.history) and a.history.shape == (31, 6)
    assert np.all(np.diff(a.history, axis=0) <= 0)          # elitism: best-so-far never worsens
    assert np.allclose(S.objective_H(a.best_x, 20), a.best_h)
    assert np.all(a.best_h >= 0.25)
    lo, hi = np.array(S.PAPER_BOX).T
    assert np.all((a.best_x >= lo) & (a.best_x <= hi))
    # the mean rates used: Pc falls from 0.99, Pm rises from 0.005 (corrected Eq. 23)
    assert a.pc[1] > a.pc[-1] and a.pm[-1] > a.pm[1] and a.pm.max() <= 0.09 + 1e-12
    t = S.run_ga(20, adaptive=False, pc=0.7, pm=0.02, encoding="real", **kw)
    assert np.allclose(t.pc[1:], 0.7) and np.allclose(t.pm[1:], 0.02)
    per_run_k = S.run_ga(np.array([4, 4, 4, 10, 10, 10]), **kw)
    assert per_run_k.best_h.shape == (6,)


def test_equivalent_layouts_share_the_objective_and_the_canonical_member():
    rng = np.random.default_rng(31)
    x = np.column_stack([rng.uniform(0, 2 * np.pi, (40, 3)), rng.uniform(0.2, 2.5, 40)])
    m = S.equivalent_genes(x)                                   # (40, 48, 4)
    assert m.shape == (40, 48, 4)
    assert np.allclose(m[:, 0], np.c_[np.mod(x[:, :3], 2 * np.pi), x[:, 3]])
    ok = np.all(np.isfinite(m), axis=-1)
    assert ok.sum(axis=1).min() >= 40                 # a few relabellings may be degenerate
    for k in (2, 7, 20, 41):
        h = np.where(ok, S.objective_H(np.nan_to_num(m), k), np.nan)
        assert np.nanmax(np.abs(h / S.objective_H(x, k)[:, None] - 1)) < 1e-9
    hw = np.where(ok, S.objective_worst(np.nan_to_num(m), np.arange(2, 21)), np.nan)
    assert np.nanmax(np.abs(hw / S.objective_worst(x, np.arange(2, 21))[:, None] - 1)) < 1e-9
    # every member has the same canonical member (the class, not the description, decides)
    c = S.canonical_genes(x)
    for j in (5, 17, 30, 47):
        sel = ok[:, j]
        assert np.allclose(S.canonical_genes(m[sel, j]), c[sel], atol=1e-9)
    # within a box only members inside count, and x itself is always a candidate
    box = list(S.PAPER_BOX)
    lo, hi = np.array(box).T
    xb = lo + rng.random((40, 4)) * (hi - lo)
    cb = S.canonical_genes(xb, box)
    assert np.all((cb >= lo - 1e-12) & (cb <= hi + 1e-12))
    assert all(tuple(np.round(a, 9)) <= tuple(np.round(b, 9)) for a, b in zip(cb, xb, strict=True))
    assert np.allclose(S.objective_H(cb, 20), S.objective_H(xb, 20), rtol=1e-9)


def test_select_best_breaks_ties_by_the_canonical_member_whatever_the_order():
    x = np.array([0.3, 2.0, 5.0, 1.3])
    m = S.equivalent_genes(x)
    copies = m[np.all(np.isfinite(m), axis=-1)][[0, 7, 19, 33]]        # one layout, four copies
    h = S.objective_H(copies, 20)
    worse = np.array([[0.5, 2.2, 5.1, 1.0]])
    cands = np.concatenate([copies, worse])
    hc = np.r_[h * (1 + np.array([3e-10, 0, -2e-10, 1e-10])), 2 * h.max()]
    picks = set()
    for perm in ([0, 1, 2, 3, 4], [4, 3, 2, 1, 0], [2, 0, 4, 1, 3]):
        i, g = S.select_best(hc[perm], cands[perm])
        assert perm[i] != 4
        picks.add(tuple(np.round(g, 9)))
    assert len(picks) == 1                                      # the same layout every time
    assert np.allclose(next(iter(picks)), S.canonical_genes(x), atol=1e-9)
    # outside the tie tolerance the smaller H wins even if it is not canonical
    hc2 = hc.copy()
    hc2[3] *= 1 - 1e-6
    assert S.select_best(hc2, cands, rel_tol=1e-9)[0] == 3
    # batched over leading axes
    i2, g2 = S.select_best(np.stack([hc, hc[::-1]]), np.stack([cands, cands[::-1]]))
    assert np.allclose(g2[0], g2[1]) and i2[0] != 4 and i2[1] != 0


def test_batched_reference_optima_and_differential_evolution():
    box = list(S.PAPER_BOX)
    ks = np.array([5, 10, 20])
    h, g = S.reference_optima(ks, bounds=box, n_starts=2, seed=3)
    assert h.shape == (3,) and g.shape == (3, 4)
    assert np.all(h >= S.lower_bound_H(4)) and np.all(h < 0.27)
    assert np.allclose(S.objective_H(g, ks), h, rtol=1e-9)       # Eq. 20 at the genes reported
    assert np.allclose(S.canonical_genes(g, box), g)             # canonical members
    h1, g1 = S.reference_optimum(10, bounds=box, n_starts=2, seed=3)
    assert h1 <= h[1] * (1 + 1e-9) or np.isclose(h1, h[1], rtol=1e-6)
    # over the whole circle the bound 1/4 is never passed (the near-degenerate labellings, where
    # the closed form breaks down, are excluded), and at k = 4 it is reached (a pair layout)
    hf, _ = S.reference_optima([4, 9, 20], bounds=S.FULL_BOX, n_starts=2, seed=1)
    assert np.all(hf >= 0.25 - 1e-12) and hf[0] < 0.2501
    # the baseline: all runs in one batch, reproducible, best-so-far history
    d = S.run_de(20, bounds=box, n_runs=24, generations=60, seed=np.random.default_rng(4))
    e = S.run_de(20, bounds=box, n_runs=24, generations=60, seed=np.random.default_rng(4))
    assert np.array_equal(d.history, e.history) and d.history.shape == (61, 24)
    assert np.all(np.diff(d.history, axis=0) <= 0)
    assert np.allclose(d.history[-1], d.best_h)
    assert np.allclose(S.objective_H(d.best_x, 20), d.best_h)
    assert np.median(d.best_h) < 1.02 * S.reference_optimum(20, bounds=box, n_starts=2, seed=0)[0]


def test_convergence_generation():
    hist = np.array([[1.0, 1.0], [0.5, 0.9], [0.26, 0.8], [0.25, 0.8]])
    assert list(S.convergence_generation(hist, 0.25, 0.05)) == [2, -1]


def test_roundness_lsc_and_minimum_zone():
    t = 2 * np.pi * np.arange(258) / 258        # the trilobe's extremes fall on samples
    r = 0.5 * np.cos(3 * t) + 0.2 + 0.3 * np.cos(t) - 0.1 * np.sin(t)     # eccentric trilobe
    lsc, coef = S.lsc_roundness(r)
    mz, _ = S.mz_roundness(r)
    assert lsc == pytest.approx(1.0) and mz == pytest.approx(1.0, abs=1e-9)
    assert np.allclose(coef, [0.2, 0.3, -0.1])
    rng = np.random.default_rng(0)
    rr = S.lowpass(rng.standard_normal((10, 256)), 30)
    assert np.all(S.mz_roundness(rr)[0] <= S.lsc_roundness(rr)[0] + 1e-12)
    prof = S.random_profile(128, np.arange(2, 30), rng=rng, roundness=3.0)
    assert S.mz_roundness(prof)[0] == pytest.approx(3.0)


def test_simulated_measurements_average_the_noise():
    rng = np.random.default_rng(1)
    r = np.zeros(N)
    y1 = S.simulate_measurements(r, r, r, POS, n_rev=2, interleave=2, async_sd=0.0,
                                 noise_sd=1.0, n_measurements=400, rng=rng)
    y8 = S.simulate_measurements(r, r, r, POS, n_rev=16, interleave=2, async_sd=0.0,
                                 noise_sd=1.0, n_measurements=400, rng=rng)
    assert y1.shape == (400, 4, N)
    assert y1.std() == pytest.approx(1.0, rel=0.05) and y8.std() == pytest.approx(1 / 8 ** 0.5,
                                                                                  rel=0.05)


@pytest.mark.parametrize("call, match", [
    (lambda: S.weights([0.3, 0.3, 2.0], 1.0), "coincident or opposite"),
    (lambda: S.weights([0.1, 0.3, 0.5, 2.0], 1.0), "phi_0 must be 0"),
    (lambda: S.weights([0.3, 2.0], 1.0), "last axis 3"),
    (lambda: S.probe_angles([0, 14.5, 65, 116], 128), "integer sample"),
    (lambda: S.separate(np.zeros((3, 128)), S.probe_angles(POS, 128), [1, 1, 1]),
     r"\(\.\.\., 4, N\)"),
    (lambda: S.separate(np.zeros((4, 128)), [0.1, 2.0, 5.0], [1, 1, 1]), "integer p"),
    (lambda: S.separate(np.zeros((4, 128)), S.probe_angles(POS, 128), [1.7487, 2.8273, 1.953]),
     "do not cancel the first harmonic"),
    (lambda: S.separate(np.full((4, 128), np.nan), S.probe_angles(POS, 128), [1, 1, 1]), "NaN"),
    (lambda: S.objective_H(np.array([0.3, 2.0, 5.0, 1.0]), 1), "k = 1 is cancelled"),
    (lambda: S.run_ga(20, pop_size=7), "even"),
    (lambda: S.run_ga(20, generations=0), "generations"),
    (lambda: S.run_ga(20, pc=1.5), r"pc must be a probability in \[0, 1\], got 1.5"),
    (lambda: S.run_ga(20, n_runs=2.5), r"n_runs must be an integer >= 1, got 2.5"),
    (lambda: S.run_de(20, popsize=0), r"popsize must be an integer >= 1, got 0"),
    (lambda: S.reference_optima([5], popsize=1), r"popsize must be an integer >= 2, got 1"),
    (lambda: S.reference_optima([5], n_starts=True), r"n_starts must be an integer >= 1"),
    (lambda: S.bound_layout(8, m=4), r"m must be an integer in \[1, 3\], got 4"),
    (lambda: S.lower_bound_H(2), r"n_probes must be an integer >= 3, got 2"),
    (lambda: S.worst_case_bound(7), r"n_samples must be an integer >= 8, got 7"),
    (lambda: S.separate(np.zeros((4, 6)), [0.1, 2.0, 5.0], [1, 1, 1]),
     r"samples per revolution \(the signals' last axis\) must be an integer >= 8, got 6"),
    (lambda: S.simulate_measurements(np.zeros(8), np.zeros(8), np.zeros(8), [0, 1, 2, 3],
                                     n_rev=2, interleave=0, async_sd=0, noise_sd=0,
                                     n_measurements=1, rng=0), "interleave must be an integer"),
    (lambda: S.random_profile(64, [2, 3], rng=True), "seed must be"),
    (lambda: S.run_ga(20, bounds=[(0, 1)] * 3), "four"),
    (lambda: S.run_ga(20, harmonics=[2, 3]), "either k"),
    (lambda: _rates(1.0, 5, 4), r"generation must be an integer in \[0, max_generation = 4\]"),
    (lambda: _rates(1.0, 1.5), r"generation must be an integer"),
    (lambda: _rates(1.0, 1, 4, eq23="minus"), "eq23"),
    (lambda: S.motion_from_scalar(np.zeros(8), "polar"), "unknown mapping"),
    (lambda: S.lowpass(np.zeros(16), 9), r"max_harmonic must be an integer in \[1, 8\], got 9"),
    (lambda: S.separate(np.zeros((4, 128)), S.probe_angles(POS, 128),
                        S.full_weights(S.probe_angles(POS, 128), 1.0), max_harmonic=65),
     "max_harmonic"),
    (lambda: S.select_best(np.ones(3), np.ones((2, 4))), "must be"),
    (lambda: S.reference_optima([1, 5]), "k = 1 is cancelled"),
])
def test_bad_inputs_are_refused_clearly(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_coincidence_ratio_separates_scatter_from_a_systematic_difference():
    rng = np.random.default_rng(21)
    base = np.sin(np.linspace(0, 2 * np.pi, 64, endpoint=False))
    same = base + 0.1 * rng.standard_normal((4, 20, 64))             # one curve, four groups
    r = S.coincidence_ratio(same)
    assert r.shape == (4, 4) and np.all(np.diag(r) == 0) and np.allclose(r, r.T)
    assert 0.3 < r[np.triu_indices(4, 1)].mean() < 0.7              # about 1/k = 0.5
    shifted = same.copy()
    shifted[2] += 0.2 * np.cos(np.linspace(0, 2 * np.pi, 64, endpoint=False))
    r2 = S.coincidence_ratio(shifted)
    assert r2[2, [0, 1, 3]].min() > 2 and r2[0, 1] == pytest.approx(r[0, 1])
    # hand case: two groups of two, variances 0.5 each, means 0 and 1: 1 / sqrt((0.5 + 0.5) / 2)
    hand = S.coincidence_ratio([[[0.5], [-0.5]], [[1.5], [0.5]]], k=1)
    assert hand[0, 1] == pytest.approx(np.sqrt(2))
    with pytest.raises(ValueError, match="measurements >= 2"):
        S.coincidence_ratio(np.zeros((3, 1, 5)))


# --- least squares over all probes (the multi-probe estimator) ---------------------------------

@pytest.mark.parametrize("trial", range(3))
def test_least_squares_separation_is_exact_and_equals_the_weighted_one_without_noise(trial):
    rng = np.random.default_rng(300 + trial)
    p, phi, w = _layout(rng)
    r = rng.standard_normal((2, N))
    dxy = np.array([_motion_without_fundamental(rng) for _ in range(2)])
    y = S.probe_signals(r, dxy[:, 0], dxy[:, 1], p)
    ls = S.separate_least_squares(y, phi)
    weighted = S.separate_details(y, phi, w)
    for got in (ls, weighted):
        assert np.abs(got.profile - r).max() < 1e-10 * np.abs(r).max()
        assert np.abs(got.dx - dxy[:, 0]).max() < 1e-10 * np.abs(r).max()
    assert list(ls.cancelled) == [1]


def test_least_squares_transfer_predicts_its_noise_and_never_exceeds_the_weighted_one():
    rng = np.random.default_rng(12)
    phi = S.probe_angles(POS, N)
    w = S.full_weights(phi, 1.953)
    sigma, m = 0.3, 4000
    s = S.separate_least_squares(rng.standard_normal((m, 4, N)) * sigma, phi)
    ks = np.array([2, 5, 20, 40])
    a_k, b_k = S.harmonic_coefficients(s.profile_no_first, ks)
    pred = 2 * S.least_squares_transfer(phi[1:], ks) * sigma ** 2 / N
    assert np.allclose(a_k.var(axis=0), pred, rtol=0.1)
    assert np.allclose(b_k.var(axis=0), pred, rtol=0.1)
    # Gauss-Markov: least squares is the best linear unbiased estimator, for every layout and
    # every weights that cancel the motion
    ks = np.arange(2, N // 2)
    for trial in range(20):
        _, ph, wt = _layout(np.random.default_rng(700 + trial))
        assert np.all(S.least_squares_transfer(ph[1:], ks) <= S.transfer(ph, wt, ks) * (1 + 1e-9))
    # the paper's layout and weights, harmonics 2..20 (the figures quoted in the docstring)
    assert S.transfer(phi, w, np.arange(2, 21)).max() == pytest.approx(112.85, abs=0.01)
    ls_worst = S.least_squares_transfer(phi[1:], np.arange(2, 21)).max()
    assert ls_worst == pytest.approx(6.40, abs=0.01)
    assert np.isinf(S.least_squares_transfer(phi[1:], [1])[0])


def test_least_squares_with_more_probes_and_a_layout_it_cannot_use():
    rng = np.random.default_rng(31)
    pos = [0, 9, 40, 77, 101]                                   # five probes
    phi = S.probe_angles(pos, N)
    r = rng.standard_normal(N)
    dx, dy = _motion_without_fundamental(rng)
    t = 2 * np.pi * np.arange(N) / N
    y = np.stack([r[(np.arange(N) + q) % N] + dx * np.cos(f) + dy * np.sin(f)
                  for q, f in zip(pos, phi, strict=True)])
    s = S.separate_least_squares(y, phi)
    assert np.abs(s.profile - r).max() < 1e-10 and np.abs(s.dy - dy).max() < 1e-10
    assert np.all(S.least_squares_transfer(phi, np.arange(2, 64)) < np.inf)
    # probes 0 and 180 degrees and 90 and 270: every odd harmonic reads as a motion would
    half = [0, 32, 64, 96]
    y4 = S.probe_signals(r, 0 * t, 0 * t, half)
    with pytest.raises(ValueError, match=r"cannot separate harmonic\(s\) 3, 5, 7"):
        S.separate_least_squares(y4, S.probe_angles(half, N))
    with pytest.raises(ValueError, match="L >= 3 probes"):
        S.separate_least_squares(y4[:2], S.probe_angles(half, N)[:2])
    with pytest.raises(ValueError, match="integer p"):
        S.separate_least_squares(y4, S.probe_angles(half, N) + 0.01)


def test_grid_layout_snaps_to_samples_and_cancelled_harmonics_match_separate():
    p, phi, w = S.grid_layout(np.r_[S.probe_angles([14, 65, 116], N) + 0.01, 1.953], N)
    assert p.tolist() == [0, 14, 65, 116] and np.allclose(w, S.full_weights(phi, 1.953))
    assert S.cancelled_harmonics(phi, w, n_samples=N) == []
    _, ph2, w2 = _half_circle_layout()                      # weights (1, 0, 0, 1): every odd k
    assert S.cancelled_harmonics(ph2, w2, n_samples=N) == list(range(3, N // 2, 2))
    with pytest.raises(ValueError, match="one gene vector"):
        S.grid_layout(np.zeros((2, 4)), N)


def test_measure_separated_counts_revolutions_and_separates_a_clean_signal():
    rng = np.random.default_rng(5)
    r = S.lowpass(rng.standard_normal(N), 20)
    dx, dy = (S.lowpass(v, 20) for v in _motion_without_fundamental(rng))
    p, phi, w = S.grid_layout(np.r_[S.probe_angles([14, 65, 116], N), 1.953], N)
    kw = dict(duration_s=1.0, interleave=2, async_sd_600=0.0, async_exponent=1.0, noise_sd=0.0,
              n_measurements=3, lowpass_harmonic=30, first_harmonic="eccentricity", rng=rng)
    s, n_rev = S.measure_separated(r, dx, dy, p, phi, w, speed_rpm=600, **kw)
    assert n_rev == 10 and s.profile.shape == (3, N)
    assert np.abs(s.profile - r).max() < 1e-9 and np.abs(s.dx - dx).max() < 1e-9
    assert S.measure_separated(r, dx, dy, p, phi, w, speed_rpm=30, **kw)[1] == 2  # one set at least
