"""Abbe references of the linear axes (machines.chain ``references``, the axis table's
``reference_mm``), the datums that absorb removed location errors, and the readers' every-problem,
closed-file refusals (issue: notebook 06 depends on where the travel's zero is).

Physical model of our own: a moving-gantry five-axis machine over a trunnion table (A on the bed,
C on A; the gantry X carries the saddle Y, which carries the ram Z and the tool), entered once
with X 0..4000 and once with X -2000..2000, the reference shifted with it;
and a one-axis slide with a tool, computed by hand."""

import os

import numpy as np
import pytest

from mtaccuracy import sensitivity as S
from mtaccuracy.machines import readers as R
from mtaccuracy.machines.iso import iso_machine

GANTRY = "w C A b X Y Z t"
PIVOTS = {"A": [0.0, 0.0, -200.0], "C": [0.0, 0.0, 50.0]}
TRAVELS = {"y": (-800.0, 800.0), "z": (-500.0, 0.0), "A": (-2.0, 2.0), "C": (0.0, 6.0)}
TOOL = ("tx", "ty", "tz")
SHIFT = 2000.0                                   # mm: X 0..4000 entered as -2000..2000


def _gantry(low, **kw):
    return iso_machine(GANTRY, name="gantry", pivots=PIVOTS, tool_offsets=TOOL,
                       travels={**TRAVELS, "x": (low, low + 4000.0)}, **kw)


def _poses(rng, n):
    return dict(x=rng.uniform(0.0, 4000.0, n), y=rng.uniform(-800, 800, n),
                z=rng.uniform(-500, 0, n), A=rng.uniform(-2, 2, n), C=rng.uniform(0, 6, n),
                B=rng.uniform(-2, 2, n),
                tx=np.zeros(n), ty=np.zeros(n), tz=np.full(n, -150.0))


def _errors(machine, rng, n):
    half = np.where([e.translational for e in machine.catalogue], 5e-3, 2e-5)   # mm, rad
    return rng.uniform(-1.0, 1.0, (n, machine.n_errors)) * half


HEADS = {"B": [0.0, 0.0, 150.0], "C": [0.0, 0.0, 300.0], "A": [0.0, 0.0, 150.0]}


def _machine(topology, low, **kw):
    """``topology`` with X's travel from ``low`` (4000 mm long), rotary axes on the head."""
    rot = [a for a in "ABC" if a in topology.split()]
    travels = {"x": (low, low + 4000.0), "y": (-800.0, 800.0), "z": (-500.0, 0.0),
               **{a: (-2.0, 2.0) for a in rot}}
    return iso_machine(topology, name="gantry", pivots={a: HEADS[a] for a in rot},
                       tool_offsets=TOOL, travels=travels, **kw)


@pytest.mark.parametrize("topology, depends", [("w b X Y Z C A t", False),
                                               ("w Y b X Z B t", True), ("w X b Y Z B t", True),
                                               ("w Y X b Z t", True)])
def test_a_shifted_zero_with_its_reference_is_the_same_machine(topology, depends):
    """The same machine entered with X 0..4000 and -2000..2000, X's reference shifted with it
    and nothing else changed (tool offsets, pivots, the other references): a moving gantry with
    a two-axis head (every error motion turns with the tool carriage: X's zero and reference
    matter nowhere), a gantry over a moving table, a moving table under a gantry, a cross
    table (the table's tilts turn about its point under the tool carriage at the references:
    X's reference matters)."""
    refs = {"Y": 100.0, "Z": -50.0}
    one = _machine(topology, 0.0, references={**refs, "X": 2500.0})
    two = _machine(topology, -SHIFT, references={**refs, "X": 2500.0 - SHIFT})
    unreferred = _machine(topology, -SHIFT, references={**refs, "X": 2500.0})
    assert one.error_names == two.error_names and one.removed == two.removed
    rng = np.random.default_rng(5)
    pose = {k: v for k, v in _poses(rng, 400).items() if k in (*one.axes, *one.tool_offsets)}
    moved = {**pose, "x": pose["x"] - SHIFT}
    e = _errors(one, rng, 400)
    p1, p2 = one.pose_error(e, pose), two.pose_error(e, moved)
    # exact chain, squareness errors included: the same pose errors to rounding (mm, rad)
    assert np.abs(p1 - p2).max() < 1e-11 < 1e-3 < np.abs(p1[:, :3]).max()
    # with the reference left where it was, a table's arms are measured from elsewhere
    assert (np.abs(unreferred.pose_error(e, moved) - p1).max() > 1e-2) == depends
    # the closed form and the atlas's indices agree too
    j1, j2 = one.jacobian(pose), two.jacobian(moved)
    assert np.abs(j1 - j2).max() < 1e-9 * np.abs(j1).max()
    var = (2 * np.where([s.translational for s in one.catalogue], 5e-3, 2e-5)) ** 2 / 12
    i1, i2 = S.indices_at_poses(j1, var=var), S.indices_at_poses(j2, var=var)
    assert np.abs(i1 - i2).max() < 1e-10
    i0 = S.indices_at_poses(unreferred.jacobian(moved), var=var)
    assert (np.abs(i0 - i1).max() > 0.01) == depends


