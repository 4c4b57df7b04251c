"""Support vector regression for the thermal models (Xu et al. 2022, Section 4.3).

scikit-learn's ``SVR`` on standardised data (:class:`StandardisedSVR`), hyperparameters by
``GridSearchCV`` with ``GroupKFold`` (one experiment held out per fold: :func:`svr_search`,
:class:`GroupedSVR`), tied scores to the simplest candidate (:func:`canonical_best`,
:func:`tie_margin`), C bounded by the number of rows (:func:`bounded_grid`); a fit whose model
an already fitted smaller C determines is not fitted again (:class:`UnboundedFits`).
:class:`GroupedSVR` is the inner estimator of the paper's models
(:class:`~mtaccuracy.thermal.models.PointByPointRegressor`,
:class:`~mtaccuracy.thermal.models.DecoupledRegressor`) when they are not MLR.

Units: as the models': inputs in degC, targets in um or um/m; epsilon and gamma in standardised
units.
"""

from __future__ import annotations

import copy
import functools
import hashlib
import itertools
import threading

import numpy as np
from joblib import parallel_config
from sklearn import config_context
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.model_selection import GridSearchCV, ParameterGrid
from sklearn.svm import SVR
from sklearn.utils.validation import check_is_fitted, validate_data

from .. import validate
from .models import SearchedRegressor, grouped_folds

__all__ = [
    "StandardisedSVR", "GroupedSVR", "svr_search", "svr_simplicity", "canonical_best",
    "tie_margin", "UnboundedFits", "bounded_grid", "SVR_GRID", "SVR_SOLVER_TOL",
    "SVR_TIE_RTOL", "SVR_MAX_CN",
]

#: SVR search grid (inputs and target standardised inside :class:`StandardisedSVR`, so
#: epsilon and gamma are in standard units).  Linear and RBF kernels both compete.  A search
#: on n training rows leaves out the C with ``C * n >`` :data:`SVR_MAX_CN` (a bounded grid).
SVR_GRID = [
    {"kernel": ["linear"], "C": [0.01, 0.1, 1.0, 10.0, 100.0], "epsilon": [0.01, 0.1]},
    {"kernel": ["rbf"], "C": [0.1, 1.0, 10.0, 100.0, 1000.0], "gamma": [0.01, 0.1, 1.0],
     "epsilon": [0.01, 0.1]},
]

#: libsvm's stopping tolerance (the KKT violation, in standardised units).  Where libsvm stops
#: short of the optimum depends on the floating-point path that led there, and another CPU's
#: BLAS kernel (OpenBLAS chooses one per CPU) changes the inputs by rounding (1e-16 relative):
#: scikit-learn's default, 1e-3, then moved cross-validated RMSEs by up to 2 % and held-out
#: metrics by 0.5 % (ill-conditioned candidates: RBF with gamma 0.01 and C 1000 is nearly a
#: linear model with a huge C).  The spread shrinks in proportion to the tolerance: over the
#: SVR results of notebook 04 (the main split's search, every split of leave one experiment
#: out, both sensor choices), ``OPENBLAS_CORETYPE=Haswell, Sandybridge, Prescott`` against this
#: machine's kernel moved them by up to 3e-5 relative at 1e-6 (the sixth digit of the stored
#: tables: 24 of 172 numbers), 2.4e-7 at 1e-8, 7.8e-9 at 1e-10 and 2.0e-11 at 1e-12 (none of
#: the 172 at six digits).  At 1e-12 the results are the optimum's to about 1e-11, a property
#: of the data and not of the CPU, and the sixth digit of a table is safe; the time hardly
#: changes (one split of notebook 04 at the reader's size limits: 87 s at 1e-6, 97 s at 1e-12;
#: no candidate reached libsvm's iteration limit).
SVR_SOLVER_TOL = 1e-12

