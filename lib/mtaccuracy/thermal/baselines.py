"""Baselines of a thermal error model: what sensor selection gains or costs (beyond Xu 2022).

The paper compares its decoupled models only with its own point-by-point model, both on the
sensitive points its selection picks.  Whether the selection helps shows only against models
that do without it, fitted and judged on the same splits:

* ``uncompensated``: no model at all; the residual is the measured error itself.
* ``ridge_all_sensors``: the decoupled model (Eqs. 6, 7) with k regressed on the absolute
  temperatures of **every** sensor and b on the rises of every sensor, by ridge regression on
  standardised inputs, its penalty chosen by the same leave-one-experiment-out
  cross-validation as the SVR (:class:`GroupedRidge`).

:func:`pool_metrics` pools per-experiment metrics into one number per model, with the one RMSE
definition used throughout: the root of the mean of all squared residuals (over positions,
measurements and held-out experiments alike).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from sklearn.linear_model import Ridge
from sklearn.model_selection import GridSearchCV
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.utils.validation import validate_data

from .. import validate
from .models import DecoupledRegressor, SearchedRegressor, grouped_folds

__all__ = ["BASELINES", "RIDGE_ALPHAS", "RIDGE_TIE_RTOL", "GroupedRidge", "ridge_all_sensors",
           "pool_metrics", "selection_vs_baselines", "selection_verdict"]

#: The baselines :func:`mtaccuracy.thermal.evaluate_split` adds when asked (``baselines=``).
BASELINES = ("uncompensated", "ridge_all_sensors")

#: Ridge penalties searched, on standardised inputs (so in units of the number of samples'
#: worth of shrinkage): from practically none (1e-4) to a model close to the training mean
#: (1e4), two per decade.
RIDGE_ALPHAS = tuple(float(a) for a in np.logspace(-4, 4, 17))

#: Cross-validated RMSEs within this relative distance of the best are ties, won by the
#: largest penalty (the simplest model); as :data:`mtaccuracy.thermal.SVR_TIE_RTOL`.
RIDGE_TIE_RTOL = 1e-3


def _largest_tied_alpha(cv_results: dict, rtol: float = RIDGE_TIE_RTOL) -> int:
    """Index of the largest penalty whose mean CV RMSE is within ``rtol`` of the best."""
    rmse = -np.asarray(cv_results["mean_test_score"], dtype=float)
    alpha = np.asarray([p["ridge__alpha"] for p in cv_results["params"]], dtype=float)
    tied = np.flatnonzero(rmse <= rmse.min() * (1.0 + rtol))
    return int(tied[np.argmax(alpha[tied])])


class GroupedRidge(SearchedRegressor):
    """Ridge regression on standardised inputs, its penalty chosen by grouped cross-validation.

    scikit-learn's ``Ridge`` in a ``StandardScaler`` pipeline, searched over ``alphas`` by
    ``GridSearchCV`` with one fold per group (an experiment held out at a time, as the SVR of
    :class:`mtaccuracy.thermal.GroupedSVR`), scored by RMSE; the largest penalty within
    :data:`RIDGE_TIE_RTOL` of the best wins, and is refitted on all data.  scikit-learn's
    ``RidgeCV`` chooses by leave-one-*sample*-out, which lets a model learn an experiment's own
    drift from its neighbouring measurements; a thermal model is used on experiments it has not
    seen, so the folds are experiments.

    Parameters
    ----------
    alphas : sequence of float, optional
        Penalties searched; default :data:`RIDGE_ALPHAS`.

    Attributes
    ----------
    search_ : GridSearchCV
        The fitted search.
    best_estimator_ : Pipeline
        The chosen pipeline refitted on all data.
    alpha_ : float
        The chosen penalty.
    n_features_in_ : int
        Number of inputs.
    """

    def __init__(self, alphas=None):
        self.alphas = alphas

    def fit(self, X, y, groups=None):
        """Search the penalties with grouped folds and refit the chosen one.

        Parameters
        ----------
        X : array (n, p)
            Inputs (temperatures or rises, degC).
        y : array (n,)
            Target (k in um/m or b in um).
        groups : array (n,), optional
            Experiment of each row: one fold per experiment; None: ``KFold(min(5, n))``.

        Returns
        -------
        self
        """
        X, y = validate_data(self, X, y, y_numeric=True)
        cv = grouped_folds(len(y), groups, "ridge")
        alphas = list(RIDGE_ALPHAS if self.alphas is None else self.alphas)
        self.search_ = GridSearchCV(make_pipeline(StandardScaler(), Ridge()),
                                    {"ridge__alpha": alphas}, cv=cv, n_jobs=1,
                                    scoring="neg_root_mean_squared_error",
                                    refit=_largest_tied_alpha)
        self.search_.fit(X, y, groups=groups)
        self.best_estimator_ = self.search_.best_estimator_
        self.alpha_ = float(self.search_.best_params_["ridge__alpha"])
        return self


def ridge_all_sensors(offsets_mm, n_sensors: int) -> DecoupledRegressor:
    """The ridge baseline, unfitted: k and b each a :class:`GroupedRidge` on every sensor.

    k on the first ``n_sensors`` columns (absolute temperatures), b on the next ``n_sensors``
    (rises).

    Parameters
    ----------
    offsets_mm : array (P,)
        Target positions from the first target (mm).
    n_sensors : int
        Number of sensors, at least 1; the design is ``[temperatures, rises]``,
        (n, 2 * n_sensors).

    Returns
    -------
    DecoupledRegressor
        Unfitted, with a :class:`GroupedRidge` for k and for b.
    """
    n_sensors = validate.integer(n_sensors, "n_sensors", low=1)
    return DecoupledRegressor(offsets_mm, list(range(n_sensors)),
                              list(range(n_sensors, 2 * n_sensors)),
                              k_estimator=GroupedRidge(), b_estimator=GroupedRidge())


def pool_metrics(table: pd.DataFrame, by) -> pd.DataFrame:
    """Pool per-split metrics into one row per group: the RMSE of all residuals together.

    With ``n`` residuals behind each row, the pooled RMSE is ``sqrt(sum(n rmse**2) / sum(n))``
    (exactly the RMSE of the residuals of all rows at once), the pooled MAE
    ``sum(n mae) / sum(n)``, the pooled largest residual the largest of the rows.

    Parameters
    ----------
    table : DataFrame
        Columns ``rmse``, ``max_residual``, ``mae``, ``n_residuals`` and those of ``by``.
    by : list of str
        Columns that identify a pooled row (e.g. inputs, method, target).

    Returns
    -------
    DataFrame
        ``by`` then ``rmse``, ``max_residual``, ``mae``, ``n_residuals``.
    """
    t = table.assign(_sq=table.rmse**2 * table.n_residuals, _ab=table.mae * table.n_residuals)
    g = t.groupby(list(by), sort=False)
    n = g.n_residuals.sum()
    return pd.DataFrame({"rmse": np.sqrt(g._sq.sum() / n), "max_residual": g.max_residual.max(),
                         "mae": g._ab.sum() / n, "n_residuals": n}).reset_index()


ERROR_TARGET = "thermal positioning error"


def selection_vs_baselines(loeo: pd.DataFrame) -> pd.DataFrame:
    """The error metrics of every model of a leave-one-out run, per held-out experiment and pooled.

    The pooled rows (over all held-out experiments) have ``held_out == "all"``.

    Parameters
    ----------
    loeo : DataFrame
        :func:`mtaccuracy.thermal.leave_one_experiment_out` results (with ``baselines=``),
        concatenated over sensor choices with a column ``inputs`` ("published", "selected").

    Returns
    -------
    DataFrame
        ``held_out`` (the experiment as text, or "all"), ``model`` (a label: the baselines by
        name, the paper's models with the sensors they used, e.g. "decoupled_mlr (selected)"),
        ``rmse``, ``max_residual``, ``mae`` (um) and ``n_residuals``; baselines once, even if
        ``loeo`` holds them for several sensor choices.
    """
    err = loeo[loeo.target == ERROR_TARGET].copy()
    base = err.method.isin(BASELINES)
    err["model"] = np.where(base, err.method, err.method + " (" + err.inputs.astype(str) + ")")
    err = err.drop_duplicates(subset=["model", "held_out"])
    order = [*BASELINES, *dict.fromkeys(err.model[~base])]
    err["model"] = pd.Categorical(err.model, categories=[m for m in order if m in set(err.model)],
                                  ordered=True)
    err = err.sort_values(["held_out", "model"], kind="stable")
    cols = ["rmse", "max_residual", "mae", "n_residuals"]
    per = err[["held_out", "model", *cols]].assign(held_out=err.held_out.astype(str))
    pooled = pool_metrics(err.sort_values("model", kind="stable"), ["model"]).assign(held_out="all")
    out = pd.concat([per, pooled[["held_out", "model", *cols]]], ignore_index=True)
    out["model"] = out.model.astype(str)
    return out


def selection_verdict(pooled: pd.DataFrame) -> str:
    """One line per model on the selected sensors: its pooled RMSE against the two baselines.

    Parameters
    ----------
    pooled : DataFrame
        The ``held_out == "all"`` rows of :func:`selection_vs_baselines`, indexed by ``model``.

    Returns
    -------
    str
        E.g. "decoupled_mlr (selected): 1.20 um; ridge on all sensors 1.00 um (selection
        costs 20 %); uncompensated 3.00 um (the model removes 60 %)".
    """
    ridge, none = pooled.rmse.get("ridge_all_sensors"), pooled.rmse.get("uncompensated")
    lines = []
    for model, r in pooled.rmse.items():
        if model in BASELINES:
            continue
        text = f"{model}: {r:.2f} um"
        if ridge is not None:
            change = r / ridge - 1.0
            text += (f"; ridge on all sensors {ridge:.2f} um (selection "
                     f"{'costs' if change > 0 else 'gains'} {abs(change):.0%})")
        if none is not None:
            text += f"; uncompensated {none:.2f} um (the model removes {1.0 - r / none:.0%})"
        lines.append(text)
    return "\n".join(lines)
