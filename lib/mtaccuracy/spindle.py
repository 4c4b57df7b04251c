"""Spindle radial error separation with four probes (Yang et al. 2021).

The model (Yang et al. 2021, Eqs. 7 and 11): probe ``l`` at angle ``phi_l`` (``phi_0 = 0``)
reads, at sample ``n`` of ``N`` per revolution (``theta_n = 2 pi n / N``),

    y_l(n) = r(n + p_l) + dx(n) cos(phi_l) + dy(n) sin(phi_l),   phi_l = 2 pi p_l / N,

with ``r`` the workpiece profile and ``(dx, dy)`` the spindle's radial error motion in the fixed
frame.  The weighted sum ``Y = sum_l a_l y_l`` with ``a_0 = 1`` and ``a_1, a_2`` from Eq. 5/15
(given ``a_3``) cancels the motion, because ``lambda_1 = mu_1 = 0`` (Eq. 14).  What is left is
``Y = A r`` with ``A`` the circulant matrix of Eq. 6.  Its eigenvalues are

    Lambda_k = sum_l a_l exp(i k phi_l) = lambda_k + i mu_k      (Eq. 14),

so ``Lambda_1 = Lambda_{N-1} = 0`` *by design*: ``rank(A) <= N - 2``, not ``N`` as printed.  The
system has a solution for every profile but not a unique one (any first harmonic can be added);
:func:`separate` solves it with the pseudo-inverse, i.e. harmonic by harmonic
``R_k = Y_k / Lambda_k`` with every harmonic whose ``|Lambda_k|`` vanishes (the first, and any other
the layout happens to cancel) set aside and reported.  :func:`circulant_matrix` builds ``A`` itself
so that the rank and the equality with ``scipy.linalg.lstsq`` can be shown.

The first harmonic of the profile and a once-per-revolution motion that turns with the workpiece
(``dx + i dy`` proportional to ``exp(-i theta)``) give the four probes *identical* signals, so no
algorithm can split them; a convention must.  :func:`separate` offers two:

``"eccentricity"``
    the motion has no such component (ISO 230-7: the fundamental is eccentricity, not error
    motion); all of it goes to the profile's first harmonic.
``"radial"``
    the motion is purely radial in the rotating direction, ``(dx, dy) = delta (cos, sin)``, the
    scalar ``delta(theta)`` of the paper's Eq. 9; the tangential part of the separated motion then
    fixes the first harmonic ``C, D`` exactly.

Optimisation (Section 2): the objective ``H = q_k^2`` (Eqs. 19-20) for the genes
``x = (phi_1, phi_2, phi_3, a_3)``, fitness ``1/H`` (Eq. 21), a genetic algorithm (binary or real
coded) with fixed rates and the same algorithm with the adaptive rates of Eqs. 22-23, and
differential evolution as the baseline, all batched over independent runs and population (arrays
of shape ``(runs, population, 4)``; the only Python loop is over generations).  ``H >= 1/4`` for
four probes at every harmonic (Cauchy-Schwarz), reached for even ``k``; :func:`optimal_a3` gives
the best ``a_3`` for given angles in closed form.  ``H`` belongs to the physical layout: the 48
gene vectors that describe one layout (:func:`equivalent_genes`: reference probe, labels, mirror)
share it, so a best layout is picked with ties (``H`` equal within a relative tolerance) broken by
the canonical member of the class (:func:`select_best`, :func:`canonical_genes`), and the
optimisers' own ties (equal ``H`` in a population) go to the lowest index.

Roundness (Section 3): least-squares circle (limacon model, ``scipy.linalg.lstsq``) and minimum zone
(a linear programme, ``scipy.optimize.linprog``).

Lengths are in any one unit (the separation is linear); the compendium passes millimetres, or
micrometres where it mirrors a paper's printed functions.  Angles are radians.

Why hand-written: the four-point separation, its weights and transfer function, and the adaptive
genetic algorithm are what the paper contributes, so they are written out here to be checked line
by line against its equations; the numerical building blocks come from numpy (FFT) and scipy
(``linalg.lstsq``/``pinv``, ``linalg.circulant``, ``optimize.linprog``, ``optimize.minimize``).
The baseline differential evolution follows the scheme of ``scipy.optimize.differential_evolution``
but is written out batched over runs (:func:`_differential_evolution`): scipy runs one
optimisation at a time, looping over the population in Python, and hundreds of runs are needed.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg
from scipy.optimize import linprog, minimize

TWO_PI = 2.0 * np.pi

#: Probabilities of the improved GA (Section 2.2): crossover Pc max/min, mutation Pm max/min.
PC_MAX, PC_MIN, PM_MAX, PM_MIN = 0.99, 0.4, 0.09, 0.005

#: The search box the paper recommends (Section 3, end) and within which every Table 1 layout lies:
#: phi_1 in [0, pi/4], phi_2 in [pi/4, 3 pi/2], phi_3 in [3 pi/2, 2 pi]; a_3 is our assumption.
PAPER_BOX = ((0.0, np.pi / 4), (np.pi / 4, 1.5 * np.pi), (1.5 * np.pi, TWO_PI), (0.1, 3.0))

#: The whole circle for every probe.
FULL_BOX = ((0.0, TWO_PI), (0.0, TWO_PI), (0.0, TWO_PI), (0.1, 3.0))

_DEGENERATE = 1e-12
#: The reference optimum (:func:`reference_optima`) excludes layouts with |sin(phi_2 - phi_1)|
#: below this (weights above 1e4, closed-form H inaccurate).
_NEAR_DEGENERATE = 1e-4

__all__ = [
    "PAPER_BOX", "FULL_BOX", "PC_MAX", "PC_MIN", "PM_MAX", "PM_MIN",
    "Separation", "GAResult", "CancelledHarmonicsWarning",
    "probe_angles", "weights", "full_weights", "eigenvalues", "transfer", "circulant_matrix",
    "probe_signals", "separate", "separate_details", "separate_least_squares",
    "least_squares_transfer", "rotation_error", "motion_from_scalar",
    "MAPPINGS", "objective_H", "objective_worst", "fitness", "optimal_a3", "genes_to_layout",
    "lower_bound_H", "weights_bound_H", "bound_layout", "worst_case_bound",
    "adaptive_probabilities", "run_ga", "run_de", "convergence_generation", "reference_optimum",
    "reference_optima",
    "equivalent_genes", "canonical_genes", "select_best", "harmonic_coefficients",
    "lowpass", "lsc_roundness", "mz_roundness", "random_profile", "simulate_measurements",
    "coincidence_ratio",
]


# ----------------------------------------------------------------------------- layout and weights

def probe_angles(positions, n_samples: int) -> np.ndarray:
    """Angles ``2 pi p / N`` of probes at integer sample positions ``p`` (Section 1.3)."""
    p = np.asarray(positions, dtype=float)
    n_samples = _check_n(n_samples)
    if not np.all(np.isfinite(p)) or np.any(p != np.round(p)):
        raise ValueError(f"probe positions must be integer sample indices, got {positions!r}")
    return TWO_PI * p / n_samples


def _check_n(n) -> int:
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 8:
        raise ValueError(f"samples per revolution must be an integer >= 8, got {n!r}")
    return int(n)


def _split_phi(phi) -> np.ndarray:
    """``(..., 3)`` angles phi_1..phi_3 from ``(..., 3)`` or ``(..., 4)`` with phi_0 = 0."""
    phi = np.asarray(phi, dtype=float)
    if phi.ndim == 0 or phi.shape[-1] not in (3, 4):
        raise ValueError("phi must hold the probe angles phi_1..phi_3 (last axis 3) or "
                         f"phi_0..phi_3 with phi_0 = 0 (last axis 4); got shape {phi.shape}")
    if not np.all(np.isfinite(phi)):
        raise ValueError("probe angles must be finite")
    if phi.shape[-1] == 4:
        if np.any(np.abs(np.angle(np.exp(1j * phi[..., 0]))) > 1e-12):
            raise ValueError("the first probe defines the x axis: phi_0 must be 0 (Eqs. 5, 15)")
        phi = phi[..., 1:]
    return phi


def _raw_weights(phi3, a3):
    """Eq. 15 without checks: ``phi3`` (..., 3), ``a3`` broadcastable; inf/nan if degenerate."""
    f1, f2, f3 = phi3[..., 0], phi3[..., 1], phi3[..., 2]
    s = np.sin(f2 - f1)
    with np.errstate(divide="ignore", invalid="ignore"):
        a1 = (a3 * np.sin(f3 - f2) - np.sin(f2)) / s
        a2 = -(a3 * np.sin(f3 - f1) - np.sin(f1)) / s
    bad = np.abs(s) < _DEGENERATE
    return np.where(bad, np.inf, a1), np.where(bad, np.inf, a2)


def weights(phi, a3):
    """Weights ``(a1, a2)`` that cancel the first harmonic, given ``a3`` (Eq. 5 = Eq. 15, a0 = 1).

    ``phi``: probe angles phi_1..phi_3 (last axis 3) or phi_0..phi_3 with phi_0 = 0 (last axis 4),
    in radians; batched over leading axes, broadcast against ``a3``.  Refuses layouts with
    ``sin(phi_2 - phi_1) = 0`` (probes 1 and 2 coincident or opposite), where Eq. 15 has no
    solution.
    """
    phi3 = _split_phi(phi)
    a3 = np.asarray(a3, dtype=float)
    if not np.all(np.isfinite(a3)):
        raise ValueError("a3 must be finite")
    if np.any(np.abs(np.sin(phi3[..., 1] - phi3[..., 0])) < _DEGENERATE):
        raise ValueError("sin(phi_2 - phi_1) = 0: probes 1 and 2 are coincident or opposite, "
                         "Eq. 15 cannot give a1, a2; move probe 2")
    a1, a2 = _raw_weights(phi3, a3)
    return a1, a2


def full_weights(phi, a3) -> np.ndarray:
    """``(..., 4)`` weights ``a0..a3`` with ``a0 = 1`` and ``a1, a2`` from :func:`weights`."""
    a1, a2 = weights(phi, a3)
    a3 = np.broadcast_to(np.asarray(a3, dtype=float), np.shape(a1))
    return np.stack([np.ones_like(a1), a1, a2, a3], axis=-1)


def _full(phi, w):
    """Angles and weights as ``(..., 4)`` arrays (a leading phi_0 = 0, a0 = 1 added if omitted)."""
    phi3 = _split_phi(phi)
    phi4 = np.concatenate([np.zeros(phi3.shape[:-1] + (1,)), phi3], axis=-1)
    w = np.asarray(w, dtype=float)
    if w.ndim == 0 or w.shape[-1] not in (3, 4):
        raise ValueError("weights must be a1..a3 (last axis 3, a0 = 1) or a0..a3 (last axis 4); "
                         f"got shape {w.shape}")
    if w.shape[-1] == 3:
        w = np.concatenate([np.ones(w.shape[:-1] + (1,)), w], axis=-1)
    return phi4, w


def eigenvalues(phi, w, harmonics) -> np.ndarray:
    """``Lambda_k = lambda_k + i mu_k = sum_l a_l exp(i k phi_l)`` (Eq. 14), shape (..., K)."""
    phi4, w = _full(phi, w)
    k = np.asarray(harmonics, dtype=float)
    return np.einsum("...l,...kl->...k", w,
                     np.exp(1j * k[..., :, None] * phi4[..., None, :]))


def transfer(phi, w, harmonics) -> np.ndarray:
    """Error transfer function ``q_k^2 = sum a_l^2 / (lambda_k^2 + mu_k^2)`` (Eqs. 14, 19).

    ``phi``: angles (last axis 3 or 4, see :func:`weights`); ``w``: a1..a3 or a0..a3;
    ``harmonics``: the orders k.  Returns ``q_k^2`` per harmonic (``inf`` where the layout cancels
    the harmonic, always at k = 1).  With white sensor noise of standard deviation ``sigma`` the
    estimated Fourier coefficients ``A_k, B_k`` of the profile have variance
    ``2 q_k^2 sigma^2 / N`` (Eq. 18 prints ``2 q_k^2 sigma^2``, without the ``1/N`` its own
    definition of ``F_k, G_k`` implies).
    """
    phi4, w = _full(phi, w)
    lam = eigenvalues(phi4, w, harmonics)
    num = (w ** 2).sum(axis=-1)[..., None]
    den = np.abs(lam) ** 2
    with np.errstate(divide="ignore"):
        q2 = num / den
    cancelled = den <= (1e-24 * num)
    return np.where(cancelled, np.inf, q2)


def circulant_matrix(positions, w, n_samples: int) -> np.ndarray:
    """The matrix ``A`` of Eq. 6: ``(A r)(n) = sum_l a_l r(n + p_l)``, built with
    ``scipy.linalg.circulant``; its eigenvalues are ``Lambda_k`` of :func:`eigenvalues`.

    (The printed definition, ``eps_{p, q + p_l} = 1`` when ``p = q``, would make ``A`` diagonal;
    the intended one is ``A[p, q] = sum_l a_l [q = p + p_l mod N]``.)
    """
    n_samples = _check_n(n_samples)
    p = np.asarray(positions)
    if p.shape != (4,) or np.any(p != np.round(p)):
        raise ValueError(f"positions must be 4 integer sample indices p_0..p_3, got {positions!r}")
    _, w = _full(np.zeros(4), w)
    c = np.zeros(n_samples)
    np.add.at(c, p.astype(int) % n_samples, w)
    return scipy.linalg.circulant(c).T


# ----------------------------------------------------------------------------- the separation

def probe_signals(profile, dx, dy, positions) -> np.ndarray:
    """Four-probe signals ``(..., 4, N)`` of Eq. 7 from a profile and an error motion ``(..., N)``.

    ``positions`` are the integer sample indices ``p_l`` (``p_0 = 0`` included); sample ``n`` of
    probe ``l`` reads the profile at sample ``n + p_l``.
    """
    r = np.asarray(profile, dtype=float)
    n = r.shape[-1]
    phi = probe_angles(positions, n)
    if len(phi) != 4 or phi[0] != 0:
        raise ValueError(f"need 4 probe positions with p_0 = 0, got {positions!r}")
    p = np.asarray(positions, dtype=int)
    idx = (np.arange(n)[None, :] + p[:, None]) % n                      # (4, N)
    shifted = r[..., idx]                                                # (..., 4, N)
    dx = np.asarray(dx, dtype=float)[..., None, :]
    dy = np.asarray(dy, dtype=float)[..., None, :]
    return shifted + dx * np.cos(phi)[:, None] + dy * np.sin(phi)[:, None]


@dataclass
class Separation:
    """Everything :func:`separate_details` finds; ``(profile, dx, dy)`` is what :func:`separate`
    returns."""

    profile: np.ndarray            # (..., N) profile with the reconstructed first harmonic
    dx: np.ndarray                 # (..., N) error motion along x
    dy: np.ndarray                 # (..., N) error motion along y
    profile_no_first: np.ndarray   # (..., N) the pseudo-inverse solution of Eq. 6 (no 1st harmonic)
    first_harmonic: np.ndarray     # (..., 2) C, D: the profile's first harmonic C cos + D sin
    cancelled: np.ndarray          # harmonics 0..N/2 set aside (|Lambda_k| ~ 0), always has 1
    rank: int                      # rank of the Eq. 6 matrix = N - number of cancelled DFT bins
    residual_rms: np.ndarray       # (...,) rms misfit of the 4-probe least squares for dx, dy
    convention: str = "eccentricity"
    eigen: np.ndarray = field(default=None, repr=False)  # Lambda_k, k = 0..N-1


def _check_signals(signals, phi, w, check):
    y = np.asarray(signals, dtype=float)
    if y.ndim < 2 or y.shape[-2] != 4:
        raise ValueError(f"signals must have shape (..., 4, N), got {y.shape}")
    n = _check_n(y.shape[-1])
    if not np.all(np.isfinite(y)):
        raise ValueError("signals contain NaN or inf")
    phi4, w = _full(phi, w)
    if phi4.shape != (4,) or w.shape != (4,):
        raise ValueError("separate takes one layout: phi of shape (3,) or (4,), weights of "
                         "shape (3,) or (4,)")
    p = phi4 * n / TWO_PI
    if np.any(np.abs(p - np.round(p)) > 1e-6):
        raise ValueError(
            "the matrix method shifts the profile by whole samples: every probe angle must be "
            f"2 pi p / N with integer p (N = {n}); the nearest positions are "
            f"{np.round(p).astype(int).tolist()}, at angles {np.round(p) * TWO_PI / n}")
    lam1 = complex(eigenvalues(phi4, w, [1])[0])
    if check and abs(lam1) > 1e-8 * np.abs(w).sum():
        raise ValueError(
            f"the weights do not cancel the first harmonic (lambda_1 = {lam1.real:.4g}, "
            f"mu_1 = {lam1.imag:.4g}; Eq. 14 needs both 0), so the error motion would stay in "
            "the combined signal; compute a1, a2 with weights(phi, a3), or pass check=False")
    return y, n, phi4, w, np.round(p).astype(int) % n


class CancelledHarmonicsWarning(UserWarning):
    """:func:`separate` was told (``allow_cancelled=True``) to proceed on a layout whose weights
    cancel harmonics besides the first; the separated profile lacks them."""


def _harmonic_list(ks, limit: int = 12) -> str:
    ks = [int(k) for k in ks]
    if len(ks) <= limit:
        return ", ".join(map(str, ks))
    return (", ".join(map(str, ks[:limit - 2])) + f", ..., {ks[-1]} ({len(ks)} harmonics"
            + ("; every odd one" if ks == list(range(ks[0], ks[-1] + 1, 2)) and ks[0] % 2 else "")
            + ")")


def separate_details(signals, phi, w, *, first_harmonic: str = "eccentricity",
                     rcond: float = 1e-9, check: bool = True,
                     allow_cancelled: bool = False, max_harmonic: int | None = None) -> Separation:
    """Four-point separation with the matrix method (Eqs. 3-10); see :func:`separate`.

    Steps: combined signal ``Y = sum a_l y_l``; ``R_k = Y_k / Lambda_k`` for every DFT bin with
    ``|Lambda_k| > rcond * max|Lambda|`` (the pseudo-inverse of Eq. 6's circulant matrix, computed
    by FFT; equal to ``scipy.linalg.lstsq(A, Y)``), the others set aside; ``dx, dy`` at each sample
    by least squares over the four probes after removing the profile; the first harmonic by the
    chosen ``first_harmonic`` convention (module docstring).

    A layout whose weights cancel a harmonic other than the first (``|Lambda_k|`` below the
    threshold, e.g. a probe at 180 degrees with ``a3 = 1``, which cancels every odd one) cannot
    recover it: the profile would silently lose it.  Such a layout is refused with a
    ``ValueError`` naming the harmonics; ``allow_cancelled=True`` proceeds without them and
    warns (:class:`CancelledHarmonicsWarning`), naming them.  ``max_harmonic``: the highest
    harmonic the signals can contain (e.g. after :func:`lowpass`); a cancelled harmonic above it
    loses nothing and is set aside without complaint.
    """
    if first_harmonic not in ("eccentricity", "radial"):
        raise ValueError(f"first_harmonic must be 'eccentricity' or 'radial', "
                         f"got {first_harmonic!r}")
    if not (0 < rcond < 1):
        raise ValueError(f"rcond must be in (0, 1), got {rcond!r}")
    y, n, phi4, w, p = _check_signals(signals, phi, w, check)
    if max_harmonic is None:
        max_harmonic = n // 2
    if isinstance(max_harmonic, bool) or not isinstance(max_harmonic, int | np.integer) \
            or not 1 <= max_harmonic <= n // 2:
        raise ValueError(f"max_harmonic must be an integer in 1..N/2 = {n // 2}, "
                         f"got {max_harmonic!r}")

    # Profile without the cancelled harmonics: pseudo-inverse of the circulant matrix by FFT.
    big_y = np.einsum("l,...ln->...n", w, y)
    lam = eigenvalues(phi4, w, np.arange(n))            # numpy's FFT: shift +p -> exp(+i k phi)
    keep = np.abs(lam) > rcond * np.abs(lam).max()
    keep[[1, n - 1]] = False                            # cancelled by design (Eq. 15)
    inv = np.zeros(n, dtype=complex)
    inv[keep] = 1.0 / lam[keep]
    r0 = np.fft.ifft(np.fft.fft(big_y, axis=-1) * inv, axis=-1).real
    harm = np.arange(n // 2 + 1)
    cancelled = harm[~keep[: n // 2 + 1]]
    extra = cancelled[(cancelled != 1) & (cancelled <= max_harmonic)]
    if extra.size:
        msg = (f"the layout (probe positions {p.tolist()} of N = {n}, weights "
               f"{np.round(w, 4).tolist()}) cancels harmonic(s) {_harmonic_list(extra)} besides "
               f"the first (|Lambda_k| <= rcond * max|Lambda| = {rcond:g} * "
               f"{np.abs(lam).max():.4g}): the separated profile would lack them")
        if not allow_cancelled:
            raise ValueError(msg + "; move a probe or change a3, or pass allow_cancelled=True "
                             "to separate without them")
        warnings.warn(msg + " (allow_cancelled=True: proceeding without them)",
                      CancelledHarmonicsWarning, stacklevel=3)

    profile, z, cd, residual_rms = _motion_and_first_harmonic(y, r0, phi4, p, first_harmonic)
    return Separation(profile=profile, dx=z.real, dy=z.imag, profile_no_first=r0,
                      first_harmonic=cd, cancelled=cancelled,
                      rank=int(keep.sum()), residual_rms=residual_rms,
                      convention=first_harmonic, eigen=lam)


def _motion_and_first_harmonic(y, r0, phi4, p, first_harmonic):
    """Given the profile without its first harmonic ``r0`` (..., N): the error motion by least
    squares over the probes at each sample, then the first harmonic by the convention.  Returns
    ``(profile, dx + i dy, (C, D), residual_rms)``."""
    n = y.shape[-1]
    theta = TWO_PI * np.arange(n) / n
    # Error motion (plus what the profile's first harmonic looks like) by least squares per sample.
    idx = (np.arange(n)[None, :] + p[:, None]) % n
    resid = y - r0[..., idx]                                            # (..., 4, N)
    g = np.column_stack([np.cos(phi4), np.sin(phi4)])                   # (4, 2)
    gp = scipy.linalg.pinv(g)                                           # (2, 4)
    dxy = np.einsum("jl,...ln->...jn", gp, resid)                       # (..., 2, N)
    fit = np.einsum("lj,...jn->...ln", g, dxy)
    residual_rms = np.sqrt(((resid - fit) ** 2).mean(axis=(-2, -1)))

    # The first harmonic: the motion component exp(-i theta) is indistinguishable from it.
    z = dxy[..., 0, :] + 1j * dxy[..., 1, :]
    if first_harmonic == "eccentricity":
        c = (z * np.exp(1j * theta)).mean(axis=-1)                      # coefficient of e^{-i th}
    else:
        tang = (z * np.exp(-1j * theta)).imag                           # = D cos 2t - C sin 2t
        c = -2 * (tang * np.sin(2 * theta)).mean(axis=-1) \
            + 2j * (tang * np.cos(2 * theta)).mean(axis=-1)
    cc, dd = c.real, c.imag
    z = z - c[..., None] * np.exp(-1j * theta)
    profile = r0 + cc[..., None] * np.cos(theta) + dd[..., None] * np.sin(theta)
    return profile, z, np.stack([cc, dd], axis=-1), residual_rms


# ------------------------------------------------ least squares over all probes (multi-probe)

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
    """Noise amplification of the least-squares multi-probe estimator, per harmonic: the variance
    of the estimated profile harmonic ``R_k`` in units of one probe's noise variance at that
    harmonic, ``[(A_k^H A_k)^-1]_00`` with ``A_k`` (probes x 3) the readings of the profile
    harmonic and of the two motion components (:func:`separate_least_squares`).

    The counterpart of :func:`transfer` (``q_k^2`` of the weighted four-point method, in the same
    units).  By the Gauss-Markov theorem it is never larger than ``q_k^2`` of any weights that
    cancel the motion (a test checks it).  ``inf`` where the layout cannot separate the harmonic
    (always k = 1: ``exp(i phi)`` is ``cos phi + i sin phi``).  ``phi``: probe angles (last axis
    3, with phi_0 = 0, or the full list of L >= 3 angles)."""
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
    """Profile and radial error motion from multi-probe signals by least squares, harmonic by
    harmonic, over all probes: for each DFT bin k the probes read ``Y_l(k) = R_k exp(i k phi_l)
    + X_k cos(phi_l) + Y_k sin(phi_l)``; the three unknowns are fitted to the L >= 3 readings
    (``numpy.linalg.lstsq`` per bin, batched by the pseudo-inverse).  The first harmonic, which
    no probe layout separates, is set by ``first_harmonic`` exactly as in :func:`separate`.

    This is the estimator of the public multi-probe roundness tools, written beside the paper's
    weighted four-point method (:func:`separate_details`): it needs no weights, uses every probe
    at every harmonic, and its noise amplification (:func:`least_squares_transfer`) is the
    smallest of any linear unbiased estimator (Gauss-Markov), e.g. a worst case over harmonics
    2..20 of 6.4 on Yang et al.'s layout against 112.9 for their weights.  Same arguments and
    result as :func:`separate_details` (``eigen`` holds the smallest singular value of each
    bin's design, ``rank`` the number of bins solved in full); ``signals`` may have any number
    L >= 3 of probes, ``phi`` their L angles (or L - 1 with phi_0 = 0)."""
    if first_harmonic not in ("eccentricity", "radial"):
        raise ValueError(f"first_harmonic must be 'eccentricity' or 'radial', "
                         f"got {first_harmonic!r}")
    if not (0 < rcond < 1):
        raise ValueError(f"rcond must be in (0, 1), got {rcond!r}")
    y = np.asarray(signals, dtype=float)
    if y.ndim < 2 or y.shape[-2] < 3:
        raise ValueError(f"signals must have shape (..., L, N) with L >= 3 probes, got {y.shape}")
    n = _check_n(y.shape[-1])
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
    if max_harmonic is None:
        max_harmonic = n // 2
    if isinstance(max_harmonic, bool) or not isinstance(max_harmonic, int | np.integer) \
            or not 1 <= max_harmonic <= n // 2:
        raise ValueError(f"max_harmonic must be an integer in 1..N/2 = {n // 2}, "
                         f"got {max_harmonic!r}")
    a = _ls_design(phi, np.arange(n))                                    # (N, L, 3)
    sv = np.linalg.svd(a, compute_uv=False)
    keep = sv[:, -1] > rcond * sv[:, 0]
    keep[[1, n - 1]] = False                             # the first harmonic: never separable
    harm = np.arange(n // 2 + 1)
    cancelled = harm[~keep[: n // 2 + 1]]
    extra = cancelled[(cancelled != 1) & (cancelled <= max_harmonic)]
    if extra.size:
        msg = (f"the layout (probe positions {p.tolist()} of N = {n}) cannot separate "
               f"harmonic(s) {_harmonic_list(extra)} besides the first (the profile harmonic "
               f"reads on the probes as a motion would): the separated profile would lack them")
        if not allow_cancelled:
            raise ValueError(msg + "; move a probe, or pass allow_cancelled=True")
        warnings.warn(msg + " (allow_cancelled=True: proceeding without them)",
                      CancelledHarmonicsWarning, stacklevel=2)
    pinv = np.zeros((n, 3, n_probes), dtype=complex)
    pinv[keep] = np.linalg.pinv(a[keep])
    spec = np.fft.fft(y, axis=-1)                                        # (..., L, N)
    r_k = np.einsum("kl,...lk->...k", pinv[:, 0, :], spec)               # profile harmonics
    r0 = np.fft.ifft(r_k, axis=-1).real
    profile, z, cd, residual_rms = _motion_and_first_harmonic(y, r0, phi, p, first_harmonic)
    return Separation(profile=profile, dx=z.real, dy=z.imag, profile_no_first=r0,
                      first_harmonic=cd, cancelled=cancelled, rank=int(keep.sum()),
                      residual_rms=residual_rms, convention=first_harmonic, eigen=sv[:, -1])


def separate(signals, phi, w, *, first_harmonic: str = "eccentricity", rcond: float = 1e-9,
             check: bool = True, allow_cancelled: bool = False, max_harmonic: int | None = None):
    """Separate the profile and the radial error motion from four probe signals.

    Parameters
    ----------
    signals : (..., 4, N) probe readings ``y_0..y_3`` (Eq. 7), batched over leading axes.
    phi : probe angles phi_1..phi_3 (or phi_0..phi_3 with phi_0 = 0), on the sampling grid
        ``2 pi p / N`` (the matrix method shifts by whole samples; other angles are refused).
    w : weights a1..a3 (a0 = 1) or a0..a3; they must cancel the first harmonic (Eq. 15) unless
        ``check=False`` (used to show what non-cancelling weights do).
    first_harmonic : ``"eccentricity"`` or ``"radial"``, the convention that splits the profile's
        first harmonic from the motion (module docstring).
    rcond : harmonics with ``|Lambda_k| <= rcond * max|Lambda|`` are set aside (not recoverable).
    allow_cancelled : a layout that cancels a harmonic other than the first is refused
        (``ValueError`` naming them) unless this is True; then it proceeds without them and
        warns with :class:`CancelledHarmonicsWarning`, naming them.
    max_harmonic : the highest harmonic the signals can contain (default N/2); cancelled
        harmonics above it are set aside silently, as they carry nothing.

    Returns
    -------
    profile, dx, dy : arrays (..., N).  :func:`separate_details` returns the intermediate results
    (the pseudo-inverse profile, ``C, D``, the cancelled harmonics, the matrix rank).
    """
    s = separate_details(signals, phi, w, first_harmonic=first_harmonic, rcond=rcond,
                         check=check, allow_cancelled=allow_cancelled,
                         max_harmonic=max_harmonic)
    return s.profile, s.dx, s.dy


def rotation_error(dx, dy, theta=None) -> np.ndarray:
    """Scalar radial error ``delta = dx cos(theta) + dy sin(theta)`` of Eq. 9 (rotating
    direction)."""
    dx, dy = np.asarray(dx, dtype=float), np.asarray(dy, dtype=float)
    if theta is None:
        theta = TWO_PI * np.arange(dx.shape[-1]) / dx.shape[-1]
    return dx * np.cos(theta) + dy * np.sin(theta)


#: Ways to turn the paper's scalar rotation error delta(theta) into (dx, dy), and back.
MAPPINGS = {
    "radial": "dx = delta cos(theta), dy = delta sin(theta): radial along the rotating direction "
              "(the inverse of Eq. 9, delta = dx cos + dy sin)",
    "radial_reversed": "dx = delta cos(theta), dy = -delta sin(theta): radial along the direction "
                       "turning with the workpiece (y = r(theta + phi) turns it by -theta)",
    "x_only": "dx = delta, dy = 0: a fixed sensitive direction along the first probe",
}


def motion_from_scalar(delta, mapping: str = "radial", theta=None):
    """``(dx, dy)`` from a scalar rotation error under one of :data:`MAPPINGS`; also returns the
    inverse map as a function ``(dx, dy) -> delta``."""
    delta = np.asarray(delta, dtype=float)
    if theta is None:
        theta = TWO_PI * np.arange(delta.shape[-1]) / delta.shape[-1]
    c, s = np.cos(theta), np.sin(theta)
    if mapping == "radial":
        return delta * c, delta * s, lambda dx, dy: dx * c + dy * s
    if mapping == "radial_reversed":
        return delta * c, -delta * s, lambda dx, dy: dx * c - dy * s
    if mapping == "x_only":
        return delta, np.zeros_like(delta), lambda dx, dy: np.asarray(dx)
    raise ValueError(f"unknown mapping {mapping!r}; known: {', '.join(MAPPINGS)}")


def harmonic_coefficients(signal, harmonics) -> tuple[np.ndarray, np.ndarray]:
    """``A_k, B_k`` with ``signal = A_0 + sum A_k cos k theta + B_k sin k theta`` (Eq. 12)."""
    x = np.asarray(signal, dtype=float)
    n = x.shape[-1]
    k = np.asarray(harmonics)
    if np.any((k < 1) | (k >= n / 2)):
        raise ValueError(f"harmonics must be in 1..N/2-1 = {n // 2 - 1}")
    spec = np.fft.rfft(x, axis=-1)[..., k] * 2 / n
    return spec.real, -spec.imag


# ----------------------------------------------------------------------------- objective

def _genes(x):
    x = np.asarray(x, dtype=float)
    if x.ndim == 0 or x.shape[-1] != 4:
        raise ValueError(f"genes must be (..., 4) = phi_1, phi_2, phi_3, a_3; got shape {x.shape}")
    return x


def genes_to_layout(x):
    """Genes ``(phi_1, phi_2, phi_3, a_3)`` -> angles ``(..., 4)`` with phi_0 = 0 and weights
    ``(..., 4)`` with a0 = 1 (a1, a2 from Eq. 15; inf for degenerate layouts)."""
    x = _genes(x)
    a1, a2 = _raw_weights(x[..., :3], x[..., 3])
    phi = np.concatenate([np.zeros(x.shape[:-1] + (1,)), x[..., :3]], axis=-1)
    w = np.stack([np.ones_like(a1), a1, a2, x[..., 3]], axis=-1)
    return phi, w


def objective_H(x, k) -> np.ndarray:
    """``H = q_k^2`` (Eq. 20) of genes ``x = (..., 4)`` at harmonic ``k`` (broadcast against
    ``x[..., 0]``); ``inf`` for degenerate or cancelling layouts."""
    x = _genes(x)
    k = np.asarray(k, dtype=float)
    if np.any(k < 2) or np.any(k != np.round(k)):
        raise ValueError("the harmonic order k must be an integer >= 2 (k = 1 is cancelled by "
                         "design: lambda_1 = mu_1 = 0)")
    a1, a2 = _raw_weights(x[..., :3], x[..., 3])
    a3 = x[..., 3]
    f1, f2, f3 = x[..., 0], x[..., 1], x[..., 2]
    with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
        lam = 1 + a1 * np.cos(k * f1) + a2 * np.cos(k * f2) + a3 * np.cos(k * f3)
        mu = a1 * np.sin(k * f1) + a2 * np.sin(k * f2) + a3 * np.sin(k * f3)
        h = (1 + a1 ** 2 + a2 ** 2 + a3 ** 2) / (lam ** 2 + mu ** 2)
    return np.where(np.isfinite(h), h, np.inf)


def objective_worst(x, harmonics) -> np.ndarray:
    """Worst case over harmonics: ``max_k q_k^2`` for every ``k`` in ``harmonics`` (beyond the
    paper, which protects one harmonic at a time)."""
    x = _genes(x)
    ks = np.asarray(harmonics)
    if ks.ndim != 1 or ks.size == 0 or np.any(ks < 2):
        raise ValueError("harmonics must be a non-empty list of orders >= 2")
    h = objective_H(x[..., None, :], ks)
    return h.max(axis=-1)


def fitness(h) -> np.ndarray:
    """``F = 1/H`` (Eq. 21); 0 where ``H`` is infinite."""
    h = np.asarray(h, dtype=float)
    with np.errstate(divide="ignore"):
        return np.where(np.isfinite(h) & (h > 0), 1.0 / h, 0.0)


def optimal_a3(phi, k, a3_bounds=(-np.inf, np.inf)):
    """The ``a_3`` minimising ``H`` for given angles, in closed form, and that ``H``.

    ``a1, a2`` are affine in ``a3``, so ``H(a3)`` is a ratio of two quadratics; its stationary
    points solve a quadratic, and the minimum over an interval is at one of them or an end.
    ``phi``: (..., 3) angles phi_1..phi_3; returns ``(a3, H)`` of shape (...).
    """
    phi3 = _split_phi(phi)
    lo, hi = a3_bounds
    if not lo < hi:
        raise ValueError(f"a3_bounds must be (low, high) with low < high, got {a3_bounds!r}")
    k = np.asarray(k, dtype=float)
    # a = u + a3 v (a0..a3) with u = (1, u1, u2, 0), v = (0, v1, v2, 1) from Eq. 15;
    # H = (a.a) / |c.a|^2 with c_l = exp(i k phi_l), written out in real arithmetic
    f1, f2, f3 = phi3[..., 0], phi3[..., 1], phi3[..., 2]
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        sd = np.sin(f2 - f1)
        sd = np.where(np.abs(sd) < _DEGENERATE, np.nan, sd)
        u1, u2 = -np.sin(f2) / sd, np.sin(f1) / sd
        v1, v2 = np.sin(f3 - f2) / sd, -np.sin(f3 - f1) / sd
        c1, c2, c3 = np.cos(k * f1), np.cos(k * f2), np.cos(k * f3)
        s1, s2, s3 = np.sin(k * f1), np.sin(k * f2), np.sin(k * f3)
        cur, cui = 1 + u1 * c1 + u2 * c2, u1 * s1 + u2 * s2
        cvr, cvi = v1 * c1 + v2 * c2 + c3, v1 * s1 + v2 * s2 + s3
        p0, p1, p2 = 1 + u1 ** 2 + u2 ** 2, 2 * (u1 * v1 + u2 * v2), v1 ** 2 + v2 ** 2 + 1
        q0, q1, q2 = cur ** 2 + cui ** 2, 2 * (cur * cvr + cui * cvi), cvr ** 2 + cvi ** 2
        qa, qb, qc = p2 * q1 - p1 * q2, 2 * (p2 * q0 - p0 * q2), p1 * q0 - p0 * q1
        disc = np.sqrt(np.maximum(qb ** 2 - 4 * qa * qc, 0))
        roots = np.stack([(-qb + disc) / (2 * qa), (-qb - disc) / (2 * qa), -qc / qb], axis=-1)
    cands = np.concatenate([roots, np.broadcast_to(np.array([lo, hi], dtype=float),
                                                   roots.shape[:-1] + (2,))], axis=-1)
    cands = np.where(np.isfinite(cands) & (cands >= lo) & (cands <= hi), cands, np.nan)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        a = cands
        h = (p0[..., None] + p1[..., None] * a + p2[..., None] * a ** 2) / (
            q0[..., None] + q1[..., None] * a + q2[..., None] * a ** 2)
    h = np.where(np.isfinite(h) & (h > 0), h, np.inf)
    best = np.argmin(h, axis=-1)
    a3 = np.take_along_axis(a, best[..., None], -1)[..., 0]
    hb = np.take_along_axis(h, best[..., None], -1)[..., 0]
    return a3, hb


def lower_bound_H(n_probes: int = 4) -> float:
    """``H >= 1/n`` for ``n`` probes at every harmonic.

    ``|Lambda_k| = |sum a_l e^{i k phi_l}| <= sum |a_l| <= sqrt(n sum a_l^2)`` (triangle and
    Cauchy-Schwarz inequalities), so ``q_k^2 >= 1/n``; equality needs ``|a_l|`` all equal and
    ``a_l e^{i k phi_l}`` all in phase.  With four probes and ``sum a_l e^{i phi_l} = 0`` this is
    possible exactly when ``k`` is even (:func:`bound_layout`).
    """
    if isinstance(n_probes, bool) or not isinstance(n_probes, int) or n_probes < 3:
        raise ValueError(f"n_probes must be an integer >= 3, got {n_probes!r}")
    return 1.0 / n_probes


def weights_bound_H(w, half_units=None) -> np.ndarray:
    """Lower bound of ``H = q_k^2`` that depends on the weights only: valid for every choice of
    probe angles and every harmonic ``k``.

    ``w``: weights ``a1..a3`` (last axis 3, ``a0 = 1`` exact) or ``a0..a3`` (last axis 4),
    batched over leading axes.  ``half_units`` (same shape, optional): half-widths of the
    intervals ``[w - half_units, w + half_units]`` the weights are only known to lie in (e.g. half
    a unit of their last printed digit); the bound then holds for every weight in those intervals.

    Proof.  ``Lambda_k = sum_l a_l exp(i k phi_l)``, so by the triangle inequality
    ``|Lambda_k| <= sum_l |a_l|`` whatever the angles, and therefore

        H = sum_l a_l^2 / |Lambda_k|^2 >= sum_l a_l^2 / (sum_l |a_l|)^2 =: B(a),

    for every ``phi_1, phi_2, phi_3`` and every ``k`` (equality exactly when all ``a_l e^{i k
    phi_l}`` share one phase, e.g. ``k phi_l = 0 mod 2 pi`` with positive weights, so ``B`` is the
    infimum over unconstrained angles).  If ``a_l`` is only known to lie in ``[c_l - h_l, c_l +
    h_l]``, then ``a_l^2 >= m_l^2`` with ``m_l = max(|c_l| - h_l, 0)`` (the distance from 0 to the
    interval) and ``|a_l| <= |c_l| + h_l``, so ``B(a) >= sum m_l^2 / (sum (|c_l| + h_l))^2`` for
    every ``a`` in the intervals.  ``B(a) >= 1/4`` (Cauchy-Schwarz, :func:`lower_bound_H`), with
    equality for equal ``|a_l|``; the interval version can fall slightly below 1/4.  The bound
    does not use Eq. 15: it holds whether or not the weights cancel the first harmonic, and it
    ignores the signs of the weights (a sign lost in print does not change it).
    """
    w = np.asarray(w, dtype=float)
    if w.ndim == 0 or w.shape[-1] not in (3, 4):
        raise ValueError("weights must be a1..a3 (last axis 3, a0 = 1) or a0..a3 (last axis 4); "
                         f"got shape {w.shape}")
    h = np.zeros_like(w) if half_units is None else np.broadcast_to(
        np.asarray(half_units, dtype=float), w.shape)
    if not (np.all(np.isfinite(w)) and np.all(np.isfinite(h))) or np.any(h < 0):
        raise ValueError("weights must be finite and half_units finite and >= 0")
    if w.shape[-1] == 3:
        w = np.concatenate([np.ones(w.shape[:-1] + (1,)), w], axis=-1)
        h = np.concatenate([np.zeros(h.shape[:-1] + (1,)), h], axis=-1)
    low = np.maximum(np.abs(w) - h, 0.0)
    high = np.abs(w) + h
    if np.any(high.sum(axis=-1) == 0):
        raise ValueError("all weights are zero: H is undefined")
    return (low ** 2).sum(axis=-1) / high.sum(axis=-1) ** 2


def bound_layout(k: int, m: int = 1) -> np.ndarray:
    """Genes of a layout reaching ``H = 1/4`` at even ``k``: two diametral pairs,
    ``phi = (0, 2 pi m / k, pi, pi + 2 pi m / k)``, ``a = (1, 1, 1, 1)`` (for k = 2:
    ``(0, pi/2, pi, 3 pi/2)``, ``a = (1, -1, 1, -1)``).  It also cancels every odd harmonic:
    ``Lambda_j = (1 + e^{i j pi})(1 + e^{i j phi_1})``."""
    if not isinstance(k, int | np.integer) or k < 2 or k % 2:
        raise ValueError(f"H = 1/4 is reachable only at even k >= 2 (got {k!r}); for odd k the "
                         "infimum is larger, see reference_optimum")
    if k == 2:   # phi_1 = 2 pi m / k would fall on probe 2; use a1 = a3 = -1 at pi/2, 3pi/2
        return np.array([np.pi / 2, np.pi, 1.5 * np.pi, -1.0])
    if not 0 < 2 * m < k:
        raise ValueError(f"m must satisfy 0 < 2m < k, got m={m!r}")
    f1 = TWO_PI * m / k
    return np.array([f1, np.pi, np.pi + f1, 1.0])


def worst_case_bound(n_samples: int) -> float:
    """Lower bound of ``max_{k=2..N-2} q_k^2`` for probes on the sampling grid: ``(N - 3) / N``.

    Parseval: ``sum_{k=0}^{N-1} |Lambda_k|^2 = N sum a_l^2`` for distinct positions; with
    ``Lambda_1 = Lambda_{N-1} = 0`` the smallest of the other ``N - 3`` terms is at most
    ``N sum a_l^2 / (N - 3)``.
    """
    n = _check_n(n_samples)
    return (n - 3) / n


# ----------------------------------------------------------------------------- genetic algorithms

def adaptive_probabilities(f, f_mean, generation, max_generation, *, pc_max=PC_MAX,
                           pc_min=PC_MIN, pm_max=PM_MAX, pm_min=PM_MIN,
                           eq23: str = "corrected"):
    """Crossover and mutation probabilities of the improved GA (Eqs. 22-23).

    ``Pc = Pc_max`` if ``F < F_mean``, else ``Pc_max - (Pc_max - Pc_min) alpha / alpha_max``;
    ``Pm = Pm_min`` if ``F < F_mean``, else, as printed (``eq23="printed"``),
    ``Pm_min - (Pm_max - Pm_min) alpha / alpha_max``, which falls from ``Pm_min`` and is negative
    once ``alpha / alpha_max > Pm_min / (Pm_max - Pm_min)`` (after 6 % of the run with the paper's
    values); corrected (default), ``Pm_min + (Pm_max - Pm_min) alpha / alpha_max``, rising from
    0.005 to 0.09 as the text describes.  ``alpha`` = ``generation``, ``alpha_max`` =
    ``max_generation``.
    Returns the raw values (the printed Eq. 23 is not clipped here; :func:`run_ga` clips to [0, 1]).
    """
    if eq23 not in ("corrected", "printed"):
        raise ValueError(f"eq23 must be 'corrected' or 'printed', got {eq23!r}")
    if not 0 <= generation <= max_generation or max_generation < 1:
        raise ValueError(f"need 0 <= generation <= max_generation (>= 1), got {generation!r}, "
                         f"{max_generation!r}")
    if not (0 <= pc_min <= pc_max <= 1 and 0 <= pm_min <= pm_max <= 1):
        raise ValueError("need 0 <= pc_min <= pc_max <= 1 and 0 <= pm_min <= pm_max <= 1")
    f = np.asarray(f, dtype=float)
    above = f >= np.asarray(f_mean, dtype=float)
    frac = generation / max_generation
    pc = np.where(above, pc_max - (pc_max - pc_min) * frac, pc_max)
    sign = 1.0 if eq23 == "corrected" else -1.0
    pm = np.where(above, pm_min + sign * (pm_max - pm_min) * frac, pm_min)
    return pc, pm


@dataclass
class GAResult:
    """Runs of a genetic algorithm (or of differential evolution), batched over runs."""

    best_x: np.ndarray      # (runs, 4) best genes found
    best_h: np.ndarray      # (runs,) best objective
    history: np.ndarray     # (generations + 1, runs) best-so-far objective; row 0 = initial pop.
    pc: np.ndarray          # (generations + 1,) mean crossover probability used
    pm: np.ndarray          # (generations + 1,) mean mutation probability used
    evaluations_per_generation: int
    label: str = ""


def _box(bounds):
    b = np.asarray(bounds, dtype=float)
    if b.shape != (4, 2) or not np.all(np.isfinite(b)) or np.any(b[:, 0] >= b[:, 1]):
        raise ValueError("bounds must be four (low, high) pairs with low < high for "
                         f"phi_1, phi_2, phi_3, a_3; got {bounds!r}")
    return b[:, 0], b[:, 1]


def _reflect(x, lo, hi):
    w = hi - lo
    y = np.mod(x - lo, 2 * w)
    return lo + np.where(y > w, 2 * w - y, y)


def _make_objective(k, harmonics, n_runs):
    """``objective(x, runs=all)``: H of genes ``x`` (len(runs), pop, 4) for those runs."""
    if (k is None) == (harmonics is None):
        raise ValueError("give either k (one harmonic, Eq. 20) or harmonics (worst case)")
    if harmonics is not None:
        hs = np.asarray(harmonics)
        objective_worst(np.zeros(4) + 1.0, hs)  # validates
        return lambda x, runs=None: objective_worst(x, hs)
    ks = np.broadcast_to(np.asarray(k), (n_runs,)).astype(float)
    objective_H(np.array([0.3, 2.0, 5.0, 1.0]), ks)  # validates k

    def objective(x, runs=None):
        return objective_H(x, (ks if runs is None else ks[runs])[:, None])
    return objective


def run_ga(k=None, *, harmonics=None, bounds=PAPER_BOX, n_runs: int = 32, pop_size: int = 50,
           generations: int = 200, seed=0, adaptive: bool = True, pc: float = 0.8,
           pm: float = 0.05, eq23: str = "corrected", encoding: str = "real",
           mutation_scale: float = 0.1, bits: int = 16,
           pc_max=PC_MAX, pc_min=PC_MIN, pm_max=PM_MAX, pm_min=PM_MIN) -> GAResult:
    """Genetic algorithm minimising ``H`` (fitness ``1/H``, Eq. 21), ``n_runs`` runs at once.

    Hand-written because the adaptive crossover and mutation rates (Eqs. 22-23) are the paper's
    contribution.  The paper gives neither the encoding nor the operators; ours, stated here:
    genes ``(phi_1, phi_2, phi_3, a_3)`` in ``bounds``; uniform initial population;
    roulette-wheel (fitness-proportional) selection; consecutive selected parents paired and
    crossed with probability ``Pc`` per pair; elitism (the best so far replaces the worst child).

    ``encoding="real"``: arithmetic crossover (child = ``b x1 + (1 - b) x2``, ``b ~ U(0, 1)`` per
    gene); each gene mutated with probability ``Pm`` by a Gaussian step of ``mutation_scale`` x
    its range, reflected into the box.  ``encoding="binary"``: each gene a ``bits``-bit integer
    over its range (the classic GA of the toolboxes of the time); single-point crossover; each bit
    flipped with probability ``Pm``.

    ``adaptive=False``: the traditional GA, fixed ``pc`` and ``pm``.  ``adaptive=True``: Eq. 22 for
    ``Pc`` with ``F`` the fitness of the fitter parent of the pair, Eq. 23 for ``Pm`` with ``F`` the
    fitness of the child's own parent; ``F_mean`` the mean fitness of the current population;
    ``eq23`` picks the printed or the corrected sign (:func:`adaptive_probabilities`).

    ``k`` (scalar, or one per run) optimises Eq. 20 at that harmonic; ``harmonics`` optimises the
    worst case over them.  Everything is an array over (runs, population); the only loop is over
    generations.  ``seed`` seeds one ``numpy.random.Generator`` (or pass a Generator).
    """
    for name, v, low in (("n_runs", n_runs, 1), ("pop_size", pop_size, 4),
                         ("generations", generations, 1), ("bits", bits, 2)):
        if isinstance(v, bool) or not isinstance(v, int | np.integer) or v < low:
            raise ValueError(f"{name} must be an integer >= {low}, got {v!r}")
    if pop_size % 2:
        raise ValueError(f"pop_size must be even (parents are paired), got {pop_size}")
    if not (0 <= pc <= 1 and 0 <= pm <= 1):
        raise ValueError(f"pc and pm must be probabilities in [0, 1], got {pc!r}, {pm!r}")
    if not mutation_scale > 0:
        raise ValueError(f"mutation_scale must be > 0, got {mutation_scale!r}")
    if encoding not in ("real", "binary"):
        raise ValueError(f"encoding must be 'real' or 'binary', got {encoding!r}")
    if bits > 30:
        raise ValueError(f"bits must be <= 30, got {bits}")
    lo, hi = _box(bounds)
    objective = _make_objective(k, harmonics, n_runs)
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    s, p, d = n_runs, pop_size, 4
    if adaptive:  # validates the probabilities and eq23 once
        adaptive_probabilities(1.0, 1.0, 0, 1, pc_max=pc_max, pc_min=pc_min, pm_max=pm_max,
                               pm_min=pm_min, eq23=eq23)
    binary = encoding == "binary"
    if binary:
        # Genes are stored as integers (runs, pop, 4), bit j of gene i being bit j of the
        # string of 4 * bits (most significant first); random bits are drawn as that string
        # and packed exactly (sums of powers of two below 2**53).
        pow2 = 2.0 ** np.arange(bits - 1, -1, -1)
        gene_no = np.arange(d)

        def pack(bitstring):
            return (bitstring.reshape(bitstring.shape[:-1] + (d, bits)) @ pow2).astype(np.int64)

        def decode(gen):
            return lo + (hi - lo) * gen / (2.0 ** bits - 1)

        geno = pack(rng.random((s, p, d * bits)) < 0.5)
    else:
        def decode(gen):
            return gen

        geno = lo + rng.random((s, p, d)) * (hi - lo)
    h = objective(decode(geno))
    ar = np.arange(s)
    ib = np.argmin(h, axis=1)
    best_g = geno[ar, ib]
    best_h = h[ar, ib]
    hist = [best_h.copy()]
    pcs, pms = [pc if not adaptive else pc_max], [pm if not adaptive else pm_min]
    rows = ar[:, None]
    n_search = int(np.ceil(np.log2(p))) + 1
    for g in range(1, generations + 1):
        f = fitness(h)
        total = f.sum(axis=1, keepdims=True)
        prob = np.where(total > 0, f / np.where(total > 0, total, 1), 1.0 / p)
        cum = np.cumsum(prob, axis=1)
        u = rng.random((s, p))
        # roulette wheel: index = number of cumulative probabilities below u (cum is sorted),
        # found by a batched binary search over the population axis
        low_i = np.zeros((s, p), dtype=np.int64)
        high_i = np.full((s, p), p, dtype=np.int64)
        for _ in range(n_search):
            mid = (low_i + high_i) // 2
            below = cum[rows, np.minimum(mid, p - 1)] < u
            active = low_i < high_i
            low_i = np.where(active & below, mid + 1, low_i)
            high_i = np.where(active & ~below, mid, high_i)
        idx = np.minimum(low_i, p - 1)
        par = geno[rows, idx]
        fpar = f[rows, idx]
        a, b = par[:, 0::2], par[:, 1::2]                    # (s, p/2, genes)
        fa, fb = fpar[:, 0::2], fpar[:, 1::2]
        if adaptive:
            fmean = f.mean(axis=1, keepdims=True)
            pc_pair, _ = adaptive_probabilities(np.maximum(fa, fb), fmean, g, generations,
                                                pc_max=pc_max, pc_min=pc_min, pm_max=pm_max,
                                                pm_min=pm_min, eq23=eq23)
            _, pm_ind = adaptive_probabilities(np.concatenate([fa, fb], 1), fmean, g,
                                               generations, pc_max=pc_max, pc_min=pc_min,
                                               pm_max=pm_max, pm_min=pm_min, eq23=eq23)
            pm_ind = np.clip(pm_ind, 0.0, 1.0)
        else:
            pc_pair = np.full((s, p // 2), pc)
            pm_ind = np.full((s, p), pm)
        cross = (rng.random((s, p // 2)) < pc_pair)[..., None]
        if binary:
            cut = rng.integers(1, d * bits, size=(s, p // 2, 1))
            # single-point crossover at bit `cut` of the string: the tail of gene i is its
            # last bits - clip(cut - i * bits, 0, bits) bits
            tail_bits = bits - np.clip(cut - gene_no * bits, 0, bits)
            swap = np.where(cross, (np.int64(1) << tail_bits) - 1, 0)
            c1 = (a & ~swap) | (b & swap)
            c2 = (b & ~swap) | (a & swap)
        else:
            beta = rng.random((s, p // 2, d))
            c1 = np.where(cross, beta * a + (1 - beta) * b, a)
            c2 = np.where(cross, (1 - beta) * a + beta * b, b)
        child = np.concatenate([c1, c2], axis=1)             # pm_ind is ordered alike
        if binary:
            geno = child ^ pack(rng.random((s, p, d * bits)) < pm_ind[..., None])
        else:
            mut = rng.random(child.shape) < pm_ind[..., None]
            step = rng.normal(size=child.shape) * mutation_scale * (hi - lo)
            geno = _reflect(np.where(mut, child + step, child), lo, hi)
        h = objective(decode(geno))
        # elitism: the best so far replaces the worst child; ties (equal H, e.g. several
        # degenerate layouts with H = inf) go to the lowest population index (argmax/argmin
        # return the first), so a run is a function of its random numbers only
        iw = np.argmax(h, axis=1)
        geno[ar, iw] = best_g
        h[ar, iw] = best_h
        ib = np.argmin(h, axis=1)
        better = h[ar, ib] < best_h
        best_g = np.where(better[:, None], geno[ar, ib], best_g)
        best_h = np.where(better, h[ar, ib], best_h)
        hist.append(best_h.copy())
        pcs.append(float(pc_pair.mean()))
        pms.append(float(pm_ind.mean()))
    label = ("improved GA (Eqs. 22-23" + (", printed Eq. 23)" if eq23 == "printed" else ")")
             if adaptive else f"traditional GA (Pc={pc:g}, Pm={pm:g})")
    return GAResult(best_x=decode(best_g), best_h=best_h, history=np.array(hist),
                    pc=np.array(pcs), pm=np.array(pms), evaluations_per_generation=p,
                    label=f"{label}, {encoding}")


def _differential_evolution(objective, lo, hi, n_runs: int, n_pop: int, generations: int, rng,
                            *, tol: float = 0.0, mutation=(0.5, 1.0),
                            recombination: float = 0.7):
    """Differential evolution, scipy's default scheme, ``n_runs`` independent runs at once.

    The scheme of ``scipy.optimize.differential_evolution`` with ``strategy="best1bin"``,
    ``mutation=(0.5, 1)`` (dithered: a new factor per run and generation),
    ``recombination=0.7``, ``init="latinhypercube"``, ``updating="deferred"`` and ``tol``
    (a run stops when the standard deviation of its population's energies is at most ``tol``
    times their mean): the trial of member ``i`` is ``best + F (x_r0 - x_r1)`` with ``r0, r1, i``
    distinct, crossed binomially with member ``i`` (one gene always from the trial); genes that
    leave the box are redrawn uniformly in it; a trial replaces its member when not worse.
    Hand-written because scipy runs one optimisation at a time with a Python loop over the
    population every generation, and the compendium needs hundreds of runs: here every step is
    an array over (runs, population, genes) and the only loop is over generations.

    ``objective(x, runs)``: energies ``(len(runs), n_pop)`` of genes ``x`` ``(len(runs), n_pop,
    d)`` for the runs with indices ``runs``.  Returns ``(population, energies, history,
    generations_run)``: the final population ``(n_runs, n_pop, d)`` and its energies, the best
    energy after each generation ``(generations + 1, n_runs)`` (row 0: the initial population;
    a stopped run keeps its value), and the number of generations each run made.
    """
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    s, p, d = n_runs, n_pop, lo.size
    if p < 4:
        raise ValueError(f"differential evolution needs at least 4 members, got {p}")
    every = np.arange(s)

    def energy(unit, runs):
        with np.errstate(over="ignore", invalid="ignore"):
            e = np.asarray(objective(lo + unit * (hi - lo), runs), dtype=float)
        return np.where(np.isfinite(e), np.minimum(e, 1e300), 1e300)

    # Latin hypercube: one point in each of n_pop slices of every gene, slices shuffled per gene
    unit = (rng.random((s, p, d)) + np.arange(p)[:, None]) / p
    unit = np.take_along_axis(unit, np.argsort(rng.random((s, p, d)), axis=1), axis=1)
    e = energy(unit, every)
    hist = np.empty((generations + 1, s))
    hist[0] = e.min(axis=1)
    done = np.zeros(s, dtype=bool)
    made = np.zeros(s, dtype=np.int64)
    member = np.arange(p)
    for g in range(1, generations + 1):
        runs = np.flatnonzero(~done)
        if runs.size:
            m = runs.size
            pop, en = unit[runs], e[runs]
            rows = np.arange(m)[:, None]
            best = pop[np.arange(m), np.argmin(en, axis=1)]          # first index on ties
            f = rng.uniform(mutation[0], mutation[1], size=(m, 1, 1))
            r0 = rng.integers(0, p - 1, size=(m, p))
            r0 = r0 + (r0 >= member)                                  # r0 != i
            r1 = rng.integers(0, p - 2, size=(m, p))
            first, second = np.minimum(member, r0), np.maximum(member, r0)
            r1 = r1 + (r1 >= first)
            r1 = r1 + (r1 >= second)                                  # r1 != i, r0
            mutant = best[:, None, :] + f * (pop[rows, r0] - pop[rows, r1])
            cross = rng.random((m, p, d)) < recombination
            cross[rows, member, rng.integers(0, d, size=(m, p))] = True
            trial = np.where(cross, mutant, pop)
            outside = (trial < 0) | (trial > 1)
            trial = np.where(outside, rng.random((m, p, d)), trial)
            et = energy(trial, runs)
            take = et <= en
            unit[runs] = np.where(take[..., None], trial, pop)
            e[runs] = np.where(take, et, en)
            made[runs] += 1
            if tol > 0:
                with np.errstate(over="ignore", invalid="ignore"):
                    spread = e[runs].std(axis=1) <= tol * np.abs(e[runs].mean(axis=1))
                done[runs] = spread
        hist[g] = e.min(axis=1)
    return lo + unit * (hi - lo), e, hist, made


def _polish(fun, x0, lo, hi):
    """L-BFGS-B from ``x0`` within the box (what scipy's ``polish=True`` does); returns
    ``(x, f)`` of the better of the start and the end point."""
    f0 = float(fun(x0))
    res = minimize(fun, x0, method="L-BFGS-B", bounds=list(zip(lo, hi, strict=True)))
    if res.fun < f0:
        return np.clip(res.x, lo, hi), float(res.fun)
    return np.asarray(x0, dtype=float), f0


def run_de(k=None, *, harmonics=None, bounds=PAPER_BOX, n_runs: int = 32, popsize: int = 13,
           generations: int = 200, seed: int = 0, polish: bool = False) -> GAResult:
    """Baseline: differential evolution (scipy's default scheme, :func:`_differential_evolution`)
    on the same genes and objective, ``n_runs`` runs at once.

    ``popsize * 4`` members, no early stop, so every run lasts ``generations``; ``polish``
    refines each run's best with L-BFGS-B as scipy's ``polish=True`` does.  ``seed`` seeds one
    ``numpy.random.Generator`` for all runs (or pass a Generator).
    """
    for name, v, low in (("n_runs", n_runs, 1), ("popsize", popsize, 1),
                         ("generations", generations, 1)):
        if isinstance(v, bool) or not isinstance(v, int | np.integer) or v < low:
            raise ValueError(f"{name} must be an integer >= {low}, got {v!r}")
    if k is not None and np.ndim(k) != 0:
        raise ValueError("run_de takes one harmonic order k")
    lo, hi = _box(bounds)
    objective = _make_objective(k, harmonics, n_runs)
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    pop, e, hist, _ = _differential_evolution(lambda x, runs: objective(x, runs), lo, hi,
                                              n_runs, popsize * 4, generations, rng)
    ib = np.argmin(e, axis=1)
    best_x = pop[np.arange(n_runs), ib]
    best_h = e[np.arange(n_runs), ib]
    if polish:
        for r in range(n_runs):
            def fun(x, r=r):
                return float(np.minimum(objective(np.asarray(x)[None, None], np.array([r]))
                                        [0, 0], 1e300))
            best_x[r], best_h[r] = _polish(fun, best_x[r], lo, hi)
    best_h = np.asarray(objective(best_x[:, None], np.arange(n_runs))[:, 0], dtype=float)
    return GAResult(best_x=best_x, best_h=best_h, history=hist,
                    pc=np.full(generations + 1, np.nan), pm=np.full(generations + 1, np.nan),
                    evaluations_per_generation=popsize * 4,
                    label="differential evolution (best1bin" + (", polished)" if polish else ")"))


def convergence_generation(history, target, rel_tol: float = 0.01) -> np.ndarray:
    """First generation at which the best-so-far objective is within ``rel_tol`` of ``target``
    (``history``: (generations + 1, runs); ``target``: scalar or per run).  ``-1`` if never."""
    hist = np.asarray(history, dtype=float)
    if hist.ndim != 2:
        raise ValueError("history must be (generations + 1, runs)")
    if not rel_tol >= 0:
        raise ValueError(f"rel_tol must be >= 0, got {rel_tol!r}")
    ok = hist <= np.asarray(target, dtype=float) * (1 + rel_tol)
    return np.where(ok.any(axis=0), ok.argmax(axis=0), -1)


def reference_optima(ks, bounds=PAPER_BOX, n_starts: int = 2, seed: int = 0,
                     maxiter: int = 400, popsize: int = 30, rel_tol: float = 1e-9):
    """Best known ``H`` at every harmonic of ``ks`` within ``bounds``: differential evolution
    over the three angles with the optimal ``a_3`` in closed form (:func:`optimal_a3`),
    ``n_starts`` runs per harmonic (all harmonics and starts in one batch, each run stopping
    when its population's energies agree to ``1e-12``), each polished with L-BFGS-B; the
    result's ``H`` is Eq. 20 evaluated at the genes found.  Layouts with
    ``|sin(phi_2 - phi_1)| < 1e-4`` are excluded: Eq. 15 would need weights above ``1e4``
    there, and the closed form of :func:`optimal_a3` loses its accuracy (it can even return
    values below the bound 1/4).

    Returns ``(H, genes)`` of shapes ``(K,)`` and ``(K, 4)``.  The best start is chosen by
    :func:`select_best` (starts whose ``H`` agree within ``rel_tol`` are ties, broken by the
    canonical layout), and the genes are the canonical member of the layout's symmetry class
    (:func:`canonical_genes`).  A numerical reference, not a proof.
    """
    ks = np.atleast_1d(np.asarray(ks))
    if ks.ndim != 1 or ks.size == 0:
        raise ValueError("ks must be a non-empty list of harmonic orders")
    objective_H(np.array([0.3, 2.0, 5.0, 1.0]), ks)  # validates the orders
    if isinstance(n_starts, bool) or not isinstance(n_starts, int | np.integer) or n_starts < 1:
        raise ValueError(f"n_starts must be an integer >= 1, got {n_starts!r}")
    lo, hi = _box(bounds)
    a3b = (lo[3], hi[3])
    k_run = np.repeat(ks.astype(float), n_starts)

    def objective(x3, runs):
        h = optimal_a3(x3, k_run[runs, None], a3b)[1]
        return np.where(np.abs(np.sin(x3[..., 1] - x3[..., 0])) < _NEAR_DEGENERATE, np.inf, h)

    rng = np.random.default_rng(seed)
    pop, e, _, _ = _differential_evolution(objective, lo[:3], hi[:3], k_run.size, popsize * 3,
                                           maxiter, rng, tol=1e-12)
    n = k_run.size
    x3 = pop[np.arange(n), np.argmin(e, axis=1)]
    h = np.empty(n)
    for r in range(n):
        def fun(v, r=r):
            return float(np.minimum(objective(np.asarray(v)[None, None], np.array([r]))[0, 0],
                                    1e300))
        x3[r], _ = _polish(fun, x3[r], lo[:3], hi[:3])
    a3 = optimal_a3(x3, k_run, a3b)[0]
    genes = np.concatenate([x3, a3[:, None]], axis=1)
    h = np.where(np.abs(np.sin(x3[:, 1] - x3[:, 0])) < _NEAR_DEGENERATE, np.inf,
                 objective_H(genes, k_run))                     # Eq. 20 itself, as the GAs
    genes = genes.reshape(ks.size, n_starts, 4)
    h = h.reshape(ks.size, n_starts)
    best, genes_best = select_best(h, genes, bounds, rel_tol=rel_tol)
    return h[np.arange(ks.size), best], genes_best


def reference_optimum(k: int, bounds=PAPER_BOX, n_starts: int = 4, seed: int = 0,
                      maxiter: int = 400):
    """Best known ``H`` at harmonic ``k`` in ``bounds`` (:func:`reference_optima` for one
    harmonic).  Returns ``(H, genes)``, the genes canonical (:func:`canonical_genes`)."""
    h, g = reference_optima([k], bounds, n_starts=n_starts, seed=seed, maxiter=maxiter)
    return float(h[0]), g[0]


# ----------------------------------------------------------------------------- symmetry

def equivalent_genes(x) -> np.ndarray:
    """Every gene vector describing the same physical layout as ``x``: ``(..., 48, 4)``.

    ``H`` (Eq. 20), at every harmonic, and the worst case over harmonics are unchanged when
    (a) another probe is taken as the reference (all angles turned by ``-phi_j``; the weights
    divided by ``a_j``, so ``a_0`` stays 1: ``|Lambda_k|`` is turned, and ``H`` is a ratio
    invariant under scaling the weights), (b) the three other probes are relabelled (six
    orders; ``a_3`` is the weight of whichever comes last), and (c) the layout is mirrored
    (``phi -> -phi``: ``Lambda_k -> conj(Lambda_k)``, Eq. 15's weights unchanged).  That is
    4 x 6 x 2 = 48 gene vectors per layout, computed here (angles in ``[0, 2 pi)``; NaN rows
    where a relabelling is degenerate, ``a_j = 0`` or ``sin(phi_2 - phi_1) = 0``).  Member 0 is
    ``x`` itself (angles taken modulo ``2 pi``).
    """
    x = _genes(x)
    phi, w = genes_to_layout(x)                                 # (..., 4) each
    out = []
    perms = ((0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0))
    for mirror in (1.0, -1.0):
        for j in range(4):
            others = [i for i in range(4) if i != j]
            with np.errstate(divide="ignore", invalid="ignore"):
                scale = 1.0 / w[..., j]
            for perm in perms:
                idx = [others[i] for i in perm]
                ang = np.mod(mirror * (phi[..., idx] - phi[..., j:j + 1]), TWO_PI)
                ang = np.where(ang >= TWO_PI, ang - TWO_PI, ang)
                a3 = w[..., idx[2]] * scale
                g = np.concatenate([ang, a3[..., None]], axis=-1)
                bad = (~np.isfinite(a3)) | (np.abs(np.sin(ang[..., 1] - ang[..., 0]))
                                            < _DEGENERATE) | (np.abs(w[..., j]) < _DEGENERATE)
                out.append(np.where(bad[..., None], np.nan, g))
    return np.stack(out, axis=-2)


def _lexicographic_first(keys, valid):
    """Index (over axis -2) of the lexicographically smallest row of ``keys`` (..., M, 4)
    among ``valid``; keys are compared rounded to 1e-9 so that two rows equal up to round-off
    are a tie decided by the next key (and finally by the lower index)."""
    q = np.where(valid[..., None], np.round(keys, 9), np.inf)
    order = np.broadcast_to(np.arange(q.shape[-2]), q.shape[:-1]).copy()
    for c in range(q.shape[-1] - 1, -1, -1):
        v = np.take_along_axis(q[..., c], order, axis=-1)
        order = np.take_along_axis(order, np.argsort(v, axis=-1, kind="stable"), axis=-1)
    return order[..., 0]


def canonical_genes(x, bounds=None) -> np.ndarray:
    """The canonical member of the symmetry class of ``x`` (:func:`equivalent_genes`): the
    lexicographically smallest ``(phi_1, phi_2, phi_3, a_3)`` among the members inside
    ``bounds`` (``x`` itself counts as inside; angles within 1e-12 of a bound are put on it, and
    an angle 0 counts as 2 pi where only that is inside).  ``bounds=None``: all members."""
    x = _genes(x)
    members = equivalent_genes(x)
    members = np.concatenate([x[..., None, :], members], axis=-2)
    valid = np.all(np.isfinite(members), axis=-1)
    if bounds is not None:
        lo, hi = _box(bounds)
        wrap = np.r_[TWO_PI, TWO_PI, TWO_PI, 0.0]
        alt = members + wrap
        members = np.where((members < lo - 1e-12) & (alt <= hi + 1e-12), alt, members)
        inside = np.all((members >= lo - 1e-12) & (members <= hi + 1e-12), axis=-1)
        members = np.clip(members, lo, hi)
        valid &= inside
        valid[..., 0] = True
    first = _lexicographic_first(members, valid)
    return np.take_along_axis(members, first[..., None, None], axis=-2)[..., 0, :]


def select_best(h, x, bounds=None, rel_tol: float = 1e-9):
    """The best of several candidate layouts, with canonical tie-breaking.

    ``h`` (..., M) objective values (smaller is better), ``x`` (..., M, 4) their genes.  The
    candidates whose ``H`` is within ``rel_tol`` of the smallest are ties (two optimisers, or
    two round-off orders, that found the same optimum or symmetric copies of it); among them
    the one whose canonical genes (:func:`canonical_genes` in ``bounds``) are lexicographically
    smallest wins.  Returns ``(index, canonical genes)`` of shapes (...) and (..., 4).
    """
    h = np.asarray(h, dtype=float)
    x = _genes(x)
    if h.shape != x.shape[:-1] or h.shape[-1] < 1:
        raise ValueError(f"h {h.shape} and x {x.shape} must be (..., M) and (..., M, 4)")
    if not rel_tol >= 0:
        raise ValueError(f"rel_tol must be >= 0, got {rel_tol!r}")
    hmin = np.min(h, axis=-1, keepdims=True)
    tied = h <= hmin + rel_tol * np.abs(hmin)
    canon = canonical_genes(x, bounds)
    first = _lexicographic_first(canon, tied)
    return first, np.take_along_axis(canon, first[..., None, None], axis=-2)[..., 0, :]


# ----------------------------------------------------------------------------- roundness, filter

def lowpass(signals, max_harmonic: int) -> np.ndarray:
    """Low-pass FFT filter along the last axis: harmonics above ``max_harmonic`` set to zero."""
    x = np.asarray(signals, dtype=float)
    n = x.shape[-1]
    if isinstance(max_harmonic, bool) or not isinstance(max_harmonic, int | np.integer) \
            or not 1 <= max_harmonic <= n // 2:
        raise ValueError(f"max_harmonic must be an integer in 1..N/2 = {n // 2}, "
                         f"got {max_harmonic!r}")
    spec = np.fft.rfft(x, axis=-1)
    spec[..., max_harmonic + 1:] = 0
    return np.fft.irfft(spec, n=n, axis=-1)


def _profile(profile):
    r = np.asarray(profile, dtype=float)
    if r.ndim < 1 or r.shape[-1] < 8 or not np.all(np.isfinite(r)):
        raise ValueError("profile must be finite with at least 8 samples on the last axis")
    return r


def lsc_roundness(profile):
    """Least-squares circle roundness of radial deviations sampled uniformly over a turn.

    The limacon model ``r(theta) ~ R0 + a cos theta + b sin theta`` (deviations small against
    the radius), fitted with ``scipy.linalg.lstsq``; batched over leading axes.  Returns
    ``(roundness, (R0, a, b))``: roundness is the peak-to-valley of the residual.
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
    """Minimum-zone roundness (limacon model) by linear programming (``scipy.optimize.linprog``).

    Minimise ``t_out - t_in`` over ``(a, b, t_in, t_out)`` subject to
    ``t_in <= r_i - a cos theta_i - b sin theta_i <= t_out``.  One LP per profile (leading axes
    looped).  Returns ``(roundness, (a, b))``.
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


def random_profile(n_samples: int, harmonics, rng, decay: float = 1.0,
                   roundness: float | None = None) -> np.ndarray:
    """A random profile with the given harmonics, amplitudes ``~ k^-decay`` and random phases;
    scaled so that its minimum-zone roundness equals ``roundness`` when given."""
    n = _check_n(n_samples)
    ks = np.asarray(harmonics)
    if ks.ndim != 1 or ks.size == 0 or np.any(ks < 0) or np.any(ks >= n / 2):
        raise ValueError(f"harmonics must be orders in 0..N/2-1 = {n // 2 - 1}")
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
    ``async_sd`` per axis); each probe adds white noise ``noise_sd``.  Returns ``(M, 4, N)``.
    """
    r = _profile(profile)
    n = r.shape[-1]
    for name, v in (("n_rev", n_rev), ("interleave", interleave),
                    ("n_measurements", n_measurements)):
        if isinstance(v, bool) or not isinstance(v, int | np.integer) or v < 1:
            raise ValueError(f"{name} must be an integer >= 1, got {v!r}")
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
    """How far apart the mean curves of groups of repeated measurements are, in units of ``k``
    standard errors of their difference: ``(G, G)`` matrix, 0 on the diagonal.

    ``curves``: ``(G, M, P)``, ``G`` groups (e.g. spindle speeds), ``M >= 2`` repeated
    measurements of a curve of ``P`` points each.  For groups ``a, b`` with means ``m_a, m_b`` and
    pointwise sample variances ``v_a, v_b`` (``ddof = 1``):

        ratio_ab = rms_P(m_a - m_b) / (k * sqrt(mean_P(v_a + v_b) / M)).

    If both groups measure the same curve with independent scatter, ``E[rms^2] =
    mean_P(v_a + v_b) / M``, so the ratio is about ``1 / k``; a ratio at most 1 means the groups'
    curves coincide within ``k`` standard errors of the measurement scatter (the ``k = 2`` of the
    compendium's tolerance policy), a ratio above 1 a systematic difference between groups.
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
