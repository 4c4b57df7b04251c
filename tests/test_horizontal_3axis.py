"""The three-axis horizontal machining centre of Rong et al.: screw-theory model, layouts.

The paper's study on it (the closed-form indices, the tool lengths) is tested in test_rong.py."""

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
# the named layouts and three more as chain topologies: every axis on the tool side, every axis
# on the workpiece side (Z carries the workpiece), Y table with the X headstock on a Z column
LAYOUTS = [*h3.LAYOUTS, "w b X Y Z t", "w Z Y X b t", "w Y b Z X t"]


def one(symbol, value, n=1):
    e = np.zeros((n, 21))
    e[:, NAMES.index(symbol)] = value
    return e


def test_registry_and_api():
    assert M.name == "horizontal_3axis" and M.layout == h3.DEFAULT_LAYOUT == "z/xy"
    assert M.topology.work == ("Z",) and M.topology.tool == ("X", "Y")
    assert M.axes == ("x", "y", "z") and M.tool_offsets == ("tool_x", "tool_y", "tool_z")
    assert M.n_errors == 21 and NAMES[-3:] == ["S_xy", "S_yz", "S_xz"]
    assert M.pose_error(np.zeros((4, 21)), POSE).shape == (4, 6)
    assert M.position_error(np.zeros((4, 21)), POSE).shape == (4, 3)
    assert "Z table" in M.describe() and "X column" in M.describe()
    assert build("horizontal_3axis", layout="x/zy").topology.tool == ("Z", "Y")


@pytest.mark.parametrize("name", list(h3.LAYOUTS))
def test_a_named_layout_is_its_topology_in_the_chain_grammar(name):
    """A named layout and its topology (spaced or compact) build the same machine, named alike."""
    topology = h3.LAYOUTS[name].topology
    e = RNG.uniform(-1, 1, size=(5, 21)) * SCALE * 10
    by_name = h3.Horizontal3Axis(name).pose_error(e, POSE)
    for text in (topology, topology.replace(" ", "")):
        m = h3.Horizontal3Axis(text)
        assert m.layout == name and m.describe() == h3.Horizontal3Axis(name).describe()
        assert np.array_equal(m.pose_error(e, POSE), by_name)
    # a name W/T lists each side from the bed outwards: "zx/y" is "w X Z b Y t"
    work, tool = name.split("/")
    assert h3.Horizontal3Axis(name).topology.work == tuple(work.upper())
    assert h3.Horizontal3Axis(name).topology.tool == tuple(tool.upper())


def test_an_unnamed_layout_is_described_by_its_topology():
    m = h3.Horizontal3Axis("w b X Y Z t")
    assert m.layout == "w b X Y Z t"
    assert m.describe() == ("layout 'w b X Y Z t': workpiece <- (fixed) <- bed -> X -> Y -> Z -> "
                            "spindle -> tool")


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
    lin = (m.jacobian(POSE)[0] @ e.T).T
    assert np.allclose(p1, lin, rtol=0, atol=1e-3 * np.abs(p1).max())


@pytest.mark.parametrize("layout", LAYOUTS)
@pytest.mark.parametrize("axis", ["x", "y", "z"])
def test_pure_positioning_error_moves_the_tip_only_along_its_axis(layout, axis):
    m = h3.Horizontal3Axis(layout)
    pe = m.pose_error(one(f"d{axis}({axis})", 2e-3), POSE)[0]
    k = "xyz".index(axis)
    sign = -1.0 if axis.upper() in m.topology.work else 1.0  # a table error moves the part
    expected = np.zeros(6)
    expected[k] = sign * 2e-3
    assert np.allclose(pe, expected, atol=1e-15)


@pytest.mark.parametrize("symbol, component", [("dy(x)", 1), ("dz(x)", 2), ("dx(y)", 0),
                                               ("dz(y)", 2), ("dx(z)", 0), ("dy(z)", 1)])
