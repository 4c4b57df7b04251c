"""The readers of a researcher's own machine (machines.chain, notebook 06): the topology string,
the axis table and the range file.  A message about a bad row names the file and the line an
editor shows.  Inputs no machine could need are refused at once, by their size. A travel too
large for any machine is refused, and a redundancy explanation is never blank.

The large inputs are built in tmp_path.  No test measures time, but each runs in well under a
second only while the checks are linear (the quadratic ones took minutes on these inputs)."""

import re

import numpy as np
import pytest

from mtaccuracy.machines import chain as C

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
    travels, pivots = C.read_axis_table(_write(tmp_path, AXES), TOPOLOGY)
    travels0, pivots0 = C.read_axis_table(_write(tmp_path, plain, "plain.csv"), TOPOLOGY)
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
        C.read_axis_table(f, TOPOLOGY)


# a note column whose quoted value spans four lines and holds a '#' and a blank line
NOTE = '"the X axis,\nover four lines # not a comment\n\nend"'
AXES_NOTE = AXES.replace("pivot_z_mm\n", "pivot_z_mm,note\n").replace(
    "X,-400,400,mm,,,\n", f"X,-400,400,mm,,,,{NOTE}\n")


def test_a_quoted_field_over_several_lines_shifts_the_lines_after_it(tmp_path):
    assert C.read_axis_table(_write(tmp_path, AXES_NOTE), TOPOLOGY)[0] == \
        C.read_axis_table(_write(tmp_path, AXES, "plain.csv"), TOPOLOGY)[0]
    text = AXES_NOTE.replace("Z,-250,250,mm", "Z,250,-250,mm")
    assert _line_of(text, "Z,") == 12
    with pytest.raises(ValueError, match=r"line 12 \(Z\): the travel must be finite"):
        C.read_axis_table(_write(tmp_path, text), TOPOLOGY)
    text = AXES_NOTE.replace("X,-400,400,mm", "X,400,-400,mm")      # the record of lines 5-8
    with pytest.raises(ValueError, match=r"lines 5-8 \(X\): the travel must be finite"):
        C.read_axis_table(_write(tmp_path, text), TOPOLOGY)


def test_unknown_repeated_and_missing_axes_point_at_their_lines(tmp_path):
    n = len(AXES.splitlines())
    with pytest.raises(ValueError, match=rf"line {n + 1} \(A\), line {n + 2} \(Q\): axis/axes "
                                         r"\['A', 'Q'\] not in the topology"):
        C.read_axis_table(_write(tmp_path, AXES + "A,0,90,deg,,,\nQ,0,1,mm,,,\n"), TOPOLOGY)
    with pytest.raises(ValueError, match=rf"lines 5 and {n + 1} \(X\): axis/axes \['X'\] given "
                                         "more than once"):
        C.read_axis_table(_write(tmp_path, AXES + "X,0,90,mm,,,\n"), TOPOLOGY)
    with pytest.raises(ValueError, match=r"\(header on line 4, rows on lines 5-10\): no row for "
                                         r"axis/axes \['C'\]"):
        C.read_axis_table(_write(tmp_path, AXES.replace("C,0,360,deg,,,\n", "")), TOPOLOGY)
    with pytest.raises(ValueError, match=r"line 4 \(the header\): lacks column\(s\) "
                                         r"\['pivot_z_mm'\]"):
        C.read_axis_table(_write(tmp_path, AXES.replace("pivot_z_mm", "pivot_z")), TOPOLOGY)


def test_a_malformed_csv_is_named_by_its_line(tmp_path):
    with pytest.raises(ValueError, match="line 9: a quoted field opens here and is never closed"):
        C.read_axis_table(_write(tmp_path, AXES.replace("Z,-250", 'Z,"-250')), TOPOLOGY)
    with pytest.raises(ValueError, match=r"line 9: 8 fields, but the header \(line 4\) names 7"):
        C.read_axis_table(_write(tmp_path, AXES.replace("Z,-250,250,mm,,,",
                                                        "Z,-250,250,mm,,,,7")), TOPOLOGY)
    f = tmp_path / "latin1.csv"
    f.write_bytes(AXES.replace("# the Y axis", "# the Y axis \xb1 1 mm").encode("latin-1"))
    with pytest.raises(ValueError, match="line 7: not UTF-8 text"):
        C.read_axis_table(f, TOPOLOGY)
    with pytest.raises(ValueError, match="has no header line"):
        C.read_axis_table(_write(tmp_path, "# nothing but a comment\n\n"), TOPOLOGY)


@pytest.fixture(scope="module")
def machine():
    return C.iso_machine(TOPOLOGY)


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
        C.read_ranges(f, machine)
    text = _ranges(machine, lambda rows: [r.replace("EXC,-5,5", "EXC,5,-5") for r in rows])
    with pytest.raises(ValueError, match=r"line 5 \(EXC\): the range must be finite with "
                                         "high > low"):
        C.read_ranges(_write(tmp_path, text, "ranges.csv"), machine)


