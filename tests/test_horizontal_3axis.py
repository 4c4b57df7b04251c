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