def test_straightness_error_moves_the_tip_only_along_its_direction(symbol, component):
    pe = M.pose_error(one(symbol, -3e-3), POSE)[0]
    nonzero = np.flatnonzero(np.abs(pe) > 1e-15)
    assert list(nonzero) == [component] and abs(pe[component]) == pytest.approx(3e-3)


def test_the_jacobian_matches_a_hand_derivation():
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
    jac = M.jacobian(POSE)[0][:3]
    for j, s in enumerate(NAMES):
        assert np.allclose(jac[:, j], ref[s], atol=1e-6), s
    # orientation: angular errors tilt the tool, tool side +, table side -
    assert M.jacobian(POSE)[0][3:, NAMES.index("ex(y)")] == pytest.approx([1, 0, 0])
    assert M.jacobian(POSE)[0][3:, NAMES.index("ez(z)")] == pytest.approx([0, 0, -1])


def test_last_tool_axis_angular_errors_act_only_through_the_tool_offset():
    e = one("ex(y)", 5e-5)
    no_tool = dict(x=700.0, y=600.0, z=500.0)
    assert np.abs(M.position_error(e, no_tool)).max() < 1e-15
    assert M.position_error(e, dict(no_tool, tool_z=-100.0))[0, 1] == pytest.approx(100 * 5e-5)


def test_layout_moves_an_axis_error_between_tool_and_table():
    e = one("ez(z)", 1e-5)
    table = h3.Horizontal3Axis("z/xy").position_error(e, POSE)[0]
    column = h3.Horizontal3Axis("w b X Y Z t").position_error(e, POSE)[0]
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


def _error_transform(eps, delta, exact):
    """The error motion of a carriage: exp of the twist (eps, delta), or the first-order I + xi^."""
    if exact:
        return kinematics.screw_exp(eps, delta)
    return kinematics.homogeneous(np.eye(3) + kinematics.hat(np.asarray(eps, dtype=float)), delta)


def test_the_machines_error_motion_is_the_exponential_of_the_error_twist():
    """The six error motions of the last tool-side axis alone: the tool frame is the nominal
    translation times screw_exp of their twist, which is the matrix exponential of the twist
    (exact=False: the first-order matrix I + xi^), at sizes where every order matters."""
    m_exact = h3.Horizontal3Axis("w b X Y Z t", exact=True)
    m_first = h3.Horizontal3Axis("w b X Y Z t", exact=False)
    pose = dict(x=120.0, y=-40.0, z=75.0)
    move = kinematics.translation(np.array([pose["x"], pose["y"], pose["z"]]))
    cols = [NAMES.index(f"e{c}(z)") for c in "xyz"] + [NAMES.index(f"d{c}(z)") for c in "xyz"]
    for eps in ([1e-4, -2e-4, 3e-5], [0.3, -0.2, 0.5], [0.0, 0.0, 0.0], [1e-9, 0, 0]):
        eps, delta = np.array(eps, dtype=float), np.array([0.01, -0.02, 0.005])
        xi = np.zeros((4, 4))
        xi[:3, :3] = kinematics.hat(eps)
        xi[:3, 3] = delta
        assert np.allclose(kinematics.screw_exp(eps, delta), expm(xi), atol=1e-15)
        e = np.zeros((1, 21))
        e[0, cols] = np.r_[eps, delta]
        assert np.allclose(m_exact.transforms(e, pose)[0][0], move @ expm(xi), atol=1e-12)
        assert np.allclose(m_exact.transforms(e, pose)[0][0],
                           move @ kinematics.screw_exp(eps, delta), atol=1e-12)
        assert np.allclose(m_first.transforms(e, pose)[0][0], move @ (np.eye(4) + xi),
                           atol=1e-12)
    # a prismatic twist (0, d) q is the translation q d, as the module builds it
    d = np.array([0.6, 0.0, 0.8])
    assert np.allclose(kinematics.twist_exp(np.zeros(3), d, 250.0),
                       kinematics.translation(250.0 * d))


