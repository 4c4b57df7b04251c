"""The readers of a researcher's own machine (notebook 06): the topology string
(machines.topology), the axis table and the range file (machines.readers).  A message about a
bad row names the file and the line an editor shows.  Inputs no machine could need are refused
at once, by their size. A travel too large for any machine is refused, and a redundancy
explanation is never blank.  A value that makes sense only in another unit (metres or inches
labelled mm, radians labelled deg, microns labelled mm, an angle in a length unit) is refused
when no machine tool has it, warned when only a rare one does, with the file, the line, the
limit and the likely unit (issue 22).

The large inputs are built in tmp_path.  No test measures time, but each runs in well under a
second only while the checks are linear (the quadratic ones took minutes on these inputs)."""

import re
import warnings

import numpy as np
import pytest

from mtaccuracy import errors
from mtaccuracy.compendium.provenance import ROOT
from mtaccuracy.machines import iso as ISO
from mtaccuracy.machines import readers as R
from mtaccuracy.machines import topology as T
from mtaccuracy.machines import units as U

TOPOLOGY = "w C b X Y Z B t"

# comments before the header, a blank line and a comment line between the rows
AXES = """\
# Travels of the axes (mm, deg) and the pivots (mm).
# B: the head swivels about y.

axis,low,high,unit,pivot_x_mm,pivot_y_mm,pivot_z_mm
X,-400,400,mm,,,

# the Y axis carries the head
Y,-300,300,mm,,,  # a comment after the values
Z,-250,250,mm,,,
B,-110,110,deg,0,0,150
C,0,360,deg,,,
"""


def _line_of(text, start):
    """The 1-based line (as an editor numbers them) of the only line starting with ``start``."""
    (n,) = [i for i, line in enumerate(text.splitlines(), 1) if line.startswith(start)]
    return n


def _write(tmp_path, text, name="axes.csv", newline="\n"):
    f = tmp_path / name
    f.write_bytes(text.replace("\n", newline).encode())
    return f


def test_the_line_counts_of_the_fixture_are_an_editors():
    # the counts the tests below compute, checked once by hand
    assert [_line_of(AXES, s) for s in ("axis", "X,", "Y,", "Z,", "B,", "C,")] == \
        [4, 5, 8, 9, 10, 11]


def test_a_commented_axis_table_reads_like_a_plain_one(tmp_path):
    plain = "".join(line.split("#")[0].rstrip() + "\n" for line in AXES.splitlines()
                    if line and not line.startswith("#"))
    assert "#" not in plain and plain.count("\n") == 6
    travels, pivots = R.read_axis_table(_write(tmp_path, AXES), TOPOLOGY)
    travels0, pivots0 = R.read_axis_table(_write(tmp_path, plain, "plain.csv"), TOPOLOGY)
    assert travels == travels0 and travels["y"] == (-300.0, 300.0)
    assert set(pivots) == set(pivots0) == {"B"} and np.array_equal(pivots["B"], [0, 0, 150])


@pytest.mark.parametrize("newline", ["\n", "\r\n"], ids=["lf", "crlf"])
@pytest.mark.parametrize("old, new, message", [
    ("Z,-250,250,mm", "Z,250,-250,mm", "the travel must be finite with high > low"),
    ("B,-110,110,deg", "B,-110,110,rad", "unit must be 'deg' for a rotary axis, got 'rad'"),
    ("C,0,360", "C,0,x", "low and high must be numbers, got '0', 'x'"),
    ("Y,-300,300,mm,,,", "Y,-300,300,mm,1,2,3", "a linear axis has no pivot"),
    ("B,-110,110,deg,0,0,150", "B,-110,110,deg,0,,150", r"give all three pivot_\*_mm or none"),
])
def test_a_bad_row_is_named_by_its_line_in_the_file(tmp_path, newline, old, new, message):
    text = AXES.replace(old, new)
    f = _write(tmp_path, text, newline=newline)
    line = _line_of(text, new[:2])
    with pytest.raises(ValueError, match=rf"^axis table '{re.escape(str(f))}', line {line} "
                                         rf"\({new[0]}\): {message}"):
        R.read_axis_table(f, TOPOLOGY)


# a note column whose quoted value spans four lines and holds a '#' and a blank line
NOTE = '"the X axis,\nover four lines # not a comment\n\nend"'
AXES_NOTE = AXES.replace("pivot_z_mm\n", "pivot_z_mm,note\n").replace(
    "X,-400,400,mm,,,\n", f"X,-400,400,mm,,,,{NOTE}\n")


def test_a_quoted_field_over_several_lines_shifts_the_lines_after_it(tmp_path):
    assert R.read_axis_table(_write(tmp_path, AXES_NOTE), TOPOLOGY)[0] == \
        R.read_axis_table(_write(tmp_path, AXES, "plain.csv"), TOPOLOGY)[0]
    text = AXES_NOTE.replace("Z,-250,250,mm", "Z,250,-250,mm")
    assert _line_of(text, "Z,") == 12
    with pytest.raises(ValueError, match=r"line 12 \(Z\): the travel must be finite"):
        R.read_axis_table(_write(tmp_path, text), TOPOLOGY)
    text = AXES_NOTE.replace("X,-400,400,mm", "X,400,-400,mm")      # the record of lines 5-8
    with pytest.raises(ValueError, match=r"lines 5-8 \(X\): the travel must be finite"):
        R.read_axis_table(_write(tmp_path, text), TOPOLOGY)


