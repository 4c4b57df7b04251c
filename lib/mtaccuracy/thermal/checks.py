"""The checks of the thermal schema: columns, units, plausible values, sizes, consistency.

Each refuses what breaks ``data/thermal/README.md`` with a
:class:`~mtaccuracy.thermal.schema.DataFormatError` naming the file, the column and, for bad
values, the lines an editor shows: a column in another unit (:func:`_check_units`), a missing
column (:func:`_require`), values outside a plausible range or spanning too little for their
unit (:func:`_check_range`, :func:`_check_span`), too much data (:func:`_check_size`), the
columns of ``temperatures.csv`` (:func:`_temperature_columns`: units are part of the names),
an ``experiments.csv`` that does not list the data's experiments (:func:`_check_listed`), and
re-zeroed measurements (:func:`_check_zeroing`).  The readers of the files
(:mod:`~mtaccuracy.thermal.io`) call them in the order the schema's README lists them.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd

from .csvfile import _is_number_column, _lines, _parse
from .schema import _KEYS, _TEMP_UNIT, _problem

__all__: list[str] = []


def _check_units(path, columns, quantity: str, expected: str) -> None:
    """Refuse a column naming ``quantity`` in another unit (called when ``expected`` is missing)."""
    for c in columns:
        if c == expected or not c.startswith(quantity + "_"):
            continue
        unit = c[len(quantity) + 1:]
        raise _problem(path, f"column {c!r} gives {quantity} in {unit!r}; the schema needs "
                             f"{expected!r} (unit {expected.split('_', 1)[1]}); convert the "
                             f"values and rename the column")


def _require(path, df, columns) -> None:
    missing = [c for c in columns if c not in df.columns]
    if missing:
        lower = {str(c).lower(): c for c in df.columns}
        near = [f"{lower[m.lower()]!r}" for m in missing if m.lower() in lower]
        hint = f" (names are case-sensitive: {', '.join(near)})" if near else ""
        raise _problem(path, f"missing column(s) {missing}; found {list(df.columns)}{hint}")


def _check_range(path, column, values, lo, hi, unit, hint) -> None:
    """Refuse values outside [lo, hi], naming the column, lines, values and limits."""
    bad = (values < lo) | (values > hi)
    if bad.any():
        shown = ", ".join(f"{v:g}" for v in values[bad][:3])
        raise _problem(path, f"column {column!r} has value(s) {shown} {unit} on line(s) "
                             f"{_lines(path, bad)}, outside the plausible range {lo:g} .. {hi:g} "
                             f"{unit}; {hint}")


def _check_span(path, column, values, least, unit, what) -> None:
    """Refuse a column whose values span less than ``least`` (a unit mix-up), naming it."""
    span = float(np.ptp(values))
    if span < least:
        raise _problem(path, f"column {column!r} spans only {span:g} {unit} ({values.min():g} .. "
                             f"{values.max():g}), less than the plausible {least:g} {unit} {what}")


def _check_size(path, what, n, limit, why) -> None:
    if n > limit:
        raise _problem(path, f"{n} {what}; at most {limit} are supported ({why})")


# Columns of temperatures.csv.  Units are part of the names: ``<sensor>_degC`` is a sensor, and
# so is ``<sensor> [°C]`` (a Celsius unit in brackets, as loggers write it: ``[°C]``, ``(°C)``,
# ``[degC]``, ``[C]``, ``[Celsius]``; the brackets leave no doubt that it is a unit); a
# name ending in another temperature unit (``_K``, ``_degF``, ``_C``, ``[K]`` ...: see
# :func:`_temperature_unit`) is a temperature in the wrong unit or spelling, refused; a name
# ending in any other unit (``spindle_speed_rpm``) is another quantity, ignored; a name with
# no unit is refused when the column holds numbers (a sensor that lost its unit: ``T3``) and
# ignored when it holds text (``note``).

#: A unit in brackets at the end of a column name: ``T1 [°C]``, ``speed (rpm)``.
_BRACKETED = re.compile(r"\s*[\[(]\s*([^\[\]()]*?)\s*[\])]\s*$")
_CELSIUS = {"c", "oc", "celsius", "centigrade"}
_OTHER_SCALES = {"k", "kelvin", "f", "fahrenheit"}


def _unit(name: str) -> str | None:
    """The unit a column name ends in, or None.

    ``[unit]`` or ``(unit)``, else what follows its last ``_`` unless that is a number.
    """
    m = _BRACKETED.search(name)
    if m:
        return m.group(1)
    if "_" in name:
        unit = name.rsplit("_", 1)[1].strip()
        if unit and not re.fullmatch(r"[\d.]+", unit):
            return unit
    return None


def _temperature_unit(unit: str) -> str | None:
    """``"celsius"`` or ``"other"`` for a temperature unit however spelled, else None.

    Spellings: ``C``, ``degc``, ``°C``, ``oC``, ``K``, ``degK``, ``kelvin``, ``F``, ``degF``
    ...; None for anything else (``rpm``, ``deg`` alone: an angle).
    """
    u = re.sub(r"[\s°º]", "", unit.lower())
    u = re.sub(r"^(degrees?|deg|grad)_?", "", u)
    return "celsius" if u in _CELSIUS else "other" if u in _OTHER_SCALES else None


def _holds_numbers(s: pd.Series, sep: str) -> bool:
    """Whether a column has a value and every value it has is a number."""
    if _is_number_column(s):
        return bool(s.notna().any())
    values = s.dropna()
    return not values.empty and bool(np.isfinite(_parse(values, sep)).all())


def _celsius_bracket(name: str) -> str | None:
    """The sensor of a column ``<sensor> [°C]`` (a Celsius unit in brackets), else None."""
    m = _BRACKETED.search(name)
    if m and _temperature_unit(m.group(1)) == "celsius":
        return name[:m.start()].strip()
    return None


def _temperature_columns(path: Path, df: pd.DataFrame,
                         keys=(*_KEYS, "timestamp")) -> tuple[dict[str, str], dict[str, str]]:
    """Sensor name -> its column (``<sensor>_degC`` or ``<sensor> [°C]``), and the columns
    ignored (column -> why); ``keys`` are the columns that are no sensor.

    Refuses temperatures in another unit or spelling and columns of numbers without a unit.
    """
    sep = df.attrs.get("separator", ",")
    sensors: dict[str, str] = {}
    ignored: dict[str, str] = {}
    tail = ("; a column that is not a temperature is ignored when its name ends in its own "
            "unit (e.g. spindle_speed_rpm)")
    for c in df.columns:
        if c in keys:
            continue
        bracketed = _celsius_bracket(c)
        if c.endswith(_TEMP_UNIT) or bracketed is not None:
            name = c[:-len(_TEMP_UNIT)].strip() if bracketed is None else bracketed
            if not name:
                raise _problem(path, f"column {c!r} names no sensor; write <sensor>{_TEMP_UNIT}, "
                                     f"e.g. T1{_TEMP_UNIT}")
            if name in sensors:
                raise _problem(path, f"duplicate sensor name {name!r}: columns "
                                     f"{sensors[name]!r} and {c!r}; every column needs its own "
                                     f"name (two sensors, two names)")
            sensors[name] = c
            continue
        if c.startswith("<unnamed column "):
            if _holds_numbers(df[c], sep):
                raise _problem(path, f"column {c[16:-1]} has no name in the header but holds "
                                     f"numbers; name it (<sensor>{_TEMP_UNIT} for a "
                                     f"temperature){tail}")
            ignored[c] = "no name, " + ("empty" if df[c].isna().all() else "text")
            continue
        unit = _unit(c)
        scale = None if unit is None else _temperature_unit(unit)
        if scale is not None:
            m = _BRACKETED.search(c)
            stem = (c[:m.start()] if m else c.rsplit("_", 1)[0]).strip()
            stem = re.sub(r"[_ ]*(degrees?|deg|grad)$", "", stem, flags=re.I) or "<sensor>"
            fix = (f"rename it {stem + _TEMP_UNIT!r} or {stem + ' [°C]'!r}"
                   if scale == "celsius" else
                   f"convert the values to degrees Celsius (degC = K - 273.15 = (degF - 32) / "
                   f"1.8) and rename it {stem + _TEMP_UNIT!r}")
            raise _problem(path, f"column {c!r}: temperatures must be in degrees Celsius, named "
                                 f"<sensor>{_TEMP_UNIT} (found {unit!r}); {fix}{tail}")
        if unit is None and _holds_numbers(df[c], sep):
            raise _problem(path, f"column {c!r}: temperatures must be in degrees Celsius, named "
                                 f"<sensor>{_TEMP_UNIT} (found 'no unit'); a column of numbers "
                                 f"needs its unit in its name: <sensor>{_TEMP_UNIT} for a "
                                 f"temperature, its own unit for any other quantity, which is "
                                 f"then ignored (e.g. spindle_speed_rpm, run_no)")
        ignored[c] = (f"another quantity (its name ends in {unit!r}, not a temperature "
                      f"unit)" if unit is not None else
                      "no unit, " + ("empty" if df[c].isna().all() else "text"))
    return sensors, ignored


def _constant(values: dict[str, np.ndarray], experiments: np.ndarray) -> dict[str, str]:
    """The sensors whose reading never changes within any experiment (sensor -> why).

    The why names the value: such a sensor carries no rise, the only thing the models learn
    from a temperature.
    """
    if not values:
        return {}
    g = pd.DataFrame(values).groupby(experiments, sort=True)
    lo, hi = g.min(), g.max()
    out = {}
    for name in values:
        if not (lo[name] == hi[name]).all():
            continue
        per = lo[name]
        if per.nunique() == 1:
            out[name] = f"reads {per.iloc[0]:g} degC in every measurement"
        else:
            shown = ", ".join(f"{v:g} in experiment {e}" for e, v in per.iloc[:4].items())
            out[name] = (f"reads one value through each experiment ({shown}"
                         f"{' ...' if len(per) > 4 else ''} degC): it never changes within an "
                         f"experiment")
    return out


def _check_listed(path: Path, listed: np.ndarray, data: set, files: str) -> None:
    """Refuse an ``experiments.csv`` listing an experiment without data or missing one with.

    The message names the experiments (and the lines of the ones listed).
    """
    extra = np.array([e not in data for e in listed.tolist()])
    missing = sorted(data - set(listed.tolist()))
    problems = []
    if extra.any():
        problems.append(f"lists experiment(s) {sorted(set(listed[extra].tolist()))} (line(s) "
                        f"{_lines(path, extra)}) that have no measurements in {files}")
    if missing:
        problems.append(f"misses experiment(s) {missing}, which have measurements in {files}")
    if problems:
        raise _problem(path, f"{' and '.join(problems)}; list every experiment of the data once "
                             f"(with its feed) and no other, or delete {path.name}")


def _check_zeroing(path, experiments: np.ndarray, errors: np.ndarray, positions) -> None:
    """Refuse re-zeroed measurements.

    *Re-zeroed* means the interferometer was set to zero again before each measurement, so
    that the thermal drift of the zero point (what the intercept b models) is lost.  Its
    signature, detected here: **every** measurement of an experiment reads exactly 0 at one
    common target position (written as 0, 0.0, 0.000 ...).  Kept relative to the zero set at
    the first measurement (as the schema asks), only the first measurement reads exactly 0
    there; the later ones carry the drift, and all of them reading exactly 0 at the
    interferometer's resolution is no drift at all.  A single re-zeroed measurement among
    drifting ones cannot be told from a drift that happens to read 0, and is not refused.
    """
    for e in np.unique(experiments):
        rows = experiments == e
        zero = np.flatnonzero(np.all(errors[rows] == 0.0, axis=0))
        if zero.size:
            raise _problem(path, f"experiment {e}: all {int(rows.sum())} measurements read "
                                 f"exactly 0 at {positions[zero[0]]:g} mm, the signature of "
                                 f"an interferometer re-zeroed before every measurement, "
                                 f"which removes the drift the intercept b models; keep the "
                                 f"readings relative to the zero set at the first measurement "
                                 f"of the experiment (if the axis really reads 0 there every "
                                 f"time, write the readings at the interferometer's full "
                                 f"resolution)")
