"""Thermal error models (Xu et al. 2022, Section 4): decoupling, and the MLR structure.

* :func:`decouple`, :func:`compose`: the least-squares line of every measurement (Eq. 6) and
  back (Eq. 7); by hand, the paper's contribution and two lines of algebra.
* :class:`PointByPointRegressor`: one regression per target position (Eqs. 5, 8).
* :class:`DecoupledRegressor`: the slope k and the intercept b each regressed on their own
  sensors, the error composed as k x + b (Eqs. 7, 9).
* :func:`fit_linear`, :func:`predict_linear`: least squares on a stack of problems at once
  (the batched twin of ``LinearRegression``, for noise replicates).
* :func:`grouped_folds`, :class:`SearchedRegressor`: the folds of a hyperparameter search (an
  experiment held out at a time) and the base of a regressor that searches at ``fit``.

Both regressors take any scikit-learn regressor and default to ``LinearRegression()`` (the
paper's MLR); the paper's SVR, with its hyperparameter search, is
:mod:`~mtaccuracy.thermal.svr`.  They are scikit-learn estimators: constructor arguments stored
unchanged, ``fit(X, y)`` on arrays, fitted attributes ending in ``_``,
``get_params``/``set_params``, ``clone``; they compose with ``GridSearchCV``,
``cross_val_score`` and ``GroupKFold`` (``groups`` is passed through ``fit`` to an inner
estimator that takes it).

Units: positions in mm, errors in um, slopes k in um/m (so ``k * x_mm / 1000`` is um).
"""

from __future__ import annotations

import inspect

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin, clone
from sklearn.linear_model import LinearRegression
from sklearn.model_selection import GroupKFold, KFold
from sklearn.utils.validation import check_is_fitted, validate_data

__all__ = [
    "decouple", "compose", "PointByPointRegressor", "DecoupledRegressor", "fit_linear",
    "predict_linear", "grouped_folds", "SearchedRegressor",
]

# --------------------------------------------------------------------------------------------
# Decoupling (Eq. 6) and composition (Eq. 7)
# --------------------------------------------------------------------------------------------