def test_unknown_repeated_and_missing_axes_point_at_their_lines(tmp_path):
    n = len(AXES.splitlines())
    with pytest.raises(ValueError, match=rf"line {n + 1} \(A\), line {n + 2} \(Q\): axis/axes "
                                         r"\['A', 'Q'\] not in the topology"):
        R.read_axis_table(_write(tmp_path, AXES + "A,0,90,deg,,,\nQ,0,1,mm,,,\n"), TOPOLOGY)
    with pytest.raises(ValueError, match=rf"lines 5 and {n + 1} \(X\): axis/axes \['X'\] given "
                                         "more than once"):
        R.read_axis_table(_write(tmp_path, AXES + "X,0,90,mm,,,\n"), TOPOLOGY)
    with pytest.raises(ValueError, match=r"\(header on line 4, rows on lines 5-10\): no row for "
                                         r"axis/axes \['C'\]"):
        R.read_axis_table(_write(tmp_path, AXES.replace("C,0,360,deg,,,\n", "")), TOPOLOGY)
    with pytest.raises(ValueError, match=r"line 4 \(the header\): lacks column\(s\) "
                                         r"\['pivot_z_mm'\]"):
        R.read_axis_table(_write(tmp_path, AXES.replace("pivot_z_mm", "pivot_z")), TOPOLOGY)


def test_a_malformed_csv_is_named_by_its_line(tmp_path):
    with pytest.raises(ValueError, match="line 9: a quoted field opens here and is never closed"):
        R.read_axis_table(_write(tmp_path, AXES.replace("Z,-250", 'Z,"-250')), TOPOLOGY)
    with pytest.raises(ValueError, match=r"line 9: 8 fields, but the header \(line 4\) names 7"):
        R.read_axis_table(_write(tmp_path, AXES.replace("Z,-250,250,mm,,,",
                                                        "Z,-250,250,mm,,,,7")), TOPOLOGY)
    f = tmp_path / "latin1.csv"
    f.write_bytes(AXES.replace("# the Y axis", "# the Y axis \xb1 1 mm").encode("latin-1"))
    with pytest.raises(ValueError, match="line 7: not UTF-8 text"):
        R.read_axis_table(f, TOPOLOGY)
    with pytest.raises(ValueError, match="has no header line"):
        R.read_axis_table(_write(tmp_path, "# nothing but a comment\n\n"), TOPOLOGY)


@pytest.fixture(scope="module")
def machine():
    return ISO.iso_machine(TOPOLOGY)


def _ranges(machine, edit=lambda rows: rows):
    """A range file with two comment lines, a blank line and a comment between its rows."""
    rows = [f"{e.symbol},-5,5,{'um' if e.translational else 'urad'}" for e in machine.catalogue]
    rows = edit(rows)
    return ("# error ranges\n# (illustrative)\n\nsymbol,low,high,unit\n" + "\n".join(rows[:10])
            + "\n# the linear axes\n" + "\n".join(rows[10:]) + "\n")


def test_the_range_file_names_the_line_of_a_bad_row(tmp_path, machine):
    def bad_unit(rows):
        return [r.replace("EZZ,-5,5,um", "EZZ,-5,5,urad") for r in rows]
    text = _ranges(machine, bad_unit)
    f = _write(tmp_path, text, "ranges.csv")
    line = _line_of(text, "EZZ,")
    assert line == 4 + 10 + 1 + 11           # header, ten rows, a comment, EZZ the 21st error
    with pytest.raises(ValueError, match=rf"^range file '{re.escape(str(f))}', line {line} "
                                         r"\(EZZ\): EZZ is a translation, unit 'urad' is not"):
        R.read_ranges(f, machine)
    text = _ranges(machine, lambda rows: [r.replace("EXC,-5,5", "EXC,5,-5") for r in rows])
    with pytest.raises(ValueError, match=r"line 5 \(EXC\): the range must be finite with "
                                         "high > low"):
        R.read_ranges(_write(tmp_path, text, "ranges.csv"), machine)


def test_the_range_file_points_at_unknown_repeated_and_missing_errors(tmp_path, machine):
    text = _ranges(machine, lambda rows: [*rows, "EX0C,-1,1,um"])
    line = _line_of(text, "EX0C,")
    with pytest.raises(ValueError, match=rf"line {line} \(EX0C\): error\(s\) \['EX0C'\] not in "
                                         r"the catalogue .*EX0C \(removed: same effect as the "
                                         "zero of x"):
        R.read_ranges(_write(tmp_path, text, "ranges.csv"), machine)
    text = _ranges(machine, lambda rows: [*rows, rows[0]])
    assert text.splitlines()[4] == text.splitlines()[-1] == "EXC,-5,5,um"
    with pytest.raises(ValueError, match=rf"lines 5 and {len(text.splitlines())} \(EXC\): "
                                         r"error\(s\) \['EXC'\] given more than once"):
        R.read_ranges(_write(tmp_path, text, "ranges.csv"), machine)
    text = _ranges(machine, lambda rows: [r for r in rows if not r.startswith("EXX,")])
    last = len(text.splitlines())
    with pytest.raises(ValueError, match=rf"\(header on line 4, rows on lines 5-{last}\): no "
                                         r"range for error\(s\) \['EXX'\]"):
        R.read_ranges(_write(tmp_path, text, "ranges.csv"), machine)


