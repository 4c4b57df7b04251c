"""Sobol estimators: agreement with SALib, the Ishigami function, chunking and streaming
invariance, bootstrap intervals held and streamed."""

import warnings

import numpy as np
import pytest
from SALib.analyze import sobol as salib_sobol
from scipy import stats
from scipy.stats import qmc

from mtaccuracy import sensitivity as S
from mtaccuracy.sensitivity.benchmarks import ishigami as ishigami_benchmark


def ishigami(x, a=7.0, b=0.1):
    return np.sin(x[:, 0]) + a * np.sin(x[:, 1]) ** 2 + b * x[:, 2] ** 4 * np.sin(x[:, 0])


def ishigami_exact(a=7.0, b=0.1):
    v1 = 0.5 * (1 + b * np.pi**4 / 5) ** 2
    v2 = a**2 / 8
    v13 = b**2 * np.pi**8 * (1 / 18 - 1 / 50)
    v = v1 + v2 + v13
    return np.array([v1, v2, 0.0]) / v, np.array([v1 + v13, v2, v13]) / v


BOUNDS = np.array([[-np.pi] * 3, [np.pi] * 3])
ISHIGAMI_INPUTS = S.Inputs.from_bounds(BOUNDS)          # x_i uniform on [-pi, pi]


def test_agrees_with_salib_on_the_same_runs():
    ua, ub = S.base_samples(256, 3, method="sobol", seed=0)
    a, b = ISHIGAMI_INPUTS.from_unit(ua), ISHIGAMI_INPUTS.from_unit(ub)
    ya, yb, yab = S.sobol_evaluate(ishigami, a, b)
    s1, st = S.sobol_estimate(ya, yb, yab)
    # SALib's layout without second order: per base row A, AB_1..AB_D, B.
    y = np.concatenate([ya, yab[:, :, 0].T, yb], axis=1).ravel()
    problem = {"num_vars": 3, "names": ["x1", "x2", "x3"], "bounds": BOUNDS.T.tolist()}
    ref = salib_sobol.analyze(problem, y, calc_second_order=False, num_resamples=10, seed=1)
    assert np.allclose(s1[:, 0], ref["S1"], atol=1e-12)
    assert np.allclose(st[:, 0], ref["ST"], atol=1e-12)


@pytest.mark.parametrize("method", ["mc", "lhs", "sobol"])
def test_ishigami_converges_to_the_analytic_indices(method):
    ua, ub = S.base_samples(2**14, 3, method=method, seed=4)
    s1, st = S.sobol_indices(ishigami, ISHIGAMI_INPUTS.from_unit(ua),
                             ISHIGAMI_INPUTS.from_unit(ub))
    e1, et = ishigami_exact()
    assert np.allclose(s1[:, 0], e1, atol=0.04) and np.allclose(st[:, 0], et, atol=0.04)


def test_chunking_does_not_change_the_result_and_reports_progress():
    ua, ub = S.base_samples(100, 3, method="mc", seed=2)
    seen = []
    one = S.sobol_evaluate(ishigami, ua, ub, chunk=10_000)
    many = S.sobol_evaluate(ishigami, ua, ub, chunk=37, progress=lambda d, t: seen.append((d, t)))
    for x, y in zip(one, many, strict=True):
        assert np.array_equal(x, y)
    assert seen[-1] == (500, 500) and len(seen) > 10


