"""Closed-form Sobol indices of the first-order model (sensitivity.linear): against sampling,
analytic pose integrals, one-pose-at-a-time evaluation, and the size of the remainder."""

import numpy as np
import pytest

from mtaccuracy import sensitivity as S
from mtaccuracy.machines import build

H3 = build("horizontal_3axis")
# 2 x the acceptance values of data/rong (mm, rad): positioning, straightness, angular, squareness
SCALE = np.array([7.5e-3] * 3 + [1e-2] * 6 + [8e-5] * 9 + [4.75e-6] * 3)
ZHENG = build("ac_double_turntable")
ZHENG_SD = np.array([e.to_library * (15.0 if e.translational else 10.0) / 3
                     for e in ZHENG.catalogue])
ZHENG_POSE = dict(x=106.1, y=-58.6, z=-255.3, A=np.deg2rad(60.7), C=np.deg2rad(56.7))


def test_uniform_moments_and_linear_indices_equal_sampling_with_uniform_offset_errors():
    """Uniform errors that are not centred (0 to 2 x SCALE, as tolerances are often given):
    the closed form needs only the variances (the means shift the output, no index)."""
    bounds = np.vstack([np.zeros(21), 2 * SCALE])
    mean, var = S.uniform_moments(bounds)
    assert np.allclose(mean, SCALE) and np.allclose(var, (2 * SCALE) ** 2 / 12)
    pose = dict(x=560.0, y=120.0, z=410.0, tool_z=-80.0)
    jac = H3.jacobian(pose)[0, :3]                       # (3, 21)
    lin = S.linear_indices(jac, sd=np.sqrt(var))                        # (21, 3), as st
    ua, ub = S.base_samples(2**13, 21, method="sobol", seed=3)
    s1, st = S.sobol_indices(lambda e: e @ jac.T, S.Inputs.from_bounds(bounds).from_unit(ua),
                             S.Inputs.from_bounds(bounds).from_unit(ub))
    # Sobol' design, N = 8192: the sampling error of these indices is below 0.01
    assert np.abs(st - lin).max() < 0.015 and np.abs(s1 - lin).max() < 0.015
    assert lin[:, 0].max() > 0.1  # not a trivial comparison


def _affine_case():
    """J(t, x, y) = A + t D + x B + y C: affine in the box coordinates x, y and in the case
    parameter t; q = 2 outputs, d = 4 inputs."""
    rng = np.random.default_rng(11)
    a, b, c, d = (rng.normal(size=(2, 4)) for _ in range(4))

    def jac(p):
        t, x, y = (np.asarray(p[k], dtype=float)[:, None, None] for k in ("t", "x", "y"))
        return a + t * d + x * b + y * c
    return jac, a, b, c, d


@pytest.mark.parametrize("nodes", [2, 3, 5])
def test_pose_box_indices_are_the_exact_integrals_when_affine_in_the_pose(nodes):
    jac, a, b, c, d = _affine_case()
    mean, var = np.array([0.3, -1.0, 0.0, 2.0]), np.array([1.0, 0.5, 2.0, 0.1])
    ts = np.array([-1.0, 0.0, 2.5])
    box = dict(x=(-1.0, 3.0), y=(2.0, 2.5))
    s1, st, v = S.pose_box_indices(jac, mean=mean, var=var, poses=dict(t=ts), pose_bounds=box,
                                   nodes=nodes)
    assert s1.shape == st.shape == (3, 4, 2) and v.shape == (3, 2)
    # analytic: x, y independent uniforms; E[J] at the centre, E[J^2] adds B^2 var_x + C^2
    # var_y, and Var_pose(J m) = (B m)^2 var_x + (C m)^2 var_y
    mx, vx = 1.0, 4.0**2 / 12
    my, vy = 2.25, 0.5**2 / 12
    for i, t in enumerate(ts):
        ej = a + t * d + mx * b + my * c
        ej2 = ej**2 + b**2 * vx + c**2 * vy
        vv = ej2 @ var + (b @ mean) ** 2 * vx + (c @ mean) ** 2 * vy
        assert np.allclose(v[i], vv, rtol=1e-13, atol=0)
        assert np.allclose(s1[i], (ej**2 * var / vv[:, None]).T, rtol=1e-12, atol=1e-15)
        assert np.allclose(st[i], (ej2 * var / vv[:, None]).T, rtol=1e-12, atol=1e-15)
    # one node is the midpoint: the mean is right, the spread over the box is lost
    m1, t1, _ = S.pose_box_indices(jac, mean=mean, var=var, poses=dict(t=ts), pose_bounds=box,
                                   nodes=1)
    assert np.allclose(m1, t1) and not np.allclose(t1, st, atol=1e-3)


