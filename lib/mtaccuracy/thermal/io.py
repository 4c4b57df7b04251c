"""Reading and writing the thermal measurements of one axis (``data/thermal/README.md``).

:func:`read_measurements` reads and validates the three files of a folder, each by its own
reader (``temperatures.csv``: :func:`_read_temperatures`, ``errors.csv``: :func:`_read_errors`,
``experiments.csv``: :func:`_read_experiments`), then checks them against one another; it
raises a :class:`~mtaccuracy.thermal.schema.DataFormatError` naming the file and the problem for
anything malformed and warns (:class:`~mtaccuracy.thermal.schema.DroppedSensorWarning`,
:class:`~mtaccuracy.thermal.schema.IgnoredColumnWarning`) about what it sets aside.
:func:`write_measurements` writes them, :func:`save_csv` any table with fixed bytes.  The
schema's names and limits are :mod:`~mtaccuracy.thermal.schema`'s, its checks
:mod:`~mtaccuracy.thermal.checks`', the reading of one CSV file
:mod:`~mtaccuracy.thermal.csvfile`'s.  Written by hand: the schema is ours.

Units: positions in mm, errors in um, temperatures in degrees Celsius, times in minutes.
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

from .. import validate
from .checks import (
    _check_listed,
    _check_range,
    _check_size,
    _check_span,
    _check_units,
    _check_zeroing,
    _constant,
    _require,
    _temperature_columns,
)
from .csvfile import (
    _is_number_column,
    _line_numbers,
    _lines,
    _numeric,
    _parse,
    _read_csv,
    _source,
    _where,
)
from .data import ThermalData
from .labexport import _timestamps, layout, read_lab_export
from .schema import (
    _TEMP_UNIT,
    ERROR_LIMIT_UM,
    ERROR_MIN_SPAN_UM,
    ERRORS_FILE,
    EXPERIMENTS_FILE,
    MAX_MEASUREMENTS,
    MAX_POSITIONS,
    MAX_SENSORS,
    MIN_SENSORS,
    POSITION_LIMIT_MM,
    POSITION_MIN_SPAN_MM,
    TEMPERATURE_RANGE_C,
    TEMPERATURES_FILE,
    DataFormatError,
    DroppedSensorWarning,
    IgnoredColumnWarning,
    _problem,
)

__all__ = ["read_measurements", "write_measurements", "save_csv"]


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


def _read_temperatures(tp: Path, on_read):
    """Read and check ``temperatures.csv``.

    Returns the keys ``experiment, measurement, time_min`` (sorted by experiment and
    measurement), the working sensors' temperatures in that order, the experiment and
    measurement of each row as the file has them, the sensor columns (name -> column), the
    dead sensors (name -> why, column order) and the columns ignored (column -> why).
    """
    t = _read_csv(tp, on_read)
    stamped = "timestamp" in t.columns
    if stamped and "time_min" in t.columns:
        raise _problem(tp, "holds both 'time_min' and 'timestamp': give the time once (delete "
                           "one column)")
    if "time_min" not in t.columns and not stamped:
        _check_units(tp, t.columns, "time", "time_min")
    _require(tp, t, ["experiment", "measurement", "timestamp" if stamped else "time_min"])
    sensors, ignored_t = _temperature_columns(tp, t)
    if len(sensors) < MIN_SENSORS:
        raise _problem(tp, f"needs at least {MIN_SENSORS} temperature columns "
                           f"<sensor>{_TEMP_UNIT}, found {len(sensors)}")
    _check_size(tp, "temperature columns", len(sensors), MAX_SENSORS,
                "the fuzzy clustering holds n_sensors**3 numbers")
    _check_size(tp, "measurements (rows)", len(t), MAX_MEASUREMENTS,
                "the SVR search's time grows with the measurements")
    t_exp = _numeric(tp, t, "experiment", integer=True)
    t_meas = _numeric(tp, t, "measurement", integer=True)
    if stamped:                                      # minutes since each experiment's first
        col = list(t.columns).index("timestamp")
        blank = t["timestamp"].isna().to_numpy()
        if blank.any():
            where = _where(tp, np.flatnonzero(blank)[:10], col)
            raise _problem(tp, f"column 'timestamp' is empty on line(s) "
                               f"{[ln for ln, _ in where]}")
        stamps, _ = _timestamps(tp, t["timestamp"],
                                lambda i: f"line {_line_numbers(tp, [i])[0]}")
        first = pd.DataFrame({"e": t_exp, "m": t_meas, "t": stamps}).sort_values(
            ["e", "m"], kind="stable").groupby("e").t.transform("first")
        t_time = ((stamps - first.sort_index().to_numpy()) / np.timedelta64(1, "s") / 60.0)
    else:
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
    return keys, temps, t_exp, t_meas, sensors, dead, ignored_t


def _read_errors(ep: Path, on_read):
    """Read and check ``errors.csv``.

    Returns the errors as a long table (``experiment, measurement, position_mm, error_um``, file
    order), the number of positions of each measurement, the target positions (ascending) and
    the columns ignored.
    """
    er = _read_csv(ep, on_read)
    for quantity, expected in (("position", "position_mm"), ("error", "error_um")):
        if expected not in er.columns:
            _check_units(ep, er.columns, quantity, expected)
    error_columns = ["experiment", "measurement", "position_mm", "error_um"]
    _require(ep, er, error_columns)
    ignored = [c for c in er.columns if c not in error_columns]
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
        hint = (f"; the reader ignores column(s) {ignored}: it reads one error per target "
                f"and measurement (a bidirectional measurement: keep one direction, or the "
                f"mean of both, per target)" if ignored else "")
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
    return long, sizes, positions, ignored


def _read_experiments(xp: Path, on_read, experiments: set, files: str):
    """Read and check ``experiments.csv`` against the experiments of the data (in ``files``).

    Returns the feeds (experiment -> mm/min) and the columns ignored.
    """
    x = _read_csv(xp, on_read)
    if "feed_mm_per_min" not in x.columns:
        _check_units(xp, x.columns, "feed", "feed_mm_per_min")
    _require(xp, x, ["experiment", "feed_mm_per_min"])
    ignored = [c for c in x.columns if c not in ("experiment", "feed_mm_per_min")]
    x_exp = _numeric(xp, x, "experiment", integer=True)
    x_feed = _numeric(xp, x, "feed_mm_per_min")
    dup = pd.Series(x_exp).duplicated(keep=False).to_numpy()
    if dup.any():
        twice = sorted(set(x_exp[dup].tolist()))
        raise _problem(xp, f"experiment(s) {twice} listed more than once (lines "
                           f"{_lines(xp, dup)}); each experiment needs one row")
    _check_listed(xp, x_exp, experiments, files)
    return dict(zip(x_exp.tolist(), x_feed.tolist(), strict=True)), ignored


def read_measurements(folder, on_read=None) -> ThermalData:
    """Read and validate a folder of thermal measurements: the schema's files or a lab export.

    A folder holds one of two layouts (``data/thermal/README.md``; one holding both, or
    neither, is refused with the fix: :func:`~mtaccuracy.thermal.labexport.layout`):

    * a **lab export**, per experiment ``<experiment>_temperatures.csv`` (a logger's
      ``timestamp`` and ``<sensor> [°C]`` columns, short gaps interpolated) and
      ``<experiment>_laser.csv`` (``target_mm`` and one column per run headed by its
      timestamp): :func:`~mtaccuracy.thermal.labexport.read_lab_export`, with an optional
      ``experiments.csv``;
    * the **schema**, ``temperatures.csv``, ``errors.csv`` (and ``experiments.csv`` if there),
      as follows.

    The schema:

    * ``temperatures.csv``: ``experiment, measurement, time_min, <sensor>_degC ...`` one row per
      measurement, in any row order; at least :data:`MIN_SENSORS` working sensors.  A
      ``timestamp`` column (ISO 8601) may stand for ``time_min`` (which is then counted from
      each experiment's first measurement), and ``<sensor> [°C]`` for ``<sensor>_degC``.
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
    a column in other units (``error_mm``, ``T1_K``, ``T1_degF``, ``T1_C``), a column of
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
        Holds ``temperatures.csv``, ``errors.csv`` and, optionally, ``experiments.csv``; or a
        lab export.
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
    InterpolatedGapWarning
        A lab export only: once per sensor and logger file with short gaps, naming the lines.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise DataFormatError(f"{folder}: not a folder (data_dir must name a folder holding "
                              f"{TEMPERATURES_FILE} and {ERRORS_FILE}, or a lab export)")
    tp, ep, xp = (_source(folder / n) for n in (TEMPERATURES_FILE, ERRORS_FILE,
                                                EXPERIMENTS_FILE))
    if layout(folder) == "lab":
        data = read_lab_export(folder, on_read)
        if not xp.exists():
            return data
        feeds, ignored_x = _read_experiments(xp, on_read, set(data.experiments),
                                             "the lab export")
        if ignored_x:
            warnings.warn(f"{xp}: column(s) {ignored_x} ignored: not part of the schema, which "
                          f"reads experiment, feed_mm_per_min (data/thermal/README.md)",
                          IgnoredColumnWarning, stacklevel=2)
        return ThermalData(data.index, data.temperatures, data.errors, data.positions_mm, feeds,
                           data.source, data.dropped,
                           {**data.ignored_columns, **{c: f"{xp.name}: not part of the schema"
                                                       for c in ignored_x}}, data.filled)

    keys, temps, t_exp, t_meas, sensors, dead, ignored_t = _read_temperatures(tp, on_read)
    ignored = {tp: list(ignored_t)}
    long, sizes, positions, ignored[ep] = _read_errors(ep, on_read)

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
        feeds, ignored[xp] = _read_experiments(xp, on_read, set(keys.experiment.tolist()),
                                               f"{tp.name} and {ep.name}")

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
