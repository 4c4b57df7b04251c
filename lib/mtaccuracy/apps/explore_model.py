"""What the interactive explorer computes, as plain functions (no Panel, no Bokeh).

:mod:`mtaccuracy.apps.explore` draws these; the tests and ``make bench`` call them.  Nothing here
is new science: every number comes from the library's functions, with the defaults the notebooks
declare (their ``Parameters``, :mod:`mtaccuracy.papers`).

Error ranges: every error is uniform on ``+- h_i``; the default ``h_i`` are notebook 01's
``position_range_um`` and ``angular_range_arcsec``, notebook 02's ``range_factor`` x the
acceptance values of its ``ranges_file``, the half widths of notebook 03's ``[0, r]`` ranges
(the same variance), and +-5 um, +-3 arcsec for a typed topology (the explorer's choice, about
notebook 06's illustrative ranges).  Every error's half range can be set on its own
(:func:`ranges_table`, :func:`checked_half_ranges`, or a ranges file read as notebook 06 reads it:
:func:`ranges_from_file`); two sliders scale a group: the largest translational half range (um)
and the largest angular one (arcsec), the others keeping their ratio to it
(:func:`scaled_group`).  Indices of the linear model depend only on the ratios of the variances,
so the distribution does not matter.
"""

from __future__ import annotations

import io
import math
import numbers
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import pandas as pd

from .. import errors as _errors
from .. import sensitivity as S
from .. import spindle as SP
from .. import thermal
from ..compendium.notebook import input_path
from ..machines import build
from ..machines.iso import iso_machine
from ..machines.readers import read_ranges
from ..machines.topology import ROTARY
from ..papers import guo2016, rong, xu2022, yang2021, zheng2024

#: The papers' machines offered by the explorer: registry name -> label.
MACHINES = {
    "ac_double_turntable": "AC double turntable (Zheng et al. 2024, 41 errors)",
    "horizontal_3axis": "Horizontal 3-axis machining centre (Rong et al., 21 errors)",
    "vertical_xyfz": "Vertical XYFZ (Guo et al. 2016, 21 errors)",
}
#: The key of a machine typed in as a topology.
TOPOLOGY = "topology"
#: Grid points per axis of the dominant-error map (25 x 25 = 625 poses per update).
GRID_STEPS = 25
#: One arc second in rad.
ARCSEC = _errors.UNIT_SCALE["arcsec"]

# -- What a reader may set: every bound, checked on the server before any work ---------------------

#: The range sliders' bounds: the largest half range of a group (um, arcsec).
RANGE_BOUNDS = (0.1, 100.0)
#: The highest harmonic the Spindle tab analyses (its cost grows with it: 100 takes ~10 ms).
HARMONIC_BOUNDS = (3, 100)
#: A probe's angle (deg), 0 included, 360 excluded (the same direction as 0).
ANGLE_BOUNDS = (0.0, 360.0)
#: Probes in a layout (the library needs at least 3; more is not a layout a reader types).
MAX_PROBES = 12
#: "amplified when q_k above".
AMPLIFIED_BOUNDS = (1.5, 20.0)
#: Grid points per axis of the dominant-error map.
STEPS_BOUNDS = (2, 101)
#: The longest topology accepted (an ISO 230-1 chain of six axes is 15 characters with spaces).
MAX_TOPOLOGY_CHARS = 80
#: Ties in the top-error table: closed-form indices ``J_i**2 var_i / sum_j J_j**2 var_j`` carry
#: a relative rounding error of a few ``d`` ulp (d <= 41 errors: below 1e-14); errors entering
#: the model identically tie exactly in exact arithmetic.  1e-9 is 1e5 times that rounding and
#: 1e5 times below the 4 decimals shown; the absolute 1e-12 only acts near 0.
TOP_TIE_REL, TOP_TIE_ABS = 1e-9, 1e-12


