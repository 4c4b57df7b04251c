"""The three-axis horizontal machining centre of Rong et al.: screw-theory model, layouts."""

import numpy as np
import pytest
from scipy.linalg import expm

from mtaccuracy import kinematics
from mtaccuracy.machines import build
from mtaccuracy.machines import horizontal_3axis as h3

M = build("horizontal_3axis")
NAMES = M.error_names
RNG = np.random.default_rng(4)
# 2 x the acceptance values of data/rong (mm, rad): positioning, straightness, angular, squareness
SCALE = np.array([7.5e-3] * 3 + [1e-2] * 6 + [8e-5] * 9 + [4.75e-6] * 3)
POSE = dict(x=420.0, y=-150.0, z=310.0, tool_x=5.0, tool_y=-8.0, tool_z=-120.0)
LAYOUTS = [*h3.LAYOUTS, "/xyz", "xyz/", "y/zx"]


def one(symbol, value, n=1):
    e = np.zeros((n, 21))
    e[:, NAMES.index(symbol)] = value
    return e


def test_registry_and_api():
    assert M.name == "horizontal_3axis" and M.layout == h3.DEFAULT_LAYOUT == "z/xy"
    assert M.workpiece_axes == ("z",) and M.tool_axes == ("x", "y")
    assert M.axes == ("x", "y", "z") and M.tool_offsets == ("tool_x", "tool_y", "tool_z")
    assert M.n_errors == 21 and NAMES[-3:] == ["S_xy", "S_yz", "S_xz"]
    assert M.pose_error(np.zeros((4, 21)), POSE).shape == (4, 6)
    assert M.position_error(np.zeros((4, 21)), POSE).shape == (4, 3)
    assert "Z table" in M.describe() and "X column" in M.describe()
    assert build("horizontal_3axis", layout="x/zy").tool_axes == ("z", "y")


@pytest.mark.parametrize("layout", LAYOUTS)
@pytest.mark.parametrize("exact", [True, False])
def test_zero_errors_give_zero_at_any_pose(layout, exact):
    m = h3.Horizontal3Axis(layout, exact=exact)
    poses = {k: RNG.uniform(-700, 700, 9) for k in ("x", "y", "z")}
    poses["tool_z"] = RNG.uniform(-200, 0, 9)
    assert np.abs(m.pose_error(np.zeros((9, 21)), poses)).max() < 1e-12


@pytest.mark.parametrize("layout", LAYOUTS)
def test_ideal_tool_position_is_the_commanded_relative_position(layout):
    m = h3.Horizontal3Axis(layout)
    actual, ideal = m.transforms(np.zeros((1, 21)), POSE)
    expected = [POSE["x"] + POSE["tool_x"], POSE["y"] + POSE["tool_y"], POSE["z"] + POSE["tool_z"]]
    assert np.allclose(ideal[0, :3, 3], expected, atol=1e-12)
    assert np.allclose(ideal[0, :3, :3], np.eye(3)) and np.allclose(actual, ideal)


@pytest.mark.parametrize("layout", LAYOUTS)
def test_response_is_linear_for_small_errors(layout):
    m = h3.Horizontal3Axis(layout)
    e = RNG.uniform(-1, 1, size=(5, 21)) * SCALE
    p1, p2 = m.pose_error(e, POSE), m.pose_error(1e-3 * e, POSE)
    # scaling the errors scales the response; what is left is second order (relative ~1e-4 at
    # these sizes), measured against the largest component
    assert np.abs(p2 - 1e-3 * p1).max() < 1e-3 * np.abs(p2).max()
    # and the first-order coefficients reproduce the response to that order
    lin = (m.first_order_coefficients(POSE) @ e.T).T
    assert np.allclose(p1, lin, rtol=0, atol=1e-3 * np.abs(p1).max())


@pytest.mark.parametrize("layout", LAYOUTS)
@pytest.mark.parametrize("axis", ["x", "y", "z"])
def test_pure_positioning_error_moves_the_tip_only_along_its_axis(layout, axis):
    m = h3.Horizontal3Axis(layout)
    pe = m.pose_error(one(f"d{axis}({axis})", 2e-3), POSE)[0]
    k = "xyz".index(axis)
    sign = -1.0 if axis in m.workpiece_axes else 1.0  # a table error moves the part, not the tool
    expected = np.zeros(6)
    expected[k] = sign * 2e-3
    assert np.allclose(pe, expected, atol=1e-15)