# -- sizes ---------------------------------------------------------------------------------

def test_a_huge_topology_is_refused_at_once_with_an_excerpt():
    text = " ".join(["w", "b", *["X"] * 99_997, "t"])            # 100,000 tokens
    with pytest.raises(ValueError) as info:
        T.parse_topology(text)
    msg = str(info.value)
    assert f"is longer than {T.MAX_TOPOLOGY_CHARS} characters" in msg
    assert repr(text[:60]) + "... (199999 characters)" in msg and len(msg) < 600
    with pytest.raises(ValueError, match=rf"has 100 tokens, more than {T.MAX_TOPOLOGY_TOKENS}"):
        T.parse_topology("w" + "X" * 98 + "t")


def test_the_topology_cap_is_on_the_characters_and_messages_quote_an_excerpt():
    padded = "w C b X Y Z B t".ljust(T.MAX_TOPOLOGY_CHARS)
    assert T.parse_topology(padded).axes == ("C", "X", "Y", "Z", "B")
    with pytest.raises(ValueError, match="longer than 200 characters"):
        T.parse_topology(padded + " ")
    text = "w b X X" + " " * 150 + "t"
    with pytest.raises(ValueError, match=r"axis \['X'\] appears more than once in topology "
                                         r"'w b X X {53}'\.\.\. \(158 characters\)$"):
        T.parse_topology(text)


def test_topology_parsing_is_linear(monkeypatch):
    # with the caps lifted, the repeated-axis check of a 100,000-token string (quadratic: about
    # 40 s on the project machine; linear: hundredths of a second)
    monkeypatch.setattr(T, "MAX_TOPOLOGY_CHARS", 10**9)
    monkeypatch.setattr(T, "MAX_TOPOLOGY_TOKENS", 10**9)
    text = " ".join(["w", "b", *["X"] * 99_997, "t"])
    with pytest.raises(ValueError, match=r"axis \['X'\] appears more than once .*\.\.\. "
                                         r"\(199999 characters\)$"):
        T.parse_topology(text)


def test_files_larger_than_any_machine_needs_are_refused_at_once(tmp_path, machine):
    header = ",".join(R.AXIS_TABLE_COLUMNS) + "\n"
    f = _write(tmp_path, header + "X,-400,400,mm,,,\n" * 200_000)          # 3.4 MB
    with pytest.raises(ValueError, match=rf"^axis table '{re.escape(str(f))}' is 3400052 bytes, "
                                         rf"more than the {R.MAX_TABLE_BYTES} bytes allowed"):
        R.read_axis_table(f, TOPOLOGY)
    f = _write(tmp_path, header + "X,0,1,mm,,,\n" * 100_000)               # 1.2 MB
    with pytest.raises(ValueError, match="has 100001 lines, more than the 10000 allowed"):
        R.read_axis_table(f, TOPOLOGY)
    f = _write(tmp_path, header + "X,0,1,mm,,,\n" * 1500)
    with pytest.raises(ValueError, match=r"line 1002: more than 1000 data rows; it should hold "
                                         "one row per axis"):
        R.read_axis_table(f, TOPOLOGY)
    f = _write(tmp_path, "symbol,low,high,unit\n" + "EXX,-5,5,um\n" * 200_000, "ranges.csv")
    with pytest.raises(ValueError, match=r"^range file .* is 2400021 bytes, more than the"):
        R.read_ranges(f, machine)
    f = _write(tmp_path, "symbol,low,high,unit\n" + "EXX,-5,5,um\n" * 5000, "ranges.csv")
    with pytest.raises(ValueError, match="line 1002: more than 1000 data rows; it should hold "
                                         "one row per error"):
        R.read_ranges(f, machine)


def test_a_message_about_many_repeats_stays_short(tmp_path):
    f = _write(tmp_path, ",".join(R.AXIS_TABLE_COLUMNS) + "\n" + "X,0,1,mm,,,\n" * 900)
    with pytest.raises(ValueError) as info:
        R.read_axis_table(f, TOPOLOGY)
    msg = str(info.value)
    # the repeat and the missing axes, each once, in one short message
    assert msg.count("\n") == 2 and len(msg) < 400 + 3 * len(str(f))
    assert msg.split("\n")[1].endswith(r"lines 2, 3, 4, 5, 6, ... (900 lines) (X): axis/axes "
                                       "['X'] given more than once")
    assert "no row for axis/axes ['C', 'Y', 'Z', 'B']" in msg.split("\n")[2]


def test_the_checks_of_the_readers_are_linear(tmp_path, machine, monkeypatch):
    # with the caps lifted, 20,000 repeated rows (list.count per row: seconds; now linear)
    monkeypatch.setattr(R, "MAX_TABLE_ROWS", 10**9)
    monkeypatch.setattr(R, "MAX_TABLE_BYTES", 10**9)
    f = _write(tmp_path, "symbol,low,high,unit\n" + "EXX,-5,5,um\n" * 20_000, "ranges.csv")
    with pytest.raises(ValueError, match=r"lines 2, 3, 4, 5, 6, ... \(20000 lines\) \(EXX\)"):
        R.read_ranges(f, machine)
    f = _write(tmp_path, ",".join(R.AXIS_TABLE_COLUMNS) + "\n" + "Y,0,1,mm,,,\n" * 20_000)
    with pytest.raises(ValueError, match=r"\(20000 lines\) \(Y\): axis/axes \['Y'\] given"):
        R.read_axis_table(f, TOPOLOGY)


