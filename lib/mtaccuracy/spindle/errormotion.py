"""Radial error motion of an axis of rotation in the terms of ISO 230-7.

From the motion ``(x(theta), y(theta))`` of every revolution that a multi-probe separation gives
(:func:`~mtaccuracy.spindle.probes.separate_probes`).

ISO 230-7:2015 (Geometric accuracy of axes of rotation), Clause 3, in brief:

* **Sensitive direction.**  *Fixed*: the direction does not turn with the spindle (a turning
  tool facing a workpiece on a lathe spindle); the error motion is the projection
  ``u = x cos(alpha) + y sin(alpha)``.  *Rotating*: it turns with the spindle (a boring bar, a
  milling cutter).  With the probe file's geometry (:mod:`~mtaccuracy.spindle.probes`: the
  probe at ``phi`` reads ``r(theta + phi)``, so the spindle turns the artefact by ``-theta``
  in the probes' frame; ``rotation="cw"``) a direction fixed to the spindle that points at
  ``alpha`` when ``theta = 0`` points at ``alpha - theta``: ``u = x cos(alpha - theta) + y
  sin(alpha - theta)``; with ``rotation="ccw"`` (the probe reads ``r(phi - theta)``, the
  spindle turns the artefact by ``+theta``) it points at ``alpha + theta``.  (``x cos(theta +
  alpha) + y sin(theta + alpha)``, Eq. 9 of Yang et al. 2021 and
  :func:`~mtaccuracy.spindle.separation.rotation_error`, turns against the spindle under this
  geometry: a centring error fixed to the artefact would read as a twice-per-revolution
  motion there, and as the constant it is here.)
* **Polar plots.**  The error motion drawn at the spindle angle around a base circle, to a
  scale: the *total* error motion polar plot (every revolution), the *synchronous* one (the
  average over revolutions at each angle) and the *asynchronous* one (the deviations of the
  revolutions from that average, a band around it).
* **Centres.**  *PC* the polar chart's centre; *LSC* the centre of the least-squares circle of
  the plot; *MRS* the centre of the two concentric circles of minimum radial separation that
  contain it.  ISO 230-7 uses LSC unless another is stated, and so does this module.  Centring
  the plot on LSC or MRS removes its *fundamental* (once-per-revolution) component, which for a
  radial error motion is the centring of the artefact on the axis, not error motion.
* **Values.**  Total and synchronous error motion value: the difference in radii of two
  circles concentric about the stated centre that just contain the total or synchronous polar
  plot.  Asynchronous error motion value: the largest width of the asynchronous band measured
  along a radial line (through PC).

The error motion is micrometres against a base circle of any radius; as roundness instruments
do, the circles are evaluated in the limit of a large base circle (the limacon), where the LSC
centring is the least-squares fit of ``c_0 + a cos + b sin`` (:func:`~mtaccuracy.roundness.
lsc_roundness`), the MRS centring a linear programme (:func:`~mtaccuracy.roundness.
mz_roundness`), and a radial line through any of these centres crosses the band at one spindle
angle: the asynchronous value is ``max_theta (max_rev u - min_rev u)``.  The total plot's LSC
is that of the synchronous plot (every revolution has the same angles).  Why hand-written: the
definitions are the standard's; the fits are scipy's (``linalg.lstsq``, ``optimize.linprog``),
the MRS of a band (the total plot) a small ``linprog`` beside :func:`mz_roundness`; no
maintained package evaluates ISO 230-7.

**Filter.**  ISO 230-7 asks for the measurement's bandwidth to be stated, in undulations per
revolution (UPR).  ``max_upr`` (:func:`error_motion_table`, :func:`filter_motion`) is the
Gaussian low-pass of ISO 16610-21 (:func:`~mtaccuracy.roundness.upr_filter`, 50 % at the
cutoff), applied to the motion of all the revolutions as one continuous record; 0 is no filter.
The probes' noise is white up to ``N / 2`` UPR, so without a filter it widens the asynchronous
band by about its own size; below the cutoff it stays.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.optimize import linprog

from ..roundness import TWO_PI, lsc_roundness, mz_roundness, upr_filter
from .checks import ROTATIONS

__all__ = ["CENTRES", "ErrorMotion", "sensitive_component", "radial_error_motion",
           "error_motion_table", "fixed_directions", "about_lsc", "filter_motion",
           "error_motion_samples", "asynchronous_spectrum"]

#: The polar-plot centres offered (ISO 230-7): LSC (the default) and MRS.
CENTRES = ("LSC", "MRS")


def sensitive_component(dx, dy, theta, *, direction, rotating: bool = False,
                        rotation: str = "cw") -> np.ndarray:
    """The radial error motion along a fixed or rotating sensitive direction (ISO 230-7, Cl. 3).

    Fixed: ``u = x cos(alpha) + y sin(alpha)``.  Rotating (the direction turns with the spindle,
    pointing at ``alpha`` when ``theta = 0``; module docstring for the sense):
    ``u = x cos(alpha -+ theta) + y sin(alpha -+ theta)``, ``-`` for ``rotation="cw"``, ``+`` for
    ``"ccw"``.

    Parameters
    ----------
    dx, dy : arrays (..., N)
        Radial error motion in the probes' frame (any length unit), at the spindle angles
        ``theta``.
    theta : array (N,)
        Spindle angle of each sample (rad).
    direction : float or array (D,)
        ``alpha`` (rad): the fixed direction, or the rotating one at ``theta = 0``.
    rotating : bool
        A rotating sensitive direction instead of a fixed one.
    rotation : {"cw", "ccw"}
        The sense the spindle turns in (:func:`~mtaccuracy.spindle.probes.separate_probes`).

    Returns
    -------
    array (D, ..., N) or (..., N)
        ``u``, in the unit of ``dx``; a leading axis per direction when ``direction`` is an
        array.
    """
    dx, dy = np.asarray(dx, dtype=float), np.asarray(dy, dtype=float)
    theta = np.asarray(theta, dtype=float)
    if dx.shape != dy.shape or dx.ndim < 1 or theta.shape != dx.shape[-1:]:
        raise ValueError(f"dx, dy must share a shape (..., N) and theta be (N,); got "
                         f"{dx.shape}, {dy.shape}, {theta.shape}")
    alpha = np.asarray(direction, dtype=float)
    if alpha.ndim > 1 or not np.all(np.isfinite(alpha)):
        raise ValueError(f"direction must be a finite angle or a 1-D array of them (rad), got "
                         f"{direction!r}")
    if rotation not in ROTATIONS:
        raise ValueError(f"rotation must be 'cw' or 'ccw', got {rotation!r}")
    a = alpha.reshape(alpha.shape + (1,) * dx.ndim)
    turn = -theta if rotation == "cw" else theta
    ang = a + turn if rotating else a + 0.0 * theta
    return dx * np.cos(ang) + dy * np.sin(ang)


@dataclass
class ErrorMotion:
    """Radial error motion along one sensitive direction, as ISO 230-7 evaluates it.

    The result of :func:`radial_error_motion`.

    Attributes
    ----------
    centre : str
        ``"LSC"`` or ``"MRS"``, the centre of the polar plots and of the values.
    synchronous_value : array (...)
        Synchronous error motion value (unit of the motion).
    asynchronous_value : array (...)
        Asynchronous error motion value; NaN with a single revolution.
    total_value : array (...)
        Total error motion value.
    synchronous_plot : array (..., N)
        The synchronous polar plot's radius about the centre, minus the mean radius of the
        circles (the plot is ``base + scale x synchronous_plot``).
    total_plot : array (..., R, N)
        Every revolution about the same centre (the asynchronous band lies between its minimum
        and maximum over revolutions).
    circles : array (..., 2)
        Inner and outer radius of the circles about the centre that just contain the
        synchronous plot, in the coordinates of ``synchronous_plot``.
    fundamental : array (..., 2)
        ``a, b`` of the once-per-revolution component ``a cos + b sin`` the centre removes
        (grid angles ``2 pi n / N`` from the first sample).
    """

    centre: str
    synchronous_value: np.ndarray
    asynchronous_value: np.ndarray
    total_value: np.ndarray
    synchronous_plot: np.ndarray
    total_plot: np.ndarray
    circles: np.ndarray
    fundamental: np.ndarray


def _band_zone(upper, lower):
    """Minimum radial separation of a band (limacon model): minimise ``t_out - t_in`` over
    ``(a, b, t_in, t_out)`` with ``upper_n - a cos - b sin <= t_out`` and ``lower_n - a cos -
    b sin >= t_in`` (``scipy.optimize.linprog``, HiGHS), one programme per leading index;
    :func:`~mtaccuracy.roundness.mz_roundness` when ``upper = lower``."""
    up, lo = np.asarray(upper, dtype=float), np.asarray(lower, dtype=float)
    n = up.shape[-1]
    t = TWO_PI * np.arange(n) / n
    c, s = np.cos(t)[:, None], np.sin(t)[:, None]
    zero, one = np.zeros((n, 1)), np.ones((n, 1))
    a_ub = np.block([[-c, -s, zero, -one], [c, s, one, zero]])
    cost = np.array([0.0, 0.0, -1.0, 1.0])
    flat_u, flat_l = up.reshape(-1, n), lo.reshape(-1, n)
    width = np.empty(len(flat_u))
    for i, (ui, li) in enumerate(zip(flat_u, flat_l, strict=True)):
        res = linprog(cost, A_ub=a_ub, b_ub=np.concatenate([-ui, li]),
                      bounds=[(None, None)] * 4, method="highs")
        if not res.success:
            raise RuntimeError(f"minimum radial separation LP failed: {res.message}")
        width[i] = res.fun
    return width.reshape(up.shape[:-1])


def radial_error_motion(u, *, centre: str = "LSC") -> ErrorMotion:
    """Synchronous, asynchronous and total radial error motion values (ISO 230-7:2015, Cl. 3).

    Of ``R`` revolutions along one sensitive direction (Clause 3: error motion polar plots,
    polar plot centres, error motion values).

    The synchronous polar plot is the average of the revolutions at each angle.  The centre
    (LSC by default, as ISO 230-7 when none is stated; or MRS) is fitted to the synchronous plot
    in the limacon model (module docstring), which removes the fundamental (the artefact's
    centring).  Synchronous value: outer minus inner radius of the circles about that centre
    that just contain the synchronous plot (:func:`~mtaccuracy.roundness.lsc_roundness` or
    :func:`~mtaccuracy.roundness.mz_roundness` of it).  Asynchronous value: the largest spread
    of the revolutions at one spindle angle, ``max_n (max_r u - min_r u)``, the width of the
    band along a radial line.  Total value: the same circles for every revolution at once,
    about the total plot's own centre (LSC: the synchronous plot's, every revolution having the
    same angles; MRS: the band's own minimum radial separation).

    Parameters
    ----------
    u : array (..., R, N)
        Error motion along the sensitive direction (:func:`sensitive_component`; any length
        unit), R >= 1 revolutions of N >= 8 samples equally spaced over a revolution.
    centre : {"LSC", "MRS"}
        The polar plots' centre.

    Returns
    -------
    ErrorMotion
        The values (..., ) in the unit of ``u``, and the plots about the centre.
    """
    if centre not in CENTRES:
        raise ValueError(f"centre must be one of {', '.join(CENTRES)} (ISO 230-7), got "
                         f"{centre!r}")
    u = np.asarray(u, dtype=float)
    if u.ndim < 2 or u.shape[-1] < 8 or u.shape[-2] < 1 or not np.all(np.isfinite(u)):
        raise ValueError(f"u must be finite, (..., R, N) with R >= 1 revolutions of N >= 8 "
                         f"samples, got shape {u.shape}")
    n = u.shape[-1]
    t = TWO_PI * np.arange(n) / n
    sync = u.mean(axis=-2)
    if centre == "LSC":
        sync_value, coef = lsc_roundness(sync)
        ab = coef[..., 1:]
        fit = coef[..., :1] + ab[..., :1] * np.cos(t) + ab[..., 1:] * np.sin(t)
    else:
        sync_value, ab = mz_roundness(sync)
        rest = sync - ab[..., :1] * np.cos(t) - ab[..., 1:] * np.sin(t)
        mid = 0.5 * (rest.max(axis=-1) + rest.min(axis=-1))
        fit = mid[..., None] + (sync - rest)
    sync_plot = sync - fit
    total_plot = u - fit[..., None, :]
    if centre == "LSC":
        total_value = np.ptp(total_plot, axis=(-2, -1))
    else:
        total_value = _band_zone(u.max(axis=-2), u.min(axis=-2))
    asynchronous = (np.ptp(u, axis=-2).max(axis=-1) if u.shape[-2] > 1
                    else np.full(u.shape[:-2], np.nan))
    circles = np.stack([sync_plot.min(axis=-1), sync_plot.max(axis=-1)], axis=-1)
    return ErrorMotion(centre=centre, synchronous_value=np.asarray(sync_value),
                       asynchronous_value=np.asarray(asynchronous),
                       total_value=np.asarray(total_value), synchronous_plot=sync_plot,
                       total_plot=total_plot, circles=circles, fundamental=np.asarray(ab))


def error_motion_table(dx, dy, theta, *, fixed_directions, rotating_direction,
                       centre: str = "LSC", rotation: str = "cw", max_upr: float = 0.0):
    """ISO 230-7 radial error motion values along fixed sensitive directions and a rotating one.

    The motion is first low-pass filtered at ``max_upr`` (:func:`filter_motion`; 0: not).

    Parameters
    ----------
    dx, dy : arrays (R, N)
        Radial error motion of every revolution (um) at the spindle angles ``theta``.
    theta : array (N,)
        Spindle angles (rad).
    fixed_directions : array (D,)
        Fixed sensitive directions (rad), e.g. the probes' axes.
    rotating_direction : float
        The rotating sensitive direction at ``theta = 0`` (rad).
    centre : {"LSC", "MRS"}
        The polar plots' centre.
    rotation : {"cw", "ccw"}
        The sense the spindle turns in: the rotating direction points at ``alpha -+ theta``.
    max_upr : float
        The Gaussian low-pass cutoff (undulations per revolution), 0 for none.

    Returns
    -------
    table : DataFrame
        One row per direction: ``sensitive_direction`` ("fixed" or "rotating"),
        ``direction_deg``, ``synchronous_um``, ``asynchronous_um``, ``total_um``.
    motions : list of ErrorMotion
        In the table's order (the polar plots).
    """
    fixed = np.atleast_1d(np.asarray(fixed_directions, dtype=float))
    dx, dy = filter_motion(dx, dy, max_upr=max_upr)
    u_fixed = sensitive_component(dx, dy, theta, direction=fixed)                 # (D, R, N)
    u_rot = sensitive_component(dx, dy, theta, direction=float(rotating_direction),
                                rotating=True, rotation=rotation)
    motions = [radial_error_motion(u, centre=centre) for u in (*u_fixed, u_rot)]
    table = pd.DataFrame({
        "sensitive_direction": ["fixed"] * len(fixed) + ["rotating"],
        "direction_deg": np.rad2deg(np.r_[fixed, rotating_direction]),
        "synchronous_um": [float(m.synchronous_value) for m in motions],
        "asynchronous_um": [float(m.asynchronous_value) for m in motions],
        "total_um": [float(m.total_value) for m in motions]})
    return table, motions


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


def fixed_directions(data, report_probes) -> np.ndarray:
    """Fixed sensitive directions along the named probes' axes (all probes when none is named).

    The probes are named by their mounting angles (deg); an angle that is no probe's is refused.

    Parameters
    ----------
    data : ProbeData
        The probe file (:class:`~mtaccuracy.spindle.probedata.ProbeData`).
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