#: Bounded grid (issue 22): a search on n training rows tries only the C of the grid with
#: ``C * n <= SVR_MAX_CN``.  C weighs the sum of the n samples' losses against the
#: regularisation, so C * n, not C, is the weight of the whole fit: the bound keeps the least
#: regularised candidate no less regularised than the grid's at 30 rows (C = 1000 there; the
#: paper's 24 training measurements are searched over the whole grid) instead of letting it
#: go towards no regularisation as n grows, and libsvm's time, which grows with
#: C * n (the dual variables at their bound C are many and move a little per iteration), with
#: it: on 10 experiments x 100 measurements (900 training rows, the reader's limit) the two
#: searches of a split took 15 minutes over the whole grid, all but half a minute of it in
#: the candidates with C >= 100; within the bound (C <= 33 there) they take half a minute and
#: chose the same candidates.
SVR_MAX_CN = 30_000.0

#: Cross-validated RMSEs within this relative distance of the best are ties: candidates that
#: give the same model (a C larger than every dual variable needs, an epsilon tube no sample
#: touches) score equal up to rounding, and which of them scikit-learn's "first best" picks
#: would follow floating-point noise.  1e-3 is far above the scatter of near-best scores under
#: rounding-level perturbations (< 1e-10 at :data:`SVR_SOLVER_TOL`; < 2e-6 at the 1e-6 used
#: before) and far below any difference a cross-validation over a few experiments can resolve.
SVR_TIE_RTOL = 1e-3


class StandardisedSVR(RegressorMixin, BaseEstimator):
    """scikit-learn's :class:`~sklearn.svm.SVR` on standardised inputs and target.

    The same model as ``TransformedTargetRegressor(Pipeline([StandardScaler(), SVR()]),
    transformer=StandardScaler())`` (a constant column keeps scale 1, as there), in one
    estimator: :class:`~sklearn.model_selection.GridSearchCV` clones, validates and scores
    every candidate in every fold, and with four nested estimators that overhead, not libsvm,
    took most of the search's time (this one estimator halves it).  Standardising is two
    lines, so it is written here.

    Parameters
    ----------
    kernel, C, gamma, epsilon, tol
        As :class:`sklearn.svm.SVR` (gamma and epsilon in standardised units); ``tol``
        default :data:`SVR_SOLVER_TOL`.

    Attributes
    ----------
    x_mean_, x_scale_ : arrays (p,)
        Input means and standard deviations (1 for a constant input).
    y_mean_, y_scale_ : float
        Target mean and standard deviation (1 for a constant target).
    svr_ : sklearn.svm.SVR
        The SVR fitted on the standardised data.
    """

    def __init__(self, *, kernel="rbf", C=1.0, gamma="scale", epsilon=0.1, tol=SVR_SOLVER_TOL):
        self.kernel = kernel
        self.C = C
        self.gamma = gamma
        self.epsilon = epsilon
        self.tol = tol

    def fit(self, X, y, unbounded_fits=None):
        """Fit on standardised inputs and target.

        Parameters
        ----------
        X : array (n, p)
            Inputs (temperatures or rises, degC).
        y : array (n,)
            Target (k in um/m, b in um, or an error in um).
        unbounded_fits : UnboundedFits, optional
            Fits of the same data with a smaller C whose dual variables all stayed below it:
            when one is there, it is this fit's model (not fitted again); when this fit is
            such a fit, it is added.  :func:`svr_search` passes one per search.

        Returns
        -------
        self
        """
        X, y = validate_data(self, X, y, y_numeric=True, dtype=np.float64)
        self.x_mean_, sx = X.mean(axis=0), X.std(axis=0)
        self.x_scale_ = np.where(sx > 0, sx, 1.0)
        self.y_mean_, sy = float(y.mean()), float(y.std())
        self.y_scale_ = sy if sy > 0 else 1.0
        svr = SVR(kernel=self.kernel, C=self.C, gamma=self.gamma, epsilon=self.epsilon,
                  tol=self.tol)
        same = None if unbounded_fits is None else unbounded_fits.find(X, y, svr)
        if same is not None:
            self.svr_ = same
            return self
        self.svr_ = svr.fit((X - self.x_mean_) / self.x_scale_,
                            (y - self.y_mean_) / self.y_scale_)
        if unbounded_fits is not None:
            unbounded_fits.add(X, y, self.svr_)
        return self

    def predict(self, X):
        """Predictions in the target's units.

        Parameters
        ----------
        X : array (n, p)
            Inputs, the columns of ``fit``'s (degC).

        Returns
        -------
        array (n,)
            Predicted target.
        """
        check_is_fitted(self)
        z = (validate_data(self, X, reset=False, dtype=np.float64) - self.x_mean_) / self.x_scale_
        return self.svr_.predict(z) * self.y_scale_ + self.y_mean_


