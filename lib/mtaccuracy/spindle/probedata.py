"""A multi-probe measurement, whatever file it came from, and the checks it passes.

:class:`ProbeData` is what a reader of probe readings returns (:func:`~mtaccuracy.spindle.
probefile.read_probe_file` for the angle- or time-sampled CSV file of
``data/spindle/README.md``), and
:class:`ProbeFileError` what it raises, naming the file and the line.  The checks here hold
for any file format: the probe columns ``probe_<mounting angle in degrees>_um``, plausible
readings in micrometres, and a probe layout that separates the harmonics asked for
(:func:`~mtaccuracy.spindle.probes.layout_cancelled`).  Written by hand: the schema is ours.
"""

from __future__ import annotations

import re
import warnings
from dataclasses import dataclass

import numpy as np

from .probes import (
    _CANCELLED_HINT,
    MAX_PROBES,
    MIN_PROBES,
    _cancelled_message,
    _check_band,
    layout_cancelled,
)
from .separation import TWO_PI, CancelledHarmonicsWarning

__all__ = ["ProbeFileError", "ProbeData", "Resampling", "probe_column", "MAX_SAMPLES", "MAX_ABS_UM",
           "MIN_SPAN_UM"]

#: Samples per revolution: up to 16384 (harmonics up to 8191; a roundness instrument takes 3600
#: points a turn at most, a spindle analyser 4096); at least
#: :data:`~mtaccuracy.spindle.probes.MIN_SAMPLES`.
MAX_SAMPLES = 16384
#: Plausible readings (um).  A displacement probe used for spindle tests (capacitive, inductive,
#: LVDT) has a range within +-2 mm; a reading beyond +-10 mm is not one (in nm, most likely).
#: Every probe's readings over the file span at least 0.01 um (10 nm): its noise over thousands
#: of samples, the artefact's form and any spindle's error motion (an air-bearing spindle's,
#: about 10-50 nm, included) exceed that; a file in mm spans 1000 times less than in um, so a
#: file of a spindle whose runout is below 10 um, written in mm, is refused.
MAX_ABS_UM = 10_000.0
MIN_SPAN_UM = 0.01
_PROBE = re.compile(r"^probe_(?P<angle>[+-]?(?:\d+(?:\.\d*)?|\.\d+))_(?P<unit>[^_]+)$")


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
class Resampling:
    """How a time-sampled probe file was resampled onto equal spindle angles.

    Made by :mod:`~mtaccuracy.spindle.timefile`, for a notebook to print (:meth:`describe`).

    Attributes
    ----------
    reference : {"index", "encoder"}
        What gave the spindle angle: a once-per-revolution index pulse or an encoder.
    sample_rate_hz : float
        The data acquisition's sample rate (Hz), fitted to ``time_s``.
    samples_per_revolution : float
        The mean samples per revolution of the file, S.
    n_samples : int
        N, the equal angles per revolution resampled onto.
    marks : int
        The index pulses (or the encoder's zero crossings) the speed was fitted to.
    revolutions : int
        The complete revolutions resampled, R.
    speed_rpm : float
        The fitted mean speed (rev/min) over the marks.
    drift_per_s : float
        The fitted relative change of speed per second (1/s; 0.005 is +0.5 %/s).
    fit_degree : int
        The degree of the polynomial of the spindle's revolutions in time.
    residual_s : float
        The largest residual of the fit, in time (s): a mark's, or an encoder sample's.
    residual_limit_s : float
        What the sample period explains (s): beyond it the reader warned that the speed is not
        steady.
    spline_degree : int
        The degree of the interpolating spline of the probes in time.
    interpolation_bound : float
        The interpolation's largest relative error at the top harmonic separated (relative to
        that harmonic's amplitude in the readings; lower harmonics much less).
    first_line, last_line : int
        The file lines of the first and the last mark used.
    start_s : float
        The fitted time (s, the file's ``time_s``) of the first resampled revolution's
        theta = 0.
    """

    reference: str
    sample_rate_hz: float
    samples_per_revolution: float
    n_samples: int
    marks: int
    revolutions: int
    speed_rpm: float
    drift_per_s: float
    fit_degree: int
    residual_s: float
    residual_limit_s: float
    spline_degree: int
    interpolation_bound: float
    first_line: int
    last_line: int
    start_s: float

    def describe(self) -> str:
        """One line saying how the file was resampled.

        Returns
        -------
        str
        """
        return (f"time-sampled at {self.sample_rate_hz:.6g} Hz, {self.samples_per_revolution:.1f}"
                f" samples per revolution; {self.marks} {self.reference} marks (lines "
                f"{self.first_line}-{self.last_line}) fitted together: {self.speed_rpm:.2f} rpm, "
                f"drift {100 * self.drift_per_s:+.3f} %/s (degree {self.fit_degree}), largest "
                f"residual {1e6 * self.residual_s:.3g} us (sample period "
                f"{1e6 * self.residual_limit_s:.3g} us); {self.revolutions} complete revolutions "
                f"resampled onto N = {self.n_samples} angles by a degree-"
                f"{self.spline_degree} spline (error <= {self.interpolation_bound:.1e} of the "
                f"top harmonic's amplitude)")


