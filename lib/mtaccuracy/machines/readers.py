"""A reader's machine from files: the axis table and the error ranges, checked before any work.

:func:`read_axis_table` reads the travels and the rotary pivots of a topology's axes,
:func:`read_ranges` the uniform ranges of a machine's errors, each from a small CSV file that
is refused, naming the file and the line, before any work when it is malformed or a value is
implausible for its unit (:mod:`.units`); what only a rare machine has is used as written,
with a :class:`.units.SuspectUnitWarning`.  :func:`catalogue_table` shows a machine's errors
with their ranges in the units a reader writes (notebook 06).
"""

from __future__ import annotations

import re
import warnings
from dataclasses import dataclass

import numpy as np
import pandas as pd

from .. import csvlines, validate
from .. import errors as _errors
from . import units as _units
from .chain import COMPONENTS, ChainMachine
from .topology import LINEAR, _excerpt, _listed, parse_topology

AXIS_TABLE_COLUMNS = ("axis", "low", "high", "unit", "pivot_x_mm", "pivot_y_mm", "pivot_z_mm")
RANGE_COLUMNS = ("symbol", "low", "high", "unit")
#: Optional columns of the axis table: the Abbe reference of a linear axis (mm).
AXIS_TABLE_OPTIONAL = ("reference_mm",)
#: At most this many problems are listed in the one error a refused file raises, then how many
#: more (every row of a file of :data:`MAX_TABLE_ROWS` rows may be wrong).
MAX_PROBLEMS = 50
#: Size caps of the input files, checked before (bytes) and while (rows) they are parsed.  An
#: axis table has one row per axis (at most six); a range file one per error of the catalogue
#: (51 for six axes with ISO 230-1/230-7: 36 error motions, 3 squareness errors, 12 location
#: errors).  1000 data rows leave a margin of twenty times that (a range file may hold up to
#: twice its machine's catalogue when that is larger); 2 MiB, 2000 rows of 1000 characters,
#: leaves ample room for comments.  A larger file is not a machine's description (a wrong
#: file, a log, a data dump) and is refused at once, naming the file and the limit.
MAX_TABLE_BYTES = 2 * 1024 * 1024
MAX_TABLE_ROWS = 1000
#: Bounds of a travel and of a pivot in the axis table.  The longest axes of machine tools
#: (gantry mills for ship hulls and aircraft spars) travel a few tens of metres, so no
#: coordinate of a linear axis or a pivot exceeds 100 m (1e5 mm).  A rotary axis repeats every
#: turn; ten turns either way (3600 deg) leave room for a multi-turn count.  Values far beyond
#: these are not a machine: from about 1e154 mm the squares in the rank test of
#: :func:`.iso.redundant_location_errors` overflow.
MAX_LINEAR_MM = 1e5
MAX_ROTARY_DEG = 3600.0
#: At most this many :class:`.units.SuspectUnitWarning` per file, one per row, then one naming
#: the lines of the rest (a file written wholly in another unit would otherwise give one per
#: row).
MAX_UNIT_WARNINGS = 5


@dataclass(frozen=True)
class _Row:
    """One data record of a CSV file: its first and last physical line (1-based, as an
    editor numbers them; a quoted field may span lines) and its values by column."""

    first: int
    last: int
    values: dict

    @property
    def where(self) -> str:
        return f"line {self.first}" if self.first == self.last else \
            f"lines {self.first}-{self.last}"


@dataclass(frozen=True)
class _Table:
    """A checked CSV file: its header line, its data records and where they stand."""

    header_line: int
    rows: list
    problems: list = None   # row-level problems found while parsing (messages)

    def span(self) -> str:
        """Where the header and the rows stand, for a message about a missing entry."""
        if not self.rows:
            return f"header on line {self.header_line}, no data rows"
        return (f"header on line {self.header_line}, rows on lines {self.rows[0].first}-"
                f"{self.rows[-1].last}")