# -- travels too large for any machine, and the explanations of redundant errors ------------

@pytest.mark.parametrize("old, new, message", [
    ("X,-400,400", "X,-1e300,1e300", r"the travel \(-1e300, 1e300\) mm goes beyond "
                                     r"\+-100000 mm \(no machine axis travels more than 100 m\)"),
    ("X,-400,400", "X,-400,100001", r"the travel \(-400, 100001\) mm goes beyond \+-100000 mm"),
    ("C,0,360", "C,0,3601", r"the travel \(0, 3601\) deg goes beyond \+-3600 deg"),
    ("B,-110,110,deg,0,0,150", "B,-110,110,deg,0,0,1e300",
     r"the pivot \[0, 0, 1e300\] mm lies beyond \+-100000 mm"),
])
def test_a_travel_or_pivot_no_machine_has_is_refused(tmp_path, old, new, message):
    text = AXES.replace(old, new)
    with pytest.raises(ValueError, match=rf"line {_line_of(text, new[:2])} \({new[0]}\): "
                                         + message):
        R.read_axis_table(_write(tmp_path, text), TOPOLOGY)


def test_the_bounds_themselves_are_accepted(tmp_path):
    text = AXES.replace("X,-400,400", "X,-1e5,1e5").replace("C,0,360", "C,-3600,3600")
    travels, _ = R.read_axis_table(_write(tmp_path, text), TOPOLOGY)
    assert travels["x"] == (-1e5, 1e5) and np.allclose(travels["C"], [-20 * np.pi, 20 * np.pi])


_EFFECT = re.compile(r"the zero of \w+|the workpiece set-up (along|about) [xyz]"
                     r"|the tool offset along [xyz]|E\w+")


@pytest.mark.parametrize("travels", [{}, {"x": (-1e300, 1e300)}, {"x": (-1e155, 1e155)},
                                     {"x": (-1e300, 1e300), "y": (-1e300, 1e300)}], ids=str)
def test_an_explanation_is_never_blank(travels):
    # a travel of 1e300 mm: the squares in the norm of a Jacobian column overflowed, the unit
    # column came out all zeros and was "explained" by no term: "same effect as "
    removed = ISO.iso_machine(TOPOLOGY, travels=travels).removed
    assert removed
    for symbol, reason in removed:
        assert reason.strip() and not reason.rstrip().endswith("as"), (symbol, reason)
        if reason.startswith("same effect as "):
            terms = reason.removeprefix("same effect as ").split(" + ")
            assert all(_EFFECT.fullmatch(t) for t in terms), (symbol, reason)


def test_a_combination_the_fit_cannot_name_is_said_in_words():
    assert ISO._same_effect(["the zero of x", "EA0C"]) == "same effect as the zero of x + EA0C"
    words = ISO._same_effect([])
    assert not words.rstrip().endswith("as") and "none of which could be named" in words


def test_a_travel_beyond_floating_point_is_refused_by_the_rank_test():
    with pytest.raises(ValueError, match=r"the travel \(-inf, inf\) of x is not finite"):
        ISO.iso_machine(TOPOLOGY, travels={"x": (-np.inf, np.inf)})
    with pytest.raises(ValueError, match=r"travel \(-1e\+308, 1e\+308\) of x is not finite "
                                         r"\(or its width overflows\)"):
        ISO.iso_machine(TOPOLOGY, travels={"x": (-1e308, 1e308)})


# -- units: a value that makes sense only in another unit (issue 22) ------------------------
# Refused: what no machine tool has in the unit written; warned: what only a rare one has.
# Every message names the file, the line, the value and unit, the limit and the likely unit
# with the numbers to write.

