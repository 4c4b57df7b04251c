"""Guo et al. 2016 (notebook 03): the printed Eqs. 8, 11-13 against the second-order expansion
of the matrix product; the second audit: the model-free eigenvalue bound on sums of squared
Spearman coefficients, its law over Latin hypercube designs, the exchangeable pairs, the
units-slip reading of Eq. 12 and what an XY circle sees in the paper's model."""

import numpy as np
import pandas as pd
import pytest
import sympy as sp

from mtaccuracy import errors, sensitivity
from mtaccuracy.machines import build
from mtaccuracy.papers import guo2016

MACHINE = build("vertical_xyfz")
NAMES = MACHINE.error_names
KINDS = [e.kind for e in MACHINE.catalogue]
RANGES = {"positioning": (0.0, 3.0), "straightness": (0.0, 4.0), "angular": (0.0, 3.2e-5),
          "squareness": (0.0, 1.9)}
BOUNDS = errors.uniform_bounds(MACHINE.catalogue, RANGES)
#: errors of realistic size (mm, rad) by kind, in catalogue order, and a pose (mm)
SCALE = np.array([3e-3] * 3 + [4e-3] * 6 + [3.2e-5] * 9 + [1.9e-6] * 3)
POSE = dict(x=120.0, y=-80.0, z=150.0, D1=10.0, D2=-20.0, D3=90.0)


def test_second_order_expansion_has_third_order_remainder():
    rng = np.random.default_rng(2)
    sym_e, sym_p = guo2016.symbols()
    f2 = sp.lambdify([list(sym_e.values()), list(sym_p.values())], guo2016.second_order(), "numpy")
    e = rng.uniform(-1, 1, size=(4, 21)) * SCALE
    gaps = []
    for t in (10.0, 20.0):
        full = MACHINE.pose_error(t * e, POSE)[:, :3]
        gaps.append(np.abs(full - np.column_stack(f2((t * e).T, [POSE[k] for k in sym_p]))).max())
    assert gaps[1] / gaps[0] == pytest.approx(8.0, rel=0.05)  # scales as t^3


def test_typo_list_finds_the_known_typos():
    rows = {(r["equation"], r["term"]): r for r in guo2016.closed_form_typos()}
    assert rows[("Eq. 11", "1")]["printed"] == "D1"  # spurious constant
    assert rows[("Eq. 12", "1")]["printed"] == "D2"
    assert rows[("Eq. 11", "dy(y)*ez(x)")]["printed"] == "-2"  # dy(y) written twice
    assert rows[("Eq. 11", "dy(z)*ez(x)")]["kind"] == "missing"
    assert rows[("Eq. 12", "dx(y)*dz(x)")]["kind"] == "spurious"  # dz(x) for ez(x)
    assert rows[("Eq. 13", "ey(x)*ey(y)")]["printed"] == "-D3 + z"  # sign of z term
    assert ("Eq. 8", "-ey(z)") in rows
    # No first-order term is wrong except the spurious constants.
    in_eqs = [r for r in rows.values() if r["equation"] != "Eq. 8" and r["kind"] != "bracket"]
    assert {r["degree"] for r in in_eqs} == {0, 2}  # no first-order term is wrong
    # Eq. 13: the missing z*S_xz*ey(x) and the bracket after y, never closed as printed
    assert rows[("Eq. 13", "S_xz*ey(x)")]["derived"] == "z"
    assert rows[("Eq. 13", "y*(S_xy*ey(x) + ex(x))")]["kind"] == "bracket"


def test_the_bracket_reading_is_the_one_compared():
    """The y terms of the transcribed Eq. 13 are exactly the declared reading of its unclosed
    bracket, and that reading is also what the matrix product gives."""
    e, p = guo2016.symbols()
    assert list(p) == ["x", "y", "z", "D1", "D2", "D3"]
    ez = sp.expand(guo2016.printed_closed_form(e, **p)[2])
    y_terms = sp.expand(sp.diff(ez, p["y"]) * p["y"])
    (eq, comp, _, reading, degree), = guo2016.PRINTED_UNBALANCED
    assert (eq, comp, degree) == ("Eq. 13", "Ez", 1)
    expected = p["y"] * (e["S_xy"] * e["ey(x)"] + e["ex(x)"])
    assert str(expected) == reading
    assert sp.expand(y_terms - expected) == 0
    derived_y = sp.expand(sp.diff(guo2016.second_order()[2], p["y"]) * p["y"])
    assert sp.expand(derived_y - expected) == 0


