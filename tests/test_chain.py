"""The generic kinematic chain (machines.chain): topology parsing, the three papers' machines
as descriptions against today's hand-written chains, the closed-form Jacobian, the ISO
catalogue and its redundant location errors."""

import numpy as np
import pytest

from mtaccuracy.machines import build
from mtaccuracy.machines import chain as C

RNG = np.random.default_rng(20261124)


def _errors(machine, n, scale=1.0):
    """Errors of realistic size: 10 um and 50 urad (sd), times ``scale``."""
    sd = np.array([1e-2 if s.translational else 5e-5 for s in machine.catalogue]) * scale
    return RNG.standard_normal((n, machine.n_errors)) * sd


def _poses(names, n):
    out = {}
    for k in names:
        if k == "A":
            out[k] = RNG.uniform(-2.2, 2.2, n)
        elif k in ("B", "C"):
            out[k] = RNG.uniform(0.0, 2 * np.pi, n)
        else:
            out[k] = RNG.uniform(-400.0, 400.0, n)
    return out


CASES = [
    (lambda: build("ac_double_turntable"), lambda: C.zheng_ac()),
    (lambda: build("ac_double_turntable", convention="fixed"), lambda: C.zheng_ac("fixed")),
    (lambda: build("vertical_xyfz"), lambda: C.guo_vertical()),
    (lambda: build("vertical_xyfz", exact=True), lambda: C.guo_vertical(exact=True)),
    *[(lambda lay=lay, ex=ex: build("horizontal_3axis", layout=lay, exact=ex),
       lambda lay=lay, ex=ex: C.rong_horizontal(lay, exact=ex))
      for lay in ("z/xy", "x/zy", "zx/y", "/xyz", "xyz/") for ex in (True, False)],
]


@pytest.mark.parametrize("case", range(len(CASES)))
@pytest.mark.parametrize("scale", [1.0, 30.0])
def test_the_papers_machines_as_descriptions_reproduce_the_hand_written_chains(case, scale):
    old, new = CASES[case][0](), CASES[case][1]()
    assert [e.symbol for e in new.catalogue] == old.error_names
    e = _errors(old, 3000, scale)
    poses = _poses(old.axes + old.tool_offsets, 3000)
    assert np.abs(new.pose_error(e, poses) - old.pose_error(e, poses)).max() < 1e-12
    one = {k: float(v[0]) for k, v in poses.items()}           # one pose: the fast paths
    assert np.abs(new.pose_error(e, one) - old.pose_error(e, one)).max() < 1e-12


@pytest.mark.parametrize("case", range(len(CASES)))
def test_closed_form_jacobian(case):
    old, new = CASES[case][0](), CASES[case][1]()
    poses = _poses(old.axes + old.tool_offsets, 40)
    jac = new.linear_jacobian(poses)
    # against central differences of the chain itself (which lose ~8 digits: 1e-7 here)
    fd = new.jacobian(poses)
    assert np.abs(jac - fd).max() < 1e-6 * max(1.0, np.abs(jac).max())
    # against today's closed forms, where there is one: equal to rounding
    ref = (old.linear_jacobian(poses) if getattr(old, "convention", None) == "moving"
           else old.first_order_jacobian(poses) if hasattr(old, "first_order_jacobian")
           else None)
    if ref is not None:
        assert np.abs(jac - ref).max() < 1e-12


def test_a_machine_no_paper_covers_swivel_head_with_pivot():
    m = C.iso_machine("w C b X Y Z B t", pivots={"B": (0.0, 0.0, 150.0)}, tool_offsets=("L",))
    poses = _poses(m.axes, 30)
    poses["L"] = np.full(30, 120.0)
    jac = m.linear_jacobian(poses)
    assert np.abs(jac - m.jacobian(poses)).max() < 1e-6 * np.abs(jac).max()
    # the ideal chain: the tool axis is the head's B rotation seen from the turned table
    r, t = m.relative(np.zeros((30, m.n_errors)), poses, with_errors=False)
    b, c = poses["B"], poses["C"]
    axis = np.stack([np.cos(c) * np.sin(b), -np.sin(c) * np.sin(b), np.cos(b)], -1)
    assert np.allclose(r[:, :, 2], axis, atol=1e-14)
    # the tip: the pivot moves with X, Y, Z; the tool hangs 150 + 120 mm below ... above it
    arm = 150.0 * np.array([0, 0, 1.0]) + (-150.0 + 120.0) * np.stack(
        [np.sin(b), np.zeros_like(b), np.cos(b)], -1)
    base = np.stack([poses["x"], poses["y"], poses["z"]], -1) + arm
    rc_t = np.stack([np.stack([np.cos(c), np.sin(c), 0 * c], -1),
                     np.stack([-np.sin(c), np.cos(c), 0 * c], -1),
                     np.stack([0 * c, 0 * c, 1 + 0 * c], -1)], -2)
    assert np.allclose(t, np.einsum("nij,nj->ni", rc_t, base), atol=1e-10)


