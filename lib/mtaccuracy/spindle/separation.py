"""Four-probe separation of a spindle's radial error motion from the workpiece profile.

Yang et al. 2021, Section 1: the model, the weights, the transfer function and the matrix method,
with the first-harmonic conventions; the least-squares estimator beside it is
:mod:`~mtaccuracy.spindle.least_squares`.

The model (Yang et al. 2021, Eqs. 7 and 11): probe ``l`` at angle ``phi_l`` (``phi_0 = 0``)
reads, at sample ``n`` of ``N`` per revolution (``theta_n = 2 pi n / N``),

    y_l(n) = r(theta_n + phi_l) + dx(n) cos(phi_l) + dy(n) sin(phi_l),

and the weighted sum ``Y = sum_l a_l y_l`` with weights that cancel the motion (``sum_l a_l
cos(phi_l) = sum_l a_l sin(phi_l) = 0``, Eq. 15) is ``Y = A r`` (Eq. 6), ``A`` circulant with
the eigenvalues ``Lambda_k = sum_l a_l exp(i k phi_l)`` (Eq. 14); the same two conditions make
``Lambda_1 = Lambda_{N-1} = 0`` *by design*: ``rank(A) <= N - 2``, not ``N`` as printed.  The
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

Lengths are in any one unit (the separation is linear); the compendium passes millimetres, or
micrometres where it mirrors a paper's printed functions.  Angles are radians.
"""

from __future__ import annotations

__all__ = ["Separation", "CancelledHarmonicsWarning", "probe_angles", "weights", "full_weights",
           "eigenvalues", "transfer", "circulant_matrix", "probe_signals", "separate",
           "separate_details",
           "rotation_error", "motion_from_scalar", "MAPPINGS",
           "cancelled_harmonics", "rank_check"]

import warnings
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg

from .. import validate
from ..roundness import _MIN_SAMPLES, TWO_PI

_DEGENERATE = 1e-12


def probe_angles(positions, n_samples: int) -> np.ndarray:
    """Angles ``2 pi p / N`` of probes at integer sample positions ``p`` (Section 1.3).

    Parameters
    ----------
    positions : sequence of int
        Sample indices of the probes.
    n_samples : int
        Samples per turn N (>= 8).

    Returns
    -------
    array
        The angles (rad), the shape of ``positions``.
    """
    p = np.asarray(positions, dtype=float)
    n_samples = _check_n(n_samples)
    if not np.all(np.isfinite(p)) or np.any(p != np.round(p)):
        raise ValueError(f"probe positions must be integer sample indices, got {positions!r}")
    return TWO_PI * p / n_samples


def _check_n(n, name: str = "n_samples") -> int:
    """Samples per revolution, checked: an integer >= 8."""
    return validate.integer(n, name, low=_MIN_SAMPLES)


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

    Parameters
    ----------
    phi : array (..., 3) or (..., 4)
        Probe angles (rad).
    a3 : float or array (...)
        The free weight of probe 3.

    Returns
    -------
    a1, a2 : arrays (...)
        The weights of probes 1 and 2 (a0 = 1).
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
    """``(..., 4)`` weights ``a0..a3`` with ``a0 = 1`` and ``a1, a2`` from :func:`weights`.

    Parameters
    ----------
    phi : array (..., 3) or (..., 4)
        Probe angles (rad).
    a3 : float or array (...)
        The free weight of probe 3.

    Returns
    -------
    array (..., 4)
        a0..a3.
    """
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
    """``Lambda_k = lambda_k + i mu_k = sum_l a_l exp(i k phi_l)`` (Eq. 14), shape (..., K).

    Parameters
    ----------
    phi : array (..., 3) or (..., 4)
        Probe angles (rad).
    w : array (..., 3) or (..., 4)
        Weights a1..a3 (a0 = 1) or a0..a3.
    harmonics : array of int (K,)
        Harmonic orders k.

    Returns
    -------
    array of complex (..., K)
        ``Lambda_k``.
    """
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

    Parameters
    ----------
    phi : array (..., 3) or (..., 4)
        Probe angles (rad).
    w : array (..., 3) or (..., 4)
        Weights a1..a3 (a0 = 1) or a0..a3.
    harmonics : array of int (K,)
        Harmonic orders k.

    Returns
    -------
    array (..., K)
        q_k^2 (dimensionless), inf where the layout cancels the harmonic.
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
    """The matrix ``A`` of Eq. 6, ``(A r)(n) = sum_l a_l r(n + p_l)`` (``scipy.linalg.circulant``).

    Its eigenvalues are ``Lambda_k`` of :func:`eigenvalues`.  (The printed definition, ``eps_{p, q +
    p_l} = 1`` when ``p = q``, would make ``A`` diagonal; the intended one is ``A[p, q] = sum_l a_l
    [q = p + p_l mod N]``.)

    Parameters
    ----------
    positions : sequence of int (4,)
        Probe positions p_l (sample indices).
    w : array (4,)
        Weights a0..a3.
    n_samples : int
        Samples per revolution N (>= 8).

    Returns
    -------
    array (N, N)
        A.
    """
    n_samples = _check_n(n_samples)
    p = np.asarray(positions)
    if p.shape != (4,) or np.any(p != np.round(p)):
        raise ValueError(f"positions must be 4 integer sample indices p_0..p_3, got {positions!r}")
    _, w = _full(np.zeros(4), w)
    c = np.zeros(n_samples)
    np.add.at(c, p.astype(int) % n_samples, w)
    return scipy.linalg.circulant(c).T