def _read_csv(path, columns, what, max_rows=None, optional=()) -> _Table:
    """Read a small CSV file with the physical line of every record, checked.

    ``#`` starts a comment (outside quotes) and lines left blank are skipped, like
    ``pandas.read_csv(comment="#", skip_blank_lines=True, skipinitialspace=True)``; records
    whose fields are all empty are skipped too.  Values are stripped strings; a short record
    is padded with empty strings.  The file must be UTF-8 (a byte-order mark is allowed).
    Refused before parsing: more than :data:`MAX_TABLE_BYTES` bytes or ``10 * max_rows``
    lines; while parsing: more than ``max_rows`` data rows (default
    :data:`MAX_TABLE_ROWS`).  The file is read through :func:`mtaccuracy.validate.file_bytes`
    (a directory, FIFO, device or a link to one is refused before a byte is read).  A record
    with more fields than the header is a row-level problem, collected in ``problems`` (the
    readers report every problem of a file at once); ``optional`` columns may be absent
    (their values are then empty strings)."""
    path = str(path)
    max_rows = MAX_TABLE_ROWS if max_rows is None else max_rows
    try:        # a directory, FIFO, device or a link to one: refused before a byte is read
        raw = validate.file_bytes(path, max_bytes=MAX_TABLE_BYTES)
    except validate.FileRefused as exc:
        if exc.reason == "missing":
            raise FileNotFoundError(f"{what} {path!r} not found") from None
        if exc.size is not None:
            raise ValueError(f"{what} {path!r} is {exc.size} bytes, more than the "
                             f"{MAX_TABLE_BYTES} bytes allowed; it should hold a few dozen rows "
                             f"(is it the right file?)") from None
        raise ValueError(f"{what} {path!r}: {exc}") from None
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ValueError(f"{what} {path!r}, line {csvlines.bad_byte_line(raw, exc)}: not UTF-8 "
                         f"text ({exc.reason})") from None
    flat = text.replace("\r\n", "\n").replace("\r", "\n")  # as an editor counts lines
    n_lines = flat.count("\n") + (not flat.endswith("\n"))
    if n_lines > 10 * max_rows:
        raise ValueError(f"{what} {path!r} has {n_lines} lines, more than the {10 * max_rows} "
                         f"allowed ({max_rows} data rows, with comments); it should hold a few "
                         f"dozen rows (is it the right file?)")
    header, index, rows, problems = None, {}, [], []
    found = csvlines.records(text, comment="#")
    while True:
        try:
            first, last, fields = next(found)
        except StopIteration:
            break
        except csvlines.CSVLineError as exc:
            raise ValueError(f"{what} {path!r}, line {exc.line}: {exc.reason}") from None
        if header is None:
            header = [h.strip() for h in fields]
            header_line = first
            where = f"{what} {path!r}, line {first} (the header)"
            twice = sorted(c for c in (*columns, *optional) if header.count(c) > 1)
            if twice:
                raise ValueError(f"{where}: column(s) {twice} given more than once")
            missing = [c for c in columns if c not in header]
            if missing:
                raise ValueError(f"{where}: lacks column(s) {missing}; it needs "
                                 f"{', '.join(columns)}")
            index = {c: header.index(c) for c in (*columns, *optional) if c in header}
            continue
        if not "".join(fields).strip():
            continue
        if len(rows) == max_rows:
            raise ValueError(f"{what} {path!r}, line {first}: more than {max_rows} data rows; "
                             f"it should hold one row per "
                             f"{'axis' if what == 'axis table' else 'error'} (is it the right "
                             f"file?)")
        row = _Row(first, last, {c: fields[i].strip() if i < len(fields) else ""
                                 for c, i in index.items()})
        if len(fields) > len(header) and any(f.strip() for f in fields[len(header):]):
            problems.append(f"{what} {path!r}, {row.where}: {len(fields)} fields, but the "
                            f"header (line {header_line}) names {len(header)} columns")
            continue
        rows.append(row)
    if header is None:
        raise ValueError(f"{what} {path!r} has no header line (it is empty or all comments); "
                         f"it needs the columns {', '.join(columns)}")
    for row in rows:
        for c in optional:
            row.values.setdefault(c, "")
    return _Table(header_line, rows, problems)


