"""Thermal measurements of one axis: the CSV schema of ``data/thermal/README.md``.

:class:`ThermalData` holds the measurements; :func:`read_measurements` reads and validates the
three files (a clear :class:`DataFormatError` naming the file and the problem for anything
malformed; a :class:`DroppedSensorWarning` or :class:`IgnoredColumnWarning` for what it sets
aside), :func:`write_measurements` writes them.  Written by hand: the schema is ours.

Units: positions in mm, errors in um, temperatures in degrees Celsius, times in minutes.
"""

from __future__ import annotations

import contextlib
import os
import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from .. import csvlines, validate

__all__ = [
    "DataFormatError", "DroppedSensorWarning", "IgnoredColumnWarning", "ThermalData",
    "read_measurements", "write_measurements", "save_csv", "rises_of",
    "TEMPERATURES_FILE", "ERRORS_FILE", "EXPERIMENTS_FILE", "TEMPERATURE_RANGE_C",
    "ERROR_LIMIT_UM", "ERROR_MIN_SPAN_UM", "POSITION_MIN_SPAN_MM", "POSITION_LIMIT_MM",
    "MIN_SENSORS", "MAX_SENSORS", "MAX_POSITIONS", "MAX_MEASUREMENTS", "MAX_FILE_BYTES",
]

# --------------------------------------------------------------------------------------------
# Data: the CSV schema
# --------------------------------------------------------------------------------------------

TEMPERATURES_FILE = "temperatures.csv"
ERRORS_FILE = "errors.csv"
EXPERIMENTS_FILE = "experiments.csv"
_TEMP_UNIT = "_degC"
#: Plausible values of each quantity, refused outside (the limits are in the message).
#: Temperatures (degC): a machine shop's air, structure, drives and motor windings lie within
#: -30..200 degC (insulation class H is rated to 180 degC); a temperature in kelvin does not
#: (any shop above -30 degC reads above 243 K).
TEMPERATURE_RANGE_C = (-30.0, 200.0)
#: Errors (um): a machine tool's positioning error stays within +-1000 um (1 mm); larger
#: readings are most likely in nm.  Over a whole file the errors span at least 1 um: the pitch
#: error, the warm-up drift and the interferometer's own scatter each reach that; a file whose
#: errors all lie within 1 um is most likely in mm.
ERROR_LIMIT_UM = 1000.0
ERROR_MIN_SPAN_UM = 1.0
#: Target positions (mm): they span at least 1 mm and lie within +-100 m; positions in m span
#: less than 1 mm over any machine-tool axis shorter than 1 km.
POSITION_MIN_SPAN_MM = 1.0
POSITION_LIMIT_MM = 1e5
#: Size limits of a readable dataset, so that a run stays within memory and time on a small
#: machine: the fuzzy closure holds n_sensors**3 numbers, the point-by-point selection runs
#: once per position, and the SVR search's time grows with the measurements (its grid bounded
#: by :data:`mtaccuracy.thermal.SVR_MAX_CN`): at the limits one train/test split of notebook 04
#: takes about 50 s, the whole notebook about 8 min on 2 cores, 0.6 GB.
MAX_SENSORS = 100
#: At least this many working sensors (after dead ones are dropped): the clustering and the
#: selection of sensitive points need a choice.
MIN_SENSORS = 3
MAX_POSITIONS = 500
MAX_MEASUREMENTS = 1000
#: A file larger than this is refused before it is read (errors.csv at the limits above, 500 000
#: rows, takes about 15 MB).
MAX_FILE_BYTES = 100_000_000


class DataFormatError(ValueError):
    """A measurement file breaks the CSV schema; the message names the file and the problem."""


class DroppedSensorWarning(UserWarning):
    """A dead sensor was dropped by :func:`read_measurements`.

    Dead: its reading never changes within an experiment, or it holds no number.  The message
    names the file, the sensor and the value.
    """


class IgnoredColumnWarning(UserWarning):
    """Columns outside the schema (``spindle_speed_rpm``, ``note``) were ignored on reading.

    Raised by :func:`read_measurements`; the message names the file and the columns.
    """


@dataclass(frozen=True)
class ThermalData:
    """Measurements of one axis: rows are measurements (experiment, measurement number, time).

    Attributes
    ----------
    index : DataFrame (n, 3)
        ``experiment``, ``measurement``, ``time_min`` of each measurement.
    temperatures : DataFrame (n, S)
        One column per sensor (degC).
    errors : array (n, P)
        Positioning error (um) at each target position.
    positions_mm : array (P,)
        Target positions (mm).
    feeds : dict
        Experiment -> feed (mm/min), when ``experiments.csv`` gives it.
    source : str
        Where the data came from (a folder, or ``"reconstructed"``).
    dropped : dict
        Sensor name -> why :func:`read_measurements` dropped it (a dead sensor, with the file
        and the value it reads); empty when none was.
    ignored_columns : dict
        Column name -> why :func:`read_measurements` ignored it (the file holding it and what
        it is, e.g. ``"temperatures.csv: no unit, text"``); empty when none was.
    """

    index: pd.DataFrame
    temperatures: pd.DataFrame
    errors: np.ndarray
    positions_mm: np.ndarray
    feeds: dict = field(default_factory=dict)
    source: str = ""
    dropped: dict = field(default_factory=dict)
    ignored_columns: dict = field(default_factory=dict)

    def __post_init__(self):
        n = len(self.index)
        if len(self.temperatures) != n or self.errors.shape != (n, len(self.positions_mm)):
            raise ValueError(f"inconsistent shapes: {n} measurements, temperatures "
                             f"{self.temperatures.shape}, errors {self.errors.shape}, "
                             f"{len(self.positions_mm)} positions")

    @property
    def sensors(self) -> list[str]:
        """list of str: the sensor names, in column order."""
        return list(self.temperatures.columns)

    @property
    def experiments(self) -> list[int]:
        """list of int: the experiment numbers, ascending."""
        return sorted(self.index.experiment.unique().tolist())

    @property
    def groups(self) -> np.ndarray:
        """The experiment of every row (for grouped cross-validation)."""
        return self.index.experiment.to_numpy()

    def subset(self, experiments) -> ThermalData:
        """The rows of the given experiments, in the stored order.

        Parameters
        ----------
        experiments : int or sequence of int
            Experiments kept (ValueError for an unknown one).

        Returns
        -------
        ThermalData
            Their measurements, with their feeds; positions and source unchanged.
        """
        experiments = [int(e) for e in np.atleast_1d(experiments)]
        unknown = sorted(set(experiments) - set(self.experiments))
        if unknown:
            raise ValueError(f"unknown experiment(s) {unknown}; the data have {self.experiments}")
        m = self.index.experiment.isin(experiments).to_numpy()
        return ThermalData(self.index[m].reset_index(drop=True),
                           self.temperatures[m].reset_index(drop=True), self.errors[m],
                           self.positions_mm,
                           {e: f for e, f in self.feeds.items() if e in experiments}, self.source,
                           dict(self.dropped), dict(self.ignored_columns))

    def rises(self) -> pd.DataFrame:
        """Temperatures relative to the first measurement of each experiment (Eq. 9's T - T0).

        Returns
        -------
        DataFrame (n, S)
            degC.
        """
        t = self.temperatures
        r = rises_of(t.to_numpy(dtype=float)[None], self.index.experiment.to_numpy())[0]
        return pd.DataFrame(r, index=t.index, columns=t.columns)

    def offsets_mm(self) -> np.ndarray:
        """Target positions shifted to start at 0 (185..445 mm -> 0..260 mm).

        Returns
        -------
        array (P,)
            mm.
        """
        return self.positions_mm - self.positions_mm[0]


