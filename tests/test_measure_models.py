"""The standard tests as models (mtaccuracy.measure.instruments) on error motions that vary with
position (mtaccuracy.measure.motions): linearisation against the exact chain, hand formulas,
and what each test sees or is blind to, by rank and null-space computations written here."""

import numpy as np
import pytest

from mtaccuracy.machines.iso import iso_machine
from mtaccuracy.measure import instruments as ins
from mtaccuracy.measure.design import combine
from mtaccuracy.measure.motions import motion_model

TRAVELS3 = {"x": (-300.0, 300.0), "y": (-200.0, 200.0), "z": (-250.0, 250.0)}
TRAVELS5 = {"x": (-400.0, 400.0), "y": (-300.0, 300.0), "z": (-250.0, 250.0),
            "B": (-1.9, 1.9), "C": (0.0, 2 * np.pi)}


@pytest.fixture(scope="module")
def three():
    return motion_model(iso_machine("w b X Y Z t", travels=TRAVELS3), degree=2)


@pytest.fixture(scope="module")
def five():
    m = iso_machine("w C b X Y Z B t", travels=TRAVELS5, pivots={"B": (0.0, 0.0, 150.0)})
    return motion_model(m, degree=2)


def _truth(model, seed, um=1.0, urad=2.0):
    """A machine of our own: every parameter drawn at um / urad sizes (mm, rad)."""
    rng = np.random.default_rng(seed)
    scale = np.where(np.array(model.units) == "mm", um * 1e-3, urad * 1e-6)
    return rng.normal(size=model.n_params) * scale


def _free(design):
    """A with the nuisances projected out: what the readings see of the errors."""
    if design.N.shape[1] == 0:
        return design.A
    q, _ = np.linalg.qr(design.N)
    return design.A - q @ (q.T @ design.A)


def _blind(a, col, rtol=1e-9):
    """Is column (or combination) ``col`` of the errors invisible in ``a`` (nuisance-free)?"""
    return np.linalg.norm(a @ col) <= rtol * np.linalg.norm(a) * np.linalg.norm(col)


def _unit(model, **values):
    v = np.zeros(model.n_params)
    for k, val in values.items():
        v[model.names.index(k.replace("_", "[", 1) + "]" if "_" in k else k)] = val
    return v


# --- the motion model --------------------------------------------------------------------

def test_names_datums_and_the_dropped_slope(three, five):
    assert three.names[:3] == ("EXX[0]", "EXX[1]", "EXX[2]")
    assert "EYX[1]" not in three.names and "EYX[1]" in three.dropped
    assert "EAX[1]" in three.names                     # an angular error keeps its slope
    assert "EC0Y" in three.names                       # squareness: one constant
    assert set(three.datums) == {"EXX[0]", "EYY[0]", "EZZ[0]"}
    # five-axis: the linear zeros stand for the C axis line; C's zero is the alignment
    assert set(five.datums) == {"ECC"}
    # 3 axes x (6 x 3 terms - 2 dropped slopes) + 3 squareness
    assert three.n_params == 3 * 16 + 3


def test_legendre_terms_at_the_ends_and_middle(three):
    p = _unit(three, EXX_1=2e-3, EXX_2=1e-3)
    e = three.chain_errors(p, {"x": np.array([-300.0, 0.0, 300.0]), "y": 0.0, "z": 0.0})
    j = three.machine.error_names.index("EXX")
    # P1 = -1, 0, 1 and P2 = 1, -1/2, 1 at u = -1, 0, 1
    np.testing.assert_allclose(e[:, j], [-2e-3 + 1e-3, -0.5e-3, 3e-3], atol=1e-15)


def test_motion_model_refuses_a_machine_without_travels():
    with pytest.raises(ValueError, match=r"no travel of x.*travels=\{'x'"):
        motion_model(iso_machine("w b X t"), degree=1)
    assert motion_model(iso_machine("w b X t"), degree=0).names[0] == "EXX"


def test_parameters_of_the_wrong_length_are_refused(three):
    t = ins.laser_positioning(three, axis="X")
    with pytest.raises(ValueError, match="must be 51 finite values"):
        t.readings(np.zeros(5))


