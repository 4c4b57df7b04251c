"""Identification of a machine's errors from a test's readings, with uncertainty, and prediction.

The model and its coordinates are :mod:`.identifiability`'s: whitened readings
``y~ = y / sigma``, prior-scaled errors ``z = eps / prior_sd``, the nuisances projected out
exactly, ``A_perp = U S V'``, and the seen directions (``s_i**2 >= shrink - 1``) first.

**Truncated SVD** (``method="tsvd"``, the default): the minimum-norm least-squares estimate in
the subspace the data determine (every direction above :data:`NULL_RTOL` of the strongest, not
only the seen ones: a weak direction left at the prior mean would bias the seen errors that
touch it), ``z^ = V_d S_d^-1 U_d' y~``, and the prior mean (zero) along the null directions.
The estimate of a *seen* error uses the data alone and is unbiased; its covariance is
``V_d S_d^-2 V_d'`` plus, for the null part, the prior's ``V_b V_b'``.  **MAP**
(``method="map"``): ``z^ = V diag(S / (1 + S**2)) U' y~``, covariance
``V diag(1 / (1 + S**2)) V'`` (the Gaussian posterior; shrunk towards zero, biased for a
frequentist).  Either way ``z^ - z = B z + G e~`` with ``G`` the estimator and
``B = G A~ - I``, so the covariances of the errors and of the nuisances
(``nu^ = N~^+ (y~ - A~ z^)``) follow exactly from ``B`` and ``G`` with the prior ``z ~ N(0, I)``.

**Chi-square**: the whitened residuals' sum of squares, with ``n_obs - rank(N) - d`` degrees of
freedom for the truncated SVD (``d`` determined directions) and
``n_obs - rank(N) - sum S**2/(1+S**2)`` (the hat matrix's trace, approximate) for MAP; the
p-value is ``P(chi2_dof > value)``.

**Refinement** on an exact model ``exact(eps, nu) -> y`` (e.g. the exact chain and the test's
exact geometry): :func:`scipy.optimize.least_squares` from the linear estimate, over the seen
coordinates and the nuisances (TSVD: the unseen part stays at the prior mean) or over all
coordinates with the prior's residuals ``z`` appended (MAP); the covariance is
``(J' J)^-1`` at the solution (plus the prior's along the unseen directions for TSVD).
"""

from __future__ import annotations

__all__ = ["Identification", "Prediction", "identify", "predict", "MISFIT_P", "UNIT_FACTORS"]

import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy import optimize, stats

from .design import Design
from .identifiability import (
    _check_shrink,
    _core,
    _learned,
    _nuisance_basis,
    _statuses,
    prior_vector,
)

#: Below this p-value of the chi-square, :func:`identify` warns that the model misfits.
MISFIT_P = 1e-3

#: Display units and their factor from the design's units (mm, rad, and mm/mm for a scale).
UNIT_FACTORS = {"mm": 1.0, "um": 1e3, "nm": 1e6, "rad": 1.0, "mrad": 1e3, "urad": 1e6,
                "deg": 180.0 / np.pi, "arcsec": 180.0 * 3600.0 / np.pi, "um/m": 1e6,
                "mm/m": 1e3, "ppm": 1e6, "1": 1.0}


def _units(units, errors) -> tuple[list[str], np.ndarray]:
    if units is None:
        return ["design unit"] * len(errors), np.ones(len(errors))
    if not isinstance(units, Mapping):
        raise ValueError("units must map error symbols to units such as 'um', 'urad', 'um/m'")
    unknown = {e: u for e, u in units.items() if u not in UNIT_FACTORS}
    extra = [e for e in units if e not in errors]
    if unknown or extra:
        raise ValueError(f"units: unknown unit(s) {unknown} (known: {sorted(UNIT_FACTORS)}), "
                         f"unknown error(s) {extra}")
    names = [units.get(e, "design unit") for e in errors]
    return names, np.array([UNIT_FACTORS.get(u, 1.0) for u in names])


