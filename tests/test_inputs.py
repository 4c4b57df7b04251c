"""Inputs: one description of independent inputs, and the estimators taking it (issue 25, 2)."""

import numpy as np
import pytest
from scipy import special, stats
from scipy.stats import qmc

from mtaccuracy import sensitivity as S
from mtaccuracy.machines import build
from mtaccuracy.sensitivity import benchmarks

MIXED = S.Inputs([stats.uniform(-2.0, 5.0), stats.norm(1.5, 0.3), stats.lognorm(0.5),
                  stats.gamma(3.0, scale=2.0)], names=["u", "n", "ln", "g"])


def test_moments_equal_scipy_and_the_closed_forms():
    laws = MIXED.marginals
    assert np.allclose(MIXED.mean, [m.mean() for m in laws], rtol=1e-15, atol=0)
    assert np.allclose(MIXED.var, [m.var() for m in laws], rtol=1e-14, atol=0)
    assert np.allclose(MIXED.sd, [m.std() for m in laws], rtol=1e-14, atol=0)
    # uniform on [-2, 3]: mean 1/2, variance 25/12; normal: its own parameters, bitwise
    assert MIXED.mean[0] == 0.5 and MIXED.var[0] == 25 / 12 and MIXED.sd[1] == 0.3
    assert MIXED.var[1] == 0.3**2 and MIXED.mean[1] == 1.5
    # the moments uniform_moments computes from bounds, bitwise
    bounds = np.array([[-0.01, -2e-5, 0.0], [0.01, 2e-5, 0.004]])
    mean, var = S.uniform_moments(bounds)
    inp = S.Inputs.from_bounds(bounds)
    assert np.array_equal(inp.var, var) and np.array_equal(inp.mean[:2], mean[:2])
    assert np.array_equal(inp.bounds, bounds)
    with pytest.raises(ValueError, match=r"\['n', 'ln', 'g'\] have an unbounded law"):
        _ = MIXED.bounds


@pytest.mark.parametrize("method", ["mc", "lhs", "sobol"])
def test_each_sampling_method_draws_the_marginals(method):
    x = MIXED.sample(1024, method=method, seed=3)
    assert x.shape == (1024, 4)
    for i, m in enumerate(MIXED.marginals):     # Kolmogorov-Smirnov against each law
        assert stats.kstest(x[:, i], m.cdf).pvalue > 0.01, (method, i)
    # the stream: unit-cube points of the named generator through each law's ppf
    rng = np.random.default_rng(3)
    u = {"mc": lambda: rng.random((1024, 4)),
         "lhs": lambda: qmc.LatinHypercube(d=4, rng=rng).random(1024),
         "sobol": lambda: qmc.Sobol(d=4, scramble=True, rng=rng).random(1024)}[method]()
    ref = np.column_stack([m.ppf(u[:, i]) for i, m in enumerate(MIXED.marginals)])
    assert np.array_equal(x, ref)            # uniform and normal too: scipy's ppf, bitwise
    # a Latin hypercube has one point per stratum in every column
    if method == "lhs":
        cdf = np.column_stack([m.cdf(x[:, i]) for i, m in enumerate(MIXED.marginals)])
        assert all(np.array_equal(np.sort(np.floor(c * 1024)), np.arange(1024)) for c in cdf.T)
    # a Generator continues its stream; an int starts afresh
    g = np.random.default_rng(3)
    first, second = MIXED.sample(8, method=method, seed=g), MIXED.sample(8, method=method, seed=g)
    assert not np.array_equal(first, second)
    assert np.array_equal(first, MIXED.sample(8, method=method, seed=3))


def test_from_unit_is_the_old_samplers_bitwise():
    u = np.random.default_rng(0).random((500, 3))
    sd = np.array([0.01, 2e-5, 0.3])
    # the formulas the notebooks' committed designs were drawn with (before Inputs): sd times
    # the standard normal quantile, and low + u (high - low)
    assert np.array_equal(S.Inputs.normal(0.0, sd).from_unit(u), 0.0 + sd * special.ndtri(u))
    bounds = np.array([[-0.5, 0.1, -np.pi], [1.5, 0.3, np.pi]])
    assert np.array_equal(S.Inputs.from_bounds(bounds).from_unit(u),
                          bounds[0] + u * (bounds[1] - bounds[0]))