class UnboundedFits:
    """Fitted SVRs none of whose dual variables reached C: the models of every larger C.

    libsvm's epsilon-SVR dual bounds every dual variable, ``0 <= alpha_i, alpha*_i <= C``.
    When a fit stops with all of them below C, that bound is inactive: the same dual point
    meets libsvm's stopping rule (its largest KKT violation below ``tol``; which variables may
    move up or down, and which are free for the intercept, depend only on the bounds they sit
    at, and none sits at C) for every larger C, and the problem being convex, the optimum is
    the same.  So a candidate with a larger C and otherwise the same parameters, on the same
    data, has that model: it is taken as it is instead of being fitted again (its scores are
    the smaller C's, exactly).  libsvm would reach the same optimum from zero by another path,
    to within ``tol``: such candidates scored equal up to rounding before and still tie
    (:data:`SVR_TIE_RTOL`), and the simplest, the smaller C, wins as before.

    ``dual_coef_`` holds ``alpha_i - alpha*_i``.  Where libsvm stops, at most one of the two is
    non-zero when ``2 epsilon > tol`` (both non-zero make the KKT violation at least
    ``2 epsilon``), so ``|dual_coef_| < C`` is the test; with a smaller epsilon, or a fit that
    stopped at libsvm's iteration limit, nothing is reused.  Written by hand: libsvm (through
    scikit-learn) has no warm start, and this is the one case where none is needed.

    Attributes
    ----------
    reused : int
        Fits answered from a smaller C so far.
    """

    def __init__(self):
        self._fits = {}
        self.reused = 0
        self._lock = threading.Lock()      # the fits of a search may run on threads

    @staticmethod
    def _key(X, y, svr) -> tuple:
        h = hashlib.blake2b(digest_size=16)
        for a in (X, y):
            a = np.ascontiguousarray(a, dtype=np.float64)
            h.update(repr(a.shape).encode())
            h.update(a.tobytes())
        return h.hexdigest(), tuple(sorted((k, v) for k, v in svr.get_params().items()
                                           if k != "C"))

    @staticmethod
    def _applies(svr) -> bool:
        return 2.0 * svr.epsilon > svr.tol

    def find(self, X, y, svr):
        """The model of ``svr`` (unfitted) on ``(X, y)`` if a smaller C already determines it.

        Parameters
        ----------
        X : array (n, p)
            Inputs, as given to the estimator's ``fit`` (before standardising).
        y : array (n,)
            Target, as given.
        svr : sklearn.svm.SVR
            The unfitted SVR with the candidate's parameters.

        Returns
        -------
        sklearn.svm.SVR or None
            A copy of the fitted SVR of the largest such smaller C, its ``C`` set to
            ``svr.C``; None when there is none.
        """
        if not self._applies(svr):
            return None
        fits = [f for f in self._fits.get(self._key(X, y, svr), ()) if f.C < svr.C]
        if not fits:
            return None
        same = copy.copy(max(fits, key=lambda f: f.C))
        same.C = svr.C
        with self._lock:
            self.reused += 1
        return same

    def add(self, X, y, svr) -> None:
        """Keep a fitted SVR if none of its dual variables reached C.

        Parameters
        ----------
        X : array (n, p)
            Inputs, as given to the estimator's ``fit``.
        y : array (n,)
            Target, as given.
        svr : sklearn.svm.SVR
            Fitted on the standardised ``(X, y)``.
        """
        if (self._applies(svr) and svr.fit_status_ == 0
                and np.abs(svr.dual_coef_).max(initial=0.0) < svr.C):
            key = self._key(X, y, svr)
            with self._lock:
                self._fits.setdefault(key, []).append(svr)


