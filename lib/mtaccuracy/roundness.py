"""Roundness of a sampled profile: least-squares circle, minimum zone, harmonics, low-pass.

Least-squares circle (limacon model, ``scipy.linalg.lstsq``) and minimum zone (a linear
programme, ``scipy.optimize.linprog``), the profile's Fourier coefficients, a sharp low-pass
filter (:func:`lowpass`) and the Gaussian filter of ISO 16610-21 in undulations per revolution
(:func:`upr_filter`, the filter ISO 12181-2 prescribes for roundness and ISO 230-7 asks to be
stated for error motion).  Reusable for any roundness measurement; lengths in any one unit.
"""

from __future__ import annotations

__all__ = ["harmonic_coefficients", "lowpass", "lsc_roundness", "mz_roundness",
           "gaussian_transmission", "upr_filter", "GAUSSIAN_ALPHA"]

import numpy as np
import scipy.linalg
from scipy.optimize import linprog

from . import validate

TWO_PI = 2.0 * np.pi

#: The fewest samples per revolution the library takes for a profile (and so separates).
_MIN_SAMPLES = 8


def harmonic_coefficients(signal, harmonics) -> tuple[np.ndarray, np.ndarray]:
    """Fourier coefficients of a profile sampled uniformly over a turn (Yang et al. 2021, Eq. 12).

    ``signal = A_0 + sum_k A_k cos k theta + B_k sin k theta`` with ``theta_i = 2 pi i / n``;
    computed with the FFT.

    Parameters
    ----------
    signal : array (..., n)
        Samples over one turn (any length unit).
    harmonics : array of int (m,)
        Harmonic orders, each in ``1 <= k < n / 2``.

    Returns
    -------
    A, B : arrays (..., m)
        Cosine and sine coefficients, in the unit of ``signal``.
    """
    x = np.asarray(signal, dtype=float)
    n = x.shape[-1]
    k = np.asarray(harmonics)
    if np.any((k < 1) | (k >= n / 2)):
        raise ValueError(f"harmonics must be in 1..N/2-1 = {n // 2 - 1}")
    spec = np.fft.rfft(x, axis=-1)[..., k] * 2 / n
    return spec.real, -spec.imag