def checked_number(value, name: str, *, low: float, high: float, unit: str = "",
                   integer: bool = False, high_open: bool = False):
    """``value`` as a float (int if ``integer``) in ``low..high``, else a ValueError saying why.

    What every input of the explorer passes before any work: an empty box (None), text, a
    boolean, NaN, an infinity (``1e999``), a fraction where a whole number is due, or a value
    outside the bounds are refused with a message naming the control (``name``) and its bounds.
    ``high_open`` excludes ``high`` itself (an angle of 360 deg).
    """
    span = f"{low:g} to {high:g}{unit}" + (" (excluded)" if high_open else "")
    if value is None or (isinstance(value, str) and not value.strip()):
        raise ValueError(f"{name} is empty: type a number from {span}")
    if isinstance(value, bool | np.bool_) or not isinstance(value, numbers.Real):
        raise ValueError(f"{name} must be a number from {span}, got {value!r}")
    v = float(value)
    if math.isnan(v):
        raise ValueError(f"{name} is not a number (NaN): type a number from {span}")
    if math.isinf(v):
        raise ValueError(f"{name} is infinite (a number too large, such as 1e999): type a "
                         f"number from {span}")
    if integer and v != round(v):
        raise ValueError(f"{name} must be a whole number from {span}, got {v:g}")
    if not low <= v <= high or (high_open and v == high):
        raise ValueError(f"{name} = {v:g} is out of bounds: type a number from {span}")
    return int(round(v)) if integer else v


# -- Machines --------------------------------------------------------------------------------------

class AxisRange(NamedTuple):
    """One pose slider: its range and start, in ``unit`` (mm, or deg for a rotary axis)."""

    name: str
    low: float
    high: float
    default: float
    unit: str

    @property
    def rotary(self) -> bool:
        """Degrees on the slider, rad in the library."""
        return self.unit == "deg"


@dataclass(frozen=True)
class MachineSetup:
    """A machine with its pose sliders, tool offsets (mm), default error half ranges (mm, rad)."""

    key: str
    label: str
    machine: object
    axes: tuple
    tool: dict
    half_range: np.ndarray
    notes: tuple

    @property
    def names(self) -> list[str]:
        """The error symbols, in catalogue order."""
        return list(self.machine.error_names)

    @property
    def outputs(self) -> list[str]:
        """The output names (``machine.components``)."""
        return list(self.machine.components)

    @property
    def translational(self) -> np.ndarray:
        """Which errors the position slider scales (the others: the angular one)."""
        return np.array([e.translational for e in self.machine.catalogue])

    @property
    def position_um(self) -> float:
        """The position slider's start: the largest translational half range (um)."""
        t = self.translational
        return float(self.half_range[t].max() / 1e-3) if t.any() else 0.0

    @property
    def angular_arcsec(self) -> float:
        """The angular slider's start: the largest angular half range (arcsec)."""
        t = ~self.translational
        return float(self.half_range[t].max() / ARCSEC) if t.any() else 0.0

    def axis(self, name: str) -> AxisRange:
        """The slider of pose axis ``name`` (a ValueError names the others)."""
        for a in self.axes:
            if a.name == name:
                return a
        raise ValueError(f"{self.label} has no axis {name!r}; axes: "
                         f"{', '.join(a.name for a in self.axes)}")


def _axes(m, start: dict | None = None) -> tuple:
    """The machine's travels, else -300..300 mm and -180..180 deg; ``start``, else centred."""
    out = []
    for a in m.axes:
        rotary = a in ROTARY
        lo, hi = m.travels.get(a, (-np.pi, np.pi) if rotary else (-300.0, 300.0))
        lo, hi = np.rad2deg((lo, hi)) if rotary else (lo, hi)
        out.append(AxisRange(a, float(lo), float(hi), float((start or {}).get(a, (lo + hi) / 2)),
                             "deg" if rotary else "mm"))
    return tuple(out)


def _largest_by_kind(m, half) -> str:
    """The largest half range of each kind of error, in words (µm, µrad)."""
    largest: dict[str, tuple[float, str]] = {}
    for e, h in zip(m.catalogue, half, strict=True):
        v = (h * 1e3, "µm") if e.translational else (h * 1e6, "µrad")
        largest[e.kind] = max(largest.get(e.kind, v), v)
    return ", ".join(f"±{v:.3g} {unit} {k}" for k, (v, unit) in largest.items())


def _zheng(m):
    p = zheng2024.Parameters.defaults()
    pos, ang = p["position_range_um"], p["angular_range_arcsec"]
    half = [pos * 1e-3 if e.translational else ang * ARCSEC for e in m.catalogue]
    axes = _axes(m, dict(x=120.0, y=-80.0, z=150.0, A=40.0, C=75.0))  # notebook 01's check pose
    return axes, {}, half, (
        "travels: the library's (ac_double_turntable.TRAVELS); starting pose: notebook 01's "
        "check pose", f"errors: ±{pos:g} µm and ±{ang:g} arcsec (Zheng et al. 2024, notebook "
        f"01's position_range_um and angular_range_arcsec)")