@pytest.mark.parametrize("old, new, message", [
    # metres labelled mm: a 0.8 m travel
    ("X,-400,400,mm", "X,-0.4,0.4,mm",
     r"the travel \(-0.4, 0.4\) mm spans 0.8 mm, less than the 1 mm any slide of a machine "
     r"tool travels \(sub-millimetre strokes are those of fine-positioning actuators.*\); "
     r"likely in m \(write -400, 400 mm\)$"),
    ("Z,-250,250,mm", "Z,0,0.4,mm", r"the travel \(0, 0.4\) mm spans 0.4 mm, less than the "
                                    r"1 mm .*likely in m \(write 0, 400 mm\)$"),
    # radians labelled deg: a +-110 deg swivel, a +-30 deg tilt
    ("B,-110,110,deg", "B,-1.92,1.92,deg",
     r"the travel \(-1.92, 1.92\) deg spans 3.84 deg, less than the 5 deg any rotary axis of "
     r"a machine tool turns through \(.*\); likely in rad \(write -110, 110 deg\)$"),
    ("B,-110,110,deg", "B,-0.5236,0.5236,deg", r".*; likely in rad \(write -30, 30 deg\)$"),
    # a full turn in radians: 5-15 deg would only be warned, but its ends are 0 and 2 pi
    ("C,0,360,deg", "C,0,6.2832,deg",
     r"the travel \(0, 6.2832\) deg spans 6.2832 deg, less than the 15 deg of a grinder's "
     r"table swivel, and read in radians its ends are whole multiples of 5 deg; likely in "
     r"rad \(write 0, 360 deg\)$"),
    ("C,0,360,deg", "C,-3.1416,3.1416,deg", r".*; likely in rad \(write -180, 180 deg\)$"),
    # a unit the table does not take: converted, or judged in it
    ("B,-110,110,deg", "B,-1.92,1.92,rad", r"unit must be 'deg' for a rotary axis, got 'rad'; "
                                           r"\(-1.92, 1.92\) rad is \(-110, 110\) deg$"),
    ("B,-110,110,deg", "B,-110,110,rad", r".*got 'rad'; read in rad, the travel \(-110, 110\) rad "
                                         r"spans 220 rad, beyond \+-62.83 rad; likely in deg "
                                         r"\(write -110, 110 deg\)$"),
    ("X,-400,400,mm", "X,-0.4,0.4,m", r"unit must be 'mm' for a linear axis, got 'm'; "
                                      r"\(-0.4, 0.4\) m is \(-400, 400\) mm$"),
    ("X,-400,400,mm", "X,-16,16,in", r".*got 'in'; \(-16, 16\) inch is \(-406.4, 406.4\) mm$"),
    ("C,0,360,deg", "C,0,360,°", r"unit must be 'deg' for a rotary axis, got '°'; '°' is "
                                 r"written 'deg'$"),
    ("C,0,360,deg", "C,0,x,°", r".*got '°'; '°' is written 'deg'$"),
    # microns labelled mm: beyond 100 m
    ("X,-400,400,mm", "X,-400000,400000,mm", r".* goes beyond \+-100000 mm \(no machine axis "
                                             r"travels more than 100 m\); if it is in um, "
                                             r"write -400, 400 mm$"),
])
def test_a_travel_in_another_unit_is_refused_with_the_likely_unit(tmp_path, old, new, message):
    text = AXES.replace(old, new)
    f = _write(tmp_path, text)
    with pytest.raises(ValueError, match=rf"^axis table '{re.escape(str(f))}', line "
                                         rf"{_line_of(text, new[:2])} \({new[0]}\): {message}"):
        R.read_axis_table(f, TOPOLOGY)


@pytest.mark.parametrize("old, new, message", [
    # 4 mm: a micro machine's slide, or a 4 m travel in metres
    ("Y,-300,300,mm", "Y,-2,2,mm",
     r"the travel \(-2, 2\) mm spans 4 mm, less than the 10 mm of the smallest machine-tool "
     r"slides \(micro machine tools\); a travel of 1-10 m written in metres reads as this; if "
     r"it is in m, write -2000, 2000 mm; if it is in inch, write -50.8, 50.8 mm; used as "
     r"written$"),
    # the table swivel of a cylindrical grinder (+-6 deg), or +-344 deg in radians
    ("B,-110,110,deg", "B,-6,6,deg",
     r"the travel \(-6, 6\) deg spans 12 deg, less than the 15 deg that only the table swivel "
     r"of a grinder turns through \(.*\); if it is in rad, write -343.8, 343.8 deg; used as "
     r"written$"),
])
def test_a_travel_only_a_rare_machine_has_is_warned_and_used(tmp_path, old, new, message):
    text = AXES.replace(old, new)
    f = _write(tmp_path, text)
    with pytest.warns(U.SuspectUnitWarning) as record:
        travels, _ = R.read_axis_table(f, TOPOLOGY)
    assert len(record) == 1 and record[0].filename == __file__          # the caller's line
    assert re.match(rf"^axis table '{re.escape(str(f))}', line {_line_of(text, new[:2])} "
                    rf"\({new[0]}\): {message}", str(record[0].message)), str(record[0].message)
    lo, hi = (float(x) for x in new.split(",")[1:3])
    name = new[0].lower() if new[0] in T.LINEAR else new[0]
    scale = 1.0 if new[0] in T.LINEAR else np.pi / 180
    assert travels[name] == pytest.approx((lo * scale, hi * scale))   # used as written


# Travels of real kinds of machine (mm, deg), read quietly; in metres and radians, caught.
REAL_MACHINES = {
    "micro milling machine": ("w b X Y Z t", {"X": (0, 50), "Y": (0, 50), "Z": (0, 10)}),
    "ultra-precision lathe": ("w C b X Z t", {"C": (0, 360), "X": (-110, 110), "Z": (0, 150)}),
    "trunnion five-axis mill": ("w C A b X Y Z t", {"C": (-3600, 3600), "A": (-120, 30),
                                                    "X": (0, 650), "Y": (0, 520),
                                                    "Z": (0, 475)}),
    "swivel head over a table": ("w C b X Y Z B t", {"C": (0, 360), "X": (-400, 400),
                                                     "Y": (-300, 300), "Z": (-250, 250),
                                                     "B": (-30, 30)}),
    "gantry mill": ("w b X Y Z A C t", {"X": (0, 20000), "Y": (0, 4000), "Z": (0, 1500),
                                       "A": (-110, 110), "C": (-360, 360)}),
}
#: What no check catches (data/machines/README.md): a travel of 10 m or more in metres, a
#: rotary axis of more than two turns in radians.
BLIND_SPOTS = {"gantry mill": {"X"}, "trunnion five-axis mill": {"C"}}


