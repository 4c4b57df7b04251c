"""The compendium's side of notebook 04 (Xu et al. 2022): published values, files, tolerances.

The thermal science (:mod:`mtaccuracy.thermal`) takes arrays and tables and never reads
``data/papers/`` or knows the repository's folders; this module does that for the notebook:
it reads the published tables the reconstruction is built from (the seeded generator is
:mod:`mtaccuracy.compendium.xu2022_reconstruction`), decides where the reconstruction is
written (never over a reader's own measurements), reads the measurements with provenance
recorded, and declares how closely regenerated tables must agree.
"""

from __future__ import annotations

import itertools
import math
import time
from pathlib import Path

import numpy as np

from .. import thermal, validate
from . import paths, provenance, reproduction, xu2022_reconstruction
from .parameters import ParameterError
from .xu2022_reconstruction import DEFAULT_SEED

__all__ = [
    "DEFAULT_DIR", "LSTSQ_TOLERANCE", "SVR_TOLERANCE", "published_targets", "published_models",
    "published_metrics",
    "reconstruct", "noise_replicates", "calibrate", "read", "is_default_dir", "prepare",
    "EditedDataError", "reconstruction_seed", "resolve_split", "resolve_inputs", "Progress",
    "reader_notes", "partition_fits", "table3_consistency", "rows_fitted_by",
]

#: Where the committed reconstruction lives (relative to the repository root).
DEFAULT_DIR = "data/thermal"

#: How closely tables of least-squares results (MLR coefficients, their predictions and
#: metrics) regenerated on another machine must agree: ``LinearRegression`` solves through
#: LAPACK and BLAS, whose kernels round differently; the centred designs of the notebook have
#: condition numbers below 30, so the coefficients move by about cond**2 * eps < 2e-13
#: relative (observed < 2e-10 on the metrics, which subtract predictions from errors).
LSTSQ_TOLERANCE = reproduction.Tolerance(
    rel=1e-8, why="least-squares solve (LAPACK/BLAS) with condition number < 30: "
                  "kernel-dependent rounding moves results by < 1e-9 relative")
#: ... and of tables with SVR results (and mixed tables holding them): libsvm stops at
#: ``thermal.SVR_SOLVER_TOL`` (1e-12), and where that stopping point is reached along another
#: floating-point path the results move by up to 2e-11 relative (observed; 3e-5 at the 1e-6
#: used before); the held-out metrics are those of predictions stored to 1e-4 um
#: (``thermal.PREDICTION_DECIMALS``), so a prediction on a rounding edge moves one by less.
SVR_TOLERANCE = reproduction.Tolerance(
    rel=1e-3, why="SVR solved by libsvm to tol 1e-12: rounding-level input changes move "
                  "held-out metrics by < 1e-10 relative (predictions stored to 1e-4 um); "
                  "1e-3 bounds that with margin")


def published_targets(folder=None) -> xu2022_reconstruction.Targets:
    """Table 5 (k, b) and Table 1 (feeds, ambient ranges) from ``data/papers``."""
    t5 = reproduction.published("xu2022_table5_slope_intercept",
                                ["experiment", "measurement", "k_um_per_m", "b_um"], folder)
    t1 = reproduction.published("xu2022_table1_experiments",
                                ["experiment", "feed_mm_per_min", "ambient_min_C",
                                 "ambient_max_C"], folder)
    return xu2022_reconstruction.targets_from_tables(t5, t1)


def published_models(folder=None):
    """The printed models (Eqs. 8-9) from ``data/papers/xu2022_models.csv``."""
    return reproduction.published("xu2022_models", ["model", "target", "term", "coefficient"],
                                  folder)


def published_inputs(folder=None) -> dict[str, list[str]]:
    """The paper's sensitive points, read off the terms of its printed models.

    From ``data/papers/xu2022_models.csv``: ``{"point": Eq. 8's sensors, "k": Eq. 9's for the
    slope, "b": Eq. 9's for the intercept}``, each in the order the paper prints them.
    """
    models = published_models(folder)
    terms = models[models.term != "intercept"]

    def of(model, prefix=""):
        rows = terms[(terms.model == model) & terms.target.str.startswith(prefix)]
        return list(dict.fromkeys(t.removeprefix("d") for t in rows.term))
    return {"point": of("point_by_point_mlr"), "k": of("decoupled_mlr", "k"),
            "b": of("decoupled_mlr", "b")}


