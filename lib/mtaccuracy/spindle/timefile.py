"""Time-sampled probe readings, as a data acquisition records them, resampled onto equal angles.

A DAQ samples the probes on a clock, not on the spindle's angle: the file has ``time_s``, the
probes, and either ``index`` (1 on the samples where the once-per-revolution mark is seen, else
0) or ``encoder_deg`` (the spindle angle, wrapping at 360 or accumulating).  The separation
needs the readings at N equal angles per revolution, the same every revolution
(:class:`~mtaccuracy.spindle.probedata.ProbeData`).  :func:`resample_time_series` gets them:

1. **The clock.** The sample times are taken as ``t0 + i dt`` with ``t0, dt`` fitted by least
   squares to ``time_s`` (a DAQ's clock is uniform; this removes the rounding of written time
   stamps).  A step of ``time_s`` outside ``(1 +- TIME_STEP_TOLERANCE) dt`` (a dropped or
   repeated sample, a pause) or a time stamp more than half a period off the line is refused.
2. **The marks.**  Index: a mark is a rising edge (0 then 1; a pulse lasting several samples
   counts once, at its first sample; a pulse already high at the first sample is not a mark),
   placed half a period before the sample that sees it (the mark passed between the two samples:
   this removes the quantisation's mean, and leaves an error within +-dt/2, standard deviation
   dt / sqrt(12)).  Encoder: the unwrapped angle at every sample, in revolutions.
3. **The speed, fitted to all marks together.**  The spindle's revolutions since the first mark
   are a polynomial of degree :data:`FIT_DEGREE` = 2 in time, fitted by least squares to every
   mark (index: pulse number 0, 1, ... against its time; encoder: angle / 360 against time):
   a speed and its linear drift, which is how a spindle's speed wanders over a record of seconds
   (thermal growth, the drive's control).  Degree 2 and not more: each further coefficient adds
   the quantisation's variance to every angle, while a drift that is not linear shows in the
   residual, which is checked: when a mark's residual exceeds one sample period (twice what the
   quantisation explains), :class:`UnsteadySpeedWarning` says that the speed is not steady.
   Fitting each revolution to its own two pulses instead puts each pulse's quantisation (up to
   dt/2) into that revolution's angles whole; the fit averages it over all pulses.
4. **The angles.**  theta = 0 at a mark (where the fitted revolutions are whole); revolution r
   is sampled at the times where the fitted revolutions equal ``r + j / N`` (Newton's method
   on the polynomial), only for complete revolutions between the first and the last mark whose
   times lie at least :data:`EDGE_SAMPLES` samples inside the record (a spline's error grows
   near the record's ends).
5. **The readings** at those times: an interpolating spline of degree :data:`SPLINE_DEGREE`
   (``scipy.interpolate.make_interp_spline``) through each probe's samples.  For a harmonic of
   ``nu`` cycles per sample (``nu = k / S``, S samples per revolution), a cardinal spline of
   degree m interpolates with a relative error at most ``2 (nu / (1 - nu))^(m + 1)`` (the
   first alias of its frequency response dominates; checked in ``tests/test_spindle_files.py``):
   with m = 7 and the rule for N below, the top harmonic separated has ``nu <= 1/3`` and an
   error <= 2 (1/2)^8 = 0.8 % of its own amplitude, harmonics at half the band <= 5e-6.
6. **N**, the samples per revolution: the largest power of two not above ``2 S / 3`` (S the
   mean samples per revolution), within ``MIN_SAMPLES..MAX_SAMPLES``.  Then the top harmonic
   separated, ``(N - 1) // 2``, is at most a third of the sample rate's samples per revolution
   (the bound above); a power of two for the FFT.  A file whose S gives N < MIN_SAMPLES (S < 12)
   is refused.

Written by hand: resampling by a fitted phase is the method; numpy fits the polynomial and scipy
interpolates.
"""

from __future__ import annotations

import warnings

import numpy as np
from scipy.interpolate import make_interp_spline