def test_standard_map_round_trip_and_families():
    assert MIXED.families == ("legendre", "hermite", "hermite", "hermite")
    x = MIXED.sample(200, method="lhs", seed=1)
    z = MIXED.to_standard(x)
    assert np.allclose(MIXED.from_standard(z), x, rtol=1e-12, atol=1e-12)
    assert np.all(np.abs(z[:, 0]) <= 1)                                 # Legendre on [-1, 1]
    assert np.allclose(z[:, 1], (x[:, 1] - 1.5) / 0.3)                  # standardised normal
    assert np.allclose(z[:, 2], np.log(x[:, 2]) / 0.5)                  # Phi^-1(F(x))
    with pytest.raises(ValueError, match=r"inputs must be \(n, 4\)"):
        MIXED.to_standard(x[:, :3])
    with pytest.raises(ValueError, match=r"standard variables must be \(n, 4\)"):
        MIXED.from_standard(z[0])


def test_names_and_errors():
    assert S.Inputs.uniform([0, 0, 0], 1).names == ("x1", "x2", "x3")
    assert MIXED.names == ("u", "n", "ln", "g") and MIXED.dim == len(MIXED) == 4
    assert "ln: lognorm" in repr(MIXED)
    with pytest.raises(ValueError, match="distinct"):
        S.Inputs.normal(0, [1, 2], names=["a", "a"])
    with pytest.raises(ValueError, match="2 non-empty strings"):
        S.Inputs.normal(0, [1, 2], names=["a"])
    with pytest.raises(TypeError, match="frozen scipy.stats"):
        S.Inputs([0.5])
    with pytest.raises(ValueError, match="at least one"):
        S.Inputs([])
    with pytest.raises(ValueError, match="lower < upper"):
        S.Inputs.uniform([0, 1], [1, 1])
    with pytest.raises(ValueError, match="sd > 0"):
        S.Inputs.normal(0, [1, 0])
    with pytest.raises(ValueError, match=r"\(2, d\)"):
        S.Inputs.from_bounds(np.zeros((3, 2)))
    with pytest.raises(ValueError, match="unknown sampling method 'halton'"):
        MIXED.sample(4, method="halton")
    with pytest.raises(ValueError, match="n must be an integer >= 1, got 0"):
        MIXED.sample(0)
    with pytest.raises(ValueError, match="seed must be"):
        MIXED.sample(4, seed=-1)


# --- the estimators take an Inputs and give the numbers of the old call forms ---------------

ZHENG = build("ac_double_turntable")
POSE = dict(x=120.0, y=-40.0, z=200.0, A=0.4, C=1.1)


def test_linear_closed_forms_take_inputs():
    rng = np.random.default_rng(5)
    sd = rng.uniform(1e-3, 1e-2, ZHENG.n_errors)
    inp = S.Inputs.normal(0.0, sd)
    jac = ZHENG.jacobian(POSE)
    assert np.array_equal(S.linear_indices(jac, inp), S.linear_indices(jac, sd=sd))
    assert np.allclose(S.linear_indices(jac, var=sd**2), S.linear_indices(jac, sd=sd),
                       rtol=1e-13, atol=1e-16)
    assert np.array_equal(S.indices_at_poses(jac, inp), S.indices_at_poses(jac, var=sd**2))
    bounds = np.vstack([-sd, 2 * sd])
    uni = S.Inputs.from_bounds(bounds)
    mean, var = S.uniform_moments(bounds)
    box = dict(x=(0.0, 100.0), z=(50.0, 150.0))
    fixed = dict(y=-40.0, A=0.4, C=1.1)
    new = S.pose_box_indices(ZHENG.jacobian, uni, poses=fixed, pose_bounds=box)
    old = S.pose_box_indices(ZHENG.jacobian, mean=mean, var=var, poses=fixed, pose_bounds=box)
    for a, b in zip(new, old, strict=True):
        assert np.allclose(a, b, rtol=1e-14, atol=1e-18)
    with pytest.raises(TypeError, match="sd= or var="):
        S.linear_indices(jac, sd)                 # a bare array is never taken positionally
    with pytest.raises(ValueError, match="once"):
        S.indices_at_poses(jac, inp, var=sd**2)
    with pytest.raises(ValueError, match=r"sd must be \(41,\)"):
        S.linear_indices(jac, sd=sd[:3])
    with pytest.raises(ValueError, match="mean= and var="):
        S.pose_box_indices(ZHENG.jacobian, var=var, poses=dict(POSE))


