"""Thermal measurements of one axis: the CSV schema of ``data/thermal/README.md``.

:class:`ThermalData` holds the measurements; :func:`read_measurements` reads and validates the
three files (a clear :class:`DataFormatError` naming the file and the problem for anything
malformed), :func:`write_measurements` writes them.  Written by hand: the schema is ours.

Units: positions in mm, errors in um, temperatures in degrees Celsius, times in minutes.
"""

from __future__ import annotations

import contextlib
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from .. import csvlines

__all__ = [
    "DataFormatError", "ThermalData", "read_measurements", "write_measurements", "save_csv",
    "rises_of",
    "TEMPERATURES_FILE", "ERRORS_FILE", "EXPERIMENTS_FILE", "TEMPERATURE_RANGE_C",
    "ERROR_LIMIT_UM", "ERROR_MIN_SPAN_UM", "POSITION_MIN_SPAN_MM", "POSITION_LIMIT_MM",
    "MAX_SENSORS", "MAX_POSITIONS", "MAX_MEASUREMENTS", "MAX_FILE_BYTES",
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
#: once per position, and the SVR search's time grows with the square of the measurements.
MAX_SENSORS = 100
MAX_POSITIONS = 500
MAX_MEASUREMENTS = 1000
#: A file larger than this is refused before it is read (errors.csv at the limits above, 500 000
#: rows, takes about 15 MB).
MAX_FILE_BYTES = 100_000_000


class DataFormatError(ValueError):
    """A measurement file breaks the CSV schema; the message names the file and the problem."""


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
    """

    index: pd.DataFrame
    temperatures: pd.DataFrame
    errors: np.ndarray
    positions_mm: np.ndarray
    feeds: dict = field(default_factory=dict)
    source: str = ""

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
        """
        experiments = [int(e) for e in np.atleast_1d(experiments)]
        unknown = sorted(set(experiments) - set(self.experiments))
        if unknown:
            raise ValueError(f"unknown experiment(s) {unknown}; the data have {self.experiments}")
        m = self.index.experiment.isin(experiments).to_numpy()
        return ThermalData(self.index[m].reset_index(drop=True),
                           self.temperatures[m].reset_index(drop=True), self.errors[m],
                           self.positions_mm,
                           {e: f for e, f in self.feeds.items() if e in experiments}, self.source)

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


# Line numbers.  pandas numbers the rows it keeps, not the file's lines: it skips blank lines
# and a quoted field may hold line breaks.  Every message about a bad row names the line an
# editor shows, from :func:`mtaccuracy.csvlines.records` (the schema has no comment lines).  It
# runs only when a message is written, so reading a good file costs nothing extra.


def _records(path: Path):
    """The file's records with their lines (:func:`mtaccuracy.csvlines.records`), the header
    first."""
    return csvlines.records(path.read_bytes().decode("utf-8-sig", errors="replace"))


def _line_numbers(path: Path, rows) -> list[int]:
    """The file's line numbers (1-based, as an editor shows them) of data rows ``rows``
    (positions in the table pandas read, header excluded), in the order given."""
    wanted = {int(r) for r in rows}
    found: dict[int, int] = {}
    records = _records(path)
    with contextlib.suppress(csvlines.CSVLineError):
        next(records, None)                          # the header
        for row, rec in enumerate(records):
            if row in wanted:
                found[row] = rec.first
                if len(found) == len(wanted):
                    break
    return [found.get(int(r), -1) for r in rows]


def _lines(path: Path, mask) -> str:
    """The file's line numbers of the data rows where ``mask`` holds, at most ten shown."""
    rows = np.flatnonzero(np.asarray(mask))
    return f"{_line_numbers(path, rows[:10])}{' ...' if len(rows) > 10 else ''}"


def _unreadable(path: Path, exc: Exception) -> DataFormatError:
    """The message for a file pandas cannot tokenise or decode, naming the line at fault (the
    line pandas names counts records, not lines)."""
    if isinstance(exc, UnicodeDecodeError):
        data = path.read_bytes()
        try:
            data.decode("utf-8")
        except UnicodeDecodeError as e:
            return _problem(path, f"not UTF-8 text: byte 0x{data[e.start]:02x} on line "
                                  f"{csvlines.bad_byte_line(data, e)}; save the file as UTF-8")
    if isinstance(exc, pd.errors.ParserError):
        problem = _ragged(path)
        if problem is not None:
            return problem
    return _problem(path, f"not a readable CSV file ({exc})")


def _ragged(path: Path) -> DataFormatError | None:
    """The first row with more fields than the header, or a quote never closed (None if
    neither)."""
    records = _records(path)
    try:
        header = next(records, None)
        for line, _, fields in records:
            if header is not None and len(fields) > len(header.fields):
                return _problem(path, f"line {line} has {len(fields)} fields, the header (line "
                                      f"{header.first}) has {len(header.fields)}")
    except csvlines.UnclosedQuote as exc:
        return _problem(path, f"a quoted field of the row starting on line {exc.line} is never "
                              f"closed (a '\"' is missing)")
    except csvlines.CSVLineError:
        return None
    return None


def _read_csv(path: Path, on_read=None) -> pd.DataFrame:
    """Read one file of the schema as text; its data rows are numbered by position (the file's
    line numbers of any of them: :func:`_line_numbers`)."""
    if not path.exists():
        raise _problem(path, "file not found (the schema needs temperatures.csv and errors.csv; "
                             "see data/thermal/README.md)")
    size = path.stat().st_size
    if size > MAX_FILE_BYTES:
        raise _problem(path, f"{size} bytes; files up to {MAX_FILE_BYTES} bytes are read (the "
                             f"size limits of the schema need far less)")
    try:
        df = pd.read_csv(path, dtype=str, keep_default_na=False, skipinitialspace=True)
        if on_read is not None:
            on_read(path)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise _unreadable(path, exc) from None
    if not isinstance(df.index, pd.RangeIndex):
        # pandas takes a first data row with more fields than the header as the sign of an
        # index column and shifts every column; the schema has none
        raise _ragged(path) or _problem(path, "has more fields in its rows than in its header")
    df.columns = [c.strip() for c in df.columns]
    if df.empty:
        raise _problem(path, "has a header but no data rows")
    return df


def _check_units(path, columns, quantity: str, expected: str) -> None:
    """Refuse a column that names ``quantity`` in another unit than ``expected``."""
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
        raise _problem(path, f"missing column(s) {missing}; found {list(df.columns)}")


def _numeric(path, df, column, integer=False) -> np.ndarray:
    text = df[column].str.strip()
    values = pd.to_numeric(text, errors="coerce")
    bad = (values.isna() | ~np.isfinite(values.fillna(0.0))).to_numpy()
    if bad.any():
        shown = ", ".join(repr(t) for t in text[bad].head(3))
        raise _problem(path, f"column {column!r} has a missing, NaN or non-numeric value "
                             f"({shown}) on line(s) {_lines(path, bad)}")
    out = values.to_numpy(dtype=float)
    if integer:
        if not np.all(out == np.round(out)):
            raise _problem(path, f"column {column!r} must hold whole numbers (line(s) "
                                 f"{_lines(path, out != np.round(out))})")
        return out.astype(int)
    return out


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


def read_measurements(folder, on_read=None) -> ThermalData:
    """Read and validate ``temperatures.csv``, ``errors.csv`` (and ``experiments.csv`` if there).

    The schema (``data/thermal/README.md``):

    * ``temperatures.csv``: ``experiment, measurement, time_min, <sensor>_degC ...`` one row per
      measurement, in any row order; at least three sensors.
    * ``errors.csv``: ``experiment, measurement, position_mm, error_um`` one row per target
      position and measurement; every measurement has the same target positions.
    * ``experiments.csv`` (optional): ``experiment, feed_mm_per_min`` (other columns ignored),
      each experiment once.

    Raises :class:`DataFormatError` naming the file and the problem: a missing file or column,
    a column in other units (``error_mm``, ``T1_K``), a missing/NaN/non-numeric value, a value
    outside its unit's plausible range (:data:`TEMPERATURE_RANGE_C`, :data:`ERROR_LIMIT_UM`,
    :data:`ERROR_MIN_SPAN_UM`, :data:`POSITION_MIN_SPAN_MM`, :data:`POSITION_LIMIT_MM`: kelvin
    under ``_degC``, mm or nm under ``_um``), times that do not increase with the measurement
    number, duplicated or unmatched measurements or experiments, measurements of unequal
    length, re-zeroed measurements (every measurement of an experiment reading exactly 0 at
    one target, see :func:`_check_zeroing`), or more data than :data:`MAX_SENSORS`,
    :data:`MAX_POSITIONS`, :data:`MAX_MEASUREMENTS`.

    Parameters
    ----------
    folder : path
        The folder holding the files.
    on_read : callable, optional
        Called as ``on_read(path)`` for every file read (the compendium passes
        ``provenance.track`` to hash its inputs).

    Returns
    -------
    ThermalData
        n measurements (rows sorted by experiment, measurement), S sensors, P positions.

    Raises
    ------
    DataFormatError
        Naming the file and the problem; a problem of some rows names their lines as an
        editor shows them (1-based, blank lines and line breaks inside quoted fields counted).
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise DataFormatError(f"{folder}: not a folder (data_dir must name a folder holding "
                              f"{TEMPERATURES_FILE} and {ERRORS_FILE})")
    tp, ep, xp = folder / TEMPERATURES_FILE, folder / ERRORS_FILE, folder / EXPERIMENTS_FILE

    t = _read_csv(tp, on_read)
    _check_units(tp, t.columns, "time", "time_min")
    _require(tp, t, ["experiment", "measurement", "time_min"])
    rest = [c for c in t.columns if c not in ("experiment", "measurement", "time_min")]
    for c in rest:
        if not c.endswith(_TEMP_UNIT):
            unit = c.rsplit("_", 1)[1] if "_" in c else "no unit"
            raise _problem(tp, f"column {c!r}: temperatures must be in degrees Celsius, named "
                               f"<sensor>{_TEMP_UNIT} (found {unit!r})")
    if len(rest) < 3:
        raise _problem(tp, f"needs at least 3 temperature columns <sensor>{_TEMP_UNIT}, "
                           f"found {len(rest)}")
    _check_size(tp, "temperature columns", len(rest), MAX_SENSORS,
                "the fuzzy clustering holds n_sensors**3 numbers")
    _check_size(tp, "measurements (rows)", len(t), MAX_MEASUREMENTS,
                "the SVR search's time grows with the square of the measurements")
    t_exp = _numeric(tp, t, "experiment", integer=True)
    t_meas = _numeric(tp, t, "measurement", integer=True)
    t_time = _numeric(tp, t, "time_min")
    temps = pd.DataFrame({c[:-len(_TEMP_UNIT)]: _numeric(tp, t, c) for c in rest})
    lo, hi = TEMPERATURE_RANGE_C
    for c in rest:
        _check_range(tp, c, temps[c[:-len(_TEMP_UNIT)]].to_numpy(), lo, hi, "degC",
                     "the range of a machine shop's air, structure, drives and motors; "
                     "kelvin? (degC = K - 273.15)")
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
    temps = temps.loc[order].reset_index(drop=True)
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

    er = _read_csv(ep, on_read)
    _check_units(ep, er.columns, "position", "position_mm")
    _check_units(ep, er.columns, "error", "error_um")
    _require(ep, er, ["experiment", "measurement", "position_mm", "error_um"])
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
        raise _problem(ep, f"experiment {int(r.experiment)} measurement {int(r.measurement)} "
                           f"lists position {r.position_mm:g} mm twice "
                           f"(lines {_lines(ep, twice)})")
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
        _check_units(xp, x.columns, "feed", "feed_mm_per_min")
        _require(xp, x, ["experiment", "feed_mm_per_min"])
        x_exp = _numeric(xp, x, "experiment", integer=True)
        x_feed = _numeric(xp, x, "feed_mm_per_min")
        dup = pd.Series(x_exp).duplicated(keep=False).to_numpy()
        if dup.any():
            twice = sorted(set(x_exp[dup].tolist()))
            raise _problem(xp, f"experiment(s) {twice} listed more than once (lines "
                               f"{_lines(xp, dup)}); each experiment needs one row")
        feeds = dict(zip(x_exp.tolist(), x_feed.tolist(), strict=True))
    return ThermalData(keys, temps, errors, positions, feeds, source=str(folder))


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
        The table.
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


def write_measurements(data: ThermalData, folder, temperature_decimals: int = 2,
                       error_decimals: int = 3, save=None, before_overwrite=None) -> list[Path]:
    """Write ``data`` in the schema of :func:`read_measurements`.

    Every table is formatted first; a file whose bytes would not change is not touched.

    Parameters
    ----------
    data : ThermalData
        The measurements.
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