@pytest.mark.parametrize("symbol, component", [("dy(x)", 1), ("dz(x)", 2), ("dx(y)", 0),
                                               ("dz(y)", 2), ("dx(z)", 0), ("dy(z)", 1)])
def test_straightness_error_moves_the_tip_only_along_its_direction(symbol, component):
    pe = M.pose_error(one(symbol, -3e-3), POSE)[0]
    nonzero = np.flatnonzero(np.abs(pe) > 1e-15)
    assert list(nonzero) == [component] and abs(pe[component]) == pytest.approx(3e-3)


def test_first_order_coefficients_match_a_hand_derivation():
    """Default layout Z table / X column / Y headstock, derived on paper from
    E = dX + dY - dZ + eps_X x (t + y e_y) + eps_Y x t - eps_Z x (p) + squareness terms, with
    t the tool offset and p = (x, y, z) + t the tip relative to the table's reference point."""
    x, y, z = POSE["x"], POSE["y"], POSE["z"]
    t = np.array([POSE["tool_x"], POSE["tool_y"], POSE["tool_z"]])
    p = np.array([x, y, z]) + t
    arm_x = t + np.array([0.0, y, 0.0])
    e3 = np.eye(3)
    ref = {}
    for k, a in enumerate("xyz"):
        ref[f"d{a}(x)"] = e3[k]
        ref[f"d{a}(y)"] = e3[k]
        ref[f"d{a}(z)"] = -e3[k]
        ref[f"e{a}(x)"] = np.cross(e3[k], arm_x)
        ref[f"e{a}(y)"] = np.cross(e3[k], t)
        ref[f"e{a}(z)"] = -np.cross(e3[k], p)
    ref["S_xy"] = np.array([-y, 0.0, 0.0])
    ref["S_xz"] = np.array([z, 0.0, 0.0])
    ref["S_yz"] = np.array([0.0, -z, 0.0])
    jac = M.first_order_coefficients(POSE)[:3]
    for j, s in enumerate(NAMES):
        assert np.allclose(jac[:, j], ref[s], atol=1e-6), s
    # orientation: angular errors tilt the tool, tool side +, table side -
    assert M.first_order_coefficients(POSE)[3:, NAMES.index("ex(y)")] == pytest.approx([1, 0, 0])
    assert M.first_order_coefficients(POSE)[3:, NAMES.index("ez(z)")] == pytest.approx([0, 0, -1])


def test_last_tool_axis_angular_errors_act_only_through_the_tool_offset():
    e = one("ex(y)", 5e-5)
    no_tool = dict(x=700.0, y=600.0, z=500.0)
    assert np.abs(M.position_error(e, no_tool)).max() < 1e-15
    assert M.position_error(e, dict(no_tool, tool_z=-100.0))[0, 1] == pytest.approx(100 * 5e-5)


def test_layout_moves_an_axis_error_between_tool_and_table():
    e = one("ez(z)", 1e-5)
    table = h3.Horizontal3Axis("z/xy").position_error(e, POSE)[0]
    column = h3.Horizontal3Axis("/xyz").position_error(e, POSE)[0]
    t = np.array([POSE["tool_x"], POSE["tool_y"], POSE["tool_z"]])
    p = np.array([POSE["x"], POSE["y"], POSE["z"]]) + t
    assert np.allclose(table, -np.cross([0, 0, 1e-5], p), atol=1e-8)  # + O(eps^2 |p|)
    assert np.allclose(column, np.cross([0, 0, 1e-5], t), atol=1e-8)  # Z last: arm = tool


def test_exact_and_first_order_matrices_differ_at_second_order_only():
    e = RNG.uniform(-1, 1, size=(6, 21)) * SCALE
    exact = h3.Horizontal3Axis(exact=True).pose_error(e, POSE)
    first = h3.Horizontal3Axis(exact=False).pose_error(e, POSE)
    diff = np.abs(exact - first).max()
    assert 0 < diff < 10 * np.abs(SCALE[9:18]).max() * np.abs(exact).max()


def test_error_twist_exponential_equals_the_matrix_exponential():
    for eps in ([1e-4, -2e-4, 3e-5], [0.3, -0.2, 0.5], [0.0, 0.0, 0.0], [1e-9, 0, 0]):
        eps, delta = np.array(eps, dtype=float), np.array([0.01, -0.02, 0.005])
        xi = np.zeros((4, 4))
        xi[:3, :3] = kinematics.hat(eps)
        xi[:3, 3] = delta
        assert np.allclose(h3.error_twist_exp(eps, delta), expm(xi), atol=1e-15)
        assert np.allclose(h3.error_twist_exp(eps, delta, exact=False), np.eye(4) + xi)
    # a prismatic twist (0, d) q is the translation q d, as the module builds it
    d = np.array([0.6, 0.0, 0.8])
    assert np.allclose(kinematics.twist_exp(np.zeros(3), d, 250.0),
                       kinematics.translation(250.0 * d))