def _problem(path, message) -> DataFormatError:
    return DataFormatError(f"{path}: {message}")


# Reading a file.  pandas reads the data (fast: numbers come as float columns); everything a
# message needs is taken from the text itself.
#
# Line numbers.  pandas numbers the rows it keeps, not the file's lines: it skips blank lines
# and a quoted field may hold line breaks.  Every message about a bad row names the line an
# editor shows, from :func:`mtaccuracy.csvlines.records` (the schema has no comment lines).  It
# runs only when a message is written, so reading a good file costs nothing extra.  A row whose
# every field is empty (``,,,`` or ``;;;``, as a spreadsheet writes an empty row) is dropped on
# both sides, so that pandas' rows and the scanned records stay in step.
#
# Separator.  A file is comma-separated with decimal points, or semicolon-separated (as
# European spreadsheet software writes CSV) with decimal commas or points; the first non-blank
# line, the header, tells which (:func:`_separator`); ``csvlines.records(text, sep=sep)``
# scans either.


def _decode(path: Path, raw: bytes) -> str:
    """The text of a file's bytes: UTF-8, without the byte-order mark Excel writes first."""
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")) or b"\x00" in raw[:4096]:
        what = ("UTF-16 text" if raw.startswith((b"\xff\xfe", b"\xfe\xff")) else
                "holds NUL bytes, as UTF-16 text does")
        raise _problem(path, f"{what} (what Excel saves as 'Unicode Text'); save the file as "
                             f"'CSV UTF-8' (comma-separated) instead")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        raise _problem(path, f"not UTF-8 text: byte 0x{raw[e.start]:02x} on line "
                             f"{csvlines.bad_byte_line(raw, e)}; save the file as UTF-8") from None
    return text.removeprefix("\ufeff")


def _header_line(text: str) -> tuple[int, int, int]:
    """Start, end and number (1-based) of the first non-blank line; ``(0, 0, 1)`` if blank."""
    first = re.search(r"\S", text)
    if first is None:
        return 0, 0, 1
    start = max(text.rfind("\n", 0, first.start()), text.rfind("\r", 0, first.start())) + 1
    head = text[:start]
    return (start, re.compile(r"[^\r\n]*").match(text, first.start()).end(),
            head.count("\n") + head.count("\r") - head.count("\r\n") + 1)


def _separator(path: Path, text: str) -> str:
    """The header's field separator, ``","`` or ``";"``; refuse tabs and a header with both.

    The header is the first non-blank line; ``";"`` when it holds ``;`` and no ``,``.
    """
    start, end, number = _header_line(text)
    line = text[start:end]
    if ";" in line and "," in line:
        raise _problem(path, f"the header (line {number}) holds both ',' and ';', so the field "
                             f"separator is unclear; save the file comma-separated with decimal "
                             f"points (or semicolon-separated, with no ',' in the header)")
    if ";" in line:
        return ";"
    if "\t" in line and "," not in line:
        raise _problem(path, f"tab-separated (the header, line {number}, holds tabs and no "
                             f"','); save the file comma-separated with decimal points, or "
                             f"semicolon-separated with decimal commas")
    return ","


def _records_of(text: str, sep: str):
    """A file's records (:func:`mtaccuracy.csvlines.records`), header first, fields as written."""
    return csvlines.records(text, sep=sep)


def _records(path: Path):
    """The file's records with their lines, the header first (see :func:`_records_of`)."""
    text = _decode(path, path.read_bytes())
    return _records_of(text, _separator(path, text))


def _blank(fields) -> bool:
    """Whether a record is a row the reader drops (every field empty)."""
    return all(not f.strip() for f in fields)


def _where(path: Path, rows, column: int | None = None) -> list[tuple[int, str]]:
    """The line and, with ``column``, the field text of each data row of ``rows``, in order.

    Lines are 1-based, as an editor shows them; ``rows`` are positions in the table
    :func:`_read_csv` returns, ``column`` a position in the header; the text is '' where the
    row is short.
    """
    wanted = {int(r) for r in rows}
    found: dict[int, tuple[int, str]] = {}
    text = _decode(path, path.read_bytes())
    sep = _separator(path, text)
    records = _records_of(text, sep)
    with contextlib.suppress(csvlines.CSVLineError):
        next(records, None)                          # the header
        row = -1
        for rec in records:
            if _blank(rec.fields):
                continue
            row += 1
            if row in wanted:
                f = rec.fields[column] if column is not None and column < len(rec.fields) else ""
                found[row] = (rec.first, f.strip())
                if len(found) == len(wanted):
                    break
    return [found.get(int(r), (-1, "")) for r in rows]


def _line_numbers(path: Path, rows) -> list[int]:
    """The file's line numbers (1-based, as an editor shows them) of data rows ``rows``.

    ``rows`` are positions in the table :func:`_read_csv` returns; the order is kept.
    """
    return [line for line, _ in _where(path, rows)]