from .probedata import MAX_SAMPLES, ProbeFileError, Resampling, _show_number
from .probes import MIN_SAMPLES

__all__ = ["resample_time_series", "UnsteadySpeedWarning", "FIT_DEGREE", "SPLINE_DEGREE",
           "EDGE_SAMPLES", "TIME_STEP_TOLERANCE", "MARK_INTERVAL_TOLERANCE",
           "MIN_REVOLUTIONS", "interpolation_bound", "samples_per_revolution_rule"]

#: The degree of the spindle's revolutions as a polynomial in time: speed and linear drift.
FIT_DEGREE = 2
#: The degree of the interpolating spline of the probes in time (odd).
SPLINE_DEGREE = 7
#: Resampled times lie at least this many samples inside the record: a spline's error near an end
#: of the record decays by a factor 0.535 a sample inwards (the root of the Euler-Frobenius
#: polynomial of degree 7 nearest -1), to below 5e-5 of its size at the end 16 samples in,
#: where it is under the interior's bound at every frequency tested.
EDGE_SAMPLES = 16
#: A step of ``time_s`` may differ from the sample period by this fraction (rounded time stamps);
#: a dropped sample (2 periods) or a repeated one (0) is refused.
TIME_STEP_TOLERANCE = 0.5
#: An interval between index pulses may differ from their median by this fraction (the drift); a
#: missed pulse (2 revolutions) or a bouncing one is refused.
MARK_INTERVAL_TOLERANCE = 1.0 / 3.0
#: Complete revolutions needed: the asynchronous motion needs at least two.
MIN_REVOLUTIONS = 2


class UnsteadySpeedWarning(UserWarning):
    """The fitted speed and drift leave a mark more than one sample period off: the spindle's
    speed is not steady within the record (the resampled angles err by about that much)."""


def interpolation_bound(nu, *, degree: int = SPLINE_DEGREE):
    """The largest relative error of a cardinal spline interpolating a sinusoid.

    The spline of odd degree m through the samples of ``exp(2 pi i nu t)`` (t in samples) is
    that frequency and its aliases ``nu + j`` with weights ``w_j / W``, ``w_j = (nu / (nu +
    j))^(m + 1)``, ``W = sum_j w_j`` (Schoenberg's cardinal interpolation); its error is at most
    ``|1 - w_0 / W| + sum_{j != 0} w_j / W = 2 (W - 1) / W``, about ``2 (nu / (1 - nu))^(m + 1)``
    (the first alias dominates).  Away from the record's ends (:data:`EDGE_SAMPLES`).

    Parameters
    ----------
    nu : float or array
        Frequency in cycles per sample, 0 <= nu < 1/2.
    degree : int
        The spline's degree (odd).

    Returns
    -------
    float or array
        The bound, relative to the sinusoid's amplitude.
    """
    nu = np.asarray(nu, dtype=float)
    j = np.arange(-64, 65)
    j = j[j != 0].reshape((-1,) + (1,) * nu.ndim)
    aliases = np.sum((nu / (nu + j)) ** (degree + 1), axis=0)
    return 2.0 * aliases / (1.0 + aliases)


def samples_per_revolution_rule(samples_per_revolution: float) -> int:
    """N: the largest power of two not above 2/3 of the samples per revolution.

    At most :data:`~mtaccuracy.spindle.probedata.MAX_SAMPLES`; it may be below MIN_SAMPLES (the
    reader refuses that).

    Parameters
    ----------
    samples_per_revolution : float
        S, the mean samples per revolution of the record.

    Returns
    -------
    int
        N.
    """
    top = 2.0 * float(samples_per_revolution) / 3.0
    n = 1 << max(int(np.floor(np.log2(top))), 0) if top >= 1 else 1
    return min(n, MAX_SAMPLES)


_show = _show_number