def test_linear_indices_are_exact_shares_of_variance():
    b = np.vstack([-SCALE, SCALE])
    s1, st = h3.linear_sobol_indices(M, b, pose=dict(x=700.0, y=600.0, z=500.0))
    assert np.allclose(s1, st) and np.allclose(st.sum(0), 1.0)
    c = M.first_order_coefficients(dict(x=700.0, y=600.0, z=500.0))[:3]
    v = c**2 * SCALE**2 / 3
    assert np.allclose(st, (v / v.sum(1, keepdims=True)).T)
    # pose uniform in a box: total >= first order, both sum as they must
    s1, st = h3.linear_sobol_indices(M, b, pose_bounds=dict(x=(0, 700), y=(0, 600), z=(0, 500)))
    assert np.all(st >= s1 - 1e-15) and np.allclose(st.sum(0), 1.0) and np.all(s1.sum(0) < 1)
    # exact: the coefficients are affine in the pose, c = c0 + sum_k g_k (p_k - centre_k), so
    # E[c^2] = c0^2 + sum_k g_k^2 L_k^2 / 12 for a uniform pose
    centre, lengths = dict(x=350.0, y=300.0, z=250.0), dict(x=700.0, y=600.0, z=500.0)
    c0 = M.first_order_coefficients(centre)[:3]
    ec2 = c0**2
    for k in "xyz":
        coef = M.first_order_coefficients
        g = coef(dict(centre, **{k: centre[k] + 100.0}))[:3] - c0
        back = coef(dict(centre, **{k: centre[k] - 250.0}))[:3] - c0
        assert np.allclose(back, -2.5 * g, atol=1e-5)  # affine in the pose
        ec2 = ec2 + (g / 100.0) ** 2 * lengths[k] ** 2 / 12
    v = ec2 * SCALE**2 / 3
    assert np.allclose(st, (v / v.sum(1, keepdims=True)).T, atol=1e-9)
    assert np.allclose(s1, (c0**2 * SCALE**2 / 3 / v.sum(1, keepdims=True)).T, atol=1e-9)


@pytest.mark.parametrize("layout, message", [
    ("zxy", "one '/'"), ("z/x/y", "one '/'"), ("zz/xy", "exactly once"), ("z/x", "exactly once"),
    ("a/xyz", "exactly once"),
])
def test_bad_layouts_are_refused(layout, message):
    with pytest.raises(ValueError, match=message):
        build("horizontal_3axis", layout=layout)


def test_bad_inputs():
    assert h3.parse_layout(" Z/XY ") == (("z",), ("x", "y"))
    with pytest.raises(TypeError, match="layout must be a string"):
        h3.Horizontal3Axis(layout=3)
    with pytest.raises(ValueError, match=r"shape \(n, 21\)"):
        M.pose_error(np.zeros((3, 20)), POSE)
    with pytest.raises(ValueError, match="lacks axis"):
        M.pose_error(np.zeros((1, 21)), dict(x=1.0, y=2.0))
    with pytest.raises(ValueError, match="unknown pose name"):
        M.pose_error(np.zeros((1, 21)), dict(x=1.0, y=2.0, z=3.0, D3=4.0))
    with pytest.raises(ValueError, match="one pose"):
        M.first_order_coefficients(dict(x=[1.0, 2.0], y=0.0, z=0.0))
    with pytest.raises(ValueError, match="high > low"):
        h3.linear_sobol_indices(M, np.zeros((2, 21)), pose=POSE)
    with pytest.raises(ValueError, match="lacks axis"):
        h3.linear_sobol_indices(M, np.vstack([-SCALE, SCALE]), pose=dict(x=0.0))
    with pytest.raises(ValueError, match="unknown machine"):
        build("horizontal_5axis")