def reconstruct(seed: int = DEFAULT_SEED, papers_folder=None) -> thermal.ThermalData:
    """:func:`.xu2022_reconstruction.reconstruct` on the published targets."""
    return xu2022_reconstruction.reconstruct(published_targets(papers_folder), seed)


def noise_replicates(seed: int = DEFAULT_SEED, n: int = 40, papers_folder=None):
    """:func:`.xu2022_reconstruction.noise_replicates` on the published targets."""
    return xu2022_reconstruction.noise_replicates(published_targets(papers_folder), seed, n)


def published_metrics(folder=None):
    """The printed prediction metrics (Tables 4, 7, 8) from ``data/papers/xu2022_metrics.csv``."""
    return reproduction.published("xu2022_metrics", ["table", "method", "target", "rmse",
                                                     "max_residual", "mae", "unit"], folder)


def calibrate(papers_folder=None, **kwargs):
    """:func:`.xu2022_reconstruction.calibrate` on the published tables (about a minute)."""
    return xu2022_reconstruction.calibrate(
        published_targets(papers_folder), published_models(papers_folder),
        published_metrics(papers_folder), **kwargs)


def read(folder) -> thermal.ThermalData:
    """:func:`mtaccuracy.thermal.read_measurements`, every file read recorded in the provenance."""
    return thermal.read_measurements(folder, on_read=provenance.track)


def is_default_dir(data_dir) -> bool:
    """Whether ``data_dir`` names the committed reconstruction folder ``data/thermal``."""
    p = Path(data_dir)
    p = p if p.is_absolute() else paths.ROOT / p
    return p.resolve() == (paths.ROOT / DEFAULT_DIR).resolve()


class EditedDataError(RuntimeError):
    """A file of the reconstruction folder was edited since the compendium last wrote it.

    It no longer holds the bytes the compendium wrote there: regenerating would overwrite the
    edit, so nothing is written.
    """


def _shown(folder: Path, out=None):
    """How a message names ``folder``: repository-relative, ``<output_dir>/...``, or as it is."""
    return (folder.relative_to(paths.ROOT).as_posix() if folder.is_relative_to(paths.ROOT)
            else f"<output_dir>/{folder.name}" if out is not None and folder.parent == Path(out)
            else folder)


def _refuse_edited(folder: Path, files, out=None) -> None:
    """Refuse (:class:`EditedDataError`) to overwrite a file the compendium did not last write.

    A file of ``files`` is refused when its bytes are not the ones the folder's
    ``provenance.json`` records for the compendium's last write.

    The rule "a run never overwrites a file it did not write": a user who edits
    ``data/thermal/temperatures.csv`` in place and runs notebook 04 again with
    ``regenerate_data = True`` gets this one-line message, naming the file and both ways on,
    instead of losing the edit.  A file without a record (no ``provenance.json``, or one that
    does not list it) is not known to be ours either, and is refused the same way.
    """
    recorded = provenance.read(folder).get("files", {})
    edited = [p for p in files
              if recorded.get(p.name, {}).get("sha256") != provenance.sha256(p)]
    if not edited:
        return
    where = _shown(folder, out)
    names = ", ".join(f"{where}/{p.name}" for p in edited)
    if is_default_dir(folder):
        how = (f"run with regenerate_data = False to use the edited data, or restore the "
               f"committed files with `git checkout {DEFAULT_DIR}` and run again")
    else:
        how = (f"run with data_dir = '{folder}' to use the edited data (read, never written), "
               f"or delete the edited file(s) to regenerate them")
    raise EditedDataError(
        f"{names}: edited since the compendium wrote it (its SHA-256 is not the one recorded in "
        f"{where}/{provenance.SIDECAR}); regenerating would overwrite the edit, so nothing was "
        f"written: {how}")


