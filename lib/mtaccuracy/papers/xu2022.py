"""Notebook 04's paper code (Xu et al. 2022): published values, the reconstruction, the figures.

The thermal science (:mod:`mtaccuracy.thermal`) takes arrays and tables and never reads
``data/papers/`` or knows the repository's folders; this module does that for notebook 04: it
reads the published tables the reconstruction is built from (the seeded generator is
:mod:`mtaccuracy.papers.xu2022_reconstruction`), says by content whether a folder holds the
committed reconstruction (:func:`reconstruction_seed`), and holds the notebook's checks,
scorecard helpers and figure captions (:data:`FIGURES`).

A normal run of the notebook only reads its ``data_dir``.  Rewriting ``data/thermal`` is a
command of its own, :func:`regenerate`::

    python -m mtaccuracy.papers.xu2022 regenerate [FOLDER] [--seed S]
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import sys
import time
from pathlib import Path

import numpy as np
import param

from .. import thermal, validate
from . import printed, xu2022_reconstruction
from .figure import Caption, figures
from .parameters import InputFolder, NotebookParameters, NumberList, OutputFolder, ParameterError
from .xu2022_reconstruction import DEFAULT_SEED

__all__ = [
    "DATA", "DATA_FILES", "published_targets", "published_models", "published_inputs",
    "published_metrics", "reconstruct", "noise_replicates", "calibrate", "reconstruction_seed",
    "regenerate", "data_origin", "resolve_split", "resolve_inputs", "check_experiments",
    "check_data", "reader_notes", "Progress", "sampling_se", "stated", "beats",
    "prediction_figure", "kb_figure", "data_fields", "model_fields", "loeo_fields",
    "pooled_fields", "caption", "FIGURES", "partition_fits", "table3_consistency",
    "rows_fitted_by", "main",
]

#: The committed reconstruction (``data/thermal``), with its ``provenance.json``: the generator,
#: the seed and the hashes of the files it wrote there (:func:`regenerate`).
DATA = printed.FOLDER.parent / "thermal"
#: The files whose content makes a folder the reconstruction (``experiments.csv`` may be absent).
DATA_FILES = ("temperatures.csv", "errors.csv", "experiments.csv")


def published_targets(*, on_read=None) -> xu2022_reconstruction.Targets:
    """Table 5 (k, b) and Table 1 (feeds, ambient ranges) from ``data/papers``.

    Parameters
    ----------
    on_read : callable, optional
        Called with each file read (``run.track``, for the run's provenance).

    Returns
    -------
    xu2022_reconstruction.Targets
        What the generator is built from.
    """
    t5 = printed.published("xu2022_table5_slope_intercept",
                           ["experiment", "measurement", "k_um_per_m", "b_um"], on_read=on_read)
    t1 = printed.published("xu2022_table1_experiments",
                           ["experiment", "feed_mm_per_min", "ambient_min_C", "ambient_max_C"],
                           on_read=on_read)
    return xu2022_reconstruction.targets_from_tables(t5, t1)


def published_models(*, on_read=None):
    """The printed models (Eqs. 8-9) from ``data/papers/xu2022_models.csv``.

    Parameters
    ----------
    on_read : callable, optional
        Called with the file read.

    Returns
    -------
    pandas.DataFrame
        ``model, target, term, coefficient``, as printed (text).
    """
    return printed.published("xu2022_models", ["model", "target", "term", "coefficient"],
                             on_read=on_read)


def published_inputs(*, on_read=None) -> dict[str, list[str]]:
    """The paper's sensitive points, read off the terms of its printed models.

    Parameters
    ----------
    on_read : callable, optional
        Called with the file read (``data/papers/xu2022_models.csv``).

    Returns
    -------
    dict
        ``{"point": Eq. 8's sensors, "k": Eq. 9's for the slope, "b": Eq. 9's for the
        intercept}``, each in the order the paper prints them.
    """
    models = published_models(on_read=on_read)
    terms = models[models.term != "intercept"]

    def of(model, prefix=""):
        rows = terms[(terms.model == model) & terms.target.str.startswith(prefix)]
        return list(dict.fromkeys(t.removeprefix("d") for t in rows.term))
    return {"point": of("point_by_point_mlr"), "k": of("decoupled_mlr", "k"),
            "b": of("decoupled_mlr", "b")}


def published_metrics(*, on_read=None):
    """The printed prediction metrics (Tables 4, 7, 8) from ``data/papers/xu2022_metrics.csv``.

    Parameters
    ----------
    on_read : callable, optional
        Called with the file read.

    Returns
    -------
    pandas.DataFrame
        ``table, method, target, rmse, max_residual, mae, unit``, as printed (text).
    """
    return printed.published("xu2022_metrics", ["table", "method", "target", "rmse",
                                                "max_residual", "mae", "unit"], on_read=on_read)


def reconstruct(seed: int = DEFAULT_SEED, *, on_read=None) -> thermal.ThermalData:
    """:func:`.xu2022_reconstruction.reconstruct` on the published targets, in memory.

    Parameters
    ----------
    seed : int
        Seed of the reconstruction's noise (:data:`DEFAULT_SEED` gives ``data/thermal``).
    on_read : callable, optional
        Called with each published table read.

    Returns
    -------
    ThermalData
        The reconstruction, as :func:`mtaccuracy.thermal.read_measurements` would read it
        written.
    """
    return xu2022_reconstruction.reconstruct(published_targets(on_read=on_read), seed)


def noise_replicates(seed: int = DEFAULT_SEED, n: int = 40, *, on_read=None):
    """:func:`.xu2022_reconstruction.noise_replicates` on the published targets.

    Parameters
    ----------
    seed : int
        Seed of the reconstruction (replicate 0).
    n : int
        Replicates, replicate 0 included.
    on_read : callable, optional
        Called with each published table read.

    Returns
    -------
    xu2022_reconstruction.Replicates
        ``n`` realisations of the reconstruction's noise.
    """
    return xu2022_reconstruction.noise_replicates(published_targets(on_read=on_read), seed, n)


def calibrate(**kwargs):
    """:func:`.xu2022_reconstruction.calibrate` on the published tables (about a minute).

    Parameters
    ----------
    **kwargs
        Passed on to :func:`.xu2022_reconstruction.calibrate`.

    Returns
    -------
    object
        What :func:`.xu2022_reconstruction.calibrate` returns.
    """
    return xu2022_reconstruction.calibrate(published_targets(), published_models(),
                                           published_metrics(), **kwargs)


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _recorded() -> tuple[int | None, dict]:
    """The seed and ``{file: sha256}`` that ``data/thermal/provenance.json`` records."""
    try:
        side = json.loads((DATA / "provenance.json").read_text(encoding="utf-8"))
        files = {n: e["sha256"] for n, e in side["files"].items() if "sha256" in e}
        return int(side["run"]["seed"]), files
    except (OSError, ValueError, KeyError, TypeError):
        return None, {}


def reconstruction_seed(folder) -> int | None:
    """The seed of the committed reconstruction when ``folder`` holds it, else None.

    Decided by content: its ``temperatures.csv`` and ``errors.csv`` (and ``experiments.csv``,
    if it has one) are byte-identical to the files whose SHA-256 ``data/thermal/provenance.json``
    records.  A copy anywhere is the reconstruction; an edited file in ``data/thermal`` is not.
    The seed is the one that file records (:data:`DEFAULT_SEED`, 2022, as committed).

    Parameters
    ----------
    folder : path
        The folder the measurements were read from.

    Returns
    -------
    int or None
        The seed of the reconstruction, or None for a reader's own data.
    """
    folder = Path(folder)
    seed, recorded = _recorded()
    names = [n for n in DATA_FILES if n != "experiments.csv" or (folder / n).is_file()]
    if recorded and all((folder / n).is_file() and recorded.get(n) == _sha256(folder / n)
                        for n in names):
        return seed
    return None


def regenerate(folder=DATA, *, seed: int = DEFAULT_SEED) -> list[Path]:
    """Write the reconstruction with ``seed`` into ``folder`` (``data/thermal``): its own command.

    A normal run of notebook 04 only reads its data; this rewrites them (``python -m
    mtaccuracy.papers.xu2022 regenerate``) and the folder's ``provenance.json`` (generator,
    seed, each file's SHA-256).  A file is written only when its bytes change, and a file whose
    bytes are not those ``data/thermal/provenance.json`` records (edited by someone; in any
    other folder, every existing file that would change) is never overwritten: nothing is
    written and the error names it.

    Parameters
    ----------
    folder : path
        Where to write (created if missing).
    seed : int
        Seed of the reconstruction's noise; the committed files are :data:`DEFAULT_SEED`'s.

    Returns
    -------
    list of Path
        The data files that changed.

    Raises
    ------
    RuntimeError
        A file would be overwritten that the generator did not write last.
    """
    folder = Path(folder)
    recorded = _recorded()[1] if folder.resolve() == DATA.resolve() else {}

    def refuse(files):
        edited = [p for p in files if recorded.get(p.name) != _sha256(p)]
        if edited:
            raise RuntimeError(f"{', '.join(str(p) for p in edited)}: edited since the "
                               f"generator wrote it (not the SHA-256 {folder}/provenance.json "
                               f"records); nothing was written: restore it (git checkout) or "
                               f"move it away first")
    folder.mkdir(parents=True, exist_ok=True)
    changed = thermal.write_measurements(reconstruct(seed), folder, before_overwrite=refuse)
    files = {n: {"sha256": _sha256(folder / n)} for n in DATA_FILES if (folder / n).is_file()}
    side = {"run": {"generator": "mtaccuracy.papers.xu2022_reconstruction", "seed": seed},
            "files": files}
    text = json.dumps(side, sort_keys=True, indent=1) + "\n"
    if not (folder / "provenance.json").is_file() or \
            (folder / "provenance.json").read_text(encoding="utf-8") != text:
        (folder / "provenance.json").write_text(text, encoding="utf-8")
    return changed


def data_origin(data_dir, recon_seed: int | None, seed: int) -> str:
    """What notebook 04 does with its data, in one line (its output says so).

    Parameters
    ----------
    data_dir : str
        The ``data_dir`` parameter, as given.
    recon_seed : int or None
        :func:`reconstruction_seed` of the folder read.
    seed : int
        The ``seed`` parameter.

    Returns
    -------
    str
        The reconstruction read as it is, the reconstruction with another seed built in memory
        (nothing written), or a reader's own data ("not the paper's reconstruction").
    """
    if recon_seed is None:
        return (f"{data_dir}: your measurements, read only; not the paper's reconstruction: the "
                f"method on these data, no comparison with the paper (seed does not apply)")
    if seed == recon_seed:
        return (f"{data_dir}: the paper's reconstruction (seed {seed}; its files' SHA-256 are "
                f"those data/thermal/provenance.json records), read only: compared with the "
                f"paper below")
    return (f"{data_dir}: the paper's reconstruction with seed {recon_seed}; seed = {seed}: the "
            f"reconstruction with seed {seed}, built in memory (nothing written; `python -m "
            f"mtaccuracy.papers.xu2022 regenerate FOLDER --seed {seed}` writes it): compared "
            f"with the paper below")


# ------------------------------------------------------------------------------------------
# Notebook 04's checks and scorecard helpers
# ------------------------------------------------------------------------------------------

RECONSTRUCTED_LABEL = "reconstructed data, not the paper's measurements"
ERROR = "thermal positioning error"
METRIC_NAMES = {"rmse": "RMSE", "max_residual": "largest residual", "mae": "MAE"}
METHODS = ("point_by_point_mlr", "decoupled_mlr", "decoupled_svr")


def resolve_split(stem: str, data, *, train, test) -> tuple[list[int], int]:
    """The experiments of the notebook's split: ``(train, test)`` with the defaults resolved.

    ``test`` 0 is the last experiment, an empty ``train`` every other one (on the
    reconstruction: train 1 2 3, test 4, as the paper).

    Parameters
    ----------
    stem : str
        The notebook, for the messages.
    data : ThermalData
        The measurements.
    train : list of int
        ``train_experiments`` as given (empty: all but the test one).
    test : int
        ``test_experiment`` as given (0: the last one).

    Returns
    -------
    (list of int, int)
        The training experiments and the test experiment.

    Raises
    ------
    ParameterError
        Experiments the data lack, a test experiment also trained on, fewer than 2 training
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

    Parameters
    ----------
    inputs : str
        ``auto``, ``published`` or ``selected``.
    paper : bool
        Whether the data are the paper's reconstruction.

    Returns
    -------
    str
        ``auto``: the paper's sensitive points (``published``) on its reconstruction, the ones
        the paper's procedure selects (``selected``) on any other data.
    """
    return ("published" if paper else "selected") if inputs == "auto" else inputs


def check_experiments(stem: str, train, test) -> None:
    """Refuse a split whose test experiment is also trained on, or with < 2 training experiments.

    Parameters
    ----------
    stem : str
        The notebook, for the messages.
    train : list of int
        The training experiments.
    test : int or None
        The test experiment (None: not known yet).

    Raises
    ------
    ParameterError
        The SVR's cross-validation leaves one training experiment out: it needs two.
    """
    if test in train:
        raise ParameterError(f"{stem}: test_experiment {test} is also a training experiment")
    if len(set(train)) < 2:
        raise ParameterError(f"{stem}: train_experiments needs at least 2 experiments (SVR "
                             f"cross-validation leaves one out), got {train}")


def check_data(stem: str, data, folder, train, test, n_clusters: int, inputs: str,
               paper_inputs: dict) -> list[str]:
    """Refuse parameters the data cannot serve; return the paper's sensors the data lack.

    Parameters
    ----------
    stem : str
        The notebook, for the messages.
    data : ThermalData
        The measurements.
    folder : path
        Where they were read from, for the messages.
    train, test : list of int, int
        The resolved split (:func:`resolve_split`).
    n_clusters : int
        Clusters of the fuzzy clustering: at most the number of sensors.
    inputs : str
        The resolved model inputs: ``published`` needs every sensor of the paper's models.
    paper_inputs : dict
        :func:`published_inputs`.

    Returns
    -------
    list of str
        The paper's sensitive points the data have no column for.

    Raises
    ------
    ParameterError
        Naming the parameter and what the data hold.
    """
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
    """What the reader set aside (dead sensors, ignored columns), one line each.

    Parameters
    ----------
    data : ThermalData
        As read.

    Returns
    -------
    str
        One line per dropped sensor or ignored column, or "the reader set nothing aside".
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

    Parameters
    ----------
    what : str
        What is computed, the start of the line.
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

    Parameters
    ----------
    rep_se : pandas.Series or None
        Standard deviations over the noise replicates, indexed by tuples.
    *key
        The number's index in ``rep_se``.

    Returns
    -------
    float or None
        None without replicates or for a number they do not cover.
    """
    return None if rep_se is None or key not in rep_se.index else float(rep_se[key])


def stated(ours, method: str, col: str) -> tuple[str, bool]:
    """The paper's conclusion about one error metric of ``method``, and whether ours keep it.

    Parameters
    ----------
    ours : pandas.DataFrame
        ``split.table`` indexed by method and target.
    method : str
        One of :data:`METHODS`.
    col : str
        ``rmse``, ``max_residual`` or ``mae``.

    Returns
    -------
    (str, bool)
        The conclusion of Sections 3.1 and 3.3 about that metric, and whether it holds.
    """
    pbp, mlr, svr = (ours.loc[(m, ERROR), col] for m in METHODS)
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

    Parameters
    ----------
    result : SplitResult
        :func:`mtaccuracy.thermal.evaluate_split`.

    Returns
    -------
    (dict, pandas.Series)
        ``{method: bool}`` for the decoupled models, and the largest residuals by (method,
        target).
    """
    t = result.table.set_index(["method", "target"]).max_residual
    pbp = t[("point_by_point_mlr", ERROR)]
    return {m: t[(m, ERROR)] < pbp for m in ("decoupled_mlr", "decoupled_svr")}, t


# ------------------------------------------------------------------------------------------
# The captions' numbers: every one computed by the run (:func:`caption` fills them in)
# ------------------------------------------------------------------------------------------

_WORDS = ("no", "one", "two", "three", "four", "five", "six", "seven", "eight", "nine", "ten",
          "eleven", "twelve")


def _counted(n: int, noun: str) -> str:
    """``four experiments``, ``one sensor``, ``15 positions``."""
    return f"{_WORDS[n] if 0 <= n < len(_WORDS) else n} {noun}{'' if n == 1 else 's'}"


def _listed(items) -> str:
    """``1 to 3`` (three or more consecutive integers), else ``1, 3 and 5``."""
    items = [str(v) for v in items]
    as_int = [int(v) for v in items if v.lstrip("-").isdigit()]
    if len(items) >= 3 and len(as_int) == len(items) and as_int == list(
            range(as_int[0], as_int[0] + len(as_int))):
        return f"{items[0]} to {items[-1]}"
    return items[0] if len(items) == 1 else f"{', '.join(items[:-1])} and {items[-1]}"


def _um(v: float, digits: int = 1) -> str:
    """A signed number with a typographic minus (``−6.0``)."""
    return f"{v + 0.0:.{digits}f}".replace("-", "−")


def _extreme(d) -> tuple[float, float]:
    """The error of largest magnitude of ``d`` and its position (mm)."""
    i, j = np.unravel_index(np.abs(d.errors).argmax(), d.errors.shape)
    return float(d.errors[i, j]), float(d.positions_mm[j])


def _farthest(data, others, test) -> str:
    """The sentence of Fig. 9's caption on the experiments that drift furthest."""
    ext = {e: _extreme(data.subset(e)) for e in others}
    far = max(others, key=lambda e: abs(ext[e][0]))
    v, p = ext[far]
    predicted = ", the one predicted in Figs. 11 to 17,"
    if far == test:
        return f"Experiment {far}{predicted} drifts furthest ({_um(v)} µm at {p:g} mm)."
    out = f"Experiment {far} drifts furthest ({_um(v)} µm at {p:g} mm)"
    if test in ext:
        out += f"; experiment {test}{predicted} reaches {_um(ext[test][0])} µm"
    return out + "."


def data_fields(data, *, train, test, air) -> dict[str, str]:
    """The numbers the captions of the data figures (Figs. 3, 5-10, 12) state, as text.

    Parameters
    ----------
    data : ThermalData
        The measurements.
    train : list of int
        The training experiments.
    test : int
        The test experiment.
    air : str or None
        The ambient sensor, if the data have it.

    Returns
    -------
    dict of str
        Fields of :data:`FIGURES`' texts: the experiments, measurements, times, feeds,
        positions and sensors; the first experiment's largest error, drift and zeroed spread
        (Figs. 5-8); the experiments that drift furthest (Fig. 9); the warmest and steadiest
        sensors (Fig. 10); the split.
    """
    exps = [int(e) for e in data.experiments]
    first, others = exps[0], exps[1:]
    per = data.index.groupby("experiment").size()
    d = data.subset(first)
    t, pos = d.index.time_min.to_numpy(float), data.positions_mm
    drift = np.ptp(d.errors, axis=0)
    v, p = _extreme(d)
    temps = d.temperatures
    feed = {e: f"{data.feeds[e]:g}" for e in exps if e in data.feeds}
    feeds = [float(data.feeds[e]) for e in exps if e in data.feeds]
    return {
        "air": air or "",
        "experiments": _counted(len(exps), "warm-up experiment"),
        "measurements": (_counted(int(per.iloc[0]), "measurement") if per.nunique() == 1
                         else f"{per.min()} to {per.max()} measurements"),
        "times": f"{data.index.time_min.min():g} to {data.index.time_min.max():g} min",
        "feeds": f", feeds {min(feeds):g} to {max(feeds):g} mm/min" if feeds else "",
        "first": str(first),
        "first_feed": f" ({feed[first]} mm/min)" if first in feed else "",
        "positions": f"{_counted(len(pos), 'target position')} {pos[0]:g} to {pos[-1]:g} mm",
        "pos_first": f"{pos[0]:g}", "pos_last": f"{pos[-1]:g}",
        "first_times": f"{t[0]:g} to {t[-1]:g} min", "duration": f"{t[-1] - t[0]:g}",
        "first_extreme": f"{_um(v)} µm at {p:g} mm",
        "drift": f"{drift.min():.1f} to {drift.max():.1f} µm",
        "zeroed": f"{np.ptp(d.errors - d.errors[:, [0]], axis=0).max():.1f}",
        "others": _listed(others),
        "others_feeds": (f" ({', '.join(feed[e] for e in others)} mm/min)"
                         if all(e in feed for e in others) else ""),
        "farthest": _farthest(data, others, test),
        "sensors": _counted(len(data.sensors), "sensor"),
        "warmest": _listed(temps.mean().sort_values(ascending=False, kind="stable").index[:3]),
        "steadiest": _listed((temps.max() - temps.min()).sort_values(kind="stable").index[:3]),
        "train": _listed(train), "test": str(test),
    }


def _points(sensors, paper: bool) -> str:
    return (f"the paper's sensitive points {_listed(sensors)}" if paper else
            f"the sensitive points {_listed(sensors)}, selected on the training experiments")


def model_fields(split, paper_inputs: dict, metrics=None) -> dict[str, str]:
    """The numbers the captions of the model figures (Figs. 11, 14-17) state, as text.

    Parameters
    ----------
    split : SplitResult
        :func:`mtaccuracy.thermal.evaluate_split` on the notebook's split.
    paper_inputs : dict
        :func:`published_inputs`, to say whether the models used the paper's points.
    metrics : pandas.DataFrame, optional
        :func:`published_metrics`: given (on the paper's reconstruction), each model's
        numbers are followed by the paper's, e.g. `` (Table 7: 0.6 µm)``.

    Returns
    -------
    dict of str
        ``points``, ``k_points``, ``b_points``, ``kernels``, and for ``pbp``, ``mlr``,
        ``svr``: ``<m>_lo``, ``<m>_hi`` (the residual's range, µm), ``<m>_rmse``, ``<m>_k_max``,
        ``<m>_b_max`` and the paper's ``<m>_paper``, ``<m>_kb_paper`` (empty without
        ``metrics``).
    """
    t = split.table.set_index(["method", "target"])
    kinds = thermal.svr_hyperparameters(split.models["decoupled_svr"]).kernel.tolist()
    names = [{"rbf": "an RBF kernel"}.get(k, f"a {k} kernel") for k in kinds]
    paper = {k: split.inputs[k] == paper_inputs[k] for k in ("point", "k", "b")}
    out = {"points": _points(split.inputs["point"], paper["point"]),
           "k_points": _listed(split.inputs["k"]), "b_points": _listed(split.inputs["b"]),
           "kb_how": ("the paper's sensitive points" if paper["k"] and paper["b"]
                      else "sensitive points selected on the training experiments"),
           "kernels": (f"{kinds[0]} kernels".replace("rbf", "RBF") if len(set(kinds)) == 1
                       else f"{names[0]} for k and {names[1]} for b")}
    p = metrics.set_index(["method", "target"]) if metrics is not None else None
    for short, m in zip(("pbp", "mlr", "svr"), METHODS, strict=True):
        resid = split.measured - split.predictions[m]
        out |= {f"{short}_lo": _um(resid.min()), f"{short}_hi": _um(resid.max()),
                f"{short}_rmse": f"{t.loc[(m, ERROR), 'rmse']:.2f}",
                f"{short}_paper": "", f"{short}_kb_paper": ""}
        if m != "point_by_point_mlr":
            out |= {f"{short}_k_max": f"{t.loc[(m, 'slope k'), 'max_residual']:.2f}",
                    f"{short}_b_max": f"{t.loc[(m, 'intercept b'), 'max_residual']:.2f}"}
        if p is not None and (m, ERROR) in p.index:
            row = p.loc[(m, ERROR)]
            out[f"{short}_paper"] = f" (Table {row.table}: {row.rmse} µm)"
            if (m, "slope k") in p.index and (m, "intercept b") in p.index:
                out[f"{short}_kb_paper"] = (f" (Table {row.table}: "
                                            f"{p.loc[(m, 'slope k'), 'max_residual']} µm/m and "
                                            f"{p.loc[(m, 'intercept b'), 'max_residual']} µm)")
    return out


_CHOICES = {"published": "the paper's points", "selected": "re-selected points"}


def loeo_fields(wide, choices) -> dict[str, str]:
    """The numbers the caption of the leave-one-experiment-out figure states, as text.

    Parameters
    ----------
    wide : pandas.DataFrame
        Held-out RMSE by (inputs, held_out) and method, with the columns ``decoupled MLR beats
        point-by-point`` and ``decoupled SVR beats point-by-point``.
    choices : list of str
        The sensor choices run: ``published`` and/or ``selected``.

    Returns
    -------
    dict of str
        ``panels`` (what each panel shows) and ``wins`` (in how many splits each decoupled
        model beats point-by-point, per choice).
    """
    panels = {"published": "with the paper's sensitive points",
              "selected": "with points re-selected by the paper's own procedure on each "
                          "training set"}
    where = [" (left)", " (right)"] if len(choices) == 2 else [""]
    wins = []
    for c in choices:
        w = wide.loc[c]
        wins.append(f"with {_CHOICES[c]}, decoupled MLR beats point-by-point in "
                    f"{int(w['decoupled MLR beats point-by-point'].sum())} of {len(w)} splits "
                    f"and decoupled SVR in {int(w['decoupled SVR beats point-by-point'].sum())}")
    text = "; ".join(wins)
    return {"panels": " and ".join(panels[c] + s for c, s in zip(choices, where, strict=True)),
            "wins": text[0].upper() + text[1:] + "."}


def pooled_fields(pooled, n_sensors: int) -> dict[str, str]:
    """The numbers the caption of the baselines figure states, as text.

    Parameters
    ----------
    pooled : pandas.DataFrame
        The pooled rows of :func:`mtaccuracy.thermal.selection_vs_baselines`, indexed by model.
    n_sensors : int
        Sensors of the data (the ridge baseline uses all).

    Returns
    -------
    dict of str
        ``all_sensors``, ``with_points`` (the sensor choices shown) and ``pooled`` (every
        model's pooled RMSE, µm).
    """
    r = pooled.rmse
    label = {"point_by_point_mlr": "point-by-point", "decoupled_mlr": "decoupled MLR",
             "decoupled_svr": "decoupled SVR"}
    parts = [f"uncompensated {r['uncompensated']:.2f}", f"ridge {r['ridge_all_sensors']:.2f}"]
    choices = [c for c in _CHOICES if f"decoupled_mlr ({c})" in r.index]
    for c in choices:
        parts.append(f"with {_CHOICES[c]}: " + ", ".join(
            f"{label[m]} {r[f'{m} ({c})']:.2f}" for m in METHODS if f"{m} ({c})" in r.index))
    return {"all_sensors": _counted(n_sensors, "sensor"), "pooled": "; ".join(parts),
            "with_points": " and ".join(f"with {_CHOICES[c]}" for c in choices)}


# ------------------------------------------------------------------------------------------
# The figures drawn here, each with its caption; the chapter's captions (:data:`FIGURES`)
# ------------------------------------------------------------------------------------------

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

    Figs. 11, 15 and 17 (:data:`FIG11`, :data:`FIG15`, :data:`FIG17`), drawn to
    :data:`PLOT_DECIMALS` decimals.

    Parameters
    ----------
    positions_mm : array (P,)
        Target positions.
    index : pandas.DataFrame
        The test measurements (``time_min`` labels the curves).
    measured, predicted : array (n, P)
        Errors (µm).
    title : str
        The figure's title.

    Returns
    -------
    matplotlib.figure.Figure
        Two panels: the errors, and their residuals.
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


FIG11 = Caption(
    "fig11_point_by_point_prediction", "Fig. 11",
    "Point-by-point MLR (Eq. 8): one regression per target on the temperature rises of {points}, "
    "trained on experiments {train} and predicting experiment {test} from its temperatures. "
    "Left: measured (solid) and predicted (dashed) error per measurement. Right: the residual, "
    "{pbp_lo} to {pbp_hi} µm; RMSE {pbp_rmse} µm{pbp_paper}. {data}",
    rows=("Table 4", "Section 3.1"))
FIG15 = Caption(
    "fig15_mlr_error_prediction", "Fig. 15",
    "The error of experiment {test} recombined from the MLR-predicted k and b (Eq. 7). Left: "
    "measured (solid) and predicted (dashed) per measurement. Right: the residual, {mlr_lo} to "
    "{mlr_hi} µm, against position; RMSE {mlr_rmse} µm{mlr_paper}, against {pbp_rmse} µm for "
    "the point-by-point model of Fig. 11. {data}",
    rows=("Table 7", "Section 3.2: decoupled_mlr*"))
FIG17 = Caption(
    "fig17_svr_error_prediction", "Fig. 17",
    "The error of experiment {test} recombined from the SVR-predicted k and b: measured (solid) "
    "and predicted (dashed), and the residual, {svr_lo} to {svr_hi} µm, against position. RMSE "
    "{svr_rmse} µm{svr_paper}, against {mlr_rmse} µm{mlr_paper} for the decoupled MLR of "
    "Fig. 15. {data}",
    rows=("Table 8", "Section 3.2: decoupled_svr*", "Section 5"))


def kb_figure(measurement, measured_kb, predicted_kb, *, title: str, colour):
    """Slope k and intercept b of every test measurement: decoupled and predicted.

    Figs. 14 and 16 (:data:`FIG14`, :data:`FIG16`): k and b decoupled from the data
    (circles), and predicted from the temperatures (squares), drawn to :data:`PLOT_DECIMALS`
    decimals.

    Parameters
    ----------
    measurement : array (n,)
        The test measurements' numbers.
    measured_kb, predicted_kb : (array (n,), array (n,))
        (k, b) decoupled from the data, and predicted.
    title : str
        The figure's title.
    colour : str
        Colour of the decoupled values.

    Returns
    -------
    matplotlib.figure.Figure
        Two panels: k and b.
    """
    import matplotlib.pyplot as plt  # heavy (a GUI backend): loaded only to draw

    measured_kb = [_plotted(v) for v in measured_kb]
    predicted_kb = [_plotted(v) for v in predicted_kb]
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


FIG14 = Caption(
    "fig14_mlr_slope_intercept", "Fig. 14",
    "Slope k and intercept b of experiment {test}, decoupled from the data (circles) and "
    "predicted from its temperatures by the decoupled MLR of Eq. 9 (squares): k from the "
    "absolute temperatures of {k_points}, b from the rises of {b_points} ({kb_how}), trained on "
    "experiments {train}. Largest residuals {mlr_k_max} µm/m and {mlr_b_max} µm{mlr_kb_paper}. "
    "{data}",
    rows=("Eq. 9", "Table 7: decoupled_mlr, slope k*", "Table 7: decoupled_mlr, intercept b*"))
FIG16 = Caption(
    "fig16_svr_slope_intercept", "Fig. 16",
    "As Fig. 14, with support vector regression (inputs and target standardised, "
    "hyperparameters chosen by leave-one-experiment-out cross-validation on experiments "
    "{train}, which picks {kernels}): k and b of experiment {test}, decoupled (circles) and "
    "predicted (squares). Largest residuals {svr_k_max} µm/m and {svr_b_max} µm{svr_kb_paper}. "
    "{data}",
    rows=("Table 8: decoupled_svr, slope k*", "Table 8: decoupled_svr, intercept b*"))

#: What Figs. 5-9 show is scored by these rows.
_ERROR_ROWS = ("Table 5", "Eq. 8", "Section 3.2: largest error*")

#: The chapter's captions, in the paper's order (the book's).  ``{data}`` is what the figure's
#: data are (:func:`caption`); every other field is a number the run computed
#: (:func:`data_fields`, :func:`model_fields`, :func:`loeo_fields`, :func:`pooled_fields`).
FIGURES = figures(
    Caption("fig03_ambient_temperature", "Fig. 3",
            "Ambient temperature (sensor {air}, °C) over the {measurements} ({times}) of each "
            "of the {experiments}{feeds}. {data}", rows=("Table 1",)),
    Caption("fig05_error_vs_position", "Fig. 5",
            "Thermal positioning error (µm) of the axis at the {positions}, one curve per "
            "measurement ({first_times}) of experiment {first}{first_feed}; the laser is "
            "zeroed only at the first measurement. The largest error is {first_extreme}. "
            "{data}", rows=_ERROR_ROWS),
    Caption("fig06_error_vs_time", "Fig. 6",
            "The errors of Fig. 5 (experiment {first}) against time, one curve per target "
            "position from {pos_first} to {pos_last} mm. Over the {duration} minutes each target "
            "drifts by {drift} (the range of its readings). {data}", rows=_ERROR_ROWS),
    Caption("fig07_error_surface", "Fig. 7",
            "The errors of Figs. 5 and 6 as one surface over position ({pos_first} to "
            "{pos_last} mm) and time ({first_times}), experiment {first} (µm). {data}",
            rows=_ERROR_ROWS),
    Caption("fig08_error_zeroed", "Fig. 8",
            "The errors of Fig. 5 zeroed at the first target ({pos_first} mm) of every "
            "measurement, as a conventional measurement would show them (experiment {first}, "
            "µm). The paper's point is that zeroing hides the drift: the zeroed curves lie "
            "within {zeroed} µm of each other at every target, against a drift of {drift} in "
            "Figs. 5 and 6. {data}", rows=_ERROR_ROWS),
    Caption("fig09_error_other_experiments", "Fig. 9",
            "Thermal positioning error (µm) against position for experiments "
            "{others}{others_feeds}, one curve per measurement. {farthest} {data}",
            rows=_ERROR_ROWS),
    Caption("fig10_temperatures", "Fig. 10",
            "Temperatures (°C) of the {sensors} over experiment {first}{first_feed}. Warmest on "
            "average: {warmest}; smallest change: {steadiest}. {data}",
            rows=("Table 6", "Section 3.1: three most frequent sensitive points "
                             "(point-by-point inputs)")),
    FIG11,
    Caption("fig12_slope_intercept", "Fig. 12",
            "Slope k (µm/m) and intercept b (µm) of the straight line fitted to every "
            "measurement (Eq. 6), positions counted from the first target, {experiments} of "
            "{measurements} each; lines ours. {data}", rows=("Table 5",)),
    FIG14, FIG15, FIG16, FIG17,
    Caption("beyond_leave_one_experiment_out", "Beyond the paper",
            "RMSE of the error (µm, pooled over positions and measurements) when each "
            "experiment in turn is predicted from models trained on the others: point-by-point "
            "MLR, decoupled MLR and decoupled SVR, {panels}. {wins} {data}"),
    Caption("beyond_selection_vs_baselines", "Beyond the paper",
            "The same held-out experiments against two baselines, no compensation and a ridge "
            "regression of k and b on all {all_sensors}, beside the paper's three models "
            "{with_points}; the last group pools every held-out experiment. Pooled RMSE (µm): "
            "{pooled}. {data}"),
)

#: ``{data}`` of a caption on the paper's reconstruction (default: the first entry).
ON_RECONSTRUCTION = {
    "": "Reconstructed data, not the paper's measurements.",
    "fig03_ambient_temperature":
        "Reconstructed data, not the paper's measurements: the generator moves the air "
        "monotonically across Table 1's ambient range of each experiment, up in experiments 1 "
        "and 2 and down in 3 and 4, so the minima and maxima match Table 1 by construction.",
    "fig05_error_vs_position":
        "Reconstructed data, not the paper's measurements: built so that each measurement's "
        "straight-line fit is Table 5's. The scorecard's largest-error row concerns experiment "
        "{test} (Fig. 9).",
    "fig10_temperatures":
        "Reconstructed data, not the paper's measurements, the sensors at the locations of the "
        "paper's Table 2 (screw sleeve, sliders, bearing seat, motor housing and interior, bed, "
        "nut, air); the sensitive points chosen from such histories of the training experiments "
        "are scored against the paper's Tables 3 and 6.",
    "fig12_slope_intercept":
        "Diamonds: the paper's Table 5. They agree by construction: the reconstructed data were "
        "built from Table 5's lines, so this checks the pipeline, not the paper.",
    "fig15_mlr_error_prediction":
        "Reconstructed data, built so that the printed Eq. 9 misses experiment 4 by Table 7's "
        "residuals.",
    "beyond_leave_one_experiment_out":
        "Reconstructed data, not the paper's measurements, built around the paper's points.",
}
#: ``{data}`` of a caption on any other data.
ON_OWN_DATA = ("Measured data from data_dir, not the paper's reconstruction: nothing here is "
               "compared with the paper.")


def caption(name: str, reconstructed: bool, **values) -> Caption:
    """A figure's caption (:data:`FIGURES`) with its fields filled, saying what the data are.

    Parameters
    ----------
    name : str
        The figure's file name (a key of :data:`FIGURES`).
    reconstructed : bool
        Whether the data are the paper's reconstruction (:data:`ON_RECONSTRUCTION`), or any
        other (:data:`ON_OWN_DATA`).
    **values
        The caption's numbers (:func:`data_fields`, :func:`model_fields`, ...); unused ones are
        ignored.

    Returns
    -------
    Caption
        Ready for ``run.figure``.
    """
    note = (ON_RECONSTRUCTION.get(name, ON_RECONSTRUCTION[""]) if reconstructed
            else ON_OWN_DATA).format(**values)
    return FIGURES[name].format(**{**values, "data": note})


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


class Parameters(NotebookParameters):
    """Notebook 04: Xu et al. 2022, thermal error decoupling, MLR and SVR."""

    stem = "04_xu2022_thermal_mlr_svr"
    # a normal run only reads data_dir; on the reconstruction (decided by content) another seed
    # builds the reconstruction with it in memory; on a reader's own data the seed does not apply
    seed = param.Integer(2022, bounds=(0, 4294967295),
                         doc="seed of the reconstruction's noise (data/thermal: 2022)")
    # at the reader's limits (1000 measurements x 100 sensors x 500 positions) a run takes about
    # 8 min on 2 cores, one split about 50 s
    data_dir = InputFolder("data/thermal",
                           doc="temperatures.csv and errors.csv (data/thermal/README.md)")
    train_experiments = NumberList([], item_type=int, item_bounds=(1, None),
                                   doc="experiments fitted; empty: all but the test one")
    test_experiment = param.Integer(0, bounds=(0, 1000000),
                                    doc="experiment predicted; 0: the last one (paper: 4)")
    inputs = param.Selector(default="auto", objects=["auto", "published", "selected"],
                            doc="sensitive points: the paper's, selected, or auto")
    ambient_sensor = param.String("T10", doc="the sensor reading the workshop air (Fig. 3)")
    n_clusters = param.Integer(3, bounds=(1, 100),
                               doc="clusters of the fuzzy equivalence clustering (paper: 3)")
    rho = param.Number(0.5, bounds=(0.0, 1.0), inclusive_bounds=(False, True),
                       doc="distinguishing coefficient of the grey grade (paper: 0.5)")
    leave_one_out = param.Boolean(True, doc="also hold out every experiment in turn")
    # SVR refits cost about 40 ms each
    n_replicates = param.Integer(20, bounds=(2, 200),
                                 doc="noise realisations behind the sampling standard errors")
    output_dir = OutputFolder("figures/04_xu2022_thermal_mlr_svr",
                              doc="where figures and tables are written")

    def check(self) -> None:
        """Refuse a split that contradicts itself, before any data are read."""
        if self.train_experiments:
            check_experiments(self.stem, list(self.train_experiments),
                              self.test_experiment or None)

    def memory_bytes(self) -> float:
        """Peak bytes of a run: the data drive memory, not the parameters."""
        # 0.28 GB measured at the defaults; the data drive memory, and the reader's limits (100
        # sensors, 500 positions, 1000 measurements) keep them below 0.7 GB (0.58 GB measured)
        return 7e8


def main(argv=None) -> int:
    """``python -m mtaccuracy.papers.xu2022 regenerate [FOLDER] [--seed S]``: :func:`regenerate`.

    Parameters
    ----------
    argv : list of str, optional
        The command line's arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        0, or 2 when a file was edited (nothing is written).
    """
    import argparse  # the command line: only when run as a command

    ap = argparse.ArgumentParser(prog="python -m mtaccuracy.papers.xu2022")
    ap.add_argument("command", choices=["regenerate"])
    ap.add_argument("folder", nargs="?", default=str(DATA))
    ap.add_argument("--seed", type=int, default=DEFAULT_SEED)
    args = ap.parse_args(argv)
    try:
        changed = regenerate(args.folder, seed=args.seed)
    except RuntimeError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(f"{args.folder}: reconstruction with seed {args.seed}: "
          + (f"{len(changed)} file(s) rewritten" if changed else "every file byte-identical"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