def _rong(m):
    p = rong.Parameters.defaults()
    axes = tuple(AxisRange(a, 0.0, float(w), w / 2, "mm")
                 for a, w in zip(m.axes, p["workspace_mm"], strict=True))
    half = p["range_factor"] * read_ranges(input_path(p["ranges_file"], "ranges_file"), m)[1]
    return axes, dict(zip(m.tool_offsets, p["tool_offset_mm"], strict=True)), half, (
        "axes: notebook 02's workspace_mm (the library has no travels for this machine); "
        "starting pose: its centre", f"errors: ±{p['range_factor']:g} x the acceptance values "
        f"of {p['ranges_file']} (notebook 02's range_factor and ranges_file): "
        f"{_largest_by_kind(m, half)}")


def _guo(m):
    p = guo2016.Parameters.defaults()
    axes = tuple(AxisRange(a, 0.0, float(p["workspace_mm"]), float(p[f"{a}_mm"]), "mm")
                 for a in m.axes)
    lo, hi = _errors.uniform_bounds(m.catalogue, {
        k: (0.0, p[f"{k}_{unit}"]) for k, unit in (
            ("positioning", "um"), ("straightness", "um"), ("angular", "rad"),
            ("squareness", "um_per_m"))})
    half = (hi - lo) / 2  # a uniform on [0, r] has the variance of one on +- r / 2
    return axes, {t: p[f"{t}_mm"] for t in m.tool_offsets}, half, (
        "axes: notebook 03's pose grid, 0 to workspace_mm (the library has no travels for "
        "this machine); starting pose: its x_mm, y_mm, z_mm",
        f"errors: half widths of notebook 03's [0, r] ranges: {_largest_by_kind(m, half)}")


_PAPERS = {"ac_double_turntable": _zheng, "horizontal_3axis": _rong, "vertical_xyfz": _guo}


def machine_setup(key: str) -> MachineSetup:
    """One of :data:`MACHINES` with its notebook's declared defaults, else a typed topology."""
    if key not in _PAPERS:
        return topology_setup(key)
    m = build(key)
    axes, tool, half, notes = _PAPERS[key](m)
    return MachineSetup(key, MACHINES[key], m, axes,
                        {t: float(tool.get(t, 0.0)) for t in m.tool_offsets},
                        np.asarray(half, dtype=float), notes)


def topology_setup(topology: str) -> MachineSetup:
    """A machine typed in as a topology; one the library refuses raises its own ValueError."""
    if not isinstance(topology, str) or len(topology) > MAX_TOPOLOGY_CHARS:
        raise ValueError(f"a topology is a text of at most {MAX_TOPOLOGY_CHARS} characters, "
                         f"such as 'w C b X Y Z B t'")
    m = iso_machine(topology, name="typed topology")
    half = np.array([5e-3 if e.translational else 3.0 * ARCSEC for e in m.catalogue])
    removed = f"; {len(m.removed)} redundant location errors removed" if m.removed else ""
    return MachineSetup(
        TOPOLOGY, f"topology {topology.strip()!r} ({m.n_errors} errors)", m, _axes(m),
        {t: 0.0 for t in m.tool_offsets}, half, (
            f"{m.topology.describe()}: ISO 230-1/230-7 catalogue of {m.n_errors} errors"
            f"{removed}", "axes: -300..300 mm and -180..180 deg (no travels known); starting "
            "pose: the centre", "errors: ±5 µm and ±3 arcsec for every error (the explorer's "
            "choice, about notebook 06's illustrative ranges)"))


def error_half_ranges(setup: MachineSetup, position_um: float | None = None,
                      angular_arcsec: float | None = None) -> np.ndarray:
    """Every error's half range (mm, rad) for the two range sliders (None: the notebook's).

    A slider value outside :data:`RANGE_BOUNDS` (or not a finite number) raises a ValueError.
    """
    pos, ang = (default if v is None else checked_number(v, name, low=RANGE_BOUNDS[0],
                                                         high=RANGE_BOUNDS[1], unit=unit)
                for v, default, name, unit in (
                    (position_um, setup.position_um, "the position-error half range", " µm"),
                    (angular_arcsec, setup.angular_arcsec, "the angular-error half range",
                     " arcsec")))
    scale = np.where(setup.translational, pos / setup.position_um if setup.position_um else 0.0,
                     ang / setup.angular_arcsec if setup.angular_arcsec else 0.0)
    return setup.half_range * scale