def prepare(data_dir: str = DEFAULT_DIR, *, regenerate: bool = True, seed: int = DEFAULT_SEED,
            out=None) -> tuple[Path, list[Path], str]:
    """Decide where to read from and, for the reconstruction only, regenerate it first.

    * ``data_dir`` is the default ``data/thermal``, ``regenerate`` is true and ``seed`` is the
      committed one: the generator writes into it (resolved like an output folder, so under the
      tests it goes to ``$MTACCURACY_OUTPUT_BASE/data/thermal``), a file only when its bytes
      change.
    * the same with another ``seed``: the reconstruction goes to ``<out>/reconstruction`` (the
      run's own output folder), never over the committed data.
    * any other ``data_dir`` is the reader's own measurements: read, **never written**.

    A file of the reconstruction folder whose bytes are not those the folder's
    ``provenance.json`` records for the compendium's last write (a user edited it) is never
    overwritten: :class:`EditedDataError`, before anything is written, saying how to use the
    edit (``regenerate_data = False``) or drop it.  A missing file is simply written.  The
    sidecar records the hashes of the bytes on disk, in its file entries and in the run's
    inputs.

    Returns (folder to read, files that changed, a sentence saying what happened).
    """
    if not is_default_dir(data_dir):
        p = Path(data_dir)
        p = p if p.is_absolute() else paths.ROOT / p
        what = (f"{data_dir}: your measurements, read only"
                + (" (regenerate_data applies to the reconstruction only)" if regenerate else ""))
        return p, [], what
    if not regenerate:
        return paths.ROOT / DEFAULT_DIR, [], f"{DEFAULT_DIR}: committed reconstruction, as stored"
    if seed == DEFAULT_SEED:
        folder = paths.resolve_output(DEFAULT_DIR)
    elif out is None:
        raise ValueError(f"a reconstruction with seed {seed} (not the committed "
                         f"{DEFAULT_SEED}) is written into the run's output folder: "
                         f"pass out=")
    else:
        folder = Path(out) / "reconstruction"
    folder.mkdir(parents=True, exist_ok=True)
    changed = thermal.write_measurements(
        reconstruct(seed), folder, save=reproduction.save_table,
        before_overwrite=lambda files: _refuse_edited(folder, files, out))
    what = (f"{_shown(folder, out)}: reconstruction regenerated with seed {seed}: "
            + (f"{len(changed)} file(s) rewritten ({', '.join(p.name for p in changed)})"
               if changed else "every file byte-identical, nothing rewritten"))
    return folder, changed, what


# ------------------------------------------------------------------------------------------
# Notebook 04's checks, scorecard helpers and figures
# ------------------------------------------------------------------------------------------

#: The scorecard rows that score what a figure shows, where its name is not their item.
FIGURE_ROWS = {"fig03_ambient_temperature": ["Table 1"],
               **{f: ["Table 5", "Eq. 8", "Section 3.2: largest error*"]
                  for f in ("fig05_error_vs_position", "fig06_error_vs_time", "fig07_error_surface",
                            "fig08_error_zeroed", "fig09_error_other_experiments")},
               "fig10_temperatures": ["Table 6", "Section 3.1: three most frequent sensitive "
                                                 "points (point-by-point inputs)"],
               "fig11_point_by_point_prediction": ["Table 4", "Section 3.1"],
               "fig12_slope_intercept": ["Table 5"],
               "fig14_mlr_slope_intercept": ["Eq. 9", "Table 7: decoupled_mlr, slope k*",
                                             "Table 7: decoupled_mlr, intercept b*"],
               "fig15_mlr_error_prediction": ["Table 7", "Section 3.2: decoupled_mlr*"],
               "fig16_svr_slope_intercept": ["Table 8: decoupled_svr, slope k*",
                                             "Table 8: decoupled_svr, intercept b*"],
               "fig17_svr_error_prediction": ["Table 8", "Section 3.2: decoupled_svr*",
                                              "Section 5"]}
RECONSTRUCTED_LABEL = "reconstructed data, not the paper's measurements"
ERROR = "thermal positioning error"
METRIC_NAMES = {"rmse": "RMSE", "max_residual": "largest residual", "mae": "MAE"}


#: The files whose content makes a folder the reconstruction (``experiments.csv`` may be absent).
DATA_FILES = ("temperatures.csv", "errors.csv")


def _same_numbers(data, other) -> bool:
    """Whether two datasets hold the same measurements to the resolution of the files.

    The reconstruction is written to 0.01 degC and 0.001 um: equal within half a unit, plus
    rounding.
    """
    return (data.sensors == other.sensors and data.index.shape == other.index.shape
            and np.array_equal(data.index.to_numpy(float), other.index.to_numpy(float))
            and np.array_equal(data.positions_mm, other.positions_mm)
            and np.allclose(data.temperatures.to_numpy(float), other.temperatures.to_numpy(float),
                            rtol=0, atol=0.005 + 1e-9)
            and np.allclose(data.errors, other.errors, rtol=0, atol=0.0005 + 1e-9))