def _lines(path: Path, mask) -> str:
    """The file's line numbers of the data rows where ``mask`` holds, at most ten shown."""
    rows = np.flatnonzero(np.asarray(mask))
    return f"{_line_numbers(path, rows[:10])}{' ...' if len(rows) > 10 else ''}"


def _unreadable(path: Path, exc: Exception) -> DataFormatError:
    """The message for a file pandas cannot tokenise, naming the line at fault.

    The line pandas names counts records, not lines, so the file is scanned again.
    """
    if isinstance(exc, pd.errors.EmptyDataError):
        return _problem(path, "is empty (no header line)")
    if isinstance(exc, pd.errors.ParserError):
        problem = _ragged(path)
        if problem is not None:
            return problem
    return _problem(path, f"not a readable CSV file ({exc})")


def _ragged(path: Path) -> DataFormatError | None:
    """The error for the first row wider than the header or a quote never closed, else None.

    When the first data rows all have more fields than the header, a comma file with decimal
    commas is the likely cause, and the message says so.
    """
    text = _decode(path, path.read_bytes())
    sep = _separator(path, text)
    records = _records_of(text, sep)
    try:
        header = next(records, None)
        if header is None:
            return None
        width, wider, bad = len(header.fields), [], None
        for rec in records:
            if _blank(rec.fields):
                continue
            if len(wider) < 3:
                wider.append(len(rec.fields) > width)
            if bad is None and len(rec.fields) > width:
                bad = rec
            if bad is not None and len(wider) >= 3:
                break
    except csvlines.UnclosedQuote as exc:
        return _problem(path, f"a quoted field of the row starting on line {exc.line} is never "
                              f"closed (a '\"' is missing)")
    except csvlines.CSVLineError:
        return None
    if bad is None:
        return None
    hint = ("; the first rows all have more fields than the header: decimal commas (30,41) in "
            "a comma-separated file? Write decimal points, or separate the fields with ';'"
            if sep == "," and all(wider) else "")
    return _problem(path, f"line {bad.first} has {len(bad.fields)} fields, the header (line "
                          f"{header.first}) has {width}{hint}")


#: How a column without a name in the header is called in messages (1-based position).
_UNNAMED = "<unnamed column {}>"


def _header(path: Path, text: str, sep: str) -> list[str] | None:
    """The header's column names, stripped; refuse a name given twice.

    An empty name becomes :data:`_UNNAMED` (pandas would rename a second ``T1_degC``
    ``T1_degC.1`` silently).  None when the scanner cannot read the header (pandas' error then
    names the problem).
    """
    try:
        # the header line alone when it is a whole record (no quoted line break in it)
        rec = next(_records_of(text[:_header_line(text)[1]], sep), None)
    except csvlines.CSVLineError:
        try:
            rec = next(_records_of(text, sep), None)
        except csvlines.CSVLineError:
            return None
    if rec is None:
        return None
    names = [f.strip() for f in rec.fields]
    names = [n or _UNNAMED.format(i + 1) for i, n in enumerate(names)]
    seen: dict[str, list[int]] = {}
    for i, n in enumerate(names):
        seen.setdefault(n, []).append(i + 1)
    for n, at in seen.items():
        if len(at) > 1:
            what = (f"duplicate sensor name {n[:-len(_TEMP_UNIT)]!r}: column {n!r}"
                    if n.endswith(_TEMP_UNIT) else f"duplicate column name {n!r}")
            raise _problem(path, f"{what} appears {len(at)} times in the header (line "
                                 f"{rec.first}), as columns {', '.join(map(str, at))}; every "
                                 f"column needs its own name (two sensors, two names)")
    return names


def _read_csv(path: Path, on_read=None) -> pd.DataFrame:
    """Read one file of the schema (comma- or semicolon-separated, see :func:`_separator`).

    Its data rows are numbered by position (the file's line numbers of any of them:
    :func:`_where`), rows whose every field is empty are dropped, the columns carry the
    header's names (stripped).  A column whose every value reads as a number comes as numbers
    (an empty field is NaN), any other as text (:func:`_numeric` converts it and names the
    values that are not numbers).  ``df.attrs["separator"]`` is the separator.
    """
    if not path.exists():
        raise _problem(path, "file not found (the schema needs temperatures.csv and errors.csv; "
                             "see data/thermal/README.md)")
    size = path.stat().st_size
    if size > MAX_FILE_BYTES:
        raise _problem(path, f"{size} bytes; files up to {MAX_FILE_BYTES} bytes are read (the "
                             f"size limits of the schema need far less)")
    text = _decode(path, path.read_bytes())
    sep = _separator(path, text)
    names = _header(path, text, sep)
    try:
        with warnings.catch_warnings():
            # a column mixing numbers and text, read in chunks: :func:`_numeric` handles it
            warnings.simplefilter("ignore", pd.errors.DtypeWarning)
            df = pd.read_csv(path, sep=sep, decimal="," if sep == ";" else ".",
                             encoding="utf-8-sig", keep_default_na=False, na_values=[""],
                             skipinitialspace=True)
        if on_read is not None:
            on_read(path)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise _unreadable(path, exc) from None
    if not isinstance(df.index, pd.RangeIndex):
        # pandas takes a first data row with more fields than the header as the sign of an
        # index column and shifts every column; the schema has none
        raise _ragged(path) or _problem(path, "has more fields in its rows than in its header")
    if names is not None and len(names) == len(df.columns):
        df.columns = names
    else:
        df.columns = [str(c).strip() for c in df.columns]
    empty = df.isna().all(axis=1).to_numpy()
    if empty.any():
        df = df.loc[~empty].reset_index(drop=True)
    if df.empty:
        raise _problem(path, "has a header but no data rows")
    df.attrs["separator"] = sep
    return df


def _check_units(path, columns, quantity: str, expected: str) -> None:
    """Refuse a column naming ``quantity`` in another unit (called when ``expected`` is missing)."""
    for c in columns:
        if c == expected or not c.startswith(quantity + "_"):
            continue
        unit = c[len(quantity) + 1:]
        raise _problem(path, f"column {c!r} gives {quantity} in {unit!r}; the schema needs "
                             f"{expected!r} (unit {expected.split('_', 1)[1]}); convert the "
                             f"values and rename the column")


