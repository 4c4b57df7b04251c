"""Thermal positioning error of a linear axis (Xu et al. 2022): data, sensitive points, models.

* :class:`ThermalData`, :func:`read_measurements`, :func:`write_measurements`: the CSV schema
  of ``data/thermal/README.md`` (read, validate, write); ours, written by hand.
* :func:`similarity_matrix`, :func:`transitive_closure`, :func:`lambda_cut`,
  :func:`fuzzy_clusters`: fuzzy equivalence clustering (Eqs. 1-3); by hand, because it is the
  paper's method and neither scipy nor scikit-learn has it.
* :func:`grey_relational_grade`, :func:`select_sensitive_points`: Deng's grade (Eq. 4) and the
  selection rule; by hand, as above.
* :func:`decouple`, :func:`compose`: the least-squares line per measurement (Eq. 6) and back
  (Eq. 7); by hand, the paper's contribution and two lines of algebra.
* :class:`PointByPoint`, :class:`Decoupled`, :func:`svr_search`: the MLR and SVR models
  (Eqs. 5, 8, 9) are scikit-learn's ``LinearRegression`` and ``SVR`` (on standardised data,
  :class:`StandardisedSVR`), hyperparameters by ``GridSearchCV`` with ``GroupKFold``; tied
  scores go to the simplest candidate (:func:`canonical_best`).
* :func:`metrics`, :func:`evaluate_split`, :func:`leave_one_experiment_out`: RMSE, largest
  residual, MAE; one train/test split; every experiment held out in turn.
* :func:`replicate_split` (with :func:`fit_linear`, :func:`batch_metrics`): the same fits with
  fixed inputs on a stack of noise replicates at once, for sampling standard errors.

Units: positions in mm, errors in um, slopes k in um/m (so ``k * x_mm / 1000`` is um), temperatures
in degrees Celsius.  The position axis is shifted to start at 0 (the paper models 185..445 mm as
0..260 mm so that the intercept b is the error at the first target).
"""

from __future__ import annotations

import hashlib
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
from sklearn import config_context
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.linear_model import LinearRegression
from sklearn.model_selection import GridSearchCV, GroupKFold
from sklearn.svm import SVR

from .compendium import provenance, reproduction

__all__ = [
    "DataFormatError", "ThermalData", "read_measurements", "write_measurements",
    "similarity_matrix", "max_min_compose", "transitive_closure", "lambda_cut", "fuzzy_clusters",
    "cut_levels", "cut_for", "LEVEL_RTOL",
    "Clustering", "normalise_range", "grey_relational_grade", "Selection",
    "select_sensitive_points", "most_frequent", "decouple", "compose", "metrics",
    "PointByPoint", "Decoupled", "svr_search", "svr_simplicity", "canonical_best",
    "tie_margin", "StandardisedSVR", "SVR_SOLVER_TOL", "evaluate_split",
    "leave_one_experiment_out", "SVR_GRID", "SVR_TIE_RTOL", "LSTSQ_TOLERANCE", "SVR_TOLERANCE",
    "fit_linear", "predict_linear", "batch_metrics", "rises_of", "replicate_split",
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

    ``temperatures`` has one column per sensor (degC), ``errors`` one row per measurement and one
    column per target position (``positions_mm``), in um.  ``feeds`` maps experiment -> feed
    (mm/min) when ``experiments.csv`` gives it.
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
        return list(self.temperatures.columns)

    @property
    def experiments(self) -> list[int]:
        return sorted(self.index.experiment.unique().tolist())

    @property
    def groups(self) -> np.ndarray:
        """The experiment of every row (for grouped cross-validation)."""
        return self.index.experiment.to_numpy()

    def subset(self, experiments) -> ThermalData:
        """The rows of the given experiments, in the stored order."""
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
        """Temperatures relative to the first measurement of each experiment (Eq. 9's T - T0)."""
        t = self.temperatures
        r = rises_of(t.to_numpy(dtype=float)[None], self.index.experiment.to_numpy())[0]
        return pd.DataFrame(r, index=t.index, columns=t.columns)

    def offsets_mm(self) -> np.ndarray:
        """Target positions shifted to start at 0 (185..445 mm -> 0..260 mm)."""
        return self.positions_mm - self.positions_mm[0]


def _problem(path, message) -> DataFormatError:
    return DataFormatError(f"{path}: {message}")


def _read_csv(path: Path) -> pd.DataFrame:
    if not path.exists():
        raise _problem(path, "file not found (the schema needs temperatures.csv and errors.csv; "
                             "see data/thermal/README.md)")
    size = path.stat().st_size
    if size > MAX_FILE_BYTES:
        raise _problem(path, f"{size} bytes; files up to {MAX_FILE_BYTES} bytes are read (the "
                             f"size limits of the schema need far less)")
    try:
        df = pd.read_csv(path, dtype=str, keep_default_na=False, skipinitialspace=True)
        provenance.track(path)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise _problem(path, f"not a readable CSV file ({exc})") from None
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
    bad = values.isna() | ~np.isfinite(values.fillna(0.0))
    if bad.any():
        rows = (np.flatnonzero(bad.to_numpy()) + 2).tolist()  # file line numbers (header = 1)
        shown = ", ".join(repr(t) for t in text[bad].head(3))
        raise _problem(path, f"column {column!r} has a missing, NaN or non-numeric value "
                             f"({shown}) on line(s) {rows[:10]}{' ...' if len(rows) > 10 else ''}")
    out = values.to_numpy(dtype=float)
    if integer:
        if not np.all(out == np.round(out)):
            rows = (np.flatnonzero(out != np.round(out)) + 2).tolist()
            raise _problem(path, f"column {column!r} must hold whole numbers (line(s) {rows[:10]})")
        return out.astype(int)
    return out


def _lines(mask) -> str:
    """File line numbers (header = line 1) of the rows where ``mask`` holds, at most ten."""
    rows = (np.flatnonzero(np.asarray(mask)) + 2).tolist()
    return f"{rows[:10]}{' ...' if len(rows) > 10 else ''}"


def _check_range(path, column, values, lo, hi, unit, hint) -> None:
    """Refuse values outside [lo, hi], naming the column, lines, values and limits."""
    bad = (values < lo) | (values > hi)
    if bad.any():
        shown = ", ".join(f"{v:g}" for v in values[bad][:3])
        raise _problem(path, f"column {column!r} has value(s) {shown} {unit} on line(s) "
                             f"{_lines(bad)}, outside the plausible range {lo:g} .. {hi:g} "
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


def read_measurements(folder) -> ThermalData:
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
    :data:`MAX_POSITIONS`, :data:`MAX_MEASUREMENTS`.  The rows come back sorted by
    (experiment, measurement).
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise DataFormatError(f"{folder}: not a folder (data_dir must name a folder holding "
                              f"{TEMPERATURES_FILE} and {ERRORS_FILE})")
    tp, ep, xp = folder / TEMPERATURES_FILE, folder / ERRORS_FILE, folder / EXPERIMENTS_FILE

    t = _read_csv(tp)
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
                         "line": np.arange(len(t)) + 2})
    dup = keys.duplicated(["experiment", "measurement"])
    if dup.any():
        r = keys[dup].iloc[0]
        raise _problem(tp, f"experiment {int(r.experiment)} measurement {int(r.measurement)} "
                           f"appears more than once (line {int(r.line)})")
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
            raise _problem(tp, f"experiment {e}: time_min must increase with the measurement "
                               f"number, but measurement {int(b.measurement)} (line "
                               f"{int(b.line)}, {b.time_min:g} min) does not come after "
                               f"measurement {int(a.measurement)} (line {int(a.line)}, "
                               f"{a.time_min:g} min); times in measurement order: "
                               f"{' -> '.join(f'{v:g}' for v in tm[:12])}"
                               f"{' ...' if len(tm) > 12 else ''}")
    keys = keys.drop(columns="line")

    er = _read_csv(ep)
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
    dup = long.duplicated(["experiment", "measurement", "position_mm"])
    if dup.any():
        r = long[dup].iloc[0]
        raise _problem(ep, f"experiment {int(r.experiment)} measurement {int(r.measurement)} "
                           f"lists position {r.position_mm:g} mm twice "
                           f"(line {int(np.flatnonzero(dup)[0]) + 2})")
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
        x = _read_csv(xp)
        _check_units(xp, x.columns, "feed", "feed_mm_per_min")
        _require(xp, x, ["experiment", "feed_mm_per_min"])
        x_exp = _numeric(xp, x, "experiment", integer=True)
        x_feed = _numeric(xp, x, "feed_mm_per_min")
        dup = pd.Series(x_exp).duplicated(keep=False).to_numpy()
        if dup.any():
            twice = sorted(set(x_exp[dup].tolist()))
            raise _problem(xp, f"experiment(s) {twice} listed more than once (lines "
                               f"{_lines(dup)}); each experiment needs one row")
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