@pytest.mark.parametrize("n, chunk", [(300, 10_000), (300, 700), (300, 128)])
def test_streaming_indices_equal_the_stored_estimate(n, chunk):
    """sobol_indices never holds yab; it must give sobol_estimate's numbers, for every way
    the runs are batched (several AB blocks per call, one, or one block over several)."""
    ua, ub = S.base_samples(n, 5, method="mc", seed=11)

    def model(x):   # two outputs far from zero (centring matters) with interactions
        return np.c_[ishigami(x) + 40.0, x[:, 3] * x[:, 4] - 3.0 + x[:, 0]]
    five = S.Inputs.from_bounds(np.array([[-np.pi] * 5, [np.pi] * 5]))
    a, b = five.from_unit(ua), five.from_unit(ub)
    seen = []
    s1, st = S.sobol_indices(model, a, b, chunk=chunk, progress=lambda d, t: seen.append((d, t)))
    e1, et = S.sobol_estimate(*S.sobol_evaluate(model, a, b, chunk=chunk))
    assert s1.shape == (5, 2) and np.allclose(s1, e1, rtol=0, atol=1e-12)
    assert np.allclose(st, et, rtol=0, atol=1e-12)
    assert seen[-1] == (7 * n, 7 * n)


def test_a_model_returning_a_view_of_its_input_is_safe():
    """The AB blocks share one buffer, changed between calls: outputs must be copied."""
    ua, ub = S.base_samples(50, 4, method="mc", seed=5)
    ya, yb, yab = S.sobol_evaluate(lambda x: x, ua, ub, chunk=120)
    assert np.array_equal(ya, ua) and np.array_equal(yb, ub)
    for i in range(4):
        ab = ua.copy()
        ab[:, i] = ub[:, i]
        assert np.array_equal(yab[i], ab)
    s1, st = S.sobol_indices(lambda x: x, ua, ub, chunk=120)
    e1, et = S.sobol_estimate(ya, yb, yab)
    assert np.allclose(s1, e1, atol=1e-12) and np.allclose(st, et, atol=1e-12)


def test_estimate_by_input_blocks_equals_one_block(monkeypatch):
    ua, ub = S.base_samples(64, 6, method="mc", seed=8)
    y = S.sobol_evaluate(lambda x: np.c_[ishigami(x), x.sum(1)], ua, ub)
    whole = S.sobol_estimate(*y)
    monkeypatch.setattr(S.sobol, "_ESTIMATE_BLOCK", 130)     # one input at a time
    for x, z in zip(whole, S.sobol_estimate(*y), strict=True):
        assert np.allclose(x, z, rtol=0, atol=1e-14)
    boot = S.sobol_estimate(y[0][None], y[1][None], y[2][None])   # a leading axis
    assert np.allclose(boot[1][0], whole[1], rtol=0, atol=1e-14)


def test_bootstrap_half_width_shrinks_with_n():
    widths = []
    for n in (256, 4096):
        ua, ub = S.base_samples(n, 3, method="mc", seed=3)
        ya, yb, yab = S.sobol_evaluate(ishigami, ISHIGAMI_INPUTS.from_unit(ua),
                                       ISHIGAMI_INPUTS.from_unit(ub))
        w1, wt = S.sobol_bootstrap(ya, yb, yab, n_boot=50, seed=0)
        assert w1.shape == wt.shape == (3, 1)
        widths.append(wt[1, 0])
    assert widths[1] < widths[0] / 2.5  # ~ 1/sqrt(N): factor 4 expected


def test_bad_input():
    with pytest.raises(ValueError, match="allowed: mc, lhs, sobol"):
        S.base_samples(8, 2, method="halton", seed=0)
    with pytest.raises(ValueError, match="one shape"):
        S.sobol_evaluate(ishigami, np.zeros((4, 3)), np.zeros((5, 3)))


def test_linear_indices_equal_the_sampling_estimate_of_a_linear_model():
    jac = np.array([[2.0, -1.0, 0.5], [0.0, 0.0, 0.0]])
    sd = np.array([1.0, 3.0, 2.0])
    lin = S.linear_indices(jac, sd=sd)                    # (inputs, outputs), as st
    assert np.allclose(lin[:, 0], [4.0, 9.0, 1.0] / np.float64(14.0)) and not lin[:, 1].any()
    ua, ub = S.base_samples(2**14, 3, method="sobol", seed=5)
    s1, st = S.sobol_indices(lambda x: x @ jac[0], S.Inputs.normal(0.0, sd).from_unit(ua),
                             S.Inputs.normal(0.0, sd).from_unit(ub))
    assert np.allclose(st[:, 0], lin[:, 0], atol=0.02) and \
        np.allclose(s1[:, 0], lin[:, 0], atol=0.02)



