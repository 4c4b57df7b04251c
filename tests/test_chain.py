"""The generic kinematic chain (machines.chain): topology parsing (machines.topology), the
closed-form Jacobian, batching, the ISO catalogue and its redundant location errors
(machines.iso), a machine no paper covers.
The papers' machines are held to independent formulations in their own test files."""

import numpy as np
import pytest

from mtaccuracy.machines import build
from mtaccuracy.machines import chain as C
from mtaccuracy.machines import iso as ISO
from mtaccuracy.machines import readers as R
from mtaccuracy.machines import topology as T

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


CASES = [("ac_double_turntable", {}), ("ac_double_turntable", {"convention": "fixed"}),
         ("vertical_xyfz", {}), ("vertical_xyfz", {"exact": True}),
         *[("horizontal_3axis", {"layout": lay, "exact": ex})
           for lay in ("z/xy", "x/zy", "w b X Y Z t", "w Z Y X b t") for ex in (True, False)]]


@pytest.mark.parametrize("case", CASES, ids=str)
def test_closed_form_jacobian(case):
    m = build(case[0], **case[1])
    poses = _poses(m.axes + m.tool_offsets, 40)
    jac = m.jacobian(poses)
    # against central differences of the chain itself (which lose ~8 digits: 1e-7 here)
    fd = m.jacobian(poses, step=1e-6)
    assert np.abs(jac - fd).max() < 1e-6 * max(1.0, np.abs(jac).max())


@pytest.mark.parametrize("case", CASES, ids=str)
def test_batches_do_not_change_the_result(case):
    m = build(case[0], **case[1])
    e = _errors(m, 1000, 3.0)
    poses = _poses(m.axes + m.tool_offsets, 1000)
    whole = m.pose_error(e, poses)
    m.chunk = 333                                   # batches of 333, 333, 333, 1
    assert np.array_equal(m.pose_error(e, poses), whole)
    one = {k: v[0] for k, v in poses.items()}
    assert np.array_equal(m.pose_error(e[:5], one), m.pose_error(e[:5], {k: np.full(5, v)
                                                                        for k, v in one.items()}))


def test_a_machine_no_paper_covers_swivel_head_with_pivot():
    m = ISO.iso_machine("w C b X Y Z B t", pivots={"B": (0.0, 0.0, 150.0)}, tool_offsets=("L",))
    poses = _poses(m.axes, 30)
    poses["L"] = np.full(30, 120.0)
    jac = m.jacobian(poses)
    assert np.abs(jac - m.jacobian(poses, step=1e-6)).max() < 1e-6 * np.abs(jac).max()
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
    m = ISO.iso_machine("w C A b Y X Z t")
    poses = _poses(m.axes + m.tool_offsets, 50)
    assert np.abs(m.pose_error(np.zeros((50, m.n_errors)), poses)).max() < 1e-12
    jac = m.jacobian(poses)

    def remainder(scale):
        e = _errors(m, 50, scale)
        return np.abs(m.pose_error(e, poses) - np.einsum("npd,nd->np", jac, e)).max()
    assert remainder(1e-4) < 2e-12            # 1 nm, 5 nrad: the rounding floor
    ratio = remainder(1e-2) / remainder(1e-3)  # above it, the remainder is second order
    assert 30 < ratio < 300


def test_iso_catalogue_and_redundant_location_errors():
    cat, placements = ISO.iso_catalogue("w C A b Y X Z t")
    assert len(cat) == 5 * 6 + 3 + 2 * 4
    assert [e.symbol for e in cat[:6]] == ["EXA", "EYA", "EZA", "EAA", "EBA", "ECA"]
    assert {"EC0Y", "EB0Z", "EA0Z"} <= {e.symbol for e in cat}
    m = ISO.iso_machine("w C A b Y X Z t")
    removed = dict(m.removed)
    # a shift of the A axis line along y or z is a shift of the Y or Z zero; a C axis line
    # tilted about x turns like the A axis; an x shift of C moves along A's axis
    assert set(removed) == {"EY0A", "EZ0A", "EX0C", "EA0C"}
    assert removed["EA0C"] == "same effect as the zero of A"
    assert m.n_errors == 37 and "EB0C" in m.error_names and "EY0C" in m.error_names
    # no redundancy among the three squareness errors of a three-axis machine
    assert ISO.iso_machine("w Z b X Y t").removed == []


