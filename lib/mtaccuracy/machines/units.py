"""Plausibility of the units of a reader's machine data: the travels and the error ranges.

The readers of notebook 06 (:func:`.readers.read_axis_table`, :func:`.readers.read_ranges`)
take a file's ``unit`` column at its word.  A number that makes sense only in another unit (a
travel in metres labelled ``mm``, radians labelled ``deg``, microns labelled ``mm``) would
otherwise build a machine a thousand times too small, or errors a thousand times too large, and
every result after it would be wrong without a word.  These checks compare each value with what
machine tools are (ISO 230-1 vocabulary; the typical magnitudes of ISO 230-2 and ISO 10791
acceptance tolerances):

* **refused** (``ValueError``): a value no machine tool has, in the unit written;
* **warned** (:class:`SuspectUnitWarning`): a value only a rare machine has; the reader goes
  on with the value as written.

A finding names the value, its unit, the limit and why, and the unit(s) in which the value
would be typical for a machine tool, with the numbers to write (:func:`check`).  The limits
(:data:`LINEAR_TRAVEL`, :data:`ROTARY_TRAVEL`, :data:`TRANSLATION_ERROR`,
:data:`ANGULAR_ERROR`) and their reasons are documented in ``data/machines/README.md``.

What no such check can catch: a confusion whose result is still plausible.  The travel of a
20 m gantry written in metres (20 "mm"), a travel in inches or centimetres labelled mm, an
angle in arcsec labelled urad (a factor 4.85), an error of 0.006 mm written 0.006 with the unit
um (6 nm: an ultra-precision machine's error) all stay within the limits.  Rotary pivots are
not checked beyond their bound (:data:`.readers.MAX_LINEAR_MM`): a pivot may lie at, or a
fraction of a millimetre from, the origin of its frame, so no small value tells its unit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field


class SuspectUnitWarning(UserWarning):
    """A value of a machine file that is rare in the unit written (the value is used as written).

    It may have been meant in another unit; the message names it."""


@dataclass(frozen=True)
class Limits:
    """The plausibility limits of one quantity of a machine file.

    Attributes
    ----------
    what : str
        What the value is, for messages (``"the travel"``, ``"the range"``).
    unit : str
        The unit of every limit below (``mm``, ``deg``, ``rad``).
    measure : str
        ``"span"``: the limits bound ``high - low``; ``"size"``: ``max(|low|, |high|)``.
    refuse_below, warn_below, warn_above, refuse_above : float
        The measure is refused outside ``[refuse_below, refuse_above]`` and warned outside
        ``[warn_below, warn_above]`` (in ``unit``).
    bound : float
        No end of the interval lies beyond +-``bound`` (``unit``; a travel's own bound,
        checked by the reader; here it keeps a suggested unit within it).
    typical : tuple of float
        The measure of a typical machine tool (``unit``): the unit that brings a value into it
        is named as the likely one.
    why : dict of str to str
        The reason of each limit, keyed by its name (``refuse_below``, ...), written to follow
        "less/more than the <limit> <unit>".
    units : dict of str to float
        Every unit a value of this quantity may come in (accepted or not), with its size in
        ``unit``; in the order a suggestion names them (the more common confusion first).
    accepted : tuple of str
        The units a file may use; a suggestion in another unit is written in the first.
    suggested : tuple of str
        The units :func:`suggest` may name (default: all of ``units``; a unit of the same size
        as one before it is never named).
    """

    what: str
    unit: str
    measure: str
    refuse_below: float
    warn_below: float
    warn_above: float
    refuse_above: float
    bound: float
    typical: tuple[float, float]
    why: dict = field(repr=False)
    units: dict = field(repr=False)
    accepted: tuple[str, ...] = ()
    suggested: tuple[str, ...] | None = None


@dataclass(frozen=True)
class Finding:
    """What :func:`check` found: refuse or warn, and the message (without the file and line).

    Attributes
    ----------
    refuse : bool
        True: the value is refused (no machine tool has it); False: a warning.
    message : str
        The value, its unit, the limit crossed and why, and the likely unit(s) with the numbers
        to write.
    likely : tuple of str
        The units in which the value would be typical, the most typical first (may be empty).
    """

    refuse: bool
    message: str
    likely: tuple[str, ...] = ()


_ARCSEC = math.pi / 180 / 3600

#: A linear travel (mm), judged by its span.  The slides of machine tools travel from about
#: 10 mm (micro machine tools) to a few tens of metres (gantries for ship hulls and aircraft
#: spars).  A span below 1 mm is refused: sub-millimetre strokes are those of fine-positioning
#: actuators (fast tool servos, piezo stages), not of the slides this chain describes, while
#: the travels of most machines written in metres (0.05 m to 1 m) fall there.  Between 1 and
#: 10 mm a warning: a micro machine tool may travel that little, and so does a machine of 1 to
#: 10 m written in metres.
LINEAR_TRAVEL = Limits(
    what="the travel", unit="mm", measure="span", refuse_below=1.0, warn_below=10.0,
    warn_above=math.inf, refuse_above=math.inf, bound=1e5, typical=(50.0, 2e4),
    why={"refuse_below": "any slide of a machine tool travels (sub-millimetre strokes are "
                         "those of fine-positioning actuators, fast tool servos or piezo "
                         "stages, not of the slides of this chain)",
         "warn_below": "of the smallest machine-tool slides (micro machine tools); a travel "
                       "of 1-10 m written in metres reads as this"},
    units={"mm": 1.0, "m": 1e3, "inch": 25.4, "um": 1e-3}, accepted=("mm",))

#: A rotary travel (deg), judged by its span.  The smallest rotary axes of machine tools, the
#: table swivels of cylindrical grinders, turn through about 12 deg (+-6 deg); tilting tables
#: and swivel heads through 60 deg or more; tables and spindles through full turns.  A span
#: below 5 deg is refused: read in radians it is a tilt of +-15 to +-143 deg.  Between 5 and
#: 15 deg a warning (a grinder's swivel; or radians of up to two turns, 4 pi = 12.6); refused
#: there too when its ends read in radians are whole multiples of 5 deg (to 0.25 %, e.g.
#: 6.2832 = 360 deg) and not whole numbers in degrees.
ROTARY_TRAVEL = Limits(
    what="the travel", unit="deg", measure="span", refuse_below=5.0, warn_below=15.0,
    warn_above=math.inf, refuse_above=math.inf, bound=3600.0, typical=(20.0, 720.0),
    why={"refuse_below": "any rotary axis of a machine tool turns through (the smallest, the "
                         "table swivel of a cylindrical grinder, turns about +-6 deg; tilting "
                         "tables and swivel heads 60 deg or more)",
         "warn_below": "that only the table swivel of a grinder turns through (a travel in "
                       "radians of up to two turns reads as less)",
         "radians": "of a grinder's table swivel, and read in radians its ends are whole "
                    "multiples of 5 deg"},
    units={"deg": 1.0, "rad": 180.0 / math.pi}, accepted=("deg",))

#: A translational error range (mm), judged by its size ``max(|low|, |high|)``.  The geometric
#: errors of machine tools (positioning, straightness, radial and axial error motions, the
#: offsets of rotary axes) are 0.1 um (ultra-precision machines) to 100 um (large machines);
#: ISO 230-2 positioning deviations are 5-50 um per metre of travel.  Above 1 mm a warning:
#: only the uncompensated thermal growth of a very large machine nears it (11.5 um/m/K over
#: 40 m and 5 K is 2.3 mm); above 10 mm refused: no machine tool in service is a centimetre
#: off.  Below 1e-7 mm (0.1 nm, an atom) a warning: no geometric error is measured that small
#: (laser interferometers resolve about 1 nm); it may be meant to make the error negligible.
TRANSLATION_ERROR = Limits(
    what="the range", unit="mm", measure="size", refuse_below=0.0, warn_below=1e-7,
    warn_above=1.0, refuse_above=10.0, bound=math.inf, typical=(1e-4, 0.1),
    why={"warn_below": "of an atom (0.1 nm): no geometric error is measured that small "
                       "(laser interferometers resolve about 1 nm)",
         "warn_above": "a geometric error of a machine tool reaches (ISO 230-1 errors are "
                       "0.1-100 um; only the uncompensated thermal growth of a very large "
                       "machine nears 1 mm)",
         "refuse_above": "any machine tool in service is off by (its geometric errors are "
                         "0.1-100 um; no machine tool is a centimetre off)"},
    units={"um": 1e-3, "mm": 1.0, "nm": 1e-6, "m": 1e3}, accepted=("um", "mm"))

#: An angular error range (rad), judged by its size ``max(|low|, |high|)``.  Angular error
#: motions, squareness and the orientation of rotary axes are 0.5 urad (0.1 arcsec,
#: ultra-precision) to 500 urad (100 arcsec, an uncompensated rotary table); ISO 10791
#: acceptance tolerances of angular deviations and squareness are 20-60 um/m.  Above 1e-3 rad
#: (1 mm/m, 206 arcsec) a warning: only a worn or badly aligned machine reaches it; above 1e-2
#: rad (10 mm/m, 0.57 deg) refused: a misalignment seen by eye, not a geometric error.  Below
#: 1e-9 rad (0.0002 arcsec) a warning: below anything measured (autocollimators resolve about
#: 0.005 arcsec, 25 nrad); it may be meant to make the error negligible.
ANGULAR_ERROR = Limits(
    what="the range", unit="rad", measure="size", refuse_below=0.0, warn_below=1e-9,
    warn_above=1e-3, refuse_above=1e-2, bound=math.inf, typical=(5e-7, 5e-4),
    why={"warn_below": "below which no angular error is measured (0.0002 arcsec; "
                       "autocollimators resolve about 0.005 arcsec)",
         "warn_above": "an angular error of a machine tool reaches (1 mm/m, 206 arcsec; "
                       "ISO 230-1 errors are 0.5-500 urad, 0.1-100 arcsec)",
         "refuse_above": "of a misalignment seen by eye (10 mm/m, 0.57 deg); an angular "
                         "error of a machine tool is 0.5-500 urad (0.1-100 arcsec)"},
    units={"urad": 1e-6, "arcsec": _ARCSEC, "rad": 1.0, "um/m": 1e-6, "mrad": 1e-3,
           "mm/m": 1e-3, "deg": math.pi / 180},
    accepted=("urad", "rad", "arcsec", "um/m"), suggested=("urad", "rad", "arcsec", "mrad", "deg"))

#: Spellings of a unit a file may use by habit, and the unit they mean.
ALIASES = {"µm": "um", "μm": "um", "micron": "um", "microns": "um", "µrad": "urad",
           "μrad": "urad", "″": "arcsec", "arc sec": "arcsec", "arcsecond": "arcsec",
           "arcseconds": "arcsec", "arc-sec": "arcsec", "°": "deg", "degree": "deg",
           "degrees": "deg", "millimetre": "mm", "millimeter": "mm", "millimetres": "mm",
           "millimeters": "mm", "radian": "rad", "radians": "rad", "in": "inch",
           "inches": "inch"}


def _measure(lim: Limits, lo: float, hi: float) -> float:
    return hi - lo if lim.measure == "span" else max(abs(lo), abs(hi))


#: A value on a limit, written in another unit, may come out a rounding off it (1e-3 urad is
#: 1.0000000000000001e-09 rad): the limits are crossed only beyond this relative margin.
_ROUNDING = 1e-9


def _crossed(lim: Limits, lo: float, hi: float) -> str | None:
    """The first limit ``(lo, hi)`` (in ``lim.unit``) crosses, refusals first, or None; the
    limits themselves (to rounding) are not crossed."""
    m = _measure(lim, lo, hi)
    below, above = 1 - _ROUNDING, 1 + _ROUNDING
    if max(abs(lo), abs(hi)) > lim.bound * above:
        return "bound"
    for name, beyond in (("refuse_below", m < lim.refuse_below * below),
                         ("refuse_above", m > lim.refuse_above * above),
                         ("warn_below", m < lim.warn_below * below),
                         ("warn_above", m > lim.warn_above * above)):
        if beyond:
            return name
    return None


def _radian_like(lo: float, hi: float) -> bool:
    """Whether a rotary travel written in degrees reads in radians as whole multiples of 5 deg
    (to 0.25 %), with an end that is no whole number: ``(0, 6.2832)``, ``(-1.92, 1.92)``."""
    ends = [v for v in (lo, hi) if v != 0]
    if not ends or all(float(v).is_integer() for v in ends):
        return False
    deg = [math.degrees(v) for v in ends]
    return all(round(d / 5) != 0 and abs(d - 5 * round(d / 5)) <= 2.5e-3 * abs(d) for d in deg)


def _num(v: float, digits: int) -> str:
    text = f"{v:.{digits}g}"
    return "0" if text == "-0" else text


def _digits(factor: float) -> int:
    """Significant digits of a converted number: 6 when the factor is a power of ten (the
    conversion is exact), else 4 (a unit's numbers are seldom given to more)."""
    return 6 if abs(math.log10(factor) - round(math.log10(factor))) < 1e-9 else 4


def _likely(lim: Limits, lo: float, hi: float, unit: str) -> list[tuple[str, str]]:
    """The units (other than ``unit``) in which the numbers ``lo, hi`` are a typical value,
    in the order of ``lim.units`` (the more common confusion first), or, when none is, the
    one in which they are the plausible value nearest the typical; each with the numbers to
    write: ``[("m", "-400, 400 mm"), ...]``."""
    size = lim.units[unit]
    centre = math.sqrt(lim.typical[0] * lim.typical[1])
    typical, plausible, seen = [], [], {size}
    for rank, (u, s) in enumerate(lim.units.items()):
        if s in seen or (lim.suggested is not None and u not in lim.suggested):
            continue
        seen.add(s)
        a, b = lo * s, hi * s
        if _crossed(lim, a, b) is not None:
            continue
        m = _measure(lim, a, b)
        if lim.typical[0] <= m <= lim.typical[1]:
            typical.append((rank, u))
        else:
            plausible.append((abs(math.log(m / centre)) if m > 0 else math.inf, u))
    chosen = typical or sorted(plausible)[:1]
    out = []
    for _, u in chosen[:2]:
        write = u if u in lim.accepted else lim.accepted[0]
        factor = lim.units[u] / lim.units[write]
        d = _digits(factor)
        out.append((u, f"{_num(lo * factor, d)}, {_num(hi * factor, d)} {write}"))
    return out


def check(lim: Limits, low: float, high: float, *, unit: str,
          written: tuple[str, str] | None = None) -> Finding | None:
    """Whether a travel or an error range is plausible for a machine tool in the unit written.

    Parameters
    ----------
    lim : Limits
        The quantity's limits (:data:`LINEAR_TRAVEL`, :data:`ROTARY_TRAVEL`,
        :data:`TRANSLATION_ERROR`, :data:`ANGULAR_ERROR`).
    low, high : float
        The interval as written in the file (finite, ``low < high``).
    unit : str
        The unit written, a key of ``lim.units`` (it may be one the file does not accept,
        e.g. ``deg`` for an angular error: the finding then says what the value is in it).
    written : (str, str), optional
        ``low`` and ``high`` as the file writes them, quoted in the message instead of their
        rounded values (a 26-digit number is shown as written, not as ``1.23457e+25``).

    Returns
    -------
    Finding or None
        None when the value is plausible; else whether it is refused, and the message: the
        value and unit, the limit (in the unit written, and in the limit's own unit when they
        differ) and why, and the likely unit(s) with the numbers to write (:func:`suggest`).
        A rotary travel of 5-15 deg whose ends read in radians are whole multiples of 5 deg
        is refused.

    Examples
    --------
    >>> check(LINEAR_TRAVEL, -400, 400, unit="mm") is None
    True
    >>> f = check(LINEAR_TRAVEL, -0.4, 0.4, unit="mm")
    >>> f.refuse, f.likely
    (True, ('m',))
    >>> f.message.split("; ")[-1]
    'likely in m (write -400, 400 mm)'
    >>> check(ROTARY_TRAVEL, -1.92, 1.92, unit="deg").message.split("; ")[-1]
    'likely in rad (write -110, 110 deg)'
    >>> check(ANGULAR_ERROR, -15, 15, unit="rad").likely
    ('urad', 'arcsec')
    >>> check(TRANSLATION_ERROR, -6, 6, unit="mm").refuse            # a warning: 6 um as mm?
    False
    """
    size = lim.units[unit]
    name = _crossed(lim, low * size, high * size)
    if name is None:
        return None
    if name == "warn_below" and lim is ROTARY_TRAVEL and _radian_like(low, high):
        name = "radians"
    refuse = name in ("bound", "radians") or name.startswith("refuse")
    m = _measure(lim, low, high)
    verb = "spans" if lim.measure == "span" else "reaches only" if name == "warn_below" \
        else "reaches"
    shown = f"{written[0]}, {written[1]}" if written else f"{low:g}, {high:g}"
    reach = _num(m, 6)
    if written and lim.measure == "size":       # the larger end as written, not rounded
        reach = written[0 if abs(low) >= abs(high) else 1].lstrip("+-")
    text = f"{lim.what} ({shown}) {unit} {verb} {reach} {unit}"
    d = 6 if size == 1 else _digits(size)
    if name == "bound":
        text += f", beyond +-{_num(lim.bound / size, d)} {unit}"
    else:
        limit = getattr(lim, "warn_below" if name == "radians" else name)
        own = f" ({limit:g} {lim.unit})" if unit != lim.unit else ""
        side = "less" if name.endswith("below") or name == "radians" else "more"
        text += f", {side} than the {_num(limit / size, d)} {unit}{own} {lim.why[name]}"
    likely = _likely(lim, low, high, unit)
    if likely:
        text += "; " + _said(likely, refuse)
    if not refuse:
        text += "; used as written"
    return Finding(refuse, text, tuple(u for u, _ in likely))


def _said(likely, refuse: bool = True) -> str:
    if refuse:
        return "likely in " + " or ".join(f"{u} (write {w})" for u, w in likely)
    return "; ".join(f"if it is in {u}, write {w}" for u, w in likely)


def suggest(lim: Limits, low: float, high: float, *, unit: str, sure: bool = True) -> str:
    """The unit(s) in which numbers given in ``unit`` would be typical, with the numbers to write.

    ``"likely in m (write -400, 400 mm)"``, or ``""`` when no unit does.

    Parameters
    ----------
    lim : Limits
        The quantity's limits.
    low, high : float
        The interval as written.
    unit : str
        The unit written (a key of ``lim.units``); it is not suggested again.
    sure : bool
        ``"likely in m (write ...)"`` when True (the value is refused), ``"if it is in m,
        write ..."`` when False.

    Returns
    -------
    str
        At most two units, the most typical first (a plausible one when none is typical).
    """
    likely = _likely(lim, low, high, unit)
    return _said(likely, sure) if likely else ""


def in_unit(lim: Limits, low: float, high: float, *, unit: str,
            written: tuple[str, str] | None = None) -> str:
    """What numbers written in a unit a file does not take are in the one it does.

    Parameters
    ----------
    lim : Limits
        The quantity's limits.
    low, high : float
        The interval as written (finite, ``low < high``).
    unit : str
        The unit written, not one of ``lim.accepted`` (an alias is read as its unit,
        :func:`canonical`).
    written : (str, str), optional
        ``low`` and ``high`` as written, quoted instead of their rounded values.

    Returns
    -------
    str
        ``"(-1.92, 1.92) rad is (-110, 110) deg"`` (in ``lim.accepted[0]``) when the value is
        plausible in ``unit``; what :func:`check` says of it when it is not; ``"'µm' is
        written 'um'"`` when ``unit`` is another spelling of an accepted unit; ``""`` when it
        is no unit of ``lim``.
    """
    spelled, unit = unit, canonical(unit)
    if unit in lim.accepted:
        return f"{spelled!r} is written {unit!r}"
    if unit not in lim.units:
        return ""
    found = check(lim, low, high, unit=unit, written=written)
    if found is not None:
        return f"read in {unit}, {found.message}"
    write = lim.accepted[0]
    factor = lim.units[unit] / lim.units[write]
    d = _digits(factor)
    shown = f"{written[0]}, {written[1]}" if written else f"{low:g}, {high:g}"
    return (f"({shown}) {unit} is ({_num(low * factor, d)}, "
            f"{_num(high * factor, d)}) {write}")


def canonical(unit: str) -> str:
    """A unit as the files write it: ``µm`` -> ``um``, ``°`` -> ``deg``, ``MM`` -> ``mm``.

    Parameters
    ----------
    unit : str
        The unit as written (stripped).

    Returns
    -------
    str
        Its spelling in :data:`ALIASES`' values, or ``unit`` itself (in lower case when it is
        ASCII: ``MM`` -> ``mm``).
    """
    key = unit.lower() if unit.isascii() else unit
    return ALIASES.get(key, key)