def _at(groups, n: int = 5) -> str:
    """Where entries stand, from ``(name, [lines])`` pairs: ``line 7 (A)``, ``lines 3 and 8
    (X)``, ... at most ``n`` names and ``n`` lines each, then how many more."""
    parts = []
    for name, lines in groups[:n]:
        name = "empty" if not name else name if len(name) <= 20 else name[:20] + "..."
        if len(lines) == 1:
            parts.append(f"line {lines[0]} ({name})")
        elif len(lines) == 2:
            parts.append(f"lines {lines[0]} and {lines[1]} ({name})")
        else:
            more = f", ... ({len(lines)} lines)" if len(lines) > n else ""
            parts.append(f"lines {', '.join(map(str, lines[:n]))}{more} ({name})")
    if len(groups) > n:
        parts.append(f"... ({len(groups) - n} more)")
    return ", ".join(parts)


def _check_entries(table: _Table, column: str, wanted):
    """How the entries of ``column`` fail to name each of ``wanted`` exactly once: the
    unknown entries (in file order) and the repeated ones (sorted), each as ``(name, [lines
    where it stands])``, and the missing names (in ``wanted``'s order).  Linear in the rows
    (one dictionary of lines per name; no ``list.count`` per row)."""
    lines: dict[str, list[int]] = {}
    for row in table.rows:
        lines.setdefault(row.values[column], []).append(row.first)
    allowed = set(wanted)
    unknown = [(s, ls) for s, ls in lines.items() if s not in allowed]
    dup = sorted((s, ls) for s, ls in lines.items() if len(ls) > 1 and s in allowed)
    missing = [s for s in wanted if s not in lines]
    return unknown, dup, missing


def _in_unit(lim: _units.Limits, v, unit: str) -> str:
    """``; `` and what a row written in a unit the file does not take says: another spelling
    of an accepted unit, or its numbers in an accepted unit (:func:`.units.in_unit`); or
    ``""``."""
    canon = _units.canonical(unit)
    if canon in lim.accepted:
        return f"; {unit!r} is written {canon!r}"
    try:
        lo, hi = float(v["low"]), float(v["high"])
    except ValueError:
        return ""
    if not (np.isfinite(lo) and np.isfinite(hi) and hi > lo):
        return ""
    text = _units.in_unit(lim, lo, hi, unit=unit, written=(_shown(v["low"]), _shown(v["high"])))
    return f"; {text}" if text else ""


def _warn_rows(where: str, found: list) -> None:
    """Emit the :class:`.units.SuspectUnitWarning` of ``found`` (``(row, message)`` pairs): one
    per row up to :data:`MAX_UNIT_WARNINGS`, then one naming the lines of the rest.  Attributed
    to the reader's caller (a notebook cell shows them under it)."""
    for _, message in found[:MAX_UNIT_WARNINGS]:
        warnings.warn(message, _units.SuspectUnitWarning, stacklevel=3)
    rest = found[MAX_UNIT_WARNINGS:]
    if rest:
        warnings.warn(f"{where}: {len(rest)} more row(s) with a value that suggests another "
                      f"unit, at {', '.join(r.where for r, _ in rest[:20])}"
                      + (", ..." if len(rest) > 20 else ""),
                      _units.SuspectUnitWarning, stacklevel=3)


def _refuse(where: str, problems: list) -> None:
    """Raise one ValueError listing every ``(line, message)`` problem of a file (sorted by
    line, a problem without a line last), or nothing when there is none.  One problem is its
    message alone; several are listed one per line, at most :data:`MAX_PROBLEMS`."""
    if not problems:
        return
    msgs = [m for _, m in sorted(problems, key=lambda p: p[0])]
    if len(msgs) == 1:
        raise ValueError(msgs[0])
    more = (f"\n  ... and {len(msgs) - MAX_PROBLEMS} more" if len(msgs) > MAX_PROBLEMS else "")
    raise ValueError(f"{where}: {len(msgs)} problems, each on its line:\n  "
                     + "\n  ".join(msgs[:MAX_PROBLEMS]) + more)


def _entry_problems(table: _Table, column: str, wanted, where: str, *, kind: str,
                    unknown_why) -> tuple[list, set]:
    """The problems of the entries of ``column`` (unknown, repeated; each at its first line)
    and the entries whose rows are not checked further (unknown ones)."""
    unknown, dup, _ = _check_entries(table, column, wanted)
    out = []
    if unknown:
        shown = [s for s, _ in unknown]
        out.append((unknown[0][1][0], f"{where}, {_at(unknown)}: {kind} {_listed(shown)} "
                                      f"{unknown_why(shown)}"))
    if dup:
        out.append((dup[0][1][0], f"{where}, {_at(dup)}: {kind} "
                                  f"{_listed([s for s, _ in dup])} given more than once"))
    return out, {s for s, _ in unknown}


