"""Roundness of a sampled profile: least-squares circle, minimum zone, harmonics, low-pass.

Least-squares circle (limacon model, ``scipy.linalg.lstsq``) and minimum zone (a linear
programme, ``scipy.optimize.linprog``), the profile's Fourier coefficients, and a low-pass
filter.  Reusable for any roundness measurement; lengths in any one unit.
"""

from __future__ import annotations

__all__ = ["harmonic_coefficients", "lowpass", "lsc_roundness", "mz_roundness"]

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
