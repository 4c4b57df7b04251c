"""The XYFZ machine of Guo et al. 2016: the chain against the independent sympy product of the
paper's matrices (:mod:`mtaccuracy.papers.guo2016`), arms, linearity, bad input."""

import numpy as np
import pytest
import sympy as sp

from mtaccuracy.machines import build
from mtaccuracy.papers import guo2016

M = build("vertical_xyfz")
NAMES = M.error_names
RNG = np.random.default_rng(2)
SCALE = np.array([3e-3] * 3 + [4e-3] * 6 + [3.2e-5] * 9 + [1.9e-6] * 3)
POSE = dict(x=120.0, y=-80.0, z=150.0, D1=10.0, D2=-20.0, D3=90.0)


def one(symbol, value, n=1):
    e = np.zeros((n, 21))
    e[:, NAMES.index(symbol)] = value
    return e


def test_api():
    assert NAMES[:3] == ["dx(x)", "dy(y)", "dz(z)"] and NAMES[-3:] == ["S_xy", "S_yz", "S_xz"]
    assert M.axes == ("x", "y", "z") and M.tool_offsets == ("D1", "D2", "D3")
    assert M.pose_error(np.zeros((4, 21)), POSE).shape == (4, 6)


def test_zero_errors_give_zero_at_any_pose():
    poses = dict(x=RNG.uniform(-500, 500, 7), y=RNG.uniform(-500, 500, 7),
                 z=RNG.uniform(-500, 500, 7), D3=RNG.uniform(0, 200, 7))
    assert np.abs(M.pose_error(np.zeros((7, 21)), poses)).max() < 1e-12


@pytest.mark.parametrize("symbol, component", [("dx(x)", 0), ("dy(y)", 1), ("dz(z)", 2),
                                               ("dz(x)", 2), ("dx(y)", 0)])
def test_pure_translation_error_moves_only_its_direction(symbol, component):
    pe = M.pose_error(one(symbol, 2e-3), POSE)[0]
    expected = np.zeros(6)
    expected[component] = 2e-3
    assert np.allclose(pe, expected, atol=1e-15)


def test_abbe_and_squareness_arms():
    pe = M.pose_error(one("ez(x)", 1e-5), POSE)[0]  # Ex = -(y + D2) ez(x), Ey = D1 ez(x)
    assert pe[0] == pytest.approx(-(POSE["y"] + POSE["D2"]) * 1e-5)
    assert pe[1] == pytest.approx(POSE["D1"] * 1e-5)
    assert pe[5] == pytest.approx(1e-5)
    assert M.pose_error(one("S_xy", 1e-6), POSE)[0, 0] == pytest.approx(-POSE["y"] * 1e-6)
    assert M.pose_error(one("S_yz", 1e-6), POSE)[0, 1] == pytest.approx(-POSE["z"] * 1e-6)


def test_x_never_enters_the_error():
    e = RNG.uniform(size=(5, 21)) * SCALE
    a = M.pose_error(e, dict(POSE, x=0.0))
    b = M.pose_error(e, dict(POSE, x=400.0))
    assert np.allclose(a, b, atol=1e-15)


def test_response_is_linear_for_small_errors():
    e = RNG.uniform(-1, 1, size=(3, 21)) * SCALE
    p1, p2 = M.pose_error(e, POSE), M.pose_error(1e-3 * e, POSE)
    assert np.allclose(p2, 1e-3 * p1, rtol=1e-3, atol=1e-15)


def test_numpy_product_equals_independent_sympy_product():
    exprs = guo2016.symbolic_position_error()
    sym_e, sym_p = guo2016.symbols()
    f = sp.lambdify([list(sym_e.values()), list(sym_p.values())], exprs, "numpy")
    e = RNG.uniform(-1, 1, size=(6, 21)) * SCALE * 50  # large errors: every order matters
    num = M.pose_error(e, POSE)[:, :3]
    ref = np.column_stack(f(e.T, [POSE[k] for k in sym_p]))
    # actual - ideal cancels ~100 mm terms: agreement to 1e-12 mm is all doubles allow
    assert np.allclose(num, ref, rtol=1e-10, atol=1e-12)


def test_exact_rotations_agree_to_first_order():
    e = RNG.uniform(-1, 1, size=(4, 21)) * SCALE
    a, b = M.pose_error(e, POSE), build("vertical_xyfz", exact=True).pose_error(e, POSE)
    assert 0 < np.abs(a - b).max() < 1e-6  # eps^2 * arm: (3.2e-5)^2 * 300 mm ~ 3e-7 mm


@pytest.mark.parametrize("errors, pose, message", [
    (np.zeros((3, 20)), dict(x=0, y=0, z=0), "shape \\(n, 21\\)"),
    (np.zeros(21), dict(x=0, y=0, z=0), "shape \\(n, 21\\)"),
    (np.zeros((1, 21)), dict(x=0, y=0, z=0, w=1), "unknown pose name.*allowed: x, y, z, D1"),
    (np.zeros((1, 21)), dict(x=0, y=0), "lacks axis value"),
    (np.zeros((2, 21)), dict(x=np.zeros(3), y=0, z=0), "scalar or have shape \\(2,\\)"),
])
def test_bad_input_is_refused_with_a_clear_message(errors, pose, message):
    with pytest.raises(ValueError, match=message):
        M.pose_error(errors, pose)


def test_unknown_machine_names_the_allowed_ones():
    with pytest.raises(ValueError, match="allowed: .*vertical_xyfz"):
        build("gantry")