def filter_motion(dx, dy, *, max_upr: float):
    """The radial error motion low-pass filtered in undulations per revolution (ISO 230-7).

    The Gaussian filter of ISO 16610-21 (:func:`~mtaccuracy.roundness.upr_filter`, 50 % at the
    cutoff) on the R revolutions taken as one continuous record (module docstring).

    Parameters
    ----------
    dx, dy : arrays (..., R, N)
        Radial error motion of every revolution (any length unit).
    max_upr : float
        The cutoff (undulations per revolution), >= 0; 0 returns the motion as it is.

    Returns
    -------
    dx, dy : arrays (..., R, N)
        Filtered, in the unit of ``dx``.
    """
    return (upr_filter(dx, max_upr=max_upr, continuous=True),
            upr_filter(dy, max_upr=max_upr, continuous=True))


def error_motion_samples(dx, dy, *, revolutions, angle_deg) -> pd.DataFrame:
    """The separated radial error motion per sample, as a table.

    Parameters
    ----------
    dx, dy : arrays (R, N)
        Radial error motion in the probes' frame (um), filtered as the caller states.
    revolutions : array of int (R,)
        The revolutions' numbers.
    angle_deg : array (N,)
        The spindle angle of each sample (deg).

    Returns
    -------
    DataFrame
        ``revolution, angle_deg, x_um, y_um``, R N rows, revolution by revolution.
    """
    dx, dy = np.asarray(dx, dtype=float), np.asarray(dy, dtype=float)
    revolutions, angle_deg = np.asarray(revolutions), np.asarray(angle_deg, dtype=float)
    if dx.ndim != 2 or dx.shape != dy.shape or dx.shape != (len(revolutions), len(angle_deg)):
        raise ValueError(f"dx, dy must be (R, N) = ({len(revolutions)}, {len(angle_deg)}), got "
                         f"{dx.shape} and {dy.shape}")
    r, n = dx.shape
    return pd.DataFrame({"revolution": np.repeat(revolutions, n),
                         "angle_deg": np.tile(angle_deg, r),
                         "x_um": dx.ravel(), "y_um": dy.ravel()})