def _axis_table(travels, si=None):
    """An axis table of ``travels`` (mm, deg), the axis ``si`` written in metres or radians
    (still labelled mm or deg)."""
    rows = []
    for a, (lo, hi) in travels.items():
        k = 1.0 if a != si else 1e-3 if a in T.LINEAR else np.pi / 180
        rows.append(f"{a},{lo * k:.5g},{hi * k:.5g},{'mm' if a in T.LINEAR else 'deg'},,,")
    return ",".join(R.AXIS_TABLE_COLUMNS) + "\n" + "\n".join(rows) + "\n"


@pytest.mark.parametrize("kind", REAL_MACHINES)
def test_real_machines_are_read_quietly_and_their_metres_and_radians_are_caught(tmp_path, kind):
    topology, travels = REAL_MACHINES[kind]
    f = _write(tmp_path, _axis_table(travels), "real.csv")
    got, _ = _read_axes_quietly(f, topology)
    assert len(got) == len(travels)
    missed = set()
    for a, (lo, hi) in travels.items():
        f = _write(tmp_path, _axis_table(travels, si=a), "si.csv")
        linear = a in T.LINEAR
        span = (hi - lo) * (1e-3 if linear else np.pi / 180)     # as the file now reads
        likely = "m" if linear else "rad"
        if span < (1 if linear else 5) or (not linear and span < 15):
            # refused: a span no machine has (for a rotary axis of 5-15 "deg": ends that read
            # as whole multiples of 5 deg in radians, true of every machine here)
            with pytest.raises(ValueError, match=rf"line \d+ \({a}\): the travel .* likely in "
                                                 rf"{likely} \(write "):
                R.read_axis_table(f, topology)
        elif span < (10 if linear else 15):
            with pytest.warns(U.SuspectUnitWarning, match=rf"\({a}\): .*if it is in {likely}"):
                R.read_axis_table(f, topology)
        else:
            _read_axes_quietly(f, topology)
            missed.add(a)
    assert missed == BLIND_SPOTS.get(kind, set())


def _read_axes_quietly(f, topology=TOPOLOGY):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return R.read_axis_table(f, topology)


def _edit_row(symbol, new):
    """An edit of :func:`_ranges`' rows: the row of ``symbol`` replaced by ``new``."""
    return lambda rows: [new if r.startswith(f"{symbol},") else r for r in rows]


@pytest.mark.parametrize("symbol, new, message", [
    # a translation of 15 mm: microns labelled mm
    ("EXX", "EXX,-15,15,mm",
     r"the range \(-15, 15\) mm reaches 15 mm, more than the 10 mm any machine tool in "
     r"service is off by \(.*\); likely in um \(write -15, 15 um\)$"),
    # an angle of 15 rad: urad or arcsec labelled rad
    ("EAX", "EAX,-15,15,rad",
     r"the range \(-15, 15\) rad reaches 15 rad, more than the 0.01 rad of a misalignment "
     r"seen by eye \(10 mm/m, 0.57 deg\); .*; likely in urad \(write -15, 15 urad\) or "
     r"arcsec \(write -15, 15 arcsec\)$"),
    ("EC0Y", "EC0Y,-5000,5000,arcsec",
     r"the range \(-5000, 5000\) arcsec reaches 5000 arcsec, more than the 2063 arcsec "
     r"\(0.01 rad\) of a misalignment seen by eye .*\(0.1-100 arcsec\)$"),   # no unit fits
    # an angle in a linear unit, a translation in an angular one: the units of the kind
    ("EXX", "EXX,-15,15,arcsec",
     r"EXX is a translation, unit 'arcsec' is not \(positioning: write it in um or mm\)$"),
    ("EC0Y", "EC0Y,-12,12,um",
     r"EC0Y is an angle, unit 'um' is not \(squareness: write it in urad, rad, arcsec or "
     r"um/m\); a deviation over a length is an angle: divide by the length, um/m$"),
    # 15 deg is no angular error; 0.001 deg is, and is said in urad
    ("EAX", "EAX,-15,15,deg",
     r"unknown unit 'deg'; allowed: um, mm, rad, urad, um/m, arcsec; EAX is an angle "
     r"\(angular\): write it in urad, rad, arcsec or um/m; read in deg, the range \(-15, 15\) "
     r"deg reaches 15 deg, more than the 0.573 deg \(0.01 rad\) .*; likely in urad \(write "
     r"-15, 15 urad\) or arcsec \(write -15, 15 arcsec\)$"),
    ("EBY", "EBY,-0.001,0.001,deg", r"unknown unit 'deg'.*; \(-0.001, 0.001\) deg is "
                                    r"\(-17.45, 17.45\) urad$"),
    ("EC0Y", "EC0Y,-0.02,0.02,mm/m", r"unknown unit 'mm/m'.*EC0Y is an angle \(squareness\).*; "
                                     r"\(-0.02, 0.02\) mm/m is \(-20, 20\) urad$"),
    ("EZZ", "EZZ,-6,6,µm", r"unknown unit 'µm'; allowed: um, mm, rad, urad, um/m, arcsec; EZZ "
                           r"is a translation \(positioning\): write it in um or mm; 'µm' is "
                           r"written 'um'$"),
])
def test_a_range_in_another_unit_is_refused_with_the_likely_unit(tmp_path, machine, symbol,
                                                                 new, message):
    text = _ranges(machine, _edit_row(symbol, new))
    f = _write(tmp_path, text, "ranges.csv")
    with pytest.raises(ValueError, match=rf"^range file '{re.escape(str(f))}', line "
                                         rf"{_line_of(text, symbol + ',')} \({symbol}\): "
                                         rf"{message}"):
        R.read_ranges(f, machine)