def test_sobol_design_of_inputs_is_the_old_design_and_labels_the_result():
    sd = np.array([1.0, 2.0, 0.5])
    inp = S.Inputs.normal(0.0, sd, names=["a", "b", "c"])
    model = lambda x: np.c_[x @ [1.0, 0.5, 2.0], x[:, 0] * x[:, 1]]  # noqa: E731
    for method in ("mc", "sobol"):
        new = S.sobol_indices(model, S.SobolDesign(256, inp, method=method, seed=4), rows=100,
                              outputs=["lin", "prod"])
        old = S.sobol_indices(model, S.SobolDesign(256, 3, method=method, seed=4,
                                                   to_inputs=lambda u: sd * special.ndtri(u)),
                              rows=100)
        assert all(np.array_equal(x, y) for x, y in zip(new, old, strict=True))
    a, b = S.base_samples(64, inp, method="lhs", seed=2)
    ua, ub = S.base_samples(64, 3, method="lhs", seed=2)
    assert np.array_equal(a, 0.0 + sd * special.ndtri(ua)) and np.array_equal(b, inp.from_unit(ub))
    # a linear model: S1 = ST = (c sd)^2 / sum, the labels in long form
    df = new.to_df()
    assert list(df.columns) == ["output", "input", "S1", "ST"] and len(df) == 6
    assert list(df.output) == ["lin"] * 3 + ["prod"] * 3 and list(df.input) == ["a", "b", "c"] * 2
    exact = np.array([1.0, 1.0, 1.0]) / 3.0           # (1*1)^2, (0.5*2)^2, (2*0.5)^2 equal
    assert np.allclose(df.ST[:3], exact, atol=0.05) and np.array_equal(df.S1, new.s1.T.ravel())
    with pytest.raises(ValueError, match="not both"):
        S.SobolDesign(16, inp, to_inputs=inp.from_unit)


def test_sobol_indices_with_intervals_to_df():
    ua, ub = S.base_samples(512, 3, method="sobol", seed=0)
    bench = benchmarks.ishigami()
    a, b = bench.inputs.from_unit(ua), bench.inputs.from_unit(ub)
    ya, yb, yab = S.sobol_evaluate(bench.model, a, b)
    s1, st = S.sobol_estimate(ya, yb, yab)
    w1, wt = S.sobol_bootstrap(ya, yb, yab, n_boot=40, seed=1)
    res = S.SobolIndices(s1, st, names=bench.inputs.names, outputs=["f"], s1_ci=w1, st_ci=wt)
    df = res.to_df()
    assert list(df.columns) == ["output", "input", "S1", "S1_ci95", "ST", "ST_ci95"]
    assert np.array_equal(df.ST_ci95, wt[:, 0]) and (df.ST_ci95 > 0).all()
    # the exact total indices lie within about two half-widths (0.25 ... 0.56 at N = 512)
    assert np.all(np.abs(df.ST - bench.st) < 3 * df.ST_ci95 + 0.02)
    with pytest.raises(ValueError, match="2 input and 1 output names"):
        S.SobolIndices(s1, st, names=["a", "b"])
    with pytest.raises(ValueError, match="s1_ci and st_ci"):
        S.SobolIndices(s1, st, s1_ci=w1[:2])


def test_benchmarks_sample_through_their_inputs_with_the_old_stream():
    b = benchmarks.ishigami()
    assert isinstance(b.inputs, S.Inputs) and b.inputs.names == ("x1", "x2", "x3")
    rng = np.random.default_rng(31)        # what Benchmark.sample drew before it had Inputs
    u = qmc.LatinHypercube(d=3, rng=rng).random(200)
    old = np.column_stack([m.ppf(u[:, i]) for i, m in enumerate(b.inputs.marginals)])
    assert np.array_equal(b.sample(200, 31), old)
    assert np.allclose(b.inputs.var, (2 * np.pi) ** 2 / 12)


def test_sparse_pce_takes_inputs_and_labels_its_indices():
    b = benchmarks.BENCHMARKS["interaction_polynomial"]()
    named = S.Inputs(b.inputs.marginals, names=list("abcde"))
    x = b.sample(120, 4)
    res = S.fit_sparse_pce(x, b.model(x), inputs=named)
    same = S.fit_sparse_pce(x, b.model(x), inputs=b.inputs)
    assert np.array_equal(res.st, same.st) and np.allclose(res.st, b.st, atol=1e-12)
    df = res.to_df("f")
    assert list(df.input) == list("abcde") and (df.output == "f").all() and df.reliable.all()
    assert np.array_equal(df.S1, res.s1)
    with pytest.raises(TypeError):
        S.fit_sparse_pce(x, b.model(x), b.inputs)          # keyword-only after the data
    with pytest.raises(ValueError, match=r"folds must be an integer in \[2, 60\], got 61"):
        S.fit_sparse_pce(x, b.model(x), inputs=b.inputs, folds=61)


