"""Reading thermal data as a lab exports them: a logger file and a laser file per experiment.

The layout (``data/thermal/README.md``, "A lab export"): per experiment
``<experiment>_temperatures.csv`` (a ``timestamp`` column in ISO 8601, then one column per
sensor, ``<sensor> [°C]`` or ``<sensor>_degC``, logged at any rate; blank or NaN cells allowed)
and ``<experiment>_laser.csv`` (``target_mm``, then one column of errors in um per measurement
run, headed by the run's ISO 8601 timestamp).  :func:`read_lab_export` turns them into the
:class:`~mtaccuracy.thermal.data.ThermalData` the schema's reader gives:

* **experiment numbers** from ``<experiment>``: a number, optionally after letters and one
  ``_``, ``-`` or space (``1``, ``exp2``, ``E03``, ``run_4``: experiments 1, 2, 3, 4); two
  names giving one number (``exp1`` and ``E01``), or a name that is not of this form
  (``2024-03-15``), is refused with the fix (:func:`experiment_number`);
* **measurements** are the runs in time order, numbered 1, 2, ... within an experiment;
  ``time_min`` counts from the experiment's first run (so measurement 1 is at 0 min, as in the
  schema and the paper, and the logger's own start, which varies with when someone pressed
  record, changes nothing);
* **temperatures at a run** are interpolated linearly in time between the two logger samples
  around the run's timestamp (a run outside the logged span is refused, naming it); linear
  interpolation over a sampling interval h misses a smooth temperature by at most
  ``h**2 / 8 * max|T''|``;
* **gaps** (blank or NaN cells of a sensor): a short one (the readings around it at most
  :data:`~mtaccuracy.thermal.schema.SHORT_GAP_MIN` apart) is interpolated linearly in time and
  named in an :class:`~mtaccuracy.thermal.schema.InterpolatedGapWarning` (sensor, experiment,
  file, lines); a longer one, or one at the start or end of the log, drops the sensor with a
  :class:`~mtaccuracy.thermal.schema.DroppedSensorWarning` (the same words).

The files are read through the schema's CSV reader (:mod:`~mtaccuracy.thermal.csvfile`: one
read through :func:`mtaccuracy.validate.file_bytes`, comma or semicolon with decimal commas,
messages naming the lines an editor shows); the schema's checks apply to what comes out.
Written by hand: the layout is ours.

Units: positions in mm, errors in um, temperatures in degrees Celsius, times in minutes.
"""

from __future__ import annotations

import os
import re
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