def _direct_bootstrap(ya, yb, yab, n_boot, seed, chunk=20):
    """The resampling as it used to be done: copy the resampled rows, re-estimate."""
    rng = np.random.default_rng(seed)
    s1s, sts = [], []
    for start in range(0, n_boot, chunk):
        idx = rng.integers(0, ya.shape[0], size=(min(chunk, n_boot - start), ya.shape[0]))
        s1, st = S.sobol_estimate(ya[idx], yb[idx], np.moveaxis(yab[:, idx], 0, 1))
        s1s.append(s1)
        sts.append(st)
    return np.concatenate(s1s), np.concatenate(sts)


def test_bootstrap_by_counts_equals_resampling_the_rows():
    ua, ub = S.base_samples(300, 3, method="mc", seed=6)
    ya, yb, yab = S.sobol_evaluate(lambda x: np.c_[ishigami(x) + 50.0, x[:, 0]],
                                   ISHIGAMI_INPUTS.from_unit(ua), ISHIGAMI_INPUTS.from_unit(ub))
    ref1, reft = _direct_bootstrap(ya, yb, yab, 45, 9)
    for block in (2**21, 300 * 7):  # one product, or several (the draws do not change)
        s1b, stb = S.sobol_bootstrap_samples(ya, yb, yab, n_boot=45, seed=9, block=block)
        assert s1b.shape == stb.shape == (45, 3, 2)
        assert np.allclose(s1b, ref1, rtol=0, atol=1e-12)  # an offset of 50 costs no precision
        assert np.allclose(stb, reft, rtol=0, atol=1e-12)
    w1, wt = S.sobol_bootstrap(ya, yb, yab, n_boot=45, seed=9)
    assert np.allclose(w1, S.ci_half_width(ref1)) and np.allclose(wt, S.ci_half_width(reft))


def test_bootstrap_counts_are_resamples():
    blocks = list(S.bootstrap_counts(10, 7, seed=3, chunk=3, block=20))
    w = np.concatenate(blocks)
    assert w.shape == (7, 10) and np.all(w.sum(1) == 10) and len(blocks) > 1
    with pytest.raises(ValueError, match="n_boot must be an integer >= 1, got 0"):
        next(S.bootstrap_counts(10, 0, seed=3))


def test_merge_ties_makes_the_sort_canonical():
    st = np.array([0.2, 0.3, 0.3 * (1 + 1e-13), 0.05, 1e-20, 0.0])
    merged = S.merge_ties(st)
    assert merged[1] == merged[2] == st[2] and merged[4] == merged[5]
    assert merged[0] == st[0] and merged[3] == st[3]
    assert list(np.argsort(-merged, kind="stable")) == [1, 2, 0, 3, 4, 5]
    # the 90 % rule then takes the tied pair in catalogue order whichever member rounding favours
    for j in (1, 2):
        a = st.copy()
        a[j] = 0.3 * (1 + 2e-13)
        assert S.key_errors(S.merge_ties(a), threshold=0.5).index == (1, 2)
    # leading axes (bootstrap) and columns are handled independently
    many = S.merge_ties(np.stack([np.c_[st, st[::-1]]] * 2))
    assert many.shape == (2, 6, 2) and np.array_equal(many[1, :, 0], merged)
    assert np.array_equal(many[0, :, 1], merged[::-1])


