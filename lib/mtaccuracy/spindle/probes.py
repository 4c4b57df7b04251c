"""A reader's own multi-probe roundness / spindle measurement, separated at any probe angles.

The probe file, its checks, and the separation of the artefact's profile from the spindle's
radial error motion at any probe angles.

**The file** (``data/spindle/README.md``): a CSV with the columns ``revolution``, ``angle_deg``
(the spindle's angle of each sample, equally spaced over a revolution, the same samples every
revolution) and one column per probe named ``probe_<mounting angle in degrees>_um``
(``probe_0_um``, ``probe_38.5_um``): three probes or more, at any angles, readings in
micrometres.  :func:`read_probe_file` reads it and refuses, before any work and with a message
naming the file and the line, everything that breaks the schema (:class:`ProbeFileError`).

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
:func:`~mtaccuracy.spindle.separation.separate_least_squares`) shift the profile by whole samples
and so need probes on the sampling grid.  In the Fourier domain no grid is needed: harmonic
``k`` of ``r(theta + phi)`` is ``R_k exp(i k phi)`` for any ``phi``, so :func:`separate_probes`
solves harmonic by harmonic, either with the paper's weighted multi-point method (a weighted sum
``sum a_l y_l`` with ``sum a_l exp(i phi_l) = 0`` cancels the motion, ``R_k = Y_k / Lambda_k``,
Eqs. 5, 14; weights for the given angles from :func:`layout_weights`) or by least squares over
all probes.  Both reduce to the library's functions on grid layouts (a test checks it to
round-off).  The harmonics it recovers are ``2..max_harmonic`` with ``max_harmonic <= (N - 1) //
2`` (:func:`resolvable_harmonic`; the Nyquist harmonic ``N / 2`` is only a cosine on the grid and
cannot be shifted by a fraction of a sample).  The mean of each probe is its unknown zero and is
removed, so the profile and the motion have zero mean; the first harmonic of the profile cannot
be told from a once-per-revolution motion turning with the artefact (its centring error) and is
given all of it (the ``"eccentricity"`` convention of :mod:`~mtaccuracy.spindle.separation`).

Why hand-written: the schema and its checks are ours; the separation at off-grid angles is the
paper's method (and the least-squares estimator beside it) written in the Fourier domain, built
from numpy's FFT and pseudo-inverse and scipy's ``null_space``, ``minimize`` and
``minimize_scalar``; no maintained package separates multi-probe spindle data.
"""

from __future__ import annotations

import hashlib
import io
import json
import re
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
import scipy.linalg
import scipy.optimize
import scipy.special
import scipy.stats

from .. import csvlines, validate
from ..roundness import lsc_roundness
from .separation import (
    _MIN_SAMPLES,
    TWO_PI,
    CancelledHarmonicsWarning,
    _harmonic_list,
    _ls_design,
)

__all__ = [
    "ProbeFileError", "ProbeData", "ProbeSeparation", "read_probe_file", "write_probe_file",
    "probe_column", "resolvable_harmonic", "layout_cancelled", "layout_weights",
    "noise_amplification", "profile_noise_rms", "separate_probes", "separate_probe_data",
    "probe_noise_estimate", "about_lsc", "fixed_directions",
    "example_measurement", "write_example", "match_example", "EXAMPLE_SETUP",
    "MIN_PROBES", "MAX_PROBES", "MIN_SAMPLES", "MAX_SAMPLES", "MAX_ROWS", "MAX_FILE_BYTES",
    "MAX_ABS_UM", "MIN_SPAN_UM", "ANGLE_TOLERANCE", "RCOND", "EXAMPLE_FILES",
]

# --------------------------------------------------------------------------------------------
# The schema's limits
# --------------------------------------------------------------------------------------------

#: Probes: three is the least that separates a profile from a two-dimensional motion; 16 is more
#: than any multi-probe set-up uses (they use 3 to 5) and bounds the weight search (L - 3 free
#: weights).
MIN_PROBES = 3
MAX_PROBES = 16
#: Samples per revolution: 8 (the library's least) to 16384 (harmonics up to 8191; a roundness
#: instrument takes 3600 points a turn at most, a spindle analyser 4096).
MIN_SAMPLES = _MIN_SAMPLES
MAX_SAMPLES = 16384
#: Data rows (revolutions x samples): 500 000 rows (e.g. 122 revolutions of 4096 samples) keep a
#: run of notebook 07 within 0.6 GB of memory and about 20 s (measured with 16 probes); a larger
#: file is refused as soon as the parser reaches row 500 001, and one of more than
#: :data:`MAX_FILE_BYTES` bytes before it is read (500 000 rows of 16 probes at 12 characters a
#: value take about 100 MB).
MAX_ROWS = 500_000
MAX_FILE_BYTES = 120_000_000
#: Plausible readings (um).  A displacement probe used for spindle tests (capacitive, inductive,
#: LVDT) has a range within +-2 mm; a reading beyond +-10 mm is not one (in nm, most likely).
#: Every probe's readings over the file span at least 0.01 um (10 nm): its noise over thousands
#: of samples, the artefact's form and any spindle's error motion (an air-bearing spindle's,
#: about 10-50 nm, included) exceed that; a file in mm spans 1000 times less than in um, so a
#: file of a spindle whose runout is below 10 um, written in mm, is refused.
MAX_ABS_UM = 10_000.0
MIN_SPAN_UM = 0.01
#: ``angle_deg`` may deviate from the equally spaced grid of its revolution by this fraction of
#: the step ``360 / N`` (angles written with few decimals); a missing, repeated or shifted sample
#: deviates by a whole step.
ANGLE_TOLERANCE = 0.05
#: A harmonic is cancelled by a layout when the smallest singular value of the least-squares
#: design of that harmonic (the profile harmonic and the two motion components read by every
#: probe) is below this fraction of the largest, the threshold of
#: :func:`~mtaccuracy.spindle.separation.separate_least_squares`.
RCOND = 1e-9

