"""Simulated four-probe measurements (Yang et al. 2021, Section 3 simulated).

Random profiles, probe signals with asynchronous error motion and noise sampled over several
revolutions (multi-turn coincidence sampling, Eqs. 1-2), and the coincidence ratio of repeated
curves.
"""

from __future__ import annotations

__all__ = ["random_profile", "simulate_measurements", "coincidence_ratio", "measure_separated",
           "separation_statistics"]

import numpy as np

from .. import validate
from ..roundness import _profile, lowpass, lsc_roundness, mz_roundness
from .separation import TWO_PI, _check_n, probe_angles, probe_signals, separate_details


def random_profile(n_samples: int, harmonics, *, rng, decay: float = 1.0,
                   roundness: float | None = None) -> np.ndarray:
    """A random profile of the given harmonics, amplitudes ``~ k^-decay``, random phases.

    Scaled so that its minimum-zone roundness equals ``roundness`` when given.

    Parameters
    ----------
    n_samples : int
        Samples over one turn (>= 8).
    harmonics : sequence of int
        Harmonic orders present, each in 0..N/2-1.
    rng : None, int or numpy.random.Generator
        The stream the amplitudes and phases are drawn from (a Generator is used as it is).
    decay : float
        Exponent of the amplitudes' decay with the order.
    roundness : float, optional
        Minimum-zone roundness wanted (the profile's unit).

    Returns
    -------
    array (n_samples,)
        The profile (unit of ``roundness``, or arbitrary).
    """
    n = _check_n(n_samples)
    ks = np.asarray(harmonics)
    if ks.ndim != 1 or ks.size == 0 or np.any(ks < 0) or np.any(ks >= n / 2):
        raise ValueError(f"harmonics must be orders in 0..N/2-1 = {n // 2 - 1}")
    rng = validate.rng(rng)
    t = TWO_PI * np.arange(n) / n
    amp = rng.standard_normal(len(ks)) * np.maximum(ks, 1) ** (-float(decay))
    ph = rng.uniform(0, TWO_PI, len(ks))
    r = (amp[:, None] * np.cos(ks[:, None] * t + ph[:, None])).sum(0)
    if roundness is not None:
        if not roundness > 0:
            raise ValueError(f"roundness must be > 0, got {roundness!r}")
        r = r * roundness / mz_roundness(r)[0]
    return r