def write_measurements(data: ThermalData, folder, temperature_decimals: int = 2,
                       error_decimals: int = 3) -> list[Path]:
    """Write ``data`` in the schema (:func:`mtaccuracy.compendium.reproduction.save_table`,
    which rewrites a file only when its bytes change).  Returns the files whose content changed."""
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
    changed = []
    for name, df, fmt in tables:
        p = folder / name
        before = p.read_bytes() if p.exists() else None
        reproduction.save_table(df, p, float_format=fmt)
        if p.read_bytes() != before:
            changed.append(p)
    return changed


# --------------------------------------------------------------------------------------------
# Temperature-sensitive points: fuzzy equivalence clustering and grey relational grade
# --------------------------------------------------------------------------------------------

def similarity_matrix(x: np.ndarray) -> np.ndarray:
    """Eq. 1: r_ij = sum_k |x_i(k) - m_i| |x_j(k) - m_j| / (||x_i - m_i|| ||x_j - m_j||).

    ``x`` is (n_samples, n_variables).  As printed, the numerator takes absolute deviations, so
    r_ij is in [0, 1] and blind to sign (a falling and a rising sensor can be similar).  The
    printed denominator has ``x_i(k) - mean_j`` under the second root, a typo for ``x_j(k)``.
    """
    x = np.asarray(x, dtype=float)
    if x.ndim != 2 or x.shape[0] < 2:
        raise ValueError(f"need (n_samples >= 2, n_variables), got shape {x.shape}")
    d = x - x.mean(axis=0)
    norm = np.sqrt((d**2).sum(axis=0))
    flat = np.flatnonzero(norm == 0)
    if flat.size:
        raise ValueError(f"variable(s) {flat.tolist()} are constant; their similarity is "
                         f"undefined (drop them)")
    a = np.abs(d)
    # summed over the samples in a fixed order, not by BLAS: equal columns give bitwise-equal
    # rows and r is exactly symmetric on every machine, so ties stay ties for the lambda cut
    r = (a[:, :, None] * a[:, None, :]).sum(axis=0) / np.outer(norm, norm)
    np.fill_diagonal(r, 1.0)
    return np.clip(r, 0.0, 1.0)