# --- linearisation ------------------------------------------------------------------------

@pytest.mark.parametrize("which", ["three", "five"])
def test_every_standard_test_is_linear_within_1e3_of_the_exact_chain(which, request):
    model = request.getfixturevalue(which)
    truth = _truth(model, 7)
    for t in ins.standard_plan(model):
        y = t.readings(truth)
        lin = t.design().A @ truth
        rel = np.linalg.norm(y - lin) / np.linalg.norm(y)
        assert rel < 1e-3, (t.name, rel)


def test_nuisances_enter_linearly(three):
    t = ins.circle(three, plane="XY", radius=80.0, n_points=24)
    truth, nu = _truth(three, 3), np.array([2.0, -1.0, 5.0])
    np.testing.assert_allclose(t.readings(truth, nu) - t.readings(truth), t.N @ nu, atol=1e-12)


# --- hand formulas ------------------------------------------------------------------------

def test_circle_squareness_gives_minus_r_alpha_sin_2theta_over_2(three):
    r, alpha = 100.0, 20e-6
    t = ins.circle(three, plane="XY", radius=r, n_points=36, directions=("ccw",))
    y = t.readings(_unit(three, EC0Y=alpha))
    theta = 2 * np.pi * np.arange(36) / 36
    hand = -1000.0 * r * alpha * np.sin(2 * theta) / 2       # um, first order
    # second order: (r alpha)^2 / r ~ 4e-8 mm = 4e-5 um of a 1 um signal
    np.testing.assert_allclose(y, hand, atol=1e-4 * np.abs(hand).max())
    # exactly: Y's direction turned to (-sin alpha, cos alpha), the ball at x + y d_Y
    x, yy = r * np.cos(theta), r * np.sin(theta)
    exact = np.hypot(x - yy * np.sin(alpha), yy * np.cos(alpha)) - r
    np.testing.assert_allclose(y, 1000.0 * exact, atol=1e-9)


def test_circle_scale_gives_s_r_cos2_theta(three):
    # the travel's middle is the circle's centre: EXX(x) = s x with s = EXX[1] / 300 mm
    r, s = 100.0, 10e-6
    t = ins.circle(three, plane="XY", radius=r, n_points=36, directions=("ccw",))
    y = t.readings(_unit(three, EXX_1=s * 300.0))
    theta = 2 * np.pi * np.arange(36) / 36
    exact = np.hypot((1 + s) * r * np.cos(theta), r * np.sin(theta)) - r
    np.testing.assert_allclose(y, 1000.0 * exact, atol=1e-9)
    np.testing.assert_allclose(y, 1000.0 * s * r * np.cos(theta) ** 2, atol=1e-5)


def test_the_beam_offset_reads_pitch_times_the_offset(three):
    # a reflector 50 mm above the tool point (tool frame z) minus one at it: the pitch EBX(x)
    # about y moves the offset point by EBX(x) * 50 mm along x (w x o = (b e_y) x (50 e_z))
    truth = _truth(three, 11)
    at = ins.laser_positioning(three, axis="X", offset=(0.0, 0.0, 50.0))
    on = ins.laser_positioning(three, axis="X")
    x = at.pose["x"]
    u = x / 300.0
    k = [three.names.index(f"EBX[{i}]") for i in range(3)]
    ebx = truth[k[0]] + truth[k[1]] * u + truth[k[2]] * (3 * u ** 2 - 1) / 2
    # Y and Z stand at the middle of their travels (u = 0: P1 = 0, P2 = -1/2): their pitches
    # about y add a constant
    rest = sum(truth[three.names.index(f"EB{a}[0]")] - truth[three.names.index(f"EB{a}[2]")] / 2
               for a in "YZ")
    diff = at.readings(truth) - on.readings(truth)
    np.testing.assert_allclose(diff, 1000.0 * 50.0 * (ebx + rest), rtol=1e-4, atol=1e-6)