def simulate_measurements(profile, dx, dy, positions, *, n_rev: int, interleave: int,
                          async_sd: float, noise_sd: float, n_measurements: int, rng,
                          async_harmonics=(2, 30)) -> np.ndarray:
    """Averaged four-probe signals of repeated measurements (a simulation of Section 3).

    Each measurement lasts ``n_rev`` revolutions.  Multi-turn coincidence sampling (Eqs. 1-2):
    revolution ``j`` samples only the angles ``n`` with ``n = j mod interleave``, so one full set
    of ``N`` angles takes ``interleave`` revolutions and the ``n_rev // interleave`` sets are
    averaged angle by angle.  The synchronous motion ``dx, dy`` repeats every revolution; the
    asynchronous motion is new every revolution (random harmonics in ``async_harmonics``, rms
    ``async_sd`` per axis); each probe adds white noise ``noise_sd``.

    Parameters
    ----------
    profile, dx, dy : arrays (N,)
        The true profile and synchronous error motion (mm).
    positions : sequence of int (4,)
        Probe positions (sample indices, p_0 = 0).
    n_rev : int
        Revolutions per measurement (>= interleave).
    interleave : int
        Revolutions per full set of angles (>= 1, dividing N).
    async_sd, noise_sd : float
        Asynchronous motion and probe noise (mm).
    n_measurements : int
        Repeated measurements M (>= 1).
    rng : None, int or numpy.random.Generator
        The stream of the motion and the noise (a Generator is used as it is).
    async_harmonics : (int, int)
        Harmonic band of the asynchronous motion.

    Returns
    -------
    array (M, 4, N)
        The averaged probe signals (mm).
    """
    r = _profile(profile)
    n = r.shape[-1]
    n_rev = validate.integer(n_rev, "n_rev", low=1)
    interleave = validate.integer(interleave, "interleave", low=1)
    n_measurements = validate.integer(n_measurements, "n_measurements", low=1)
    rng = validate.rng(rng)
    if n % interleave:
        raise ValueError(f"interleave ({interleave}) must divide N ({n})")
    if n_rev < interleave:
        raise ValueError(f"n_rev ({n_rev}) must be at least interleave ({interleave})")
    if async_sd < 0 or noise_sd < 0:
        raise ValueError("async_sd and noise_sd must be >= 0")
    sets = n_rev // interleave
    m = n_measurements
    clean = probe_signals(r, dx, dy, positions)                       # (4, N)
    phi = probe_angles(positions, n)
    t = TWO_PI * np.arange(n) / n
    # every sample n of set s was taken in revolution s*interleave + (n mod interleave); the
    # asynchronous motion of that revolution at angle n is what it saw.
    k0, k1 = async_harmonics
    ks = np.arange(k0, k1 + 1)
    shape = (m, sets, interleave, 2, len(ks))
    coef = rng.standard_normal(shape + (2,)) * async_sd / np.sqrt(len(ks))
    basis = np.stack([np.cos(ks[:, None] * t), np.sin(ks[:, None] * t)], axis=-1)  # (K, N, 2)
    motion = np.einsum("msiaKc,Knc->msian", coef, basis)            # (m, sets, il, 2, N)
    which = np.arange(n) % interleave                                # revolution within a set
    motion = motion[:, :, which, :, np.arange(n)]                   # (N, m, sets, 2)
    motion = np.moveaxis(motion, 0, -1)                              # (m, sets, 2, N)
    proj = motion[:, :, 0, None, :] * np.cos(phi)[:, None] + motion[:, :, 1, None, :] \
        * np.sin(phi)[:, None]                                       # (m, sets, 4, N)
    noise = rng.standard_normal((m, sets, 4, n)) * noise_sd
    return clean + (proj + noise).mean(axis=1)


def coincidence_ratio(curves, k: float = 2.0) -> np.ndarray:
    """How far apart groups' mean curves are, in units of ``k`` standard errors of the difference.

    ``curves``: ``(G, M, P)``, ``G`` groups (e.g. spindle speeds), ``M >= 2`` repeated
    measurements of a curve of ``P`` points each.  For groups ``a, b`` with means ``m_a, m_b`` and
    pointwise sample variances ``v_a, v_b`` (``ddof = 1``):

        ratio_ab = rms_P(m_a - m_b) / (k * sqrt(mean_P(v_a + v_b) / M)).

    If both groups measure the same curve with independent scatter, ``E[rms^2] =
    mean_P(v_a + v_b) / M``, so the ratio is about ``1 / k``; a ratio at most 1 means the groups'
    curves coincide within ``k`` standard errors of the measurement scatter (the ``k = 2`` of the
    compendium's tolerance policy), a ratio above 1 a systematic difference between groups.

    Parameters
    ----------
    curves : array (G, M, P)
        G groups of M >= 2 repeated curves of P points.
    k : float
        Standard errors per unit of the ratio.

    Returns
    -------
    array (G, G)
        The ratios, symmetric, 0 on the diagonal.
    """
    c = np.asarray(curves, dtype=float)
    if c.ndim != 3 or c.shape[1] < 2 or c.shape[2] < 1:
        raise ValueError(f"curves must be (groups, measurements >= 2, points), got {c.shape}")
    if not np.all(np.isfinite(c)) or not (np.isfinite(k) and k > 0):
        raise ValueError("curves must be finite and k > 0")
    m = c.mean(axis=1)                                               # (G, P)
    v = c.var(axis=1, ddof=1)                                        # (G, P)
    rms = np.sqrt(((m[:, None] - m[None]) ** 2).mean(axis=-1))       # (G, G)
    se = np.sqrt((v[:, None] + v[None]).mean(axis=-1) / c.shape[1])
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.where(se > 0, rms / (k * se), np.where(rms > 0, np.inf, 0.0))
    return out