#: The shipped simulated example (:func:`write_example`) and its record.
EXAMPLE_FILES = {"probes": "example_probes.csv", "truth": "example_truth.csv",
                 "record": "provenance.json"}

_REQUIRED = ("revolution", "angle_deg")
#: The header and the blank lines before it lie within this many characters of the start.
_HEAD_CHARS = 1_000_000
_PROBE = re.compile(r"^probe_(?P<angle>[+-]?(?:\d+(?:\.\d*)?|\.\d+))_(?P<unit>[^_]+)$")
_DECIMAL_COMMA = re.compile(r"^\s*[+-]?\d+,\d+\s*$")
_COMMA_HINT = ("; decimal commas (1,5)? In a comma-separated file write decimal points (1.5), or "
               "save the file semicolon-separated")


class ProbeFileError(ValueError):
    """A probe file breaks the schema; the message names the file, the line and the problem.

    Parameters
    ----------
    path : str
        The probe file at fault.
    line : int or None
        The physical line at fault (1-based, as an editor shows it), None for the whole file.
    problem : str
        What is wrong and what to do.
    """

    def __init__(self, path, line, problem: str):
        where = f"{path}" if line is None else f"{path}, line {line}"
        super().__init__(f"{where}: {problem}")
        self.path, self.line, self.problem = str(path), line, problem


@dataclass(frozen=True)
class ProbeData:
    """A checked probe file.

    Attributes
    ----------
    path : str
        The file read.
    columns : tuple of str
        The probe columns, in file order.
    angles_deg : array (L,)
        The probes' mounting angles (deg), as the column names give them.
    sample_deg : array (N,)
        The spindle angle of each sample of a revolution (deg, the file's ``angle_deg`` of the
        first revolution; every revolution has the same).
    revolutions : array of int (R,)
        The revolution numbers, in file order.
    signals_um : array (R, L, N)
        Probe readings (um).
    max_harmonic : int
        The highest profile harmonic to separate (:func:`resolvable_harmonic` unless lowered).
    cancelled : tuple of int
        Harmonics in ``2..max_harmonic`` the layout cannot separate (empty unless the reader was
        told ``allow_cancelled=True``).
    ignored_columns : tuple of str
        Other columns of the file, not used.
    header_line : int
        The line of the header.
    """

    path: str
    columns: tuple
    angles_deg: np.ndarray
    sample_deg: np.ndarray
    revolutions: np.ndarray
    signals_um: np.ndarray
    max_harmonic: int
    cancelled: tuple = ()
    ignored_columns: tuple = ()
    header_line: int = 1

    @property
    def phi(self) -> np.ndarray:
        """array (L,): the probes' mounting angles (rad)."""
        return np.deg2rad(self.angles_deg)

    @property
    def theta(self) -> np.ndarray:
        """array (N,): the spindle angle of each sample (rad)."""
        return np.deg2rad(self.sample_deg)

    @property
    def n_probes(self) -> int:
        """int: L."""
        return self.signals_um.shape[1]

    @property
    def n_revolutions(self) -> int:
        """int: R."""
        return self.signals_um.shape[0]

    @property
    def n_samples(self) -> int:
        """int: N, samples per revolution."""
        return self.signals_um.shape[2]


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
        Noise amplification ``q_k`` of the estimator per harmonic (inf where set aside).
    cancelled : list of int
        Harmonics set aside (the layout cannot separate them).
    max_harmonic : int
        The highest harmonic separated.
    first_harmonic : array (..., 2)
        ``C, D`` of the profile's first harmonic ``C cos + D sin`` (grid angles
        ``2 pi n / N``).
    residual_rms : array (..., R)
        RMS misfit of the probes, per revolution, once the profile and the motion are fitted.
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
                    allow_cancelled: bool = False) -> ProbeSeparation:
    """Separate profile and radial error motion from L >= 3 probes at any angles, R revolutions.

    Steps (module docstring): remove each probe's mean (its unknown zero); average the
    revolutions (the profile is the same every revolution; the asynchronous motion does not
    reach the profile, as every estimator cancels or fits the motion); estimate every
    harmonic ``k = 2..max_harmonic`` of the profile from the FFT of the averaged signals, by
    least squares over the probes (``R_k`` from ``Y_l(k) = R_k exp(i k phi_l) + X_k cos(phi_l)
    + Y_k sin(phi_l)``, the estimator of
    :func:`~mtaccuracy.spindle.separation.separate_least_squares`) or by the weighted method
    (``R_k = sum a_l Y_l(k) / Lambda_k``, Yang et al. 2021, Eqs. 5-6, 14, the FFT form of
    :func:`~mtaccuracy.spindle.separation.separate_details`); shift the profile to each probe
    (``R_k exp(i k phi_l)``) and fit ``x, y`` at every sample of every revolution to the rest by
    least squares over the probes (Eq. 7); give the profile's first harmonic the mean
    once-per-revolution motion that turns with the artefact (the eccentricity convention).

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

    Returns
    -------
    ProbeSeparation
        ``profile`` (..., N) at the sample angles, ``dx, dy`` (..., R, N), and the estimator's
        weights, amplification and set-aside harmonics.
    """
    if method not in ("least_squares", "weighted"):
        raise ValueError(f"method must be 'least_squares' or 'weighted', got {method!r}")
    if not (np.isfinite(rcond) and 0 < rcond < 1):
        raise ValueError(f"rcond must be in (0, 1), got {rcond!r}")
    y = np.asarray(signals, dtype=float)
    phi = _check_phi(phi)
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
    msg = _cancelled_message(np.rad2deg(phi), cancelled, n, k_top) if cancelled else ""
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
    amp = np.where(np.isin(harmonics, cancelled), np.inf, amp)
    r0 = np.fft.ifft(r_k, axis=-1).real                                 # (..., N)
    at_probe = np.fft.ifft(r_k[..., None, :] * shift.T, axis=-1).real    # (..., L, N)

    resid = y - at_probe[..., None, :, :]                               # (..., R, L, N)
    g = np.column_stack([np.cos(phi), np.sin(phi)])                     # (L, 2)
    dxy = np.einsum("jl,...ln->...jn", np.linalg.pinv(g), resid)        # (..., R, 2, N)
    misfit = resid - np.einsum("lj,...jn->...ln", g, dxy)
    residual_rms = np.sqrt((misfit ** 2).mean(axis=(-2, -1)))
    z = dxy[..., 0, :] + 1j * dxy[..., 1, :]                            # (..., R, N)
    grid = TWO_PI * np.arange(n) / n
    c = (z * np.exp(1j * grid)).mean(axis=(-2, -1))                     # coefficient of e^-it
    z = z - c[..., None, None] * np.exp(-1j * grid)
    profile = r0 + c.real[..., None] * np.cos(grid) + c.imag[..., None] * np.sin(grid)
    return ProbeSeparation(profile=profile, dx=z.real, dy=z.imag, method=method, weights=w,
                           harmonics=harmonics, amplification=amp, cancelled=list(cancelled),
                           max_harmonic=k_top, first_harmonic=np.stack([c.real, c.imag], -1),
                           residual_rms=residual_rms)