def test_trigonometric_pose_dependence_converges_as_nodes_grow():
    """J depends on cos and sin of an angle uniform on (-2.27, 2.27) rad (the A travel), so
    no Gauss rule is exact; the error falls fast with the number of nodes."""
    lo, hi = -2.27, 2.27
    m = np.array([1.0, 0.5])
    var = np.array([0.2, 1.0])

    def jac(p):
        th = np.asarray(p["A"], dtype=float)
        return np.stack([np.stack([np.cos(th), np.full_like(th, 0.3)], -1),
                         np.stack([np.sin(th), np.cos(th) * np.sin(th)], -1)], -2)
    # exact: E[cos] = (sin hi - sin lo)/L, E[cos^2] = 1/2 + sin(2hi)-sin(2lo) / 4L, ...
    L = hi - lo
    e_cos = (np.sin(hi) - np.sin(lo)) / L
    e_cos2 = 0.5 + (np.sin(2 * hi) - np.sin(2 * lo)) / (4 * L)
    e_sin = (np.cos(lo) - np.cos(hi)) / L                  # 0: symmetric box
    e_sin2 = 1 - e_cos2
    e_cs = (np.sin(hi) ** 2 - np.sin(lo) ** 2) / (2 * L)   # 0 as well
    e_cs2 = (L / 8 - (np.sin(4 * hi) - np.sin(4 * lo)) / 32) / L
    ej = np.array([[e_cos, 0.3], [e_sin, e_cs]])
    ej2 = np.array([[e_cos2, 0.09], [e_sin2, e_cs2]])
    # Var_pose(J m): row 0 = cos + 0.15, row 1 = sin + 0.5 cos sin
    e_sin2_cos = (np.sin(hi) ** 3 - np.sin(lo) ** 3) / (3 * L)
    var_pose = np.array([e_cos2 - e_cos**2,
                         e_sin2 + e_sin2_cos + 0.25 * e_cs2 - (e_sin + 0.5 * e_cs) ** 2])
    vv = ej2 @ var + var_pose
    exact_s1, exact_st = (ej**2 * var / vv[:, None]).T, (ej2 * var / vv[:, None]).T
    errors = []
    for nodes in (2, 4, 8, 16):
        s1, st, v = S.pose_box_indices(jac, mean=m, var=var, pose_bounds=dict(A=(lo, hi)),
                                         nodes=nodes)
        errors.append(np.abs(st[0] - exact_st).max())
    assert errors[0] > 1e-3                       # two nodes are not enough here
    assert errors[1] < errors[0] / 10 and errors[2] < errors[1] / 100
    assert errors[3] < 1e-13 and np.allclose(v[0], vv, rtol=1e-13)
    assert np.allclose(s1[0], exact_s1, rtol=0, atol=1e-13)