def _numbers(v, line: str, what: str):
    """``(low, high)`` of a row as floats, or a problem: not numbers, not finite with high >
    low (quoted as written)."""
    try:
        lo, hi = float(v["low"]), float(v["high"])
    except ValueError:
        return None, (f"{line}: low and high must be numbers, got {_excerpt(v['low'], 20)}, "
                      f"{_excerpt(v['high'], 20)}")
    if not (np.isfinite(lo) and np.isfinite(hi) and hi > lo):
        return None, (f"{line}: the {what} must be finite with high > low, got "
                      f"({_shown(v['low'])}, {_shown(v['high'])})")
    return (lo, hi), None


def _shown(text: str) -> str:
    """A number as the file writes it (cut to 30 characters), for a message."""
    return text if len(text) <= 30 else text[:30] + "..."


def _travel(v, a: str, line: str):
    """The travel of one row (mm, rad), a suspect-unit message or None, and the problem (or
    None) of its unit and travel."""
    unit = v["unit"]
    want = "mm" if a in LINEAR else "deg"
    lim = _units.LINEAR_TRAVEL if a in LINEAR else _units.ROTARY_TRAVEL
    written = (_shown(v["low"]), _shown(v["high"]))
    if unit != want:
        kind = "linear" if a in LINEAR else "rotary"
        return None, None, (f"{line}: unit must be {want!r} for a {kind} axis, got "
                            f"{_excerpt(unit, 20)}" + _in_unit(lim, v, unit))
    travel, bad = _numbers(v, line, "travel")
    if bad:
        return None, None, bad
    lo, hi = travel
    bound = MAX_LINEAR_MM if a in LINEAR else MAX_ROTARY_DEG
    if max(-lo, hi) > bound:
        why = ("no machine axis travels more than 100 m" if a in LINEAR
               else "a rotary axis repeats every turn; ten turns either way at most")
        hint = _units.suggest(lim, lo, hi, unit=unit, sure=False)
        return None, None, (f"{line}: the travel ({written[0]}, {written[1]}) {unit} goes "
                            f"beyond +-{bound:g} {unit} ({why})" + (f"; {hint}" if hint else ""))
    found = _units.check(lim, lo, hi, unit=unit, written=written)
    if found is not None and found.refuse:
        return None, None, f"{line}: {found.message}"
    scale = 1.0 if a in LINEAR else np.pi / 180.0
    return (lo * scale, hi * scale), (f"{line}: {found.message}" if found else None), None


def _pivot(v, a: str, line: str):
    """The pivot of one row ((3,) mm or None) and its problem (or None)."""
    piv = [v["pivot_x_mm"], v["pivot_y_mm"], v["pivot_z_mm"]]
    given = [p != "" for p in piv]
    if a in LINEAR:
        return None, (f"{line}: a linear axis has no pivot; leave pivot_*_mm empty"
                      if any(given) else None)
    if any(given) and not all(given):
        return None, f"{line}: give all three pivot_*_mm or none"
    if not all(given):
        return None, None
    try:
        point = np.array([float(p) for p in piv])
    except ValueError:
        return None, (f"{line}: pivot_*_mm must be numbers, got "
                      f"{[_excerpt(p, 20) for p in piv]}")
    if not np.all(np.isfinite(point)):
        return None, f"{line}: pivot_*_mm must be finite, got {[_shown(p) for p in piv]}"
    if np.abs(point).max() > MAX_LINEAR_MM:
        return None, (f"{line}: the pivot [{', '.join(_shown(p) for p in piv)}] mm lies beyond "
                      f"+-{MAX_LINEAR_MM:g} mm (no machine is larger than 100 m)")
    return point, None