def separate_probe_data(data: ProbeData, *, method: str = "least_squares") -> ProbeSeparation:
    """:func:`separate_probes` on a checked probe file, with its ``max_harmonic``.

    The harmonics its reader set aside stay aside (the reader already refused or warned about
    them).

    Parameters
    ----------
    data : ProbeData
        From :func:`read_probe_file`.
    method : {"least_squares", "weighted"}
        The estimator of the profile.

    Returns
    -------
    ProbeSeparation
        In um.
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", CancelledHarmonicsWarning)
        return separate_probes(data.signals_um, data.phi, method=method,
                               max_harmonic=data.max_harmonic,
                               allow_cancelled=bool(data.cancelled))


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


def about_lsc(profile) -> np.ndarray:
    """A profile's deviations from its least-squares circle (ISO 12181-1's LSC reference).

    In the limacon model of :func:`~mtaccuracy.roundness.lsc_roundness`: the profile without its
    mean and first harmonic, i.e. without the centring.

    Parameters
    ----------
    profile : array (..., N)
        Radial deviations sampled uniformly over a turn (any length unit).

    Returns
    -------
    array (..., N)
        In the unit of ``profile``; its peak-to-valley is the LSC roundness.
    """
    p = np.asarray(profile, dtype=float)
    _, coef = lsc_roundness(p)
    t = TWO_PI * np.arange(p.shape[-1]) / p.shape[-1]
    return p - coef[..., :1] - coef[..., 1:2] * np.cos(t) - coef[..., 2:] * np.sin(t)


def fixed_directions(data: ProbeData, report_probes) -> np.ndarray:
    """Fixed sensitive directions along the named probes' axes (all probes when none is named).

    The probes are named by their mounting angles (deg); an angle that is no probe's is refused.

    Parameters
    ----------
    data : ProbeData
        The probe file.
    report_probes : sequence of float
        Mounting angles (deg) of probes of the file (modulo 360); empty: every probe.

    Returns
    -------
    array (D,)
        The directions (rad), in the order given (file order when empty).
    """
    wanted = [float(a) for a in report_probes] or list(data.angles_deg)
    out = []
    for a in wanted:
        hit = np.flatnonzero(np.abs(np.angle(np.exp(1j * np.deg2rad(a - data.angles_deg))))
                             < 1e-9)
        if not hit.size:
            raise ValueError(f"no probe of {data.path} is mounted at {a:g} deg; its probes are "
                             f"at {', '.join(f'{v:g}' for v in data.angles_deg)} deg")
        out.append(data.phi[hit[0]])
    return np.array(out)


# --------------------------------------------------------------------------------------------
# The reader
# --------------------------------------------------------------------------------------------


def probe_column(angle_deg: float) -> str:
    """The column name ``probe_<angle>_um`` of a probe at ``angle_deg``, in plain decimals.

    Parameters
    ----------
    angle_deg : float
        Mounting angle (deg).

    Returns
    -------
    str
        E.g. ``probe_38.5_um``.
    """
    return f"probe_{np.format_float_positional(float(angle_deg), trim='-')}_um"


def _text(path: Path) -> str:
    """The file's text (UTF-8, a byte-order mark allowed; checked when it was first read)."""
    return path.read_bytes().decode("utf-8-sig")


def _records(text: str, sep: str):
    """The records of a file's text with their lines (:func:`mtaccuracy.csvlines.records`),
    the header first, the fields as the file has them (swapped back in a semicolon file), rows
    whose every field is empty left out (pandas' rows and these stay in step)."""
    for rec in csvlines.records(text, sep=sep):
        if any(f.strip() for f in rec.fields):
            yield rec


class _Lines:
    """The physical lines of data rows, found (the file read again, one pass of
    :func:`csvlines.records`) only when a message needs them."""

    def __init__(self, path: Path, sep: str):
        self.path, self.sep, self._cache = path, sep, None

    def _all(self):
        if self._cache is None:
            first = []
            recs = _records(_text(self.path), self.sep)
            try:
                next(recs, None)
                first = [r.first for r in recs]
            except csvlines.CSVLineError:
                pass
            self._cache = first
        return self._cache

    def __call__(self, row: int) -> int:
        lines = self._all()
        return lines[row] if 0 <= row < len(lines) else -1

    def some(self, rows, limit: int = 10) -> str:
        rows = list(rows)
        shown = ", ".join(str(self(r)) for r in rows[:limit])
        return shown + (f", ... ({len(rows)} lines)" if len(rows) > limit else "")


def _name(column: str, sep: str) -> str:
    """A column's name as the reader uses it: stripped, and in a semicolon file a probe's
    angle written with a decimal comma (``probe_38,5_um``) written with a point."""
    column = column.strip()
    return column.replace(",", ".") if sep == ";" and column.lower().startswith("probe") \
        else column