def test_the_angular_test_reads_the_sum_of_the_pitches(three):
    truth = _truth(three, 5)
    t = ins.angular(three, axis="X", about="y")
    u = t.pose["x"] / 300.0
    total = sum(truth[three.names.index(f"EB{a}[0]")] for a in "XYZ") \
        + truth[three.names.index("EBX[1]")] * u \
        + truth[three.names.index("EBX[2]")] * (3 * u ** 2 - 1) / 2 \
        - sum(truth[three.names.index(f"EB{a}[2]")] for a in "YZ") / 2
    np.testing.assert_allclose(t.readings(truth), 1e6 * total, rtol=1e-4)


def test_follow_puts_the_ideal_tool_tip_on_the_path(five):
    rng = np.random.default_rng(2)
    tip = rng.uniform(-100.0, 100.0, (20, 3))
    pose = ins.follow(five, tip, pose={"C": rng.uniform(0, 6, 20), "B": rng.uniform(-1, 1, 20),
                                       "L": 120.0})
    _, t = five.machine.relative(np.zeros((20, five.machine.n_errors)), pose,
                                 with_errors=False)
    np.testing.assert_allclose(t, tip, atol=1e-9)
    with pytest.raises(ValueError, match="cannot put the tool tip"):
        ins.follow(motion_model(iso_machine("w b X Y t"), degree=0), [[0.0, 0.0, 5.0]],
                   pose={})


def test_the_r_test_reads_a_tool_offset_as_a_constant(five):
    # the tool 3 um off in x in the machine frame (the zero of x): in the workpiece frame the
    # error turns with the table, Rot(-C) d; the sensors turn with it (tool frame Rot(-C)), so
    # every reading is (d, 0, 0); the sphere's set-up (the nuisance) is a first harmonic
    t = ins.r_test(five, axis="C", radius=150.0, height=100.0, n_angles=12)
    y = t.readings(_unit(five, EXX_0=3e-3)).reshape(12, 3)
    np.testing.assert_allclose(y, np.tile([3.0, 0.0, 0.0], (12, 1)), atol=1e-9)
    c = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    np.testing.assert_allclose(t.N[0::3, 0], -np.cos(c), atol=1e-12)


# --- what each test sees --------------------------------------------------------------------

def test_circle_sees_scale_difference_and_squareness_not_mean_scale_or_centre(three):
    a = _free(ins.circle(three, plane="XY", radius=100.0).design())
    hx, hy = 300.0, 200.0
    mean = _unit(three, EXX_1=hx, EYY_1=hy)              # the same scale on both axes
    diff = _unit(three, EXX_1=hx, EYY_1=-hy)
    assert _blind(a, mean)
    assert _blind(a, _unit(three, EXX_0=1.0)) and _blind(a, _unit(three, EYY_0=1.0))
    assert not _blind(a, diff, rtol=1e-3) and not _blind(a, _unit(three, EC0Y=1.0), rtol=1e-3)
    # a second harmonic is orthogonal to the nuisances: nothing of it is lost
    sq = _unit(three, EC0Y=1.0)
    d = ins.circle(three, plane="XY", radius=100.0).design()
    np.testing.assert_allclose(np.linalg.norm(a @ sq), np.linalg.norm(d.A @ sq), rtol=1e-9)


def test_laser_line_is_blind_to_roll_and_sees_pitch_through_the_offset(three):
    a = _free(ins.laser_positioning(three, axis="X", offset=(0.0, 40.0, 50.0)).design())
    for k in range(3):
        assert _blind(a, _unit(three, **{f"EAX_{k}": 1.0}))
    assert _blind(a, _unit(three, EXX_0=1.0))            # the laser's zero
    assert not _blind(a, _unit(three, EXX_1=1.0), rtol=1e-3)
    assert not _blind(a, _unit(three, EBX_1=1.0), rtol=1e-3)
    # on the tool point pitch and yaw vanish too (no Abbe offset)
    a0 = _free(ins.laser_positioning(three, axis="X", at={"L": 0.0}, tool=0.0).design())
    assert _blind(a0, _unit(three, EBX_1=1.0))