#: One error's half range in the ranges table: 0 (the error held at its mean) to 10 mm in µm
#: or 10 000 arcsec (an angle beyond the 0.01 rad the library's reader takes).
ERROR_RANGE_BOUNDS = (0.0, 10_000.0)


def range_units(setup: MachineSetup) -> list[str]:
    """The ranges table's unit of each error: ``"µm"`` (translational) or ``"arcsec"``."""
    return ["µm" if t else "arcsec" for t in setup.translational]


def _per_unit(setup: MachineSetup) -> np.ndarray:
    """mm or rad per table unit, per error (1e-3 for µm, :data:`ARCSEC` for arcsec)."""
    return np.where(setup.translational, 1e-3, ARCSEC)


def ranges_table(setup: MachineSetup, half_range=None) -> pd.DataFrame:
    """The ranges table: one row per error, its half range and the notebook's, in µm or arcsec.

    ``half_range`` (mm, rad; None: the notebook's) must pass :func:`checked_half_ranges`.
    """
    half = setup.half_range if half_range is None else checked_half_ranges(setup, half_range)
    unit = _per_unit(setup)
    return pd.DataFrame({
        "error": setup.names, "unit": range_units(setup),
        "half_range": half / unit, "notebook": setup.half_range / unit})


def checked_half_ranges(setup: MachineSetup, half_range, *, in_table_units: bool = False):
    """Every error's half range (mm, rad) checked: ``d`` finite numbers in the table's bounds.

    ``half_range`` is in mm and rad, or in µm and arcsec (the table's) when ``in_table_units``.
    A wrong count, a value that is not a finite number or one outside :data:`ERROR_RANGE_BOUNDS`
    (in the table's units) raises a ValueError naming the error and its bounds.
    """
    values = list(np.ravel(np.asarray(half_range, dtype=object)))
    d = len(setup.names)
    if len(values) != d:
        raise ValueError(f"the ranges table has {d} errors, got {len(values)} half ranges")
    unit = _per_unit(setup)
    shown = np.array([checked_number(
        v if in_table_units else (v / u if isinstance(v, numbers.Real) and not isinstance(
            v, bool | np.bool_) else v),
        f"the half range of {n}", low=ERROR_RANGE_BOUNDS[0], high=ERROR_RANGE_BOUNDS[1],
        unit=f" {un}") for v, u, n, un in zip(values, unit, setup.names, range_units(setup),
                                            strict=True)])
    return shown * unit if in_table_units else np.array(values, dtype=float)   # as given


def scaled_group(setup: MachineSetup, half_range, *, translational: bool, largest: float):
    """``half_range`` (mm, rad) with one group's largest half range set to ``largest``.

    The group (translational errors in µm, else angular ones in arcsec) keeps its ratios; a
    group whose errors are all 0 gets ``largest`` for each.  ``largest`` must lie in
    :data:`RANGE_BOUNDS` (the group sliders).
    """
    half = checked_half_ranges(setup, half_range)
    name, unit = (("the position-error half range", " µm") if translational
                  else ("the angular-error half range", " arcsec"))
    largest = checked_number(largest, name, low=RANGE_BOUNDS[0], high=RANGE_BOUNDS[1], unit=unit)
    group = setup.translational == translational
    if not group.any():
        return half
    per = _per_unit(setup)
    top = (half[group] / per[group]).max()
    out = half.copy()
    out[group] = half[group] * (largest / top) if top > 0 else largest * per[group]
    return out


def ranges_from_file(setup: MachineSetup, path) -> np.ndarray:
    """Every error's half range (mm, rad) from a ranges file, read as notebook 06 reads it.

    :func:`mtaccuracy.machines.readers.read_ranges` against the setup's catalogue (its
    refusals, naming the file and the line, unchanged); a range ``[low, high]`` becomes the half
    width ``(high - low) / 2`` (the same variance; the indices of the linear model do not
    depend on the mean), then :func:`checked_half_ranges`.
    """
    low, high = read_ranges(path, setup.machine)
    return checked_half_ranges(setup, (high - low) / 2.0)


def _half(setup, half_range, position_um, angular_arcsec) -> np.ndarray:
    if half_range is None:
        return error_half_ranges(setup, position_um, angular_arcsec)
    return checked_half_ranges(setup, half_range)