def test_printed_form_differs_from_product_only_by_its_typos():
    e = np.random.default_rng(3).uniform(0, 1, size=(50, 21)) * SCALE
    named = {s: e[:, j] for j, s in enumerate(NAMES)}
    printed = np.column_stack(guo2016.printed_closed_form(named, **POSE))
    full = MACHINE.pose_error(e, POSE)[:, :3]
    gap = printed - full - np.array([POSE["D1"], POSE["D2"], 0.0])
    assert np.abs(gap).max() < 1e-4  # second-order size (the dz*dx typo is ~1e-5 mm)
    assert np.abs(gap).max() > 1e-7  # but not zero: the typos are real



def test_the_pose_is_passed_by_name():
    e, p = guo2016.symbols()
    with pytest.raises(TypeError, match="positional"):
        guo2016.printed_closed_form(e, *p.values())


def _lambda_max(x):
    return np.linalg.eigvalsh(sensitivity.spearman(x, x))[..., -1]


def _models(x, rng):
    """Outputs of very different kinds: monotone, non-monotone, interacting, noisy, tied."""
    w = rng.normal(size=x.shape[1])
    lin = x @ w
    return np.column_stack([
        lin, np.exp(lin / lin.std()), np.sin(5 * x[:, 0]) + x[:, 1] * x[:, 2],
        np.abs(x[:, 0] - 0.5) - x[:, 3] ** 3, rng.normal(size=len(x)),
        np.round(lin, 0),                                    # heavy ties
        x[:, 0] + 0.01 * rng.normal(size=len(x)),
    ])