@pytest.mark.parametrize("symbol, new, message", [
    # 6 mm: the thermal growth of a huge machine, or 6 um labelled mm
    ("EXX", "EXX,-6,6,mm",
     r"the range \(-6, 6\) mm reaches 6 mm, more than the 1 mm a geometric error of a machine "
     r"tool reaches \(ISO 230-1 errors are 0.1-100 um; .*\); if it is in um, write -6, 6 um; "
     r"used as written$"),
    ("EAZ", "EAZ,-0.002,0.002,rad",
     r"the range \(-0.002, 0.002\) rad reaches 0.002 rad, more than the 0.001 rad an angular "
     r"error of a machine tool reaches \(1 mm/m, 206 arcsec; .*\); if it is in mrad, write "
     r"-2, 2 urad; if it is in deg, write -34.91, 34.91 urad; used as written$"),
    # smaller than anything measured: another unit, or meant to make the error negligible
    ("EYZ", "EYZ,-6e-6,6e-6,um",
     r"the range \(-6e-6, 6e-6\) um reaches only 6e-6 um, less than the 0.0001 um "
     r"\(1e-07 mm\) of an atom \(0.1 nm\): .*; if it is in m, write -6, 6 um; used as "
     r"written$"),
    ("EBB", "EBB,-1.5e-5,1.5e-5,urad",
     r"the range \(-1.5e-5, 1.5e-5\) urad reaches only 1.5e-5 urad, less than the "
     r"0.001 urad \(1e-09 rad\) below which no "
     r"angular error is measured .*; if it is in rad, write -1.5e-05, 1.5e-05 rad; used as "
     r"written$"),
])
def test_a_range_only_a_rare_machine_has_is_warned_and_used(tmp_path, machine, symbol, new,
                                                           message):
    text = _ranges(machine, _edit_row(symbol, new))
    f = _write(tmp_path, text, "ranges.csv")
    with pytest.warns(U.SuspectUnitWarning) as record:
        bounds = R.read_ranges(f, machine)
    assert len(record) == 1 and record[0].filename == __file__
    assert re.match(rf"^range file '{re.escape(str(f))}', line {_line_of(text, symbol + ',')} "
                    rf"\({symbol}\): {message}", str(record[0].message)), str(record[0].message)
    lo, hi, unit = new.split(",")[1:]
    j = machine.error_names.index(symbol)
    assert bounds[:, j] == pytest.approx(np.array([float(lo), float(hi)])
                                         * errors.UNIT_SCALE[unit], rel=1e-12)


def test_a_file_written_wholly_in_another_unit_warns_a_few_times_and_names_the_rest(
        tmp_path, machine):
    # every translation in mm instead of um: one warning per row for the first five, then one
    text = _ranges(machine, lambda rows: [r.replace("-5,5,um", "-5,5,mm") for r in rows])
    f = _write(tmp_path, text, "ranges.csv")
    n = sum(e.translational for e in machine.catalogue)
    with pytest.warns(U.SuspectUnitWarning) as record:
        R.read_ranges(f, machine)
    messages = [str(w.message) for w in record]
    assert len(messages) == R.MAX_UNIT_WARNINGS + 1 and n > R.MAX_UNIT_WARNINGS
    assert all("reaches 5 mm, more than the 1 mm" in m for m in messages[:-1])
    lines = [i for i, line in enumerate(text.splitlines(), 1) if ",mm" in line]
    assert messages[-1] == (f"range file {str(f)!r}: {n - R.MAX_UNIT_WARNINGS} more row(s) "
                            f"with a value that suggests another unit, at "
                            + ", ".join(f"line {i}" for i in lines[R.MAX_UNIT_WARNINGS:]))


def test_a_refused_file_warns_of_nothing(tmp_path, machine):
    text = _ranges(machine, lambda rows: [r.replace("EXC,-5,5,um", "EXC,-5,5,mm")
                                          .replace("EZZ,-5,5,um", "EZZ,-50,50,mm") for r in rows])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ValueError, match=r"\(EZZ\): the range \(-50, 50\) mm reaches 50 mm"):
            R.read_ranges(_write(tmp_path, text, "ranges.csv"), machine)