def _header(path, text):
    """The header record: (line, names, separator); refuses an empty file, a tab-separated one
    and repeated names.  ``text``: the start of the file (the header and any blank lines before
    it lie within :data:`_HEAD_CHARS` characters).  The first non-blank line tells the
    separator: ``;`` when it holds one (a spreadsheet's CSV in a locale with decimal commas),
    else ``,``."""
    first = next((ln for ln in text.splitlines() if ln.strip()), "")
    sep = ";" if ";" in first else ","
    if sep == "," and "\t" in first and "," not in first:
        number = text.splitlines().index(first) + 1
        raise ProbeFileError(path, number, (
            "the header is tab-separated; the schema is comma-separated with decimal points (or "
            "semicolon-separated, as a spreadsheet in a locale with decimal commas writes it): "
            "export the file as CSV"))
    recs = _records(text, sep)
    try:
        head = next(recs, None)
    except csvlines.CSVLineError as exc:
        raise ProbeFileError(path, exc.line, exc.reason) from None
    if head is None:
        raise ProbeFileError(path, None, "the file is empty; it needs the header revolution,"
                                         "angle_deg,probe_<angle>_um,... and data rows")
    names = [_name(f, sep) for f in head.fields]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise ProbeFileError(path, head.first, f"column(s) {twice} appear more than once")
    return head.first, names, sep


def _probe_columns(path, line, names):
    """The probe columns and their angles (deg) from the header, checked."""
    for want, alts in (("revolution", ("rev", "revolutions", "turn")),
                       ("angle_deg", ("angle", "angle_rad", "theta", "theta_deg"))):
        if want not in names:
            like = [n for n in names if n.lower() in alts or n.lower() == want]
            hint = (f" ({like[0]!r} found: rename it {want!r}"
                    + ("; angles in degrees" if want == "angle_deg" else "") + ")") if like else ""
            raise ProbeFileError(path, line, f"missing column {want!r}{hint}; the header needs "
                                             f"revolution, angle_deg and probe_<angle>_um columns")
    probes, angles, ignored = [], [], []
    for n in names:
        if n in _REQUIRED:
            continue
        if not n.lower().startswith("probe"):
            ignored.append(n)
            continue
        m = _PROBE.match(n)
        if m is None:
            raise ProbeFileError(path, line, (
                f"column {n!r} is not named probe_<mounting angle in degrees>_um (e.g. "
                f"probe_0_um, probe_38.5_um): write the angle as a plain number and the unit "
                f"um"))
        unit = m.group("unit")
        if unit != "um":
            what = {"mm": "in mm: multiply the values by 1000", "m": "in m: multiply by 1e6",
                    "nm": "in nm: divide the values by 1000",
                    "µm": "named with 'µm': write 'um'", "μm": "named with 'μm': write 'um'",
                    "deg": "named with the angle's unit: the unit is that of the readings"}
            raise ProbeFileError(path, line, (
                f"column {n!r}: probe readings must be in um, named probe_<angle>_um; this "
                f"column is {what.get(unit, f'in {unit!r}: convert to um')} and rename it "
                f"{probe_column(float(m.group('angle')))!r}"))
        probes.append(n)
        angles.append(float(m.group("angle")))
    if len(probes) < MIN_PROBES:
        raise ProbeFileError(path, line, (
            f"{len(probes)} probe column(s) {probes}; at least {MIN_PROBES} are needed to "
            f"separate the profile from a two-dimensional error motion (columns "
            f"probe_<mounting angle in degrees>_um)"))
    if len(probes) > MAX_PROBES:
        raise ProbeFileError(path, line, f"{len(probes)} probe columns; at most {MAX_PROBES} "
                                         f"are supported (multi-probe set-ups use 3 to 5)")
    ang = np.array(angles)
    if np.any(np.abs(ang) > 360):
        bad = probes[int(np.argmax(np.abs(ang) > 360))]
        raise ProbeFileError(path, line, f"column {bad!r}: a mounting angle must lie within "
                                         f"-360..360 deg")
    if np.all((ang >= 0) & (ang <= TWO_PI)):
        raise ProbeFileError(path, line, (
            f"the mounting angles {', '.join(f'{a:g}' for a in ang)} all lie within 0..2 pi: "
            f"radians? The column names give degrees (deg = rad x 180 / pi); probes a few "
            f"degrees apart cannot separate a profile"))
    wrapped = np.mod(ang, 360.0)
    for i in range(len(ang)):
        for j in range(i):
            if min(abs(wrapped[i] - wrapped[j]), 360 - abs(wrapped[i] - wrapped[j])) < 1e-9:
                raise ProbeFileError(path, line, (
                    f"columns {probes[j]!r} and {probes[i]!r} name the same mounting angle "
                    f"(modulo 360 deg); every probe needs its own angle"))
    return probes, ang, ignored