def _require(path, df, columns) -> None:
    missing = [c for c in columns if c not in df.columns]
    if missing:
        lower = {str(c).lower(): c for c in df.columns}
        near = [f"{lower[m.lower()]!r}" for m in missing if m.lower() in lower]
        hint = f" (names are case-sensitive: {', '.join(near)})" if near else ""
        raise _problem(path, f"missing column(s) {missing}; found {list(df.columns)}{hint}")


def _parse(s: pd.Series, sep: str) -> np.ndarray:
    """The numbers of a text column, NaN where a value is not one.

    In a semicolon file a decimal comma reads as a decimal point.
    """
    text = s.astype(str).str.strip()
    if sep == ";":
        text = text.str.replace(",", ".", regex=False)
    return pd.to_numeric(text, errors="coerce").to_numpy(dtype=float)


def _is_number_column(s: pd.Series) -> bool:
    return pd.api.types.is_numeric_dtype(s.dtype) and not pd.api.types.is_bool_dtype(s.dtype)


def _numeric(path, df, column, integer=False) -> np.ndarray:
    s = df[column]
    values = (s.to_numpy(dtype=float) if _is_number_column(s)
              else _parse(s, df.attrs.get("separator", ",")))
    bad = ~np.isfinite(values)
    if bad.any():
        rows = np.flatnonzero(bad)
        where = _where(path, rows[:10], list(df.columns).index(column))
        shown = [v for _, v in where[:3]]
        hint = ("; a decimal comma? Write decimal points (30.41), or save the file "
                "semicolon-separated" if df.attrs.get("separator", ",") == "," and
                any(re.fullmatch(r"[+-]?\d*,\d+", v) for v in shown) else "")
        raise _problem(path, f"column {column!r} has a missing, NaN or non-numeric value "
                             f"({', '.join(map(repr, shown))}) on line(s) "
                             f"{[line for line, _ in where]}{' ...' if len(rows) > 10 else ''}"
                             f"{hint}")
    if integer:
        if not np.all(values == np.round(values)):
            raise _problem(path, f"column {column!r} must hold whole numbers (line(s) "
                                 f"{_lines(path, values != np.round(values))})")
        return values.astype(int)
    return values


def _check_range(path, column, values, lo, hi, unit, hint) -> None:
    """Refuse values outside [lo, hi], naming the column, lines, values and limits."""
    bad = (values < lo) | (values > hi)
    if bad.any():
        shown = ", ".join(f"{v:g}" for v in values[bad][:3])
        raise _problem(path, f"column {column!r} has value(s) {shown} {unit} on line(s) "
                             f"{_lines(path, bad)}, outside the plausible range {lo:g} .. {hi:g} "
                             f"{unit}; {hint}")


def _check_span(path, column, values, least, unit, what) -> None:
    """Refuse a column whose values span less than ``least`` (a unit mix-up), naming it."""
    span = float(np.ptp(values))
    if span < least:
        raise _problem(path, f"column {column!r} spans only {span:g} {unit} ({values.min():g} .. "
                             f"{values.max():g}), less than the plausible {least:g} {unit} {what}")


def _check_size(path, what, n, limit, why) -> None:
    if n > limit:
        raise _problem(path, f"{n} {what}; at most {limit} are supported ({why})")


# Columns of temperatures.csv.  Units are part of the names: ``<sensor>_degC`` is a sensor; a
# name ending in another temperature unit (``_K``, ``_degF``, ``_C``, ``[°C]`` ...: see
# :func:`_temperature_unit`) is a temperature in the wrong unit or spelling, refused; a name
# ending in any other unit (``spindle_speed_rpm``) is another quantity, ignored; a name with
# no unit is refused when the column holds numbers (a sensor that lost its unit: ``T3``) and
# ignored when it holds text (``note``).

_KEYS = ("experiment", "measurement", "time_min")
#: A unit in brackets at the end of a column name: ``T1 [°C]``, ``speed (rpm)``.
_BRACKETED = re.compile(r"\s*[\[(]\s*([^\[\]()]*?)\s*[\])]\s*$")
_CELSIUS = {"c", "oc", "celsius", "centigrade"}
_OTHER_SCALES = {"k", "kelvin", "f", "fahrenheit"}


def _unit(name: str) -> str | None:
    """The unit a column name ends in, or None.

    ``[unit]`` or ``(unit)``, else what follows its last ``_`` unless that is a number.
    """
    m = _BRACKETED.search(name)
    if m:
        return m.group(1)
    if "_" in name:
        unit = name.rsplit("_", 1)[1].strip()
        if unit and not re.fullmatch(r"[\d.]+", unit):
            return unit
    return None


def _temperature_unit(unit: str) -> str | None:
    """``"celsius"`` or ``"other"`` for a temperature unit however spelled, else None.

    Spellings: ``C``, ``degc``, ``°C``, ``oC``, ``K``, ``degK``, ``kelvin``, ``F``, ``degF``
    ...; None for anything else (``rpm``, ``deg`` alone: an angle).
    """
    u = re.sub(r"[\s°º]", "", unit.lower())
    u = re.sub(r"^(degrees?|deg|grad)_?", "", u)
    return "celsius" if u in _CELSIUS else "other" if u in _OTHER_SCALES else None


def _holds_numbers(s: pd.Series, sep: str) -> bool:
    """Whether a column has a value and every value it has is a number."""
    if _is_number_column(s):
        return bool(s.notna().any())
    values = s.dropna()
    return not values.empty and bool(np.isfinite(_parse(values, sep)).all())