def test_the_range_file_points_at_unknown_repeated_and_missing_errors(tmp_path, machine):
    text = _ranges(machine, lambda rows: [*rows, "EX0C,-1,1,um"])
    line = _line_of(text, "EX0C,")
    with pytest.raises(ValueError, match=rf"line {line} \(EX0C\): error\(s\) \['EX0C'\] not in "
                                         r"the catalogue .*EX0C \(removed: same effect as the "
                                         "zero of x"):
        C.read_ranges(_write(tmp_path, text, "ranges.csv"), machine)
    text = _ranges(machine, lambda rows: [*rows, rows[0]])
    assert text.splitlines()[4] == text.splitlines()[-1] == "EXC,-5,5,um"
    with pytest.raises(ValueError, match=rf"lines 5 and {len(text.splitlines())} \(EXC\): "
                                         r"error\(s\) \['EXC'\] given more than once"):
        C.read_ranges(_write(tmp_path, text, "ranges.csv"), machine)
    text = _ranges(machine, lambda rows: [r for r in rows if not r.startswith("EXX,")])
    last = len(text.splitlines())
    with pytest.raises(ValueError, match=rf"\(header on line 4, rows on lines 5-{last}\): no "
                                         r"range for error\(s\) \['EXX'\]"):
        C.read_ranges(_write(tmp_path, text, "ranges.csv"), machine)


# -- sizes ---------------------------------------------------------------------------------

def test_a_huge_topology_is_refused_at_once_with_an_excerpt():
    text = " ".join(["w", "b", *["X"] * 99_997, "t"])            # 100,000 tokens
    with pytest.raises(ValueError) as info:
        C.parse_topology(text)
    msg = str(info.value)
    assert f"is longer than {C.MAX_TOPOLOGY_CHARS} characters" in msg
    assert repr(text[:60]) + "... (199999 characters)" in msg and len(msg) < 600
    with pytest.raises(ValueError, match=rf"has 100 tokens, more than {C.MAX_TOPOLOGY_TOKENS}"):
        C.parse_topology("w" + "X" * 98 + "t")


def test_the_topology_cap_is_on_the_characters_and_messages_quote_an_excerpt():
    padded = "w C b X Y Z B t".ljust(C.MAX_TOPOLOGY_CHARS)
    assert C.parse_topology(padded).axes == ("C", "X", "Y", "Z", "B")
    with pytest.raises(ValueError, match="longer than 200 characters"):
        C.parse_topology(padded + " ")
    text = "w b X X" + " " * 150 + "t"
    with pytest.raises(ValueError, match=r"axis \['X'\] appears more than once in topology "
                                         r"'w b X X {53}'\.\.\. \(158 characters\)$"):
        C.parse_topology(text)


def test_topology_parsing_is_linear(monkeypatch):
    # with the caps lifted, the repeated-axis check of a 100,000-token string (quadratic: about
    # 40 s on the project machine; linear: hundredths of a second)
    monkeypatch.setattr(C, "MAX_TOPOLOGY_CHARS", 10**9)
    monkeypatch.setattr(C, "MAX_TOPOLOGY_TOKENS", 10**9)
    text = " ".join(["w", "b", *["X"] * 99_997, "t"])
    with pytest.raises(ValueError, match=r"axis \['X'\] appears more than once .*\.\.\. "
                                         r"\(199999 characters\)$"):
        C.parse_topology(text)


def test_files_larger_than_any_machine_needs_are_refused_at_once(tmp_path, machine):
    header = ",".join(C.AXIS_TABLE_COLUMNS) + "\n"
    f = _write(tmp_path, header + "X,-400,400,mm,,,\n" * 200_000)          # 3.4 MB
    with pytest.raises(ValueError, match=rf"^axis table '{re.escape(str(f))}' is 3400052 bytes, "
                                         rf"more than the {C.MAX_TABLE_BYTES} bytes allowed"):
        C.read_axis_table(f, TOPOLOGY)
    f = _write(tmp_path, header + "X,0,1,mm,,,\n" * 100_000)               # 1.2 MB
    with pytest.raises(ValueError, match="has 100001 lines, more than the 10000 allowed"):
        C.read_axis_table(f, TOPOLOGY)
    f = _write(tmp_path, header + "X,0,1,mm,,,\n" * 1500)
    with pytest.raises(ValueError, match=r"line 1002: more than 1000 data rows; it should hold "
                                         "one row per axis"):
        C.read_axis_table(f, TOPOLOGY)
    f = _write(tmp_path, "symbol,low,high,unit\n" + "EXX,-5,5,um\n" * 200_000, "ranges.csv")
    with pytest.raises(ValueError, match=r"^range file .* is 2400021 bytes, more than the"):
        C.read_ranges(f, machine)
    f = _write(tmp_path, "symbol,low,high,unit\n" + "EXX,-5,5,um\n" * 5000, "ranges.csv")
    with pytest.raises(ValueError, match="line 1002: more than 1000 data rows; it should hold "
                                         "one row per error"):
        C.read_ranges(f, machine)