def _parse(path, raw, names, header_line, sep):
    """The data rows as a DataFrame (pandas' C parser; blank rows, and rows whose every field
    is empty, skipped), or a message naming the line of a row with more fields than the
    header."""
    def ragged():
        recs = _records(_text(path), sep)
        try:
            next(recs, None)
            for rec in recs:
                if len(rec.fields) > len(names):
                    comma = sep == "," and any(_DECIMAL_COMMA.match(f"{a},{b}") for a, b in
                                               zip(rec.fields, rec.fields[1:], strict=False))
                    return ProbeFileError(path, rec.first, (
                        f"{len(rec.fields)} fields, but the header names {len(names)} "
                        f"columns{_COMMA_HINT if comma else ''}"))
        except csvlines.UnclosedQuote as exc:
            return ProbeFileError(path, exc.line, "a quoted field opens here and is never "
                                                  "closed (a '\"' is missing)")
        except csvlines.CSVLineError as exc:
            return ProbeFileError(path, exc.line, exc.reason)
        return ProbeFileError(path, None, "not a readable CSV file")

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", pd.errors.ParserWarning)
        try:
            df = pd.read_csv(io.BytesIO(raw), encoding="utf-8-sig", sep=sep,
                             decimal="," if sep == ";" else ".", na_filter=False,
                             skipinitialspace=True, index_col=False, nrows=MAX_ROWS + 1)
        except pd.errors.ParserError:
            raise ragged() from None
        except pd.errors.EmptyDataError:
            raise ProbeFileError(path, None, "the file is empty") from None
    if any(issubclass(w.category, pd.errors.ParserWarning) for w in caught):
        raise ragged()
    df.columns = [_name(c, sep) for c in df.columns]
    text_cols = [c for c in df.columns if not pd.api.types.is_numeric_dtype(df[c])]
    if len(text_cols) == len(df.columns) and len(df):       # rows a spreadsheet left empty
        empty = np.logical_and.reduce([df[c].astype(str).str.strip().eq("").to_numpy()
                                       for c in df.columns])
        df = df[~empty].reset_index(drop=True)
    if df.empty:
        raise ProbeFileError(path, header_line, "the file has a header but no data rows")
    if len(df) > MAX_ROWS:
        raise ProbeFileError(path, _Lines(path, sep)(MAX_ROWS), (
            f"more than {MAX_ROWS} data rows; at most {MAX_ROWS} (revolutions x samples per "
            f"revolution) are read, to keep a run within about 0.6 GB of memory: keep fewer "
            f"revolutions"))
    return df


def _numbers(path, df, column, lines, sep) -> np.ndarray:
    """A column as finite floats: pandas parsed it as numbers, or it holds text (a semicolon
    file's decimal points or commas, both read; anything else refused at its first bad
    cell)."""
    col = df[column]
    if pd.api.types.is_numeric_dtype(col) and not pd.api.types.is_bool_dtype(col):
        values = col.to_numpy(dtype=float)
        text = pd.Series([repr(v) for v in values]) if not np.all(np.isfinite(values)) else None
    else:
        text = col.astype(str).str.strip()
        number = text.str.replace(",", ".", regex=False) if sep == ";" else text
        values = pd.to_numeric(number, errors="coerce").to_numpy(dtype=float)
    bad = ~np.isfinite(values)
    if bad.any():
        rows = np.flatnonzero(bad)
        shown = ", ".join(repr(t) for t in text.iloc[rows[:3]])
        comma = sep == "," and any(_DECIMAL_COMMA.match(t) for t in text.iloc[rows[:3]])
        hint = _COMMA_HINT if comma else "; every cell needs a finite number"
        raise ProbeFileError(path, lines(rows[0]), (
            f"column {column!r} has a missing, NaN, infinite or non-numeric value ({shown}); "
            f"line(s) {lines.some(rows)}{hint}"))
    return values


def _check_structure(path, rev, ang, lines):
    """Revolutions in order and of equal length, angles increasing and equally spaced, the same
    every revolution; returns (revolution numbers, N, the first revolution's angles)."""
    if np.any(rev != np.round(rev)):
        row = int(np.flatnonzero(rev != np.round(rev))[0])
        raise ProbeFileError(path, lines(row), f"revolution {rev[row]:g} is not a whole number")
    back = np.flatnonzero(np.diff(rev) < 0)
    if back.size:
        i = int(back[0])
        raise ProbeFileError(path, lines(i + 1), (
            f"revolution {rev[i + 1]:g} comes after revolution {rev[i]:g} (line {lines(i)}): "
            f"the rows of a revolution must stand together and the revolutions in the order "
            f"measured"))
    starts = np.r_[0, np.flatnonzero(np.diff(rev) > 0) + 1]
    sizes = np.diff(np.r_[starts, len(rev)])
    if np.any(sizes != sizes[0]):
        j = int(np.flatnonzero(sizes != sizes[0])[0])
        a, b = starts[j], starts[j] + sizes[j] - 1
        raise ProbeFileError(path, lines(a), (
            f"unequal samples per revolution: revolution {rev[a]:g} (lines {lines(a)}-"
            f"{lines(b)}) has {sizes[j]} samples, revolution {rev[0]:g} (lines {lines(0)}-"
            f"{lines(sizes[0] - 1)}) has {sizes[0]}; every revolution needs the same samples"))
    n, n_rev = int(sizes[0]), len(starts)
    if not MIN_SAMPLES <= n <= MAX_SAMPLES:
        raise ProbeFileError(path, lines(0), (
            f"{n} samples per revolution; {MIN_SAMPLES}..{MAX_SAMPLES} are supported"))
    a = ang.reshape(n_rev, n)
    if np.any(np.abs(a[0]) > 720):
        row = int(np.flatnonzero(np.abs(a[0]) > 720)[0])
        raise ProbeFileError(path, lines(row), (
            f"angle_deg = {ang[row]:g}: the spindle angle within a revolution, in degrees, "
            f"lies within -360..720"))
    step = np.diff(a, axis=1)
    if np.any(step <= 0):
        r, i = (int(v) for v in np.argwhere(step <= 0)[0])
        row = r * n + i + 1
        if np.all(step < 0):
            hint = ("; the angles decrease throughout: if the spindle turned the other way, "
                    "negate angle_deg and every probe's mounting angle (the probe angles count "
                    "in the sense the spindle angle increases)")
        else:
            hint = ""
        raise ProbeFileError(path, lines(row), (
            f"angle_deg must increase within a revolution: {a[r, i + 1]:g} deg does not come "
            f"after {a[r, i]:g} deg (line {lines(row - 1)}) in revolution {rev[r * n]:g}{hint}"))
    pitch = 360.0 / n
    expected = a[0, :1] + pitch * np.arange(n)
    off = np.abs(a[0] - expected) > ANGLE_TOLERANCE * pitch
    if off.any():
        i = int(np.flatnonzero(off)[0])
        span = a[0, -1] - a[0, 0]
        if abs(span - 360.0) < ANGLE_TOLERANCE * 360.0 / (n - 1):
            raise ProbeFileError(path, lines(n - 1), (
                f"the last sample of revolution {rev[0]:g} ({a[0, -1]:g} deg) repeats its "
                f"first ({a[0, 0]:g} deg, line {lines(0)}), 360 deg later: the N samples of a "
                f"revolution are 360 / N apart and end one step before 360 deg; drop the "
                f"repeated sample from every revolution"))
        hint = ""
        if abs(span - TWO_PI * (n - 1) / n) < ANGLE_TOLERANCE * TWO_PI / n:
            hint = (f"; they span {span:.4g}, 2 pi (N - 1) / N: radians? (deg = rad x 180 / "
                    f"pi)")
        raise ProbeFileError(path, lines(i), (
            f"angle_deg is not equally spaced over the revolution: {a[0, i]:g} deg where "
            f"{n} samples from {a[0, 0]:g} deg (line {lines(0)}), 360 / {n} = {pitch:.6g} deg "
            f"apart, put sample {i + 1} at {expected[i]:.6g} deg (tolerance "
            f"{ANGLE_TOLERANCE:g} of a step){hint}"))
    moved = np.abs(a - a[:1]) > ANGLE_TOLERANCE * pitch
    if moved.any():
        r, i = (int(v) for v in np.argwhere(moved)[0])
        raise ProbeFileError(path, lines(r * n + i), (
            f"revolution {rev[r * n]:g} has sample {i + 1} at {a[r, i]:g} deg where revolution "
            f"{rev[0]:g} has it at {a[0, i]:g} deg (line {lines(i)}); every revolution needs "
            f"the same angles: angle_deg is the angle within the revolution (if it counts on "
            f"across revolutions, write it modulo 360)"))
    return rev[starts].astype(int), n, a[0]