def _clock(time_s, refuse, lines):
    """(t0, dt): the sample clock fitted to ``time_s``; refuses a time not increasing, a step
    far from the period, a time stamp more than half a period off the fitted line."""
    t = np.asarray(time_s, dtype=float)
    n = t.size
    step = np.diff(t)
    back = np.flatnonzero(step <= 0)
    if back.size:
        i = int(back[0])
        refuse(i + 1, f"time_s must increase: {_show(t[i + 1])} s does not come after "
                      f"{_show(t[i])} s (line {lines(i)}); the rows are the samples in the order "
                      f"recorded, each with its own time")
    period = float(np.median(step))
    off = np.flatnonzero(np.abs(step - period) > TIME_STEP_TOLERANCE * period)
    if off.size:
        i = int(off[0])
        refuse(i + 1, (
            f"time_s steps {step[i]:.6g} s from line {lines(i)} ({_show(t[i])} s) to here "
            f"({_show(t[i + 1])} s), {step[i] / period:.3g} sample periods (the period is "
            f"{period:.6g} s): samples dropped or repeated; a DAQ samples on a uniform clock: "
            f"record again, or keep the part of the file before or after the gap"))
    u = np.arange(n, dtype=float)
    t0, dt = np.polynomial.polynomial.polyfit(u, t, 1)
    dev = np.abs(t - (t0 + dt * u))
    if dev.max() > 0.5 * dt:
        i = int(np.argmax(dev))
        refuse(i, f"time_s {_show(t[i])} s lies {dev[i] / dt:.3g} sample periods off the "
                  f"uniform clock fitted to the whole file (period {dt:.6g} s): the sample "
                  f"rate is not steady")
    return float(t0), float(dt)


def _index_marks(index, refuse, lines, header_line):
    """The marks of an index channel: (sample position of each mark, rows of their edges)."""
    v = np.asarray(index, dtype=float)
    bad = np.flatnonzero((v != 0) & (v != 1))
    if bad.size:
        i = int(bad[0])
        refuse(i, f"index is {_show(v[i])}; the index channel is 1 on the samples where the "
                  f"once-per-revolution mark is seen, else 0 (a voltage? write 1 where it "
                  f"exceeds half its high level, else 0)")
    rises = np.flatnonzero((v[1:] == 1) & (v[:-1] == 0)) + 1
    if rises.size == 0:
        refuse(None, "the index column has no pulse (no 0 followed by 1): the "
                     "once-per-revolution mark was not recorded", line=header_line)
    if rises.size < MIN_REVOLUTIONS + 1:
        refuse(int(rises[-1]), (
            f"{rises.size} index pulse(s) (line(s) {', '.join(str(lines(r)) for r in rises)}); "
            f"at least {MIN_REVOLUTIONS + 1} are needed, for {MIN_REVOLUTIONS} complete "
            f"revolutions between the first and the last: record longer"))
    gaps = np.diff(rises).astype(float)
    typical = float(np.median(gaps))
    off = np.flatnonzero(np.abs(gaps - typical) > MARK_INTERVAL_TOLERANCE * typical)
    if off.size:
        j = int(off[0])
        what = ("a pulse missed (or the spindle slowed down)" if gaps[j] > typical else
                "a pulse that bounced (0, 1, 0, 1 within a revolution) or a second mark")
        refuse(int(rises[j + 1]), (
            f"this index pulse comes {int(gaps[j])} samples after the one at line "
            f"{lines(int(rises[j]))}, where the pulses are {typical:g} samples apart "
            f"(median): {what}; the pulses must mark every revolution once"))
    return rises - 0.5, rises


def _encoder_marks(encoder_deg, refuse, lines):
    """The encoder's angle at every sample, unwrapped, in revolutions."""
    a = np.asarray(encoder_deg, dtype=float)
    step = np.diff(a)
    wrap = step < -180.0
    turns = np.concatenate([[0.0], np.cumsum(wrap)])
    step = step + 360.0 * wrap
    bad = np.flatnonzero((step <= 0) | (step >= 180))
    if bad.size:
        i = int(bad[0])
        why = ("the spindle turning the other way? Negate encoder_deg and every probe's "
               "mounting angle" if step[i] <= 0 else
               "more than half a turn between two samples: the sample rate is too low")
        refuse(i + 1, (
            f"encoder_deg must increase (wrapping at 360 or counting on): {_show(a[i + 1])} deg "
            f"after {_show(a[i])} deg (line {lines(i)}); {why}"))
    return (a + 360.0 * turns) / 360.0