def test_a_message_about_many_repeats_stays_short(tmp_path):
    f = _write(tmp_path, ",".join(C.AXIS_TABLE_COLUMNS) + "\n" + "X,0,1,mm,,,\n" * 900)
    with pytest.raises(ValueError) as info:
        C.read_axis_table(f, TOPOLOGY)
    msg = str(info.value)
    assert msg.endswith(r"lines 2, 3, 4, 5, 6, ... (900 lines) (X): axis/axes ['X'] given more "
                        "than once") and len(msg) < 150 + len(str(f))


def test_the_checks_of_the_readers_are_linear(tmp_path, machine, monkeypatch):
    # with the caps lifted, 20,000 repeated rows (list.count per row: seconds; now linear)
    monkeypatch.setattr(C, "MAX_TABLE_ROWS", 10**9)
    monkeypatch.setattr(C, "MAX_TABLE_BYTES", 10**9)
    f = _write(tmp_path, "symbol,low,high,unit\n" + "EXX,-5,5,um\n" * 20_000, "ranges.csv")
    with pytest.raises(ValueError, match=r"lines 2, 3, 4, 5, 6, ... \(20000 lines\) \(EXX\)"):
        C.read_ranges(f, machine)
    f = _write(tmp_path, ",".join(C.AXIS_TABLE_COLUMNS) + "\n" + "Y,0,1,mm,,,\n" * 20_000)
    with pytest.raises(ValueError, match=r"\(20000 lines\) \(Y\): axis/axes \['Y'\] given"):
        C.read_axis_table(f, TOPOLOGY)


# -- travels too large for any machine, and the explanations of redundant errors ------------

@pytest.mark.parametrize("old, new, message", [
    ("X,-400,400", "X,-1e300,1e300", r"the travel \(-1e\+300, 1e\+300\) mm goes beyond "
                                     r"\+-100000 mm \(no machine axis travels more than 100 m\)"),
    ("X,-400,400", "X,-400,100001", r"the travel \(-400, 100001\) mm goes beyond \+-100000 mm"),
    ("C,0,360", "C,0,3601", r"the travel \(0, 3601\) deg goes beyond \+-3600 deg"),
    ("B,-110,110,deg,0,0,150", "B,-110,110,deg,0,0,1e300",
     r"the pivot \[0.0, 0.0, 1e\+300\] mm lies beyond \+-100000 mm"),
])
def test_a_travel_or_pivot_no_machine_has_is_refused(tmp_path, old, new, message):
    text = AXES.replace(old, new)
    with pytest.raises(ValueError, match=rf"line {_line_of(text, new[:2])} \({new[0]}\): "
                                         + message):
        C.read_axis_table(_write(tmp_path, text), TOPOLOGY)


def test_the_bounds_themselves_are_accepted(tmp_path):
    text = AXES.replace("X,-400,400", "X,-1e5,1e5").replace("C,0,360", "C,-3600,3600")
    travels, _ = C.read_axis_table(_write(tmp_path, text), TOPOLOGY)
    assert travels["x"] == (-1e5, 1e5) and np.allclose(travels["C"], [-20 * np.pi, 20 * np.pi])


_EFFECT = re.compile(r"the zero of \w+|the workpiece set-up (along|about) [xyz]"
                     r"|the tool offset along [xyz]|E\w+")


@pytest.mark.parametrize("travels", [{}, {"x": (-1e300, 1e300)}, {"x": (-1e155, 1e155)},
                                     {"x": (-1e300, 1e300), "y": (-1e300, 1e300)}], ids=str)
def test_an_explanation_is_never_blank(travels):
    # a travel of 1e300 mm: the squares in the norm of a Jacobian column overflowed, the unit
    # column came out all zeros and was "explained" by no term: "same effect as "
    removed = C.iso_machine(TOPOLOGY, travels=travels).removed
    assert removed
    for symbol, reason in removed:
        assert reason.strip() and not reason.rstrip().endswith("as"), (symbol, reason)
        if reason.startswith("same effect as "):
            terms = reason.removeprefix("same effect as ").split(" + ")
            assert all(_EFFECT.fullmatch(t) for t in terms), (symbol, reason)


def test_a_combination_the_fit_cannot_name_is_said_in_words():
    assert C._same_effect(["the zero of x", "EA0C"]) == "same effect as the zero of x + EA0C"
    words = C._same_effect([])
    assert not words.rstrip().endswith("as") and "none of which could be named" in words


def test_a_travel_beyond_floating_point_is_refused_by_the_rank_test():
    with pytest.raises(ValueError, match=r"the travel \(-inf, inf\) of x is not finite"):
        C.iso_machine(TOPOLOGY, travels={"x": (-np.inf, np.inf)})
    with pytest.raises(ValueError, match=r"travel \(-1e\+308, 1e\+308\) of x is not finite "
                                         r"\(or its width overflows\)"):
        C.iso_machine(TOPOLOGY, travels={"x": (-1e308, 1e308)})