def _check_values(path, columns, values, lines, header_line) -> None:
    for c, v in zip(columns, values, strict=True):
        big = np.abs(v) > MAX_ABS_UM
        if big.any():
            rows = np.flatnonzero(big)
            raise ProbeFileError(path, lines(rows[0]), (
                f"column {c!r} reads {v[rows[0]]:g} um, beyond +-{MAX_ABS_UM:g} um (10 mm), "
                f"more than a displacement probe's range; lines {lines.some(rows)}: in nm? "
                f"(um = nm / 1000)"))
        span = float(np.ptp(v))
        if span < MIN_SPAN_UM:
            raise ProbeFileError(path, header_line, (
                f"column {c!r} spans only {span:.3g} um over the whole file ({v.min():g} .. "
                f"{v.max():g}), less than the {MIN_SPAN_UM:g} um (10 nm) that probe noise, the "
                f"artefact's form and any spindle's error motion give: in mm? (um = mm x "
                f"1000), or a probe that did not read"))


def read_probe_file(path, *, max_harmonic: int | None = None, allow_cancelled: bool = False,
                    on_read=None) -> ProbeData:
    """Read and check a multi-probe spindle / roundness measurement (``data/spindle/README.md``).

    Refused, with a :class:`ProbeFileError` naming the file and the line (the header's for a
    problem of the columns, the row's as an editor numbers it otherwise), before any
    separation: a missing file, more than :data:`MAX_FILE_BYTES` bytes or :data:`MAX_ROWS` rows,
    text that is not UTF-8, a tab-separated file, decimal commas in a comma-separated file, a
    missing
    ``revolution`` or ``angle_deg`` column, a probe column not named
    ``probe_<angle in degrees>_um`` or in other units (``probe_0_mm``: "in mm"), fewer than
    :data:`MIN_PROBES` or more than :data:`MAX_PROBES` probes, two probes at one angle (modulo
    360), angles that look like radians, a row with more fields than the header, an empty,
    NaN, infinite or non-numeric cell, revolution numbers that are not whole or not in order,
    unequal samples per revolution (or fewer than :data:`MIN_SAMPLES`, more than
    :data:`MAX_SAMPLES`), angles that do not increase within a revolution, are not equally
    spaced over it (within :data:`ANGLE_TOLERANCE` of a step) or differ between revolutions,
    readings beyond +-:data:`MAX_ABS_UM` (nm?) or a probe spanning less than :data:`MIN_SPAN_UM`
    (mm?), and a probe layout that cannot separate harmonics within 2..max_harmonic
    (:func:`layout_cancelled`) unless ``allow_cancelled``: then those harmonics are set aside
    with a :class:`~mtaccuracy.spindle.separation.CancelledHarmonicsWarning` naming them, as the
    library's separation does.  Columns that neither are ``revolution``, ``angle_deg`` nor start
    with ``probe`` are ignored (listed in ``ignored_columns``).

    Read, as :mod:`mtaccuracy.thermal.io` reads them: a semicolon-separated file (what a
    spreadsheet writes in a locale with decimal commas; the header tells, by holding a ``;``)
    with decimal commas or points, a probe's angle in its name included (``probe_38,5_um``);
    a byte-order mark; blank lines and rows whose every field is empty (a spreadsheet's
    trailing rows), which are skipped.

    Parameters
    ----------
    path : str or Path
        The CSV file.
    max_harmonic : int, optional
        The highest profile harmonic to separate, 2..(N - 1) // 2; default all
        (:func:`resolvable_harmonic`).
    allow_cancelled : bool
        Set cancelled harmonics aside with a warning instead of refusing the file.
    on_read : callable, optional
        Called as ``on_read(path)`` once the file is read (the compendium passes
        ``provenance.track`` to hash its input).

    Returns
    -------
    ProbeData
        The readings (um) as ``(R, L, N)``, the angles and the harmonics to separate.

    Raises
    ------
    ProbeFileError
        Naming the file, the line and the problem.
    """
    path = Path(path)
    if not path.is_file():
        raise ProbeFileError(path, None, "file not found (the probe file: revolution, "
                                         "angle_deg, probe_<angle>_um columns; see "
                                         "data/spindle/README.md)")
    size = path.stat().st_size
    if size > MAX_FILE_BYTES:
        raise ProbeFileError(path, None, f"{size} bytes; files up to {MAX_FILE_BYTES} bytes "
                                         f"are read ({MAX_ROWS} rows of 16 probes take less)")
    raw = path.read_bytes()
    try:
        head = raw.decode("utf-8-sig")[:_HEAD_CHARS]
    except UnicodeDecodeError as exc:
        raise ProbeFileError(path, csvlines.bad_byte_line(raw, exc), (
            f"not UTF-8 text (byte 0x{raw[exc.start]:02x}); save the file as UTF-8")) from None
    if on_read is not None:
        on_read(path)
    header_line, names, sep = _header(path, head)
    probes, angles, ignored = _probe_columns(path, header_line, names)
    df = _parse(path, raw, names, header_line, sep)
    del raw
    lines = _Lines(path, sep)
    rev = _numbers(path, df, "revolution", lines, sep)
    ang = _numbers(path, df, "angle_deg", lines, sep)
    values = [_numbers(path, df, c, lines, sep) for c in probes]
    revolutions, n, sample_deg = _check_structure(path, rev, ang, lines)
    _check_values(path, probes, values, lines, header_line)
    try:
        k_top = _check_band(max_harmonic, n)
    except ValueError as exc:
        raise ProbeFileError(path, None, str(exc)) from None
    cancelled = layout_cancelled(np.deg2rad(angles), k_top)
    if cancelled:
        msg = _cancelled_message(angles, cancelled, n, k_top)
        if len(cancelled) == k_top - 1:
            raise ProbeFileError(path, header_line, msg + "; that is every harmonic: nothing "
                                                          "to separate" + _CANCELLED_HINT)
        if not allow_cancelled:
            raise ProbeFileError(path, header_line, msg + _CANCELLED_HINT)
        warnings.warn(f"{path}, line {header_line}: {msg} (allow_cancelled=True: separating "
                      f"without them)", CancelledHarmonicsWarning, stacklevel=2)
    signals = np.stack(values).reshape(len(probes), len(revolutions), n).transpose(1, 0, 2)
    return ProbeData(path=str(path), columns=tuple(probes), angles_deg=angles,
                     sample_deg=sample_deg, revolutions=revolutions,
                     signals_um=np.ascontiguousarray(signals), max_harmonic=k_top,
                     cancelled=tuple(cancelled), ignored_columns=tuple(ignored),
                     header_line=header_line)