def decouple(offsets_mm: np.ndarray, errors_um: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Split error profiles into their least-squares slope and intercept (Xu et al. 2022, Eq. 6).

    Written out (not ``np.polyfit``) because it *is* the paper's Eq. 6.

    Parameters
    ----------
    offsets_mm : array (P,)
        Target positions from the first target (0..260 mm in the paper), so b is the line's
        value at the first target; at least two distinct.
    errors_um : array (..., P)
        Positioning errors (um).

    Returns
    -------
    k : array (...)
        Slopes (um/m).
    b : array (...)
        Intercepts (um).
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
    """Error profiles from slopes and intercepts: ``y(x) = k x + b`` (Xu et al. 2022, Eq. 7).

    Parameters
    ----------
    k_um_per_m : array (n,)
        Slopes (um/m).
    b_um : array (n,)
        Intercepts (um).
    offsets_mm : array (P,)
        Positions from the first target (mm).

    Returns
    -------
    array (n, P)
        Errors (um).
    """
    k = np.asarray(k_um_per_m, dtype=float)[..., None]
    b = np.asarray(b_um, dtype=float)[..., None]
    return k * np.asarray(offsets_mm, dtype=float) / 1000.0 + b


def _fit_with_groups(estimator, X, y, groups, progress=None):
    """Fit ``estimator``, passing ``groups`` and ``progress`` when its ``fit`` takes them."""
    takes = inspect.signature(estimator.fit).parameters
    extra = {k: v for k, v in (("groups", groups), ("progress", progress))
             if v is not None and k in takes}
    return estimator.fit(X, y, **extra)


def _prefixed(progress, prefix: str):
    """``progress`` with ``prefix`` before every message (None stays None)."""
    return None if progress is None else (lambda text: progress(prefix + text))


def grouped_folds(n: int, groups, what: str):
    """The cross-validation folds of a thermal model's hyperparameter search.

    One fold per group (an experiment held out at a time, as the model is used on experiments
    it has not seen), or ``KFold(min(5, n))`` (unshuffled) without groups.

    Parameters
    ----------
    n : int
        Number of rows.
    groups : array (n,) or None
        Experiment of each row.
    what : str
        The model, for the message refusing fewer than 2 groups.

    Returns
    -------
    GroupKFold or KFold
        Unfitted splitter: ``GroupKFold(n_groups)`` with groups, else ``KFold(min(5, n))``.
    """
    if groups is None:
        return KFold(n_splits=min(5, n))
    n_groups = len(np.unique(groups))
    if n_groups < 2:
        raise ValueError(f"{what} cross-validation needs at least 2 training experiments")
    return GroupKFold(n_splits=n_groups)


class SearchedRegressor(RegressorMixin, BaseEstimator):
    """Base of a regressor whose ``fit`` chooses its hyperparameters by a search.

    The chosen model, refitted on all data, is kept as ``best_estimator_``
    (:class:`~mtaccuracy.thermal.svr.GroupedSVR`,
    :class:`mtaccuracy.thermal.GroupedRidge`).
    """

    def predict(self, X):
        """Predictions of the chosen candidate.

        Parameters
        ----------
        X : array (n, p)
            Inputs, the columns of ``fit``'s.

        Returns
        -------
        array (n,)
            Predicted target.
        """
        check_is_fitted(self)
        X = validate_data(self, X, reset=False)
        return self.best_estimator_.predict(X)

class PointByPointRegressor(RegressorMixin, BaseEstimator):
    """One regression per target position: the point-by-point model (Xu et al. 2022, Eqs. 5, 8).

    Parameters
    ----------
    estimator : regressor, optional
        Cloned once per column of ``y``; default ``LinearRegression()`` (the paper's MLR).

    Attributes
    ----------
    estimators_ : list
        The fitted clones, one per target position.
    n_features_in_ : int
        Number of inputs (temperature rises of the chosen sensors, degC).

    Notes
    -----
    The same model as scikit-learn's ``MultiOutputRegressor``, with ``groups`` passed to an inner
    estimator that takes them (:class:`~mtaccuracy.thermal.svr.GroupedSVR`) and a 1-D ``y`` kept
    1-D.
    """

    def __init__(self, estimator=None):
        self.estimator = estimator

    def fit(self, X, y, groups=None):
        """Fit one clone per target position.

        Parameters
        ----------
        X : array (n, p)
            Inputs (temperatures or rises, degC).
        y : array (n, P) or (n,)
            Errors (um) at P positions.
        groups : array (n,), optional
            Passed to an inner estimator that takes them
            (:class:`~mtaccuracy.thermal.svr.GroupedSVR`).

        Returns
        -------
        self
        """
        X, y = validate_data(self, X, y, multi_output=True, y_numeric=True)
        self._single = y.ndim == 1
        y2 = y[:, None] if self._single else y
        base = LinearRegression() if self.estimator is None else self.estimator
        self.estimators_ = [_fit_with_groups(clone(base), X, y2[:, i], groups)
                            for i in range(y2.shape[1])]
        return self

    def predict(self, X):
        """Predicted errors at every position.

        Parameters
        ----------
        X : array (n, p)
            Inputs, the columns of ``fit``'s (temperature rises, degC).

        Returns
        -------
        array (n, P) or (n,)
            um; 1-D when fitted on a 1-D y.
        """
        check_is_fitted(self)
        X = validate_data(self, X, reset=False)
        out = np.column_stack([m.predict(X) for m in self.estimators_])
        return out[:, 0] if self._single else out

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.target_tags.multi_output = True
        return tags


class DecoupledRegressor(RegressorMixin, BaseEstimator):
    """The decoupled model (Xu et al. 2022, Eqs. 6, 7, 9): error = k x + b.

    ``fit`` splits every measured error profile into its least-squares slope k (um/m) and
    intercept b (um) (:func:`decouple`, Eq. 6), regresses k on the columns ``k_columns`` of
    ``X`` and b on ``b_columns`` (the paper: k on absolute temperatures, b on temperature rises,
    Eq. 9), and ``predict`` composes k x + b at every position (Eq. 7).

    Parameters
    ----------
    offsets_mm : array (P,)
        Target positions measured from the first target (mm); at least two distinct.
    k_columns, b_columns : sequence of int
        Columns of ``X`` that are the inputs of k and of b.
    k_estimator, b_estimator : regressor, optional
        Cloned for k and for b; default ``LinearRegression()`` (the paper's MLR).

    Attributes
    ----------
    k_estimator_, b_estimator_ : regressor
        The fitted clones.
    n_features_in_ : int
        Number of columns of ``X``.

    Notes
    -----
    scikit-learn's ``check_estimator`` does not apply: its regressor checks fit a 1-D target,
    and this model's target is an error profile over at least two positions.  The tests check
    ``clone``, ``get_params``/``set_params`` and use in ``GridSearchCV`` with ``GroupKFold``.
    """

    def __init__(self, offsets_mm, k_columns, b_columns, *, k_estimator=None, b_estimator=None):
        self.offsets_mm = offsets_mm
        self.k_columns = k_columns
        self.b_columns = b_columns
        self.k_estimator = k_estimator
        self.b_estimator = b_estimator

    def _split(self, X):
        return X[:, list(self.k_columns)], X[:, list(self.b_columns)]

    def fit(self, X, y, groups=None, *, progress=None):
        """Decouple the error profiles into k and b (Eq. 6) and regress each.

        Parameters
        ----------
        X : array (n, p)
            Inputs (temperatures or rises, degC).
        y : array (n, P)
            Error profiles (um).
        groups : array (n,), optional
            Experiment of each row: one fold per experiment.
        progress : callable, optional
            Passed to the estimators whose ``fit`` takes it
            (:class:`~mtaccuracy.thermal.svr.GroupedSVR`), each
            message led by ``"k: "`` or ``"b: "``.

        Returns
        -------
        self
        """
        X, y = validate_data(self, X, y, multi_output=True, y_numeric=True)
        if y.ndim != 2 or y.shape[1] != len(self.offsets_mm):
            raise ValueError(f"y must be (n, {len(self.offsets_mm)}): one error per position "
                             f"of offsets_mm; got shape {y.shape}")
        k, b = decouple(self.offsets_mm, y)
        xk, xb = self._split(X)
        self.k_estimator_ = _fit_with_groups(
            clone(LinearRegression() if self.k_estimator is None else self.k_estimator),
            xk, k, groups, _prefixed(progress, "k: "))
        self.b_estimator_ = _fit_with_groups(
            clone(LinearRegression() if self.b_estimator is None else self.b_estimator),
            xb, b, groups, _prefixed(progress, "b: "))
        return self

    def predict_kb(self, X):
        """Predicted slope and intercept.

        Parameters
        ----------
        X : array (n, p)
            Inputs, the columns of ``fit``'s.

        Returns
        -------
        k : array (n,)
            Predicted slopes (um/m).
        b : array (n,)
            Predicted intercepts (um).
        """
        check_is_fitted(self)
        X = validate_data(self, X, reset=False)
        xk, xb = self._split(X)
        return self.k_estimator_.predict(xk), self.b_estimator_.predict(xb)

    def predict(self, X):
        """Predicted error profiles: k x + b at every offset (Eq. 7).

        Parameters
        ----------
        X : array (n, p)
            Inputs, the columns of ``fit``'s.

        Returns
        -------
        array (n, P)
            um.
        """
        return compose(*self.predict_kb(X), self.offsets_mm)

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.target_tags.multi_output = True
        tags.target_tags.single_output = False
        return tags


def fit_linear(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Least squares with an intercept on a stack of problems at once.

    The batched twin of scikit-learn's ``LinearRegression`` (the tests check they agree), so
    that many noise replicates are fitted in one call.

    Parameters
    ----------
    x : array (R, n, p)
        Inputs of R problems, n rows each.
    y : array (R, n) or (R, n, q)
        Targets: one or q per row.

    Returns
    -------
    array (R, 1 + p) or (R, 1 + p, q)
        Coefficients, intercept first.
    """
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    a = np.concatenate([np.ones(x.shape[:-1] + (1,)), x], axis=-1)
    single = y.ndim == x.ndim - 1
    c = np.linalg.pinv(a) @ (y[..., None] if single else y)
    return c[..., 0] if single else c


def predict_linear(coef: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``intercept + x @ slopes`` for the coefficients of :func:`fit_linear`.

    Parameters
    ----------
    coef : array (R, 1 + p) or (R, 1 + p, q)
        Coefficients, intercept first.
    x : array (R, n, p)
        Inputs of the R problems.

    Returns
    -------
    array (R, n) or (R, n, q)
        Predictions, one or q per row.
    """
    coef, x = np.asarray(coef, dtype=float), np.asarray(x, dtype=float)
    if coef.ndim == x.ndim - 1:
        return coef[..., :1] + np.einsum("rnp,rp->rn", x, coef[..., 1:])
    return coef[..., :1, :] + x @ coef[..., 1:, :]