def reconstruction_seed(folder, data, *, seeds=()) -> int | None:
    """The seed of the paper's reconstruction that ``folder`` holds, or None: decided by content.

    The folder holds the committed reconstruction when its ``temperatures.csv`` and
    ``errors.csv`` (and its ``experiments.csv``, if it has one) are byte-identical to the files
    whose SHA-256 the repository's ``data/thermal/provenance.json`` records: a copy anywhere
    is the reconstruction, and an edited file in ``data/thermal`` is not.  Otherwise, for each
    of ``seeds`` (a run's own seed, whose reconstruction it wrote into its output folder), the
    data ``read`` from the folder are compared number by number with
    :func:`reconstruct` of that seed at the resolution of the files.  Where the folder is, never
    matters.

    Parameters
    ----------
    folder : path
        The folder that was read.
    data : ThermalData
        What was read from it.
    seeds : sequence of int
        Other seeds to test (the committed one is tested by its hashes).

    Returns
    -------
    int or None
        :data:`.xu2022_reconstruction.DEFAULT_SEED`, one of ``seeds``, or None for a reader's
        own data.
    """
    folder = Path(folder)
    recorded = provenance.read(paths.ROOT / DEFAULT_DIR).get("files", {})
    names = [*DATA_FILES, *(["experiments.csv"] if (folder / "experiments.csv").is_file() else [])]
    if recorded and all((folder / n).is_file() and recorded.get(n, {}).get("sha256")
                        == provenance.sha256(folder / n) for n in names):
        return DEFAULT_SEED
    for s in dict.fromkeys(int(s) for s in seeds if int(s) != DEFAULT_SEED):
        if _same_numbers(data, reconstruct(s)):
            return s
    return None


def resolve_split(stem: str, data, *, train, test) -> tuple[list[int], int]:
    """The experiments of the notebook's split: ``(train, test)`` with the defaults resolved.

    ``test`` 0 is the last experiment, an empty ``train`` every other one (on the
    reconstruction: train 1 2 3, test 4, as the paper).  Refuses (``ParameterError``)
    experiments the data lack, a test experiment also trained on, and fewer than 2 training
    experiments (the SVR's cross-validation leaves one out).
    """
    test = int(data.experiments[-1]) if test == 0 else int(test)
    train = [int(e) for e in train] or [int(e) for e in data.experiments if e != test]
    absent = sorted(set(train + [test]) - set(int(e) for e in data.experiments))
    if absent:
        raise ParameterError(f"{stem}: experiment(s) {absent} are not in the data; they have "
                             f"{[int(e) for e in data.experiments]}")
    check_experiments(stem, train, test)
    return train, test


def resolve_inputs(inputs: str, paper: bool) -> str:
    """The model inputs ``inputs`` stands for: ``auto`` resolved, the others as they are.

    ``auto``: the paper's sensitive points on its reconstruction, the ones the paper's
    procedure selects on any other data.
    """
    return ("published" if paper else "selected") if inputs == "auto" else inputs


def check_experiments(stem: str, train, test) -> None:
    """Refuse a split whose test experiment is also trained on, or with < 2 training experiments.

    The SVR's cross-validation leaves one training experiment out.
    """
    if test in train:
        raise ParameterError(f"{stem}: test_experiment {test} is also a training experiment")
    if len(set(train)) < 2:
        raise ParameterError(f"{stem}: train_experiments needs at least 2 experiments (SVR "
                             f"cross-validation leaves one out), got {train}")


def check_data(stem: str, data, folder, train, test, n_clusters: int, inputs: str,
               paper_inputs: dict) -> list[str]:
    """Refuse parameters the data cannot serve; returns the paper's sensors the data lack."""
    absent = sorted(set(train + [test]) - set(data.experiments))
    if absent:
        raise ParameterError(f"{stem}: experiment(s) {absent} are not in {folder}; "
                             f"it has {data.experiments}")
    if n_clusters > len(data.sensors):
        raise ParameterError(f"{stem}: n_clusters = {n_clusters} exceeds the "
                             f"{len(data.sensors)} sensors")
    lacking = sorted({s for v in paper_inputs.values() for s in v} - set(data.sensors))
    if inputs == "published" and lacking:
        raise ParameterError(f"{stem}: inputs = 'published' needs the paper's sensors, and "
                             f"{folder} lacks {lacking}; use inputs = 'selected'")
    return lacking