def _temperature_columns(path: Path, df: pd.DataFrame) -> tuple[dict[str, str], dict[str, str]]:
    """Sensor name -> its column ``<sensor>_degC``, and the columns ignored (column -> why).

    Refuses temperatures in another unit or spelling and columns of numbers without a unit.
    """
    sep = df.attrs.get("separator", ",")
    sensors: dict[str, str] = {}
    ignored: dict[str, str] = {}
    tail = ("; a column that is not a temperature is ignored when its name ends in its own "
            "unit (e.g. spindle_speed_rpm)")
    for c in df.columns:
        if c in _KEYS:
            continue
        if c.endswith(_TEMP_UNIT):
            name = c[:-len(_TEMP_UNIT)].strip()
            if not name:
                raise _problem(path, f"column {c!r} names no sensor; write <sensor>{_TEMP_UNIT}, "
                                     f"e.g. T1{_TEMP_UNIT}")
            if name in sensors:
                raise _problem(path, f"duplicate sensor name {name!r}: columns "
                                     f"{sensors[name]!r} and {c!r}; every column needs its own "
                                     f"name (two sensors, two names)")
            sensors[name] = c
            continue
        if c.startswith("<unnamed column "):
            if _holds_numbers(df[c], sep):
                raise _problem(path, f"column {c[16:-1]} has no name in the header but holds "
                                     f"numbers; name it (<sensor>{_TEMP_UNIT} for a "
                                     f"temperature){tail}")
            ignored[c] = "no name, " + ("empty" if df[c].isna().all() else "text")
            continue
        unit = _unit(c)
        scale = None if unit is None else _temperature_unit(unit)
        if scale is not None:
            m = _BRACKETED.search(c)
            stem = (c[:m.start()] if m else c.rsplit("_", 1)[0]).strip()
            stem = re.sub(r"[_ ]*(degrees?|deg|grad)$", "", stem, flags=re.I) or "<sensor>"
            fix = (f"rename it {stem + _TEMP_UNIT!r}" if scale == "celsius" else
                   f"convert the values to degrees Celsius (degC = K - 273.15 = (degF - 32) / "
                   f"1.8) and rename it {stem + _TEMP_UNIT!r}")
            raise _problem(path, f"column {c!r}: temperatures must be in degrees Celsius, named "
                                 f"<sensor>{_TEMP_UNIT} (found {unit!r}); {fix}{tail}")
        if unit is None and _holds_numbers(df[c], sep):
            raise _problem(path, f"column {c!r}: temperatures must be in degrees Celsius, named "
                                 f"<sensor>{_TEMP_UNIT} (found 'no unit'); a column of numbers "
                                 f"needs its unit in its name: <sensor>{_TEMP_UNIT} for a "
                                 f"temperature, its own unit for any other quantity, which is "
                                 f"then ignored (e.g. spindle_speed_rpm, run_no)")
        ignored[c] = (f"another quantity (its name ends in {unit!r}, not a temperature "
                      f"unit)" if unit is not None else
                      "no unit, " + ("empty" if df[c].isna().all() else "text"))
    return sensors, ignored


def _readings(path: Path, df: pd.DataFrame, sensors: dict[str, str]):
    """The readings of every sensor (degC, file order), and the sensors holding no number.

    No number (sensor -> why): every cell empty, or one text such as ``NaN`` or ``OL`` in
    every cell.  A sensor with some numbers and some cells that are not numbers is refused.
    """
    sep = df.attrs.get("separator", ",")
    values, dead = {}, {}
    for name, c in sensors.items():
        s = df[c]
        if s.isna().all():
            dead[name] = "holds no reading (every cell is empty)"
            continue
        if not _is_number_column(s):
            text = s.astype(str).str.strip().unique()
            if len(text) == 1 and not np.isfinite(_parse(pd.Series(text), sep)).all():
                dead[name] = f"holds no number (every cell reads {text[0]!r})"
                continue
        values[name] = _numeric(path, df, c)
    return values, dead


def _constant(values: dict[str, np.ndarray], experiments: np.ndarray) -> dict[str, str]:
    """The sensors whose reading never changes within any experiment (sensor -> why).

    The why names the value: such a sensor carries no rise, the only thing the models learn
    from a temperature.
    """
    if not values:
        return {}
    g = pd.DataFrame(values).groupby(experiments, sort=True)
    lo, hi = g.min(), g.max()
    out = {}
    for name in values:
        if not (lo[name] == hi[name]).all():
            continue
        per = lo[name]
        if per.nunique() == 1:
            out[name] = f"reads {per.iloc[0]:g} degC in every measurement"
        else:
            shown = ", ".join(f"{v:g} in experiment {e}" for e, v in per.iloc[:4].items())
            out[name] = (f"reads one value through each experiment ({shown}"
                         f"{' ...' if len(per) > 4 else ''} degC): it never changes within an "
                         f"experiment")
    return out