def write_probe_file(path, signals_um, angles_deg, sample_deg, *, revolutions=None,
                     decimals: int = 4) -> None:
    """Write readings in the schema of :func:`read_probe_file` (Unix line ends, fixed decimals).

    Parameters
    ----------
    path : str or Path
        The file (its folder must exist).
    signals_um : array (R, L, N)
        Probe readings (um).
    angles_deg : array (L,)
        Mounting angles (deg).
    sample_deg : array (N,)
        Spindle angle of each sample (deg).
    revolutions : array of int (R,), optional
        Revolution numbers; default 1..R.
    decimals : int
        Decimals of the readings (um); the angles are written with up to 10.
    """
    y = np.asarray(signals_um, dtype=float)
    r, n_probes, n = y.shape
    revolutions = np.arange(1, r + 1) if revolutions is None else np.asarray(revolutions)
    table = pd.DataFrame({"revolution": np.repeat(revolutions, n),
                          "angle_deg": np.tile(np.round(np.asarray(sample_deg, float), 10), r)})
    for j, a in enumerate(np.asarray(angles_deg, dtype=float)):
        table[probe_column(a)] = np.round(y[:, j, :].ravel(), decimals) + 0.0
    Path(path).write_bytes(_csv_bytes(table, decimals))


def _csv_bytes(table: pd.DataFrame, decimals: int) -> bytes:
    buf = io.StringIO()
    cols = {c: (lambda v: f"{v:.{decimals}f}") for c in table.columns if c.startswith(
        ("probe_", "profile_", "x_", "y_"))}
    out = table.copy()
    for c, fmt in cols.items():
        out[c] = [fmt(v) for v in out[c]]
    out["angle_deg"] = [np.format_float_positional(v, trim="-") for v in out["angle_deg"]]
    out.to_csv(buf, index=False, lineterminator="\n")
    return buf.getvalue().encode("utf-8")


# --------------------------------------------------------------------------------------------
# The shipped simulated example
# --------------------------------------------------------------------------------------------

#: How the example is made (recorded in its provenance.json).
EXAMPLE_SETUP = dict(seed=2107, n_samples=256, n_revolutions=8,
                     angles_deg=(0.0, 38.5, 97.0, 221.0), lobes=3, lobe_um=0.35,
                     form_harmonics=(2, 40), form_um=0.25, centring_um=1.8,
                     sync_um=((2, 0.12, 0.08), (3, 0.05, 0.04), (5, 0.03, 0.02),
                              (7, 0.015, 0.02)),
                     async_harmonics=(1, 30), async_um=0.02, noise_um=0.005,
                     offsets_um=(4.2, -1.7, 6.3, -3.1), decimals=4)


