"""Probes at any angles: what a layout separates, its weights, and the separation itself.

The separation of an artefact's profile from a spindle's radial error motion, for L >= 3 probes
at any mounting angles (a reader's own measurement: :mod:`~mtaccuracy.spindle.probefile` reads
it, :mod:`~mtaccuracy.spindle.errormotion` evaluates the motion in ISO 230-7 terms).

**The geometry** (Yang et al. 2021, Eq. 7, doi:10.19650/j.cnki.cjsi.J2007206, the convention of
:mod:`~mtaccuracy.spindle.separation`): at spindle angle ``theta`` the probe mounted at angle
``phi`` (counted in the same sense) reads

    y(theta) = r(theta + phi) + x(theta) cos(phi) + y(theta) sin(phi) + offset + noise,

``r`` the artefact's radius deviation at its own angle, ``(x, y)`` the spindle's radial error
motion in the probes' frame, ``offset`` the probe's unknown zero.  The artefact point under the
probe at ``phi`` is ``theta + phi``: the spindle turns the artefact by ``-theta`` in the frame
where the probe angles count positive (a direction fixed to the spindle points at ``alpha -
theta``; :mod:`~mtaccuracy.spindle.errormotion` uses that for the rotating sensitive direction).

**The separation at any angles.**  The library's matrix method and least-squares estimator
(:func:`~mtaccuracy.spindle.separation.separate_details`,
:func:`~mtaccuracy.spindle.least_squares.separate_least_squares`) shift the profile by whole
samples and so need probes on the sampling grid.  In the Fourier domain no grid is needed:
harmonic ``k`` of ``r(theta + phi)`` is ``R_k exp(i k phi)`` for any ``phi``, so
:func:`separate_probes` solves harmonic by harmonic, either with the paper's weighted
multi-point method (a weighted sum ``sum a_l y_l`` with ``sum a_l exp(i phi_l) = 0`` cancels the
motion, ``R_k = Y_k / Lambda_k``, Eqs. 5, 14; weights for the given angles from
:func:`layout_weights`) or by least squares over all probes.  Both reduce to the library's
functions on grid layouts (a test checks it to round-off).  The harmonics it recovers are
``2..max_harmonic`` with ``max_harmonic <= (N - 1) // 2`` (:func:`resolvable_harmonic`; the
Nyquist harmonic ``N / 2`` is only a cosine on the grid and cannot be shifted by a fraction of a
sample).  The mean of each probe is its unknown zero and is removed, so the profile and the
motion have zero mean; the first harmonic of the profile cannot be told from a
once-per-revolution motion turning with the artefact (its centring error) and is given all of it
(the ``"eccentricity"`` convention of :mod:`~mtaccuracy.spindle.separation`).

Why hand-written: the separation at off-grid angles is the paper's method (and the
least-squares estimator beside it) written in the Fourier domain, built from numpy's FFT and
pseudo-inverse and scipy's ``null_space``, ``minimize`` and ``minimize_scalar``; no maintained
package separates multi-probe spindle data.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.optimize
import scipy.special
import scipy.stats

from .. import validate
from . import checks as _checks
from .checks import ROTATIONS, AliasingWarning, RotationSenseWarning, SeparationChecks
from .least_squares import _ls_design
from .separation import (
    _MIN_SAMPLES,
    TWO_PI,
    CancelledHarmonicsWarning,
    _harmonic_list,
)

__all__ = [
    "ProbeSeparation", "resolvable_harmonic", "layout_cancelled", "layout_weights",
    "noise_amplification", "profile_noise_rms", "separate_probes", "separate_probe_data",
    "probe_noise_estimate", "MIN_PROBES", "MAX_PROBES", "MIN_SAMPLES", "RCOND",
    "AMPLIFICATION_DIGITS",
]

# --------------------------------------------------------------------------------------------
# Limits
# --------------------------------------------------------------------------------------------

#: Probes: three is the least that separates a profile from a two-dimensional motion; 16 is more
#: than any multi-probe set-up uses (they use 3 to 5) and bounds the weight search (L - 3 free
#: weights).
MIN_PROBES = 3
MAX_PROBES = 16
#: Samples per revolution: at least 8, the library's least (the probe file allows up to
#: :data:`~mtaccuracy.spindle.probedata.MAX_SAMPLES`).
MIN_SAMPLES = _MIN_SAMPLES
#: Significant digits of the noise amplification a separation reports
#: (:attr:`ProbeSeparation.amplification`).  It carries rounding that another CPU changes
#: (another BLAS kernel's singular values, the weights' search: about 2e-14 relative), which
#: moved a point of notebook 07's figure of it; to 8 digits it is the same on any CPU unless
#: a value lies within that noise of a rounding edge, and a figure on a log scale resolves
#: far less (1e-8 relative is about 1e-6 of a pixel there).
AMPLIFICATION_DIGITS = 8
#: A harmonic is cancelled by a layout when the smallest singular value of the least-squares
#: design of that harmonic (the profile harmonic and the two motion components read by every
#: probe) is below this fraction of the largest, the threshold of
#: :func:`~mtaccuracy.spindle.least_squares.separate_least_squares`.
RCOND = 1e-9


# --------------------------------------------------------------------------------------------
# Harmonics a layout resolves
# --------------------------------------------------------------------------------------------


def resolvable_harmonic(n_samples: int) -> int:
    """The highest harmonic ``(N - 1) // 2`` that N samples a turn resolve at any probe angles.

    Harmonic ``N / 2`` (N even) is a cosine only on the sampling grid: its shift by a probe
    angle off the grid cannot be represented, so it is left out (it goes to the motion).

    Parameters
    ----------
    n_samples : int
        Samples per revolution N (>= 8).

    Returns
    -------
    int
        ``(N - 1) // 2``.
    """
    return (validate.integer(n_samples, "n_samples", low=MIN_SAMPLES) - 1) // 2


def _check_phi(phi) -> np.ndarray:
    phi = np.asarray(phi, dtype=float)
    if phi.ndim != 1 or phi.shape[0] < MIN_PROBES or not np.all(np.isfinite(phi)):
        raise ValueError(f"phi must hold the finite angles (rad) of at least {MIN_PROBES} "
                         f"probes, got {phi!r}")
    d = np.angle(np.exp(1j * (phi[:, None] - phi[None, :])))
    same = np.abs(d) < 1e-9
    np.fill_diagonal(same, False)
    if same.any():
        i, j = np.argwhere(same)[0]
        raise ValueError(f"probes {i} and {j} are at the same angle "
                         f"({np.rad2deg(phi[i]):g} and {np.rad2deg(phi[j]):g} deg, modulo 360)")
    return phi


def _check_band(max_harmonic, n: int) -> int:
    top = resolvable_harmonic(n)
    if max_harmonic is None:
        return top
    try:
        return validate.integer(max_harmonic, "max_harmonic", low=2, high=top)
    except ValueError as exc:
        raise ValueError(f"{exc} (the top is (N - 1) // 2 for N = {n} samples per "
                         f"revolution)") from None


def _ls_variance(phi, harmonics):
    """``[(A_k^H A_k)^-1]_00`` and the relative smallest singular value of the least-squares
    design ``A_k`` (K, L, 3) of every harmonic; inf where it is rank-deficient."""
    a = _ls_design(phi, np.asarray(harmonics))
    sv = np.linalg.svd(a, compute_uv=False)                              # (K, 3)
    rel = sv[:, -1] / sv[:, 0]
    out = np.full(a.shape[0], np.inf)
    ok = rel > RCOND
    if ok.any():
        gram = np.einsum("klr,kls->krs", a[ok].conj(), a[ok])
        out[ok] = np.linalg.inv(gram)[:, 0, 0].real
    return out, rel


def layout_cancelled(phi, max_harmonic: int, *, rcond: float = RCOND) -> list[int]:
    """The harmonics ``2..max_harmonic`` that probes at angles ``phi`` cannot separate.

    Harmonic ``k`` is cancelled when the profile harmonic reads on the probes as a motion would:
    ``exp(i k phi_l)`` lies in the span of ``cos(phi_l)`` and ``sin(phi_l)``, so that the
    least-squares design ``[exp(i k phi_l), cos(phi_l), sin(phi_l)]`` is rank-deficient (its
    smallest singular value below ``rcond`` times the largest).  No estimator recovers such a
    harmonic (three probes 120 deg apart cancel every harmonic but the multiples of 3).

    Parameters
    ----------
    phi : array (L,)
        Probe angles (rad), L >= 3, any values.
    max_harmonic : int
        The highest harmonic considered (>= 2).
    rcond : float
        Relative singular-value threshold.

    Returns
    -------
    list of int
        The cancelled harmonics, ascending.
    """
    phi = _check_phi(phi)
    ks = np.arange(2, validate.integer(max_harmonic, "max_harmonic", low=2) + 1)
    _, rel = _ls_variance(phi, ks)
    return [int(k) for k in ks[rel <= rcond]]


def noise_amplification(phi, harmonics, *, weights=None) -> np.ndarray:
    """How much a separation multiplies probe noise, per harmonic of the profile.

    With white noise of standard deviation ``sigma`` on every probe sample, the estimated
    harmonic ``R_k`` has standard deviation ``q_k sigma sqrt(N)`` (FFT normalisation), and the
    separated profile's noise is :func:`profile_noise_rms`.  ``q_k^2`` is, for the
    least-squares estimator, ``[(A_k^H A_k)^-1]_00`` with ``A_k`` the design
    ``[exp(i k phi_l), cos(phi_l), sin(phi_l)]``; for the weighted method the paper's error
    transfer function ``q_k^2 = sum a_l^2 / |Lambda_k|^2``, ``Lambda_k = sum a_l exp(i k
    phi_l)`` (Yang et al. 2021, Eqs. 14, 19, at any angles and any number of probes).

    Parameters
    ----------
    phi : array (L,)
        Probe angles (rad).
    harmonics : array of int (K,)
        Harmonic orders.
    weights : array (L,), optional
        Weights of the weighted method; None: the least-squares estimator.

    Returns
    -------
    array (K,)
        ``q_k`` (dimensionless), inf where the harmonic is cancelled.
    """
    phi = _check_phi(phi)
    ks = np.asarray(harmonics)
    if weights is None:
        var, _ = _ls_variance(phi, ks)
        return np.sqrt(var)
    a = np.asarray(weights, dtype=float)
    if a.shape != phi.shape or not np.all(np.isfinite(a)):
        raise ValueError(f"weights must be {phi.shape[0]} finite numbers, got {weights!r}")
    lam = np.exp(1j * ks[:, None] * phi[None, :]) @ a
    with np.errstate(divide="ignore"):
        q2 = (a ** 2).sum() / np.abs(lam) ** 2
    return np.where(np.abs(lam) <= RCOND * np.abs(a).sum(), np.inf, np.sqrt(q2))


def profile_noise_rms(amplification, *, n_samples: int, noise_sd: float,
                      n_revolutions: int = 1) -> float:
    """The rms error that white probe noise leaves in the separated profile (harmonics 2 up).

    Every harmonic ``k`` kept occupies the two DFT bins ``+k, -k``, each with variance
    ``N q_k^2 sigma^2 / R`` after averaging ``R`` revolutions, and the inverse FFT divides by
    ``N^2``: ``rms = sigma sqrt(2 sum_k q_k^2 / (N R))`` (Yang et al. 2021, Eq. 18, with the
    ``1/N`` its definitions imply).

    Parameters
    ----------
    amplification : array (K,)
        ``q_k`` of the harmonics kept (:func:`noise_amplification`); inf entries (cancelled
        harmonics, not estimated) are left out.
    n_samples : int
        Samples per revolution N (>= 8).
    noise_sd : float
        Probe noise standard deviation sigma (any length unit).
    n_revolutions : int
        Revolutions averaged R (>= 1).

    Returns
    -------
    float
        In the unit of ``noise_sd``.
    """
    n_samples = validate.integer(n_samples, "n_samples", low=MIN_SAMPLES)
    n_revolutions = validate.integer(n_revolutions, "n_revolutions", low=1)
    q = np.asarray(amplification, dtype=float)
    q = q[np.isfinite(q)]
    return float(noise_sd * np.sqrt(2 * (q ** 2).sum() / (n_samples * n_revolutions)))


# --------------------------------------------------------------------------------------------
# Weights of the weighted multi-point method, for any angles
# --------------------------------------------------------------------------------------------


def _worst_log_q2(t, basis, phase):
    """log of the worst ``q_k^2`` of weights ``basis @ t`` (batched over leading axes of t)."""
    a = np.einsum("lj,...j->...l", basis, t)
    lam = np.einsum("kl,...l->...k", phase, a)
    num = (a ** 2).sum(axis=-1)
    with np.errstate(divide="ignore"):
        return np.log(num) - np.log(np.min(np.abs(lam) ** 2, axis=-1))


#: How many of the best starting directions :func:`layout_weights` refines.
_REFINED = 8


def _canonical(a):
    """Weights scaled so that the first probe's is 1 (the paper's a_0 = 1), or, when it is 0,
    the largest in magnitude is +1."""
    a = np.asarray(a, dtype=float)
    j = 0 if abs(a[0]) > 1e-9 * np.abs(a).max() else int(np.argmax(np.abs(a)))
    return a / a[j]


def layout_weights(phi, harmonics) -> np.ndarray:
    """Weights of the weighted multi-point method for probes at any angles (minimax ``q_k^2``).

    They cancel the motion and minimise the worst error transfer function over ``harmonics``.

    The weights ``a`` must satisfy ``sum a_l cos(phi_l) = sum a_l sin(phi_l) = 0`` (Yang et
    al. 2021, Eq. 5 = Eq. 15 for four probes): they lie in the ``L - 2``-dimensional null space
    of ``[cos(phi); sin(phi)]`` (``scipy.linalg.null_space``).  Three probes leave one direction
    (the three-point method); four leave a circle of directions, the paper's free ``a_3``
    (:func:`~mtaccuracy.spindle.design.optimal_a3` picks it for one harmonic); here the weights
    minimise ``max_k q_k^2`` over every harmonic given (``q_k^2 = sum a_l^2 / |Lambda_k|^2``,
    Eqs. 14, 19, scale-free), the worst case of :func:`~mtaccuracy.spindle.design.objective_worst`
    extended to any number of probes.  The search: a grid of 2048 directions in the null space
    (a half circle for four probes, a fixed Halton set of directions beyond), then
    ``scipy.optimize.minimize_scalar`` (four probes) or Nelder-Mead (five or more) from the
    eight best; results within a relative ``1e-9`` of the best are ties, broken by the smallest
    weights in lexicographic order.  Harmonics no weights can separate
    (:func:`layout_cancelled`) must be left out of ``harmonics``.

    Parameters
    ----------
    phi : array (L,)
        Probe angles (rad), L >= 3.
    harmonics : array of int (K,)
        The harmonics protected (>= 2, none cancelled by the layout).

    Returns
    -------
    array (L,)
        The weights, scaled so that the first probe's is 1 (the paper's ``a_0 = 1``; when the
        best weights ignore the first probe, the largest is 1).
    """
    phi = _check_phi(phi)
    ks = np.asarray(harmonics)
    if ks.ndim != 1 or ks.size == 0 or np.any(ks < 2):
        raise ValueError("harmonics must be a non-empty list of orders >= 2")
    basis = scipy.linalg.null_space(np.vstack([np.cos(phi), np.sin(phi)]))   # (L, L - 2)
    dim = basis.shape[1]
    if dim == 1:
        return _canonical(basis[:, 0])
    phase = np.exp(1j * ks[:, None] * phi[None, :])                         # (K, L)
    if dim == 2:
        grid = np.linspace(0.0, np.pi, 2048, endpoint=False)
        starts = np.stack([np.cos(grid), np.sin(grid)], axis=-1)
    else:
        h = scipy.stats.qmc.Halton(d=dim, scramble=False).random(2049)[1:]
        starts = scipy.special.ndtri(np.clip(h, 1e-12, 1 - 1e-12))
    f = _worst_log_q2(starts, basis, phase)
    if not np.any(np.isfinite(f)):
        raise ValueError("the layout cancels one of the harmonics given: no weights separate "
                         "it (leave out the harmonics layout_cancelled names)")
    found = []
    for i in np.argsort(f, kind="stable")[:_REFINED]:
        if dim == 2:
            step = np.pi / len(starts)
            res = scipy.optimize.minimize_scalar(
                lambda u: _worst_log_q2(np.array([np.cos(u), np.sin(u)]), basis, phase),
                bounds=(grid[i] - step, grid[i] + step), method="bounded",
                options={"xatol": 1e-12})
            t = np.array([np.cos(res.x), np.sin(res.x)])
        else:
            res = scipy.optimize.minimize(
                lambda v: _worst_log_q2(v / np.linalg.norm(v), basis, phase), starts[i],
                method="Nelder-Mead", options={"xatol": 1e-9, "fatol": 1e-12,
                                               "maxiter": 200 * dim})
            t = res.x / np.linalg.norm(res.x)
        value = float(_worst_log_q2(t, basis, phase))
        found.append((value, _canonical(basis @ t)))
    best = min(v for v, _ in found)
    tied = [a for v, a in found if v <= best + 1e-9 * max(1.0, abs(best))]
    return min(tied, key=lambda a: tuple(np.round(a, 9)))


# --------------------------------------------------------------------------------------------
# The separation
# --------------------------------------------------------------------------------------------


@dataclass
class ProbeSeparation:
    """The artefact's profile and the spindle's radial error motion (:func:`separate_probes`).

    Attributes
    ----------
    profile : array (..., N)
        The artefact's radius deviation at the sample angles (the signals' unit), zero mean,
        harmonics 1..max_harmonic (the first by the eccentricity convention).
    dx, dy : arrays (..., R, N)
        The radial error motion of every revolution in the probes' frame, zero mean over the
        measurement, with no once-per-revolution part turning with the artefact on average.
    method : str
        ``"least_squares"`` or ``"weighted"``.
    weights : array (L,) or None
        The weights of the weighted method.
    harmonics : array of int (K,)
        The harmonics ``2..max_harmonic``.
    amplification : array (K,)
        Noise amplification ``q_k`` of the estimator per harmonic (inf where set aside), to
        :data:`AMPLIFICATION_DIGITS` significant digits.
    cancelled : list of int
        Harmonics set aside (the layout cannot separate them).
    max_harmonic : int
        The highest harmonic separated.
    first_harmonic : array (..., 2)
        ``C, D`` of the profile's first harmonic ``C cos + D sin`` (grid angles
        ``2 pi n / N``).
    residual_rms : array (..., R)
        RMS misfit of the probes, per revolution, once the profile and the motion are fitted.
    rotation : str
        The sense of rotation separated under (:data:`~mtaccuracy.spindle.checks.ROTATIONS`).
    checks : SeparationChecks or None
        The statistics of the sense and aliasing checks
        (:class:`~mtaccuracy.spindle.checks.SeparationChecks`).
    """

    profile: np.ndarray
    dx: np.ndarray
    dy: np.ndarray
    method: str
    weights: np.ndarray | None
    harmonics: np.ndarray
    amplification: np.ndarray
    cancelled: list
    max_harmonic: int
    first_harmonic: np.ndarray
    residual_rms: np.ndarray
    rotation: str = "cw"
    checks: SeparationChecks | None = None


def _significant(values, digits: int) -> np.ndarray:
    """``values`` rounded to ``digits`` significant digits (correctly rounded decimal; inf
    stays inf)."""
    return np.array([float(f"{v:.{digits}g}") for v in np.asarray(values, dtype=float).ravel()]
                    ).reshape(np.shape(values))


def _cancelled_message(angles_deg, cancelled, n, max_harmonic) -> str:
    shown = ", ".join(f"{a:g}" for a in angles_deg)
    return (f"the probes at {shown} deg cannot separate harmonic(s) "
            f"{_harmonic_list(cancelled)} of the profile, within 2..{max_harmonic} (N = {n} "
            f"samples per revolution): at those harmonics the profile reads on the probes "
            f"exactly as a motion would, so no estimator recovers them")


_CANCELLED_HINT = ("; move a probe by a few degrees so that the angles between probes are not "
                   "simple fractions of 360 deg (the shipped example's 0, 38.5, 97, 221 deg "
                   "cancel no harmonic below 719), add a probe, lower max_harmonic below the "
                   "first of them, or allow_cancelled=True to separate without them")


def separate_probes(signals, phi, *, method: str = "least_squares", weights=None,
                    max_harmonic: int | None = None, rcond: float = RCOND,
                    allow_cancelled: bool = False, rotation: str = "cw",
                    theta0: float = 0.0) -> ProbeSeparation:
    """Separate profile and radial error motion from L >= 3 probes at any angles, R revolutions.

    Steps (module docstring): remove each probe's mean (its unknown zero); average the
    revolutions (the profile is the same every revolution; the asynchronous motion does not
    reach the profile, as every estimator cancels or fits the motion); estimate every
    harmonic ``k = 2..max_harmonic`` of the profile from the FFT of the averaged signals, by
    least squares over the probes (``R_k`` from ``Y_l(k) = R_k exp(i k phi_l) + X_k cos(phi_l)
    + Y_k sin(phi_l)``, the estimator of
    :func:`~mtaccuracy.spindle.least_squares.separate_least_squares`) or by the weighted method
    (``R_k = sum a_l Y_l(k) / Lambda_k``, Yang et al. 2021, Eqs. 5-6, 14, the FFT form of
    :func:`~mtaccuracy.spindle.separation.separate_details`); shift the profile to each probe
    (``R_k exp(i k phi_l)``) and fit ``x, y`` at every sample of every revolution to the rest by
    least squares over the probes (Eq. 7); give the profile's first harmonic the mean
    once-per-revolution motion that turns with the artefact (the eccentricity convention).

    **The sense of rotation.**  ``rotation="cw"`` is the model above (Eq. 7: the probe at
    ``phi`` reads ``r(theta + phi)``).  ``rotation="ccw"``: the spindle turns in the sense the
    probe angles count, the probe reads ``r(phi - theta) + x cos(phi) + y sin(phi)``.  With
    ``phi' = -phi`` and ``r'(u) = r(-u)`` that is ``r'(theta + phi') + x cos(phi') + (-y)
    sin(phi')``: Eq. 7 again, so the separation runs on the negated angles and gives ``r'`` and
    ``(x, -y)``; ``y`` is negated back, and the profile is turned back to ``r`` at the sample
    angles, ``r(theta_0 + u_n) = r'(-theta_0 - u_n)``, by its Fourier series (exact: the
    profile has no harmonic above ``max_harmonic < N / 2``).  In both senses the profile is the
    artefact's radius at the angle it has in the probes' frame at ``theta = 0``, and ``(x, y)``
    is in the probes' frame.

    **Checks** (:mod:`~mtaccuracy.spindle.checks`, statistics in ``checks``): a
    :class:`~mtaccuracy.spindle.checks.RotationSenseWarning` when the data look like the other
    sense (a large once-per-revolution motion turning against the spindle: the artefact's
    centring read under the wrong sense), an
    :class:`~mtaccuracy.spindle.checks.AliasingWarning` when the readings carry more than N
    samples a revolution resolve (a synchronous misfit, or a spectrum not decayed at the top
    harmonics).

    Parameters
    ----------
    signals : array (..., R, L, N)
        Probe readings (any one length unit), R revolutions of N samples at the spindle angles
        ``theta_0 + 2 pi n / N``, batched over leading axes.
    phi : array (L,)
        Probe mounting angles (rad), any values, distinct modulo 2 pi.
    method : {"least_squares", "weighted"}
        The estimator of the profile.
    weights : array (L,), optional
        Weights of the weighted method (they must cancel the motion); default
        :func:`layout_weights` over the harmonics separated.
    max_harmonic : int, optional
        The highest harmonic separated, 2..(N - 1) // 2 (default: all,
        :func:`resolvable_harmonic`); the signals' content above it goes to the motion.
    rcond : float
        Relative singular-value threshold of a cancelled harmonic (:func:`layout_cancelled`).
    allow_cancelled : bool
        A layout that cancels harmonics within 2..max_harmonic is refused (``ValueError``
        naming them) unless this is True; then they are set aside (zero in the profile) with a
        :class:`~mtaccuracy.spindle.separation.CancelledHarmonicsWarning`.
    rotation : {"cw", "ccw"}
        The sense the spindle turns in (above): ``"cw"``, the probe at ``phi`` reads
        ``r(theta + phi)`` (Yang et al. 2021, Eq. 7; the default); ``"ccw"``, ``r(phi - theta)``.
    theta0 : float
        The spindle angle of the first sample (rad); it matters only to turn a ``"ccw"``
        profile back to the sample angles.

    Returns
    -------
    ProbeSeparation
        ``profile`` (..., N) at the sample angles ``theta0 + 2 pi n / N`` (the artefact's
        angles in the probes' frame at ``theta = 0``), ``dx, dy`` (..., R, N) in the probes'
        frame, the estimator's weights, amplification and set-aside harmonics, and the checks'
        statistics.

    Warns
    -----
    RotationSenseWarning
        The data look like the other ``rotation``.
    AliasingWarning
        The readings carry more than N samples a revolution resolve.
    """
    if method not in ("least_squares", "weighted"):
        raise ValueError(f"method must be 'least_squares' or 'weighted', got {method!r}")
    if not (np.isfinite(rcond) and 0 < rcond < 1):
        raise ValueError(f"rcond must be in (0, 1), got {rcond!r}")
    if rotation not in ROTATIONS:
        raise ValueError(f"rotation must be 'cw' (the probe at phi reads r(theta + phi), Eq. 7) "
                         f"or 'ccw' (it reads r(phi - theta)), got {rotation!r}")
    theta0 = float(theta0)
    if not np.isfinite(theta0):
        raise ValueError(f"theta0 must be a finite angle (rad), got {theta0!r}")
    y = np.asarray(signals, dtype=float)
    phi = _check_phi(phi)
    shown_deg = np.rad2deg(phi)
    if rotation == "ccw":
        phi = -phi                                  # Eq. 7 in the mirrored frame (docstring)
    if y.ndim < 3 or y.shape[-2] != phi.shape[0]:
        raise ValueError(f"signals must have shape (..., R, L, N) with L = {phi.shape[0]} "
                         f"probes (one per angle), got {y.shape}")
    n = y.shape[-1]
    k_top = _check_band(max_harmonic, n)
    if not np.all(np.isfinite(y)):
        raise ValueError("signals contain NaN or inf")
    harmonics = np.arange(2, k_top + 1)
    cancelled = layout_cancelled(phi, k_top, rcond=rcond)
    kept = np.setdiff1d(harmonics, cancelled)
    msg = _cancelled_message(shown_deg, cancelled, n, k_top) if cancelled else ""
    if not kept.size:
        raise ValueError(msg + "; that is every harmonic: nothing to separate" + _CANCELLED_HINT)
    w = None
    if method == "weighted":
        w = layout_weights(phi, kept) if weights is None else np.asarray(weights, dtype=float)
        if w.shape != phi.shape or not np.all(np.isfinite(w)) \
                or abs(w @ np.exp(1j * phi)) > 1e-8 * np.abs(w).sum():
            raise ValueError("the weights must be one per probe and cancel the motion: "
                             "sum a_l cos(phi_l) = sum a_l sin(phi_l) = 0 (Eq. 5)")
        lam_k = np.exp(1j * kept[:, None] * phi[None, :]) @ w
        by_weights = kept[np.abs(lam_k) <= rcond * np.abs(w).sum()]
        if by_weights.size:                 # weights given that cancel what the layout sees
            msg = ((msg + "; ") if msg else "") + (
                f"the weights {np.round(w, 4).tolist()} cancel harmonic(s) "
                f"{_harmonic_list(by_weights)} (Lambda_k = 0) that other weights would see")
            cancelled = sorted([*cancelled, *by_weights.tolist()])
            kept = np.setdiff1d(kept, by_weights)
    if msg:
        if not allow_cancelled:
            raise ValueError(msg + _CANCELLED_HINT)
        warnings.warn(msg + " (allow_cancelled=True: proceeding without them)",
                      CancelledHarmonicsWarning, stacklevel=2)

    y = y - y.mean(axis=(-3, -1), keepdims=True)                       # the probes' zeros
    spec = np.fft.fft(y.mean(axis=-3), axis=-1)                         # (..., L, N)
    ks = np.rint(np.fft.fftfreq(n, 1.0 / n)).astype(int)                # signed orders
    solve = np.isin(np.abs(ks), kept)
    shift = np.exp(1j * ks[:, None] * phi[None, :])                     # (N, L)
    if method == "least_squares":
        rows = np.zeros((n, phi.shape[0]), dtype=complex)
        rows[solve] = np.linalg.pinv(_ls_design(phi, ks[solve]))[:, 0, :]
        r_k = np.einsum("kl,...lk->...k", rows, spec)
        amp = noise_amplification(phi, harmonics)
    else:
        lam = shift @ w
        r_k = np.zeros(spec.shape[:-2] + (n,), dtype=complex)
        r_k[..., solve] = np.einsum("l,...lk->...k", w, spec[..., solve]) / lam[solve]
        amp = noise_amplification(phi, harmonics, weights=w)
    amp = _significant(np.where(np.isin(harmonics, cancelled), np.inf, amp),
                       AMPLIFICATION_DIGITS)
    r0 = np.fft.ifft(r_k, axis=-1).real                                 # (..., N)
    at_probe = np.fft.ifft(r_k[..., None, :] * shift.T, axis=-1).real    # (..., L, N)

    resid = y - at_probe[..., None, :, :]                               # (..., R, L, N)
    g = np.column_stack([np.cos(phi), np.sin(phi)])                     # (L, 2)
    dxy = np.einsum("jl,...ln->...jn", np.linalg.pinv(g), resid)        # (..., R, 2, N)
    misfit = resid - np.einsum("lj,...jn->...ln", g, dxy)
    residual_rms = np.sqrt((misfit ** 2).mean(axis=(-2, -1)))
    z = dxy[..., 0, :] + 1j * dxy[..., 1, :]                            # (..., R, N)
    grid = TWO_PI * np.arange(n) / n
    found = _run_checks(y, spec, misfit, z, phi, ks, kept, grid, rotation)
    c = (z * np.exp(1j * grid)).mean(axis=(-2, -1))                     # coefficient of e^-it
    z = z - c[..., None, None] * np.exp(-1j * grid)
    profile = r0 + c.real[..., None] * np.cos(grid) + c.imag[..., None] * np.sin(grid)
    first = np.stack([c.real, c.imag], -1)
    if rotation == "ccw":
        z = z.conj()                                                    # y' = -y
        spec_p = np.fft.fft(profile, axis=-1)                           # of r'(theta0 + u_n)
        mirrored = spec_p[..., -np.arange(n) % n] * np.exp(2j * ks * theta0)
        profile = np.fft.ifft(mirrored, axis=-1).real                   # r(theta0 + u_n)
        first = np.stack([2 * (profile * np.cos(grid)).mean(axis=-1),
                          2 * (profile * np.sin(grid)).mean(axis=-1)], -1)
    return ProbeSeparation(profile=profile, dx=z.real, dy=z.imag, method=method, weights=w,
                           harmonics=harmonics, amplification=amp, cancelled=list(cancelled),
                           max_harmonic=k_top, first_harmonic=first,
                           residual_rms=residual_rms, rotation=rotation, checks=found)


def _run_checks(y, spec, misfit, z, phi, ks, kept, grid, rotation) -> SeparationChecks:
    """The sense and aliasing checks of :mod:`~mtaccuracy.spindle.checks` on one separation,
    in the separation's frame (``phi`` negated for ``ccw``), warning when they fire."""
    n_probes, n = phi.shape[0], y.shape[-1]
    g = np.column_stack([np.cos(phi), np.sin(phi)])
    gram_trace = float(np.trace(np.linalg.inv(g.T @ g)))
    noise_var = np.mean(misfit ** 2, axis=(-3, -2, -1)) * n_probes / (n_probes - 2)
    co, counter, se, wrong = _checks._sense_statistics(z, grid, noise_var, gram_trace)
    # the least-squares misfit of the revolutions' average, whatever the estimator
    solve = np.isin(np.abs(ks), kept)
    resid = np.array(spec)
    design = _ls_design(phi, ks[solve])                                 # (K, L, 3)
    proj = np.einsum("klj,kjm->klm", design, np.linalg.pinv(design))     # (K, L, L)
    resid[..., solve] -= np.einsum("klm,...mk->...lk", proj, spec[..., solve])
    pg = g @ np.linalg.pinv(g)
    resid[..., ~solve] -= np.einsum("lm,...mk->...lk", pg, spec[..., ~solve])
    resid[..., ks == 0] = 0.0
    ss_mean = (np.abs(resid) ** 2).sum(axis=(-2, -1)) / n
    dof_mean = int(solve.sum()) * (n_probes - 3) + int((~solve).sum() - 1) * (n_probes - 2)
    sd, mratio, sratio, band, aliased = _checks._aliasing_statistics(
        y, spec, misfit, ss_mean, dof_mean)
    # a wrong sense leaves a synchronous misfit of its own (warned as such): not aliasing
    aliased = aliased & np.stack([~wrong, np.ones_like(wrong), np.ones_like(wrong)], axis=-1)
    found = SeparationChecks(co_rotating=co, counter_rotating=counter,
                             counter_standard_error=se, wrong_sense=wrong, noise_sd=sd,
                             misfit_ratio=mratio, spectrum_ratio=sratio, top_harmonics=band,
                             aliased=aliased)
    if np.any(wrong):
        warnings.warn(_checks._rotation_message(found, rotation), RotationSenseWarning,
                      stacklevel=3)
    if np.any(aliased):                                                 # (..., 3) criteria
        warnings.warn(_checks._aliasing_message(found, n), AliasingWarning, stacklevel=3)
    return found


def separate_probe_data(data, *, method: str = "least_squares",
                        rotation: str = "cw") -> ProbeSeparation:
    """:func:`separate_probes` on a checked probe file, with its ``max_harmonic``.

    The harmonics its reader set aside stay aside (the reader already refused or warned about
    them).

    Parameters
    ----------
    data : ProbeData
        From :func:`~mtaccuracy.spindle.probefile.read_probe_file`.
    method : {"least_squares", "weighted"}
        The estimator of the profile.
    rotation : {"cw", "ccw"}
        The sense the spindle turns in (:func:`separate_probes`); the first sample's angle is
        the file's.

    Returns
    -------
    ProbeSeparation
        In um.

    Warns
    -----
    RotationSenseWarning, AliasingWarning
        As :func:`separate_probes`.
    """
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        s = separate_probes(data.signals_um, data.phi, method=method,
                            max_harmonic=data.max_harmonic,
                            allow_cancelled=bool(data.cancelled), rotation=rotation,
                            theta0=float(np.deg2rad(data.sample_deg[0])))
    for w in caught:
        if not issubclass(w.category, CancelledHarmonicsWarning):
            warnings.warn(f"{data.path}: {w.message}", w.category, stacklevel=2)
    return s


def probe_noise_estimate(separation: ProbeSeparation, n_probes: int) -> float:
    """The probes' noise standard deviation implied by the misfit of a separation.

    Once the profile and the motion are fitted, L probes leave ``L - 2`` degrees of freedom at
    every sample: white noise of standard deviation ``sigma`` leaves a mean square misfit of
    ``sigma^2 (L - 2) / L`` (less the small part the profile absorbs, of relative order
    ``1 / R``), so ``sigma ~ rms_misfit sqrt(L / (L - 2))``.  Anything the model does not hold
    (a probe's angle error, profile harmonics above ``max_harmonic``, a probe's nonlinearity)
    adds to the misfit: the estimate is an upper bound of the noise in that sense.

    Parameters
    ----------
    separation : ProbeSeparation
        From :func:`separate_probes` (one measurement: ``residual_rms`` of shape (R,)).
    n_probes : int
        The number of probes L (>= 3).

    Returns
    -------
    float
        In the unit of the signals.
    """
    n_probes = validate.integer(n_probes, "n_probes", low=MIN_PROBES)
    ms = float(np.mean(np.asarray(separation.residual_rms) ** 2))
    return float(np.sqrt(ms * n_probes / (n_probes - 2)))