def reader_notes(data) -> str:
    """What the reader set aside (dead sensors, ignored columns), one line each, or "nothing".

    The line saying nothing was set aside is "the reader set nothing aside".
    """
    notes = [f"sensor {name} dropped: {why}" for name, why in getattr(data, "dropped", {}).items()]
    notes += [f"column {name} ignored: {why}" for name, why in
              getattr(data, "ignored_columns", {}).items()]
    return "\n".join(notes) or "the reader set nothing aside"


class Progress:
    """Progress of a long fit as one line that updates in place in the notebook.

    An IPython display handle, for ``progress=`` of :func:`thermal.evaluate_split` and
    :func:`thermal.leave_one_experiment_out`: each call shows the step and the seconds since
    the start; :meth:`done` leaves a final line without times, so that the stored notebook does
    not change from run to run.
    """

    def __init__(self, what: str):
        self.what, self.handle, self.t0 = what, None, None

    def _show(self, text: str) -> None:
        from IPython.display import Pretty, display  # IPython: only where a notebook runs

        if self.handle is None:
            self.t0 = time.perf_counter()
            self.handle = display(Pretty(text), display_id=True)
        else:
            self.handle.update(Pretty(text))

    def __call__(self, text: str) -> None:
        elapsed = 0.0 if self.t0 is None else time.perf_counter() - self.t0
        self._show(f"{self.what}: {text} ({elapsed:.0f} s)")

    def done(self) -> None:
        """Replace the line by "<what>: done" (nothing, if nothing was shown)."""
        if self.handle is not None:
            self._show(f"{self.what}: done")


def sampling_se(rep_se, *key):
    """Sampling standard error of one of our numbers (notebook 04, Section 8), or None.

    ``rep_se`` indexed by ``key``; None without replicates or for a number they do not cover.
    """
    return None if rep_se is None or key not in rep_se.index else float(rep_se[key])


def stated(ours, method: str, col: str) -> tuple[str, bool]:
    """The paper's conclusion about one error metric of ``method``, and whether ours keep it.

    The conclusions of Sections 3.1 and 3.3; ``ours`` is ``split.table`` indexed by method and
    target.
    """
    pbp, mlr, svr = (ours.loc[(m, ERROR), col] for m in
                     ("point_by_point_mlr", "decoupled_mlr", "decoupled_svr"))
    name = METRIC_NAMES[col]
    return {"point_by_point_mlr": (f"point-by-point has the largest {name} of the three models "
                                   f"(Sections 3.1, 3.3: 'prediction accuracy is poor')",
                                   pbp > max(mlr, svr)),
            "decoupled_mlr": (f"decoupled MLR has a smaller {name} than point-by-point "
                              f"(Table 7 against Table 4)", mlr < pbp),
            "decoupled_svr": (f"decoupled SVR has a smaller {name} than decoupled MLR and "
                              f"point-by-point (Table 8 against Tables 7 and 4)",
                              svr < min(mlr, pbp))}[method]


def beats(result) -> tuple[dict, object]:
    """Whether each decoupled model's largest residual is below point-by-point's (Section 5).

    Also returns the largest residuals by (method, target).
    """
    t = result.table.set_index(["method", "target"]).max_residual
    pbp = t[("point_by_point_mlr", ERROR)]
    return {m: t[(m, ERROR)] < pbp for m in ("decoupled_mlr", "decoupled_svr")}, t


#: Decimals (um, um/m) of the values the prediction figures draw: 1e-4 um is a few thousandths
#: of a pixel there (about 0.03 um a pixel).  Below it a model's predictions carry rounding
#: that another CPU changes (another BLAS kernel: about 1e-14 um for the MLR, 1e-10 um for the
#: SVR), and the PNG's antialiased pixels changed from it; drawn to 1e-4 um the figures are
#: the same on any CPU unless a value lies within that noise of a rounding edge.
PLOT_DECIMALS = 4


def _plotted(values):
    """Values as the figures draw them: to :data:`PLOT_DECIMALS` decimals."""
    return np.round(np.asarray(values, dtype=float), PLOT_DECIMALS) + 0.0