def pose_of(setup: MachineSetup, values: dict | None = None) -> dict:
    """The library's pose (mm, rad, tool offsets) from slider values (missing: the start).

    Every value must be a finite number within its axis's range (a ValueError names the axis).
    """
    values = dict(values or {})
    unknown = sorted(set(values) - {a.name for a in setup.axes})
    if unknown:
        raise ValueError(f"unknown axis(es) {unknown}; axes: "
                         f"{', '.join(a.name for a in setup.axes)}")
    pose = {}
    for a in setup.axes:
        v = values.get(a.name, a.default)
        if np.ndim(v) == 0:
            v = checked_number(v, f"axis {a.name}", low=a.low, high=a.high,
                               unit=f" {a.unit}")
        v = np.asarray(v, dtype=float)
        if not np.all((v >= a.low) & (v <= a.high)):     # NaN fails too
            raise ValueError(f"axis {a.name}: every value must lie in {a.low:g} to "
                             f"{a.high:g} {a.unit}")
        pose[a.name] = np.deg2rad(v) if a.rotary else v
    return {**pose, **setup.tool}


@dataclass(frozen=True)
class PoseIndices:
    """Closed-form indices (d, q) at a pose (0 where an output has no first-order term)."""

    indices: np.ndarray
    first_order: np.ndarray
    names: list
    outputs: list


def indices_at_pose(setup: MachineSetup, values: dict | None = None,
                    position_um: float | None = None,
                    angular_arcsec: float | None = None, *,
                    half_range=None) -> PoseIndices:
    """The first-order model's Sobol indices at one pose, from the closed-form Jacobian.

    ``half_range``: every error's (mm, rad; :func:`checked_half_ranges`), else the two group
    sliders' (:func:`error_half_ranges`).
    """
    sd = _half(setup, half_range, position_um, angular_arcsec) / np.sqrt(3.0)
    jac = setup.machine.jacobian(pose_of(setup, values))                  # (1, q, d)
    idx = S.linear_indices(jac, sd=sd)[0]                                  # (d, q)
    first = S.first_order_outputs(jac, sd**2)[0]
    idx[:, ~first] = 0.0
    return PoseIndices(idx, first, setup.names, setup.outputs)


def top_errors(result: PoseIndices) -> list[tuple[str, tuple[str, ...], float]]:
    """``(output, errors, index)``: every error tied for the largest index, per output.

    Only outputs with a first-order term.  ``errors`` holds every error whose index ties
    (:func:`mtaccuracy.sensitivity.ties`, :data:`TOP_TIE_REL`, :data:`TOP_TIE_ABS`) with the
    largest, in catalogue order; ``index`` is the largest (the ties' values differ by rounding).
    """
    idx = result.indices                                                  # (d, q)
    best = idx.max(axis=0, initial=0.0)                                   # (q,)
    tied = S.ties(idx, best[None, :], rtol=TOP_TIE_REL, atol=TOP_TIE_ABS)  # (d, q)
    return [(o, tuple(result.names[i] for i in np.flatnonzero(tied[:, k])), float(best[k]))
            for k, o in enumerate(result.outputs) if result.first_order[k]]


@dataclass(frozen=True)
class DominantMap:
    """The dominant error (m, n, q; -1: no first-order term) and its index on ``u`` x ``v``."""

    axes: tuple
    u: np.ndarray
    v: np.ndarray
    error: np.ndarray
    index: np.ndarray
    names: list
    outputs: list


def default_map_axes(setup: MachineSetup) -> tuple[str, str]:
    """The map's start: the last and first rotary axes (as notebook 06), else the first two."""
    rotary = [a.name for a in setup.axes if a.rotary]
    if len(rotary) >= 2:
        return rotary[-1], rotary[0]
    names = [a.name for a in setup.axes]
    return names[0], names[min(1, len(names) - 1)]