def max_min_compose(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Fuzzy (max-min) composition: (a o b)_ij = max_k min(a_ik, b_kj)."""
    return np.minimum(a[:, :, None], b[None, :, :]).max(axis=1)


def transitive_closure(r: np.ndarray, max_squarings: int = 64) -> tuple[np.ndarray, int]:
    """Eq. 2: square R by max-min composition until R^(2^k) = R^(2^(k+1)); returns (t(R), k).

    Max-min composition only ever picks existing entries, so the fixed point is reached exactly
    (at most ceil(log2 n) squarings for a reflexive n x n relation).
    """
    r = np.asarray(r, dtype=float)
    for k in range(max_squarings + 1):
        r2 = max_min_compose(r, r)
        if np.array_equal(r2, r):
            return r, k
        r = r2
    raise RuntimeError("transitive closure did not converge (is R reflexive?)")


def lambda_cut(t: np.ndarray, lam: float) -> np.ndarray:
    """Eq. 3: classes of the Boolean relation t_ij >= lam; labels 0, 1, ... by first member."""
    n = len(t)
    labels = np.full(n, -1)
    nxt = 0
    for i in range(n):
        if labels[i] < 0:
            labels[(t[i] >= lam) & (labels < 0)] = nxt
            nxt += 1
    return labels


@dataclass
class Clustering:
    """Result of :func:`fuzzy_clusters`: ``groups`` of variable names at the cut ``lam``."""

    groups: list[list[str]]
    lam: float
    labels: np.ndarray
    closure: np.ndarray
    squarings: int
    gap: float = np.nan


#: Levels of a transitive closure closer than this (relative) are one level.  Eq. 1 is
#: computed in closed form to about 1e-15; two levels that close are equal in exact arithmetic
#: (a sensor and a scaled copy of it, mirrored ones: Eq. 1 is blind to sign and scale) or
#: differ by nothing the data can resolve, and a cut between them would split classes by
#: rounding noise.
LEVEL_RTOL = 1e-9


def cut_levels(t: np.ndarray, rtol: float = LEVEL_RTOL) -> np.ndarray:
    """The distinct levels of t(R), highest first, where a run of levels closer than ``rtol``
    (relative) counts once, at its lowest member (a cut there keeps the run together)."""
    levels = np.unique(t)[::-1]
    last_of_run = np.append(levels[:-1] - levels[1:] > rtol * np.abs(levels[:-1]), True)
    return levels[last_of_run]


def cut_for(t: np.ndarray, n_clusters: int, rtol: float = LEVEL_RTOL):
    """(lam, labels): the highest cut of t(R) (levels from :func:`cut_levels`) with exactly
    ``n_clusters`` classes, or, where ties merge several classes at one level, the cut with
    the fewest classes above ``n_clusters``; where even the highest level has fewer classes
    (variables that are equal up to scale cannot be told apart), that level."""
    levels = cut_levels(t, rtol)
    best = (levels[0], lambda_cut(t, levels[0]))
    for lam in levels:  # from the highest level down, classes merge
        labels = lambda_cut(t, lam)
        n = labels.max() + 1
        if n >= n_clusters:
            best = (lam, labels)
        if n <= n_clusters:
            break
    return best


def fuzzy_clusters(x: np.ndarray, names, n_clusters: int = 3) -> Clustering:
    """Fuzzy equivalence clustering (Eqs. 1-3) of the columns of ``x`` into ``n_clusters``.

    The cut ``lam`` is the largest level of t(R) at which the classes number exactly
    ``n_clusters`` (levels closer than :data:`LEVEL_RTOL` count as one, :func:`cut_for`).
    Were that impossible (ties merging several classes at one level), the cut with the fewest
    classes above ``n_clusters`` is used, and ``len(groups)`` says so.
    """
    names = list(names)
    if not 1 <= n_clusters <= len(names):
        raise ValueError(f"n_clusters must be in 1..{len(names)}, got {n_clusters}")
    x = np.asarray(x, dtype=float)
    flat = [names[j] for j in np.flatnonzero(np.ptp(x, axis=0) == 0)]
    if flat:
        raise ValueError(f"sensor(s) {flat} do not change over the data used for clustering; "
                         f"drop them")
    t, k = transitive_closure(similarity_matrix(x))
    lam, labels = cut_for(t, n_clusters)
    groups = [[names[i] for i in np.flatnonzero(labels == g)] for g in range(labels.max() + 1)]
    others = cut_levels(t)
    others = others[others != lam]
    gap = float(np.abs(others - lam).min() / lam) if others.size else np.nan
    return Clustering(groups, float(lam), labels, t, k, gap)


def normalise_range(x: np.ndarray) -> np.ndarray:
    """Scale every column to [0, 1] by its range (a constant column becomes 0)."""
    x = np.asarray(x, dtype=float)
    lo, span = x.min(axis=0), np.ptp(x, axis=0)
    return np.divide(x - lo, span, out=np.zeros_like(x), where=span > 0)


def grey_relational_grade(x0: np.ndarray, x: np.ndarray, rho: float = 0.5) -> np.ndarray:
    """Eq. 4, Deng's grade of each column of ``x`` (n, m) to the reference ``x0`` (n,).

    xi_i(k) = (min_i min_k D + rho max_i max_k D) / (D_i(k) + rho max_i max_k D) with
    D_i(k) = |x0(k) - x_i(k)|; the grade is the mean of xi_i over k.  The sequences must already
    be comparable (normalised); the two-level min and max run over all m candidates together.
    """
    if not 0 < rho <= 1:
        raise ValueError(f"rho must be in (0, 1], got {rho}")
    x0 = np.asarray(x0, dtype=float).ravel()
    x = np.asarray(x, dtype=float).reshape(len(x0), -1)
    d = np.abs(x - x0[:, None])
    dmin, dmax = d.min(), d.max()
    if dmax == 0:
        return np.ones(x.shape[1])
    return ((dmin + rho * dmax) / (d + rho * dmax)).mean(axis=0)


@dataclass
class Selection:
    """Sensitive points: the clusters, every sensor's grade, the chosen sensor per cluster (in
    the order of the temperature columns), and how far each decision is from flipping:
    ``margins["level"]`` the relative distance of the cut to the nearest other level of the
    closure, ``margins["grade"]`` the smallest lead of a cluster's winner over its runner-up,
    ``margins["correlation"]`` the smallest |correlation| that decided a mirroring (NaN where
    there is nothing to decide)."""

    clusters: list[list[str]]
    grades: pd.Series
    selected: list[str]
    lam: float
    mirrored: list[str]
    margins: dict = field(default_factory=dict)


def select_sensitive_points(temperatures: pd.DataFrame, target, n_clusters: int = 3,
                            rho: float = 0.5) -> Selection:
    """Cluster the temperature sequences (Eqs. 1-3), then keep in every cluster the sensor with
    the highest grey relational grade to ``target`` (Eq. 4).

    Normalisation (the paper does not state one): every sequence, the target included, is
    scaled to [0, 1] by its range; initial-value scaling is impossible for temperature rises,
    which start at 0.  A sensor that correlates negatively with the target is mirrored
    (1 - x) before grading: the grade compares shapes, and a heating that makes the error fall is
    as informative as one that makes it rise (Eq. 1 is blind to sign in the same way).
    """
    names = list(temperatures.columns)
    x = temperatures.to_numpy(dtype=float)
    y = np.asarray(target, dtype=float).ravel()
    if len(y) != len(x):
        raise ValueError(f"target has {len(y)} values, temperatures {len(x)} rows")
    cl = fuzzy_clusters(x, names, n_clusters)
    xn = normalise_range(x)
    yn = normalise_range(y[:, None])[:, 0]
    corr = np.array([np.corrcoef(x[:, j], y)[0, 1] if np.ptp(x[:, j]) > 0 else 0.0
                     for j in range(x.shape[1])])
    flip = corr < 0
    xn[:, flip] = 1.0 - xn[:, flip]
    grades = pd.Series(grey_relational_grade(yn, xn, rho), index=names, name="grade")
    selected = sorted((max(g, key=lambda s: (grades[s], -names.index(s))) for g in cl.groups),
                      key=names.index)
    leads = [np.subtract(*np.sort(grades[g].to_numpy())[::-1][:2]) for g in cl.groups
             if len(g) > 1]
    margins = {"level": cl.gap, "grade": float(min(leads)) if leads else np.nan,
               "correlation": float(np.abs(corr[np.ptp(x, axis=0) > 0]).min())
               if (np.ptp(x, axis=0) > 0).any() else np.nan}
    return Selection(cl.groups, grades, selected, cl.lam,
                     [n for n, f in zip(names, flip, strict=True) if f], margins)


def most_frequent(selections, n: int = 3, order=None) -> list[str]:
    """The ``n`` sensors chosen most often over several selections (ties: sensor order)."""
    counts = Counter(s for sel in selections for s in sel)
    order = list(order) if order is not None else sorted(counts)
    return sorted(sorted(counts, key=lambda s: (-counts[s], order.index(s)))[:n], key=order.index)


# --------------------------------------------------------------------------------------------
# Decoupling (Eq. 6) and composition (Eq. 7)
# --------------------------------------------------------------------------------------------

def decouple(offsets_mm: np.ndarray, errors_um: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eq. 6: least-squares line through every measurement; returns k (um/m) and b (um).

    ``offsets_mm`` (n_positions,) are the positions from the first target (0..260 mm), so b is
    the line's value at the first target; ``errors_um`` is (..., n_positions).  Written out (not
    ``np.polyfit``) because it *is* the paper's Eq. 6.
    """
    x = np.asarray(offsets_mm, dtype=float)
    y = np.asarray(errors_um, dtype=float)
    if y.shape[-1] != len(x) or len(x) < 2 or np.ptp(x) == 0:
        raise ValueError(f"need >= 2 distinct positions matching the last axis of the errors; "
                         f"got {len(x)} positions and errors of shape {y.shape}")
    dx = x - x.mean()
    slope = (y - y.mean(axis=-1, keepdims=True)) @ dx / (dx @ dx)   # um per mm
    b = y.mean(axis=-1) - slope * x.mean()
    return slope * 1000.0, b