def test_zheng_location_errors_in_the_moving_reading_are_mostly_set_up():
    removed = dict(ISO.redundant_location_errors(build("ac_double_turntable")))
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
        T.parse_topology(text)


def test_topology_forms():
    t = T.parse_topology("wCAbYXZt")
    assert t.work == ("A", "C") and t.tool == ("Y", "X", "Z")
    assert T.parse_topology("w C' A' b Y X Z s t") == T.Topology("w C' A' b Y X Z s t",
                                                                  ("A", "C"), ("Y", "X", "Z"))
    assert "workpiece <- C <- A <- bed -> Y -> X -> Z -> tool" in t.describe()


def test_bad_machine_descriptions_are_refused():
    cat, pl = ISO.iso_catalogue("w b X Y t")
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


AXIS_TABLE = """axis,low,high,unit,pivot_x_mm,pivot_y_mm,pivot_z_mm
X,-400,400,mm,,,
Y,-300,300,mm,,,
Z,-250,250,mm,,,
B,-110,110,deg,0,0,150
C,0,360,deg,,,
"""


def test_axis_table_gives_travels_and_pivots(tmp_path):
    f = tmp_path / "axes.csv"
    f.write_text(AXIS_TABLE)
    travels, pivots = R.read_axis_table(f, "w C b X Y Z B t")
    assert travels["x"] == (-400.0, 400.0) and np.allclose(travels["B"], np.deg2rad([-110, 110]))
    assert set(pivots) == {"B"} and np.array_equal(pivots["B"], [0.0, 0.0, 150.0])


@pytest.mark.parametrize("edit, message", [
    (lambda t: t.replace("C,0,360,deg,,,\n", ""), r"no row for axis/axes \['C'\]"),
    (lambda t: t + "A,0,90,deg,,,\n", r"axis/axes \['A'\] not in the topology"),
    (lambda t: t + "X,0,90,mm,,,\n", r"axis/axes \['X'\] given more than once"),
    (lambda t: t.replace("X,-400,400,mm,,,", "X,-400,400,mm,1,2,3"), "a linear axis has no pivot"),
    (lambda t: t.replace("0,0,150", "0,,150"), "give all three pivot_\\*_mm or none"),
    (lambda t: t.replace("-250,250,mm", "250,-250,mm"), "high > low"),
    (lambda t: t.replace("-110,110,deg", "-110,110,rad"), "unit must be 'deg' for a rotary axis"),
    (lambda t: t.replace("pivot_z_mm", "pivot_z"), r"lacks column\(s\) \['pivot_z_mm'\]"),
])
def test_an_inconsistent_axis_table_is_refused(tmp_path, edit, message):
    f = tmp_path / "axes.csv"
    f.write_text(edit(AXIS_TABLE))
    with pytest.raises(ValueError, match=message):
        R.read_axis_table(f, "w C b X Y Z B t")


def _range_file(m, tmp_path, rows=None):
    rows = rows if rows is not None else [
        (e.symbol, -5, 5, "um" if e.translational else "urad") for e in m.catalogue]
    f = tmp_path / "ranges.csv"
    f.write_text("symbol,low,high,unit\n"
                 + "".join(f"{s},{lo},{hi},{u}\n" for s, lo, hi, u in rows))
    return f


def test_range_file_gives_bounds_in_library_units(tmp_path):
    m = ISO.iso_machine("w C A b Y X Z t")
    b = R.read_ranges(_range_file(m, tmp_path), m)
    tr = np.array([e.translational for e in m.catalogue])
    assert np.allclose(b[1, tr], 5e-3) and np.allclose(b[1, ~tr], 5e-6) and b.shape == (2, 37)