def test_the_limits_themselves_and_typical_ranges_are_read_quietly(tmp_path, machine):
    # 1 mm, 1e-3 rad: the warning limits, included; arcsec, um/m and rad of typical size
    values = {"EXX": "-1,1,mm", "EYY": "-0.006,0.006,mm", "EZZ": "-0.0001,0.0001,um",
              "EAX": "-15,15,arcsec", "EBX": "-0.001,0.001,rad", "ECX": "-1.5e-5,1.5e-5,rad",
              "EC0Y": "-20,20,um/m", "EA0Z": "-1e-3,1e-3,urad", "EX0C": "100,200,um"}
    text = _ranges(machine, lambda rows: [
        f"{r.split(',')[0]},{values[r.split(',')[0]]}" if r.split(",")[0] in values else r
        for r in rows])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        bounds = R.read_ranges(_write(tmp_path, text, "ranges.csv"), machine)
    col = machine.error_names.index
    assert bounds[1, col("EXX")] == 1.0 and bounds[1, col("EBX")] == 1e-3
    assert bounds[1, col("EAX")] == pytest.approx(15 * np.pi / 180 / 3600)


def test_edge_travels_of_real_axes_are_read_quietly(tmp_path):
    # the smallest slide read without a word (10 mm), a tilting axis of +-30 deg, a table of
    # one turn, a rotary span of exactly 15 deg, a pivot 0.2 mm off the origin (pivots are not
    # judged by size: one may lie at the origin)
    text = (AXES.replace("X,-400,400", "X,0,10").replace("B,-110,110,deg,0,0,150",
                                                        "B,-30,30,deg,0,0.2,0")
            .replace("Z,-250,250", "Z,-5,5"))
    travels, pivots = _read_axes_quietly(_write(tmp_path, text))
    assert travels["x"] == (0.0, 10.0) and travels["z"] == (-5.0, 5.0)
    assert np.allclose(travels["B"], np.deg2rad([-30, 30])) and pivots["B"][1] == 0.2
    text = AXES.replace("B,-110,110", "B,-7.5,7.5").replace("C,0,360", "C,-360,0")
    travels, _ = _read_axes_quietly(_write(tmp_path, text))
    assert np.allclose(travels["B"], np.deg2rad([-7.5, 7.5]))


def test_the_shipped_machine_files_are_read_quietly():
    folder = ROOT / "data" / "machines"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        travels, pivots = R.read_axis_table(folder / "swivel_head_axes.csv", TOPOLOGY)
        machine = ISO.iso_machine(TOPOLOGY, pivots=pivots, travels=travels,
                                tool_offsets=("tool_x", "tool_y", "tool_z"))
        bounds = R.read_ranges(folder / "swivel_head_ranges.csv", machine)
    assert bounds.shape == (2, machine.n_errors)


@pytest.mark.parametrize("edit, refused", [
    (("X,-400,400", "X,0,1"), False), (("X,-400,400", "X,0,0.999"), True),
    (("B,-110,110", "B,0,5"), False), (("B,-110,110", "B,0,4.99"), True),
], ids=["1 mm", "0.999 mm", "5 deg", "4.99 deg"])
def test_a_travel_on_the_refusal_limit_is_warned_and_below_it_refused(tmp_path, edit, refused):
    f = _write(tmp_path, AXES.replace(*edit))
    if refused:
        with pytest.raises(ValueError, match=rf"\({edit[1][0]}\): the travel .* less than the"):
            R.read_axis_table(f, TOPOLOGY)
    else:
        with pytest.warns(U.SuspectUnitWarning, match=rf"\({edit[1][0]}\): the travel"):
            R.read_axis_table(f, TOPOLOGY)


@pytest.mark.parametrize("row, refused", [
    ("EXX,-10,10,mm", False), ("EXX,-10000,10000,um", False), ("EXX,-10.01,10,mm", True),
    ("EAX,-0.01,0.01,rad", False), ("EAX,-10000,10000,urad", False),
    ("EAX,-0.0101,0.0101,rad", True),
], ids=lambda v: str(v))
def test_a_range_on_the_refusal_limit_is_warned_and_beyond_it_refused(tmp_path, machine, row,
                                                                      refused):
    f = _write(tmp_path, _ranges(machine, _edit_row(row[:3], row)), "ranges.csv")
    if refused:
        with pytest.raises(ValueError, match=rf"\({row[:3]}\): the range .* more than the "
                                             r"(10 mm|0\.01 rad) "):
            R.read_ranges(f, machine)
    else:
        with pytest.warns(U.SuspectUnitWarning, match=rf"\({row[:3]}\): the range .* more than "
                                                      r"the (1 mm|1000 um \(1 mm\)|0\.001 rad|"
                                                      r"1000 urad \(0\.001 rad\)) .*used as "
                                                      r"written$"):
            R.read_ranges(f, machine)


def test_the_plausibility_limits_know_every_unit_the_range_file_takes():
    taken = {**{u: (U.TRANSLATION_ERROR, 1.0) for u in U.TRANSLATION_ERROR.accepted},
             **{u: (U.ANGULAR_ERROR, 1.0) for u in U.ANGULAR_ERROR.accepted}}
    assert set(taken) == set(errors.UNIT_SCALE)
    for unit, (lim, _) in taken.items():     # the same size: mm and rad are the library's units
        assert lim.units[unit] == pytest.approx(errors.UNIT_SCALE[unit], rel=1e-15), unit
    assert U.LINEAR_TRAVEL.bound == R.MAX_LINEAR_MM and U.ROTARY_TRAVEL.bound == R.MAX_ROTARY_DEG