def compose(k_um_per_m, b_um, offsets_mm) -> np.ndarray:
    """Eq. 7: y(x) = k x + b at every offset; returns (n_measurements, n_positions) in um."""
    k = np.asarray(k_um_per_m, dtype=float)[..., None]
    b = np.asarray(b_um, dtype=float)[..., None]
    return k * np.asarray(offsets_mm, dtype=float) / 1000.0 + b


def metrics(residuals) -> dict:
    """RMSE, largest absolute residual (the paper's delta_max) and MAE."""
    return {k: float(v[0]) for k, v in batch_metrics(np.asarray(residuals)[None]).items()}


# --------------------------------------------------------------------------------------------
# Models: scikit-learn's LinearRegression and SVR
# --------------------------------------------------------------------------------------------

#: SVR search grid (inputs and target standardised inside :class:`StandardisedSVR`, so
#: epsilon and gamma are in standard units).  Linear and RBF kernels both compete.
SVR_GRID = [
    {"kernel": ["linear"], "C": [0.01, 0.1, 1.0, 10.0, 100.0], "epsilon": [0.01, 0.1]},
    {"kernel": ["rbf"], "C": [0.1, 1.0, 10.0, 100.0, 1000.0], "gamma": [0.01, 0.1, 1.0],
     "epsilon": [0.01, 0.1]},
]

#: libsvm's stopping tolerance (the KKT violation, in standardised units).  scikit-learn's
#: default, 1e-3, leaves ill-conditioned candidates (RBF with gamma 0.01 and C 1000 is nearly
#: a linear model with a huge C) so far from their optimum that a rounding-level change of the
#: inputs (1e-15 relative, what another BLAS kernel does) moved cross-validated RMSEs by up to
#: 2 % and held-out metrics by 0.5 %.  At 1e-6 the same perturbations move the scores of the
#: candidates within 5 % of the best by < 2e-6 and the held-out metrics by < 3e-5 (relative;
#: the reconstruction, every split of the notebook), at no measurable cost in time.
SVR_SOLVER_TOL = 1e-6