def prediction_figure(positions_mm, index, measured, predicted, *, title: str):
    """Measured (solid) and predicted (dashed) errors along the axis, and the residuals.

    Drawn to :data:`PLOT_DECIMALS` decimals.
    """
    import matplotlib.pyplot as plt  # heavy (a GUI backend): loaded only to draw

    measured, predicted = _plotted(measured), _plotted(predicted)
    resid = measured - predicted
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    cm = plt.get_cmap("plasma")(np.linspace(0, 0.85, len(index)))
    for c, (_, r), y, yp in zip(cm, index.iterrows(), measured, predicted, strict=True):
        axes[0].plot(positions_mm, y, "o-", ms=3, color=c, label=f"{r.time_min:g} min")
        axes[0].plot(positions_mm, yp, "--", color=c)
        axes[1].plot(positions_mm, y - yp, "o-", ms=3, color=c)
    axes[0].set_title("measured (solid) and predicted (dashed)")
    axes[1].set_title(f"residual: {resid.min():.1f} .. {resid.max():.1f} µm")
    for ax in axes:
        ax.set_xlabel("position (mm)")
        ax.set_ylabel("error (µm)")
    if len(index) <= 24:
        axes[0].legend(fontsize=6, ncol=2)
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def kb_figure(measurement, measured_kb, predicted_kb, *, title: str, colour):
    """Slope k and intercept b of every test measurement: decoupled and predicted.

    k and b decoupled from the data, and predicted from the temperatures; drawn to
    :data:`PLOT_DECIMALS` decimals.
    """
    import matplotlib.pyplot as plt  # heavy (a GUI backend): loaded only to draw

    measured_kb, predicted_kb = [_plotted(v) for v in measured_kb], [_plotted(v) for v in
                                                                     predicted_kb]

    fig, axes = plt.subplots(1, 2, figsize=(10, 3.6))
    for ax, meas, pred, lab in ((axes[0], measured_kb[0], predicted_kb[0], "slope k (µm/m)"),
                                (axes[1], measured_kb[1], predicted_kb[1], "intercept b (µm)")):
        ax.plot(measurement, meas, "o-", color=colour, label="decoupled from the data")
        ax.plot(measurement, pred, "s--", color="k", label="predicted from temperatures")
        ax.set_xlabel("measurement")
        ax.set_ylabel(lab)
        ax.set_title(f"largest residual {np.abs(meas - pred).max():.2f}")
    axes[0].legend(fontsize=7)
    fig.suptitle(title)
    fig.tight_layout()
    return fig


# ------------------------------------------------------------------------------------------
# Table 3 against the paper's own method (Section 1.1, steps 1-4): a check on printed numbers
# ------------------------------------------------------------------------------------------

#: Largest number of labelled assignments :func:`partition_fits` enumerates (3**14).
MAX_ASSIGNMENTS = 3 ** 14