def dominant_map(setup: MachineSetup, values: dict | None = None, axes=None,
                 steps: int = GRID_STEPS, position_um: float | None = None,
                 angular_arcsec: float | None = None, *, half_range=None) -> DominantMap:
    """The dominant error over a ``steps`` x ``steps`` grid of two axes, in one Jacobian call."""
    steps = checked_number(steps, "the map's grid steps", low=STEPS_BOUNDS[0],
                           high=STEPS_BOUNDS[1], integer=True)
    pose_of(setup, values)                      # the pose's refusals, before the grid is built
    a1, a2 = axes if axes is not None else default_map_axes(setup)
    r1, r2 = setup.axis(a1), setup.axis(a2)
    u, v = np.linspace(r1.low, r1.high, steps), np.linspace(r2.low, r2.high, steps)
    uu, vv = np.meshgrid(u, v, indexing="xy")                  # (m, n): rows follow v
    grid = {a.name: np.full(uu.size, (values or {}).get(a.name, a.default), dtype=float)
            for a in setup.axes}
    grid[a1] = uu.ravel()
    if a2 != a1:
        grid[a2] = vv.ravel()
    var = _half(setup, half_range, position_um, angular_arcsec) ** 2 / 3.0
    jac = setup.machine.jacobian(pose_of(setup, grid))                     # (G, q, d)
    dom = S.dominant_errors(jac, var)                                      # (G, q)
    idx = S.indices_at_poses(jac, var=var)                                 # (G, d, q)
    top = np.take_along_axis(idx, np.maximum(dom, 0)[:, None, :], axis=1)[:, 0, :]
    shape = (steps, steps, len(setup.outputs))
    return DominantMap((a1, a2), u, v, dom.reshape(shape),
                       np.where(dom >= 0, top, 0.0).reshape(shape), setup.names, setup.outputs)


def slider_update(setup: MachineSetup, values: dict | None = None, *, axes=None,
                  steps: int = GRID_STEPS, position_um: float | None = None,
                  angular_arcsec: float | None = None,
                  half_range=None) -> tuple[PoseIndices, DominantMap]:
    """What one move of a Machine-tab slider computes: the indices at the pose and the map."""
    half = _half(setup, half_range, position_um, angular_arcsec)
    return (indices_at_pose(setup, values, half_range=half),
            dominant_map(setup, values, axes, steps, half_range=half))


# -- Spindle: what a probe layout does to each harmonic --------------------------------------------

#: Yang et al. 2021's four-point layout as notebook 05 declares it: samples, of 128, and ``a3``.
_YANG = yang2021.Parameters.defaults()
YANG_POSITIONS = tuple(int(v) for v in _YANG["probe_positions"])
YANG_SAMPLES, YANG_A3 = int(_YANG["n_samples"]), float(_YANG["a3"])
#: Its probe angles in degrees (0, 39.375, 182.8125, 326.25).
YANG_DEG = tuple(np.rad2deg(SP.probe_angles(list(YANG_POSITIONS), YANG_SAMPLES)).tolist())


def _check_layout(deg: np.ndarray, weights: str) -> None:
    """The library's refusals of a layout, with probes numbered from 1 as in the controls."""
    d = np.abs((deg[:, None] - deg[None, :] + 180.0) % 360.0 - 180.0)       # (n, n) deg
    same = np.triu(d < np.rad2deg(1e-9), k=1)                    # the library's 1e-9 rad
    if same.any():
        i, j = np.argwhere(same)[0]
        raise ValueError(f"probes {i + 1} and {j + 1} are at the same angle ({deg[i]:g} and "
                         f"{deg[j]:g} deg): move one of them")
    if weights == "eq5" and deg.size == 4 and \
            abs(np.sin(np.deg2rad(deg[2] - deg[1]))) < 1e-12:
        raise ValueError("probes 2 and 3 are coincident or opposite (sin(phi_2 - phi_1) = 0 in "
                         "Yang et al.'s Eq. 15, which numbers from 0): Eq. 5 cannot give their "
                         "weights; move probe 3")


@dataclass(frozen=True)
class ProbeTransfer:
    """Per harmonic 2..K: each estimator's noise amplification ``q_k`` (inf: cancelled)."""

    angles_deg: np.ndarray
    harmonics: np.ndarray
    weights: np.ndarray | None
    q_least_squares: np.ndarray
    q_weighted: np.ndarray
    gain_weighted: np.ndarray
    cancelled: np.ndarray
    cancelled_by_weights: np.ndarray
    amplified_least_squares: np.ndarray
    amplified_weighted: np.ndarray
    amplified_above: float


