"""Least squares over all probes on the sampling grid: the estimator beside the paper's method.

For each DFT bin the probes read the profile harmonic and the two motion components; the three
unknowns are fitted to the L >= 3 readings (:func:`separate_least_squares`), with the noise
amplification :func:`least_squares_transfer`, the counterpart of the weighted four-point
method's error transfer function (:func:`~mtaccuracy.spindle.separation.transfer`, Yang et
al. 2021, Eqs. 14, 19).  The model, the first-harmonic conventions and the result
(:class:`~mtaccuracy.spindle.separation.Separation`) are :mod:`~mtaccuracy.spindle.separation`'s;
probes at any angles, off the grid: :mod:`~mtaccuracy.spindle.probes`.

Why hand-written: a pseudo-inverse per bin (numpy's ``linalg.pinv``, batched) and the FFT; no
maintained package separates multi-probe spindle data.
"""

from __future__ import annotations

__all__ = ["separate_least_squares", "least_squares_transfer"]

import numpy as np

from .separation import (
    TWO_PI,
    Separation,
    _check_max_harmonic,
    _check_n,
    _check_options,
    _motion_and_first_harmonic,
    _set_aside,
)


def _ls_design(phi4, harmonics):
    """``A_k`` (K, L, 3): probe l's reading of harmonic k of the profile (``exp(i k phi_l)``,
    numpy's FFT convention) and of the motion (``cos phi_l``, ``sin phi_l``)."""
    k = np.asarray(harmonics, dtype=float)[:, None]
    a = np.empty(k.shape[:1] + phi4.shape[-1:] + (3,), dtype=complex)
    a[..., 0] = np.exp(1j * k * phi4)
    a[..., 1] = np.cos(phi4)
    a[..., 2] = np.sin(phi4)
    return a


def least_squares_transfer(phi, harmonics) -> np.ndarray:
    """Noise amplification of the least-squares multi-probe estimator, per harmonic.

    Parameters
    ----------
    phi : (L - 1,) or (L,) array
        Probe angles in rad: phi_1..phi_{L-1} with phi_0 = 0, or all L (L >= 3).
    harmonics : sequence of int
        The orders k.

    Returns
    -------
    (K,) array
        ``[(A_k^H A_k)^-1]_00``: the variance of the estimated profile harmonic ``R_k`` in units
        of one probe's noise variance at that harmonic, ``A_k`` (L x 3) the readings of the
        profile harmonic (``exp(i k phi_l)``) and of the two motion components
        (``cos phi_l``, ``sin phi_l``).  ``inf`` where the layout cannot separate the harmonic
        (always k = 1).

    Notes
    -----
    The counterpart of :func:`~mtaccuracy.spindle.separation.transfer` (``q_k^2`` of the weighted
    four-point method, Yang et al. 2021, Eqs. 14 and 19, in the same units).  By the Gauss-Markov
    theorem it never exceeds ``q_k^2`` of any weights that cancel the motion (a test checks it on
    random layouts).  On Yang et al.'s layout (0, 14, 65, 116 of 128; a_3 = 1.953) the worst case
    over harmonics 2..20 is 6.40 against 112.85.
    """
    phi = np.asarray(phi, dtype=float)
    if phi.ndim != 1 or phi.shape[0] < 3 or not np.all(np.isfinite(phi)):
        raise ValueError(f"phi must be the finite angles of at least 3 probes, got {phi!r}")
    phi4 = np.concatenate([[0.0], phi]) if phi.shape[0] == 3 else phi
    a = _ls_design(phi4, harmonics)
    sv = np.linalg.svd(a, compute_uv=False)                              # (K, 3)
    ok = sv[:, -1] > 1e-9 * sv[:, 0]
    gram = np.einsum("klr,kls->krs", a.conj(), a)
    out = np.full(a.shape[0], np.inf)
    out[ok] = np.linalg.inv(gram[ok])[:, 0, 0].real
    return out