@pytest.mark.parametrize("topology", ["w C b X Y Z B t", "w C A b X Y Z t"])
def test_a_rotary_table_follows_the_shifted_zero_when_its_pivot_is_reentered(topology):
    """Rotary tables on the bed (notebook 06's default, and a trunnion): their error motions
    and location errors turn about their point at the reference point, so X 0..4000 and
    -2000..2000 are the same machine once the pivots, given in the bed's coordinates, are
    written in the new ones (the table's axis at X 2000 becomes X 0)."""
    def machine(low):
        pivots = {"B": [0.0, 0.0, 150.0], "C": [2000.0 + low, 0.0, 50.0],
                  "A": [2000.0 + low, 0.0, -200.0]}
        rot = [a for a in "ABC" if a in topology.split()]
        travels = {"x": (low, low + 4000.0), "y": (-800.0, 800.0), "z": (-500.0, 0.0),
                   **{a: (-2.0, 2.0) for a in rot}}
        return iso_machine(topology, pivots={a: pivots[a] for a in rot}, travels=travels,
                           tool_offsets=TOOL, references={"X": 2500.0 + low, "Z": -100.0})
    one, two = machine(0.0), machine(-SHIFT)
    rng = np.random.default_rng(8)
    pose = {k: v for k, v in _poses(rng, 200).items() if k in (*one.axes, *one.tool_offsets)}
    moved = {**pose, "x": pose["x"] - SHIFT}
    e = _errors(one, rng, 200)
    assert np.abs(one.pose_error(e, pose) - two.pose_error(e, moved)).max() < 1e-11
    j1 = one.jacobian(pose)
    assert np.abs(j1 - two.jacobian(moved)).max() < 1e-9 * np.abs(j1).max()
    # the closed form follows the referred exact chain for the rotary blocks too
    assert np.abs(j1 - one.jacobian(pose, step=1e-6)).max() < 1e-7 * np.abs(j1).max()


@pytest.mark.parametrize("form", ["euler", "screw", "first_order"])
def test_the_closed_form_follows_the_referred_exact_chain(form):
    m = iso_machine("w X b Y Z B t", form=form, tool_offsets=TOOL, pivots={"B": [0, 0, 150.0]},
                    references={"X": 350.0, "Y": -120.0, "Z": 80.0})
    rng = np.random.default_rng(3)
    pose = dict(x=rng.uniform(0, 1000, 6), y=rng.uniform(-300, 300, 6),
                z=rng.uniform(-250, 250, 6), B=rng.uniform(-1.5, 1.5, 6), tx=2.0, ty=-1.0,
                tz=-120.0)
    jac, diff = m.jacobian(pose), m.jacobian(pose, step=1e-6)
    # central differences are exact to step**2 x the third derivative (arms of 1e3 mm): 1e-7
    assert np.abs(jac - diff).max() < 1e-7 * max(1.0, np.abs(jac).max())