#: Cross-validated RMSEs within this relative distance of the best are ties: candidates that
#: give the same model (a C larger than every dual variable needs, an epsilon tube no sample
#: touches) score equal up to rounding, and which of them scikit-learn's "first best" picks
#: would follow floating-point noise.  1e-3 is 500 times the scatter of near-best scores under
#: rounding-level perturbations (< 2e-6 at :data:`SVR_SOLVER_TOL`) and far below any
#: difference a cross-validation over a few experiments can resolve.
SVR_TIE_RTOL = 1e-3

#: How closely tables of least-squares results (MLR coefficients, their predictions and
#: metrics) regenerated on another machine must agree: ``LinearRegression`` solves through
#: LAPACK and BLAS, whose kernels round differently; the centred designs of the notebook have
#: condition numbers below 30, so the coefficients move by about cond**2 * eps < 2e-13
#: relative (observed < 2e-10 on the metrics, which subtract predictions from errors).
LSTSQ_TOLERANCE = reproduction.Tolerance(
    rel=1e-8, why="least-squares solve (LAPACK/BLAS) with condition number < 30: "
                  "kernel-dependent rounding moves results by < 1e-9 relative")
#: ... and of tables with SVR results (and mixed tables holding them): libsvm stops at
#: :data:`SVR_SOLVER_TOL`, and where that stopping point is reached along another
#: floating-point path the metrics move by up to 3e-5 relative (observed, see above).
SVR_TOLERANCE = reproduction.Tolerance(
    rel=1e-3, why="SVR solved by libsvm to tol 1e-6: rounding-level input changes move "
                  "held-out metrics by up to 3e-5 relative; 1e-3 bounds that with margin")


class StandardisedSVR(RegressorMixin, BaseEstimator):
    """scikit-learn's :class:`~sklearn.svm.SVR` on standardised inputs and target.

    The same model as ``TransformedTargetRegressor(Pipeline([StandardScaler(), SVR()]),
    transformer=StandardScaler())`` (a constant column keeps scale 1, as there), in one
    estimator: :class:`~sklearn.model_selection.GridSearchCV` clones, validates and scores
    every candidate in every fold, and with four nested estimators that overhead, not libsvm,
    took most of the search's time (this one estimator halves it).  Standardising is two
    lines, so it is written here.
    """

    def __init__(self, kernel="rbf", C=1.0, gamma="scale", epsilon=0.1, tol=SVR_SOLVER_TOL):
        self.kernel = kernel
        self.C = C
        self.gamma = gamma
        self.epsilon = epsilon
        self.tol = tol

    def fit(self, X, y):
        X, y = np.asarray(X, dtype=float), np.asarray(y, dtype=float).ravel()
        self.x_mean_, sx = X.mean(axis=0), X.std(axis=0)
        self.x_scale_ = np.where(sx > 0, sx, 1.0)
        self.y_mean_, sy = float(y.mean()), float(y.std())
        self.y_scale_ = sy if sy > 0 else 1.0
        self.svr_ = SVR(kernel=self.kernel, C=self.C, gamma=self.gamma, epsilon=self.epsilon,
                        tol=self.tol).fit((X - self.x_mean_) / self.x_scale_,
                                          (y - self.y_mean_) / self.y_scale_)
        self.n_features_in_ = X.shape[1]
        return self

    def predict(self, X):
        z = (np.asarray(X, dtype=float) - self.x_mean_) / self.x_scale_
        return self.svr_.predict(z) * self.y_scale_ + self.y_mean_


def _svr_params(params: dict) -> dict:
    return {key.rsplit("__", 1)[-1]: v for key, v in params.items()}


def svr_simplicity(params: dict) -> tuple:
    """The canonical order among tied SVR candidates, simplest first: a linear kernel before
    RBF, then the smaller C (stronger regularisation), the smaller gamma (smoother), the
    larger epsilon (a wider tube, fewer support vectors)."""
    p = _svr_params(params)
    gamma = p.get("gamma", 0.0)
    gamma = float(gamma) if isinstance(gamma, int | float) else np.inf
    return (p.get("kernel") != "linear", float(p.get("C", 1.0)), gamma,
            -float(p.get("epsilon", 0.1)))


def canonical_best(cv_results: dict, rtol: float = SVR_TIE_RTOL) -> int:
    """Index of the chosen candidate: among those whose mean cross-validated RMSE is within
    ``rtol`` (relative) of the best, the simplest by :func:`svr_simplicity`.  Used as
    ``GridSearchCV(refit=...)``, so that the choice is a property of the scores, not of
    rounding noise or of the grid's order."""
    rmse = -np.asarray(cv_results["mean_test_score"], dtype=float)
    if not np.isfinite(rmse).any():
        raise ValueError("every SVR candidate failed in cross-validation")
    best = np.nanmin(rmse)
    tied = np.flatnonzero(rmse <= best * (1.0 + rtol))
    return int(min(tied, key=lambda i: (svr_simplicity(cv_results["params"][i]), i)))


def tie_margin(cv_results: dict, rtol: float = SVR_TIE_RTOL) -> tuple[int, float]:
    """(number of tied candidates, the best included; distance of the nearest other candidate
    to the tie window's edge, relative to the best RMSE): how far the choice is from flipping.
    The distance is NaN when there is no other candidate."""
    rmse = -np.asarray(cv_results["mean_test_score"], dtype=float)
    rmse = rmse[np.isfinite(rmse)]
    gap = rmse / rmse.min() - 1.0
    others = np.delete(gap, np.argmin(gap))
    return int((gap <= rtol).sum()), float(np.abs(others - rtol).min()) if others.size else np.nan