def _readings(y, design: Design, what: str = "y") -> np.ndarray:
    """``y`` as (n_obs,) or (R, n_obs) floats, refused with the reading named if bad."""
    try:
        y = np.asarray(y, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{what} must be numbers (um): {exc}") from None
    if y.ndim not in (1, 2) or y.shape[-1] != design.n_obs:
        raise ValueError(f"{what} must be ({design.n_obs},) or (n_replicates, {design.n_obs}) "
                         f"for design {design.name!r}, got {y.shape}")
    bad = np.argwhere(~np.isfinite(np.atleast_2d(y)))
    if bad.size:
        r, i = bad[0]
        where = f"replicate {r}, " if y.ndim == 2 else ""
        raise ValueError(f"{what} has {len(bad)} non-finite value(s), the first at {where}"
                         f"reading {i} ({design.labels[i]!r}): remove the reading from the "
                         "design and the data, or give its value")
    return y


@dataclass(frozen=True)
class Identification:
    """Estimated errors with their uncertainty and status (:func:`identify`).

    Attributes
    ----------
    design : str
        The design's name.
    errors : tuple of str
        The error symbols.
    estimate : (n_errors,) or (R, n_errors) ndarray
        The errors, design units (mm, rad); one row per replicate for batched readings.
    cov : (n_errors, n_errors) ndarray
        Their covariance, design units squared (the same for every replicate).
    status : tuple of str
        ``"seen"``, ``"combination"`` or ``"blind"`` per error (:func:`.identifiability`).
    nuisances : tuple of str
        The nuisances' names.
    nuisance_estimate : (n_nuisances,) or (R, n_nuisances) ndarray
        The nuisances, in the units their names state.
    nuisance_cov : (n_nuisances, n_nuisances) ndarray
        Their covariance.
    chi2 : float or (R,) ndarray
        The whitened residuals' sum of squares.
    dof : float
        Its degrees of freedom.
    method : str
        ``"tsvd"`` or ``"map"``, with ``"+refined"`` after a refinement on the exact model.
    units : tuple of str
        The display unit of each error.
    factors : (n_errors,) ndarray
        From the design's units to the display units.
    rank : int
        The number of seen directions.
    linear : Identification or None
        The linear estimate a refinement started from.
    """

    design: str
    errors: tuple
    estimate: np.ndarray
    cov: np.ndarray
    status: tuple
    nuisances: tuple
    nuisance_estimate: np.ndarray
    nuisance_cov: np.ndarray
    chi2: np.ndarray
    dof: float
    method: str
    units: tuple
    factors: np.ndarray
    rank: int
    linear: Identification | None = field(default=None, repr=False)

    @property
    def standard_uncertainty(self) -> np.ndarray:
        """(n_errors,) ndarray: the errors' standard uncertainties, design units."""
        return np.sqrt(np.clip(np.diag(self.cov), 0.0, None))

    @property
    def p_value(self):
        """float or (R,) ndarray: ``P(chi2_dof > chi2)``, nan without degrees of freedom."""
        return stats.chi2.sf(self.chi2, self.dof) if self.dof > 0 else np.full_like(
            np.asarray(self.chi2, dtype=float), np.nan)

    def to_df(self, replicate: int | None = None) -> pd.DataFrame:
        """One row per error in its display unit: the table ``identified_errors.csv`` holds.

        Parameters
        ----------
        replicate : int, optional
            Which replicate, for batched readings (required then).

        Returns
        -------
        pandas.DataFrame
            Columns ``symbol``, ``estimate``, ``standard_uncertainty``, ``unit``, ``status``.
        """
        est = self.estimate
        if est.ndim == 2:
            if replicate is None:
                raise ValueError(f"{est.shape[0]} replicates: pass replicate=i for one table")
            est = est[replicate]
        return pd.DataFrame({"symbol": list(self.errors), "estimate": est * self.factors,
                             "standard_uncertainty": self.standard_uncertainty * self.factors,
                             "unit": list(self.units), "status": list(self.status)})


#: A direction whose singular value is below this fraction of the largest is numerically null:
#: its information is below 1e-12 of the strongest direction's.
NULL_RTOL = 1e-6


def _estimable(core) -> int:
    """The directions the truncated SVD estimates from: every one the data determine.

    Not only the seen ones (``core.k``): a direction below the seen threshold but well above
    zero carries signal, and leaving it at the prior mean would bias the seen errors that
    touch it (the five-axis plan of notebook 08 has directions with ``S**2`` of 67 next to the
    threshold 99, which biased seen errors by more than a standard uncertainty)."""
    r = core.U.shape[1]
    S = core.S[:r]
    return int(np.sum(S > NULL_RTOL * S[0])) if r and S[0] > 0 else 0


def _estimator(core, method: str) -> tuple[np.ndarray, np.ndarray]:
    """``G`` (p, n) acting on whitened readings, and ``B = G A~ - I`` (p, p)."""
    r = core.U.shape[1]
    S, V = core.S[:r], core.V[:, :r]
    if method == "tsvd":
        k = _estimable(core)
        G = (V[:, :k] / S[:k][None, :]) @ core.U[:, :k].T
    else:
        G = (V * (S / (1.0 + S**2))[None, :]) @ core.U.T
    B = G @ core.At - np.eye(core.At.shape[1])
    return G, B


def _check_method(method: str) -> str:
    if method not in ("tsvd", "map"):
        raise ValueError(f"method must be 'tsvd' or 'map', got {method!r}")
    return method


def identify(y, design: Design, *, prior_sd, exact: Callable | None = None,
             method: str = "tsvd", shrink: float = 100.0, units=None) -> Identification:
    """Estimate the errors from a test's readings, with covariance, status and chi-square.

    Parameters
    ----------
    y : (n_obs,) or (R, n_obs) array_like
        The readings, um (a batch of R replicates at once; no loop over them).
    design : Design
        The test or plan that produced them.
    prior_sd : (n_errors,) array_like or mapping of str to float
        Each error's prior standard deviation, design units (mm, rad).
    exact : callable, optional
        ``exact(eps, nu) -> (n_obs,)`` readings, um, of the exact (nonlinear) model, ``eps``
        (n_errors,) in design units and ``nu`` (n_nuisances,): refine the linear estimate on
        it (one replicate only).
    method : {"tsvd", "map"}
        Truncated SVD (the default; unbiased for seen errors) or the Gaussian posterior mode.
    shrink : float, default 100
        The factor a direction's prior variance must shrink by to be seen.
    units : mapping of str to str, optional
        Display units per error for ``.to_df()`` (keys of :data:`UNIT_FACTORS`: ``"um"``,
        ``"urad"``, ``"um/m"``, ...); the others stay in the design's units.

    Returns
    -------
    Identification
        Estimates, covariance, statuses, nuisances and chi-square (``.to_df()``).

    Warns
    -----
    RuntimeWarning
        For one replicate whose chi-square's p-value is below :data:`MISFIT_P`, and when the
        refinement does not converge.
    """
    s = prior_vector(design, prior_sd)
    shrink = _check_shrink(shrink)
    method = _check_method(method)
    unit_names, factors = _units(units, design.errors)
    y = _readings(y, design)
    if exact is not None and (not callable(exact) or y.ndim != 1):
        raise ValueError("exact must be a callable exact(eps, nu) -> readings, and y one "
                         "replicate (n_obs,) for the refinement")
    core = _core(design, s, shrink)
    G, B = _estimator(core, method)
    yt = y / design.sigma
    z = yt @ G.T
    K = np.linalg.pinv(core.Nt) if core.Nt.shape[1] else np.zeros((0, design.n_obs))
    nu = (yt - z @ core.At.T) @ K.T
    KA = K @ core.At
    H = K - KA @ G
    cov_z = B @ B.T + G @ G.T
    cov_nu = KA @ B @ B.T @ KA.T + H @ H.T
    res = yt - z @ core.At.T - nu @ core.Nt.T
    chi2 = np.sum(res**2, axis=-1)
    r = core.U.shape[1]
    fitted = (_estimable(core) if method == "tsvd"
              else float(np.sum(core.S[:r]**2 / (1 + core.S[:r]**2))))
    dof = design.n_obs - core.Q.shape[1] - fitted
    status = _statuses(np.clip(1.0 - np.sum(core.V[:, :core.k]**2, axis=1), 0.0, 1.0),
                       _learned(core), shrink)
    lin = Identification(design.name, design.errors, z * s, cov_z * np.outer(s, s),
                         tuple(status.tolist()), design.nuisances, nu, cov_nu, chi2, dof,
                         method, tuple(unit_names), factors, core.k)
    out = lin if exact is None else _refine(y, design, lin, core, s, exact, method)
    if y.ndim == 1 and out.dof > 0 and out.p_value < MISFIT_P:
        warnings.warn(f"design {design.name!r}: chi-square {float(out.chi2):.4g} on "
                      f"{out.dof:.4g} degrees of freedom (p = {float(out.p_value):.2g}): the "
                      "readings depart from the model by more than their sigma; check sigma, "
                      "outliers, or the linearisation (give exact=)", RuntimeWarning,
                      stacklevel=2)
    return out


def _refine(y, design, lin, core, s, exact, method):
    """Least squares on the exact model from the linear estimate (see the module docstring)."""
    eps0, nu0 = lin.estimate, lin.nuisance_estimate
    first = np.asarray(exact(eps0.copy(), nu0.copy()), dtype=float)
    if first.shape != (design.n_obs,) or not np.isfinite(first).all():
        raise ValueError(f"exact(eps, nu) must return ({design.n_obs},) finite readings (um) "
                         f"for design {design.name!r}, got shape {first.shape}")
    D = core.V[:, :_estimable(core)] if method == "tsvd" else np.eye(len(s))
    cn = np.linalg.norm(core.Nt, axis=0)
    dnu = np.where(cn > 0, 1.0 / np.where(cn > 0, cn, 1.0), 1.0)
    na = D.shape[1]
    z0 = eps0 / s

    def split(x):
        return eps0 + s * (D @ x[:na]), nu0 + dnu * x[na:]

    def fun(x):
        eps, nu = split(x)
        r = (y - np.asarray(exact(eps, nu), dtype=float)) / design.sigma
        return r if method == "tsvd" else np.concatenate([r, z0 + D @ x[:na]])

    sol = optimize.least_squares(fun, np.zeros(na + len(nu0)), jac="3-point", method="trf",
                                 xtol=1e-14, ftol=1e-14, gtol=1e-14)
    if not sol.success:
        warnings.warn(f"refinement of {design.name!r} did not converge: {sol.message}",
                      RuntimeWarning, stacklevel=3)
    eps, nu = split(sol.x)
    cov_x = np.linalg.pinv(sol.jac.T @ sol.jac)
    cov_z = D @ cov_x[:na, :na] @ D.T
    if method == "tsvd":
        Vb = core.V[:, _estimable(core):]
        cov_z = cov_z + Vb @ Vb.T
    data = sol.fun[:design.n_obs]
    return Identification(lin.design, lin.errors, eps, cov_z * np.outer(s, s), lin.status,
                          lin.nuisances, nu, cov_x[na:, na:] * np.outer(dnu, dnu),
                          float(np.sum(data**2)), lin.dof, method + "+refined", lin.units,
                          lin.factors, lin.rank, lin)


@dataclass(frozen=True)
class Prediction:
    """A held-out test's readings predicted from identified errors (:func:`predict`).

    Attributes
    ----------
    design : str
        The held-out test's name.
    labels : tuple of str
        Its readings' labels.
    reading : (n_obs,) or (R, n_obs) ndarray
        The predicted readings, um (with the test's nuisances fitted when its data were given,
        else the nuisance-free part ``A eps``).
    cov : (n_obs, n_obs) ndarray
        The covariance of the prediction about the noise-free readings, um squared.
    measured : ndarray or None
        The held-out readings, um, when given.
    residual_cov : (n_obs, n_obs) ndarray or None
        The covariance of ``measured - reading`` (the estimate's and the noise's), um squared.
    """

    design: str
    labels: tuple
    reading: np.ndarray
    cov: np.ndarray
    measured: np.ndarray | None = None
    residual_cov: np.ndarray | None = None

    @property
    def standard_uncertainty(self) -> np.ndarray:
        """(n_obs,) ndarray: the predictions' standard uncertainties, um."""
        return np.sqrt(np.clip(np.diag(self.cov), 0.0, None))

    @property
    def residual_sd(self) -> np.ndarray | None:
        """(n_obs,) ndarray or None: the standard deviation of ``measured - reading``, um."""
        if self.residual_cov is None:
            return None
        return np.sqrt(np.clip(np.diag(self.residual_cov), 0.0, None))

    def to_df(self, replicate: int | None = None) -> pd.DataFrame:
        """One row per reading.

        Parameters
        ----------
        replicate : int, optional
            Which replicate, for batched predictions (required then).

        Returns
        -------
        pandas.DataFrame
            Columns ``label``, ``prediction_um``, ``standard_uncertainty_um`` and, with the
            data, ``measured_um``, ``residual_um`` and ``residual_sd_um``.
        """
        pred, meas = self.reading, self.measured
        if pred.ndim == 2:
            if replicate is None:
                raise ValueError(f"{pred.shape[0]} replicates: pass replicate=i for one table")
            pred = pred[replicate]
            meas = meas[replicate] if meas is not None and meas.ndim == 2 else meas
        out = pd.DataFrame({"label": list(self.labels), "prediction_um": pred,
                            "standard_uncertainty_um": self.standard_uncertainty})
        if meas is not None:
            out["measured_um"] = meas
            out["residual_um"] = meas - pred
            out["residual_sd_um"] = self.residual_sd
        return out


def predict(result: Identification, design: Design, *, y=None) -> Prediction:
    """Predict a held-out test's readings from identified errors, with their uncertainty.

    Without ``y``: the nuisance-free part ``A eps^`` with covariance ``A C A'``.  With the
    held-out readings ``y``: the test's own nuisances fitted to ``y - A eps^`` (weighted least
    squares), the prediction ``A eps^ + N nu^``; about the noise-free readings its covariance
    is ``(I - P) A C A' (I - P) + P`` in whitened units (``P`` the projector onto the whitened
    nuisances' range), and ``y - prediction`` has ``(I - P)(A C A' + I)(I - P)``.

    Parameters
    ----------
    result : Identification
        The errors identified from other tests (one replicate, or a batch).
    design : Design
        The held-out test, of the same machine.
    y : (n_obs,) or (R, n_obs) array_like, optional
        Its readings, um.

    Returns
    -------
    Prediction
        The predicted readings and their covariances (``.to_df()``).
    """
    if design.errors != result.errors:
        raise ValueError(f"test {design.name!r} has other errors than the identification of "
                         f"{result.design!r}: predict a test of the same machine")
    est, C = result.estimate, result.cov
    A = np.asarray(design.A)
    mean = est @ A.T
    cov_f = A @ C @ A.T
    if y is None:
        return Prediction(design.name, design.labels, mean, cov_f)
    y = _readings(y, design)
    if est.ndim == 2 and (y.ndim != 2 or y.shape[0] != est.shape[0]):
        raise ValueError(f"y must be ({est.shape[0]}, {design.n_obs}) for "
                         f"{est.shape[0]} replicates, got {y.shape}")
    sig = design.sigma
    Q = _nuisance_basis(design.N / sig[:, None])               # P = Q Q'
    At = A / sig[:, None]
    Ap = At - Q @ (Q.T @ At)                                   # (I - P) A~, P = Q Q'
    rt = (y - mean) / sig
    pred = mean + ((rt @ Q) @ Q.T) * sig
    outer = np.outer(sig, sig)
    fitted = Ap @ C @ Ap.T
    cov = (fitted + Q @ Q.T) * outer
    rcov = (fitted + np.eye(design.n_obs) - Q @ Q.T) * outer
    return Prediction(design.name, design.labels, pred, cov, y, rcov)