def test_references_of_zero_are_todays_chain_bit_for_bit():
    rng = np.random.default_rng(1)
    a = iso_machine("w C b X Y Z B t", tool_offsets=TOOL, pivots={"B": [0, 0, 150.0]})
    b = iso_machine("w C b X Y Z B t", tool_offsets=TOOL, pivots={"B": [0, 0, 150.0]},
                    references={"X": 0.0, "Y": 0.0, "Z": 0.0})
    pose = dict(x=120.0, y=-40.0, z=30.0, B=0.4, C=1.1, tz=-120.0)
    e = _errors(a, rng, 50)
    assert np.array_equal(a.pose_error(e, pose), b.pose_error(e, pose))
    assert np.array_equal(a.jacobian(pose), b.jacobian(pose))


@pytest.mark.parametrize("side", ["table", "head"])
def test_the_abbe_error_is_the_angle_times_the_arm_by_hand(side):
    # one slide X (a table under a fixed tool, or a head carrying it) and a tool L = 100 mm along
    # z; reference r = 300 mm; at q = 1000 mm a pitch EBX = w about y
    topo = "w X b t" if side == "table" else "w b X t"
    m = iso_machine(topo, tool_offsets=("L",), references={"X": 300.0})
    w, q, r, L = 2e-5, 1000.0, 300.0, 100.0
    e = np.zeros((1, m.n_errors))
    e[0, m.error_names.index("EBX")] = w
    got = m.pose_error(e, {"x": q, "L": L})[0, :3]
    if side == "table":
        # the table turns by w about y through its point at the reference; the fixed tool tip
        # sits (q - r, 0, L) from that point in the table, which the rotation moves by
        # -(w e_y) x (q - r, 0, L) relative to the tool: the tool, seen from the part, moves
        # by (-w L, 0, +w (q - r)): the Abbe error w (q - r) = 14 um up
        want = [-w * L, 0.0, w * (q - r)]
    else:
        # the head's error motions are referred to the carriage that holds the tool, whatever
        # its reference along its own travel: it turns about it, the tool L below: (w L, 0, 0)
        want = [w * L, 0.0, 0.0]
    # exact to first order: the exact chain adds w**2 x arm / 2 (below 1e-6 of the 14 um)
    np.testing.assert_allclose(got, want, rtol=0, atol=w**2 * q)
    # and a positioning error is the error at the reference, unchanged by the arm (a table's
    # +1 um moves the part, so the tool relative to it by -1 um)
    e = np.zeros((1, m.n_errors))
    e[0, m.error_names.index("EXX")] = 1e-3
    np.testing.assert_allclose(m.pose_error(e, {"x": q, "L": L})[0, :3],
                               [-1e-3 if side == "table" else 1e-3, 0, 0], atol=1e-15)


def test_a_bad_reference_is_refused():
    with pytest.raises(ValueError, match="reference given for 'B', not a linear axis"):
        iso_machine("w b X B t", references={"B": 1.0})
    with pytest.raises(ValueError, match="reference of X must be a finite number"):
        iso_machine("w b X t", references={"X": float("nan")})


def test_removed_location_errors_name_the_datum_that_absorbs_them():
    trunnion = _gantry(0.0).absorbed_by       # tool-side Z: the height of A is the tool length
    assert trunnion["EZ0A"].startswith("absorbed by the tool length offset (gauge line to tip")
    assert "or by the zero of Z" in trunnion["EZ0A"]
    # the same errors with the rotary axes on the head: the work offset absorbs them instead
    head = iso_machine("w b X Y Z A C t", tool_offsets=TOOL).absorbed_by
    assert head["EZ0A"].startswith("absorbed by the work offset (G54) in z")
    assert all(not w.startswith("absorbed by the tool") for w in head.values())


# --- the readers ---------------------------------------------------------------------------

HEADER = "axis,low,high,unit,pivot_x_mm,pivot_y_mm,pivot_z_mm,reference_mm\n"
ROWS = ("X,0,4000,mm,,,,2000\nY,-800,800,mm,,,,\nZ,-500,0,mm,,,,-250\n"
        "A,-110,110,deg,0,0,-200,\nC,0,360,deg,0,0,50,\n")


def _write(tmp_path, text, name="axes.csv"):
    f = tmp_path / name
    f.write_text(text)
    return f