def svr_search(x: np.ndarray, y: np.ndarray, groups: np.ndarray, grid=None):
    """Choose SVR hyperparameters by grouped cross-validation on the training data only.

    The folds leave one training experiment out at a time (``GroupKFold`` with one fold per
    experiment), the score is the RMSE of the held-out experiment, the winner is the simplest
    candidate within :data:`SVR_TIE_RTOL` of the best score (:func:`canonical_best`), and it
    is refitted on all training data.  Deterministic: no random state is involved.  Returns
    the fitted ``GridSearchCV`` (its ``best_score_`` is not set: use
    ``cv_results_["mean_test_score"][best_index_]``).
    """
    n_groups = len(np.unique(groups))
    if n_groups < 2:
        raise ValueError("SVR cross-validation needs at least 2 training experiments")
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    if not (np.isfinite(x).all() and np.isfinite(y).all()):
        raise ValueError("SVR inputs and target must be finite")
    search = GridSearchCV(StandardisedSVR(), grid or SVR_GRID,
                          cv=GroupKFold(n_splits=n_groups),
                          scoring="neg_root_mean_squared_error", n_jobs=1,
                          refit=canonical_best)
    # checked above, and the grid is fixed: skip scikit-learn's per-fit re-validation (a fifth
    # of the search's time)
    with config_context(assume_finite=True, skip_parameter_validation=True):
        search.fit(x, y, groups=groups)
    return search


def _fit(kind: str, x, y, groups):
    if kind == "mlr":
        return LinearRegression().fit(x, y), None
    if kind == "svr":
        s = svr_search(x, y, groups)
        return s.best_estimator_, s
    raise ValueError(f"unknown model kind {kind!r}; use 'mlr' or 'svr'")


@dataclass
class PointByPoint:
    """Eqs. 5 and 8: one regression per target position on the temperature rises of ``sensors``."""

    sensors: list[str]
    kind: str = "mlr"
    models: list = field(default_factory=list)

    def fit(self, data: ThermalData) -> PointByPoint:
        x = data.rises()[self.sensors].to_numpy()
        self.models = [_fit(self.kind, x, data.errors[:, i], data.groups)[0]
                       for i in range(data.errors.shape[1])]
        return self

    def predict(self, data: ThermalData) -> np.ndarray:
        x = data.rises()[self.sensors].to_numpy()
        return np.column_stack([m.predict(x) for m in self.models])

    def coefficients(self, positions_mm) -> pd.DataFrame:
        """Intercept and one coefficient per sensor at every position (MLR only)."""
        rows = [{"position_mm": p, "intercept": m.intercept_,
                 **dict(zip(self.sensors, m.coef_, strict=True))}
                for p, m in zip(positions_mm, self.models, strict=True)]
        return pd.DataFrame(rows)


@dataclass
class Decoupled:
    """Eqs. 7 and 9: k from the absolute temperatures of ``k_sensors``, b from the rises of
    ``b_sensors``; the error follows as k x + b."""

    k_sensors: list[str]
    b_sensors: list[str]
    kind: str = "mlr"
    k_model: object = None
    b_model: object = None
    searches: dict = field(default_factory=dict)

    def inputs(self, data: ThermalData) -> tuple[np.ndarray, np.ndarray]:
        return (data.temperatures[self.k_sensors].to_numpy(),
                data.rises()[self.b_sensors].to_numpy())

    def fit(self, data: ThermalData) -> Decoupled:
        k, b = decouple(data.offsets_mm(), data.errors)
        xk, xb = self.inputs(data)
        self.k_model, sk = _fit(self.kind, xk, k, data.groups)
        self.b_model, sb = _fit(self.kind, xb, b, data.groups)
        self.searches = {"k": sk, "b": sb} if self.kind == "svr" else {}
        return self

    def predict_kb(self, data: ThermalData) -> tuple[np.ndarray, np.ndarray]:
        xk, xb = self.inputs(data)
        return self.k_model.predict(xk), self.b_model.predict(xb)

    def predict(self, data: ThermalData) -> np.ndarray:
        return compose(*self.predict_kb(data), data.offsets_mm())

    def coefficients(self) -> pd.DataFrame:
        """Eq. 9 as a table: target, term, coefficient (MLR only)."""
        rows = []
        for target, m, names, pre in (("k (um/m)", self.k_model, self.k_sensors, ""),
                                      ("b (um)", self.b_model, self.b_sensors, "d")):
            rows.append({"target": target, "term": "intercept", "coefficient": m.intercept_})
            rows += [{"target": target, "term": pre + s, "coefficient": c}
                     for s, c in zip(names, m.coef_, strict=True)]
        return pd.DataFrame(rows)

    def hyperparameters(self) -> pd.DataFrame:
        """The cross-validated SVR hyperparameters for k and b (SVR only): the chosen
        candidate, its mean CV RMSE, how many candidates tied with the best
        (:data:`SVR_TIE_RTOL`) and the distance of the nearest one to the tie window's edge."""
        rows = []
        for target, s in self.searches.items():
            p = _svr_params(s.best_params_)
            tied, margin = tie_margin(s.cv_results_)
            rows.append({"target": target, "kernel": p["kernel"], "C": p["C"],
                         "gamma": p.get("gamma", ""), "epsilon": p["epsilon"],
                         "cv_rmse": -s.cv_results_["mean_test_score"][s.best_index_],
                         "candidates": len(s.cv_results_["params"]), "tied": tied,
                         "tie_window_margin": margin})
        return pd.DataFrame(rows)


# --------------------------------------------------------------------------------------------
# One split, and every experiment held out in turn
# --------------------------------------------------------------------------------------------

@dataclass
class SplitResult:
    """Everything :func:`evaluate_split` computed for one train/test split."""

    train: list[int]
    test: list[int]
    position_selections: list[Selection]
    selected: dict
    inputs: dict
    k_selection: Selection
    b_selection: Selection
    models: dict
    predictions: dict
    kb_predictions: dict
    measured: np.ndarray
    measured_kb: tuple
    table: pd.DataFrame
    settings: dict = field(default_factory=dict)


