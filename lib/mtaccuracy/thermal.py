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
  (Eqs. 5, 8, 9) are scikit-learn's ``LinearRegression`` and ``SVR``, hyperparameters by
  ``GridSearchCV`` with ``GroupKFold``.
* :func:`metrics`, :func:`evaluate_split`, :func:`leave_one_experiment_out`: RMSE, largest
  residual, MAE; one train/test split; every experiment held out in turn.

Units: positions in mm, errors in um, slopes k in um/m (so ``k * x_mm / 1000`` is um), temperatures
in degrees Celsius.  The position axis is shifted to start at 0 (the paper models 185..445 mm as
0..260 mm so that the intercept b is the error at the first target).
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
from sklearn.compose import TransformedTargetRegressor
from sklearn.linear_model import LinearRegression
from sklearn.model_selection import GridSearchCV, GroupKFold
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.svm import SVR

from . import provenance, reproduction

__all__ = [
    "DataFormatError", "ThermalData", "read_measurements", "write_measurements",
    "similarity_matrix", "max_min_compose", "transitive_closure", "lambda_cut", "fuzzy_clusters",
    "Clustering", "normalise_range", "grey_relational_grade", "Selection",
    "select_sensitive_points", "most_frequent", "decouple", "compose", "metrics",
    "PointByPoint", "Decoupled", "svr_search", "evaluate_split", "leave_one_experiment_out",
    "TEMPERATURES_FILE", "ERRORS_FILE", "EXPERIMENTS_FILE",
]

# --------------------------------------------------------------------------------------------
# Data: the CSV schema
# --------------------------------------------------------------------------------------------

TEMPERATURES_FILE = "temperatures.csv"
ERRORS_FILE = "errors.csv"
EXPERIMENTS_FILE = "experiments.csv"
_TEMP_UNIT = "_degC"


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
        first = self.temperatures.groupby(self.index.experiment.to_numpy()).transform("first")
        return self.temperatures - first

    def offsets_mm(self) -> np.ndarray:
        """Target positions shifted to start at 0 (185..445 mm -> 0..260 mm)."""
        return self.positions_mm - self.positions_mm[0]


def _problem(path, message) -> DataFormatError:
    return DataFormatError(f"{path}: {message}")


def _read_csv(path: Path) -> pd.DataFrame:
    if not path.exists():
        raise _problem(path, "file not found (the schema needs temperatures.csv and errors.csv; "
                             "see data/thermal/README.md)")
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