def _reference(v, a: str, line: str, travel):
    """The Abbe reference of one row (mm; 0 when empty) and its problem (or None)."""
    text = v["reference_mm"]
    if a not in LINEAR:
        return None, (f"{line}: a rotary axis has no reference_mm (its errors are referred to "
                      f"the reference point the linear axes' references give); leave it empty"
                      if text else None)
    if not text:
        return 0.0, None
    try:
        r = float(text)
    except ValueError:
        return None, f"{line}: reference_mm must be a number, got {_excerpt(text, 20)}"
    if not np.isfinite(r):
        return None, f"{line}: reference_mm must be finite, got {_shown(text)}"
    if travel is not None and not travel[0] <= r <= travel[1]:
        return None, (f"{line}: the reference {_shown(text)} mm lies outside the travel "
                      f"({_shown(v['low'])}, {_shown(v['high'])}) mm; it is a position on the "
                      f"travel (the Abbe reference: data/machines/README.md)")
    return r, None


def read_axis_table(path, topology: str, *, with_references: bool = False):
    """The travels, rotary pivots (and Abbe references) of a topology's axes from a CSV file.

    Parameters
    ----------
    path : str or Path
        A CSV with the columns ``axis, low, high, unit, pivot_x_mm, pivot_y_mm, pivot_z_mm``
        (:data:`AXIS_TABLE_COLUMNS`) and optionally ``reference_mm``; others are ignored,
        ``#`` starts a comment, blank lines are skipped: one row per axis of the topology;
        the travel in ``mm`` (linear, within +-:data:`MAX_LINEAR_MM`) or ``deg`` (rotary,
        within +-:data:`MAX_ROTARY_DEG`); for a rotary axis a point its axis line passes
        through, mm, in the frame of the body it rides on (empty: the origin; must be empty
        for a linear axis); for a linear axis its Abbe reference, the position on its travel
        to which its error motions are referred (empty: 0; must be empty for a rotary axis;
        :class:`.chain.ChainMachine`'s ``references``).  At most :data:`MAX_TABLE_BYTES`
        bytes and :data:`MAX_TABLE_ROWS` rows, a regular file
        (:func:`mtaccuracy.validate.file_bytes`).
    topology : str
        The machine's topology (:func:`.topology.parse_topology`).
    with_references : bool
        Also return the references.  When False (the two-value form) a non-zero
        ``reference_mm`` is refused rather than dropped.

    Returns
    -------
    travels : dict
        Pose name (``x y z``, ``A B C``) -> (low, high) in mm or rad.
    pivots : dict
        Rotary axis letter -> (3,) point, mm.
    references : dict
        With ``with_references``: linear axis letter -> reference, mm (0 when not given).

    Raises
    ------
    ValueError
        One error listing every row-level problem of the file, each naming the file and the
        line (1-based, as an editor numbers them): an extra or repeated axis (both lines), a
        wrong unit (with the travel converted, when the unit is one of another name), a
        travel that is not finite with low < high or beyond the bounds, a travel no machine
        tool has in the unit written (a linear span below 1 mm, a rotary span below 5 deg, or
        below 15 deg with ends that read as radians: :func:`.units.check`, naming the likely
        unit and the numbers to write), a pivot on a linear axis, half a pivot, a pivot
        beyond the bound, a reference on a rotary axis or outside the travel, a record with
        more fields than the header, and a missing axis; numbers are quoted as written.
        Alone: a missing column (the header's line), a file too large or with too many rows,
        a malformed CSV, a path that is not a regular file (a directory, FIFO, device).
    FileNotFoundError
        When the file does not exist.

    Warns
    -----
    SuspectUnitWarning
        Once per row (at most :data:`MAX_UNIT_WARNINGS`, then one for the rest) whose travel
        only a rare machine has in the unit written (a linear span of 1-10 mm, a rotary span
        of 5-15 deg), naming the file, the line, the limit and the likely unit; the travel is
        used as written.  Emitted after the whole file is checked (a refused file warns of
        nothing).
    """
    topo = parse_topology(topology)
    table = _read_csv(path, AXIS_TABLE_COLUMNS, "axis table", optional=AXIS_TABLE_OPTIONAL)
    where = f"axis table {str(path)!r}"
    problems, skip = _entry_problems(
        table, "axis", topo.axes, where, kind="axis/axes",
        unknown_why=lambda _: f"not in the topology {topology!r} (its axes: "
                              f"{', '.join(topo.axes)})")
    problems += [(_first_line(m), m) for m in table.problems]
    travels, pivots, references, suspect = {}, {}, {}, []
    for row in table.rows:
        v = row.values
        a = v["axis"]
        if a in skip:
            continue
        line = f"{where}, {row.where} ({a})"
        travel, warn, bad = _travel(v, a, line)
        point, bad_pivot = _pivot(v, a, line)
        ref, bad_ref = _reference(v, a, line, travel)
        problems += [(row.first, m) for m in (bad, bad_pivot, bad_ref) if m]
        if warn:
            suspect.append((row, warn))
        if travel is not None:
            travels[a.lower() if a in LINEAR else a] = travel
        if point is not None:
            pivots[a] = point
        if ref is not None and a in LINEAR:
            references[a] = ref
    missing = _check_entries(table, "axis", topo.axes)[2]
    if missing:
        problems.append((float("inf"), f"{where} ({table.span()}): no row for axis/axes "
                                       f"{missing} of the topology {topology!r}"))
    _refuse(where, problems)
    _warn_rows(where, suspect)
    if with_references:
        return travels, pivots, references
    given = [f"{a} {r:g} mm" for a, r in references.items() if r != 0.0]
    if given:
        raise ValueError(f"{where}: reference_mm is given ({', '.join(given)}) but this call "
                         f"would drop it; read the table with with_references=True and pass "
                         f"the references to the machine (references=...)")
    return travels, pivots