from .checks import (
    _check_range,
    _check_size,
    _check_span,
    _check_zeroing,
    _constant,
    _require,
    _temperature_columns,
)
from .csvfile import (
    _UNNAMED,
    MAX_WHOLE,
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
from .schema import (
    ERROR_LIMIT_UM,
    ERROR_MIN_SPAN_UM,
    ERRORS_FILE,
    LAB_LASER_SUFFIX,
    LAB_TEMPERATURES_SUFFIX,
    MAX_MEASUREMENTS,
    MAX_POSITIONS,
    MAX_SENSORS,
    MIN_SENSORS,
    POSITION_LIMIT_MM,
    POSITION_MIN_SPAN_MM,
    SHORT_GAP_MIN,
    TEMPERATURE_RANGE_C,
    TEMPERATURES_FILE,
    DataFormatError,
    DroppedSensorWarning,
    InterpolatedGapWarning,
    _problem,
)

__all__ = ["read_lab_export", "layout", "experiment_number"]

#: ``<experiment>``: a number, optionally after letters and one separator.
_NAME = re.compile(r"(?:[A-Za-z]+[ _-]?)?(\d+)")
#: A time-zone designator at the end of an ISO 8601 timestamp.
_ZONE = re.compile(r"(?:Z|[+-]\d\d(?::?\d\d)?)$")
_FIX_NAMES = ("name each pair <experiment>_temperatures.csv and <experiment>_laser.csv, "
              "<experiment> a number, optionally after letters (1, exp2, E03)")


def experiment_number(name: str) -> int:
    """The experiment number of a lab export's ``<experiment>`` (``exp2`` -> 2).

    Parameters
    ----------
    name : str
        The file name's part before ``_temperatures.csv`` or ``_laser.csv``.

    Returns
    -------
    int
        The number after the optional letters (leading zeros dropped: ``E03`` -> 3).

    Raises
    ------
    DataFormatError
        When the name is not a number, optionally after letters and one ``_``, ``-`` or space,
        or its number is 0 (notebook 04 reads experiment 0 as "the last") or has more than 9
        digits (named as written).
    """
    m = _NAME.fullmatch(name)
    if m is None:
        raise DataFormatError(f"{name!r}: cannot tell its experiment number; {_FIX_NAMES}")
    digits = m.group(1).lstrip("0")
    if len(digits) > len(str(MAX_WHOLE)):
        raise DataFormatError(f"{name!r}: experiment number {m.group(1)} is too large; numbers "
                              f"have at most {len(str(MAX_WHOLE))} digits")
    if not digits:
        raise DataFormatError(f"{name!r}: experiment number 0; number experiments from 1 "
                              f"(notebook 04 reads experiment 0 as 'the last')")
    return int(digits)


def _lab_names(names) -> tuple[list[str], list[str]]:
    """The stems of the logger and laser files among ``names``."""
    temps = sorted(n[:-len(LAB_TEMPERATURES_SUFFIX)] for n in names
                   if n.endswith(LAB_TEMPERATURES_SUFFIX) and n != LAB_TEMPERATURES_SUFFIX)
    laser = sorted(n[:-len(LAB_LASER_SUFFIX)] for n in names
                   if n.endswith(LAB_LASER_SUFFIX) and n != LAB_LASER_SUFFIX)
    return temps, laser


def layout(folder) -> str:
    """Which layout a folder holds: ``"schema"`` or ``"lab"``; refused when both or neither.

    Parameters
    ----------
    folder : path
        A folder (only its file names are looked at).

    Returns
    -------
    str
        ``"schema"`` (``temperatures.csv``, ``errors.csv``) or ``"lab"`` (pairs of
        ``<experiment>_temperatures.csv`` and ``<experiment>_laser.csv``).

    Raises
    ------
    DataFormatError
        Naming the files of each layout found and the fix.
    """
    folder = Path(folder)
    names = sorted(os.listdir(folder))
    schema = [n for n in (TEMPERATURES_FILE, ERRORS_FILE) if n in names]
    temps, laser = _lab_names(names)
    lab = [s + LAB_TEMPERATURES_SUFFIX for s in temps] + [s + LAB_LASER_SUFFIX for s in laser]
    if schema and lab:
        raise DataFormatError(
            f"{folder}: holds both the schema's file(s) {schema} and a lab export's "
            f"{lab[:4]}{' ...' if len(lab) > 4 else ''}: keep one layout per folder (move the "
            f"other files elsewhere; data/thermal/README.md)")
    if lab:
        return "lab"
    if schema:
        return "schema"
    raise DataFormatError(
        f"{folder}: holds neither the schema's {TEMPERATURES_FILE} and {ERRORS_FILE} nor a lab "
        f"export (<experiment>{LAB_TEMPERATURES_SUFFIX} and <experiment>{LAB_LASER_SUFFIX} per "
        f"experiment); found {names[:8]}{' ...' if len(names) > 8 else ''} "
        f"(data/thermal/README.md)")


def _pairs(folder: Path) -> dict[int, tuple[str, Path, Path]]:
    """Experiment -> (name, logger file, laser file), every file paired and every number once."""
    temps, laser = _lab_names(os.listdir(folder))
    lonely = ([s + LAB_TEMPERATURES_SUFFIX for s in temps if s not in laser]
              + [s + LAB_LASER_SUFFIX for s in laser if s not in temps])
    if lonely:
        raise DataFormatError(f"{folder}: {lonely} without its partner; every experiment needs "
                              f"both files ({_FIX_NAMES})")
    out: dict[int, tuple[str, Path, Path]] = {}
    for stem in temps:
        try:
            e = experiment_number(stem)
        except DataFormatError as exc:
            raise DataFormatError(f"{folder / (stem + LAB_TEMPERATURES_SUFFIX)}: {exc}") from None
        if e in out:
            raise DataFormatError(
                f"{folder}: {out[e][0]!r} and {stem!r} both name experiment {e}; give every "
                f"experiment its own number (delete or rename one pair)")
        out[e] = (stem, _source(folder / (stem + LAB_TEMPERATURES_SUFFIX)),
                  _source(folder / (stem + LAB_LASER_SUFFIX)))
    return dict(sorted(out.items()))


def _timestamps(path: Path, texts, where) -> tuple[np.ndarray, bool]:
    """ISO 8601 texts as datetime64 (UTC when they carry a zone) and whether they do.

    ``where(i)`` says where text ``i`` stands (its line or column), for the messages.
    """
    texts = pd.Series(texts, dtype=object).astype(str).str.strip()
    zoned = texts.str.contains(_ZONE).to_numpy()
    if zoned.any() and not zoned.all():
        i = int(np.flatnonzero(zoned != zoned[0])[0])
        raise _problem(path, f"timestamp {texts.iloc[i]!r} ({where(i)}) "
                             f"{'carries' if zoned[i] else 'lacks'} a time zone, the first "
                             f"({texts.iloc[0]!r}) {'does' if zoned[0] else 'does not'}: write "
                             f"every timestamp with its zone (2024-03-15T10:00:00+01:00) or none")
    t = pd.to_datetime(texts, format="ISO8601", errors="coerce", utc=bool(zoned.all()))
    if zoned.all():
        t = t.dt.tz_localize(None)
    bad = np.flatnonzero(t.isna().to_numpy())
    if bad.size:
        raise _problem(path, f"{texts.iloc[bad[0]]!r} ({where(int(bad[0]))}) is not an ISO 8601 "
                             f"timestamp (write e.g. 2024-03-15T10:00:00 or 2024-03-15 10:00:00)")
    return t.to_numpy(dtype="datetime64[ns]"), bool(zoned.all())


def _minutes(t: np.ndarray, origin) -> np.ndarray:
    """Minutes of datetime64 ``t`` after ``origin``."""
    return (t - origin) / np.timedelta64(1, "s") / 60.0


def _gaps(missing: np.ndarray) -> np.ndarray:
    """The gaps of a mask, as (first, last) sample indices (inclusive), shape (g, 2)."""
    d = np.diff(np.concatenate([[0], missing.astype(np.int8), [0]]))
    return np.column_stack([np.flatnonzero(d == 1), np.flatnonzero(d == -1) - 1])


def _logger(tp: Path, experiment: int, on_read):
    """One logger file: times (datetime64), readings (sensor -> array with gaps filled), the
    sensors dropped (sensor -> why), the gaps filled (sensor -> where), the sensor columns and
    whether the timestamps carry a zone."""
    df = _read_csv(tp, on_read)
    if "timestamp" not in df.columns:
        hint = ("; time_min belongs to the schema's temperatures.csv, whose rows are "
                "measurements: a logger file needs its timestamps" if "time_min" in df.columns
                else "")
        _require(tp, df, ["timestamp"])          # the message names what was found
        raise _problem(tp, f"missing column 'timestamp'{hint}")  # pragma: no cover
    sensors, ignored = _temperature_columns(tp, df, keys=("timestamp",))
    _check_size(tp, "temperature columns", len(sensors), MAX_SENSORS,
                "the fuzzy clustering holds n_sensors**3 numbers")
    col = list(df.columns).index("timestamp")
    stamps = df["timestamp"]
    if stamps.isna().any():
        rows = np.flatnonzero(stamps.isna().to_numpy())
        raise _problem(tp, f"column 'timestamp' is empty on line(s) "
                           f"{[ln for ln, _ in _where(tp, rows[:10], col)]}: every logged "
                           f"sample needs its time")
    t, zoned = _timestamps(tp, stamps, lambda i: f"line {_line_numbers(tp, [i])[0]}")
    back = np.flatnonzero(np.diff(t) <= np.timedelta64(0, "ns"))
    if back.size:
        a, b = _line_numbers(tp, [back[0], back[0] + 1])
        raise _problem(tp, f"timestamps must increase: line {b} ({stamps.iloc[back[0] + 1]}) "
                           f"does not come after line {a} ({stamps.iloc[back[0]]}); sort the "
                           f"samples by time and delete repeated ones")
    minutes = _minutes(t, t[0])
    sep = df.attrs.get("separator", ",")
    readings, dropped, filled = {}, {}, {}
    for name, c in sensors.items():
        s = df[c]
        values = s.to_numpy(dtype=float) if _is_number_column(s) else _parse(s, sep)
        missing = ~np.isfinite(values)
        if not _is_number_column(s):                 # text other than blank or NaN: refused
            text = s.astype(str).str.strip().str.lower()
            wrong = np.flatnonzero(missing & s.notna().to_numpy() & (text != "nan").to_numpy())
            if wrong.size:
                where = _where(tp, wrong[:10], list(df.columns).index(c))
                raise _problem(tp, f"column {c!r} holds {where[0][1]!r}, not a number, on "
                                   f"line(s) {[ln for ln, _ in where]}"
                                   f"{' ...' if wrong.size > 10 else ''}; a logger's gap is a "
                                   f"blank or NaN cell (interpolated when short), anything else "
                                   f"is refused")
        if missing.all():
            dropped[name] = "holds no reading (every cell is empty or NaN)"
            continue
        gaps = _gaps(missing)
        if gaps.size:
            before, after = gaps[:, 0] - 1, gaps[:, 1] + 1
            inside = (before >= 0) & (after < len(values))
            span = np.where(inside, minutes[np.clip(after, 0, len(values) - 1)]
                            - minutes[np.clip(before, 0, len(values) - 1)], np.inf)
            lines = _line_numbers(tp, gaps.ravel()[:20])
            where = [f"line{'s' if a != b else ''} {a}{f'-{b}' if a != b else ''}"
                     for a, b in zip(lines[::2], lines[1::2], strict=True)]
            long = np.flatnonzero(span > SHORT_GAP_MIN)
            if long.size:
                i = int(long[0])
                why = ("at the start of the log" if before[i] < 0 else "at the end of the log"
                       if after[i] >= len(values) else
                       f"the readings around it lie {span[i]:g} min apart")
                dropped[name] = (f"experiment {experiment}: a gap of {gaps[i, 1] - gaps[i, 0] + 1} "
                                 f"missing sample(s) on {where[i] if i < len(where) else 'lines'} "
                                 f"({why}; gaps up to {SHORT_GAP_MIN:g} min between readings "
                                 f"are interpolated, a longer one loses the sensor's course)")
                continue
            values = values.copy()
            values[missing] = np.interp(minutes[missing], minutes[~missing], values[~missing])
            filled[name] = (f"experiment {experiment}: {int(missing.sum())} missing sample(s) on "
                            f"{', '.join(where[:10])}{' ...' if len(gaps) > 10 else ''} "
                            f"interpolated linearly in time (the readings around each gap at "
                            f"most {span.max():g} min apart)")
        readings[name] = values
    lo, hi = TEMPERATURE_RANGE_C
    for name, v in readings.items():
        _check_range(tp, sensors[name], v, lo, hi, "degC",
                     "the range of a machine shop's air, structure, drives and motors; "
                     "kelvin? (degC = K - 273.15)")
    return t, readings, dropped, filled, sensors, zoned, ignored


def _laser(lp: Path, on_read):
    """One laser file: target positions (file order), run timestamps, errors (runs, targets),
    whether the timestamps carry a zone, the run columns."""
    df = _read_csv(lp, on_read)
    _require(lp, df, ["target_mm"])
    runs = [c for c in df.columns if c != "target_mm"
            and not (c.startswith(_UNNAMED.format("")[:-1]) and df[c].isna().all())]
    if len(runs) < 2:
        raise _problem(lp, f"{len(runs)} measurement run(s); at least 2 are needed (one column "
                           f"per run after target_mm, headed by its ISO 8601 timestamp)")
    names = list(df.columns)
    t, zoned = _timestamps(lp, runs, lambda i: f"the header of column {names.index(runs[i]) + 1}"
                           f"; head every run's column with its ISO 8601 timestamp")
    pos = _numeric(lp, df, "target_mm")
    dup = pd.Series(pos).duplicated(keep=False).to_numpy()
    if dup.any():
        raise _problem(lp, f"target {pos[dup][0]:g} mm listed twice (lines {_lines(lp, dup)}); "
                           f"one row per target")
    errors = np.column_stack([_numeric(lp, df, c) for c in runs]).T
    _check_range(lp, "the runs' errors", errors.ravel(), -ERROR_LIMIT_UM, ERROR_LIMIT_UM, "um",
                 "a machine tool's positioning error; nm? (um = nm / 1000)")
    _check_range(lp, "target_mm", pos, -POSITION_LIMIT_MM, POSITION_LIMIT_MM, "mm",
                 "a machine tool's axis")
    return pos, t, errors, zoned, runs


def read_lab_export(folder, on_read=None) -> ThermalData:
    """Read a lab export (a logger and a laser file per experiment) as :class:`ThermalData`.

    See the module's description for the layout and the rules; ``data/thermal/README.md``
    documents them for a reader.

    Parameters
    ----------
    folder : path
        Holds ``<experiment>_temperatures.csv`` and ``<experiment>_laser.csv`` per experiment
        (and nothing of the schema's layout).
    on_read : callable, optional
        Called as ``on_read(path)`` for every file read.

    Returns
    -------
    ThermalData
        n runs (sorted by experiment, then time) of S sensors at P targets (ascending);
        ``filled`` names the gaps interpolated, ``dropped`` the sensors lost.

    Raises
    ------
    DataFormatError
        Naming the file and the problem (and the lines, columns or runs).

    Warns
    -----
    InterpolatedGapWarning
        Once per sensor and logger file with short gaps, naming the lines.
    DroppedSensorWarning
        Once per sensor dropped (a long gap, no reading, or never changing).
    """
    folder = Path(folder)
    pairs = _pairs(folder)
    _check_size(folder, "experiments", len(pairs), MAX_MEASUREMENTS // 2,
                "each needs at least 2 measurements")
    rows, temps, errs, dropped, filled, ignored = [], [], [], {}, {}, {}
    positions, sensor_set, first_pair = None, None, None
    for e, (_, tp, lp) in pairs.items():
        t, readings, drop_e, fill_e, sensors, zoned_t, ign = _logger(tp, e, on_read)
        pos, t_runs, errors, zoned_l, runs = _laser(lp, on_read)
        if zoned_t != zoned_l:
            raise DataFormatError(f"{tp} and {lp}: the timestamps of one carry a time zone, of "
                                  f"the other not; write both with the zone or both without")
        if sensor_set is None:
            sensor_set, first_pair = list(sensors), tp
        elif set(sensors) != set(sensor_set):
            raise DataFormatError(
                f"{tp} and {first_pair}: not the same sensors (only in {tp.name}: "
                f"{sorted(set(sensors) - set(sensor_set))}; only in {first_pair.name}: "
                f"{sorted(set(sensor_set) - set(sensors))}); log the same sensors in every "
                f"experiment")
        order = np.argsort(pos, kind="stable")
        if positions is None:
            positions = pos[order]
        elif len(pos) != len(positions) or not np.array_equal(pos[order], positions):
            raise DataFormatError(
                f"{lp}: targets {pos[order][:6].tolist()} mm differ from those of the first "
                f"experiment's laser file {positions[:6].tolist()} mm; every run needs every "
                f"target")
        outside = np.flatnonzero((t_runs < t[0]) | (t_runs > t[-1]))
        if outside.size:
            i = int(outside[0])
            raise DataFormatError(
                f"{lp}: run {runs[i]!r} lies outside the logged span of {tp.name} ({t[0]} .. "
                f"{t[-1]}); its temperatures cannot be known: log over every run (or delete "
                f"the run's column)")
        dup = pd.Series(t_runs).duplicated().to_numpy()
        if dup.any():
            raise DataFormatError(f"{lp}: run {runs[int(np.flatnonzero(dup)[0])]!r} at a time "
                                  f"another run has; one column per run")
        by_time = np.argsort(t_runs, kind="stable")
        minutes = _minutes(t_runs[by_time], t_runs[by_time][0])
        at = _minutes(t_runs[by_time], t[0])
        logged = _minutes(t, t[0])
        temps.append({name: np.interp(at, logged, v) for name, v in readings.items()})
        errs.append(errors[by_time][:, order])
        rows.append(pd.DataFrame({"experiment": e, "measurement": np.arange(1, len(runs) + 1),
                                  "time_min": minutes}))
        for name, why in drop_e.items():
            dropped.setdefault(name, (tp, sensors[name], why))
        for name, why in fill_e.items():
            filled[name] = filled.get(name, ()) + ((tp, why),)
        for c, why in ign.items():
            ignored.setdefault(c, f"{tp.name}: {why}")
    index = pd.concat(rows, ignore_index=True)
    _check_size(folder, "measurements (runs)", len(index), MAX_MEASUREMENTS,
                "the SVR search's time grows with the measurements")
    _check_size(folder, "target positions", len(positions), MAX_POSITIONS,
                "the point-by-point selection and model run once per position")
    errors = np.concatenate(errs)
    last = pairs[max(pairs)][2]
    _check_span(last, "the runs' errors (all experiments)", errors.ravel(), ERROR_MIN_SPAN_UM,
                "um", "of a positioning error measured over a warm-up; mm? (um = mm x 1000)")
    _check_span(last, "target_mm", positions, POSITION_MIN_SPAN_MM, "mm",
                "between target positions; m? (mm = m x 1000)")
    live = [s for s in sensor_set if s not in dropped]
    values = {s: np.concatenate([t_e[s] for t_e in temps]) for s in live}
    experiments = index.experiment.to_numpy()
    for name, why in _constant(values, experiments).items():
        dropped[name] = (pairs[min(pairs)][1], name, why + " at the runs")
    live = [s for s in sensor_set if s not in dropped]
    if len(live) < MIN_SENSORS:
        raise DataFormatError(
            f"{folder}: {len(live)} working sensor(s) {live} once the dead ones are dropped "
            f"({'; '.join(f'{n}: {w[2]}' for n, w in dropped.items())}); at least "
            f"{MIN_SENSORS} are needed")
    _check_zeroing(last.parent / f"<experiment>{LAB_LASER_SUFFIX}", experiments, errors,
                   positions)
    out_dropped, out_filled = {}, {}
    for name in sensor_set:
        if name in dropped:
            tp, column, why = dropped[name]
            warnings.warn(f"{tp}: sensor {name!r} (column {column!r}), {why}: dropped",
                          DroppedSensorWarning, stacklevel=3)
            out_dropped[name] = f"{tp.name}, column {column!r}: {why}"
        elif name in filled:
            for tp, why in filled[name]:
                warnings.warn(f"{tp}: sensor {name!r}, {why}", InterpolatedGapWarning,
                              stacklevel=3)
            out_filled[name] = "; ".join(f"{tp.name}: {why}" for tp, why in filled[name])
    temperatures = pd.DataFrame({s: values[s] for s in live})
    return ThermalData(index, temperatures, errors, positions, {}, source=str(folder),
                       dropped=out_dropped, ignored_columns=ignored, filled=out_filled)