def evaluate_split(data: ThermalData, train, test, n_clusters: int = 3, rho: float = 0.5,
                   kinds=("mlr", "svr"), sensors: dict | None = None) -> SplitResult:
    """Select sensitive points on ``train`` only, fit point-by-point MLR and the decoupled
    models, predict ``test`` from its temperatures; returns predictions and metrics.

    ``sensors`` may fix the inputs instead of selecting them:
    ``{"point": [...], "k": [...], "b": [...]}``; the selection is still computed and returned.
    """
    missing = sorted({s for v in (sensors or {}).values() for s in v} - set(data.sensors))
    if missing:
        raise ValueError(f"the data have no sensor(s) {missing}; they have {data.sensors}")
    tr, te = data.subset(train), data.subset(test)
    offsets = data.offsets_mm()
    k_tr, b_tr = decouple(offsets, tr.errors)
    rises = tr.rises()
    pos_sel = [select_sensitive_points(rises, tr.errors[:, i], n_clusters, rho)
               for i in range(tr.errors.shape[1])]
    k_sel = select_sensitive_points(tr.temperatures, k_tr, n_clusters, rho)
    b_sel = select_sensitive_points(rises, b_tr, n_clusters, rho)
    selected = {"point": most_frequent([s.selected for s in pos_sel], n_clusters,
                                       order=data.sensors),
                "k": k_sel.selected, "b": b_sel.selected}
    chosen = {**selected, **(sensors or {})}
    models = {"point_by_point_mlr": PointByPoint(chosen["point"]).fit(tr)}
    for kind in kinds:
        models[f"decoupled_{kind}"] = Decoupled(chosen["k"], chosen["b"], kind).fit(tr)
    measured = te.errors
    measured_kb = decouple(offsets, measured)
    preds, kb_preds, rows = {}, {}, []
    for name, m in models.items():
        preds[name] = m.predict(te)
        rows.append({"method": name, "target": "thermal positioning error", "unit": "um",
                     **metrics(measured - preds[name])})
        if isinstance(m, Decoupled):
            kb_preds[name] = m.predict_kb(te)
            for target, unit, meas, pred in (("slope k", "um/m", measured_kb[0],
                                              kb_preds[name][0]),
                                             ("intercept b", "um", measured_kb[1],
                                              kb_preds[name][1])):
                rows.append({"method": name, "target": target, "unit": unit,
                             **metrics(meas - pred)})
    table = pd.DataFrame(rows)[["method", "target", "rmse", "max_residual", "mae", "unit"]]
    return SplitResult(list(tr.experiments), list(te.experiments), pos_sel, selected, chosen,
                       k_sel, b_sel, models, preds, kb_preds, measured, measured_kb, table,
                       _settings(data, train, test, n_clusters, rho, kinds, sensors))


def _settings(data, train, test, n_clusters, rho, kinds, sensors) -> dict:
    """What determines a split's result: compared to reuse a result."""
    h = hashlib.sha256()
    for a in (data.index.to_numpy(dtype=float), data.temperatures.to_numpy(dtype=float),
              data.errors, data.positions_mm):
        h.update(np.ascontiguousarray(a, dtype=float).tobytes())
    h.update(repr(data.sensors).encode())
    return {"data": h.hexdigest(), "train": sorted(int(e) for e in np.atleast_1d(train)),
            "test": sorted(int(e) for e in np.atleast_1d(test)), "n_clusters": int(n_clusters),
            "rho": float(rho), "kinds": tuple(kinds),
            "sensors": {k: list(v) for k, v in sorted((sensors or {}).items())}}


def leave_one_experiment_out(data: ThermalData, n_clusters: int = 3, rho: float = 0.5,
                             kinds=("mlr", "svr"), sensors: dict | None = None,
                             reuse=()) -> pd.DataFrame:
    """:func:`evaluate_split` with each experiment held out in turn (selection redone on the
    remaining ones every time); one row per held-out experiment, method and target.

    ``reuse``: results of :func:`evaluate_split`; one computed on the same data (compared by
    content hash) with the same settings is taken as is instead of being computed again (it
    is deterministic, so the table is the same, only faster)."""
    frames = []
    for e in data.experiments:
        train = [x for x in data.experiments if x != e]
        want = _settings(data, train, [e], n_clusters, rho, kinds, sensors)
        r = next((r for r in reuse if r.settings == want), None) or \
            evaluate_split(data, train, [e], n_clusters, rho, kinds, sensors)
        t = r.table.copy()
        t.insert(0, "held_out", e)
        for i, key in enumerate(("point", "k", "b"), 1):
            t.insert(i, f"{key}_sensors", " ".join(r.inputs[key]))
        frames.append(t)
    return pd.concat(frames, ignore_index=True)


# --------------------------------------------------------------------------------------------
# Noise replicates: the same fits on a stack of datasets (leading replicate axis)
# --------------------------------------------------------------------------------------------

