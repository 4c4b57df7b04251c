"""Notebooks 01 and 03's status tables (``papers.visibility``) and notebook 01's measurement
question (``papers.zheng2024.measurement``), checked independently.

* A ballbar worked by hand (readings ``R (sx cos^2 t + sy sin^2 t + a sin t cos t)``, centre and
  bar length as nuisances, and an error with no effect): its statuses follow from numpy's SVD of
  the columns left after the nuisances: the mean scale is a bar length (``sx + sy`` unseen), the
  squareness seen, the idle error blind; the structural status does not change with units.
* A hand-made "machine" whose error columns are a rigid translation, a rigid rotation and a
  bending: the rigid-motion residual is 0, 0 and about 1.
* The paper's machine with its 41 constant errors: the key errors the standard plan leaves
  blind are exactly those whose effect is a rigid motion of the workpiece, and the linear-axis
  tests see nothing of a constant error (their columns vanish beyond their set-up nuisances,
  redone here with numpy's least squares).
"""

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import pytest  # noqa: E402

from mtaccuracy.machines import build  # noqa: E402
from mtaccuracy.measure import instruments, motions  # noqa: E402
from mtaccuracy.measure.design import Design  # noqa: E402
from mtaccuracy.papers import visibility as V  # noqa: E402
from mtaccuracy.papers import zheng2024  # noqa: E402
from mtaccuracy.papers.zheng2024 import measurement as M  # noqa: E402

R, SIGMA = 100.0, 0.1


def _ballbar(n=36, scale=(1.0, 1.0, 1.0, 1.0), name="ballbar"):
    """Readings (um) per unit of sx, sy (mm/mm), a (rad) and an idle error; the units of each
    column multiplied by ``scale`` (a change of units)."""
    t = 2 * np.pi * np.arange(n) / n
    c, s = np.cos(t), np.sin(t)
    A = 1e3 * R * np.c_[c * c, s * s, s * c, 0 * c] * np.asarray(scale)
    N = 1e3 * np.c_[-c, -s, np.ones(n)]
    return Design(name, A, N, SIGMA, ("sx", "sy", "a", "idle"), ("cx", "cy", "L"),
                  tuple(f"t{k}" for k in range(n)))


def _svd_statuses(d):
    """seen / combination / blind from numpy: project off N, normalise columns, SVD."""
    P = d.A - d.N @ np.linalg.lstsq(d.N, d.A, rcond=None)[0]
    norm = np.linalg.norm(P, axis=0)
    zero = norm <= 1e-9 * np.linalg.norm(d.A, axis=0).clip(1e-300)
    Q = P[:, ~zero] / norm[~zero]
    _, s, vt = np.linalg.svd(Q)
    null = vt[int(np.sum(s > 1e-9 * s[0])):]
    out, k = {}, 0
    for j, e in enumerate(d.errors):
        if zero[j]:
            out[e] = "blind"
        else:
            out[e] = "combination" if null.size and np.abs(null[:, k]).max() > 1e-9 else "seen"
            k += 1
    return out


def test_hand_ballbar_statuses_follow_from_the_svd_and_not_from_units():
    d = _ballbar()
    want = _svd_statuses(d)
    assert want == {"sx": "combination", "sy": "combination", "a": "seen", "idle": "blind"}
    table, plan = V.visibility_table([d], symbols=list(d.errors))
    got = table[table.test == "plan"].set_index("symbol")
    assert got.status.to_dict() == want
    assert got.combination["sx"] == "sx + sy" == got.combination["sy"]     # the mean scale
    assert plan.rank == 2
    # new units for every column (um vs m, urad vs rad): the structure is the same
    d2 = _ballbar(scale=(1e-6, 1e3, 1e6, 1.0))
    t2, _ = V.visibility_table([d2], symbols=list(d2.errors))
    assert t2[t2.test == "plan"].status.tolist() == list(want.values())


def test_structural_priors_equalise_the_columns_left_after_the_nuisances():
    d = _ballbar(scale=(1.0, 1e3, 1e-2, 1.0))
    prior = V.structural_prior_sd(d)
    P = (d.A - d.N @ np.linalg.lstsq(d.N, d.A, rcond=None)[0]) / SIGMA
    lengths = np.linalg.norm(P * prior, axis=0)
    assert lengths[:3] == pytest.approx(V.STRUCTURAL_GAIN, rel=1e-9)
    assert prior[3] == 1.0                                             # absorbed: blind anyway


def test_the_prior_decides_at_the_derived_threshold():
    # with sx, sy known (tiny priors) the squareness is seen iff its prior moves the readings
    # enough: prior**2 ||P a||**2 / sigma**2 >= shrink - 1, ||P a||**2 = (1e3 R)**2 n / 8; it is
    # blind when the data remove at most 1/shrink of its variance (s**2 <= 1/99: a factor 1/99 of
    # the critical prior), learned in part ("combination") in between
    d = _ballbar()
    critical = np.sqrt(99.0) * SIGMA / (1e3 * R * np.sqrt(d.n_obs / 8))
    for factor, want in ((0.7, "combination"), (1.4, "seen"), (0.7 / 99, "blind"),
                         (1.4 / 99, "combination")):
        table, _ = V.visibility_table([d], symbols=["a"],
                                      prior_sd=[1e-12, 1e-12, factor * critical, 1.0])
        assert table.status.tolist() == [want, want]                    # the test and the plan