def separate_least_squares(signals, phi, *, first_harmonic: str = "eccentricity",
                           rcond: float = 1e-9, allow_cancelled: bool = False,
                           max_harmonic: int | None = None) -> Separation:
    """Profile and radial error motion from multi-probe signals by least squares over all probes.

    For each DFT bin k the probes read ``Y_l(k) = R_k exp(i k phi_l) + X_k cos(phi_l) + Y_k
    sin(phi_l)``; the three unknowns are fitted to the L >= 3 readings (the pseudo-inverse per bin,
    batched).  The first harmonic, which no probe layout separates, is set by ``first_harmonic``
    exactly as in :func:`~mtaccuracy.spindle.separation.separate`.  This is the estimator of the
    public multi-probe roundness tools, written beside the paper's weighted method
    (:func:`~mtaccuracy.spindle.separation.separate_details`): it needs no weights, uses every probe
    at every harmonic, and its noise amplification (:func:`least_squares_transfer`) is the smallest
    of any linear unbiased estimator.

    Parameters
    ----------
    signals : (..., L, N) array
        Probe readings, batched over leading axes (Yang et al. 2021, Eq. 7 for L = 4).
    phi : (L - 1,) or (L,) array
        Probe angles on the sampling grid ``2 pi p / N``, rad (phi_0 = 0).
    first_harmonic : {"eccentricity", "radial"}
        The convention that splits the profile's first harmonic from the motion.
    rcond : float
        Bins whose design has a smallest singular value below ``rcond`` x the largest are set
        aside (the profile harmonic reads on the probes as a motion would).
    allow_cancelled : bool
        Proceed without such harmonics (with a
        :class:`~mtaccuracy.spindle.separation.CancelledHarmonicsWarning`) instead of
        refusing the layout.
    max_harmonic : int, optional
        The highest harmonic the signals contain (default N/2); set-aside harmonics above it
        are no loss.

    Returns
    -------
    Separation
        As :func:`~mtaccuracy.spindle.separation.separate_details`: ``profile``, ``dx``, ``dy``
        (..., N) and the intermediate results (``eigen`` holds each bin's smallest singular value,
        ``rank`` the bins solved in full).
    """
    _check_options(first_harmonic, rcond)
    y = np.asarray(signals, dtype=float)
    if y.ndim < 2 or y.shape[-2] < 3:
        raise ValueError(f"signals must have shape (..., L, N) with L >= 3 probes, got {y.shape}")
    n = _check_n(y.shape[-1], "samples per revolution (the signals' last axis)")
    if not np.all(np.isfinite(y)):
        raise ValueError("signals contain NaN or inf")
    phi = np.asarray(phi, dtype=float)
    n_probes = y.shape[-2]
    if phi.shape == (n_probes - 1,):
        phi = np.concatenate([[0.0], phi])
    if phi.shape != (n_probes,) or not np.all(np.isfinite(phi)):
        raise ValueError(f"phi must hold the {n_probes} probe angles (or the {n_probes - 1} after "
                         f"phi_0 = 0), got shape {phi.shape}")
    pos = phi * n / TWO_PI
    if np.any(np.abs(pos - np.round(pos)) > 1e-6):
        raise ValueError("every probe angle must be 2 pi p / N with integer p (N = "
                         f"{n}); the nearest positions are {np.round(pos).astype(int).tolist()}")
    p = np.round(pos).astype(int) % n
    max_harmonic = _check_max_harmonic(max_harmonic, n)
    a = _ls_design(phi, np.arange(n))                                    # (N, L, 3)
    sv = np.linalg.svd(a, compute_uv=False)
    keep = sv[:, -1] > rcond * sv[:, 0]
    keep[[1, n - 1]] = False                             # the first harmonic: never separable
    cancelled = _set_aside(
        keep, n, max_harmonic, allow_cancelled, stacklevel=3,
        describe=lambda ks: (f"the layout (probe positions {p.tolist()} of N = {n}) cannot "
                             f"separate harmonic(s) {ks} besides the first (the profile harmonic "
                             f"reads on the probes as a motion would): the separated profile "
                             f"would lack them"),
        hint="; move a probe, or pass allow_cancelled=True")
    pinv = np.zeros((n, 3, n_probes), dtype=complex)
    pinv[keep] = np.linalg.pinv(a[keep])
    spec = np.fft.fft(y, axis=-1)                                        # (..., L, N)
    r_k = np.einsum("kl,...lk->...k", pinv[:, 0, :], spec)               # profile harmonics
    r0 = np.fft.ifft(r_k, axis=-1).real
    profile, z, cd, residual_rms = _motion_and_first_harmonic(y, r0, phi, p, first_harmonic)
    return Separation(profile=profile, dx=z.real, dy=z.imag, profile_no_first=r0,
                      first_harmonic=cd, cancelled=cancelled, rank=int(keep.sum()),
                      residual_rms=residual_rms, convention=first_harmonic, eigen=sv[:, -1])