def _first_line(message: str) -> int:
    """The first line a reader's message names (``..., line 7 ...`` or ``lines 7-9``)."""
    found = re.search(r", lines? (\d+)", message)
    return int(found.group(1)) if found else 0


def _range(v, spec, line: str):
    """The unit finding (a suspect-unit :class:`.units.Finding` or None) and the problem (or
    None) of one row of a range file, for the error ``spec``."""
    unit = v["unit"]
    s = spec.symbol
    what = "a translation" if spec.translational else "an angle"
    lim = _units.TRANSLATION_ERROR if spec.translational else _units.ANGULAR_ERROR
    takes = f"{', '.join(lim.accepted[:-1])} or {lim.accepted[-1]}"
    if unit not in _errors.UNIT_SCALE:
        return None, (f"{line}: unknown unit {_excerpt(unit, 20)}; allowed: "
                      f"{', '.join(_errors.UNIT_SCALE)}; {s} is {what} ({spec.kind}): write it "
                      f"in {takes}" + _in_unit(lim, v, unit))
    if spec.translational != (unit in _units.TRANSLATION_ERROR.accepted):
        length = "" if spec.translational else \
            "; a deviation over a length is an angle: divide by the length, um/m"
        return None, (f"{line}: {s} is {what}, unit {unit!r} is not ({spec.kind}: write it in "
                      f"{takes}){length}")
    values, bad = _numbers(v, line, "range")
    if bad:
        return None, bad
    found = _units.check(lim, *values, unit=unit, written=(_shown(v["low"]), _shown(v["high"])))
    if found is not None and found.refuse:
        return None, f"{line}: {found.message}"
    return found, None