@pytest.mark.parametrize("layout", LAYOUTS)
def test_first_order_jacobian_is_exact_and_batched(layout):
    """Closed-form coefficients: equal to central differences of the full model (which carry
    ~1e-8 of rounding), batched over poses, and bitwise equal for exchangeable errors."""
    m = h3.Horizontal3Axis(layout)
    poses = {k: RNG.uniform(-700, 700, 4) for k in ("x", "y", "z")}
    poses.update(tool_x=5.0, tool_z=RNG.uniform(-200, 0, 4))
    jac = m.first_order_jacobian(poses)
    assert jac.shape == (4, 6, 21)
    assert not np.any(np.signbit(jac) & (jac == 0))  # tables print 0, not -0
    for i in range(4):
        one_pose = {k: (v[i] if np.ndim(v) else v) for k, v in poses.items()}
        assert np.allclose(jac[i], m.jacobian(one_pose)[0], atol=1e-6)
        assert np.array_equal(jac[i], m.first_order_coefficients(one_pose))
    # translations enter with exactly +-1 or 0; straightness pairs along one direction tie exactly
    for a in "xyz":
        for b in "xyz":
            assert set(np.unique(jac[:, :3, NAMES.index(f"d{a}({b})")])) <= {-1.0, 0.0, 1.0}
    # Ex: dx(y) and dx(z) have coefficients of equal magnitude at every pose
    dxy, dxz = jac[:, 0, NAMES.index("dx(y)")], jac[:, 0, NAMES.index("dx(z)")]
    assert np.array_equal(np.abs(dxy), np.abs(dxz))


def test_linear_indices_at_poses_equal_one_pose_at_a_time_and_tie_exactly():
    b = np.vstack([-SCALE, SCALE])
    poses = dict(x=np.array([0.0, 175.0, 700.0]), y=np.array([0.0, 450.0, 600.0]),
                 z=np.array([0.0, 125.0, 500.0]))
    many = h3.linear_indices_at_poses(M, b, poses)
    assert many.shape == (3, 21, 3)
    for i in range(3):
        _, st = h3.linear_sobol_indices(M, b, pose={k: v[i] for k, v in poses.items()})
        assert np.allclose(many[i], st, rtol=1e-14, atol=0)
    # exchangeable errors (coefficient +-1, same range) get the same index to the bit
    assert many[1, NAMES.index("dx(y)"), 0] == many[1, NAMES.index("dx(z)"), 0]
    assert many[1, NAMES.index("dz(x)"), 2] == many[1, NAMES.index("dz(y)"), 2]


def test_a_coincidental_tie_is_broken_by_catalogue_order():
    """At z = 125 mm the Abbe term of ey(z) (125 mm x 80 urad = 10 um) equals the straightness
    range of dx(y) and dx(z): three tied indices in Ex, of which the 90 % rule needs one.  The
    tie is decided by catalogue order (dx(y) first), not by the last bit of the arithmetic."""
    from mtaccuracy import sensitivity as S

    b = np.vstack([-SCALE, SCALE])
    st = h3.linear_indices_at_poses(M, b, dict(x=175.0, y=450.0, z=125.0))[0]
    j = [NAMES.index(s) for s in ("ey(z)", "dx(y)", "dx(z)")]
    assert np.ptp(st[j, 0]) < 1e-15 * st[j, 0].max()  # equal up to rounding
    keys = S.key_errors_by_output(S.merge_ties(st), NAMES, ["Ex", "Ey", "Ez"], 0.9)
    assert keys["Ex"].names == ("ez(x)", "ez(z)", "dx(y)")
    # whichever of the three the rounding favours, the answer is the same
    for winner in j:
        nudged = st.copy()
        nudged[winner, 0] *= 1 + 4e-16
        again = S.key_errors_by_output(S.merge_ties(nudged), NAMES, ["Ex", "Ey", "Ez"], 0.9)
        assert again["Ex"].names == keys["Ex"].names