def asynchronous_spectrum(dx, dy) -> pd.DataFrame:
    """The amplitude spectrum of the asynchronous radial error motion, in cycles per revolution.

    The asynchronous part is the motion less its mean over the revolutions at each angle (the
    synchronous part), taken as one continuous record of the R revolutions, R N samples.  Its
    discrete Fourier transform ``X_m``, ``Y_m`` gives the frequencies ``m / R`` cycles per
    revolution, ``m = 0..R N / 2`` (resolution ``1 / R``).  The amplitude is the single-sided
    amplitude of the radial motion vector, ``sqrt(A_x^2 + A_y^2)`` with ``A_x = 2 |X_m| / (R
    N)`` (``|X_m| / (R N)`` at 0 and at ``N / 2``), likewise ``A_y``: a motion ``a cos(2 pi f
    t)`` along any one direction reads ``a`` at ``f``; a circular whirl of radius ``a`` reads
    ``sqrt(2) a``.  The synchronous part holds every integer frequency (``m`` a multiple of R),
    so there the asynchronous amplitude is 0 by construction and is written as exactly 0.

    Parameters
    ----------
    dx, dy : arrays (R, N)
        Radial error motion of every revolution (um), R >= 2.

    Returns
    -------
    DataFrame
        ``frequency_cpr``, ``amplitude_um``: R N / 2 + 1 rows (N even), ascending frequency.
    """
    dx, dy = np.asarray(dx, dtype=float), np.asarray(dy, dtype=float)
    if dx.ndim != 2 or dx.shape != dy.shape or dx.shape[0] < 2:
        raise ValueError(f"dx, dy must share a shape (R, N) with R >= 2 revolutions, got "
                         f"{dx.shape} and {dy.shape}")
    r, n = dx.shape
    amp = []
    for v in (dx, dy):
        a = np.abs(np.fft.rfft((v - v.mean(axis=0)).ravel())) / (r * n)
        a[1:(r * n + 1) // 2] *= 2                      # single-sided; not at 0 or R N / 2
        a[::r] = 0.0                                    # integer frequencies: synchronous
        amp.append(a)
    m = np.arange(len(amp[0]))
    return pd.DataFrame({"frequency_cpr": m / r, "amplitude_um": np.hypot(*amp)})