def example_measurement(setup: dict | None = None):
    """A simulated four-probe measurement at off-grid angles and the truth it was built from.

    The artefact: a three-lobed form, random harmonics 2..40 (amplitudes ~ 1/k, random phases)
    and a centring eccentricity (a first harmonic).  The spindle: a synchronous radial motion
    of harmonics 2, 3, 5, 7 (an ellipse and lobes, in x and y), plus an asynchronous motion new
    every revolution (random harmonics 1..30 of each axis, rms ``async_um``).  Each probe reads
    Eq. 7 at its off-grid angle, computed from the harmonics (no interpolation), plus its zero
    offset and white noise (``noise_um``), rounded to ``decimals``.  Every draw comes from
    ``numpy.random.default_rng(seed)``.

    Parameters
    ----------
    setup : dict, optional
        Overrides of :data:`EXAMPLE_SETUP`.

    Returns
    -------
    probes : DataFrame
        The probe file's table (columns ``revolution``, ``angle_deg``, ``probe_<angle>_um``).
    truth : DataFrame
        ``revolution``, ``angle_deg``, ``profile_um`` (the artefact at the sample angle, zero
        mean), ``x_um``, ``y_um`` (the spindle's motion at that sample).
    """
    s = {**EXAMPLE_SETUP, **(setup or {})}
    rng = np.random.default_rng(s["seed"])
    n, r = s["n_samples"], s["n_revolutions"]
    phi = np.deg2rad(np.asarray(s["angles_deg"]))
    theta = TWO_PI * np.arange(n) / n

    k0, k1 = s["form_harmonics"]
    ks = np.arange(k0, k1 + 1)
    amp = s["form_um"] * rng.standard_normal(len(ks)) / ks
    ph = rng.uniform(0, TWO_PI, len(ks))
    lobe_phase, ecc_phase = rng.uniform(0, TWO_PI, 2)

    def form(u):                                   # the artefact at its own angles u (..., )
        u = np.asarray(u)[..., None]
        return ((amp * np.cos(ks * u + ph)).sum(-1) + s["lobe_um"]
                * np.cos(s["lobes"] * u[..., 0] + lobe_phase)
                + s["centring_um"] * np.cos(u[..., 0] - ecc_phase))

    sx = sum(a * np.cos(k * theta + 0.7 * k) for k, a, _ in s["sync_um"])
    sy = sum(b * np.sin(k * theta + 0.3 * k) for k, _, b in s["sync_um"])
    a0, a1 = s["async_harmonics"]
    ka = np.arange(a0, a1 + 1)
    coef = rng.standard_normal((r, 2, 2, len(ka))) * s["async_um"] / np.sqrt(len(ka))
    basis = np.stack([np.cos(ka[:, None] * theta), np.sin(ka[:, None] * theta)])  # (2, K, N)
    asyn = np.einsum("racK,cKn->ran", coef, basis)                    # (R, 2, N)
    x, y = sx + asyn[:, 0], sy + asyn[:, 1]                           # (R, N)

    reading = (form(theta[None, :] + phi[:, None])[None]                # (1, L, N)
               + x[:, None, :] * np.cos(phi)[:, None] + y[:, None, :] * np.sin(phi)[:, None]
               + np.asarray(s["offsets_um"])[None, :, None]
               + s["noise_um"] * rng.standard_normal((r, len(phi), n)))
    deg = np.rad2deg(theta)
    table = pd.DataFrame({"revolution": np.repeat(np.arange(1, r + 1), n),
                          "angle_deg": np.tile(deg, r)})
    for j, a in enumerate(s["angles_deg"]):
        table[probe_column(a)] = np.round(reading[:, j].ravel(), s["decimals"]) + 0.0
    prof = form(theta)
    truth = pd.DataFrame({"revolution": table.revolution, "angle_deg": table.angle_deg,
                          "profile_um": np.tile(prof - prof.mean(), r),
                          "x_um": x.ravel(), "y_um": y.ravel()})
    return table, truth


def write_example(folder) -> dict:
    """Write the shipped example and its record into ``folder``.

    The files ``example_probes.csv``, ``example_truth.csv`` and ``provenance.json`` (the setup,
    the generator and each file's SHA-256).

    Parameters
    ----------
    folder : str or Path
        Where (``data/spindle`` in the repository); created if missing.

    Returns
    -------
    dict
        The record written.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    probes, truth = example_measurement()
    data = {"probes": _csv_bytes(probes, EXAMPLE_SETUP["decimals"]),
            "truth": _csv_bytes(truth, 6)}
    for key, blob in data.items():
        (folder / EXAMPLE_FILES[key]).write_bytes(blob)
    record = {"what": "SIMULATED four-probe spindle measurement (not measured data)",
              "generator": "mtaccuracy.spindle.probes.write_example (example_measurement with "
                           "EXAMPLE_SETUP)",
              "setup": {k: list(v) if isinstance(v, tuple) else v
                        for k, v in EXAMPLE_SETUP.items()},
              "sha256": {EXAMPLE_FILES[k]: hashlib.sha256(b).hexdigest()
                         for k, b in data.items()}}
    text = json.dumps(record, indent=1, sort_keys=True) + "\n"
    (folder / EXAMPLE_FILES["record"]).write_text(text, encoding="utf-8")
    return record


def match_example(path, folder):
    """The shipped example's truth when the file at ``path`` has its content (SHA-256), else None.

    Whatever the file's name or place.

    Parameters
    ----------
    path : str or Path
        A probe file.
    folder : str or Path
        The folder of the example and its ``provenance.json`` (``data/spindle``).

    Returns
    -------
    DataFrame or None
        The truth table of :func:`example_measurement` (read from ``example_truth.csv``, which
        must match its recorded hash too), or None.
    """
    folder = Path(folder)
    record_path = folder / EXAMPLE_FILES["record"]
    if not record_path.is_file():
        return None
    record = json.loads(record_path.read_text(encoding="utf-8"))
    want = record.get("sha256", {})
    if hashlib.sha256(Path(path).read_bytes()).hexdigest() != want.get(EXAMPLE_FILES["probes"]):
        return None
    truth = folder / EXAMPLE_FILES["truth"]
    if not truth.is_file() or hashlib.sha256(truth.read_bytes()).hexdigest() \
            != want.get(EXAMPLE_FILES["truth"]):
        raise ValueError(f"{truth}: missing or not the truth recorded in {record_path} (its "
                         f"SHA-256 differs); regenerate both with probes.write_example")
    return pd.read_csv(truth)