def partition_fits(rows, sensors, n_clusters: int = 3):
    """Which printed sensor sets each assignment of ``sensors`` to clusters can produce.

    Section 1.1's rule: one sensor, the best graded, from every one of ``n_clusters`` clusters.
    Xu et al. 2022 cluster the *temperatures* (Eqs. 1-3: similarities between temperature
    sequences) and only then grade each cluster's sensors against the target (Eq. 4).  Table
    3's 14 positions share their temperatures, so they share one partition; whatever the
    grades, a position's sensitive points then lie one in each cluster.  A printed set
    ``row`` fits an assignment when its sensors carry pairwise different labels and cover
    all ``n_clusters`` labels.  Written by hand: it is the paper's rule, enumerated
    exhaustively (numpy, no Python loop over assignments).

    Parameters
    ----------
    rows : sequence of sequence of str
        The printed sets (e.g. Table 3's 14 rows), each of ``n_clusters`` sensor names.
    sensors : sequence of str
        Every sensor that may be clustered (``S`` names, e.g. T1-T12).
    n_clusters : int
        Clusters of the partition (the paper: 3).

    Returns
    -------
    numpy.ndarray of bool, shape (n_clusters ** S, R)
        ``fits[a, r]``: row ``r`` is producible under assignment ``a``, where assignment
        ``a`` gives sensor ``s`` the label ``(a // n_clusters ** s) % n_clusters``.  Every
        partition into ``n_clusters`` non-empty clusters appears ``n_clusters!`` times.
    """
    sensors = list(sensors)
    n_clusters = validate.integer(n_clusters, "n_clusters", low=1)
    if n_clusters ** len(sensors) > MAX_ASSIGNMENTS:
        raise ValueError(f"{n_clusters}**{len(sensors)} assignments: more than the "
                         f"{MAX_ASSIGNMENTS} this exhaustive check enumerates")
    index = []
    for r in rows:
        r = list(r)
        unknown = [s for s in r if s not in sensors]
        if unknown or len(set(r)) != n_clusters or len(r) != n_clusters:
            raise ValueError(f"row {' '.join(r)}: needs {n_clusters} different sensors out of "
                             f"{' '.join(sensors)}" + (f" (unknown: {unknown})" if unknown else ""))
        index.append([sensors.index(s) for s in r])
    a = np.arange(n_clusters ** len(sensors), dtype=np.int64)
    labels = ((a[:, None] // n_clusters ** np.arange(len(sensors))) % n_clusters).astype(np.int8)
    lab = labels[:, np.array(index, dtype=np.intp).reshape(len(index), n_clusters)]  # (A, R, n)
    # a row of n sensors is producible when its labels are 0..n-1, one per cluster
    return (np.sort(lab, axis=-1) == np.arange(n_clusters)).all(axis=-1)


def table3_consistency(rows, sensors, n_clusters: int = 3) -> dict:
    """How much of Table 3 one partition of the sensors can produce, and which rows none can.

    Table 3 is a per-position table of sensitive points; :func:`partition_fits` enumerates the
    partitions; the smallest set of rows that no partition produces is returned too.

    Parameters
    ----------
    rows : sequence of sequence of str
        The printed sets, one per position.
    sensors : sequence of str
        Every sensor that may be clustered.
    n_clusters : int
        Clusters of the partition.

    Returns
    -------
    dict
        ``assignments`` (``n_clusters ** S``), ``best`` (most rows one assignment fits),
        ``best_assignments`` and ``best_partitions`` (how many attain it, labelled and as
        partitions: labelled / ``n_clusters!``), ``missed`` (for every row, in how many best
        assignments it is not fitted), ``best_partition`` (the canonical best: the smallest
        assignment index, as lists of sensors in cluster-label order), ``conflict`` (row
        indices of the smallest set of rows no assignment fits, the first in lexicographic
        order among the smallest; empty if every row set fits), ``fits`` (the array of
        :func:`partition_fits`).
    """
    sensors = list(sensors)
    fits = partition_fits(rows, sensors, n_clusters)
    count = fits.sum(axis=1)
    best = int(count.max())
    at_best = count == best
    first = int(np.flatnonzero(at_best)[0])
    label = (first // n_clusters ** np.arange(len(sensors))) % n_clusters
    conflict: tuple[int, ...] = ()
    if best < fits.shape[1]:
        for size in range(1, fits.shape[1] + 1):
            conflict = next((c for c in itertools.combinations(range(fits.shape[1]), size)
                             if not fits[:, list(c)].all(axis=1).any()), ())
            if conflict:
                break
    return {"assignments": int(fits.shape[0]), "best": best,
            "best_assignments": int(at_best.sum()),
            "best_partitions": int(at_best.sum()) // math.factorial(n_clusters) if best else 0,
            "missed": (~fits[at_best]).sum(axis=0), "conflict": list(conflict),
            "best_partition": sorted(([s for s, lab in zip(sensors, label, strict=True) if lab == c]
                                      for c in range(n_clusters)), key=lambda g: sensors.index(g[0])
                                     if g else len(sensors)),
            "fits": fits}


def rows_fitted_by(rows, clusters) -> list[bool]:
    """Whether each printed set takes exactly one sensor from every cluster of ``clusters``.

    A sensor in no cluster fits nowhere.

    Parameters
    ----------
    rows : sequence of sequence of str
        The printed sets.
    clusters : sequence of sequence of str
        A partition (e.g. one of Table 6's).

    Returns
    -------
    list of bool
        One entry per row.
    """
    where = {s: i for i, g in enumerate(clusters) for s in g}
    return [len(r) == len(clusters) and all(s in where for s in r)
            and len({where[s] for s in r}) == len(clusters) for r in rows]