@pytest.mark.parametrize("layout", ["z/xy", "/xyz", "xz/y"])
@pytest.mark.parametrize("exact", [True, False])
def test_rotation_translation_path_equals_the_4x4_product(layout, exact):
    """The (R, t) evaluation against the 4x4 product of the twist exponentials and a general
    matrix inverse, with errors large enough that every order matters."""
    m = h3.Horizontal3Axis(layout, exact=exact)
    n = 7
    e = RNG.uniform(-1, 1, size=(n, 21)) * SCALE * 100
    pose = dict(x=RNG.uniform(0, 700, n), y=RNG.uniform(0, 600, n), z=RNG.uniform(0, 500, n),
                tool_x=3.0, tool_z=RNG.uniform(-200, 0, n))
    col = {sym: e[:, j] for j, sym in enumerate(m.error_names)}
    zero = np.zeros(n)
    # axis directions tilted by the squareness errors: Rz(S_xy) e_y, exp([S_yz, S_xz, 0]x) e_z
    # (exact) or e + w x e (first order)
    w_y = np.stack([zero, zero, col["S_xy"]], -1)
    w_z = np.stack([col["S_yz"], col["S_xz"], zero], -1)
    unit = np.eye(3)
    tilt = ((lambda w, u: kinematics.rotation_exp(w) @ u) if exact
            else (lambda w, u: u + np.cross(w, u)))
    d = {"x": np.broadcast_to(unit[0], (n, 3)), "y": tilt(w_y, unit[1]),
         "z": tilt(w_z, unit[2])}

    def carriage(a, sign):
        eps = np.stack([col[f"e{c}({a})"] for c in "xyz"], -1)
        delta = np.stack([col[f"d{c}({a})"] for c in "xyz"], -1)
        return [kinematics.translation(d[a] * (sign * pose[a])[:, None]),
                h3.error_twist_exp(eps, delta, exact)]

    tool = [g for a in m.tool_axes for g in carriage(a, 1.0)]
    tip = np.stack([np.broadcast_to(pose.get(k, 0.0), n) for k in h3.TOOL_OFFSETS], axis=-1)
    g = kinematics.chain(*tool, kinematics.translation(tip))
    if m.workpiece_axes:
        work = kinematics.chain(*[w for a in m.workpiece_axes for w in carriage(a, -1.0)])
        g = np.linalg.inv(work) @ g
    ideal = np.stack([pose["x"] + 3.0, pose["y"], pose["z"] + pose["tool_z"]], axis=-1)
    assert np.allclose(m.position_error(e, pose), g[:, :3, 3] - ideal, rtol=0, atol=1e-12)
    actual, ideal4 = m.transforms(e, pose)
    assert np.allclose(actual, g, rtol=0, atol=1e-12)
    assert np.allclose(ideal4[:, :3, 3], ideal, rtol=0, atol=0)


def test_tool_length_sweep_is_batched_and_gives_the_last_tool_axis_an_arm():
    """Batched over tool lengths: bitwise equal to one case at a time; the variance is the
    pooled one (S_T = share of it); a tool of length L along -z gives the roll ex(y) of the
    Y headstock the coefficient +L in Ey at every pose (eps x s = e_x x (0, 0, -L)), while
    ez(y) (about the spindle axis) still cannot move the tip."""
    b = np.vstack([-SCALE, SCALE])
    box = dict(x=(0, 700), y=(0, 600), z=(0, 500))
    lengths = np.array([0.0, 50.0, 200.0])
    tools = h3.tool_length_offsets(lengths, base=(0.0, 0.0, 0.0))
    assert np.array_equal(tools["tool_z"], -lengths) and np.all(tools["tool_x"] == 0)
    s1, st, v = h3.linear_sobol_indices_batch(M, b, dict(tools), box)
    assert s1.shape == st.shape == (3, 21, 3) and v.shape == (3, 3)
    for i in range(3):
        one_s1, one_st = h3.linear_sobol_indices(M, b, {k: t[i] for k, t in tools.items()}, box)
        assert np.array_equal(one_s1, s1[i]) and np.array_equal(one_st, st[i])
    j_ex, j_ez = NAMES.index("ex(y)"), NAMES.index("ez(y)")
    var_angle = SCALE[j_ex] ** 2 / 3
    assert np.allclose(st[:, j_ex, 1], lengths**2 * var_angle / v[:, 1], rtol=1e-12)
    assert st[0, j_ex, 1] == 0 and st[2, j_ex, 1] > 0.1
    assert np.all(st[:, j_ez] == 0)
    # the variance is that of the first-order model with the pose uniform in the box
    rng = np.random.default_rng(1)
    n = 200_000
    p = {k: rng.uniform(lo, hi, n) for k, (lo, hi) in box.items()}
    c = M.first_order_jacobian(dict(p, tool_x=0.0, tool_y=0.0, tool_z=-200.0))[:, :3]
    e = rng.uniform(-1, 1, (n, 21)) * SCALE
    y = np.einsum("nqj,nj->nq", c, e)
    assert np.allclose(y.var(0), v[2], rtol=0.02)
    with pytest.raises(ValueError, match=">= 0"):
        h3.tool_length_offsets([-5.0])
    with pytest.raises(ValueError, match="different lengths"):
        h3.linear_sobol_indices_batch(M, b, dict(tools, tool_x=np.zeros(2)), box)
    with pytest.raises(ValueError, match="one pose"):
        h3.linear_sobol_indices(M, b, dict(tools), box)