def read_ranges(path, machine: ChainMachine) -> np.ndarray:
    """Uniform error ranges of a machine from a CSV file, checked against its catalogue.

    Parameters
    ----------
    path : str or Path
        A CSV with the columns ``symbol, low, high, unit`` (:data:`RANGE_COLUMNS`; others are
        ignored, ``#`` starts a comment, blank lines are skipped): one row per error of the
        catalogue; units ``um``, ``mm`` for translations and ``urad``, ``rad``, ``arcsec``,
        ``um/m`` for angles.  At most :data:`MAX_TABLE_BYTES` bytes and
        :data:`MAX_TABLE_ROWS` rows (or twice the catalogue, when that is more).
    machine : ChainMachine
        Whose catalogue the rows must match.

    Returns
    -------
    (2, n_errors) array
        Low and high bounds in mm and rad, columns in catalogue order.

    Raises
    ------
    ValueError
        One error listing every row-level problem of the file, each naming the file and the
        line (1-based, as an editor numbers them) of the offending row: an error the catalogue
        lacks (with why, when it is a redundant location
        error the catalogue removed), a repeated error (both lines), an unknown unit (with
        the units of the error's kind, and the range converted when the unit is a known one
        the file does not take: ``deg``, ``mrad``, ``mm/m``, ``nm``, ``m``, ``µm``) or one of
        the wrong kind (naming the units of its kind), a range that is not finite with low <
        high, a range no machine tool has (a translation beyond 10 mm, an angle beyond 0.01
        rad: :func:`.units.check`, naming the likely unit and the numbers to write), a record
        with more fields than the header, and a missing error; numbers are quoted as
        written.  Alone: a missing column (the header's line), a file too large or with too
        many rows, a malformed CSV, a path that is not a regular file (a directory, FIFO,
        device: :func:`mtaccuracy.validate.file_bytes`).
    FileNotFoundError
        When the file does not exist.

    Warns
    -----
    SuspectUnitWarning
        Once per row (at most :data:`MAX_UNIT_WARNINGS`, then one for the rest) whose range
        only a rare machine has in the unit written (a translation beyond 1 mm or below 0.1
        nm, an angle beyond 1e-3 rad or below 1e-9 rad), naming the file, the line, the
        limit and the likely unit; the range is used as written.  Emitted after the whole
        file is checked.
    """
    names = machine.error_names
    table = _read_csv(path, RANGE_COLUMNS, "range file",
                      max_rows=max(MAX_TABLE_ROWS, 2 * len(names)))
    where = f"range file {str(path)!r}"
    column = {s: j for j, s in enumerate(names)}
    removed = dict(getattr(machine, "removed", []))

    def unknown_why(shown):
        why = [f"{s} (removed: {removed[s]})" for s in shown[:10] if s in removed]
        return (f"not in the catalogue of {machine.name}" + (f"; {'; '.join(why)}" if why else "")
                + f"; its errors: {', '.join(names)}")

    problems, skip = _entry_problems(table, "symbol", names, where, kind="error(s)",
                                     unknown_why=unknown_why)
    problems += [(_first_line(m), m) for m in table.problems]
    bounds, suspect = np.full((2, len(names)), np.nan), []
    for row in table.rows:
        v = row.values
        s = v["symbol"]
        if s in skip:
            continue
        line = f"{where}, {row.where} ({s})"
        found, bad = _range(v, machine.catalogue[column[s]], line)
        if bad:
            problems.append((row.first, bad))
            continue
        if found is not None:
            suspect.append((row, f"{line}: {found.message}"))
        scale = _errors.UNIT_SCALE[v["unit"]]
        bounds[:, column[s]] = float(v["low"]) * scale, float(v["high"]) * scale
    missing = _check_entries(table, "symbol", names)[2]
    if missing:
        problems.append((float("inf"), f"{where} ({table.span()}): no range for error(s) "
                                       f"{missing}"))
    _refuse(where, problems)
    _warn_rows(where, suspect)
    return bounds


_SLOT_TEXT = {"motion": "error motion (after the motion)", "pre": "location (before the motion)",
              "post": "location (after the motion)", "tilt": "squareness (tilts the direction)"}


def catalogue_table(machine: ChainMachine, bounds=None):
    """A machine's errors as a table (a pandas DataFrame), with their ranges when given.

    Symbol, kind, the axis it belongs to, where it enters the chain and its component (``X Y Z``
    translations, ``A B C`` rotations), with the ``bounds`` (2, n) of uniform ranges in um and
    urad when given.

    Parameters
    ----------
    machine : ChainMachine
        The machine.
    bounds : array (2, n), optional
        Uniform ranges (mm, rad) of its errors.

    Returns
    -------
    DataFrame (n, 5 or 8)
        symbol, kind, axis, enters (where in the chain), component and, with ``bounds``, low,
        high and unit (um, urad).
    """
    table = pd.DataFrame({
        "symbol": machine.error_names, "kind": [e.kind for e in machine.catalogue],
        "axis": [p.axis for p in machine.placements],
        "enters": [_SLOT_TEXT[p.slot] for p in machine.placements],
        "component": [COMPONENTS[p.component] for p in machine.placements]})
    if bounds is not None:
        b = np.asarray(bounds, dtype=float)
        if b.shape != (2, machine.n_errors):
            raise ValueError(f"bounds must be (2, {machine.n_errors}), got {b.shape}")
        scale = np.where([e.translational for e in machine.catalogue], 1e-3, 1e-6)
        table["low"], table["high"] = b[0] / scale, b[1] / scale
        table["unit"] = ["um" if e.translational else "urad" for e in machine.catalogue]
    return table