def probe_signals(profile, dx, dy, positions) -> np.ndarray:
    """Four-probe signals ``(..., 4, N)`` of Eq. 7 from a profile and an error motion ``(..., N)``.

    ``positions`` are the integer sample indices ``p_l`` (``p_0 = 0`` included); sample ``n`` of
    probe ``l`` reads the profile at sample ``n + p_l``.

    Parameters
    ----------
    profile, dx, dy : arrays (..., N)
        Profile and error motion (any one length unit).
    positions : sequence of int (4,)
        Probe positions, p_0 = 0 first.

    Returns
    -------
    array (..., 4, N)
        The probes' readings, in the unit of ``profile``.
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
    """Everything :func:`separate_details` finds; :func:`separate` returns ``profile, dx, dy``.

    Attributes
    ----------
    profile : array (..., N)
        Profile with the reconstructed first harmonic.
    dx, dy : arrays (..., N)
        Error motion along x and y.
    profile_no_first : array (..., N)
        The pseudo-inverse solution of Eq. 6 (no first harmonic).
    first_harmonic : array (..., 2)
        C, D: the profile's first harmonic C cos + D sin.
    cancelled : array of int
        Harmonics 0..N/2 set aside (``|Lambda_k| ~ 0``); always has 1.
    rank : int
        Rank of the Eq. 6 matrix: N minus the cancelled DFT bins.
    residual_rms : array (...)
        RMS misfit of the four-probe least squares for dx, dy.
    convention : str
        The first-harmonic convention used.
    eigen : array of complex (N,)
        Lambda_k, k = 0..N-1.
    """

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
    n = _check_n(y.shape[-1], "samples per revolution (the signals' last axis)")
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
    """A separation told ``allow_cancelled=True`` went on without harmonics the layout cancels.

    The separated profile lacks them (:func:`separate`,
    :func:`~mtaccuracy.spindle.least_squares.separate_least_squares`,
    :func:`~mtaccuracy.spindle.probes.separate_probes`).
    """


def _harmonic_list(ks, limit: int = 12) -> str:
    ks = [int(k) for k in ks]
    if len(ks) <= limit:
        return ", ".join(map(str, ks))
    return (", ".join(map(str, ks[:limit - 2])) + f", ..., {ks[-1]} ({len(ks)} harmonics"
            + ("; every odd one" if ks == list(range(ks[0], ks[-1] + 1, 2)) and ks[0] % 2 else "")
            + ")")


def _check_options(first_harmonic, rcond):
    if first_harmonic not in ("eccentricity", "radial"):
        raise ValueError(f"first_harmonic must be 'eccentricity' or 'radial', "
                         f"got {first_harmonic!r}")
    if not (0 < rcond < 1):
        raise ValueError(f"rcond must be in (0, 1), got {rcond!r}")


def _check_max_harmonic(max_harmonic, n: int) -> int:
    """``max_harmonic`` (default N/2) checked to be an integer in 1..N/2."""
    if max_harmonic is None:
        return n // 2
    return validate.integer(max_harmonic, "max_harmonic", low=1, high=n // 2)


def _set_aside(keep, n, max_harmonic, allow_cancelled, describe, hint, stacklevel):
    """The harmonics 0..N/2 not solved (``~keep``); those besides the first and up to
    ``max_harmonic`` are refused (``ValueError``: ``describe(list) + hint``) or, with
    ``allow_cancelled``, named in a :class:`CancelledHarmonicsWarning`."""
    harm = np.arange(n // 2 + 1)
    cancelled = harm[~keep[: n // 2 + 1]]
    extra = cancelled[(cancelled != 1) & (cancelled <= max_harmonic)]
    if extra.size:
        msg = describe(_harmonic_list(extra))
        if not allow_cancelled:
            raise ValueError(msg + hint)
        warnings.warn(msg + " (allow_cancelled=True: proceeding without them)",
                      CancelledHarmonicsWarning, stacklevel=stacklevel)
    return cancelled


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

    Parameters
    ----------
    signals : array (..., 4, N)
        Probe readings ``y_0..y_3`` (Eq. 7), any one length unit.
    phi : array (3,) or (4,)
        Probe angles (rad), on the sampling grid.
    w : array (3,) or (4,)
        Weights a1..a3 (a0 = 1) or a0..a3.
    first_harmonic : {"eccentricity", "radial"}
        Convention of the first harmonic (module docstring).
    rcond : float
        Harmonics with ``|Lambda_k| <= rcond max|Lambda|`` are set aside.
    check : bool
        Refuse weights that do not cancel the first harmonic.
    allow_cancelled : bool
        Proceed (with a warning) when other harmonics are cancelled.
    max_harmonic : int, optional
        Highest harmonic the signals can contain, 1..N/2 (default N/2).

    Returns
    -------
    Separation
        ``profile``, ``dx``, ``dy`` (..., N) in the unit of ``signals``, and the intermediate
        results.
    """
    _check_options(first_harmonic, rcond)
    y, n, phi4, w, p = _check_signals(signals, phi, w, check)
    max_harmonic = _check_max_harmonic(max_harmonic, n)

    # Profile without the cancelled harmonics: pseudo-inverse of the circulant matrix by FFT.
    big_y = np.einsum("l,...ln->...n", w, y)
    lam = eigenvalues(phi4, w, np.arange(n))            # numpy's FFT: shift +p -> exp(+i k phi)
    keep = np.abs(lam) > rcond * np.abs(lam).max()
    keep[[1, n - 1]] = False                            # cancelled by design (Eq. 15)
    inv = np.zeros(n, dtype=complex)
    inv[keep] = 1.0 / lam[keep]
    r0 = np.fft.ifft(np.fft.fft(big_y, axis=-1) * inv, axis=-1).real
    cancelled = _set_aside(
        keep, n, max_harmonic, allow_cancelled, stacklevel=4,
        describe=lambda ks: (f"the layout (probe positions {p.tolist()} of N = {n}, weights "
                             f"{np.round(w, 4).tolist()}) cancels harmonic(s) {ks} besides the "
                             f"first (|Lambda_k| <= rcond * max|Lambda| = {rcond:g} * "
                             f"{np.abs(lam).max():.4g}): the separated profile would lack them"),
        hint="; move a probe or change a3, or pass allow_cancelled=True to separate without them")

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