def test_the_axis_table_reads_the_references(tmp_path):
    f = _write(tmp_path, HEADER + ROWS)
    travels, pivots, refs = R.read_axis_table(f, GANTRY, with_references=True)
    assert refs == {"X": 2000.0, "Y": 0.0, "Z": -250.0} and travels["x"] == (0.0, 4000.0)
    with pytest.raises(ValueError, match=r"reference_mm is given \(X 2000 mm, Z -250 mm\) but "
                                         r"this call would drop it"):
        R.read_axis_table(f, GANTRY)


def test_every_problem_of_a_file_is_reported_at_once(tmp_path):
    text = HEADER + ROWS.replace("X,0,4000,mm,,,,2000", "X,0,4000,mm,,,,5000") \
        .replace("Y,-800,800,mm", "Y,800,-800,mm") \
        .replace("C,0,360,deg,0,0,50,", "C,0,360,deg,0,0,50,7") + "Q,1,2,mm,,,,\n"
    f = _write(tmp_path, text)
    with pytest.raises(ValueError) as info:
        R.read_axis_table(f, GANTRY, with_references=True)
    lines = str(info.value).split("\n")
    assert lines[0] == f"axis table {str(f)!r}: 4 problems, each on its line:"
    assert [ln.split(", ", 1)[1].split(":")[0] for ln in lines[1:]] == \
        ["line 2 (X)", "line 3 (Y)", "line 6 (C)", "line 7 (Q)"]
    assert "the reference 5000 mm lies outside the travel (0, 4000) mm" in lines[1]
    assert "the travel must be finite with high > low, got (800, -800)" in lines[2]
    assert "a rotary axis has no reference_mm" in lines[3]
    assert "axis/axes ['Q'] not in the topology" in lines[4]


def test_every_bad_range_is_reported_at_once_with_its_number_as_written(tmp_path):
    m = iso_machine("w b X t")
    rows = [f"{s},-1,1,{'um' if e.translational else 'urad'}"
            for s, e in zip(m.error_names, m.catalogue, strict=True)]
    rows[0] = "EXX,-12345678901234567890123456,1,um"
    rows[3] = "EAX,-1,1,um"
    f = _write(tmp_path, "symbol,low,high,unit\n" + "\n".join(rows) + "\n", "ranges.csv")
    with pytest.raises(ValueError) as info:
        R.read_ranges(f, m)
    msg = str(info.value)
    assert msg.count("\n") == 2 and "line 2 (EXX): " in msg and "line 5 (EAX): EAX is an angle" \
        in msg
    assert "(-12345678901234567890123456, 1) um reaches 12345678901234567890123456 um" in msg
    assert "e+25" not in msg


def test_a_field_beyond_the_csv_limit_is_named_on_its_line(tmp_path):
    f = _write(tmp_path, HEADER + "X,0,4000,mm,,,,\n" + 'Y,"' + "9" * 140_000 + '",1,mm,,,,\n')
    with pytest.raises(ValueError, match=r"line 3: not a readable CSV: field larger than field "
                                         r"limit \(131072\)"):
        R.read_axis_table(f, GANTRY)


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no named pipes here")
def test_a_fifo_a_directory_and_a_link_to_a_device_are_refused_before_reading(tmp_path):
    fifo = tmp_path / "pipe.csv"
    os.mkfifo(fifo)                               # reading it would block forever
    with pytest.raises(ValueError, match=r"^axis table '.*pipe.csv': is a FIFO \(named pipe\)"):
        R.read_axis_table(fifo, GANTRY)
    with pytest.raises(ValueError, match=r"^range file '.*': is a directory"):
        R.read_ranges(tmp_path, iso_machine("w b X t"))
    zero = tmp_path / "zero.csv"
    zero.symlink_to("/dev/zero")                  # reading it would fill memory
    with pytest.raises(ValueError, match=r"zero.csv': is a character device"):
        R.read_axis_table(zero, GANTRY)
    with pytest.raises(FileNotFoundError, match="not found"):
        R.read_axis_table(tmp_path / "none.csv", GANTRY)