def test_pose_box_indices_equal_sampling_with_the_pose_as_an_input_on_h3():
    """The three-axis machine with the pose uniform in its box, as three more inputs of a
    Monte Carlo Sobol estimate of the first-order model, with offset error ranges (so the
    pose variance of J m counts): the closed form is what the estimates converge to."""
    bounds = np.vstack([-0.5 * SCALE, 1.5 * SCALE])
    mean, var = S.uniform_moments(bounds, 21)
    box = dict(x=(0.0, 700.0), y=(0.0, 600.0), z=(0.0, 500.0))
    tool = dict(tool_x=0.0, tool_y=0.0, tool_z=-150.0)
    s1, st, v = S.pose_box_indices(H3.jacobian, mean=mean, var=var, poses=tool, pose_bounds=box,
                                   components=3,
                                   names=H3.axes + H3.tool_offsets, required=H3.axes)
    full = np.hstack([bounds, np.array(list(box.values())).T])      # (2, 24)

    def model(z):
        p = dict(zip("xyz", z[:, 21:].T, strict=True), **tool)
        return np.einsum("nqd,nd->nq", H3.jacobian(p)[:, :3], z[:, :21])
    ua, ub = S.base_samples(2**13, 24, method="sobol", seed=8)
    a, b = S.Inputs.from_bounds(full).from_unit(ua), S.Inputs.from_bounds(full).from_unit(ub)
    es1, est = S.sobol_indices(model, a, b)
    assert np.abs(est[:21] - st[0]).max() < 0.02 and np.abs(es1[:21] - s1[0]).max() < 0.02
    assert np.allclose(model(np.vstack([a, b])).var(0), v[0], rtol=0.05)
    assert (st[0] - s1[0]).max() > 0.05           # the pose matters: S1 and ST differ


def test_rotary_box_on_the_zheng_machine_converges():
    """A and C of the five-axis machine in a box: the Gauss rule converges as nodes grow."""
    mean, var = np.zeros(41), ZHENG_SD**2
    fixed = {k: ZHENG_POSE[k] for k in "xyz"}
    box = dict(A=(0.0, 1.2), C=(0.0, 2.0))
    st = [S.pose_box_indices(ZHENG.jacobian, mean=mean, var=var, poses=fixed,
                               pose_bounds=box, nodes=n)[1][0]
          for n in (2, 4, 8, 12)]
    steps = [np.abs(st[i + 1] - st[i]).max() for i in range(3)]
    assert steps[0] > 1e-4 and steps[1] < steps[0] / 10 and steps[2] < 1e-10


def test_indices_at_poses_sum_to_one_and_equal_one_pose_at_a_time():
    rng = np.random.default_rng(5)
    poses = {k: rng.uniform(lo, hi, 7) for k, (lo, hi) in ZHENG.travels.items()}
    jac = ZHENG.jacobian(poses)                           # (7, 6, 41)
    s = S.indices_at_poses(jac, var=ZHENG_SD**2)
    assert s.shape == (7, 41, 6)
    assert np.allclose(s.sum(1), 1.0, rtol=0, atol=1e-14)
    for i in range(7):
        assert np.allclose(s[i], S.linear_indices(jac[i], sd=ZHENG_SD), rtol=1e-13, atol=0)
    # an output with no variance (here: a zero row) gets zeros, not NaN
    jac[2, 4] = 0.0
    s = S.indices_at_poses(jac, var=ZHENG_SD**2)
    assert np.all(s[2, :, 4] == 0) and np.allclose(s[2, :, 3].sum(), 1.0)


def test_remainder_of_a_linear_model_is_rounding():
    rng = np.random.default_rng(2)
    jac = rng.normal(size=(3, 5))
    e = rng.normal(size=(1000, 5))
    r = S.nonlinear_remainder(lambda x: x @ jac.T + 7.0, jac, e)
    assert np.all(r.ratio < 1e-14) and np.all(r.max_abs < 1e-13)