def separate(signals, phi, w, *, first_harmonic: str = "eccentricity", rcond: float = 1e-9,
             check: bool = True, allow_cancelled: bool = False, max_harmonic: int | None = None):
    """Separate the profile and the radial error motion from four probe signals (Eqs. 3-10).

    The four-point matrix method of Yang et al. 2021, Section 1: the weighted sum of the probes
    cancels the motion, its spectrum divided by ``Lambda_k`` (Eq. 14) gives the profile, and the
    motion follows from the probes by least squares (:func:`separate_details` gives the steps).

    Parameters
    ----------
    signals : array (..., 4, N)
        Probe readings ``y_0..y_3`` (Eq. 7) in any one length unit, batched over leading axes;
        N >= 8 samples per revolution.
    phi : array (3,) or (4,)
        Probe angles phi_1..phi_3 (or phi_0..phi_3 with phi_0 = 0), rad, on the sampling grid
        ``2 pi p / N`` (the matrix method shifts by whole samples).
    w : array (3,) or (4,)
        Weights a1..a3 (a0 = 1) or a0..a3; they must cancel the first harmonic (Eq. 15,
        :func:`weights`) unless ``check=False``.
    first_harmonic : {"eccentricity", "radial"}
        The convention that splits the profile's first harmonic from the motion (module
        docstring).
    rcond : float
        Harmonics with ``|Lambda_k| <= rcond * max|Lambda|`` are set aside, in (0, 1).
    check : bool
        Refuse weights that do not cancel the first harmonic (False shows what such weights
        do).
    allow_cancelled : bool
        Proceed without the harmonics other than the first that the layout cancels, with a
        :class:`CancelledHarmonicsWarning` naming them, instead of refusing the layout.
    max_harmonic : int, optional
        The highest harmonic the signals can contain, 1..N/2 (default N/2); cancelled
        harmonics above it are set aside silently, as they carry nothing.

    Returns
    -------
    profile : array (..., N)
        The profile, its first harmonic by the ``first_harmonic`` convention.
    dx, dy : arrays (..., N)
        The error motion along x (the direction of probe 0) and y, in the unit of ``signals``.

    Raises
    ------
    ValueError
        Signals not (..., 4, N) or not finite; angles off the sampling grid; weights that do
        not cancel the first harmonic (with ``check``); a layout that cancels another harmonic
        up to ``max_harmonic`` (unless ``allow_cancelled``), the message naming them.

    See Also
    --------
    separate_details : the same, with the intermediate results (``C, D``, the rank, the
        cancelled harmonics).
    mtaccuracy.spindle.least_squares.separate_least_squares : least squares over all probes,
        no weights needed.

    Examples
    --------
    A profile of harmonics 2 and 5 and a motion of harmonic 3, on the layout of the paper's
    Table 1 (k = 20) rounded to 128 samples:

    >>> import numpy as np
    >>> n = 128
    >>> t = 2 * np.pi * np.arange(n) / n
    >>> r = np.cos(2 * t) + 0.3 * np.sin(5 * t)
    >>> dx, dy = 0.2 * np.cos(3 * t), 0.1 * np.sin(3 * t)
    >>> pos = [0, 14, 65, 116]
    >>> phi = probe_angles(pos[1:], n)
    >>> y = probe_signals(r, dx, dy, pos)
    >>> profile, ex, ey = separate(y, phi, full_weights(phi, 1.953))
    >>> bool(np.allclose(profile, r) and np.allclose(ex, dx) and np.allclose(ey, dy))
    True
    """
    s = separate_details(signals, phi, w, first_harmonic=first_harmonic, rcond=rcond,
                         check=check, allow_cancelled=allow_cancelled,
                         max_harmonic=max_harmonic)
    return s.profile, s.dx, s.dy