# --- one sampler per design (issue "rooms that show the architecture", item 1) ---------------

@pytest.mark.parametrize("method", ["mc", "lhs", "sobol"])
@pytest.mark.parametrize("rows", [1, 7, 64, 500])
def test_sample_blocks_are_the_whole_sample_in_pieces(method, rows):
    """Drawn a block at a time the design is bitwise the whole draw, and a Generator ends
    where the whole draw leaves it (the Monte Carlo stream and the Sobol' sequence go on)."""
    whole_rng, rng = np.random.default_rng(9), np.random.default_rng(9)
    whole = MIXED.sample(64, method=method, seed=whole_rng)
    blocks = list(MIXED.sample_blocks(64, method=method, seed=rng, rows=rows))
    assert len(blocks) == -(-64 // rows) and all(len(b) <= rows for b in blocks)
    assert np.array_equal(np.concatenate(blocks), whole)
    assert rng.random() == whole_rng.random()
    with pytest.raises(ValueError, match="rows must be"):
        MIXED.sample_blocks(8, method=method, rows=0)


def test_the_unit_cube_is_its_own_design():
    rng = np.random.default_rng(4)
    u = {"mc": rng.random((40, 3)), "lhs": qmc.LatinHypercube(d=3, rng=rng).random(40),
         "sobol": qmc.Sobol(d=3, scramble=True, rng=rng).random(32)}
    g = np.random.default_rng(4)
    for method, ref in u.items():
        assert np.array_equal(S.Inputs.unit(3).sample(len(ref), method=method, seed=g), ref)
    assert S.Inputs.unit(2, names=["a", "b"]).var.tolist() == [1 / 12, 1 / 12]


def test_every_design_of_the_package_is_drawn_by_inputs_sample():
    """The Sobol' A and B, the Spearman Latin hypercubes and the benchmarks' samples are
    Inputs.sample's draws: one implementation of each design."""
    inp = S.Inputs.normal(0.0, [1.0, 2.0, 0.5])
    for method in ("mc", "lhs"):        # A then B: two successive designs of one generator
        g = np.random.default_rng(5)
        a, b = S.base_samples(50, inp, method=method, seed=5)
        assert np.array_equal(a, inp.sample(50, method=method, seed=g))
        assert np.array_equal(b, inp.sample(50, method=method, seed=g))
    # sobol: one 2d-dimensional sequence, its halves
    u = S.Inputs.unit(6).sample(64, method="sobol", seed=5)
    a, b = S.base_samples(64, inp, method="sobol", seed=5)
    assert np.array_equal(a, inp.from_unit(u[:, :3])) and np.array_equal(b, inp.from_unit(u[:, 3:]))
    # the Spearman designs: the uniform laws of the bounds, bitwise
    bounds = np.array([[0.0, -1.0, 2e-5], [3e-3, 1.0, 4e-5]])
    x = S.latin_hypercube(30, bounds, 8)
    assert np.array_equal(x, S.Inputs.from_bounds(bounds).sample(30, method="lhs", seed=8))
    assert np.array_equal(S.repeated_latin_hypercube(30, bounds, repeats=2, seed=1)[1],
                          S.Inputs.from_bounds(bounds).sample(
                              30, method="lhs", seed=np.random.SeedSequence(1).spawn(2)[1]))


def test_latin_hypercube_takes_a_zero_width_column_that_no_law_describes():
    bounds = np.array([[0.0, 5.0, -1.0], [2.0, 5.0, 1.0]])      # the middle input held at 5
    x = S.latin_hypercube(20, bounds, 3)
    assert np.all(x[:, 1] == 5.0)
    # the other columns: the unit-cube design of all three columns, mapped
    u = S.Inputs.unit(3).sample(20, method="lhs", seed=3)
    assert np.array_equal(x[:, [0, 2]], (bounds[0] + u * (bounds[1] - bounds[0]))[:, [0, 2]])
    for c in (x[:, 0], x[:, 2] + 1):        # one point per stratum of width 0.1
        assert np.array_equal(np.sort(np.floor(10 * c)), np.arange(20))
    with pytest.raises(ValueError, match="lower < upper"):
        S.Inputs.from_bounds(bounds)
    with pytest.raises(ValueError, match="lower <= upper"):
        S.latin_hypercube(20, bounds[::-1], 3)