class _Rigid:
    """Three errors on a 'machine': a translation along x, a turn about z, a bend (x**2)."""

    error_names = ("tx", "wz", "bend")
    n_errors = 3

    def relative(self, errors, pose, with_errors=False):
        tip = np.c_[pose["x"], pose["y"], pose["z"]]
        return np.tile(np.eye(3), (len(tip), 1, 1)), tip

    def jacobian(self, pose):
        x, y = np.asarray(pose["x"]), np.asarray(pose["y"])
        J = np.zeros((x.size, 6, 3))
        J[:, 0, 0] = 1.0                                        # dp = (1, 0, 0)
        J[:, 0, 1], J[:, 1, 1], J[:, 5, 1] = -y, x, 1.0          # dp = e_z x p
        J[:, 1, 2] = x * x / 100.0                               # not rigid
        return J


def test_rigid_motion_residual_on_a_hand_made_machine():
    rng = np.random.default_rng(3)
    pose = {k: rng.uniform(-200, 200, 20) for k in "xyz"}
    r = M.workpiece_motion_residual(_Rigid(), symbols=["tx", "wz", "bend"], pose=pose)
    assert r.residual["tx"] < 1e-12 and r.residual["wz"] < 1e-12
    assert r.residual["bend"] > 0.1
    assert r.effect["tx"] == pytest.approx(1.0)
    with pytest.raises(ValueError, match="unknown errors.*nope"):
        M.workpiece_motion_residual(_Rigid(), symbols=["nope"], pose=pose)


@pytest.fixture(scope="module")
def paper_plan():
    machine = build("ac_double_turntable")
    sd = np.array([e.to_library * (15.0 if e.translational else 10.0) / 3
                   for e in machine.catalogue])
    model = motions.motion_model(machine, degree=0)
    tests = instruments.standard_plan(model, tool=100.0, sigma=0.5)
    return machine, sd, [t.design() for t in tests]


def test_blind_key_errors_are_exactly_the_rigid_motions_of_the_workpiece(paper_plan):
    machine, sd, designs = paper_plan
    keys = pd.read_csv(zheng2024.__file__.rsplit("lib/", 1)[0]
                       + "data/papers/zheng2024_table2_key_errors.csv").symbol.unique().tolist()
    keys = [k for k in machine.error_names if k in keys]
    table, plan = V.visibility_table(designs, symbols=keys, prior_sd=sd)
    summary = V.per_error_summary(table)
    blind = set(summary.index[summary.status == "blind"])
    rng = np.random.default_rng(7)
    pose = {k: rng.uniform(*machine.travels[k], 30) for k in ("x", "y", "z", "A", "C")}
    pose["L"] = np.full(30, 100.0)
    rigid = M.workpiece_motion_residual(machine, symbols=keys, pose=pose)
    moves = set(rigid.index[(rigid.effect > 0) & (rigid.residual < 1e-9)])
    assert blind == moves and len(blind) >= 8
    assert (summary.n_tests[summary.status == "blind"] == 0).all()
    assert plan.rank < machine.n_errors


def test_linear_axis_tests_see_nothing_of_constant_errors(paper_plan):
    machine, sd, designs = paper_plan
    linear = [d for d in designs if d.name.startswith(("laser", "straightness", "angular"))]
    assert len(linear) == 18                     # 3 axes x (laser, 2 straightness, 3 angles)
    for d in linear:
        P = d.A - d.N @ np.linalg.lstsq(d.N, d.A, rcond=None)[0]
        assert np.abs(P).max() <= 1e-9 * np.abs(d.A).max()       # all absorbed by the set-up
    table, _ = V.visibility_table(linear, symbols=list(machine.error_names), prior_sd=sd)
    assert set(table.status) == {"blind"}


def test_bad_input_is_refused_with_the_name():
    d = _ballbar()
    with pytest.raises(ValueError, match=r"\['nope'\] are not errors"):
        V.visibility_table([d], symbols=["sx", "nope"])
    with pytest.raises(ValueError, match="at least one test"):
        V.visibility_table([], symbols=["sx"])
    with pytest.raises(ValueError, match="no rows of the plan"):
        V.per_error_summary(pd.DataFrame({"test": ["t"], "symbol": ["sx"], "status": ["seen"],
                                          "combination": [""]}))
    table, _ = V.visibility_table([d], symbols=["sx"])
    with pytest.raises(ValueError, match="colours needs a colour"):
        V.status_matrix_figure(table, colours={"seen": "#000000"}, title="t")
    with pytest.raises(ValueError, match="unknown status"):
        V.status_matrix_figure(table.assign(status="maybe"),
                               colours=dict.fromkeys(V.STATUSES, "#000000"), title="t")


def test_status_matrix_draws_one_cell_per_row_and_column_and_a_legend():
    import matplotlib.pyplot as plt

    d = _ballbar()
    with pytest.raises(ValueError, match="named twice.*ballbar"):
        V.visibility_table([d, _ballbar(n=12)], symbols=list(d.errors))
    table, _ = V.visibility_table([d, _ballbar(n=12, name="short")], symbols=list(d.errors))
    fig = V.status_matrix_figure(table.iloc[:-1], colours=dict(zip(V.STATUSES, (
        "#CC6677", "#332288", "#DDDDDD"), strict=True)), title="t", highlight=["a"])
    ax = fig.axes[0]
    assert [t.get_text() for t in ax.get_yticklabels()] == list(d.errors)
    assert [t.get_text() for t in ax.get_xticklabels()] == ["ballbar", "short", "plan"]
    letters = [t.get_text() for t in ax.texts]
    assert letters.count("-") == 1                            # the cell dropped from the table
    assert [t.get_text() for t in ax.get_legend().get_texts()] == [
        "seen (s)", "combination (c)", "blind (empty)", "n/a (-)"]
    assert [t.get_fontweight() for t in ax.get_yticklabels()].count("bold") == 1
    plt.close(fig)