def rotation_error(dx, dy, theta=None) -> np.ndarray:
    """Scalar radial error ``delta = dx cos(theta) + dy sin(theta)`` (Eq. 9, rotating direction).

    Parameters
    ----------
    dx, dy : arrays (..., N)
        Error motion (any one length unit).
    theta : array (N,), optional
        Angles (rad); default the uniform grid.

    Returns
    -------
    array (..., N)
        delta, in the unit of ``dx``.
    """
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
    """``(dx, dy)`` from a scalar rotation error under one of :data:`MAPPINGS`, and the inverse.

    Parameters
    ----------
    delta : array (N,)
        Scalar rotation error (any one length unit).
    mapping : str
        One of :data:`MAPPINGS`.
    theta : array (N,), optional
        Angles (rad); default the uniform grid.

    Returns
    -------
    dx, dy : arrays (N,)
        The error motion, in the unit of ``delta``.
    inverse : callable
        ``(dx, dy) -> delta``.
    """
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


def cancelled_harmonics(phi, w, *, n_samples: int, rcond: float = 1e-9) -> list[int]:
    """The harmonics 2..N/2 a layout's weights cancel, as :func:`separate_details` tests them.

    ``|Lambda_k| <= rcond * max|Lambda|``; :func:`separate_details` refuses such a layout unless
    told.

    Parameters
    ----------
    phi : array (3,) or (4,)
        Probe angles (rad).
    w : array (3,) or (4,)
        Weights a1..a3 (a0 = 1) or a0..a3.
    n_samples : int
        Samples per revolution N (>= 8).
    rcond : float
        Relative threshold on ``|Lambda_k|``.

    Returns
    -------
    list of int
        The cancelled harmonics, ascending (empty for a good layout).
    """
    n = _check_n(n_samples)
    lam = np.abs(eigenvalues(phi, w, np.arange(n)))
    return [k for k in range(2, n // 2 + 1) if lam[k] <= rcond * lam.max()]


def rank_check(positions, phi, w, test_profile, *, rtol: float, roundoff: float):
    """The rank of Eq. 6's matrix for one layout, and the separation checked against it.

    Builds the circulant matrix of the layout (:func:`circulant_matrix`), counts its singular
    values above ``rtol`` times the largest, separates a test profile through the FFT with the
    cancelled harmonics set aside (:func:`separate_details`, ``allow_cancelled=True``) and
    checks three things to round-off: the pseudo-inverse recovers the profile without the
    set-aside harmonics, least squares on the matrix agrees with the FFT solution, and the
    discarded singular values are zero.

    Parameters
    ----------
    positions : sequence of int (4,)
        Probe positions (sample indices, the first 0).
    phi : array (3,)
        Probe angles (rad) of probes 1-3 (:func:`probe_angles`).
    w : array (4,)
        Weights of the four probes (:func:`full_weights`).
    test_profile : array (n,)
        A profile to separate (any unit).
    rtol : float
        Relative singular-value threshold of the numerical rank (the ``rcond`` of the
        separation).
    roundoff : float
        What separates round-off from a result, relative to ``max |test_profile|``.

    Returns
    -------
    rank : int
        The numerical rank.
    sv : array (n,)
        Singular values, descending.
    separation : Separation
        Of the test profile.
    warned : list of str
        The :class:`CancelledHarmonicsWarning` messages.

    Raises
    ------
    RuntimeError
        When a check exceeds ``roundoff``.
    """
    n = len(test_profile)
    a_mat = circulant_matrix(positions, w, n)
    sv = scipy.linalg.svdvals(a_mat)                                   # descending
    rank = int((sv > rtol * sv[0]).sum())
    zero = np.zeros(n)
    y_t = probe_signals(test_profile, zero, zero, positions)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", CancelledHarmonicsWarning)
        s_t = separate_details(y_t, phi, w, rcond=rtol, allow_cancelled=True)
    keep = np.abs(s_t.eigen) > rtol * np.abs(s_t.eigen).max()
    keep[[1, n - 1]] = False
    r_kept = np.fft.ifft(np.fft.fft(test_profile) * keep).real   # without the set-aside harmonics
    ls = scipy.linalg.lstsq(a_mat, w @ y_t, cond=rtol)[0]
    scale = np.abs(test_profile).max()
    errs = {"pinv_error_rel": np.abs(s_t.profile_no_first - r_kept).max() / scale,
            "lstsq_vs_fft_rel": np.abs(ls - s_t.profile_no_first).max() / scale,
            "discarded_sv_rel": sv[rank:].max() / sv[0] if rank < n else 0.0}
    bad = {k: v for k, v in errs.items() if not v < roundoff}
    if bad:
        raise RuntimeError(f"expected round-off below {roundoff:g}, got {bad}")
    return rank, sv, s_t, [str(c.message) for c in caught]