def test_straightness_is_blind_to_squareness_without_a_square(three):
    a = _free(ins.straightness(three, axis="Y", direction="X").design())
    assert _blind(a, _unit(three, EC0Y=1.0))
    assert not _blind(a, _unit(three, EXY_2=1.0), rtol=1e-3)


ROTARY = ["EXX[0]", "EYY[0]", "EA0C", "EB0C"]


def _sub(model, design, names):
    return _free(design)[:, [model.names.index(n) for n in names]]


def _combinations_blind(model, design, h):
    """The single set-up's null space over (x zero, y zero, EA0C, EB0C): the offsets of C's
    axis line (the linear zeros stand for them) and its tilts are seen only as
    x - h EB0C and y + h EA0C (h the height above C's pivot)."""
    a = _sub(model, design, ROTARY)
    s = np.linalg.svd(a / np.linalg.norm(a, axis=0), compute_uv=False)
    assert np.sum(s > 1e-9 * s[0]) == 2
    for v in (np.array([h, 0.0, 0.0, 1.0]), np.array([0.0, -h, 1.0, 0.0])):
        assert np.linalg.norm(a @ v) < 1e-9 * np.linalg.norm(a) * np.linalg.norm(v)


def test_a_single_rotary_ballbar_trace_leaves_offset_and_height_tilt_combined(five):
    for mode in ("radial", "tangential"):
        _combinations_blind(five, ins.rotary_ballbar(five, axis="C", mode=mode,
                                                     height=100.0).design(), 100.0)
    # C's own error motions (constant in the table frame) and its zero move the workpiece
    a = _free(ins.rotary_ballbar(five, axis="C", mode="radial").design())
    for n in ("EXC", "EYC", "EZC", "EAC", "EBC", "ECC"):
        assert _blind(a, _unit(five, **{n: 1.0})), n


def test_on_axis_r_test_confounds_offset_with_height_times_tilt(five):
    low = ins.r_test(five, axis="C", height=100.0).design()
    _combinations_blind(five, low, 100.0)
    high = ins.r_test(five, axis="C", height=250.0).design()
    _combinations_blind(five, high, 250.0)
    both = _sub(five, combine([low, high]), ROTARY)
    s = np.linalg.svd(both / np.linalg.norm(both, axis=0), compute_uv=False)
    assert s.min() > 1e-3 * s.max()                    # two heights separate all four


def test_axis_zeros_are_blind_in_the_whole_standard_plan(three, five):
    for model in (three, five):
        a = _free(combine([t.design() for t in ins.standard_plan(model)]))
        for name in model.datums:
            assert _blind(a, _unit(model, **{name.replace("[", "_").rstrip("]"): 1.0})), name


def test_a_design_is_a_design_of_the_models_parameters(three):
    d = ins.circle(three, plane="ZX", radius=50.0, n_points=8).design()
    assert d.errors == three.names and d.n_obs == 16 and d.nuisances[-1] == "bar length (um)"
    assert d.labels[0].startswith("circle ZX ccw") and d.labels[8].startswith("circle ZX cw")


# --- refusals ------------------------------------------------------------------------------

def test_bad_set_ups_are_refused_with_the_fix(three, five):
    with pytest.raises(ValueError, match="not a linear axis"):
        ins.laser_positioning(three, axis="B")
    with pytest.raises(ValueError, match="not a rotary axis"):
        ins.r_test(three, axis="C")
    with pytest.raises(ValueError, match="plane must be two linear axes"):
        ins.circle(three, plane="XX")
    with pytest.raises(ValueError, match="radius must be"):
        ins.circle(three, radius=-1.0)
    with pytest.raises(ValueError, match="direction must be another"):
        ins.straightness(three, axis="X", direction="X")
    with pytest.raises(ValueError, match="unknown pose name"):
        ins.laser_positioning(three, axis="X", at={"q": 1.0})
    with pytest.raises(ValueError, match="sigma must be"):
        ins.laser_positioning(three, axis="X", sigma=0.0)
    with pytest.raises(ValueError, match="nu must be 3 values"):
        ins.circle(three, n_points=8).readings(np.zeros(three.n_params), [1.0])