def resample_time_series(time_s, signals_um, *, index=None, encoder_deg=None, path="<arrays>",
                         lines=None, header_line=1, stacklevel=2):
    """Resample time-sampled probe readings onto N equal spindle angles per revolution.

    The method, the rule for N and the interpolation's bound are the module's
    (:mod:`~mtaccuracy.spindle.timefile`).

    Parameters
    ----------
    time_s : array (n,)
        Sample times (s), increasing, on a uniform clock.
    signals_um : array (n, L)
        Probe readings (um).
    index : array (n,), optional
        1 on the samples where the once-per-revolution mark is seen, else 0.
    encoder_deg : array (n,), optional
        The spindle angle (deg), increasing, wrapping at 360 or accumulating.  Exactly one of
        ``index`` and ``encoder_deg``.
    path : str
        The file's name in messages.
    lines : callable, optional
        ``lines(row)``: the file line of a data row (default ``row + 2``: a header and no
        blank lines).
    header_line : int
        The header's line (messages about a whole column).
    stacklevel : int
        Where :class:`UnsteadySpeedWarning` points, as ``warnings.warn`` counts (2: at the
        caller of this function).

    Returns
    -------
    signals : array (R, L, N)
        The readings at ``theta_j = 360 j / N`` deg of each complete revolution (um).
    resampling : Resampling
        What was done (sample rate, marks, speed, drift, residual, N).

    Raises
    ------
    ProbeFileError
        Naming the line: time not increasing or not uniform, an index not 0/1, no pulse,
        fewer than 3 pulses, a missed or bouncing pulse, an encoder not increasing, fewer
        than 12 samples per revolution (N < MIN_SAMPLES), fewer than 2 complete revolutions.

    Warns
    -----
    UnsteadySpeedWarning
        When a mark's residual exceeds one sample period.
    """
    lines = (lambda row: row + 2) if lines is None else lines

    def refuse(row, message, line=None):
        raise ProbeFileError(path, line if row is None else lines(row), message)

    if (index is None) == (encoder_deg is None):
        raise ValueError("give exactly one of index and encoder_deg")
    y = np.asarray(signals_um, dtype=float)
    n = y.shape[0]
    if n < 2 * EDGE_SAMPLES + MIN_SAMPLES:
        refuse(None, f"{n} samples; a time-sampled file needs complete revolutions of at "
                     f"least 12 samples each, and {EDGE_SAMPLES} samples before and after",
               line=header_line)
    t0, dt = _clock(time_s, refuse, lines)
    u_all = np.arange(n, dtype=float)
    if index is not None:
        u_marks, rows = _index_marks(index, refuse, lines, header_line)
        phase_at = np.arange(u_marks.size, dtype=float)
        fit = np.polynomial.Polynomial.fit(u_marks, phase_at, FIT_DEGREE)
        first_row, last_row = int(rows[0]), int(rows[-1])
        r_lo, r_hi = 0, u_marks.size - 1            # revolutions r_lo .. r_hi - 1
        residual_rev = phase_at - fit(u_marks)
        residual_speed = fit.deriv()(u_marks)
    else:
        revs = _encoder_marks(encoder_deg, refuse, lines)
        fit = np.polynomial.Polynomial.fit(u_all, revs, FIT_DEGREE)
        residual_rev = revs - fit(u_all)
        residual_speed = fit.deriv()(u_all)
        r_lo, r_hi = int(np.ceil(fit(0.0))), int(np.floor(fit(n - 1.0)))
        whole = np.flatnonzero(np.diff(np.floor(revs)) > 0) + 1
        first_row = int(whole[0]) if whole.size else 0
        last_row = int(whole[-1]) if whole.size else n - 1
    speed = fit.deriv()                          # revolutions per sample
    ends = speed(np.array([0.0, n - 1.0]))
    if np.any(ends <= 0):
        refuse(None, "the fitted speed changes sign within the record: the spindle stopped or "
                     "reversed; keep the part of the file at speed", line=header_line)
    s_mean = 1.0 / float(np.mean(speed(u_all)))
    n_samples = samples_per_revolution_rule(s_mean)
    if n_samples < MIN_SAMPLES:
        refuse(None, (f"{s_mean:.3g} samples per revolution ({1 / dt:.6g} Hz at "
                      f"{60 * float(np.mean(speed(u_all))) / dt:.4g} rpm); at least "
                      f"{1.5 * MIN_SAMPLES:g} are needed to resample onto {MIN_SAMPLES} angles "
                      f"(N = a power of two <= 2/3 of them): sample faster or turn slower"),
               line=header_line)
    targets = np.arange(r_lo, r_hi)[:, None] + np.arange(n_samples)[None, :] / n_samples
    u = _invert(fit, targets, s_mean)
    end = _invert(fit, np.arange(r_lo, r_hi) + 1.0, s_mean)
    keep = (u[:, 0] >= EDGE_SAMPLES) & (end <= n - 1 - EDGE_SAMPLES)
    if keep.sum() < MIN_REVOLUTIONS:
        refuse(last_row, (
            f"{int(keep.sum())} complete revolution(s) between the first mark (line "
            f"{lines(first_row)}) and the last (line {lines(last_row)}) at least {EDGE_SAMPLES}"
            f" samples inside the record; at least {MIN_REVOLUTIONS} are needed: record "
            f"longer"))
    u = u[keep]              # a contiguous run: the revolutions' times increase with r
    spline = make_interp_spline(u_all, y, k=SPLINE_DEGREE, axis=0)
    signals = spline(u.ravel()).reshape(u.shape[0], n_samples, y.shape[1]).transpose(0, 2, 1)
    residual_s = float(np.max(np.abs(residual_rev / residual_speed))) * dt
    if residual_s > dt:
        marks = "index pulses" if index is not None else "encoder angles"
        warnings.warn(
            f"{path}: the speed and drift fitted to the {marks} leave a residual of "
            f"{residual_s * 1e6:.3g} us, more than the sample period "
            f"({dt * 1e6:.3g} us) explains: the spindle's speed is not steady within the record, "
            f"and the resampled angles err by about that much; keep a steadier part",
            UnsteadySpeedWarning, stacklevel=stacklevel + 1)
    mid = 0.5 * (u[0, 0] + u[-1, -1])
    rate = float(speed(mid))
    s_min = 1.0 / float(speed(np.array([u[0, 0], u[-1, -1]])).max())
    info = Resampling(
        reference="index" if index is not None else "encoder", sample_rate_hz=1.0 / dt,
        samples_per_revolution=s_mean, n_samples=n_samples,
        marks=int(u_marks.size if index is not None else r_hi - r_lo + 1),
        revolutions=int(u.shape[0]), speed_rpm=60.0 * rate / dt,
        drift_per_s=float(speed.deriv()(mid)) / rate / dt,
        fit_degree=FIT_DEGREE, residual_s=residual_s, residual_limit_s=dt,
        spline_degree=SPLINE_DEGREE,
        interpolation_bound=float(interpolation_bound(((n_samples - 1) // 2) / s_min)),
        first_line=int(lines(first_row)), last_line=int(lines(last_row)),
        start_s=t0 + dt * float(u[0, 0]))
    return np.ascontiguousarray(signals), info


def _invert(fit, targets, s_mean):
    """The sample positions where the fitted revolutions equal ``targets`` (Newton's method,
    from the mean speed; the polynomial is nearly linear, so a few steps reach rounding)."""
    speed = fit.deriv()
    u = (targets - fit(0.0)) * s_mean
    for _ in range(50):
        step = (fit(u) - targets) / speed(u)
        u = u - step
        if np.max(np.abs(step)) < 1e-9:
            break
    return u