def test_zero_errors_give_zero_and_errors_are_linear_to_first_order():
    m = C.iso_machine("w C A b Y X Z t")
    poses = _poses(m.axes + m.tool_offsets, 50)
    assert np.abs(m.pose_error(np.zeros((50, m.n_errors)), poses)).max() < 1e-12
    jac = m.linear_jacobian(poses)

    def remainder(scale):
        e = _errors(m, 50, scale)
        return np.abs(m.pose_error(e, poses) - np.einsum("npd,nd->np", jac, e)).max()
    assert remainder(1e-4) < 2e-12            # 1 nm, 5 nrad: the rounding floor
    ratio = remainder(1e-2) / remainder(1e-3)  # above it, the remainder is second order
    assert 30 < ratio < 300


def test_iso_catalogue_and_redundant_location_errors():
    cat, placements = C.iso_catalogue("w C A b Y X Z t")
    assert len(cat) == 5 * 6 + 3 + 2 * 4
    assert [e.symbol for e in cat[:6]] == ["EXA", "EYA", "EZA", "EAA", "EBA", "ECA"]
    assert {"EC0Y", "EB0Z", "EA0Z"} <= {e.symbol for e in cat}
    m = C.iso_machine("w C A b Y X Z t")
    removed = dict(m.removed)
    # a shift of the A axis line along y or z is a shift of the Y or Z zero; a C axis line
    # tilted about x turns like the A axis; an x shift of C moves along A's axis
    assert set(removed) == {"EY0A", "EZ0A", "EX0C", "EA0C"}
    assert removed["EA0C"] == "same effect as the zero of A"
    assert m.n_errors == 37 and "EB0C" in m.error_names and "EY0C" in m.error_names
    # no redundancy among the three squareness errors of a three-axis machine
    assert C.iso_machine("w Z b X Y t").removed == []


def test_zheng_location_errors_in_the_moving_reading_are_mostly_set_up():
    removed = dict(C.redundant_location_errors(C.zheng_ac("moving")))
    assert removed["a_AM"] == "same effect as the zero of A"
    assert removed["d_yCA"] == "same effect as the workpiece set-up along y"
    assert "b_AM" not in removed


@pytest.mark.parametrize("text, message", [
    ("w C A Y X Z t", "must contain the bed 'b' exactly once"),
    ("w C Q b X t", r"unknown axis letter\(s\) \['Q'\]"),
    ("C A b X Y Z t", "must start with 'w' and end with 't'"),
    ("w X b X Z t", r"axis \['X'\] appears more than once"),
    ("w b t", "has no axis"),
    ("w b X s Y t", "'s' \\(spindle\\) may only come just before 't'"),
    ("", "empty topology"),
])
def test_bad_topologies_are_refused_with_the_grammar(text, message):
    with pytest.raises(ValueError, match=message):
        C.parse_topology(text)


def test_topology_forms():
    t = C.parse_topology("wCAbYXZt")
    assert t.work == ("A", "C") and t.tool == ("Y", "X", "Z")
    assert C.parse_topology("w C' A' b Y X Z s t") == C.Topology("w C' A' b Y X Z s t",
                                                                  ("A", "C"), ("Y", "X", "Z"))
    assert "workpiece <- C <- A <- bed -> Y -> X -> Z -> tool" in t.describe()


def test_bad_machine_descriptions_are_refused():
    cat, pl = C.iso_catalogue("w b X Y t")
    with pytest.raises(ValueError, match="unknown block form 'matrix'"):
        C.ChainMachine("w b X Y t", cat, pl, form="matrix")
    with pytest.raises(ValueError, match=r"no placement for error\(s\) \['EXX'\]"):
        C.ChainMachine("w b X Y t", cat, {k: v for k, v in pl.items() if k != "EXX"})
    bad = dict(pl, EXX=C.Placement("Z", "motion", 0))
    with pytest.raises(ValueError, match="placed on axis 'Z', which is not in the topology"):
        C.ChainMachine("w b X Y t", cat, bad)
    bad = dict(pl, EXX=C.Placement("X", "motion", 1))
    with pytest.raises(ValueError, match="errors EXX and EYX both occupy component Y"):
        C.ChainMachine("w b X Y t", cat, bad)
    with pytest.raises(ValueError, match="pivot given for 'X', not a rotary axis"):
        C.ChainMachine("w b X Y t", cat, pl, pivots={"X": (0, 0, 0)})
    m = C.ChainMachine("w b X Y t", cat, pl)
    with pytest.raises(ValueError, match=r"must have shape \(n, 13\)"):
        m.pose_error(np.zeros((2, 12)), dict(x=0.0, y=0.0))
    with pytest.raises(ValueError, match=r"lacks axis value\(s\) \['y'\]"):
        m.pose_error(np.zeros((2, 13)), dict(x=0.0))