def test_a_range_file_that_does_not_match_the_catalogue_is_refused(tmp_path):
    m = ISO.iso_machine("w C A b Y X Z t")
    good = [(e.symbol, -5, 5, "um" if e.translational else "urad") for e in m.catalogue]
    with pytest.raises(ValueError, match=r"EY0A.*removed: same effect as the zero of y"):
        R.read_ranges(_range_file(m, tmp_path, good + [("EY0A", -1, 1, "um")]), m)
    with pytest.raises(ValueError, match=r"no range for error\(s\) \['EXX'\]"):
        R.read_ranges(_range_file(m, tmp_path, [r for r in good if r[0] != "EXX"]), m)
    with pytest.raises(ValueError, match=rf"error\(s\) \['{good[0][0]}'\] given more than once"):
        R.read_ranges(_range_file(m, tmp_path, good + [good[0]]), m)
    good = sorted(good, key=lambda r: r[0] != "EXX")                 # EXX first: line 2
    bad = [("EXX", -5, 5, "urad"), *good[1:]]
    with pytest.raises(ValueError, match="EXX is a translation, unit 'urad' is not"):
        R.read_ranges(_range_file(m, tmp_path, bad), m)
    bad = [("EXX", 5, -5, "um"), *good[1:]]
    with pytest.raises(ValueError, match=r"line 2 \(EXX\): the range must be finite with high"):
        R.read_ranges(_range_file(m, tmp_path, bad), m)
    with pytest.raises(FileNotFoundError, match="range file"):
        R.read_ranges(tmp_path / "nothing.csv", m)


def test_every_machine_checks_its_errors_and_pose_the_same_way():
    """What every machine shares (the catalogue's columns, the pose checks), on ChainMachine."""
    m = ISO.iso_machine("w C b X Y Z t")
    assert isinstance(build("horizontal_3axis"), C.ChainMachine)
    assert repr(m) == (f"<ChainMachine 'iso_machine': {m.n_errors} errors, "
                       "axes ('C', 'x', 'y', 'z')>")
    assert m.n_errors == len(m.catalogue) == len(m.error_names)
    with pytest.raises(ValueError, match=rf"shape \(n, {m.n_errors}\)"):
        m.check_errors(np.zeros((2, m.n_errors + 1)))
    p = m.check_pose({"C": [0.1, 0.2], "x": 1.0, "y": 2.0, "z": 3.0}, 2)
    assert set(p) == {"C", "x", "y", "z", "L"} and p["L"].tolist() == [0.0, 0.0]
    assert p["x"].tolist() == [1.0, 1.0]
    with pytest.raises(TypeError, match="mapping"):
        m.check_pose([1.0, 2.0], 1)
    with pytest.raises(ValueError, match="unknown pose name"):
        m.check_pose({"C": 0.0, "x": 0.0, "y": 0.0, "z": 0.0, "B": 1.0}, 1)
    with pytest.raises(ValueError, match="lacks axis"):
        m.check_pose({"x": 0.0, "y": 0.0, "z": 0.0}, 1)
    with pytest.raises(ValueError, match=r"shape \(3,\)"):
        m.check_pose({"C": [0.1, 0.2], "x": 0.0, "y": 0.0, "z": 0.0}, 3)


def test_counts_and_seeds_are_checked_by_the_one_helper():
    m = build("horizontal_3axis")
    with pytest.raises(ValueError, match="chunk must be an integer >= 1, got 0"):
        C.ChainMachine("w b X t", m.catalogue[:1], {"dx(x)": C.Placement("X", "motion", 0)},
                       chunk=0)
    iso = ISO.iso_machine("w C b X t", keep_redundant=True)
    with pytest.raises(ValueError, match="n_poses must be an integer >= 1, got 2.5"):
        ISO.redundant_location_errors(iso, n_poses=2.5)
    with pytest.raises(ValueError, match="seed must be"):
        ISO.redundant_location_errors(iso, seed=True)
    # the same seed, the same answer (an int or a Generator seeded alike)
    assert ISO.redundant_location_errors(iso, seed=3) == ISO.redundant_location_errors(
        iso, seed=np.random.default_rng(3))
