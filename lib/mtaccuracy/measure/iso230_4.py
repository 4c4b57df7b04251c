"""ISO 230-4:2005 circular tests: G, H, F and the ballbar diagnostics with their uncertainties.

**The file**: a CSV ``plane,radius_mm,feed_mm_per_min,direction,angle_deg,deviation_um``, one
row per reading of one circular test run in both directions: the plane (``XY``, ``YZ`` or
``ZX``: axes a, b in that order), the nominal radius R (mm), the feed v (mm/min), the direction
(``ccw``: the angle increases with time; ``cw``: it decreases), the angle theta of the reading
(degrees, measured about the instrument's centre from the +a axis towards the +b axis: from +X
to +Y in XY, +Y to +Z in YZ, +Z to +X in ZX) and the radial deviation d (um) of the tool
centre's distance from the instrument's centre (a ballbar's pivot) from R, as a ballbar
measures it.  :func:`read_iso230_4` refuses, before any work, every problem with its line and
the fix; :func:`evaluate_iso230_4` evaluates.

**ISO 230-4 quantities** (clause 3):

- ``G_cw``, ``G_ccw``: circular deviation, the minimum radial separation of two concentric
  circles enclosing the path, both about the **least-squares centre** of that direction's path
  (the limacon fit d ~ r + c_a cos theta + c_b sin theta; the linearisation errs by c**2 / (2R),
  1e-6 um for a 10 um offset on R = 50 mm): G = max - min of the residuals.
- ``G_b``: bidirectional circular deviation (ISO 230-4:2005), the same zone enclosing both
  paths about their common least-squares centre.
- ``H``: circular hysteresis, the largest radial difference ``|d_ccw - d_cw|`` between the two
  paths, both about the **instrument's centre** (one set-up, so H does not see the centre
  offset); the cw path is interpolated (periodic, linear in theta) at the ccw path's angles.
- ``F_max``, ``F_min``: the largest and smallest radial deviation from the nominal radius R
  about the **instrument's centre**, over both directions.

**Diagnostics** by one least-squares fit of both directions at once, the first-order radial
signature of each error (d = e . u, u = (cos theta, sin theta), e the tool's position error
in the plane; s = +1 ccw, -1 cw; the second-order remainder of the exact
``d = |R u + e| - R`` is at most ``|e|**2 / (2R)``)::

    r0 (bar length, mean scale; a nuisance)       d = r0
    centre_a, centre_b (um, nuisance): the path's
      centre relative to the instrument's          d = c_a cos theta + c_b sin theta
    scale_mismatch  ds = s_a - s_b (um/m), e_a = s_a x_a, e_b = s_b x_b:
                                                   d = (R ds / 2) cos 2theta  (+ R(s_a+s_b)/2: r0)
    squareness  alpha (urad): the +b axis moves along (-sin alpha, cos alpha), so
      alpha > 0 when the angle between +a and +b EXCEEDS 90 deg; e_a = -alpha x_b:
                                                   d = -(R alpha / 2) sin 2theta
    servo_mismatch  dtau = tau_a - tau_b (ms; > 0 when axis a lags more), each axis lagging
      its command by tau: e = -tau dx/dt; dx_a/dt = -s v sin theta, dx_b/dt = s v cos theta:
                                                   d = s (v dtau / 2) sin 2theta  (flips with s)
    backlash_a, backlash_b (um; > 0 for lost motion: the axis stays behind its command by
      half of it in each direction, e_a = -(b_a/2) sign(dx_a/dt), a step of b_a outwards at
      the axis's reversal, theta = 0, 180 deg for a):
                                                   d = s (b_a / 2) sign(sin theta) cos theta
                                                     - s (b_b / 2) sign(cos theta) sin theta

Squareness and scale mismatch are the second harmonic common to both directions, servo
mismatch and backlash the part that flips with the direction (backlash separated from servo
mismatch by its step shape: its higher harmonics).  Each estimate's standard uncertainty is
sqrt(diag(s2 (X'X)^-1)) with s2 = RSS / (n - 8): it **assumes** the readings' noise independent,
of one variance and zero mean, and the eight signatures complete; a machine with other error
shapes (periodic errors, reversal spikes) leaves systematic residuals that this u
understates.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from .files import MeasurementFileError, Problems, Rows, read_rows

__all__ = ["read_iso230_4", "evaluate_iso230_4", "signatures", "CircleData", "Iso230_4Result",
           "COLUMNS", "PLANES", "MIN_POINTS", "MAX_GAP_DEG", "PARAMETERS"]

COLUMNS = ("plane", "radius_mm", "feed_mm_per_min", "direction", "angle_deg", "deviation_um")
#: The planes and their axes (a, b): theta runs from +a towards +b.
PLANES = {"XY": ("X", "Y"), "YZ": ("Y", "Z"), "ZX": ("Z", "X")}
#: Fewest readings per direction (the fit has 8 parameters over both directions).
MIN_POINTS = 16
#: Largest gap (deg) between a direction's angles: the diagnostics need the whole circle.
MAX_GAP_DEG = 20.0
#: The fit's parameters (``a``, ``b`` replaced by the plane's axes) and their units.
PARAMETERS = (("r0", "um"), ("centre_a", "um"), ("centre_b", "um"),
              ("scale_mismatch", "um/m"), ("squareness", "urad"), ("servo_mismatch", "ms"),
              ("backlash_a", "um"), ("backlash_b", "um"))
_WHAT = "an ISO 230-4 file"
_DIRECTIONS = {"ccw": True, "cw": False}


@dataclass(frozen=True)
class CircleData:
    """The checked readings of one circular test, both directions.

    Attributes
    ----------
    plane : str
        ``XY``, ``YZ`` or ``ZX``.
    radius_mm : float
        The nominal radius R, mm.
    feed_mm_per_min : float
        The feed v, mm/min.
    ccw : (n,) ndarray of bool
        True for a reading of the counter-clockwise run.
    angle_deg : (n,) ndarray
        Each reading's angle theta, deg (from +a towards +b).
    deviation_um : (n,) ndarray
        Each reading's radial deviation d from R about the instrument's centre, um.
    source : str
        The file (or "DataFrame") the readings came from.
    """

    plane: str
    radius_mm: float
    feed_mm_per_min: float
    ccw: np.ndarray
    angle_deg: np.ndarray
    deviation_um: np.ndarray
    source: str


def _single(rows, values, column, problems, unit):
    """The one value a column holds in every row, or a problem at the first other one."""
    ok = np.isfinite(values) & (values > 0)
    if not ok.any():
        return np.nan
    first = values[ok][0]
    other = np.flatnonzero(ok & (values != first))
    if other.size:
        k = other[0]
        problems.add(rows.lines[k], (
            f"{column} is {rows.text[column][k]} {unit} here, {first:g} {unit} on line "
            f"{rows.lines[np.flatnonzero(ok)[0]]}: an ISO 230-4 file holds one circular test "
            f"(one plane, radius and feed); split the file, one test per file"))
    return first


def _plane_hint(plane: str) -> str:
    """What a plane not in :data:`PLANES` probably means (lower case, or the axes swapped:
    an angle phi from +b towards +a is theta = 90 deg - phi, and the sense reverses)."""
    up = plane.upper()
    if up in PLANES:
        return f"; here {up!r}?"
    swapped = up[::-1]
    if swapped in PLANES:
        return (f"; {plane!r} is {swapped!r} with the axes swapped: write {swapped!r}, each "
                f"angle as 90 - angle (mod 360) and the directions swapped (cw <-> ccw)")
    return ""


def _check(rows: Rows) -> CircleData:
    """The readings of ``rows``, or every problem with its line and the fix."""
    problems = Problems(rows.path)
    lines = rows.lines
    radius = rows.numbers("radius_mm", problems, unit="mm")
    feed = rows.numbers("feed_mm_per_min", problems, unit="mm/min")
    angle = rows.numbers("angle_deg", problems, unit="degrees")
    dev = rows.numbers("deviation_um", problems, unit="um")
    for values, column, unit in ((radius, "radius_mm", "mm"), (feed, "feed_mm_per_min",
                                                                "mm/min")):
        for k in np.flatnonzero(values <= 0):
            problems.add(lines[k], f"{column} is {rows.text[column][k]}: write the test's "
                                   f"{'nominal radius' if unit == 'mm' else 'feed'} (> 0 {unit})")
    planes = rows.text["plane"]
    for k, p in enumerate(planes):
        if p not in PLANES:
            problems.add(lines[k], f"plane is {p!r}: write XY, YZ or ZX (the angle runs from "
                                   f"the first axis to the second){_plane_hint(p)}")
    names = list(dict.fromkeys(p for p in planes if p in PLANES))
    if len(names) > 1:
        k = planes.index(names[1])
        problems.add(lines[k], f"plane {names[1]} here, {names[0]} on line "
                               f"{lines[planes.index(names[0])]}: one test per file; split it")
    r = _single(rows, radius, "radius_mm", problems, "mm")
    v = _single(rows, feed, "feed_mm_per_min", problems, "mm/min")
    ccw = np.array([_DIRECTIONS.get(d.lower(), None) for d in rows.text["direction"]])
    for k in np.flatnonzero(ccw == None):  # noqa: E711 (an object array)
        d = rows.text["direction"][k]
        problems.add(lines[k], f"direction is {d!r}: write 'ccw' (the angle increases with "
                               f"time) or 'cw' (it decreases)")
    problems.raise_if_any()
    ccw = ccw.astype(bool)
    wrapped = np.mod(angle, 360.0)
    for run, name in ((True, "ccw"), (False, "cw")):
        idx = np.flatnonzero(ccw == run)
        if idx.size < MIN_POINTS:
            problems.add(lines[idx[0]] if idx.size else None, (
                f"{idx.size} reading(s) in direction {name}: the evaluation needs both "
                f"directions over the whole circle, at least {MIN_POINTS} readings each"))
            continue
        order = idx[np.argsort(wrapped[idx], kind="stable")]
        a = wrapped[order]
        same = np.flatnonzero(np.diff(a) == 0)
        for j in same:
            problems.add(lines[order[j + 1]], (
                f"angle {rows.text['angle_deg'][order[j + 1]]} deg in direction {name} again "
                f"(line {lines[order[j]]} has it, modulo 360): keep one reading per angle "
                f"(drop the overrun arcs, or 360 when 0 is there)"))
        gaps = np.diff(np.append(a, a[0] + 360.0))
        if gaps.max() > MAX_GAP_DEG:
            j = int(np.argmax(gaps))
            problems.add(lines[order[j]], (
                f"no reading in direction {name} between {a[j]:g} and "
                f"{(a[j] + gaps[j]) % 360:g} deg: the evaluation needs the whole circle "
                f"(gaps of at most {MAX_GAP_DEG:g} deg)"))
    problems.raise_if_any()
    return CircleData(names[0], float(r), float(v), ccw, angle, dev, rows.path)


def read_iso230_4(path) -> CircleData:
    """Read an ISO 230-4 file, refusing every problem before any work.

    Refused, each with its line and the fix: what :func:`mtaccuracy.measure.files.read_rows`
    refuses, a cell that is not a finite number, a radius or feed <= 0, a plane other than
    XY / YZ / ZX, more than one test (plane, radius or feed differing), a direction other
    than ``cw`` / ``ccw``, a direction with fewer than :data:`MIN_POINTS` readings, an angle
    repeated in a direction (modulo 360 deg), a gap over :data:`MAX_GAP_DEG` deg.

    Parameters
    ----------
    path : str or os.PathLike
        The CSV file ``plane,radius_mm,feed_mm_per_min,direction,angle_deg,deviation_um``.

    Returns
    -------
    CircleData
        The readings, in the file's order.

    Raises
    ------
    MeasurementFileError
        Listing every problem found.
    """
    return _check(read_rows(path, columns=COLUMNS, what=_WHAT))


def _from_frame(df: pd.DataFrame) -> CircleData:
    """A DataFrame's readings, checked as a file's (row k as line k + 2)."""
    missing = [c for c in COLUMNS if c not in df.columns]
    if missing:
        raise MeasurementFileError("DataFrame", [(None, f"missing column(s) {missing}; the "
                                                        f"columns are {', '.join(COLUMNS)}")])
    text = {c: [str(v).strip() for v in df[c].tolist()] for c in COLUMNS}
    return _check(Rows("DataFrame", 1, np.arange(len(df)) + 2, text))


def _sign_sin(angle_deg):
    """sign(sin theta) from degrees, exactly 0 at 0 and 180 deg."""
    a = np.mod(angle_deg, 360.0)
    return np.where((a > 0) & (a < 180), 1.0, np.where(a > 180, -1.0, 0.0))


def signatures(angle_deg, ccw, *, radius_mm: float, feed_mm_per_min: float) -> np.ndarray:
    """The first-order radial signature of each fitted parameter (the module's table).

    Parameters
    ----------
    angle_deg : (n,) array_like
        The readings' angles theta, deg.
    ccw : (n,) array_like of bool
        True for the counter-clockwise run.
    radius_mm : float
        The nominal radius R, mm.
    feed_mm_per_min : float
        The feed v, mm/min.

    Returns
    -------
    (n, 8) ndarray
        d(reading, um) / d(parameter) in the order of :data:`PARAMETERS` (um per um, per um/m,
        per urad, per ms).
    """
    a = np.asarray(angle_deg, dtype=float)
    th = np.deg2rad(a)
    s = np.where(np.asarray(ccw, dtype=bool), 1.0, -1.0)
    half_r = radius_mm * 1e-3 / 2                  # um per (um/m) and per urad
    v = feed_mm_per_min / 60.0                     # mm/s: um per ms
    sign_sin, sign_cos = _sign_sin(a), _sign_sin(a + 90.0)
    return np.column_stack([
        np.ones_like(th), np.cos(th), np.sin(th),
        half_r * np.cos(2 * th), -half_r * np.sin(2 * th), s * v / 2 * np.sin(2 * th),
        s * sign_sin * np.cos(th) / 2, -s * sign_cos * np.sin(th) / 2])


@dataclass(frozen=True)
class Iso230_4Result:
    """The evaluation of one circular test.

    Attributes
    ----------
    plane : str
        The plane; its axes name the per-axis quantities.
    radius_mm, feed_mm_per_min : float
        The test's nominal radius (mm) and feed (mm/min).
    table : DataFrame
        ``quantity, value, unit, standard_uncertainty``: ``G_cw``, ``G_ccw``, ``G_b``, ``H``,
        ``F_max``, ``F_min`` (um; no uncertainty: NaN), ``squareness`` (urad),
        ``scale_mismatch`` (um/m), ``servo_mismatch`` (ms), ``backlash_<a>``,
        ``backlash_<b>``, ``centre_<a>``, ``centre_<b>`` (um).
    residual_um : (n,) ndarray
        The fit's residuals, um, in the readings' order.
    source : str
        The file evaluated.
    """

    plane: str
    radius_mm: float
    feed_mm_per_min: float
    table: pd.DataFrame
    residual_um: np.ndarray
    source: str

    @property
    def conventions(self) -> dict:
        """What each quantity is measured about, and its sign: ``{quantity: statement}``."""
        a, b = PLANES[self.plane]
        return {
            "G_cw": "minimum radial zone of the cw path about its least-squares centre",
            "G_ccw": "minimum radial zone of the ccw path about its least-squares centre",
            "G_b": "bidirectional circular deviation: the radial zone enclosing both paths "
                   "about their common least-squares centre",
            "H": "largest |d_ccw - d_cw| at one angle, both about the instrument's centre",
            "F_max": "largest radial deviation from the nominal radius, about the "
                     "instrument's centre, both directions",
            "F_min": "smallest radial deviation from the nominal radius, about the "
                     "instrument's centre, both directions",
            "squareness": f"> 0 when the angle between +{a} and +{b} exceeds 90 deg",
            "scale_mismatch": f"scale of {a} minus scale of {b}",
            "servo_mismatch": f"lag of {a} minus lag of {b} (> 0: {a} lags more)",
            f"backlash_{a}": f"lost motion of {a} (> 0: a step outwards at {a}'s reversals)",
            f"backlash_{b}": f"lost motion of {b} (> 0: a step outwards at {b}'s reversals)",
            f"centre_{a}": f"the path's centre relative to the instrument's, along {a}",
            f"centre_{b}": f"the path's centre relative to the instrument's, along {b}",
        }

    @property
    def residual_rms_um(self) -> float:
        """The root mean square of the fit's residuals, um (the noise, if the model holds)."""
        return float(np.sqrt(np.mean(self.residual_um ** 2)))

    def describe(self) -> pd.DataFrame:
        """The table with each quantity's convention, for a reader.

        Returns
        -------
        DataFrame
            :meth:`to_df` with a column ``convention``.
        """
        return self.table.assign(convention=self.table["quantity"].map(self.conventions))

    def to_df(self) -> pd.DataFrame:
        """The table ``iso230_4.csv``.

        Returns
        -------
        DataFrame
            Columns ``quantity, value, unit, standard_uncertainty`` (see :attr:`table`).
        """
        return self.table.copy()

    def value(self, quantity: str) -> float:
        """One quantity's value.

        Parameters
        ----------
        quantity : str
            Its name (``"squareness"``, ``"backlash_X"``).

        Returns
        -------
        float
            In the unit of the table.
        """
        return float(self.table.set_index("quantity").loc[quantity, "value"])


def _lsc_zone(angle_deg, d):
    """Max - min of the residuals about the least-squares centre (the limacon fit)."""
    th = np.deg2rad(angle_deg)
    x = np.column_stack([np.ones_like(th), np.cos(th), np.sin(th)])
    res = d - x @ np.linalg.lstsq(x, d, rcond=None)[0]
    return float(np.ptp(res))


def evaluate_iso230_4(data) -> Iso230_4Result:
    """Evaluate a circular test by ISO 230-4:2005 and fit the ballbar diagnostics.

    G per direction about the least-squares centre, H and F about the instrument's centre,
    and the diagnostics of the module's table by one linear least-squares fit of both
    directions (numpy's ``lstsq``), with their standard uncertainties from the residuals.

    Parameters
    ----------
    data : CircleData, str, os.PathLike or DataFrame
        Read readings, a file (:func:`read_iso230_4`), or a DataFrame with the file's
        columns (checked as a file, row k as line k + 2).

    Returns
    -------
    Iso230_4Result
        The table ``quantity, value, unit, standard_uncertainty`` and the fit's residuals.

    Raises
    ------
    MeasurementFileError
        When the readings break the schema (every problem listed).
    """
    if isinstance(data, pd.DataFrame):
        data = _from_frame(data)
    elif not isinstance(data, CircleData):
        data = read_iso230_4(data)
    a_name, b_name = PLANES[data.plane]
    d, ang, ccw = data.deviation_um, data.angle_deg, data.ccw
    x = signatures(ang, ccw, radius_mm=data.radius_mm, feed_mm_per_min=data.feed_mm_per_min)
    coef, _, rank, _ = np.linalg.lstsq(x, d, rcond=None)
    if rank < x.shape[1]:
        raise MeasurementFileError(data.source, [(None, (
            "the readings' angles do not separate the diagnostics (a rank-deficient fit): "
            "measure both directions over the whole circle, equally spaced"))])
    res = d - x @ coef
    dof = d.size - x.shape[1]
    cov = (res @ res / dof) * np.linalg.inv(x.T @ x)
    u = np.sqrt(np.diag(cov))
    cw_at_ccw = np.interp(ang[ccw], ang[~ccw], d[~ccw], period=360.0)
    rows = [("G_cw", _lsc_zone(ang[~ccw], d[~ccw]), "um", np.nan),
            ("G_ccw", _lsc_zone(ang[ccw], d[ccw]), "um", np.nan),
            ("G_b", _lsc_zone(ang, d), "um", np.nan),
            ("H", float(np.abs(d[ccw] - cw_at_ccw).max()), "um", np.nan),
            ("F_max", float(d.max()), "um", np.nan), ("F_min", float(d.min()), "um", np.nan)]
    fitted = {name: (float(c), unit, float(s))
              for (name, unit), c, s in zip(PARAMETERS, coef, u, strict=True)}
    for name in ("squareness", "scale_mismatch", "servo_mismatch"):
        rows.append((name, *fitted[name]))
    for axis, key in ((a_name, "a"), (b_name, "b")):
        rows.append((f"backlash_{axis}", *fitted[f"backlash_{key}"]))
    for axis, key in ((a_name, "a"), (b_name, "b")):
        rows.append((f"centre_{axis}", *fitted[f"centre_{key}"]))
    table = pd.DataFrame(rows, columns=["quantity", "value", "unit", "standard_uncertainty"])
    return Iso230_4Result(data.plane, data.radius_mm, data.feed_mm_per_min, table, res,
                          data.source)