def test_remainder_of_a_quadratic_model_is_the_analytic_ratio():
    """y_k = e^T Q_k e + J_k e, e ~ N(0, diag(s^2)): the remainder is the quadratic form,
    E[r] = tr(Q S), Var(r) = 2 tr((Q S)^2), and Cov(J e, r) = 0 (odd moments), so
    Var(y) = J S J^T + 2 tr((Q S)^2)."""
    rng = np.random.default_rng(9)
    d, q, n = 4, 2, 200_000
    s = np.array([1.0, 0.5, 2.0, 0.3])
    jac = rng.normal(size=(q, d))
    qm = rng.normal(size=(q, d, d)) * 0.2
    qm = (qm + np.swapaxes(qm, 1, 2)) / 2
    e = rng.normal(size=(n, d)) * s
    r = S.nonlinear_remainder(lambda x: np.einsum("ni,kij,nj->nk", x, qm, x) + x @ jac.T,
                              jac, e)
    qs = qm * s**2                                                  # Q S, (q, d, d)
    mean_r = np.trace(qs, axis1=1, axis2=2)
    var_r = 2 * np.einsum("kij,kji->k", qs, qs)
    var_y = (jac**2 * s**2).sum(1) + var_r
    # relative standard error of a sample second moment: sqrt((kurtosis - 1) / 4n), below
    # 0.005 here (kurtosis of y and r < 15 at n = 2e5); 3 % is six of them
    assert np.allclose(r.ratio, np.sqrt((var_r + mean_r**2) / var_y), rtol=0.03)
    assert np.allclose(r.centred_ratio, np.sqrt(var_r / var_y), rtol=0.03)
    assert np.all(r.centred_ratio <= r.ratio) and np.all(r.ratio > 0.1)


def test_remainder_bounds_the_index_drift_and_is_second_order_on_a_machine():
    """y = a e1 + b e2 + c e1^2 with standard normals: the exact S1 of e1 is
    (a^2 + 2 c^2) / (a^2 + b^2 + 2 c^2), the linear one a^2 / (a^2 + b^2); they differ by
    less than twice the centred ratio sqrt(2) c / sd(y).  On the Zheng machine the ratio is
    small and grows in proportion to the errors (a second-order remainder)."""
    a, b, c = 1.0, 0.7, 0.15
    vy = a**2 + b**2 + 2 * c**2
    e = np.random.default_rng(4).normal(size=(100_000, 2))
    r = S.nonlinear_remainder(lambda x: a * x[:, 0] + b * x[:, 1] + c * x[:, 0] ** 2,
                              np.array([[a, b]]), e)
    assert np.isclose(r.centred_ratio[0], np.sqrt(2) * c / np.sqrt(vy), rtol=0.03)
    drift = abs((a**2 + 2 * c**2) / vy - a**2 / (a**2 + b**2))
    assert drift < 2 * r.centred_ratio[0]
    jac = ZHENG.jacobian(ZHENG_POSE)[0]
    z = np.random.default_rng(6).standard_normal((4000, 41))
    small, large = (S.nonlinear_remainder(lambda x: ZHENG.pose_error(x, ZHENG_POSE), jac,
                                          z * ZHENG_SD * k) for k in (1.0, 10.0))
    assert np.all(small.ratio < 1e-3)
    assert np.allclose(large.ratio / small.ratio, 10.0, rtol=0.02)


def test_bad_input_messages():
    with pytest.raises(ValueError, match=r"bounds must be \(2, 4\) with high > low"):
        S.uniform_moments(np.zeros((3, 4)))
    with pytest.raises(ValueError, match="high > low"):
        S.uniform_moments([[0.0, 1.0], [1.0, 1.0]])
    with pytest.raises(ValueError, match=r"bounds must be \(2, 21\)"):
        S.uniform_moments(np.vstack([-SCALE, SCALE])[:, :20], 21)
    jac, *_ = _affine_case()
    mean, var = np.zeros(4), np.ones(4)
    for bad in (0, -1, 1.5, True, "2"):
        with pytest.raises(ValueError, match="nodes must be an integer >= 1"):
            S.pose_box_indices(jac, mean=mean, var=var, poses=dict(t=0.0, x=0.0, y=0.0),
                               nodes=bad)
    with pytest.raises(ValueError, match="pose_bounds"):
        S.pose_box_indices(jac, mean=mean, var=var, poses=dict(t=0.0, y=0.0),
                           pose_bounds=dict(x=(1.0, 1.0)))
    with pytest.raises(ValueError, match="different lengths"):
        S.pose_box_indices(jac, mean=mean, var=var,
                           poses=dict(t=[0.0, 1.0], x=[1.0, 2.0, 3.0], y=0.0))
    with pytest.raises(ValueError, match="unknown pose name"):
        S.pose_box_indices(jac, mean=mean, var=var, poses=dict(t=0.0, x=0.0, y=0.0, w=1.0),
                           names=("t", "x", "y"))
    with pytest.raises(ValueError, match="lacks axis"):
        S.pose_box_indices(jac, mean=mean, var=var, poses=dict(t=0.0, x=0.0),
                           required=("x", "y"))
    with pytest.raises(ValueError, match=r"jacobian_fn must return \(M, q, 3\)"):
        S.pose_box_indices(jac, mean=mean[:3], var=var[:3], poses=dict(t=0.0, x=0.0, y=0.0))
    with pytest.raises(ValueError, match="var must be finite and >= 0"):
        S.pose_box_indices(jac, mean=mean, var=-var, poses=dict(t=0.0, x=0.0, y=0.0))
    with pytest.raises(ValueError, match=r"\(P, q, d\)"):
        S.indices_at_poses(np.zeros((6, 41)), var=np.ones(41))
    with pytest.raises(ValueError, match=r"model must return \(10, 2\)"):
        S.nonlinear_remainder(lambda x: x, np.zeros((2, 3)), np.zeros((10, 3)))