@pytest.mark.parametrize("method", ["mc", "lhs", "sobol"])
@pytest.mark.parametrize("rows", [1, 37, 128, 1000])
def test_base_blocks_are_the_whole_draw_in_pieces(method, rows):
    """Drawn a block at a time, A and B are bitwise the whole draw: the B stream of ``mc``
    starts n d draws on, the Sobol' sequence continues where the last block stopped."""
    n, d = 128, 5
    whole = S.base_samples(n, d, method=method, seed=7)
    rng = np.random.default_rng(7)        # the designs as scipy and numpy draw them whole
    ref = {"mc": lambda: (rng.random((n, d)), rng.random((n, d))),
           "lhs": lambda: tuple(qmc.LatinHypercube(d=d, rng=rng).random(n) for _ in "ab"),
           "sobol": lambda: np.split(qmc.Sobol(d=2 * d, scramble=True, rng=rng).random(n), 2,
                                     axis=1)}[method]()
    assert all(np.array_equal(w, r) for w, r in zip(whole, ref, strict=True))
    blocks = list(S.base_blocks(n, d, method=method, seed=7, rows=rows))
    assert len(blocks) == -(-n // rows) and all(len(a) <= rows for a, _ in blocks)
    for k in (0, 1):
        assert np.array_equal(np.concatenate([blk[k] for blk in blocks]), whole[k])


@pytest.mark.parametrize("bit_generator", [np.random.PCG64, np.random.MT19937])
def test_a_generator_seed_gives_the_whole_draw_and_ends_where_it_would(bit_generator):
    """PCG64 jumps to B (advance); a generator without ``advance`` draws and discards."""
    whole_rng = np.random.Generator(bit_generator(3))
    whole = (whole_rng.random((50, 4)), whole_rng.random((50, 4)))    # numpy's whole draw
    rng = np.random.Generator(bit_generator(3))
    blocks = list(S.base_blocks(50, 4, method="mc", seed=rng, rows=16))
    for k in (0, 1):
        assert np.array_equal(np.concatenate([blk[k] for blk in blocks]), whole[k])
    assert rng.random() == whole_rng.random()


def _offset_model(x):   # two outputs far from zero (pooling must not cancel) with interactions
    return np.c_[ishigami(x) + 40.0, x[:, 3] * x[:, 4] - 3.0 + x[:, 0]]


@pytest.mark.parametrize("method", ["mc", "lhs", "sobol"])
def test_streamed_design_equals_the_whole_array_estimate(method):
    """Base rows drawn and run in blocks give the whole-array estimate (sobol_estimate on all
    runs of base_samples' A and B, the same seed) to rounding; one block gives it bitwise."""
    n, d = 256, 5
    to_inputs = S.Inputs.from_bounds(np.array([[-np.pi] * d, [np.pi] * d])).from_unit
    ua, ub = S.base_samples(n, d, method=method, seed=12)
    a, b = to_inputs(ua), to_inputs(ub)
    e1, et = S.sobol_estimate(*S.sobol_evaluate(_offset_model, a, b))
    design = S.SobolDesign(n, d, method=method, seed=12, to_inputs=to_inputs)
    for rows in (37, 64):   # uneven and even blocks
        seen = []
        s1, st = S.sobol_indices(_offset_model, design, chunk=300, rows=rows,
                                 progress=lambda done, total, seen=seen: seen.append((done, total)))
        assert np.allclose(s1, e1, rtol=0, atol=1e-12) and np.allclose(st, et, rtol=0, atol=1e-12)
        assert seen[-1] == (n * (d + 2), n * (d + 2))
    one = S.sobol_indices(_offset_model, design, chunk=300, rows=n)
    arrays = S.sobol_indices(_offset_model, a, b, chunk=300, rows=n)
    for x, y in zip(one, arrays, strict=True):
        assert np.array_equal(x, y)
    blocked = S.sobol_indices(_offset_model, a, b, chunk=300, rows=50)   # arrays, in blocks
    assert np.allclose(blocked[0], e1, rtol=0, atol=1e-12)


def test_sobol_balance_warning_is_about_the_design_not_the_block():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        list(S.base_blocks(256, 2, method="sobol", seed=0, rows=48))  # N a power of 2: silent
    with pytest.warns(UserWarning, match="power of 2"):
        list(S.base_blocks(300, 2, method="sobol", seed=0, rows=64))  # N is not


def test_design_bad_input():
    design = S.SobolDesign(16, 2, method="mc", seed=0)
    with pytest.raises(ValueError, match="not both"):
        S.sobol_indices(lambda x: x, design, np.zeros((16, 2)))
    with pytest.raises(ValueError, match="rows must be"):
        S.sobol_indices(lambda x: x, design, rows=0)
    with pytest.raises(ValueError, match="allowed: mc, lhs, sobol"):
        S.sobol_indices(lambda x: x, S.SobolDesign(16, 2, method="halton", seed=0))
    with pytest.raises(ValueError, match="n must be"):
        S.base_blocks(1, 2, method="mc", seed=0)
    ya, yb, yab = S.sobol_evaluate(lambda x: x, design)      # a design, drawn whole
    assert np.array_equal(ya, S.base_samples(16, 2, method="mc", seed=0)[0])
    assert yab.shape == (2, 16, 2)


# --- bootstrap intervals streamed like the indices (the Poisson bootstrap) -------------------

def _poisson_ppf(seed, shape):
    """Poisson(1) counts of the uniforms of ``default_rng(seed)`` by scipy's inverse CDF."""
    return stats.poisson.ppf(np.random.default_rng(seed).random(shape), 1.0)


def test_bootstrap_weights_are_one_poisson_stream_whatever_the_blocks():
    whole = _poisson_ppf(4, (100, 7))
    for rows in (1, 33, 100, 500):
        blocks = list(S.bootstrap_weights(100, 7, seed=4, rows=rows))
        assert len(blocks) == -(-100 // rows) and np.array_equal(np.concatenate(blocks), whole)
    # Poisson(1): the frequencies of 0, 1, ..., 5 and more in 10^6 counts (chi-square)
    w = next(S.bootstrap_weights(1000, 1000, seed=5, rows=1000)).ravel()
    seen = np.bincount(np.minimum(w.astype(int), 6), minlength=7)
    expected = np.r_[stats.poisson.pmf(np.arange(6), 1.0), stats.poisson.sf(5, 1.0)] * w.size
    assert stats.chisquare(seen, expected).pvalue > 1e-3


def test_streamed_bootstrap_is_the_estimator_on_the_reweighted_rows():
    """Each re-estimate is sobol_estimate on the rows repeated as often as their Poisson count
    says (an independent formulation: no weights, the resampled data themselves), whatever the
    blocks; the point estimate is the unbootstrapped one, bitwise in one block."""
    n, n_boot = 150, 25
    inp = S.Inputs.uniform(-np.pi, np.full(5, np.pi))
    design = S.SobolDesign(n, inp, method="mc", seed=3)
    ya, yb, yab = S.sobol_evaluate(_offset_model, design)
    counts = _poisson_ppf(9, (n, n_boot)).astype(int)
    ref = [S.sobol_estimate(ya[i], yb[i], yab[:, i])
           for i in (np.repeat(np.arange(n), counts[:, b]) for b in range(n_boot))]
    plain = S.sobol_indices(_offset_model, design)
    for rows, chunk in ((n, 200_000), (40, 100), (7, 30)):   # one block; blocks; input batches
        res = S.sobol_indices(_offset_model, design, n_boot=n_boot, seed=9, rows=rows,
                              chunk=chunk)
        for b, (e1, et) in enumerate(ref):
            assert np.allclose(res.s1_boot[b], e1, rtol=0, atol=1e-12)
            assert np.allclose(res.st_boot[b], et, rtol=0, atol=1e-12)
        assert np.array_equal(res.s1_ci, S.ci_half_width(res.s1_boot))
        assert np.array_equal(res.st_ci, S.ci_half_width(res.st_boot))
        assert np.allclose(res.s1, plain.s1, rtol=0, atol=1e-12)
        if rows == n:
            assert np.array_equal(res.st, plain.st) and np.array_equal(res.s1, plain.s1)
    df = res.to_df()
    assert list(df.columns) == ["output", "input", "S1", "S1_ci95", "ST", "ST_ci95"]


def test_streamed_and_held_bootstraps_agree_in_distribution():
    """Different resamples (Poisson counts against draws with replacement), the same spread:
    on Ishigami at N = 4096 the half-widths agree within 10 % (a bootstrap standard deviation
    from 400 resamples carries about 3.5 % of Monte Carlo noise)."""
    bench = ishigami_benchmark()
    design = S.SobolDesign(4096, bench.inputs, method="sobol", seed=1)
    streamed = S.sobol_indices(bench.model, design, n_boot=400, seed=2)
    h1, ht = S.sobol_bootstrap(*S.sobol_evaluate(bench.model, design), n_boot=400, seed=2)
    assert np.all(np.abs(streamed.s1_ci / h1 - 1) < 0.1)
    assert np.all(np.abs(streamed.st_ci / ht - 1) < 0.1)
    # and the key-set frequencies take its re-estimates as they take the held ones
    freq, counts = S.key_set_bootstrap(streamed, names=list(bench.inputs.names), threshold=0.7)
    assert len(counts) == 400 and freq.set_index("symbol").loc["x2", "union"] == 1.0
    again, _ = S.key_set_bootstrap(streamed.st_boot, names=list(bench.inputs.names),
                                   threshold=0.7)
    assert freq.equals(again)
    with pytest.raises(ValueError, match="no bootstrap re-estimates"):
        S.key_set_bootstrap(S.sobol_indices(bench.model, design), names=["a", "b", "c"])


def test_streamed_bootstrap_intervals_cover_the_exact_indices_of_a_linear_model():
    """A linear model has S1 = ST = c_ik^2 var_i / sum_j c_jk^2 var_j.  Over 100 independent
    designs the 95 % intervals cover the exact indices 95 % of the time (0.90 .. 0.98 over 800
    intervals: too narrow or too wide intervals fail), and the mean half-width is the normal
    quantile times the estimates' own spread across designs (within 15 %)."""
    c = np.array([[1.0, 0.3], [0.5, -1.0], [2.0, 0.2], [0.1, 0.8]])     # (d, q)
    inp = S.Inputs.uniform(-1.0, np.ones(4))
    exact = c**2 * inp.var[:, None] / (c**2 * inp.var[:, None]).sum(0)
    runs = [S.sobol_indices(lambda x: x @ c, S.SobolDesign(256, inp, method="mc", seed=r),
                            n_boot=100, seed=1000 + r) for r in range(100)]
    z = stats.norm.ppf(0.975)
    for est, half in (("s1", "s1_ci"), ("st", "st_ci")):
        e = np.array([getattr(r, est) for r in runs])
        h = np.array([getattr(r, half) for r in runs])
        assert 0.90 <= np.mean(np.abs(e - exact) <= h) <= 0.98, est
        assert abs(np.mean(h.mean(0) / (z * e.std(0, ddof=1))) - 1) < 0.15, est


def test_streamed_bootstrap_bad_input():
    design = S.SobolDesign(64, 2, method="mc", seed=0)
    with pytest.raises(ValueError, match="n_boot must be an integer >= 2"):
        S.sobol_indices(lambda x: x, design, n_boot=1)
    with pytest.raises(ValueError, match=r"conf must be in \(0, 1\)"):
        S.sobol_indices(lambda x: x, design, n_boot=10, conf=1.0)
    with pytest.raises(ValueError, match=r"s1_boot and st_boot must be \(n_boot, 2, 1\)"):
        S.SobolIndices(np.ones((2, 1)), np.ones((2, 1)), st_boot=np.ones((5, 2)))