@dataclass(frozen=True)
class ProbeData:
    """A checked multi-probe measurement, as a reader returns it.

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
        The highest profile harmonic to separate
        (:func:`~mtaccuracy.spindle.probes.resolvable_harmonic` unless lowered).
    cancelled : tuple of int
        Harmonics in ``2..max_harmonic`` the layout cannot separate (empty unless the reader was
        told ``allow_cancelled=True``).
    ignored_columns : tuple of str
        Other columns of the file, not used.
    header_line : int
        The line of the header.
    resampling : Resampling or None
        How a time-sampled file was resampled onto equal angles; None for an angle-sampled
        file.
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
    resampling: Resampling | None = None

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


def _show_number(value) -> str:
    """A number for a message: the shortest text that reads back as the same float (never
    rounded into another value, as ``:g`` would), positional unless very large or small.

    Parameters
    ----------
    value : float

    Returns
    -------
    str
        E.g. ``360``, ``0.1``, ``1e+25``.
    """
    v = float(value)
    if v == 0 or 1e-6 <= abs(v) < 1e16:
        return np.format_float_positional(v, trim="-")
    return repr(v)


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


def _probe_columns(path, line, names, skip):
    """The probe columns and their angles (deg) from a header's column names, checked;
    the names in ``skip`` (a format's own columns) are passed over, and other names that
    do not start with ``probe`` are returned as ignored."""
    probes, angles, ignored = [], [], []
    for n in names:
        if n in skip:
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


def _check_values(path, columns, values, lines, header_line) -> None:
    """Refuse readings beyond +-:data:`MAX_ABS_UM` (nm?) and a probe spanning less than
    :data:`MIN_SPAN_UM` (mm?); ``lines(row)`` gives the file's line of a data row."""
    for c, v in zip(columns, values, strict=True):
        big = np.abs(v) > MAX_ABS_UM
        if big.any():
            rows = np.flatnonzero(big)
            raise ProbeFileError(path, lines(rows[0]), (
                f"column {c!r} reads {_show_number(v[rows[0]])} um, beyond +-{MAX_ABS_UM:g} um "
                f"(10 mm), "
                f"more than a displacement probe's range; lines {lines.some(rows)}: in nm? "
                f"(um = nm / 1000)"))
        span = float(np.ptp(v))
        if span < MIN_SPAN_UM:
            raise ProbeFileError(path, header_line, (
                f"column {c!r} spans only {span:.3g} um over the whole file "
                f"({_show_number(v.min())} .. {_show_number(v.max())}), less than the "
                f"{MIN_SPAN_UM:g} um (10 nm) that probe noise, the "
                f"artefact's form and any spindle's error motion give: in mm? (um = mm x "
                f"1000), or a probe that did not read"))


def _check_layout(path, header_line, angles_deg, n: int, max_harmonic, allow_cancelled: bool):
    """The highest harmonic to separate and the harmonics the layout cancels within it.

    A layout that cancels every harmonic is refused, one that cancels some is refused unless
    ``allow_cancelled`` (then they are named in a :class:`CancelledHarmonicsWarning`, attributed
    to the reader's caller).  Returns ``(max_harmonic, cancelled)``.
    """
    try:
        k_top = _check_band(max_harmonic, n)
    except ValueError as exc:
        raise ProbeFileError(path, None, str(exc)) from None
    cancelled = layout_cancelled(np.deg2rad(angles_deg), k_top)
    if cancelled:
        msg = _cancelled_message(angles_deg, cancelled, n, k_top)
        if len(cancelled) == k_top - 1:
            raise ProbeFileError(path, header_line, msg + "; that is every harmonic: nothing "
                                                          "to separate" + _CANCELLED_HINT)
        if not allow_cancelled:
            raise ProbeFileError(path, header_line, msg + _CANCELLED_HINT)
        warnings.warn(f"{path}, line {header_line}: {msg} (allow_cancelled=True: separating "
                      f"without them)", CancelledHarmonicsWarning, stacklevel=3)
    return k_top, cancelled