def read_measurements(folder) -> ThermalData:
    """Read and validate ``temperatures.csv``, ``errors.csv`` (and ``experiments.csv`` if there).

    The schema (``data/thermal/README.md``):

    * ``temperatures.csv``: ``experiment, measurement, time_min, <sensor>_degC ...`` one row per
      measurement; at least three sensors.
    * ``errors.csv``: ``experiment, measurement, position_mm, error_um`` one row per target
      position and measurement; every measurement has the same target positions.
    * ``experiments.csv`` (optional): ``experiment, feed_mm_per_min`` (other columns ignored).

    Raises :class:`DataFormatError` naming the file and the problem: a missing file or column,
    a column in other units (``error_mm``, ``T1_K``), a missing/NaN/non-numeric value,
    duplicated or unmatched measurements, or measurements of unequal length.
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
    t_exp = _numeric(tp, t, "experiment", integer=True)
    t_meas = _numeric(tp, t, "measurement", integer=True)
    t_time = _numeric(tp, t, "time_min")
    temps = pd.DataFrame({c[:-len(_TEMP_UNIT)]: _numeric(tp, t, c) for c in rest})
    keys = pd.DataFrame({"experiment": t_exp, "measurement": t_meas, "time_min": t_time})
    dup = keys.duplicated(["experiment", "measurement"])
    if dup.any():
        r = keys[dup].iloc[0]
        raise _problem(tp, f"experiment {int(r.experiment)} measurement {int(r.measurement)} "
                           f"appears more than once (line {int(np.flatnonzero(dup)[0]) + 2})")
    for e, g in keys.groupby("experiment"):
        if len(g) < 2:
            raise _problem(tp, f"experiment {e} has a single measurement; at least 2 are needed")
        if not np.all(np.diff(g.time_min.to_numpy()) > 0):
            raise _problem(tp, f"experiment {e}: time_min must increase from one measurement "
                               f"to the next (rows in measurement order)")

    er = _read_csv(ep)
    _check_units(ep, er.columns, "position", "position_mm")
    _check_units(ep, er.columns, "error", "error_um")
    _require(ep, er, ["experiment", "measurement", "position_mm", "error_um"])
    e_exp = _numeric(ep, er, "experiment", integer=True)
    e_meas = _numeric(ep, er, "measurement", integer=True)
    e_pos = _numeric(ep, er, "position_mm")
    e_val = _numeric(ep, er, "error_um")
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

    order = keys.sort_values(["experiment", "measurement"], kind="stable").index
    keys = keys.loc[order].reset_index(drop=True)
    temps = temps.loc[order].reset_index(drop=True)
    wide = long.pivot(index=["experiment", "measurement"], columns="position_mm",
                      values="error_um")
    errors = wide.loc[list(zip(keys.experiment, keys.measurement, strict=True)),
                      positions].to_numpy()

    feeds = {}
    if xp.exists():
        x = _read_csv(xp)
        _check_units(xp, x.columns, "feed", "feed_mm_per_min")
        _require(xp, x, ["experiment", "feed_mm_per_min"])
        feeds = dict(zip(_numeric(xp, x, "experiment", integer=True).tolist(),
                         _numeric(xp, x, "feed_mm_per_min").tolist(), strict=True))
    return ThermalData(keys, temps, errors, positions, feeds, source=str(folder))


def write_measurements(data: ThermalData, folder, temperature_decimals: int = 2,
                       error_decimals: int = 3) -> list[Path]:
    """Write ``data`` in the schema (:func:`mtaccuracy.reproduction.save_table`, which rewrites a
    file only when its bytes change).  Returns the files whose content changed."""
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
    r = (a.T @ a) / np.outer(norm, norm)
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


def fuzzy_clusters(x: np.ndarray, names, n_clusters: int = 3) -> Clustering:
    """Fuzzy equivalence clustering (Eqs. 1-3) of the columns of ``x`` into ``n_clusters``.

    The cut ``lam`` is the largest entry of t(R) at which the classes number exactly
    ``n_clusters``.  Were that impossible (ties merging several classes at one level), the cut
    with the fewest classes above ``n_clusters`` is used, and ``len(groups)`` says so.
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
    best = None
    for lam in np.unique(t)[::-1]:  # from the highest level down, classes merge
        labels = lambda_cut(t, lam)
        n = labels.max() + 1
        if n >= n_clusters:
            best = (lam, labels)
        if n <= n_clusters:
            break
    lam, labels = best
    groups = [[names[i] for i in np.flatnonzero(labels == g)] for g in range(labels.max() + 1)]
    return Clustering(groups, float(lam), labels, t, k)


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
    the order of the temperature columns)."""

    clusters: list[list[str]]
    grades: pd.Series
    selected: list[str]
    lam: float
    mirrored: list[str]


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
    return Selection(cl.groups, grades, selected, cl.lam,
                     [n for n, f in zip(names, flip, strict=True) if f])


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
    r = np.asarray(residuals, dtype=float).ravel()
    return {"rmse": float(np.sqrt(np.mean(r**2))), "max_residual": float(np.max(np.abs(r))),
            "mae": float(np.mean(np.abs(r)))}


# --------------------------------------------------------------------------------------------
# Models: scikit-learn's LinearRegression and SVR
# --------------------------------------------------------------------------------------------

#: SVR search grid (inputs and target standardised inside the pipeline, so epsilon and gamma are
#: in standard units).  Linear and RBF kernels both compete.
SVR_GRID = [
    {"regressor__svr__kernel": ["linear"], "regressor__svr__C": [0.01, 0.1, 1.0, 10.0, 100.0],
     "regressor__svr__epsilon": [0.01, 0.1]},
    {"regressor__svr__kernel": ["rbf"], "regressor__svr__C": [0.1, 1.0, 10.0, 100.0, 1000.0],
     "regressor__svr__gamma": [0.01, 0.1, 1.0], "regressor__svr__epsilon": [0.01, 0.1]},
]


def svr_search(x: np.ndarray, y: np.ndarray, groups: np.ndarray, grid=None):
    """Choose SVR hyperparameters by grouped cross-validation on the training data only.

    The folds leave one training experiment out at a time (``GroupKFold`` with one fold per
    experiment), the score is the RMSE of the held-out experiment, and the winner is refitted
    on all training data.  Deterministic: no random state is involved.  Returns the fitted
    ``GridSearchCV``.
    """
    n_groups = len(np.unique(groups))
    if n_groups < 2:
        raise ValueError("SVR cross-validation needs at least 2 training experiments")
    model = TransformedTargetRegressor(
        regressor=Pipeline([("scale", StandardScaler()), ("svr", SVR())]),
        transformer=StandardScaler())
    search = GridSearchCV(model, grid or SVR_GRID, cv=GroupKFold(n_splits=n_groups),
                          scoring="neg_root_mean_squared_error", n_jobs=1)
    search.fit(np.asarray(x, dtype=float), np.asarray(y, dtype=float), groups=groups)
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
        """The cross-validated SVR hyperparameters for k and b (SVR only)."""
        rows = []
        for target, s in self.searches.items():
            p = {key.rsplit("__", 1)[1]: v for key, v in s.best_params_.items()}
            rows.append({"target": target, "kernel": p["kernel"], "C": p["C"],
                         "gamma": p.get("gamma", ""), "epsilon": p["epsilon"],
                         "cv_rmse": -s.best_score_, "candidates": len(s.cv_results_["params"])})
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
                       k_sel, b_sel, models, preds, kb_preds, measured, measured_kb, table)


def leave_one_experiment_out(data: ThermalData, n_clusters: int = 3, rho: float = 0.5,
                             kinds=("mlr", "svr"), sensors: dict | None = None) -> pd.DataFrame:
    """:func:`evaluate_split` with each experiment held out in turn (selection redone on the
    remaining ones every time); one row per held-out experiment, method and target."""
    frames = []
    for e in data.experiments:
        train = [x for x in data.experiments if x != e]
        r = evaluate_split(data, train, [e], n_clusters, rho, kinds, sensors)
        t = r.table.copy()
        t.insert(0, "held_out", e)
        for i, key in enumerate(("point", "k", "b"), 1):
            t.insert(i, f"{key}_sensors", " ".join(r.inputs[key]))
        frames.append(t)
    return pd.concat(frames, ignore_index=True)
