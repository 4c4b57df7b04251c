"""The AC double-turntable machine of Zheng et al. 2024: three formulations must agree
(the generic chain, 4x4 homogeneous transforms, the literal product of 41 exponentials)."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from mtaccuracy import kinematics as K
from mtaccuracy.machines import build
from mtaccuracy.machines.ac_double_turntable import TRAVELS

M = build("ac_double_turntable")
NAMES = M.error_names
RNG = np.random.default_rng(5)
SD = np.array([5e-3 if e.translational else 1.6e-5 for e in M.catalogue])
POSE = dict(x=120.0, y=-80.0, z=150.0, A=0.7, C=2.1, L=35.0)


def one(symbol, value, n=1):
    e = np.zeros((n, 41))
    e[:, NAMES.index(symbol)] = value
    return e


def htm_pose_error(e, p):
    """Independent formulation: 4x4 homogeneous transforms from scipy rotations, "moving"
    convention (ideal motion, then error motion, then location error, per axis)."""
    col = {s: e[NAMES.index(s)] for s in NAMES}

    def h(rot=None, t=(0.0, 0.0, 0.0)):
        m = np.eye(4)
        m[:3, :3], m[:3, 3] = np.eye(3) if rot is None else rot, t
        return m

    def rxyz(a, b, c):
        return Rotation.from_euler("XYZ", [a, b, c]).as_matrix()

    def motion(a):
        return h(rxyz(col[f"e_x{a}"], col[f"e_y{a}"], col[f"e_z{a}"]),
                 [col[f"d_x{a}"], col[f"d_y{a}"], col[f"d_z{a}"]])

    t_y = h(t=[0, p["y"], 0]) @ motion("y") @ h(rxyz(0, 0, col["S_xy"]))
    t_x = h(t=[p["x"], 0, 0]) @ motion("x") @ h(rxyz(col["S_yz"], col["S_xz"], 0))
    t_z = h(t=[0, 0, p["z"]]) @ motion("z")
    g_bt = t_y @ t_x @ t_z @ h(t=[0, 0, p["L"]])
    loc_a = h(rxyz(col["a_AM"], col["b_AM"], col["g_AM"]),
              [col["d_xAM"], col["d_yAM"], col["d_zAM"]])
    loc_c = h(rxyz(0, col["b_CA"], 0), [0, col["d_yCA"], 0])
    g_bw = (h(rxyz(p["A"], 0, 0)) @ motion("a") @ loc_a @ h(rxyz(0, 0, p["C"])) @ motion("c")
            @ loc_c)
    g = np.linalg.inv(g_bw) @ g_bt
    g_bt0 = h(t=[p["x"], p["y"], p["z"] + p["L"]])
    g0 = np.linalg.inv(h(rxyz(p["A"], 0, 0)) @ h(rxyz(0, 0, p["C"]))) @ g_bt0
    return np.r_[g[:3, 3] - g0[:3, 3], g[:3, 2] - g0[:3, 2]]


def poe_literal(e, p):
    """Eq. 9 read literally: every error is its own unit-twist exponential (41 of them)."""
    col = {s: e[NAMES.index(s)] for s in NAMES}
    ex, ey, ez, z0 = np.eye(3)[0], np.eye(3)[1], np.eye(3)[2], np.zeros(3)

    def tw(w, v, th):  # one exponential
        return K.twist_exp(w, v, th)

    def block(names, dirs):
        m = np.eye(4)
        for s, (kind, d) in zip(names, dirs, strict=True):
            m = m @ (tw(z0, d, col[s]) if kind == "t" else tw(d, z0, col[s]))
        return m

    six = [("t", ex), ("t", ey), ("t", ez), ("r", ex), ("r", ey), ("r", ez)]

    def motion(a):
        return block([f"d_x{a}", f"d_y{a}", f"d_z{a}", f"e_x{a}", f"e_y{a}", f"e_z{a}"], six)

    t_y = tw(z0, ey, p["y"]) @ motion("y") @ tw(ez, z0, col["S_xy"])
    t_x = tw(z0, ex, p["x"]) @ motion("x") @ tw(ex, z0, col["S_yz"]) @ tw(ey, z0, col["S_xz"])
    t_z = tw(z0, ez, p["z"]) @ motion("z")
    g_bt = t_y @ t_x @ t_z @ tw(z0, ez, p["L"])
    t_a = tw(ex, z0, p["A"]) @ motion("a") @ block(["d_xAM", "d_yAM", "d_zAM", "a_AM", "b_AM",
                                                     "g_AM"], six)
    t_c = tw(ez, z0, p["C"]) @ motion("c") @ tw(z0, ey, col["d_yCA"]) @ tw(ey, z0, col["b_CA"])
    g = np.linalg.inv(t_a @ t_c) @ g_bt
    g0 = np.linalg.inv(tw(ex, z0, p["A"]) @ tw(ez, z0, p["C"])) @ tw(z0, ez, p["z"] + p["L"]) \
        @ K.translation([p["x"], p["y"], 0.0])
    return np.r_[g[:3, 3] - g0[:3, 3], g[:3, 2] - g0[:3, 2]]


def test_zero_errors_give_zero_at_any_pose():
    u = np.random.default_rng(6).random((20, len(TRAVELS)))     # 20 poses within the travels
    poses = {k: lo + u[:, i] * (hi - lo) for i, (k, (lo, hi)) in enumerate(TRAVELS.items())}
    assert np.abs(M.pose_error(np.zeros((20, 41)), poses)).max() < 1e-12
    assert np.abs(M.pose_error(np.zeros((4, 41)), POSE)).max() < 1e-12


@pytest.mark.parametrize("scale", [1.0, 10.0, 300.0])  # the three branches of _cos_sin
def test_three_formulations_agree(scale):
    e = RNG.standard_normal((5, 41)) * SD * scale
    ours = M.pose_error(e, POSE)                          # the generic chain, one pose
    arr = M.pose_error(e, {k: np.full(5, v) for k, v in POSE.items()})   # pose arrays
    htm = np.array([htm_pose_error(row, POSE) for row in e])
    poe = np.array([poe_literal(row, POSE) for row in e])
    assert np.allclose(ours, arr, rtol=0, atol=1e-12)
    assert np.allclose(ours, htm, rtol=0, atol=1e-12)
    assert np.allclose(ours, poe, rtol=0, atol=1e-12)


def test_orientation_error_is_independent_of_translational_errors():
    e = RNG.standard_normal((50, 41)) * SD
    e[:, [j for j, c in enumerate(M.catalogue) if not c.translational]] = 0.0
    pe = M.pose_error(e, POSE)
    assert np.abs(pe[:, 3:]).max() < 1e-15 and np.abs(pe[:, :3]).max() > 1e-3


def test_c_table_radial_error_moves_the_workpiece():
    pe = M.pose_error(one("d_xc", 2e-3), dict(x=10.0, y=20.0, z=30.0, A=0.0, C=0.0))[0]
    assert np.allclose(pe, [-2e-3, 0, 0, 0, 0, 0], atol=1e-15)


def test_x_rotation_reaches_vz_through_sin_a():
    for a in (0.0, 0.5, 1.2):
        pe = M.pose_error(one("e_xx", 1e-5), dict(x=0.0, y=0.0, z=0.0, A=a, C=0.0))[0]
        assert abs(abs(pe[5]) - 1e-5 * np.sin(a)) < 1e-9  # exact model: -eps^2/2 at A = 0
        assert abs(pe[3]) < 1e-15


def test_first_order_behaviour_and_jacobian():
    e = RNG.standard_normal((3, 41)) * SD
    p1, p2 = M.pose_error(e, POSE), M.pose_error(1e-3 * e, POSE)
    assert np.allclose(p2, 1e-3 * p1, rtol=2e-3, atol=1e-16)
    j = M.jacobian(POSE, step=1e-6)[0]
    assert j.shape == (6, 41)
    assert np.allclose(M.pose_error(1e-3 * e, POSE), 1e-3 * e @ j.T, rtol=1e-4, atol=1e-14)


def test_fixed_convention_squareness_has_no_attitude_effect():
    fixed = build("ac_double_turntable", convention="fixed")
    pe = fixed.pose_error(one("S_xz", 1e-5), POSE)[0]
    assert np.abs(pe[3:]).max() < 1e-15 and np.abs(pe[:3]).max() > 1e-4
    moving = M.pose_error(one("S_xz", 1e-5), POSE)[0]
    assert np.abs(moving[3:]).max() > 5e-6


def test_bad_input():
    with pytest.raises(ValueError, match="allowed: moving, fixed"):
        build("ac_double_turntable", convention="absolute")
    with pytest.raises(ValueError, match="unknown pose name.*allowed: x, y, z, A, C, L"):
        M.pose_error(np.zeros((1, 41)), dict(POSE, B=1.0))
    with pytest.raises(ValueError, match="shape \\(n, 41\\)"):
        M.pose_error(np.zeros((1, 21)), POSE)


def test_closed_form_jacobian_equals_differences_of_the_full_model():
    poses = dict(x=RNG.uniform(-400, 400, 6), y=RNG.uniform(-425, 425, 6),
                 z=RNG.uniform(-275, 275, 6), A=RNG.uniform(-2.2, 2.2, 6),
                 C=RNG.uniform(0, 6.3, 6), L=RNG.uniform(0, 120, 6))
    jac = M.jacobian(poses)
    assert jac.shape == (6, 6, 41)
    fd = M.jacobian(poses, step=1e-6)  # central differences, step 1e-6: about 1e-8 absolute noise
    assert np.abs(jac - fd).max() < 1e-6
    # a translational error enters exactly linearly: a 1 mm difference is exact to rounding
    tr = [j for j, c in enumerate(M.catalogue) if c.translational]
    fd_big = M.jacobian(poses, step=1.0)
    assert np.abs(jac[:, :, tr] - fd_big[:, :, tr]).max() < 1e-12
    # a scalar pose gives one Jacobian; the fixed convention falls back to differences
    assert M.jacobian(POSE).shape == (1, 6, 41)
    fixed = build("ac_double_turntable", convention="fixed")
    assert np.allclose(fixed.jacobian(POSE), fixed.jacobian(POSE, step=1e-6))