@pytest.mark.parametrize("n, d", [(12, 4), (50, 6), (200, 9)])
def test_sum_of_squares_never_exceeds_lambda_max_of_the_subset(n, d):
    rng = np.random.default_rng(n + d)
    for _ in range(20):
        x = sensitivity.latin_hypercube(n, np.array([np.zeros(d), np.ones(d)]), rng)
        y = _models(x, rng)
        r = sensitivity.spearman(x, y)                               # (d, q)
        for _ in range(5):
            s = np.sort(rng.choice(d, size=rng.integers(1, d + 1), replace=False))
            lam = _lambda_max(x[:, s])
            assert np.all((r[s] ** 2).sum(axis=0) <= lam * (1 + 1e-12))
            # the sharper form: r^T R^-1 r <= 1 (an R^2 of the output's ranks on the inputs')
            c = sensitivity.spearman(x[:, s], x[:, s])
            assert np.all(np.einsum("pq,pq->q", r[s], np.linalg.solve(c, r[s])) <= 1 + 1e-9)
        # interlacing: a subset's lambda_max never exceeds the whole design's
        assert _lambda_max(x[:, : d // 2 + 1]) <= _lambda_max(x) * (1 + 1e-12)


def test_the_bound_is_nearly_attained_by_the_top_eigenvector():
    rng = np.random.default_rng(1)
    x = sensitivity.latin_hypercube(400, np.array([np.zeros(8), np.ones(8)]), rng)
    u = sensitivity.centred_ranks(x)
    c = sensitivity.spearman(x, x)
    lam, vec = np.linalg.eigh(c)
    y = u @ vec[:, -1]                     # output ranked along the top eigenvector
    ss = (sensitivity.spearman(x, y[:, None])[:, 0] ** 2).sum()
    assert lam[-1] > 1.05                  # a finite design: the bound is above 1 ...
    assert 0.95 * lam[-1] <= ss <= lam[-1] * (1 + 1e-12)   # ... and nearly reached (y's ranks
    # are not exactly U a)
    assert ss > 1.0


def test_lhs_rank_eigenvalues_has_the_law_of_real_designs():
    n, k = 40, 5
    lam = sensitivity.lhs_rank_eigenvalues(n, k, designs=600, seed=3)
    designs = sensitivity.repeated_latin_hypercube(n, np.array([np.zeros(k), np.ones(k)]),
                                                   repeats=600, seed=4)
    direct = _lambda_max(designs)
    assert lam.shape == (600,) and np.all((lam >= 1) & (lam <= k))
    se = np.hypot(lam.std(), direct.std()) / np.sqrt(600)
    assert abs(lam.mean() - direct.mean()) < 4 * se
    assert abs(np.quantile(lam, 0.9) - np.quantile(direct, 0.9)) < 0.05


def test_two_inputs_give_one_plus_the_absolute_rank_correlation():
    # k = 2: lambda_max = 1 + |r12|, and r12 of two independent permutations has variance 1/(n-1)
    n = 30
    lam = sensitivity.lhs_rank_eigenvalues(n, 2, designs=4000, seed=5)
    m2 = np.mean((lam - 1) ** 2)
    assert abs(m2 - 1 / (n - 1)) < 4 * np.std((lam - 1) ** 2) / np.sqrt(lam.size)
    # exact arithmetic: r12 = 1 - 6 sum d^2 / (n (n^2 - 1)), so |r12| n (n^2 - 1) / 6 is an integer
    steps = (lam - 1) * n * (n * n - 1) / 6.0
    assert np.allclose(steps, np.round(steps), atol=1e-6)


def test_lhs_rank_eigenvalues_is_a_prefix_and_refuses_bad_sizes():
    a = sensitivity.lhs_rank_eigenvalues(20, 3, designs=2500, seed=9)
    b = sensitivity.lhs_rank_eigenvalues(20, 3, designs=1200, seed=9)
    assert np.array_equal(a[:1200], b)
    with pytest.raises(ValueError, match="k must be an integer >= 2"):
        sensitivity.lhs_rank_eigenvalues(20, 1, designs=10, seed=0)
    with pytest.raises(ValueError, match="designs must be"):
        sensitivity.lhs_rank_eigenvalues(20, 3, designs=0, seed=0)


def test_monte_carlo_p_and_the_panel_verdicts():
    sim = np.array([1.0, 1.1, 1.2, 1.3])
    assert guo2016.monte_carlo_p(1.15, sim) == 3 / 5
    assert guo2016.monte_carlo_p(9.0, sim) == 1 / 5
    # under the null the p-value is (super-)uniform: P(p <= a) <= a
    rng = np.random.default_rng(0)
    ps = np.array([guo2016.monte_carlo_p(rng.normal(), rng.normal(size=99)) for _ in range(2000)])
    assert np.mean(ps <= 0.05) < 0.05 + 3 * np.sqrt(0.05 * 0.95 / 2000)
    pub = pd.DataFrame({"output": np.repeat(["Ex", "Ey", "Ez", "Et"], 2),
                        "spearman": [0.5, 0.5, 1.0, 0.8, 0.7, 0.7, 0.95, 0.7]})
    lam8 = np.linspace(1.0, 1.3, 999)
    lam21 = np.linspace(1.2, 1.5, 999)
    t = guo2016.eigen_bound_table(pub, lam_set=lam8, lam_all=lam21, alpha=0.01).set_index("output")
    assert t.loc["Ey", "fixed_set"] == t.loc["Ey", "any_set"] == "impossible"   # 1.64
    assert t.loc["Ey", "p_any_set"] == 1 / 1000
    assert t.loc["Ex", "fixed_set"] == "not excluded"                           # 0.50
    assert (t.loc["Et", "fixed_set"], t.loc["Et", "any_set"]) == ("impossible", "not excluded")


def _first():
    sym_e, _ = guo2016.symbols()
    return {o: {s: sp.diff(c, sym_e[s]).subs({v: 0 for v in sym_e.values()}) for s in NAMES}
            for o, c in zip(("Ex", "Ey", "Ez"), guo2016.second_order(), strict=True)}


@pytest.fixture(scope="module")
def pairs():
    return guo2016.exchangeable_pairs(_first(), NAMES, KINDS)


def test_exchangeable_pairs(pairs):
    assert ("Ex", "dx(y)", "dx(z)") in pairs and ("Ez", "dz(x)", "dz(y)") in pairs
    assert ("Et", "dz(x)", "dz(y)") in pairs and ("Et", "dx(y)", "dx(z)") in pairs
    assert ("Ey", "ez(x)", "ez(z)") in pairs                 # both D1 in Ey
    assert ("Ex", "dx(x)", "dx(y)") not in pairs             # same coefficient, other range
    assert ("Et", "ez(x)", "ez(y)") not in pairs             # Ex: -D2 - y against -D2
    assert ("Ex", "dy(y)", "dz(z)") not in pairs             # both structural zeros: no pair
    # every pair is exchangeable in the model: swapping the two columns of a design leaves the
    # first-order output unchanged at a random pose
    rng = np.random.default_rng(2)
    x = sensitivity.latin_hypercube(50, BOUNDS, rng)
    pose = dict(x=10.0, y=rng.uniform(-400, 400), z=rng.uniform(-400, 400), D1=rng.uniform(-99, 99),
                D2=rng.uniform(-99, 99), D3=rng.uniform(-99, 99))
    y0 = sensitivity.position_outputs(MACHINE.pose_error(x, pose))
    for o, a, b in pairs:
        xs = x.copy()
        xs[:, [NAMES.index(a), NAMES.index(b)]] = xs[:, [NAMES.index(b), NAMES.index(a)]]
        y1 = sensitivity.position_outputs(MACHINE.pose_error(xs, pose))
        k = guo2016.OUTPUTS.index(o)
        assert np.allclose(y1[:, k], y0[:, k], rtol=0, atol=1e-3 * np.abs(y0[:, k]).max())


def test_pair_table_gaps_and_bounds():
    pub = pd.DataFrame({"output": ["Ex"] * 3 + ["Et"] * 2,
                        "symbol": ["dx(y)", "dx(z)", "dx(x)", "dz(x)", "ey(z)"],
                        "spearman": [0.6, 0.4, 0.1, 0.75, -0.2]})
    rep = np.random.default_rng(0).normal(0, 0.05, (300, 21, 4))
    pairs = [("Ex", "dx(y)", "dx(z)"), ("Et", "dz(x)", "dz(y)"), ("Et", "dy(x)", "dy(z)")]
    t = guo2016.pair_table(pub, pairs=pairs, rho_rep=rep, names=NAMES)
    assert list(t.pair) == ["dx(y) vs dx(z)", "dz(x) vs dz(y)"]      # neither dy printed: left out
    assert t.printed_gap.tolist() == pytest.approx([0.2, 0.55])       # 0.75 - |-0.2|
    assert t.gap_is_bound.tolist() == [False, True] and t.listed.tolist() == ["both", "dz(x)"]
    assert t.sd_of_gap.iloc[0] == pytest.approx(0.05 * np.sqrt(2), rel=0.15)


def test_units_slip_makes_the_typo_term_dominate_ey_at_every_pose():
    slip = guo2016.UnitsSlip(MACHINE)
    x = sensitivity.latin_hypercube(2000, BOUNDS, np.random.default_rng(7))
    um = {s: x[:, j] * (1e3 if KINDS[j] in ("positioning", "straightness") else 1.0)
          for j, s in enumerate(NAMES)}
    rho = []
    for pose in (dict(x=0.0, y=0.0, z=0.0, D1=0.0, D2=0.0, D3=0.0),
                 dict(x=100.0, y=450.0, z=-300.0, D1=150.0, D2=-80.0, D3=250.0)):
        e = slip.pose_error(x, pose)
        assert e.shape == (2000, 6) and np.all(e[:, 3:] == 0)
        hand = um["dy(x)"] + um["dy(y)"] + um["dy(z)"] + um["dz(x)"] * (um["dx(y)"] + um["dx(z)"])
        assert np.allclose(e[:, 1], hand, atol=0.05)         # angle x mm terms: < 0.05 "um"
        rho.append(sensitivity.spearman(x, sensitivity.position_outputs(e)))
    k = NAMES.index("dz(x)")
    assert abs(rho[0][k, 1] - rho[1][k, 1]) < 0.01 and rho[0][k, 1] > 0.7
    # dx(y), dx(z) stay exchangeable in the slipped Ey
    assert abs(rho[0][NAMES.index("dx(y)"), 1] - rho[0][NAMES.index("dx(z)"), 1]) < 0.1


def test_an_xy_circle_sees_only_ez_x_and_s_xy():
    t = guo2016.circle_terms().set_index("component")
    assert sp.simplify(sp.sympify(t.loc["Ex", "varies_on_circle"].replace("(x)", "_x"))
                       - sp.sympify("-y*(S_xy + ez_x)")) == 0
    assert (t.after_A == "0").all()
    assert "S_yz" not in " ".join(t.errors_seen)
    # independent check on the machine: at fixed z, the points of a circle differ only by
    # -y (ez(x) + S_xy) in x and -y S_xy ez(x) in y
    rng = np.random.default_rng(3)
    e = sensitivity.latin_hypercube(2, BOUNDS, rng)[0]
    th = np.linspace(0, 2 * np.pi, 36, endpoint=False)
    cx, cy, r0 = 30.0, -20.0, 150.0
    pose = dict(x=cx + r0 * np.cos(th), y=cy + r0 * np.sin(th), z=np.full(36, 80.0),
                D1=np.full(36, 5.0), D2=np.full(36, -7.0), D3=np.full(36, 120.0))
    p = MACHINE.pose_error(np.tile(e, (36, 1)), pose)[:, :2]
    ez_x, s_xy = e[NAMES.index("ez(x)")], e[NAMES.index("S_xy")]
    dev = p - p[0]
    dy = pose["y"] - pose["y"][0]
    assert np.allclose(dev[:, 0], -dy * (ez_x + s_xy), rtol=0, atol=1e-12)
    assert np.allclose(dev[:, 1], -dy * s_xy * ez_x, rtol=0, atol=1e-12)