def probe_transfer(angles_deg, max_harmonic: int = 20, weights: str = "optimal",
                   a3: float = YANG_A3, amplified_above: float = 3.0) -> ProbeTransfer:
    """What probes at ``angles_deg`` do to harmonics 2..``max_harmonic``, for both estimators.

    Least squares and the weighted multi-point method (Yang et al. 2021, Eqs. 14, 19) through
    :func:`mtaccuracy.spindle.probes.noise_amplification`; the weights ``"optimal"``
    (:func:`~mtaccuracy.spindle.probes.layout_weights` over the harmonics the layout keeps) or
    ``"eq5"`` (Eq. 5 with ``a3``, four probes).  Every input is checked first (angles in
    ``[0, 360)`` deg, at most :data:`MAX_PROBES`; ``max_harmonic`` in :data:`HARMONIC_BOUNDS`;
    ``a3``, ``amplified_above`` in their bounds); probes are numbered from 1, as in the
    explorer's controls (probe 1 is the first angle).  A bad layout raises a ValueError.
    """
    angles = list(np.ravel(np.asarray(angles_deg, dtype=object)))
    if not 1 <= len(angles) <= MAX_PROBES:
        raise ValueError(f"a layout has 3 to {MAX_PROBES} probes, got {len(angles)}")
    deg = np.array([checked_number(a, f"probe {i + 1} angle", low=ANGLE_BOUNDS[0],
                                   high=ANGLE_BOUNDS[1], unit=" deg", high_open=True)
                    for i, a in enumerate(angles)])
    max_harmonic = checked_number(max_harmonic, "the highest harmonic", low=HARMONIC_BOUNDS[0],
                                  high=HARMONIC_BOUNDS[1], integer=True)
    a3 = checked_number(a3, "a3 (Eq. 5)", low=yang2021.Parameters.param["a3"].bounds[0],
                        high=yang2021.Parameters.param["a3"].bounds[1])
    amplified_above = checked_number(amplified_above, "amplified when q_k above",
                                     low=AMPLIFIED_BOUNDS[0], high=AMPLIFIED_BOUNDS[1])
    _check_layout(deg, weights)
    phi = np.deg2rad(deg)
    ks = np.arange(2, int(max_harmonic) + 1)
    cancelled = np.isin(ks, SP.layout_cancelled(phi, int(max_harmonic)))
    q_ls = SP.noise_amplification(phi, ks)
    if weights == "optimal":
        w = SP.layout_weights(phi, ks[~cancelled]) if (~cancelled).any() else None
    elif weights == "eq5":
        if phi.shape != (4,):
            raise ValueError(f"Eq. 5 weights are for four probes, got {phi.shape[0]}")
        w = SP.full_weights(phi, a3)
    else:
        raise ValueError(f"weights must be 'optimal' or 'eq5', got {weights!r}")
    q_w = np.full(ks.shape, np.inf) if w is None else SP.noise_amplification(phi, ks, weights=w)
    q_w = np.where(cancelled, np.inf, q_w)
    with np.errstate(divide="ignore"):
        gain = np.where(np.isfinite(q_w), 1.0 / q_w, 0.0)
    return ProbeTransfer(
        np.rad2deg(phi), ks, None if w is None else np.asarray(w, dtype=float), q_ls, q_w, gain,
        cancelled, ~cancelled & ~np.isfinite(q_w), np.isfinite(q_ls) & (q_ls > amplified_above),
        np.isfinite(q_w) & (q_w > amplified_above), float(amplified_above))


# -- Thermal: a train/test split of notebook 04 ----------------------------------------------------

#: Notebook 04's declared defaults: its data, split, inputs, and the selection's settings.
_XU = xu2022.Parameters.defaults()


@dataclass(frozen=True)
class ThermalPrediction:
    """The test experiment's thermal error, measured and predicted (n x P positions, um)."""

    train: list
    test: int
    kind: str
    inputs: dict
    positions_mm: np.ndarray
    time_min: np.ndarray
    measurement: np.ndarray
    measured: np.ndarray
    predicted: np.ndarray
    rmse: float
    max_residual: float
    rmse_uncompensated: float


def thermal_data(folder=None):
    """Notebook 04's ``data_dir`` (or ``folder``), and whether it is the paper's reconstruction."""
    folder = input_path(_XU["data_dir"] if folder is None else folder, "data_dir")
    return thermal.read_measurements(folder), xu2022.reconstruction_seed(folder) is not None


def thermal_defaults(data, reconstructed: bool) -> dict:
    """Notebook 04's declared ``train``, ``test`` and ``inputs`` on ``data`` (the tab's start)."""
    train, test = xu2022.resolve_split(xu2022.Parameters.stem, data,
                                       train=_XU["train_experiments"], test=_XU["test_experiment"])
    return {"train": train, "test": test,
            "inputs": xu2022.resolve_inputs(_XU["inputs"], reconstructed)}