@pytest.mark.parametrize("layout, message", [
    ("zxy", "neither a named layout"), ("z/x/y", r"unknown axis letter\(s\) \['z', '/'"),
    ("/xyz", "neither a named layout"), ("w Z Z b X Y t", "more than once"),
    ("w Z b X t", "must place X, Y and Z"), ("w A b X Y Z t", "must place X, Y and Z"),
])
def test_bad_layouts_are_refused(layout, message):
    with pytest.raises(ValueError, match=message):
        build("horizontal_3axis", layout=layout)


def test_bad_inputs():
    with pytest.raises(TypeError, match="must be a string"):
        h3.Horizontal3Axis(layout=3)
    with pytest.raises(ValueError, match=r"shape \(n, 21\)"):
        M.pose_error(np.zeros((3, 20)), POSE)
    with pytest.raises(ValueError, match="lacks axis"):
        M.pose_error(np.zeros((1, 21)), dict(x=1.0, y=2.0))
    with pytest.raises(ValueError, match="unknown pose name"):
        M.pose_error(np.zeros((1, 21)), dict(x=1.0, y=2.0, z=3.0, D3=4.0))
    with pytest.raises(ValueError, match=r"must be a scalar or have shape \(3,\)"):
        M.jacobian(dict(x=[1.0, 2.0], y=[0.0, 1.0, 2.0], z=0.0))
    with pytest.raises(ValueError, match="unknown machine"):
        build("horizontal_5axis")


@pytest.mark.parametrize("layout", LAYOUTS)
def test_jacobian_is_exact_and_batched(layout):
    """Closed-form coefficients: equal to central differences of the full model (which carry
    ~1e-8 of rounding), batched over poses, and bitwise equal for exchangeable errors."""
    m = h3.Horizontal3Axis(layout)
    poses = {k: RNG.uniform(-700, 700, 4) for k in ("x", "y", "z")}
    poses.update(tool_x=5.0, tool_z=RNG.uniform(-200, 0, 4))
    jac = m.jacobian(poses)
    assert jac.shape == (4, 6, 21)
    assert not np.any(np.signbit(jac) & (jac == 0))  # tables print 0, not -0
    for i in range(4):
        one_pose = {k: (v[i] if np.ndim(v) else v) for k, v in poses.items()}
        assert np.allclose(jac[i], m.jacobian(one_pose, step=1e-6)[0], atol=1e-6)
        assert np.array_equal(jac[i], m.jacobian(one_pose)[0])
    # translations enter with exactly +-1 or 0; straightness pairs along one direction tie exactly
    for a in "xyz":
        for b in "xyz":
            assert set(np.unique(jac[:, :3, NAMES.index(f"d{a}({b})")])) <= {-1.0, 0.0, 1.0}
    # Ex: dx(y) and dx(z) have coefficients of equal magnitude at every pose
    dxy, dxz = jac[:, 0, NAMES.index("dx(y)")], jac[:, 0, NAMES.index("dx(z)")]
    assert np.array_equal(np.abs(dxy), np.abs(dxz))


@pytest.mark.parametrize("layout", ["z/xy", "w b X Y Z t", "xz/y"])
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
                _error_transform(eps, delta, exact)]

    tool = [g for a in m.topology.tool for g in carriage(a.lower(), 1.0)]
    tip = np.stack([np.broadcast_to(pose.get(k, 0.0), n) for k in h3.TOOL_OFFSETS], axis=-1)
    g = kinematics.chain(*tool, kinematics.translation(tip))
    if m.topology.work:
        work = kinematics.chain(*[w for a in m.topology.work for w in carriage(a.lower(), -1.0)])
        g = np.linalg.inv(work) @ g
    ideal = np.stack([pose["x"] + 3.0, pose["y"], pose["z"] + pose["tool_z"]], axis=-1)
    assert np.allclose(m.position_error(e, pose), g[:, :3, 3] - ideal, rtol=0, atol=1e-12)
    actual, ideal4 = m.transforms(e, pose)
    assert np.allclose(actual, g, rtol=0, atol=1e-12)
    assert np.allclose(ideal4[:, :3, 3], ideal, rtol=0, atol=0)