def fit_linear(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Least squares with an intercept on a stack of problems: ``x`` (R, n, p), ``y`` (R, n)
    or (R, n, q); returns the coefficients (R, 1 + p) or (R, 1 + p, q), intercept first.  The
    batched twin of scikit-learn's ``LinearRegression`` (the tests check they agree), so that
    many replicates are fitted at once."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    a = np.concatenate([np.ones(x.shape[:-1] + (1,)), x], axis=-1)
    single = y.ndim == x.ndim - 1
    c = np.linalg.pinv(a) @ (y[..., None] if single else y)
    return c[..., 0] if single else c


def predict_linear(coef: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``intercept + x @ slopes`` for the coefficients of :func:`fit_linear`."""
    coef, x = np.asarray(coef, dtype=float), np.asarray(x, dtype=float)
    if coef.ndim == x.ndim - 1:
        return coef[..., :1] + np.einsum("rnp,rp->rn", x, coef[..., 1:])
    return coef[..., :1, :] + x @ coef[..., 1:, :]


def batch_metrics(residuals) -> dict:
    """:func:`metrics` of every replicate (its one implementation): ``residuals`` (R, ...) ->
    {name: (R,)}."""
    r = np.asarray(residuals, dtype=float)
    r = r.reshape(len(r), -1)
    return {"rmse": np.sqrt(np.mean(r**2, axis=1)), "max_residual": np.abs(r).max(axis=1),
            "mae": np.abs(r).mean(axis=1)}


def rises_of(temperatures: np.ndarray, experiments) -> np.ndarray:
    """Temperatures (R, n, S) relative to the first row of each experiment (the one
    implementation of :meth:`ThermalData.rises`, batched)."""
    experiments = np.asarray(experiments)
    first = pd.Series(np.arange(len(experiments))).groupby(experiments).transform("first")
    t = np.asarray(temperatures, dtype=float)
    return t - t[:, first.to_numpy(), :]


def replicate_split(replicates, train, test, inputs: dict, svr_params: dict | None = None
                    ) -> pd.DataFrame:
    """The fits of :func:`evaluate_split` with fixed inputs, on every replicate at once.

    ``replicates`` has ``index``, ``sensors``, ``temperatures`` (R, n, S), ``errors``
    (R, n, P) and ``positions_mm`` (``thermal_data.noise_replicates``); ``inputs`` is
    ``{"point": [...], "k": [...], "b": [...]}``.  The MLRs are fitted batched
    (:func:`fit_linear`); the SVRs, when ``svr_params = {"k": params, "b": params}`` fixes
    their hyperparameters, one replicate at a time (libsvm solves one problem per call).
    Sensitive points and hyperparameters are not chosen again: the spread over the replicates
    is that of the fits and metrics for the given choices.

    Returns one row per replicate; the columns are 3-tuples: (method, target, metric) for
    the metrics of :func:`metrics`; ``("eq8", position, term)`` and ``("eq9", target, term)``
    for the MLR coefficients; ``(method, "residual of the error", "lowest" | "highest")``;
    ``("point_by_point_mlr", "largest residual at", position)``; and
    ``("test", "largest |error|", "")``.
    """
    exp = replicates.index.experiment.to_numpy()
    tr, te = np.isin(exp, list(train)), np.isin(exp, list(test))
    col = {s: i for i, s in enumerate(replicates.sensors)}
    missing = sorted({s for v in inputs.values() for s in v} - set(col))
    if missing:
        raise ValueError(f"the replicates have no sensor(s) {missing}")
    t = np.asarray(replicates.temperatures, dtype=float)
    e = np.asarray(replicates.errors, dtype=float)
    rises = rises_of(t, exp)
    offsets = np.asarray(replicates.positions_mm, dtype=float)
    offsets = offsets - offsets[0]
    k, b = decouple(offsets, e)                                           # (R, n)
    pick = {key: [col[s] for s in v] for key, v in inputs.items()}
    out, residuals = {}, {}

    x_p = rises[..., pick["point"]]
    c8 = fit_linear(x_p[:, tr], e[:, tr])                                # (R, 1 + p, P)
    residuals["point_by_point_mlr"] = e[:, te] - predict_linear(c8, x_p[:, te])
    for j, pos in enumerate(replicates.positions_mm):
        for i, term in enumerate(["intercept", *inputs["point"]]):
            out[("eq8", f"{pos:g}", term)] = c8[:, i, j]
    x_k, x_b = t[..., pick["k"]], rises[..., pick["b"]]
    kb = {}
    ck, cb = fit_linear(x_k[:, tr], k[:, tr]), fit_linear(x_b[:, tr], b[:, tr])
    for target, c, names in (("k (um/m)", ck, ["intercept", *inputs["k"]]),
                             ("b (um)", cb, ["intercept", *("d" + s for s in inputs["b"])])):
        for i, term in enumerate(names):
            out[("eq9", target, term)] = c[:, i]
    kb["decoupled_mlr"] = (predict_linear(ck, x_k[:, te]), predict_linear(cb, x_b[:, te]))
    if svr_params is not None:
        preds = []
        for r in range(len(t)):
            mk = StandardisedSVR(**_svr_params(svr_params["k"])).fit(x_k[r, tr], k[r, tr])
            mb = StandardisedSVR(**_svr_params(svr_params["b"])).fit(x_b[r, tr], b[r, tr])
            preds.append((mk.predict(x_k[r, te]), mb.predict(x_b[r, te])))
        kb["decoupled_svr"] = tuple(np.array(p) for p in zip(*preds, strict=True))
    for name, (kp, bp) in kb.items():
        residuals[name] = e[:, te] - compose(kp, bp, offsets)
        for target, meas, pred in (("slope k", k[:, te], kp), ("intercept b", b[:, te], bp)):
            for m, v in batch_metrics(meas - pred).items():
                out[(name, target, m)] = v
    for name, res in residuals.items():
        for m, v in batch_metrics(res).items():
            out[(name, "thermal positioning error", m)] = v
        flat = res.reshape(len(res), -1)
        out[(name, "residual of the error", "lowest")] = flat.min(axis=1)
        out[(name, "residual of the error", "highest")] = flat.max(axis=1)
    by_pos = np.abs(residuals["point_by_point_mlr"]).max(axis=1)          # (R, P)
    for j, pos in enumerate(replicates.positions_mm):
        out[("point_by_point_mlr", "largest residual at", f"{pos:g}")] = by_pos[:, j]
    out[("test", "largest |error|", "")] = np.abs(e[:, te]).reshape(len(e), -1).max(axis=1)
    frame = pd.DataFrame(out)
    frame.index.name = "replicate"
    return frame