def thermal_prediction(data, *, train, test: int, inputs: str = "published", kind: str = "mlr",
                       progress=None) -> ThermalPrediction:
    """Predict ``test`` with the decoupled model (Eq. 9) fitted on ``train``, as notebook 04.

    ``inputs``: ``"published"`` (the paper's sensitive points) or ``"selected"`` (its procedure on
    the training experiments, notebook 04's ``n_clusters`` and ``rho``); ``kind``: ``"mlr"`` or
    ``"svr"``; ``progress`` is passed to :func:`mtaccuracy.thermal.evaluate_split`.
    """
    bad = [e for e in [*train, test] if isinstance(e, bool) or not isinstance(e, numbers.Integral)]
    if bad:                                     # the library refuses unknown experiments
        raise ValueError(f"an experiment is a whole number, got {bad[0]!r}")
    if inputs not in ("published", "selected") or kind not in ("mlr", "svr"):
        raise ValueError(f"inputs must be 'published' or 'selected' and kind 'mlr' or 'svr', "
                         f"got {inputs!r}, {kind!r}")
    train, test = sorted({int(e) for e in train}), int(test)
    if not train or test in train:
        raise ValueError(f"the test experiment {test} is also a training experiment" if train
                         else "no training experiment chosen")
    if inputs not in ("published", "selected"):
        raise ValueError(f"inputs must be 'published' or 'selected', got {inputs!r}")
    res = thermal.evaluate_split(
        data, train=train, test=[test], kinds=(kind,), n_clusters=_XU["n_clusters"],
        sensors=xu2022.published_inputs() if inputs == "published" else None, rho=_XU["rho"],
        progress=progress, baselines=("uncompensated",))
    measured, predicted = res.measured, res.predictions[f"decoupled_{kind}"]
    m, te = thermal.metrics(measured - predicted), data.subset(test)
    return ThermalPrediction(
        train, test, kind, {"k": list(res.inputs["k"]), "b": list(res.inputs["b"])},
        np.asarray(data.positions_mm, dtype=float), te.index.time_min.to_numpy(float),
        te.index.measurement.to_numpy(int), measured, predicted, float(m["rmse"]),
        float(m["max_residual"]), float(thermal.metrics(measured)["rmse"]))


# -- The tables the explorer shows, as CSV ---------------------------------------------------------

def top_errors_table(result: PoseIndices) -> pd.DataFrame:
    """The top-error table: one row per output and tied error (``index`` repeated), as shown."""
    rows = [(o, e, v) for o, errs, v in top_errors(result) for e in errs]
    return pd.DataFrame(rows, columns=["output", "error", "index"])


def indices_table(result: PoseIndices) -> pd.DataFrame:
    """The heat map: one row per error, one column per output (empty: no first-order term)."""
    idx = np.where(result.first_order[None, :], result.indices, np.nan)
    return pd.DataFrame({"error": result.names,
                         **{o: idx[:, k] for k, o in enumerate(result.outputs)}})


def probe_table(t: ProbeTransfer) -> pd.DataFrame:
    """The Spindle tab per harmonic: ``q_k`` of both estimators (inf: cancelled) and flags."""
    return pd.DataFrame({
        "k": t.harmonics, "q_least_squares": t.q_least_squares, "q_weighted": t.q_weighted,
        "weighted_gain": t.gain_weighted, "cancelled_by_layout": t.cancelled,
        "cancelled_by_weights": t.cancelled_by_weights,
        "amplified_least_squares": t.amplified_least_squares,
        "amplified_weighted": t.amplified_weighted})


def thermal_table(r: ThermalPrediction) -> pd.DataFrame:
    """The Thermal tab's test experiment: one row per measurement and position (um)."""
    n, p = r.measured.shape
    return pd.DataFrame({
        "measurement": np.repeat(r.measurement, p), "time_min": np.repeat(r.time_min, p),
        "position_mm": np.tile(r.positions_mm, n), "measured_um": r.measured.ravel(),
        "predicted_um": r.predicted.ravel(), "residual_um": (r.measured - r.predicted).ravel()})


def to_csv(frame: pd.DataFrame) -> str:
    """``frame`` as CSV text: no index, full precision (``repr`` of each float), ``\\n`` lines."""
    out = io.StringIO()
    frame.to_csv(out, index=False, lineterminator="\n")
    return out.getvalue()