def lowpass(signals, max_harmonic: int) -> np.ndarray:
    """Low-pass FFT filter along the last axis: harmonics above ``max_harmonic`` set to zero.

    Parameters
    ----------
    signals : array (..., n)
        Samples over one turn.
    max_harmonic : int
        Highest harmonic kept, an integer in ``1..n // 2``.

    Returns
    -------
    array (..., n)
        The filtered signals.
    """
    x = np.asarray(signals, dtype=float)
    n = x.shape[-1]
    max_harmonic = validate.integer(max_harmonic, "max_harmonic", low=1, high=n // 2)
    spec = np.fft.rfft(x, axis=-1)
    spec[..., max_harmonic + 1:] = 0
    return np.fft.irfft(spec, n=n, axis=-1)


#: ``alpha = sqrt(ln 2 / pi)`` of the Gaussian filter (ISO 16610-21 / ISO 11562): 50 %
#: transmission at the cutoff.
GAUSSIAN_ALPHA = float(np.sqrt(np.log(2.0) / np.pi))


def gaussian_transmission(frequency, *, cutoff: float) -> np.ndarray:
    """Amplitude transmission ``a(f) = exp(-pi (alpha f / f_c)^2)`` of the Gaussian filter.

    ISO 16610-21 (formerly ISO 11562), in undulations per revolution for a roundness profile
    (ISO 12181-2) or an error motion (ISO 230-7): 50 % at the cutoff ``f_c``, 1 at ``f = 0``.

    Parameters
    ----------
    frequency : array
        Frequencies (undulations, i.e. cycles, per revolution; any sign).
    cutoff : float
        The cutoff ``f_c`` (UPR), > 0.

    Returns
    -------
    array
        The transmission, the shape of ``frequency``.
    """
    if not (np.isfinite(cutoff) and cutoff > 0):
        raise ValueError(f"cutoff must be a positive number of undulations per revolution, got "
                         f"{cutoff!r}")
    f = np.asarray(frequency, dtype=float)
    return np.exp(-np.pi * (GAUSSIAN_ALPHA * f / cutoff) ** 2)


def upr_filter(values, *, max_upr: float, continuous: bool = False) -> np.ndarray:
    """The Gaussian low-pass filter in undulations per revolution (UPR), applied by FFT.

    ISO 12181-2 filters a roundness profile with the Gaussian filter of ISO 16610-21 at a
    cutoff in UPR (15, 50, 150, 500 or 1500); ISO 230-7 asks for the filter of an error motion
    measurement to be stated, in UPR, and the usual spindle analysers (Lion Precision's SEA,
    Renishaw's) offer the same Gaussian low-pass: so this one filter serves both, with
    :func:`gaussian_transmission` (50 % at the cutoff; no phase shift, as the profile is
    periodic and filtered in the frequency domain).  ``max_upr = 0``: no filter.

    Parameters
    ----------
    values : array (..., N) or (..., R, N)
        Samples over one revolution (a profile: each revolution filtered as a periodic
        signal), or with ``continuous`` R revolutions of N samples taken as one record of R N
        samples (an error motion; its frequencies in steps of 1 / R cycles per revolution,
        the record treated as periodic over its R revolutions), any length unit.
    max_upr : float
        The cutoff (UPR), >= 0; 0 leaves the values as they are.
    continuous : bool
        Filter the last two axes as one continuous record.

    Returns
    -------
    array
        The filtered values, the shape of ``values``, in their unit.
    """
    x = np.array(values, dtype=float)
    if not (np.isfinite(max_upr) and max_upr >= 0):
        raise ValueError(f"max_upr must be 0 (no filter) or a positive cutoff in undulations "
                         f"per revolution, got {max_upr!r}")
    if max_upr == 0:
        return x
    if continuous:
        if x.ndim < 2:
            raise ValueError(f"a continuous record needs values (..., R, N), got {x.shape}")
        shape = x.shape
        x = x.reshape(shape[:-2] + (shape[-2] * shape[-1],))
        per_rev = shape[-1]
    else:
        per_rev = x.shape[-1]
    m = x.shape[-1]
    f = np.fft.rfftfreq(m, 1.0 / per_rev)                    # cycles per revolution
    out = np.fft.irfft(np.fft.rfft(x, axis=-1) * gaussian_transmission(f, cutoff=max_upr),
                       n=m, axis=-1)
    return out.reshape(shape) if continuous else out


def _profile(profile):
    r = np.asarray(profile, dtype=float)
    if r.ndim < 1 or r.shape[-1] < _MIN_SAMPLES or not np.all(np.isfinite(r)):
        raise ValueError(f"profile must be finite with at least {_MIN_SAMPLES} samples on the "
                         f"last axis")
    return r


def lsc_roundness(profile):
    """Least-squares circle (LSC) roundness of radial deviations sampled uniformly over a turn.

    The limacon model ``r(theta) ~ R0 + a cos theta + b sin theta`` (deviations small against
    the radius; ISO 12181-1's least-squares reference circle), fitted with ``scipy.linalg.lstsq``;
    batched over leading axes.

    Parameters
    ----------
    profile : array (..., n)
        Radial deviations, n >= 8, finite (any length unit).

    Returns
    -------
    roundness : array (...)
        Peak-to-valley of the residual to the circle, in the unit of ``profile``.
    coefficients : array (..., 3)
        ``R0, a, b`` of the limacon.
    """
    r = _profile(profile)
    n = r.shape[-1]
    t = TWO_PI * np.arange(n) / n
    g = np.column_stack([np.ones(n), np.cos(t), np.sin(t)])
    coef, *_ = scipy.linalg.lstsq(g, r.reshape(-1, n).T)
    res = r.reshape(-1, n) - (g @ coef).T
    rnd = (res.max(axis=1) - res.min(axis=1)).reshape(r.shape[:-1])
    return rnd, coef.T.reshape(r.shape[:-1] + (3,))


def mz_roundness(profile):
    """Minimum-zone (MZC) roundness, limacon model, by linear programming.

    Minimise ``t_out - t_in`` over ``(a, b, t_in, t_out)`` subject to
    ``t_in <= r_i - a cos theta_i - b sin theta_i <= t_out`` (``scipy.optimize.linprog``; the
    minimum-zone reference of ISO 12181-1).  One LP per profile (leading axes looped).

    Parameters
    ----------
    profile : array (..., n)
        Radial deviations, n >= 8, finite (any length unit).

    Returns
    -------
    roundness : array (...)
        Width of the narrowest annulus holding the profile, in the unit of ``profile``; never
        more than :func:`lsc_roundness`.
    centre : array (..., 2)
        ``a, b``: the annulus centre.
    """
    r = _profile(profile)
    n = r.shape[-1]
    t = TWO_PI * np.arange(n) / n
    c, s = np.cos(t), np.sin(t)
    # variables: a, b, t_in, t_out ;  r - a c - b s <= t_out ;  -(r - a c - b s) <= -t_in
    a_ub = np.block([[-c[:, None], -s[:, None], np.zeros((n, 1)), -np.ones((n, 1))],
                     [c[:, None], s[:, None], np.ones((n, 1)), np.zeros((n, 1))]])
    cost = np.array([0.0, 0.0, -1.0, 1.0])
    flat = r.reshape(-1, n)
    out = np.empty(len(flat))
    centre = np.empty((len(flat), 2))
    for i, ri in enumerate(flat):
        res = linprog(cost, A_ub=a_ub, b_ub=np.concatenate([-ri, ri]),
                      bounds=[(None, None)] * 4, method="highs")
        if not res.success:
            raise RuntimeError(f"minimum-zone LP failed: {res.message}")
        out[i] = res.fun
        centre[i] = res.x[:2]
    return out.reshape(r.shape[:-1]), centre.reshape(r.shape[:-1] + (2,))