class _CandidateSearch(GridSearchCV):
    """``GridSearchCV`` evaluating the grid in its order, a run of equal C at a time.

    The results are those of ``GridSearchCV`` (the same candidates, folds and order).  A fit
    reuses only fits of a smaller C (:class:`UnboundedFits`), so all of them are done before it
    starts whatever the scheduling; after each run ``progress("<i> of <n> candidates")`` is
    called when given.
    """

    def __init__(self, estimator, param_grid, *, scoring=None, n_jobs=None, refit=True,
                 cv=None, progress=None):
        super().__init__(estimator, param_grid, scoring=scoring, n_jobs=n_jobs, refit=refit,
                         cv=cv)
        self.progress = progress

    def _run_search(self, evaluate_candidates):
        candidates = list(ParameterGrid(self.param_grid))
        done = 0
        for _, run in itertools.groupby(candidates, key=lambda p: p.get("C")):
            run = list(run)
            evaluate_candidates(run)
            done += len(run)
            if self.progress is not None:
                self.progress(f"{done} of {len(candidates)} candidates")


def bounded_grid(grid, n_samples: int, max_cn: float = SVR_MAX_CN) -> list[dict]:
    """The candidates of an SVR grid whose C times the number of training rows is within a bound.

    Parameters
    ----------
    grid : dict or list of dict
        ``GridSearchCV`` parameter grid of :class:`StandardisedSVR` (a dict without ``"C"``
        stands for the default C = 1).
    n_samples : int
        Training rows of the search (all of them: every fold has fewer); at least 1.
    max_cn : float
        The bound on ``C * n_samples`` (:data:`SVR_MAX_CN`); ``inf`` keeps the grid.

    Returns
    -------
    list of dict
        The grid, each ``"C"`` list cut to the values within the bound, dicts left with none
        dropped; in the given order.

    Raises
    ------
    ValueError
        When no candidate is left.
    """
    n_samples = validate.integer(n_samples, "n_samples", low=1)
    out = []
    for g in [grid] if isinstance(grid, dict) else grid:
        if "C" not in g:
            if n_samples <= max_cn:
                out.append(dict(g))
            continue
        cs = [c for c in g["C"] if c * n_samples <= max_cn]
        if cs:
            out.append({**g, "C": cs})
    if not out:
        raise ValueError(f"no SVR candidate has C x n_samples <= {max_cn:g} at n_samples = "
                         f"{n_samples} (the bounded grid, SVR_MAX_CN); add smaller C")
    return out


def _svr_params(params: dict) -> dict:
    return {key.rsplit("__", 1)[-1]: v for key, v in params.items()}


def svr_simplicity(params: dict) -> tuple:
    """The canonical order among tied SVR candidates, simplest first.

    A linear kernel before RBF, then the smaller C (stronger regularisation), the smaller gamma
    (smoother), the larger epsilon (a wider tube, fewer support vectors).

    Parameters
    ----------
    params : dict
        A candidate of the grid (keys may carry an estimator prefix ``...__``).

    Returns
    -------
    tuple
        Sort key.
    """
    p = _svr_params(params)
    gamma = p.get("gamma", 0.0)
    gamma = float(gamma) if isinstance(gamma, int | float) else np.inf
    return (p.get("kernel") != "linear", float(p.get("C", 1.0)), gamma,
            -float(p.get("epsilon", 0.1)))