def read_measurements(folder, on_read=None) -> ThermalData:
    """Read and validate ``temperatures.csv``, ``errors.csv`` (and ``experiments.csv`` if there).

    The schema (``data/thermal/README.md``):

    * ``temperatures.csv``: ``experiment, measurement, time_min, <sensor>_degC ...`` one row per
      measurement, in any row order; at least :data:`MIN_SENSORS` working sensors.
    * ``errors.csv``: ``experiment, measurement, position_mm, error_um`` one row per target
      position and measurement; every measurement has the same target positions.
    * ``experiments.csv`` (optional): ``experiment, feed_mm_per_min``, each experiment of the
      data once and no other.

    Files are UTF-8 (a byte-order mark is fine), comma-separated with decimal points or
    semicolon-separated with decimal commas or points (the header line tells which); rows
    whose every field is empty are skipped.

    Set aside, with a warning: a **dead sensor**, one whose reading never changes within any
    experiment (the same value throughout, or one value per experiment) or that holds no number
    (every cell empty, or one text such as ``NaN``): it is dropped
    (:class:`DroppedSensorWarning`, :attr:`ThermalData.dropped`).  A sensor that changes in at
    least one experiment is kept, however coarse its resolution.  **Other columns**: any column
    of ``errors.csv`` or ``experiments.csv`` outside the schema, and in ``temperatures.csv`` a
    column named with a unit that is not a temperature's (``spindle_speed_rpm``) or holding
    text (``note``), is ignored (:class:`IgnoredColumnWarning`,
    :attr:`ThermalData.ignored_columns`).

    Raises :class:`DataFormatError` naming the file and the problem: a missing file or column,
    a column in other units (``error_mm``, ``T1_K``, ``T1_degF``, ``T1 [°C]``), a column of
    numbers without a unit in ``temperatures.csv`` (``T3``), a column name given twice, a
    missing/NaN/non-numeric value, a value outside its unit's plausible range
    (:data:`TEMPERATURE_RANGE_C`, :data:`ERROR_LIMIT_UM`, :data:`ERROR_MIN_SPAN_UM`,
    :data:`POSITION_MIN_SPAN_MM`, :data:`POSITION_LIMIT_MM`: kelvin under ``_degC``, mm or nm
    under ``_um``), times that do not increase with the measurement number, duplicated or
    unmatched measurements or experiments (``experiments.csv`` listing an experiment without
    data or missing one with data), measurements of unequal length, re-zeroed measurements
    (every measurement of an experiment reading exactly 0 at one target, see
    :func:`_check_zeroing`), fewer than :data:`MIN_SENSORS` sensors left once dead ones are
    dropped, more data than :data:`MAX_SENSORS`, :data:`MAX_POSITIONS`,
    :data:`MAX_MEASUREMENTS`, a tab-separated or UTF-16 file.

    Parameters
    ----------
    folder : path
        Holds ``temperatures.csv``, ``errors.csv`` and, optionally, ``experiments.csv``.
    on_read : callable, optional
        Called as ``on_read(path)`` for every file read (the compendium passes
        ``provenance.track`` to hash its inputs).

    Returns
    -------
    ThermalData
        n measurements (rows sorted by experiment, measurement), S sensors, P positions;
        ``dropped`` and ``ignored_columns`` say what was set aside.

    Raises
    ------
    DataFormatError
        Naming the file and the problem; a problem of some rows names their lines as an
        editor shows them (1-based, blank lines and line breaks inside quoted fields counted).

    Warns
    -----
    DroppedSensorWarning
        Once per dead sensor, naming the file, the sensor and its value.
    IgnoredColumnWarning
        Once per file with columns outside the schema, naming them.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise DataFormatError(f"{folder}: not a folder (data_dir must name a folder holding "
                              f"{TEMPERATURES_FILE} and {ERRORS_FILE})")
    tp, ep, xp = folder / TEMPERATURES_FILE, folder / ERRORS_FILE, folder / EXPERIMENTS_FILE

    t = _read_csv(tp, on_read)
    if "time_min" not in t.columns:
        _check_units(tp, t.columns, "time", "time_min")
    _require(tp, t, list(_KEYS))
    sensors, ignored_t = _temperature_columns(tp, t)
    ignored = {tp: list(ignored_t)}
    if len(sensors) < MIN_SENSORS:
        raise _problem(tp, f"needs at least {MIN_SENSORS} temperature columns "
                           f"<sensor>{_TEMP_UNIT}, found {len(sensors)}")
    _check_size(tp, "temperature columns", len(sensors), MAX_SENSORS,
                "the fuzzy clustering holds n_sensors**3 numbers")
    _check_size(tp, "measurements (rows)", len(t), MAX_MEASUREMENTS,
                "the SVR search's time grows with the measurements")
    t_exp = _numeric(tp, t, "experiment", integer=True)
    t_meas = _numeric(tp, t, "measurement", integer=True)
    t_time = _numeric(tp, t, "time_min")
    keys = pd.DataFrame({"experiment": t_exp, "measurement": t_meas, "time_min": t_time,
                         "row": np.arange(len(t))})
    dup = keys.duplicated(["experiment", "measurement"], keep=False)
    if dup.any():
        r = keys[dup].iloc[0]
        twice = dup & (keys.experiment == r.experiment) & (keys.measurement == r.measurement)
        raise _problem(tp, f"experiment {int(r.experiment)} measurement {int(r.measurement)} "
                           f"appears more than once (lines {_lines(tp, twice)})")
    # measurement numbers give the order; the times must agree with it
    order = keys.sort_values(["experiment", "measurement"], kind="stable").index
    keys = keys.loc[order].reset_index(drop=True)
    for e, g in keys.groupby("experiment"):
        if len(g) < 2:
            raise _problem(tp, f"experiment {e} has a single measurement; at least 2 are needed")
        tm = g.time_min.to_numpy()
        back = np.flatnonzero(np.diff(tm) <= 0)
        if back.size:
            a, b = g.iloc[back[0]], g.iloc[back[0] + 1]
            line_a, line_b = _line_numbers(tp, [a.row, b.row])
            raise _problem(tp, f"experiment {e}: time_min must increase with the measurement "
                               f"number, but measurement {int(b.measurement)} (line "
                               f"{line_b}, {b.time_min:g} min) does not come after "
                               f"measurement {int(a.measurement)} (line {line_a}, "
                               f"{a.time_min:g} min); times in measurement order: "
                               f"{' -> '.join(f'{v:g}' for v in tm[:12])}"
                               f"{' ...' if len(tm) > 12 else ''}")
    keys = keys.drop(columns="row")

    readings, dead = _readings(tp, t, sensors)
    dead.update(_constant(readings, t_exp))
    dead = {name: dead[name] for name in sensors if name in dead}       # in column order
    live = [name for name in sensors if name not in dead]
    if len(live) < MIN_SENSORS:
        raise _problem(tp, f"{len(live)} working sensor(s) {live} once the dead ones are "
                           f"dropped ({'; '.join(f'{n}: {w}' for n, w in dead.items())}); at "
                           f"least {MIN_SENSORS} are needed")
    lo, hi = TEMPERATURE_RANGE_C
    for name in live:
        _check_range(tp, sensors[name], readings[name], lo, hi, "degC",
                     "the range of a machine shop's air, structure, drives and motors; "
                     "kelvin? (degC = K - 273.15)")
    temps = pd.DataFrame({name: readings[name] for name in live}).loc[order] \
        .reset_index(drop=True)

    er = _read_csv(ep, on_read)
    for quantity, expected in (("position", "position_mm"), ("error", "error_um")):
        if expected not in er.columns:
            _check_units(ep, er.columns, quantity, expected)
    error_columns = ["experiment", "measurement", "position_mm", "error_um"]
    _require(ep, er, error_columns)
    ignored[ep] = [c for c in er.columns if c not in error_columns]
    e_exp = _numeric(ep, er, "experiment", integer=True)
    e_meas = _numeric(ep, er, "measurement", integer=True)
    e_pos = _numeric(ep, er, "position_mm")
    e_val = _numeric(ep, er, "error_um")
    _check_range(ep, "error_um", e_val, -ERROR_LIMIT_UM, ERROR_LIMIT_UM, "um",
                 "a machine tool's positioning error; nm? (um = nm / 1000)")
    _check_span(ep, "error_um", e_val, ERROR_MIN_SPAN_UM, "um",
                "of a positioning error measured over a warm-up; mm? (um = mm x 1000)")
    _check_range(ep, "position_mm", e_pos, -POSITION_LIMIT_MM, POSITION_LIMIT_MM, "mm",
                 "a machine tool's axis")
    _check_span(ep, "position_mm", e_pos, POSITION_MIN_SPAN_MM, "mm",
                "between target positions; m? (mm = m x 1000)")
    long = pd.DataFrame({"experiment": e_exp, "measurement": e_meas, "position_mm": e_pos,
                         "error_um": e_val})
    dup = long.duplicated(["experiment", "measurement", "position_mm"], keep=False)
    if dup.any():
        r = long[dup].iloc[0]
        twice = dup & (long.experiment == r.experiment) & (long.measurement == r.measurement) \
            & (long.position_mm == r.position_mm)
        hint = (f"; the reader ignores column(s) {ignored[ep]}: it reads one error per target "
                f"and measurement (a bidirectional measurement: keep one direction, or the "
                f"mean of both, per target)" if ignored[ep] else "")
        raise _problem(ep, f"experiment {int(r.experiment)} measurement {int(r.measurement)} "
                           f"lists position {r.position_mm:g} mm twice "
                           f"(lines {_lines(ep, twice)}){hint}")
    sizes = long.groupby(["experiment", "measurement"]).size()
    positions = np.sort(long.position_mm.unique())
    if len(positions) < 2:
        raise _problem(ep, "needs at least 2 target positions")
    _check_size(ep, "target positions", len(positions), MAX_POSITIONS,
                "the point-by-point selection and model run once per position")
    if (sizes != len(positions)).any():
        (e, m), n = next((k, v) for k, v in sizes.items() if v != len(positions))
        have = set(long[(long.experiment == e) & (long.measurement == m)].position_mm)
        lacking = [f"{p:g}" for p in positions if p not in have]
        raise _problem(ep, f"unequal lengths: experiment {e} measurement {m} has {n} positions, "
                           f"the data hold {len(positions)} (missing {', '.join(lacking)} mm); "
                           f"every measurement needs every target position")

    t_keys = set(zip(t_exp.tolist(), t_meas.tolist(), strict=True))
    e_keys = set(sizes.index.tolist())
    if t_keys != e_keys:
        only_t, only_e = sorted(t_keys - e_keys), sorted(e_keys - t_keys)
        raise DataFormatError(
            f"{ep} and {tp}: unequal lengths: the files do not list the same measurements "
            f"(experiment, measurement): only in {tp.name}: {only_t[:6]}; only in {ep.name}: "
            f"{only_e[:6]}")

    wide = long.pivot(index=["experiment", "measurement"], columns="position_mm",
                      values="error_um")
    errors = wide.loc[list(zip(keys.experiment, keys.measurement, strict=True)),
                      positions].to_numpy()
    _check_zeroing(ep, keys.experiment.to_numpy(), errors, positions)

    feeds = {}
    if xp.exists():
        x = _read_csv(xp, on_read)
        if "feed_mm_per_min" not in x.columns:
            _check_units(xp, x.columns, "feed", "feed_mm_per_min")
        _require(xp, x, ["experiment", "feed_mm_per_min"])
        ignored[xp] = [c for c in x.columns if c not in ("experiment", "feed_mm_per_min")]
        x_exp = _numeric(xp, x, "experiment", integer=True)
        x_feed = _numeric(xp, x, "feed_mm_per_min")
        dup = pd.Series(x_exp).duplicated(keep=False).to_numpy()
        if dup.any():
            twice = sorted(set(x_exp[dup].tolist()))
            raise _problem(xp, f"experiment(s) {twice} listed more than once (lines "
                               f"{_lines(xp, dup)}); each experiment needs one row")
        _check_listed(xp, x_exp, set(keys.experiment.tolist()), f"{tp.name} and {ep.name}")
        feeds = dict(zip(x_exp.tolist(), x_feed.tolist(), strict=True))

    ignored_columns: dict[str, str] = {}
    for path, columns in ignored.items():
        if not columns:
            continue
        uses = {tp: "experiment, measurement, time_min and the temperatures <sensor>_degC",
                ep: "experiment, measurement, position_mm, error_um",
                xp: "experiment, feed_mm_per_min"}[path]
        warnings.warn(f"{path}: column(s) {columns} ignored: not part of the schema, which "
                      f"reads {uses} (data/thermal/README.md)", IgnoredColumnWarning,
                      stacklevel=2)
        for c in columns:
            why = f"{path.name}: {ignored_t[c] if path == tp else 'not part of the schema'}"
            ignored_columns[c] = f"{ignored_columns[c]}; {why}" if c in ignored_columns else why
    dropped = {}
    for name, why in dead.items():
        warnings.warn(f"{tp}: sensor {name!r} (column {sensors[name]!r}) {why}: a dead or "
                      f"disconnected sensor carries no information; dropped (delete the column "
                      f"to silence this warning)", DroppedSensorWarning, stacklevel=2)
        dropped[name] = f"{tp.name}, column {sensors[name]!r}: {why}"
    return ThermalData(keys, temps, errors, positions, feeds, source=str(folder),
                       dropped=dropped, ignored_columns=ignored_columns)


def _check_listed(path: Path, listed: np.ndarray, data: set, files: str) -> None:
    """Refuse an ``experiments.csv`` listing an experiment without data or missing one with.

    The message names the experiments (and the lines of the ones listed).
    """
    extra = np.array([e not in data for e in listed.tolist()])
    missing = sorted(data - set(listed.tolist()))
    problems = []
    if extra.any():
        problems.append(f"lists experiment(s) {sorted(set(listed[extra].tolist()))} (line(s) "
                        f"{_lines(path, extra)}) that have no measurements in {files}")
    if missing:
        problems.append(f"misses experiment(s) {missing}, which have measurements in {files}")
    if problems:
        raise _problem(path, f"{' and '.join(problems)}; list every experiment of the data once "
                             f"(with its feed) and no other, or delete {path.name}")


def _check_zeroing(path, experiments: np.ndarray, errors: np.ndarray, positions) -> None:
    """Refuse re-zeroed measurements.

    *Re-zeroed* means the interferometer was set to zero again before each measurement, so
    that the thermal drift of the zero point (what the intercept b models) is lost.  Its
    signature, detected here: **every** measurement of an experiment reads exactly 0 at one
    common target position (written as 0, 0.0, 0.000 ...).  Kept relative to the zero set at
    the first measurement (as the schema asks), only the first measurement reads exactly 0
    there; the later ones carry the drift, and all of them reading exactly 0 at the
    interferometer's resolution is no drift at all.  A single re-zeroed measurement among
    drifting ones cannot be told from a drift that happens to read 0, and is not refused.
    """
    for e in np.unique(experiments):
        rows = experiments == e
        zero = np.flatnonzero(np.all(errors[rows] == 0.0, axis=0))
        if zero.size:
            raise _problem(path, f"experiment {e}: all {int(rows.sum())} measurements read "
                                 f"exactly 0 at {positions[zero[0]]:g} mm, the signature of "
                                 f"an interferometer re-zeroed before every measurement, "
                                 f"which removes the drift the intercept b models; keep the "
                                 f"readings relative to the zero set at the first measurement "
                                 f"of the experiment (if the axis really reads 0 there every "
                                 f"time, write the readings at the interferometer's full "
                                 f"resolution)")


def _csv_bytes(df: pd.DataFrame, float_format: str) -> bytes:
    """The bytes :func:`save_csv` writes for ``df``."""
    return df.to_csv(index=False, float_format=float_format, lineterminator="\n").encode("utf-8")


def save_csv(df: pd.DataFrame, path, float_format: str = "%.6g") -> None:
    """Write a table as CSV with fixed bytes; rewrite the file only when its bytes change.

    No index, ``float_format``, Unix line ends, UTF-8; the file is replaced atomically.

    Parameters
    ----------
    df : DataFrame
        Written without its index.
    path : path
        The file; its folder is created if missing.
    float_format : str
        printf-style format of floats.
    """
    path = Path(path)
    data = _csv_bytes(df, float_format)
    if not path.exists() or path.read_bytes() != data:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
        tmp.write_bytes(data)
        os.replace(tmp, path)


def write_measurements(data: ThermalData, folder, *, temperature_decimals: int = 2,
                       error_decimals: int = 3, save=None, before_overwrite=None) -> list[Path]:
    """Write ``data`` in the schema of :func:`read_measurements`.

    Every table is formatted first; a file whose bytes would not change is not touched.

    Parameters
    ----------
    data : ThermalData
        The measurements (read, reconstructed or simulated).
    folder : path
        Where ``temperatures.csv``, ``errors.csv`` (and ``experiments.csv`` when ``data.feeds``)
        go; created if missing.
    temperature_decimals, error_decimals : int
        Decimals written for temperatures (degC) and errors (um).
    save : callable, optional
        ``save(df, path, float_format=...)`` writes one table, with the bytes of
        :func:`save_csv` (the default: deterministic bytes, a file rewritten only when its
        bytes change).  The compendium passes its ``reproduction.save_table``, which also
        records provenance.
    before_overwrite : callable, optional
        Called once as ``before_overwrite(paths)`` with the list of existing files whose bytes
        would change, before any file is written, when there are some; an exception raised
        there leaves every file as it was.  The compendium refuses to overwrite a file a user
        edited.

    Returns
    -------
    list of Path
        The files whose content changed.
    """
    def whole(v):  # integers print without decimals
        v = np.asarray(v)
        return v.astype(int) if np.all(v == np.round(v)) else v

    temperature_decimals = validate.integer(temperature_decimals, "temperature_decimals", low=0)
    error_decimals = validate.integer(error_decimals, "error_decimals", low=0)
    folder = Path(folder)
    temps = pd.concat([data.index[["experiment", "measurement"]].astype(int),
                       pd.DataFrame({"time_min": whole(data.index.time_min)}),
                       (data.temperatures.round(temperature_decimals) + 0.0)
                       .add_suffix(_TEMP_UNIT)], axis=1)
    n_pos = len(data.positions_mm)
    errors = pd.DataFrame({
        "experiment": np.repeat(data.index.experiment.to_numpy(), n_pos),
        "measurement": np.repeat(data.index.measurement.to_numpy(), n_pos),
        "position_mm": np.tile(whole(data.positions_mm), len(data.index)),
        "error_um": np.round(data.errors, error_decimals).ravel() + 0.0})
    tables = [(TEMPERATURES_FILE, temps, f"%.{temperature_decimals}f"),
              (ERRORS_FILE, errors, f"%.{error_decimals}f")]
    if data.feeds:
        feeds = pd.DataFrame({"experiment": list(data.feeds),
                              "feed_mm_per_min": list(data.feeds.values())})
        tables.append((EXPERIMENTS_FILE, feeds, "%.0f"))
    before = {name: (folder / name).read_bytes() if (folder / name).exists() else None
              for name, _, _ in tables}
    overwritten = [folder / name for name, df, fmt in tables
                   if before[name] is not None and before[name] != _csv_bytes(df, fmt)]
    if overwritten and before_overwrite is not None:
        before_overwrite(overwritten)
    changed = []
    for name, df, fmt in tables:
        p = folder / name
        (save or save_csv)(df, p, float_format=fmt)
        if p.read_bytes() != before[name]:
            changed.append(p)
    return changed


def rises_of(temperatures: np.ndarray, experiments) -> np.ndarray:
    """Temperatures relative to the first measurement of each experiment, batched.

    The one implementation of :meth:`ThermalData.rises` (the inputs of Eqs. 8 and 9's b).

    Parameters
    ----------
    temperatures : array (R, n, S)
        R stacked datasets of n measurements of S sensors (degC).
    experiments : array (n,)
        Experiment of each measurement.

    Returns
    -------
    array (R, n, S)
        Rises (degC).
    """
    experiments = np.asarray(experiments)
    first = pd.Series(np.arange(len(experiments))).groupby(experiments).transform("first")
    t = np.asarray(temperatures, dtype=float)
    return t - t[:, first.to_numpy(), :]