# --- one result shape: labelled, with to_df ------------------------------------------------------

def test_linear_indices_are_labelled_and_tabulate_as_a_sampled_estimate():
    inp = S.Inputs.normal(0.0, ZHENG_SD, names=ZHENG.error_names)
    jac = ZHENG.jacobian(ZHENG_POSE)                        # (1, 6, 41)
    out = ["Px", "Py", "Pz", "Vx", "Vy", "Vz"]
    lin = S.linear_indices(jac, inp, outputs=out)
    assert isinstance(lin, S.LinearIndices) and lin.names == tuple(ZHENG.error_names)
    assert np.array_equal(lin, S.linear_indices(jac, sd=ZHENG_SD))   # the numbers as before
    assert type(lin[0]) is np.ndarray and lin[0].shape == (41, 6)
    df = lin.to_df()
    assert list(df.columns) == ["pose", "output", "input", "S1", "ST"]
    assert (df.S1 == df.ST).all() and np.allclose(df.groupby("output").ST.sum(), 1.0)
    # the table of a sampled estimate of the same linear model joins it row by row
    model = lambda e: e @ jac[0].T  # noqa: E731
    est = S.sobol_indices(model, S.SobolDesign(2**12, inp, method="sobol", seed=2), outputs=out)
    both = est.to_df().merge(S.linear_indices(jac[0], inp, outputs=out).to_df(),
                             on=["output", "input"], suffixes=("", "_linear"))
    assert len(both) == 41 * 6 and np.abs(both.ST - both.ST_linear).max() < 0.02
    at_poses = S.indices_at_poses(ZHENG.jacobian({k: np.repeat(v, 3) for k, v in
                                                  ZHENG_POSE.items()}), inp, outputs=out)
    assert at_poses.to_df().pose.max() == 2 and at_poses.outputs == tuple(out)


def test_pose_box_indices_unpack_as_before_and_tabulate():
    bounds = np.vstack([-SCALE, SCALE])
    inp = S.Inputs.from_bounds(bounds, names=H3.error_names)
    res = S.pose_box_indices(H3.jacobian, inp, poses=dict(tool_z=np.array([-80.0, 0.0])),
                             pose_bounds=dict(x=(0.0, 500.0), y=(0.0, 400.0), z=(0.0, 300.0)),
                             components=3, outputs=["Ex", "Ey", "Ez"])
    s1, st, var = res
    assert s1.shape == st.shape == (2, 21, 3) and var.shape == (2, 3)
    assert res.s1 is s1 and res.var is var and res.names == tuple(H3.error_names)
    df = res.to_df()
    assert list(df.columns) == ["case", "output", "input", "S1", "ST", "var"] and len(df) == 126
    row = df[(df.case == 1) & (df.output == "Ey") & (df.input == H3.error_names[4])].iloc[0]
    assert row.ST == st[1, 4, 1] and row.S1 == s1[1, 4, 1] and row["var"] == var[1, 1]
