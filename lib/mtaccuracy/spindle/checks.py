"""What a separation can tell about its own data: the sense of rotation, and aliasing.

Two checks that :func:`~mtaccuracy.spindle.probes.separate_probes` runs on every separation and
reports as warnings (:class:`RotationSenseWarning`, :class:`AliasingWarning`), with their
statistics in :class:`SeparationChecks`.

**The sense of rotation.**  With the spindle turning in the sense stated (``rotation``), the
artefact's centring error is a once-per-revolution reading that turns *with* the spindle: it
goes to the profile's first harmonic (the eccentricity convention).  Stated wrongly, the
centring reads on the probes exactly as a once-per-revolution motion turning *against* the
spindle, with the amplitude of the centring (probe at ``phi`` reading ``Re(E exp(i(phi -
theta)))`` is the motion ``conj(E) exp(+i theta)`` under ``r(theta + phi)``), and the motion
that truly counter-rotates goes to the profile instead: the two once-per-revolution components
swap.  The check compares, in the motion the separation fitted before the convention removes
anything, the mean once-per-revolution component turning with the stated sense (``co``: the
centring plus the spindle's co-rotating once-per-revolution motion) with the one turning
against it (``counter``), and warns when ``counter > SENSE_RATIO * co`` and ``counter >
SENSE_SIGNIFICANCE`` standard errors.

Why that rule: a spindle's synchronous once-per-revolution motion comes from its unbalance
response and its runout; in anisotropic bearings its orbit is an ellipse, ``a`` by ``b``, whose
forward (co-rotating) part ``(a + b) / 2`` is never smaller than its backward part ``(a - b) /
2`` (a backward whirl at the running speed needs a rotor on a resonance).  The centring of an
artefact on a spindle is micrometres, a precision spindle's once-per-revolution motion tens of
nanometres.  So on correct data ``counter <= co`` whenever the centring does not happen to
cancel the co-rotating motion, and on wrongly stated data ``counter / co`` is the centring over
the counter-rotating motion, large.  The factor 2 leaves room for a strongly elliptic whirl
partly cancelled by the centring; the significance (5 standard errors of ``counter``, from the
probes' noise and the scatter of the revolutions) keeps noise from firing it (a pure-noise
``counter`` exceeds 5 standard errors with probability ``exp(-12.5) ~ 4e-6``).
**Limits:** a perfectly centred artefact on a spindle with no once-per-revolution motion gives
``co = counter = 0``: the sense cannot be told from the data, and nothing is said; an artefact
whose centring cancels the spindle's co-rotating motion to within half its counter-rotating one
would be flagged wrongly (move the artefact by a few micrometres and measure again).

**Aliasing.**  N samples per revolution resolve harmonics up to ``N / 2``; content above folds
onto lower harmonics.  Two criteria, either of which warns:

* *the misfit is synchronous*: once the profile and the motion are fitted, the probes' misfit
  left in the revolutions' average is compared with the misfit of the revolutions about their
  average, each per degree of freedom (``L - 3`` per harmonic separated, ``L - 2`` elsewhere,
  and ``(R - 1) N (L - 2)`` about the average).  White noise gives a ratio near 1; the ratio
  exceeds :data:`MISFIT_RATIO` when the readings carry a profile the model cannot hold at N
  samples (profile harmonics above ``N / 2`` read by probes off the sample grid, or a probe's
  angle off, or its nonlinearity).  It needs two revolutions and four probes (with three the
  profile absorbs any synchronous misfit);
* *the spectrum has not decayed*: the mean power of the probes' readings over the top harmonics
  resolved (the highest tenth of ``1..N / 2``, at least three), in the revolutions' average and
  in their deviations from it, against what the probes' noise alone gives there
  (``sigma^2 / R`` and ``sigma^2 (R - 1) / R`` per bin, ``sigma`` from the misfit about the
  average, which aliasing does not reach); above :data:`SPECTRUM_RATIO` (mean amplitude twice
  the noise's) the readings still carry content where the sampling ends, and so, very likely,
  beyond it.

Neither fires on what is negligible: a synchronous misfit, or a top band's amplitude, below
:data:`NEGLIGIBLE` (a thousandth) of the readings' rms (a noise-free simulation has no noise to
compare with, and its second-order terms are not aliasing).  Limits: probes on the sample
grid read an aliased harmonic exactly as the harmonic it folds onto, so only the spectrum
criterion sees it; with one revolution the noise is estimated from
the whole misfit, which aliasing inflates, so the spectrum criterion is then conservative.

Why hand-written: these are the separation's own residual statistics (numpy FFT, pseudo-inverse).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["ROTATIONS", "RotationSenseWarning", "AliasingWarning", "SeparationChecks",
           "SENSE_RATIO", "SENSE_SIGNIFICANCE", "MISFIT_RATIO", "SPECTRUM_RATIO", "NEGLIGIBLE",
           "top_band"]

#: The senses of rotation: ``"cw"``, the probe at ``phi`` reads ``r(theta + phi)`` (Yang et al.
#: 2021, Eq. 7: the spindle turns against the sense the probe angles count), ``"ccw"``, it
#: reads ``r(phi - theta)`` (the spindle turns in the sense the probe angles count).
ROTATIONS = ("cw", "ccw")
#: The counter-rotating once-per-revolution motion must exceed the co-rotating one by this factor.
SENSE_RATIO = 2.0
#: ... and its own standard error by this factor.
SENSE_SIGNIFICANCE = 5.0
#: Synchronous misfit per degree of freedom over the misfit about the average: above this, warn.
MISFIT_RATIO = 4.0
#: Mean power over the top harmonics over the noise's: above this, warn.
SPECTRUM_RATIO = 4.0
#: Below this fraction of the readings' rms, a misfit or a top band is round-off: no warning.
_ROUNDOFF = 1e-6
#: A synchronous misfit, or a top band's mean amplitude per harmonic, below this fraction of the
#: readings' rms biases nothing that matters (a noise-free simulation's second-order terms): no
#: warning, whatever the noise.
NEGLIGIBLE = 1e-3


class RotationSenseWarning(UserWarning):
    """The data look as if the spindle turned in the other sense than ``rotation`` states.

    The separated profile and motion are then wrong (module docstring of
    :mod:`~mtaccuracy.spindle.checks`); the message names the ``rotation`` the data look like.
    """


class AliasingWarning(UserWarning):
    """The readings carry more than the samples per revolution resolve.

    The profile, the roundness and the error motion values are then biased (module docstring
    of :mod:`~mtaccuracy.spindle.checks`); measure with more samples per revolution, or filter
    the readings before sampling.
    """


@dataclass
class SeparationChecks:
    """The statistics behind the sense and aliasing checks of one separation (or a batch).

    Attributes
    ----------
    co_rotating, counter_rotating : arrays (...)
        Amplitudes of the mean once-per-revolution motion turning with and against the spindle
        in the sense stated (the signals' unit), before the eccentricity convention.
    counter_standard_error : array (...)
        Standard error of ``counter_rotating`` (the signals' unit).
    wrong_sense : array of bool (...)
        The sense check fired.
    noise_sd : array (...)
        The probes' noise estimated from the misfit about the revolutions' average (R >= 2), or
        from the whole misfit (R = 1), in the signals' unit.
    misfit_ratio : array (...)
        Synchronous misfit per degree of freedom over the misfit about the average (NaN when it
        cannot be formed: one revolution, or three probes).
    spectrum_ratio : array (..., 2)
        Mean power over the top harmonics over the noise's: revolutions' average, deviations
        from it (NaN with one revolution).
    top_harmonics : tuple of int
        The first and last harmonic of the top band.
    aliased : array of bool (..., 3)
        Which aliasing criterion fired: the synchronous misfit, the top harmonics of the
        revolutions' average, of their deviations from it.
    """

    co_rotating: np.ndarray
    counter_rotating: np.ndarray
    counter_standard_error: np.ndarray
    wrong_sense: np.ndarray
    noise_sd: np.ndarray
    misfit_ratio: np.ndarray
    spectrum_ratio: np.ndarray
    top_harmonics: tuple
    aliased: np.ndarray


def top_band(n_samples: int) -> tuple[int, int]:
    """The top harmonics of ``N`` samples a turn: the highest tenth of ``1..N // 2``, at least 3.

    Parameters
    ----------
    n_samples : int
        Samples per revolution N (>= 8).

    Returns
    -------
    first, last : int
        The band's first and last harmonic (``last = N // 2``).
    """
    last = n_samples // 2
    width = max(3, int(np.ceil(last / 10)))
    return last - width + 1, last


def _sense_statistics(z, grid, misfit_ms, gram_trace):
    """Once-per-revolution components of the fitted motion ``z`` (..., R, N) (module docstring).

    ``grid`` (N,) the sample angles from the first, ``misfit_ms`` (...) the probes' mean square
    misfit times ``L / (L - 2)`` (their noise variance), ``gram_trace`` ``tr((G^T G)^-1)`` of the
    motion's design.  Returns ``co, counter, standard error, fired`` (...); the stated sense
    turns the artefact by ``-theta`` in the separation's frame (the caller negates the angles for
    ``ccw``), so the co-rotating component is ``exp(-i theta)``.
    """
    r, n = z.shape[-2:]
    co_r = (z * np.exp(1j * grid)).mean(axis=-1)                       # (..., R)
    counter_r = (z * np.exp(-1j * grid)).mean(axis=-1)
    co, counter = np.abs(co_r.mean(axis=-1)), np.abs(counter_r.mean(axis=-1))
    var = misfit_ms * gram_trace / (n * r)
    if r > 1:
        var = var + counter_r.var(axis=-1, ddof=1) / r
    se = np.sqrt(var)
    fired = (counter > SENSE_RATIO * co) & (counter > SENSE_SIGNIFICANCE * se)
    return co, counter, se, fired


def _aliasing_statistics(y, spec, misfit, residual_mean, dof_mean):
    """The two aliasing criteria (module docstring).

    ``y`` (..., R, L, N) the readings less each probe's mean, ``spec`` (..., L, N) the FFT of
    their revolutions' average, ``misfit`` (..., R, L, N) what the fit leaves, ``residual_mean``
    (...) the sum of squares of the least-squares misfit of the revolutions' average (every
    sample of every probe), ``dof_mean`` its degrees of freedom.  Returns ``noise_sd, misfit
    ratio, spectrum ratios (..., 2), band, fired (..., 3)``: the criteria that fired (the
    misfit, the spectrum of the average, of the deviations).
    """
    r, n_probes, n = y.shape[-3:]
    scale = np.sqrt((y ** 2).mean(axis=(-3, -2, -1)))
    dev = misfit - misfit.mean(axis=-3, keepdims=True)
    dof_dev = (r - 1) * n * (n_probes - 2)
    with np.errstate(invalid="ignore", divide="ignore"):
        if r > 1:
            var = (dev ** 2).sum(axis=(-3, -2, -1)) / dof_dev
        else:
            var = (misfit ** 2).mean(axis=(-3, -2, -1)) * n_probes / (n_probes - 2)
        var = np.maximum(var, (_ROUNDOFF * scale) ** 2)
        misfit_ratio = (r * residual_mean / dof_mean) / var if (r > 1 and dof_mean >= 16) \
            else np.full(var.shape, np.nan)
        first, last = top_band(n)
        ks = np.abs(np.rint(np.fft.fftfreq(n, 1.0 / n)).astype(int))
        top = (ks >= first) & (ks <= last)
        p_mean = (np.abs(spec[..., top]) ** 2).mean(axis=(-2, -1)) / n
        ratios = [p_mean / (var / r)]
        if r > 1:
            d = np.fft.fft(y - y.mean(axis=-3, keepdims=True), axis=-1)
            p_dev = (np.abs(d[..., top]) ** 2).mean(axis=(-3, -2, -1)) / n
            ratios.append(p_dev / (var * (r - 1) / r))
        else:
            ratios.append(np.full(var.shape, np.nan))
        spectrum_ratio = np.stack(ratios, axis=-1)
        big = (NEGLIGIBLE * scale) ** 2
        sync_ms = r * residual_mean / dof_mean
        top_ms = np.stack([p_mean, p_dev if r > 1 else np.zeros_like(p_mean)], axis=-1)
        fired = np.concatenate([
            ((np.nan_to_num(misfit_ratio) > MISFIT_RATIO) & (sync_ms > big))[..., None],
            (np.nan_to_num(spectrum_ratio) > SPECTRUM_RATIO) & (top_ms > big[..., None])],
            axis=-1)
    return np.sqrt(var), misfit_ratio, spectrum_ratio, (first, last), fired


def _rotation_message(checks: SeparationChecks, rotation: str) -> str:
    """The :class:`RotationSenseWarning` text: what was seen and the ``rotation`` it suggests."""
    other = "ccw" if rotation == "cw" else "cw"
    i = np.unravel_index(np.argmax(np.where(checks.wrong_sense, checks.counter_rotating, -1.0)),
                         np.shape(checks.wrong_sense))
    co, counter = float(np.asarray(checks.co_rotating)[i]), \
        float(np.asarray(checks.counter_rotating)[i])
    return (f"the data look like rotation={other!r}, not {rotation!r}: under {rotation!r} the "
            f"separated motion holds a once-per-revolution component turning against the "
            f"spindle of {counter:.4g} (the signals' unit) against {co:.4g} turning with it, "
            f"which is what an artefact's centring reads as when the sense is stated wrongly "
            f"(the profile and the motion are then wrong); separate with rotation={other!r} "
            f"(a spindle's own once-per-revolution motion turning against it is rarely more "
            f"than half its forward one: spindle.checks)")


def _aliasing_message(checks: SeparationChecks, n_samples: int) -> str:
    """The :class:`AliasingWarning` text: which criterion fired, by how much."""
    parts = []
    mr = np.nan_to_num(np.asarray(checks.misfit_ratio))
    fired = np.asarray(checks.aliased).reshape(-1, 3).any(axis=0)
    if fired[0]:
        parts.append(f"the misfit left in the revolutions' average is {mr.max():.3g} times the "
                     f"probes' noise per degree of freedom (threshold {MISFIT_RATIO:g})")
    sr = np.nan_to_num(np.asarray(checks.spectrum_ratio))
    first, last = checks.top_harmonics
    for j, what in enumerate(("average", "deviations from the average")):
        if fired[j + 1]:
            parts.append(f"the readings' power at the top harmonics {first}..{last} (their "
                         f"revolutions' {what}) is {sr[..., j].max():.3g} times the noise's "
                         f"(threshold {SPECTRUM_RATIO:g}): the spectrum has not decayed")
    return (f"the readings seem to carry more than {n_samples} samples per revolution resolve "
            f"(aliasing): " + "; ".join(parts) + ". The profile, the roundness and the error "
            "motion values are biased; sample more finely (or low-pass the probes before "
            "sampling). A probe's angle off, or its nonlinearity, also leaves a synchronous "
            "misfit (spindle.checks)")