def canonical_best(cv_results: dict, rtol: float = SVR_TIE_RTOL) -> int:
    """Index of the chosen SVR candidate: the simplest within ``rtol`` of the best RMSE.

    Used as ``GridSearchCV(refit=...)``, so that the choice is a property of the scores, not of
    rounding noise or of the grid's order.

    Parameters
    ----------
    cv_results : dict
        ``GridSearchCV.cv_results_`` scored with ``neg_root_mean_squared_error``.
    rtol : float
        Mean cross-validated RMSEs within this relative distance of the best are ties.

    Returns
    -------
    int
        Index into ``cv_results["params"]``.

    Raises
    ------
    ValueError
        When every candidate failed.
    """
    rmse = -np.asarray(cv_results["mean_test_score"], dtype=float)
    if not np.isfinite(rmse).any():
        raise ValueError("every SVR candidate failed in cross-validation")
    best = np.nanmin(rmse)
    tied = np.flatnonzero(rmse <= best * (1.0 + rtol))
    return int(min(tied, key=lambda i: (svr_simplicity(cv_results["params"][i]), i)))


def tie_margin(cv_results: dict, rtol: float = SVR_TIE_RTOL) -> tuple[int, float]:
    """How far the SVR choice is from flipping.

    Parameters
    ----------
    cv_results : dict
        ``GridSearchCV.cv_results_`` scored with ``neg_root_mean_squared_error``.
    rtol : float
        The tie window (:data:`SVR_TIE_RTOL`).

    Returns
    -------
    tied : int
        Candidates within the window, the best included.
    margin : float
        Distance of the nearest other candidate to the window's edge, relative to the best
        RMSE; NaN when there is no other candidate.
    """
    rmse = -np.asarray(cv_results["mean_test_score"], dtype=float)
    rmse = rmse[np.isfinite(rmse)]
    gap = rmse / rmse.min() - 1.0
    others = np.delete(gap, np.argmin(gap))
    return int((gap <= rtol).sum()), float(np.abs(others - rtol).min()) if others.size else np.nan


def svr_search(x: np.ndarray, y: np.ndarray, *, groups=None, grid=None,
               tie_rtol: float = SVR_TIE_RTOL, max_cn: float = SVR_MAX_CN, progress=None):
    """Choose SVR hyperparameters by grouped cross-validation on the training data only.

    The folds leave one training experiment out at a time (``GroupKFold`` with one fold per
    experiment), the score is the RMSE of the held-out experiment, the winner is the simplest
    candidate within ``tie_rtol`` of the best score (:func:`canonical_best`), and it is
    refitted on all training data.  Deterministic: no random state is involved.  The grid is
    bounded: only the C with ``C * n <= max_cn`` are tried (:func:`bounded_grid`,
    :data:`SVR_MAX_CN`; the whole grid up to 30 rows).  Every candidate left is scored in
    every fold, but a fold's fit whose model a smaller C already determines is taken from it,
    not fitted again (:class:`UnboundedFits`; the grid lists C ascending, so the smaller C
    comes first).  The fits run one at a time; within ``joblib.parallel_config(n_jobs=2)``
    they run on two threads (libsvm releases the GIL), with the same results.

    Parameters
    ----------
    x : array (n, p)
        Inputs (temperatures or rises, degC).
    y : array (n,)
        Target (k in um/m, b in um, or an error in um).
    groups : array (n,), optional
        Experiment of each row; one fold per experiment.  None: ``KFold(min(5, n))``,
        unshuffled.
    grid : list of dict, optional
        Parameter grid of :class:`StandardisedSVR`; default :data:`SVR_GRID`.
    tie_rtol : float
        Relative RMSE window of ties (:data:`SVR_TIE_RTOL`).
    max_cn : float
        Bound on C times the number of rows (:data:`SVR_MAX_CN`); ``inf``: the whole grid.
    progress : callable, optional
        Called as ``progress("<i> of <n> candidates")`` after each run of candidates with
        equal C (all their folds).

    Returns
    -------
    GridSearchCV
        Fitted; its ``best_score_`` is not set: use
        ``cv_results_["mean_test_score"][best_index_]``.  ``reused_fits_``: the fold fits
        taken from a smaller C.
    """
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    if len(y) < 2:
        raise ValueError(f"n_samples = {len(y)}: cross-validation needs at least 2 samples")
    cv = grouped_folds(len(y), groups, "SVR")
    if not (np.isfinite(x).all() and np.isfinite(y).all()):
        raise ValueError("SVR inputs and target must be finite")
    refit = canonical_best if tie_rtol == SVR_TIE_RTOL else functools.partial(
        canonical_best, rtol=tie_rtol)
    search = _CandidateSearch(StandardisedSVR(), bounded_grid(grid or SVR_GRID, len(y), max_cn),
                              cv=cv, scoring="neg_root_mean_squared_error", refit=refit,
                              progress=progress)
    unbounded = UnboundedFits()
    # checked above, and the grid is fixed: skip scikit-learn's per-fit re-validation (a fifth
    # of the search's time); ``unbounded`` goes to every fit as a fit parameter (passed as it
    # is without metadata routing); n_jobs from the caller's joblib.parallel_config (default
    # 1), on threads, which share it
    with config_context(assume_finite=True, skip_parameter_validation=True,
                        enable_metadata_routing=False), parallel_config(backend="threading"):
        search.fit(x, y, groups=groups, unbounded_fits=unbounded)
    search.reused_fits_ = unbounded.reused
    return search


