"""Notebook 04's checks and scorecard helpers: the split, the data, the paper's conclusions.

The split and the inputs with their defaults resolved (:func:`resolve_split`,
:func:`resolve_inputs`) and refused when they contradict themselves or the data
(:func:`check_experiments`, :func:`check_data`); what the reader set aside
(:func:`reader_notes`); a long fit's progress line (:class:`Progress`); the scorecard's
helpers (:func:`sampling_se`, :func:`stated`, :func:`beats`).
"""

from __future__ import annotations

import time

from ..parameters import ParameterError

__all__ = ["RECONSTRUCTED_LABEL", "ERROR", "METRIC_NAMES", "METHODS", "resolve_split",
           "resolve_inputs", "check_experiments", "check_data", "reader_notes", "Progress",
           "sampling_se", "stated", "beats"]


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
    """What the reader set aside or filled (dropped sensors, ignored columns, filled gaps).

    Parameters
    ----------
    data : ThermalData
        As read.

    Returns
    -------
    str
        One line per dropped sensor, ignored column or sensor with gaps filled, or "the reader
        set nothing aside".
    """
    notes = [f"sensor {name} dropped: {why}" for name, why in getattr(data, "dropped", {}).items()]
    notes += [f"sensor {name}: gaps filled: {why}" for name, why in
              getattr(data, "filled", {}).items()]
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
