"""Validating thermal error models (Xu et al. 2022, Section 5): metrics, splits, replicates.

* :func:`metrics`, :func:`batch_metrics`: RMSE, largest absolute residual (the paper's
  delta_max) and MAE.
* :func:`evaluate_split`: sensitive points chosen on the training experiments only, the
  point-by-point MLR and the decoupled MLR / SVR fitted there, the held-out experiments
  predicted from their temperatures; :func:`leave_one_experiment_out` does it for every
  experiment in turn.
* :func:`replicate_split`: the same fits with fixed inputs on a stack of noise replicates at once.
* :func:`design`, :func:`eq8_table`, :func:`eq9_table`, :func:`svr_hyperparameters`: the
  inputs of a model from a :class:`ThermalData` and its fitted coefficients as tables.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from sklearn.linear_model import LinearRegression
from sklearn.metrics import make_scorer

from .baselines import BASELINES, ridge_all_sensors
from .clustering import Selection, fuzzy_clusters, most_frequent, select_sensitive_points
from .data import ThermalData, rises_of
from .models import (
    DecoupledRegressor,
    PointByPointRegressor,
    _prefixed,
    compose,
    decouple,
    fit_linear,
    predict_linear,
)
from .svr import GroupedSVR, StandardisedSVR, _svr_params, tie_margin

__all__ = [
    "metrics", "pooled_rmse", "POOLED_RMSE_SCORER", "batch_metrics", "design", "point_by_point",
    "decoupled", "eq8_table",
    "eq9_table", "svr_hyperparameters", "SplitResult", "evaluate_split",
    "leave_one_experiment_out", "replicate_split", "metrics_by_experiment",
    "METRIC_DIGITS", "straight_line_floor", "prediction_table", "FLOOR",
]


def metrics(residuals) -> dict:
    """RMSE, largest absolute residual (delta_max) and MAE (Xu et al. 2022, Tables 4, 7, 8).

    Parameters
    ----------
    residuals : array (any shape)
        Measured minus predicted (um or um/m).

    Returns
    -------
    dict
        ``{"rmse", "max_residual", "mae"}`` as floats, in the unit of ``residuals``.
    """
    return {k: float(v[0]) for k, v in batch_metrics(np.asarray(residuals)[None]).items()}


def pooled_rmse(y_true, y_pred) -> float:
    """The RMSE of all residuals at once, pooled over positions and measurements.

    The one RMSE of this package (:func:`metrics`).  scikit-learn's ``root_mean_squared_error``
    on a multi-output target averages the RMSEs of the outputs (positions) instead, which weighs
    a position of small errors like one of large ones; the two differ whenever the positions'
    errors differ in size.

    Parameters
    ----------
    y_true, y_pred : array (n, P) or (n,)
        Measured and predicted errors (um).

    Returns
    -------
    float
        um.
    """
    return metrics(np.asarray(y_true, dtype=float) - np.asarray(y_pred, dtype=float))["rmse"]


#: :func:`pooled_rmse` as a scikit-learn scorer (negated, greater is better), for
#: ``cross_val_score(..., scoring=POOLED_RMSE_SCORER)`` and ``GridSearchCV``.
POOLED_RMSE_SCORER = make_scorer(pooled_rmse, greater_is_better=False)


def design(data: ThermalData, inputs: dict, model: str) -> np.ndarray:
    """The input matrix of a model on ``data``.

    Parameters
    ----------
    data : ThermalData
        n measurements.
    inputs : dict
        ``{"point": [...], "k": [...], "b": [...]}``: the sensors of each model's inputs.
    model : {"point", "decoupled"}
        ``"point"``: the temperature rises (degC) of ``inputs["point"]``, (n, p).
        ``"decoupled"``: the absolute temperatures of ``inputs["k"]`` then the rises of
        ``inputs["b"]`` (Eq. 9), (n, len(k) + len(b)).

    Returns
    -------
    array (n, p)
        One row per measurement of ``data`` (degC).
    """
    if model == "point":
        return data.rises()[list(inputs["point"])].to_numpy()
    if model == "decoupled":
        return np.column_stack([data.temperatures[list(inputs["k"])].to_numpy(),
                                data.rises()[list(inputs["b"])].to_numpy()])
    raise ValueError(f"model must be 'point' or 'decoupled', got {model!r}")


def point_by_point(data: ThermalData, inputs: dict) -> PointByPointRegressor:
    """The point-by-point MLR (Xu et al. 2022, Eq. 8) fitted on a dataset.

    Parameters
    ----------
    data : ThermalData
        Training measurements.
    inputs : dict
        ``inputs["point"]``: the sensors whose temperature rises are the inputs.

    Returns
    -------
    PointByPointRegressor
        Fitted, one ``LinearRegression`` per target position.
    """
    return PointByPointRegressor(LinearRegression()).fit(design(data, inputs, "point"),
                                                         data.errors)


def decoupled(data: ThermalData, inputs: dict, *, kind: str = "mlr",
              progress=None) -> DecoupledRegressor:
    """The decoupled model (Xu et al. 2022, Eq. 9) fitted on a dataset.

    Parameters
    ----------
    data : ThermalData
        Training measurements.
    inputs : dict
        ``inputs["k"]``: sensors whose absolute temperatures are k's inputs; ``inputs["b"]``:
        sensors whose rises are b's inputs.
    kind : {"mlr", "svr"}
        ``LinearRegression``, or :class:`GroupedSVR` with one fold per experiment.
    progress : callable, optional
        For ``"svr"``: called as ``progress("k: <i> of <n> candidates")`` (then ``"b: ..."``)
        as the hyperparameter searches go.

    Returns
    -------
    DecoupledRegressor
        Fitted on :func:`design` ``(data, inputs, "decoupled")``.
    """
    if kind not in ("mlr", "svr"):
        raise ValueError(f"unknown model kind {kind!r}; use 'mlr' or 'svr'")
    nk, nb = len(inputs["k"]), len(inputs["b"])
    est = LinearRegression() if kind == "mlr" else GroupedSVR()
    model = DecoupledRegressor(data.offsets_mm(), list(range(nk)), list(range(nk, nk + nb)),
                               k_estimator=est, b_estimator=est)
    return model.fit(design(data, inputs, "decoupled"), data.errors, groups=data.groups,
                     progress=progress)


def eq8_table(model: PointByPointRegressor, sensors, positions_mm) -> pd.DataFrame:
    """Eq. 8 as a table: intercept and one coefficient per sensor at every position (MLR only).

    Parameters
    ----------
    model : PointByPointRegressor
        Fitted with linear estimators.
    sensors : list of str
        Names of the model's inputs, in order.
    positions_mm : array (P,)
        Target positions (mm).

    Returns
    -------
    DataFrame (P, 2 + len(sensors))
        ``position_mm``, ``intercept`` (um), one column per sensor (um/degC).
    """
    rows = [{"position_mm": p, "intercept": m.intercept_,
             **dict(zip(sensors, m.coef_, strict=True))}
            for p, m in zip(positions_mm, model.estimators_, strict=True)]
    return pd.DataFrame(rows)


def eq9_table(model: DecoupledRegressor, inputs: dict) -> pd.DataFrame:
    """Eq. 9 as a table: target, term, coefficient (MLR only); b's terms are rises ``dT``.

    Parameters
    ----------
    model : DecoupledRegressor
        Fitted with linear estimators.
    inputs : dict
        ``{"k": [...], "b": [...]}``: the sensors of k and of b, in order.

    Returns
    -------
    DataFrame
        One row per term: ``target`` ("k (um/m)" or "b (um)"), ``term``, ``coefficient``.
    """
    rows = []
    for target, m, names, pre in (("k (um/m)", model.k_estimator_, inputs["k"], ""),
                                  ("b (um)", model.b_estimator_, inputs["b"], "d")):
        rows.append({"target": target, "term": "intercept", "coefficient": m.intercept_})
        rows += [{"target": target, "term": pre + s, "coefficient": c}
                 for s, c in zip(names, m.coef_, strict=True)]
    return pd.DataFrame(rows)


def svr_hyperparameters(model: DecoupledRegressor) -> pd.DataFrame:
    """The cross-validated SVR hyperparameters of k and b of a decoupled SVR.

    Parameters
    ----------
    model : DecoupledRegressor
        Fitted with :class:`GroupedSVR` for k and b.

    Returns
    -------
    DataFrame (2, 9)
        Per target: ``kernel``, ``C``, ``gamma``, ``epsilon`` of the chosen candidate, its mean
        CV RMSE, the number of candidates tried (the grid within :data:`SVR_MAX_CN`: all 40
        up to 30 training rows), how many tied with the best (within its ``tie_rtol``) and the
        distance of the nearest other one to the tie window's edge.  The two scores to
        :data:`METRIC_DIGITS` significant digits (as tables are written): below them lie
        libsvm's stopping point (about 1e-11 relative at
        :data:`~mtaccuracy.thermal.svr.SVR_SOLVER_TOL`) and the rounding another CPU changes,
        so the table is the same on any CPU.
    """
    rows = []
    for target, est in (("k", model.k_estimator_), ("b", model.b_estimator_)):
        s = est.search_
        p = _svr_params(s.best_params_)
        tied, margin = tie_margin(s.cv_results_, est.tie_rtol)
        rows.append({"target": target, "kernel": p["kernel"], "C": p["C"],
                     "gamma": p.get("gamma", ""), "epsilon": p["epsilon"],
                     "cv_rmse": _digits(-s.cv_results_["mean_test_score"][s.best_index_],
                                        METRIC_DIGITS),
                     "candidates": len(s.cv_results_["params"]), "tied": tied,
                     "tie_window_margin": _digits(margin, METRIC_DIGITS)})
    return pd.DataFrame(rows)


# --------------------------------------------------------------------------------------------
# One split, and every experiment held out in turn
# --------------------------------------------------------------------------------------------

#: Significant digits of the metrics in a split's table (:attr:`SplitResult.table`, and so of
#: :func:`leave_one_experiment_out`), as tables are written.  Below them lies what another CPU
#: changes: the SVR's stopping point (about 1e-11 relative at
#: :data:`~mtaccuracy.thermal.svr.SVR_SOLVER_TOL`) and the MLR's rounding (1e-14); the
#: figures drawn from the table (bars a few hundred pixels high, written to 1e-6 of a pixel)
#: changed bytes from it.  Rounded here, the table is the same on any CPU unless a metric lies
#: within that noise of a rounding edge.
METRIC_DIGITS = 6


@dataclass
class SplitResult:
    """Everything :func:`evaluate_split` computed for one train/test split.

    Attributes
    ----------
    train, test : list of int
        The experiments.
    position_selections : list of Selection
        The sensitive-point selection at every position (training data).
    selected : dict
        The selected sensors ``{"point", "k", "b"}``; ``inputs`` the ones used (``sensors``
        may fix them).
    inputs : dict
        The sensors the models used.
    k_selection, b_selection : Selection
        The selections for k (absolute temperatures) and b (rises).
    models : dict
        Fitted estimators: ``point_by_point_mlr``, ``decoupled_mlr``, ``decoupled_svr``.
    predictions, kb_predictions : dict
        Per model: predicted errors (n_test, P) in um; (k, b) of the decoupled models.
    measured : array (n_test, P)
        Measured errors (um) of the test experiments.
    measured_kb : tuple
        Their decoupled (k, b).
    table : DataFrame
        method, target, rmse, max_residual, mae, unit; the metrics to
        :data:`METRIC_DIGITS` significant digits.
    settings : dict
        What determines the result (compared to reuse it).
    """

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


def evaluate_split(data: ThermalData, *, train, test, n_clusters: int = 3, rho: float = 0.5,
                   kinds=("mlr", "svr"), sensors: dict | None = None, progress=None,
                   baselines=()) -> SplitResult:
    """One train/test split: sensitive points, models, held-out metrics (Xu et al. 2022, Sec. 5).

    Selects sensitive points on ``train`` only (:func:`select_sensitive_points`), fits the
    point-by-point MLR and the decoupled models there, predicts ``test`` from its temperatures.
    The metrics table holds :data:`METRIC_DIGITS` significant digits: below them lies
    rounding that another CPU changes.

    Parameters
    ----------
    data : ThermalData
        All measurements.
    train, test : int or list of int
        Experiments to fit on and to predict.
    n_clusters : int
        Clusters of the fuzzy clustering, so sensors per model (the paper: 3).
    rho : float
        Distinguishing coefficient of the grey relational grade (Eq. 4), in (0, 1].
    kinds : tuple of {"mlr", "svr"}
        Decoupled models fitted.
    sensors : dict, optional
        ``{"point": [...], "k": [...], "b": [...]}`` fixes the inputs instead of selecting
        them; the selection is still computed and returned.
    progress : callable, optional
        Called with a short text as the work goes: ``"sensitive points: <i> of <P>
        positions"`` (about ten times), then per model, e.g. ``"decoupled_svr, k: 12 of 40
        candidates"``.  None (the default): silent.  ``print`` shows every step.
    baselines : sequence of str
        Models that need no sensor selection, fitted and judged on the same split
        (:data:`BASELINES`): ``"uncompensated"`` (no model: the residual is the measured error)
        and ``"ridge_all_sensors"`` (:func:`ridge_all_sensors`: k on every sensor's temperature,
        b on every sensor's rise).

    Returns
    -------
    SplitResult
        The selections, the fitted models, their predictions of ``test`` and its metrics table.
    """
    missing = sorted({s for v in (sensors or {}).values() for s in v} - set(data.sensors))
    if missing:
        raise ValueError(f"the data have no sensor(s) {missing}; they have {data.sensors}")
    tr, te = data.subset(train), data.subset(test)
    offsets = data.offsets_mm()
    k_tr, b_tr = decouple(offsets, tr.errors)
    rises = tr.rises()
    n_pos = tr.errors.shape[1]
    # the clusters of the rises do not depend on the target: computed once for all positions
    clusters = fuzzy_clusters(rises.to_numpy(dtype=float), list(rises.columns), n_clusters)
    pos_sel = []
    for i in range(n_pos):
        pos_sel.append(select_sensitive_points(rises, tr.errors[:, i], n_clusters=n_clusters,
                                               rho=rho, clustering=clusters))
        if progress is not None and ((i + 1) % max(1, n_pos // 10) == 0 or i + 1 == n_pos):
            progress(f"sensitive points: {i + 1} of {n_pos} positions")
    k_sel = select_sensitive_points(tr.temperatures, k_tr, n_clusters=n_clusters, rho=rho)
    b_sel = select_sensitive_points(rises, b_tr, n_clusters=n_clusters, rho=rho,
                                    clustering=clusters)
    selected = {"point": most_frequent([s.selected for s in pos_sel], n_clusters,
                                       order=data.sensors),
                "k": k_sel.selected, "b": b_sel.selected}
    chosen = {**selected, **(sensors or {})}
    if progress is not None:
        progress("point_by_point_mlr")
    models = {"point_by_point_mlr": point_by_point(tr, chosen)}
    for kind in kinds:
        if progress is not None and kind != "svr":
            progress(f"decoupled_{kind}")
        models[f"decoupled_{kind}"] = decoupled(
            tr, chosen, kind=kind, progress=_prefixed(progress, f"decoupled_{kind}, "))
    unknown = sorted(set(baselines) - set(BASELINES))
    if unknown:
        raise ValueError(f"unknown baseline(s) {unknown}; use {list(BASELINES)}")
    every = {"k": list(data.sensors), "b": list(data.sensors)}
    if "ridge_all_sensors" in baselines:
        if progress is not None:
            progress("ridge_all_sensors")
        models["ridge_all_sensors"] = ridge_all_sensors(offsets, len(data.sensors)).fit(
            design(tr, every, "decoupled"), tr.errors, groups=tr.groups)
    measured = te.errors
    measured_kb = decouple(offsets, measured)
    preds, kb_preds, rows = {}, {}, []
    if "uncompensated" in baselines:
        preds["uncompensated"] = np.zeros_like(measured)
        rows.append({"method": "uncompensated", "target": "thermal positioning error",
                     "unit": "um", **_metric_digits(metrics(measured))})
    for name, m in models.items():
        x = design(te, every if name == "ridge_all_sensors" else chosen,
                   "decoupled" if isinstance(m, DecoupledRegressor) else "point")
        preds[name] = m.predict(x)
        rows.append({"method": name, "target": "thermal positioning error", "unit": "um",
                     **_metric_digits(metrics(measured - preds[name]))})
        if isinstance(m, DecoupledRegressor):
            kb_preds[name] = m.predict_kb(x)
            for target, unit, meas, pred in (("slope k", "um/m", measured_kb[0],
                                              kb_preds[name][0]),
                                             ("intercept b", "um", measured_kb[1],
                                              kb_preds[name][1])):
                rows.append({"method": name, "target": target, "unit": unit,
                             **_metric_digits(metrics(meas - pred))})
    table = pd.DataFrame(rows)[["method", "target", "rmse", "max_residual", "mae", "unit"]]
    return SplitResult(list(tr.experiments), list(te.experiments), pos_sel, selected, chosen,
                       k_sel, b_sel, models, preds, kb_preds, measured, measured_kb, table,
                       _settings(data, train, test, n_clusters, rho, kinds, sensors, baselines))


def _digits(value: float, digits: int) -> float:
    """``value`` to ``digits`` significant digits (correctly rounded; NaN stays NaN)."""
    return float(f"{value:.{digits}g}")


def _metric_digits(values: dict) -> dict:
    """Metrics to :data:`METRIC_DIGITS` significant digits."""
    return {k: _digits(v, METRIC_DIGITS) for k, v in values.items()}


def _settings(data, train, test, n_clusters, rho, kinds, sensors, baselines=()) -> dict:
    """What determines a split's result: compared to reuse a result."""
    h = hashlib.sha256()
    for a in (data.index.to_numpy(dtype=float), data.temperatures.to_numpy(dtype=float),
              data.errors, data.positions_mm):
        h.update(np.ascontiguousarray(a, dtype=float).tobytes())
    h.update(repr(data.sensors).encode())
    return {"data": h.hexdigest(), "train": sorted(int(e) for e in np.atleast_1d(train)),
            "test": sorted(int(e) for e in np.atleast_1d(test)), "n_clusters": int(n_clusters),
            "rho": float(rho), "kinds": tuple(kinds),
            "sensors": {k: list(v) for k, v in sorted((sensors or {}).items())},
            "baselines": tuple(baselines)}


def leave_one_experiment_out(data: ThermalData, *, n_clusters: int = 3, rho: float = 0.5,
                             kinds=("mlr", "svr"), sensors: dict | None = None,
                             reuse=(), progress=None, baselines=()) -> pd.DataFrame:
    """:func:`evaluate_split` with each experiment held out in turn (selection redone each time).

    Parameters
    ----------
    data : ThermalData
        All measurements.
    n_clusters, rho, kinds, sensors
        As :func:`evaluate_split`.
    reuse : sequence of SplitResult
        Results computed on the same data (compared by content hash) with the same settings are
        taken as they are instead of being computed again.
    progress : callable, optional
        Called with a short text as the work goes, the messages of :func:`evaluate_split` led
        by ``"held out <e> (<i> of <n>): "``, e.g. ``"held out 3 (3 of 10): decoupled_svr, k:
        12 of 40 candidates"``, and ``"... reused"`` for a split taken from ``reuse``.  None
        (the default): silent.
    baselines : sequence of str
        As :func:`evaluate_split`.

    Returns
    -------
    DataFrame
        One row per held-out experiment, method and target: ``held_out``, the sensors used,
        the columns of :attr:`SplitResult.table` and ``n_residuals``, the number of residuals
        behind the row's metrics (positions x measurements for the error, measurements for k
        and b: :func:`mtaccuracy.thermal.pool_metrics` pools with them).
    """
    frames = []
    for i, e in enumerate(data.experiments, 1):
        train = [x for x in data.experiments if x != e]
        want = _settings(data, train, [e], n_clusters, rho, kinds, sensors, baselines)
        step = _prefixed(progress, f"held out {e} ({i} of {len(data.experiments)}): ")
        r = next((r for r in reuse if r.settings == want), None)
        if r is not None and step is not None:
            step("reused")
        r = r or evaluate_split(data, train=train, test=[e], n_clusters=n_clusters, rho=rho,
                                kinds=kinds, sensors=sensors, progress=step,
                                baselines=baselines)
        t = r.table.copy()
        t.insert(0, "held_out", e)
        for j, key in enumerate(("point", "k", "b"), 1):
            t.insert(j, f"{key}_sensors", " ".join(r.inputs[key]))
        # residuals behind each metric: positions x measurements for the error, measurements
        # for k and b (pooling over experiments weighs each by them: baselines.pool_metrics)
        t["n_residuals"] = np.where(t.target == "thermal positioning error", r.measured.size,
                                    len(r.measured))
        frames.append(t)
    return pd.concat(frames, ignore_index=True)


# --------------------------------------------------------------------------------------------
# Noise replicates: the same fits on a stack of datasets (leading replicate axis)
# --------------------------------------------------------------------------------------------


def batch_metrics(residuals) -> dict:
    """:func:`metrics` of every replicate at once (its one implementation).

    Parameters
    ----------
    residuals : array (R, ...)
        Residuals of R replicates.

    Returns
    -------
    dict
        ``{"rmse", "max_residual", "mae"}``, each an array (R,).
    """
    r = np.asarray(residuals, dtype=float)
    r = r.reshape(len(r), -1)
    return {"rmse": np.sqrt(np.mean(r**2, axis=1)), "max_residual": np.abs(r).max(axis=1),
            "mae": np.abs(r).mean(axis=1)}


def replicate_split(replicates, *, train, test, inputs: dict, svr_params: dict | None = None
                    ) -> pd.DataFrame:
    """The fits of :func:`evaluate_split` with fixed inputs, on every noise replicate at once.

    The MLRs are fitted batched (:func:`fit_linear`); the SVRs, when ``svr_params`` fixes their
    hyperparameters, one replicate at a time (libsvm solves one problem per call).  Sensitive
    points and hyperparameters are not chosen again: the spread over the replicates is that of
    the fits and metrics for the given choices.

    Parameters
    ----------
    replicates : Replicates
        ``index``, ``sensors``, ``temperatures`` (R, n, S), ``errors`` (R, n, P),
        ``positions_mm``: R datasets stacked on a leading axis (the compendium's
        ``xu2022_reconstruction.noise_replicates`` makes them).
    train, test : list of int
        Experiments to fit on and to predict.
    inputs : dict
        ``{"point": [...], "k": [...], "b": [...]}``: the sensors of each model's inputs.
    svr_params : dict, optional
        ``{"k": params, "b": params}`` of :class:`StandardisedSVR`; None skips the SVR.

    Returns
    -------
    DataFrame (R, ...)
        One row per replicate; the columns are 3-tuples: (method, target, metric) for the
        metrics of :func:`metrics`; ``("eq8", position, term)`` and ``("eq9", target, term)``
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


def metrics_by_experiment(frame: pd.DataFrame, column: str) -> pd.DataFrame:
    """RMSE and largest residual of ``frame[column]`` per experiment.

    Parameters
    ----------
    frame : DataFrame
        With an ``experiment`` column and the residual column.
    column : str
        The residuals (um or um/m).

    Returns
    -------
    DataFrame (n_experiments, 2)
        ``rmse``, ``max_residual``, indexed by experiment.
    """
    return pd.DataFrame({e: metrics(g[column]) for e, g in frame.groupby("experiment")}
                        ).T[["rmse", "max_residual"]]


#: The name of the straight-line floor in metric tables (:func:`straight_line_floor`).
FLOOR = "straight-line floor"


def straight_line_floor(errors, *, offsets_mm) -> dict:
    """The straight-line floor: the error left when each measurement is its own best line.

    Every model that predicts a slope k and an intercept b per measurement (the decoupled MLR
    and SVR, Eqs. 6-9) predicts a straight line in the position; the least-squares line of each
    measurement (Eq. 6 on the measured errors) is the best of them in RMSE, so no such model
    can predict that measurement with a smaller RMSE: what is left (a fixed pitch shape, a bow,
    noise) is a floor.  A point-by-point model, which fits every position on its own, is not
    bound by it.

    Parameters
    ----------
    errors : array (n, P)
        Measured errors (um) of n measurements at P positions.
    offsets_mm : array (P,)
        Positions (mm), e.g. :meth:`ThermalData.offsets_mm`.

    Returns
    -------
    dict
        ``{"rmse", "max_residual", "mae"}`` (um) of the residuals from each measurement's own
        line (:func:`metrics`), to :data:`METRIC_DIGITS` significant digits.
    """
    errors = np.asarray(errors, dtype=float)
    k, b = decouple(offsets_mm, errors)
    return _metric_digits(metrics(errors - compose(k, b, offsets_mm)))


def prediction_table(split: SplitResult, data: ThermalData) -> pd.DataFrame:
    """Predicted against measured error at every position and measurement of a split's test.

    Parameters
    ----------
    split : SplitResult
        From :func:`evaluate_split`; every model in ``split.predictions``.
    data : ThermalData
        The data the split was computed on.

    Returns
    -------
    DataFrame (n_models * n_test * P, 6)
        ``experiment, measurement, target_mm, measured_um, predicted_um, model``: one row per
        model (in ``split.predictions``' order), test measurement (stored order) and target
        position (ascending); errors in um, predictions to 1e-6 um (below lies the solvers'
        rounding, which another CPU changes).
    """
    test = data.subset(split.test)
    n, p = split.measured.shape
    frames = [pd.DataFrame({
        "experiment": np.repeat(test.index.experiment.to_numpy(), p),
        "measurement": np.repeat(test.index.measurement.to_numpy(), p),
        "target_mm": np.tile(test.positions_mm, n),
        "measured_um": split.measured.ravel(),
        "predicted_um": np.round(np.asarray(pred, dtype=float).ravel(), 6) + 0.0,
        "model": name}) for name, pred in split.predictions.items()]
    return pd.concat(frames, ignore_index=True)