class GroupedSVR(SearchedRegressor):
    """SVR whose hyperparameters are chosen by grouped cross-validation at ``fit``.

    The estimator form of :func:`svr_search`: ``fit(X, y, groups)`` searches ``grid`` with one
    fold per group (an experiment held out at a time, Xu et al. 2022 train on experiments and
    test on another), takes the simplest candidate within ``tie_rtol`` of the best RMSE and
    refits it on all of ``X``.  Without ``groups`` the folds are ``KFold(5)`` (unshuffled).

    Parameters
    ----------
    grid : list of dict, optional
        ``GridSearchCV`` parameter grid of :class:`StandardisedSVR`; default :data:`SVR_GRID`.
    tie_rtol : float
        Relative RMSE window of ties (:data:`SVR_TIE_RTOL`).
    max_cn : float
        Bound on C times the number of rows (:data:`SVR_MAX_CN`, :func:`bounded_grid`).

    Attributes
    ----------
    search_ : GridSearchCV
        The fitted search (``cv_results_``, ``best_params_``, ``best_index_``).
    best_estimator_ : StandardisedSVR
        The chosen candidate refitted on all data.
    n_features_in_ : int
        Number of inputs.
    """

    def __init__(self, grid=None, tie_rtol=SVR_TIE_RTOL, max_cn=SVR_MAX_CN):
        self.grid = grid
        self.tie_rtol = tie_rtol
        self.max_cn = max_cn

    def fit(self, X, y, groups=None, *, progress=None):
        """Search the grid with grouped folds and refit the chosen candidate.

        Parameters
        ----------
        X : array (n, p)
            Inputs (temperatures or rises, degC).
        y : array (n,)
            Target (k in um/m, b in um, or an error in um).
        groups : array (n,), optional
            Experiment of each row: one fold per experiment.
        progress : callable, optional
            Called as ``progress("<i> of <n> candidates")`` (:func:`svr_search`).

        Returns
        -------
        self
        """
        X, y = validate_data(self, X, y, y_numeric=True)
        self.search_ = svr_search(X, y, groups=groups, grid=self.grid, tie_rtol=self.tie_rtol,
                                  max_cn=self.max_cn, progress=progress)
        self.best_estimator_ = self.search_.best_estimator_
        return self