def measure_separated(profile, dx, dy, positions, phi, w, *, speed_rpm: float, duration_s: float,
                      interleave: int, async_sd_600: float, async_exponent: float,
                      noise_sd: float, n_measurements: int, lowpass_harmonic: int,
                      first_harmonic: str, rng):
    """One simulated measurement campaign at one spindle speed, separated (Section 3, simulated).

    The revolutions are those of ``duration_s`` at ``speed_rpm``, a whole number of
    ``interleave`` sets and at least one; the asynchronous motion has standard deviation
    ``async_sd_600 (speed / 600)^async_exponent``; the signals (:func:`simulate_measurements`,
    ``n_measurements`` of them) are low-passed to ``lowpass_harmonic`` and separated with the
    layout ``positions``, ``phi``, ``w`` (:func:`~.separation.separate_details`, told that no
    harmonic above the cut-off is present).

    Parameters
    ----------
    profile, dx, dy : arrays (N,)
        The true profile and synchronous error motion (mm).
    positions : sequence of int (4,)
        Probe positions (sample indices).
    phi : array (3,)
        Probe angles (rad).
    w : array (4,)
        Weights a0..a3.
    speed_rpm, duration_s : float
        Spindle speed (r/min) and acquisition time (s).
    interleave : int
        Revolutions per full set of angles (Eqs. 1-2).
    async_sd_600, async_exponent : float
        Asynchronous motion (mm at 600 r/min) and its growth with speed.
    noise_sd : float
        Probe noise (mm).
    n_measurements : int
        Repeated measurements.
    lowpass_harmonic : int
        Highest harmonic kept by the low-pass filter, 1..N/2.
    first_harmonic : str
        Convention of the first harmonic (:func:`separate_details`).
    rng : None, int or numpy.random.Generator
        The stream of the motion and the noise (a Generator is used as it is).

    Returns
    -------
    separation : Separation
        Of every measurement, ``(n_measurements, N)`` arrays.
    revolutions : int
        Revolutions per measurement.
    """
    n_rev = max(interleave, int(duration_s * speed_rpm / 60) // interleave * interleave)
    amp = async_sd_600 * (speed_rpm / 600) ** async_exponent
    y = simulate_measurements(profile, dx, dy, positions, n_rev=n_rev, interleave=interleave,
                              async_sd=amp, noise_sd=noise_sd, n_measurements=n_measurements,
                              rng=rng)
    s = separate_details(lowpass(y, lowpass_harmonic), phi, w, first_harmonic=first_harmonic,
                         max_harmonic=lowpass_harmonic)
    return s, n_rev


def separation_statistics(separated, to_error) -> dict:
    """Roundness and rotation error over repeated separations (Yang et al. 2021, Table 2).

    Parameters
    ----------
    separated : Separation
        ``profile`` (m, n), ``dx``, ``dy`` (m, n) of m repeated measurements, in mm.
    to_error : callable
        ``to_error(dx, dy)``: the scalar rotation error (mm) the notebook compares.

    Returns
    -------
    dict
        Minimum-zone roundness mean and standard deviation (um), the repeatability (its
        standard deviation over its mean, percent), the least-squares roundness mean and
        standard deviation (um) and the mean peak-to-valley rotation error (um).
    """
    mz = mz_roundness(separated.profile)[0] * 1e3
    lsc = lsc_roundness(separated.profile)[0] * 1e3
    err = to_error(separated.dx, separated.dy) * 1e3
    return dict(mz_mean_um=mz.mean(), mz_std_um=mz.std(ddof=1),
                repeatability_percent=100 * mz.std(ddof=1) / mz.mean(), lsc_mean_um=lsc.mean(),
                lsc_std_um=lsc.std(ddof=1), rotation_error_pv_mean_um=np.ptp(err, axis=-1).mean())
