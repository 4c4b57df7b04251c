"""What the interactive explorer computes, as plain functions (no Panel, no Bokeh).

:mod:`mtaccuracy.apps.explore` draws these; the tests and ``make bench`` call them directly.
Nothing here is new science: every number comes from the library's own functions, with the
inputs the notebooks declare (their ``Parameters``, :mod:`mtaccuracy.papers`).

Machines (tab "Machine")
    :func:`machine_setup` builds one of the papers' three machines or any topology typed in
    (:func:`mtaccuracy.machines.iso.iso_machine`) with the pose ranges and the default error
    ranges the explorer offers (:class:`MachineSetup` says where each came from).
    :func:`indices_at_pose` gives the closed-form Sobol indices of the first-order model at one
    pose (:func:`mtaccuracy.sensitivity.linear_indices` of ``machine.jacobian``);
    :func:`dominant_map` the error with the largest index over a grid of two axes, batched
    (one Jacobian call on every grid pose, :func:`mtaccuracy.sensitivity.dominant_errors`);
    :func:`slider_update` is what one slider move computes (timed by ``make bench``).

Error ranges
    Every error is uniform on ``+- h_i``.  The default ``h_i`` are the defaults the notebooks
    declare: notebook 01's ``position_range_um`` and ``angular_range_arcsec`` (Zheng et al.
    2024), notebook 02's ``range_factor`` x the acceptance values of its ``ranges_file`` (Rong
    et al.), the half widths of notebook 03's ``[0, r]`` ranges (Guo et al. 2016: the same
    variance); a typed topology +-5 um and +-3 arcsec for every error (a choice of the
    explorer, about the illustrative ranges of notebook 06).  Two numbers scale them: the
    *position half range* (um) is the largest half range among the translational errors, the
    *angular half range* (arcsec) the largest among the angular ones; the others keep their
    ratio to it.  Indices of the linear model depend only on the ratios of the variances, so
    the distribution (uniform here, normal in notebook 01) does not matter.

Spindle (tab "Spindle")
    :func:`probe_transfer`: per harmonic, the noise amplification ``q_k`` of the two estimators
    of :mod:`mtaccuracy.spindle.probes` (least squares, and the weighted multi-point method of
    Yang et al. 2021 with the weights :func:`~mtaccuracy.spindle.probes.layout_weights` finds
    or those of Eq. 5 for a given ``a3``), the harmonics the layout cancels and those it
    amplifies; notebook 05's layout to start with.

Thermal (tab "Thermal")
    :func:`thermal_prediction`: notebook 04's split (:func:`mtaccuracy.thermal.evaluate_split`)
    on chosen experiments, the decoupled model of Xu et al. 2022 (Eq. 9), MLR or SVR, with the
    paper's sensitive points (:func:`mtaccuracy.papers.xu2022.published_inputs`) or the ones
    its procedure selects on the training experiments; notebook 04's data and split to start
    with (:func:`thermal_defaults`).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

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


# ------------------------------------------------------------------------------------------
# Machines
# ------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class AxisRange:
    """The slider of one pose axis.

    Attributes
    ----------
    name : str
        Pose name (``x``, ``y``, ``z`` lower case; ``A``, ``B``, ``C``).
    low, high, default : float
        Range and starting value, in ``unit``.
    unit : str
        ``"mm"`` (linear axes) or ``"deg"`` (rotary axes; the library takes rad).
    """

    name: str
    low: float
    high: float
    default: float
    unit: str

    @property
    def rotary(self) -> bool:
        """bool: a rotary axis (degrees on the slider, rad in the library)."""
        return self.unit == "deg"


@dataclass(frozen=True)
class MachineSetup:
    """A machine with the explorer's pose ranges and default error ranges.

    Attributes
    ----------
    key : str
        A name of :data:`MACHINES`, or :data:`TOPOLOGY`.
    label : str
        What the explorer calls it.
    machine : ChainMachine
        The machine.
    axes : tuple of AxisRange
        One per pose axis, in ``machine.axes`` order.
    tool : dict
        Tool offsets (mm), fixed.
    half_range : array (d,)
        Default half range of every error (mm, rad): uniform on ``+- half_range``.
    position_um, angular_arcsec : float
        The default values of the two range sliders: the largest half range of the
        translational errors (um) and of the angular ones (arcsec).
    notes : tuple of str
        Where the ranges come from, in words.
    """

    key: str
    label: str
    machine: object
    axes: tuple
    tool: dict
    half_range: np.ndarray
    position_um: float
    angular_arcsec: float
    notes: tuple = field(default_factory=tuple)

    @property
    def names(self) -> list[str]:
        """list of str: the error symbols (catalogue order)."""
        return list(self.machine.error_names)

    @property
    def outputs(self) -> list[str]:
        """list of str: the output names (``machine.components``)."""
        return list(self.machine.components)

    @property
    def translational(self) -> np.ndarray:
        """array of bool (d,): the translational errors."""
        return np.array([e.translational for e in self.machine.catalogue])

    def axis(self, name: str) -> AxisRange:
        """The :class:`AxisRange` of pose axis ``name`` (a ValueError names the others)."""
        for a in self.axes:
            if a.name == name:
                return a
        raise ValueError(f"{self.label} has no axis {name!r}; axes: "
                         f"{', '.join(a.name for a in self.axes)}")


def _zheng_setup() -> tuple:
    """Notebook 01's machine: the library's travels, its check pose, its declared ranges."""
    m, p = build("ac_double_turntable"), zheng2024.Parameters.defaults()
    axes = _axes(m, dict(x=120.0, y=-80.0, z=150.0, A=40.0, C=75.0))  # notebook 01's check pose
    pos, ang = p["position_range_um"], p["angular_range_arcsec"]
    half = np.array([pos * 1e-3 if e.translational else ang * ARCSEC for e in m.catalogue])
    return m, axes, {}, half, (
        "travels: the library's (ac_double_turntable.TRAVELS); starting pose: notebook 01's "
        "check pose", f"errors: ±{pos:g} µm and ±{ang:g} arcsec (Zheng et al. 2024, notebook "
        f"01's position_range_um and angular_range_arcsec)")


def _rong_setup() -> tuple:
    """Notebook 02's machine: its declared workspace, tool offset, ranges file and factor."""
    m, p = build("horizontal_3axis"), rong.Parameters.defaults()
    work = dict(zip(m.axes, p["workspace_mm"], strict=True))
    axes = tuple(AxisRange(a, 0.0, work[a], work[a] / 2, "mm") for a in m.axes)
    factor, ranges = p["range_factor"], p["ranges_file"]
    half = factor * read_ranges(input_path(ranges, "ranges_file"), m)[1]
    tool = dict(zip(m.tool_offsets, p["tool_offset_mm"], strict=True))
    return m, axes, tool, half, (
        "axes: notebook 02's workspace_mm (the library has no travels for this machine); "
        "starting pose: its centre", f"errors: ±{factor:g} x the acceptance values of "
        f"{ranges} (notebook 02's range_factor and ranges_file): {_largest_by_kind(m, half)}")


def _guo_setup() -> tuple:
    """Notebook 03's machine: its declared pose, grid, tool offsets and ``[0, r]`` ranges."""
    m, p = build("vertical_xyfz"), guo2016.Parameters.defaults()
    high = p["workspace_mm"]
    axes = tuple(AxisRange(a, 0.0, high, p[f"{a}_mm"], "mm") for a in m.axes)
    b = _errors.uniform_bounds(m.catalogue, {
        k: (0.0, p[name]) for k, name in (
            ("positioning", "positioning_um"), ("straightness", "straightness_um"),
            ("angular", "angular_rad"), ("squareness", "squareness_um_per_m"))})
    half = (b[1] - b[0]) / 2  # a uniform on [0, r] has the variance of one on +- r / 2
    return m, axes, {t: p[f"{t}_mm"] for t in m.tool_offsets}, half, (
        "axes: notebook 03's pose grid, 0 to workspace_mm (the library has no travels for "
        "this machine); starting pose: its x_mm, y_mm, z_mm",
        f"errors: half widths of notebook 03's [0, r] ranges: {_largest_by_kind(m, half)}")


def _axes(m, start: dict | None = None) -> tuple:
    """The pose sliders: the machine's travels, else -300..300 mm and -180..180 deg (the box
    of :func:`~mtaccuracy.machines.iso.redundant_location_errors`); ``start``, else centred."""
    out = []
    for a in m.axes:
        rotary = a in ROTARY
        lo, hi = m.travels.get(a, (-np.pi, np.pi) if rotary else (-300.0, 300.0))
        lo, hi = np.rad2deg((lo, hi)) if rotary else (lo, hi)
        out.append(AxisRange(a, lo, hi, (start or {}).get(a, (lo + hi) / 2),
                             "deg" if rotary else "mm"))
    return tuple(out)


def _largest_by_kind(m, half: np.ndarray) -> str:
    """The largest half range of each kind of error, in words (µm, µrad)."""
    largest: dict[str, tuple[float, str]] = {}
    for e, h in zip(m.catalogue, half, strict=True):
        v = (h * 1e3, "µm") if e.translational else (h * 1e6, "µrad")
        largest[e.kind] = max(largest.get(e.kind, v), v)
    return ", ".join(f"±{v:.3g} {unit} {k}" for k, (v, unit) in largest.items())


def _largest(half: np.ndarray, mask: np.ndarray, unit: float) -> float:
    return float(half[mask].max() / unit) if mask.any() else 0.0


_PAPERS = {"ac_double_turntable": _zheng_setup, "horizontal_3axis": _rong_setup,
           "vertical_xyfz": _guo_setup}


def machine_setup(key: str) -> MachineSetup:
    """The machine called ``key`` with the explorer's pose and error ranges.

    Parameters
    ----------
    key : str
        A name of :data:`MACHINES`, or a topology string (``"w C b X Y Z B t"``, read by
        :func:`mtaccuracy.machines.iso.iso_machine`).

    Returns
    -------
    MachineSetup
        The papers' machines with their notebooks' declared defaults: pose ranges the
        machine's travels when the library knows them (Zheng et al.'s ``TRAVELS``), the
        notebook's workspace otherwise (notebook 02's ``workspace_mm``, notebook 03's pose
        grid); starting pose notebook 01's check pose (x 120, y -80, z 150 mm, A 40, C 75 deg),
        the centre of Rong's workspace, Guo's declared pose; tool offsets as declared (0 for
        notebook 01's).  A typed topology (:func:`topology_setup`, used for any ``key`` not in
        :data:`MACHINES`): -300..300 mm and -180..180 deg (the box of
        :func:`~mtaccuracy.machines.iso.redundant_location_errors`), the centre, no offset.

    Raises
    ------
    ValueError
        For a topology the library refuses, with the library's own message.
    """
    if key not in _PAPERS:
        return topology_setup(key)
    return _setup(key, MACHINES[key], *_PAPERS[key]())


def topology_setup(topology: str) -> MachineSetup:
    """A machine typed in as a topology, with the explorer's ranges (see :func:`machine_setup`).

    ``topology`` is read by :func:`mtaccuracy.machines.iso.iso_machine` (ISO 230-1/230-7
    catalogue, redundant location errors removed), even when it is also a machine's name; one
    the library refuses raises its ValueError, with its own message.
    """
    m = iso_machine(topology, name="typed topology")
    axes = _axes(m)
    half = np.array([5e-3 if e.translational else 3.0 * ARCSEC for e in m.catalogue])
    removed = f"; {len(m.removed)} redundant location errors removed" if m.removed else ""
    notes = (f"{m.topology.describe()}: ISO 230-1/230-7 catalogue of {m.n_errors} errors"
             f"{removed}",
             "axes: -300..300 mm and -180..180 deg (no travels known); starting pose: the "
             "centre",
             "errors: ±5 µm and ±3 arcsec for every error (the explorer's choice, about "
             "notebook 06's illustrative ranges)")
    return _setup(TOPOLOGY, f"topology {topology.strip()!r} ({m.n_errors} errors)", m, axes, {},
                  half, notes)


def _setup(key, label, m, axes, tool, half, notes) -> MachineSetup:
    axes = tuple(AxisRange(a.name, float(a.low), float(a.high), float(a.default), a.unit)
                 for a in axes)
    trans = np.array([e.translational for e in m.catalogue])
    return MachineSetup(key, label, m, axes,
                        {t: float(tool.get(t, 0.0)) for t in m.tool_offsets},
                        np.asarray(half, dtype=float), _largest(half, trans, 1e-3),
                        _largest(half, ~trans, ARCSEC), tuple(notes))


def error_half_ranges(setup: MachineSetup, *, position_um: float | None = None,
                      angular_arcsec: float | None = None) -> np.ndarray:
    """The half range of every error for the two range sliders (mm, rad).

    Parameters
    ----------
    setup : MachineSetup
        The machine.
    position_um : float, optional
        The largest half range of the translational errors (um); the others keep their ratio
        to it (default: ``setup.position_um``, the notebook's).
    angular_arcsec : float, optional
        The same for the angular errors (arcsec).

    Returns
    -------
    array (d,)
        Half ranges, mm and rad.
    """
    pos = setup.position_um if position_um is None else float(position_um)
    ang = setup.angular_arcsec if angular_arcsec is None else float(angular_arcsec)
    if not (np.isfinite(pos) and np.isfinite(ang)) or pos < 0 or ang < 0:
        raise ValueError(f"half ranges must be finite and >= 0, got {pos} µm, {ang} arcsec")
    trans = setup.translational
    scale = np.where(trans, pos / setup.position_um if setup.position_um else 0.0,
                     ang / setup.angular_arcsec if setup.angular_arcsec else 0.0)
    return setup.half_range * scale


def pose_of(setup: MachineSetup, values: Mapping[str, float] | None = None) -> dict:
    """The library's pose (mm, rad, tool offsets included) from slider values.

    Parameters
    ----------
    setup : MachineSetup
        The machine.
    values : mapping of str to float or array, optional
        Axis -> value in the slider's unit (mm, deg); missing axes take their default.

    Returns
    -------
    dict of str to float or array
        For ``machine.jacobian``.
    """
    values = dict(values or {})
    unknown = sorted(set(values) - {a.name for a in setup.axes})
    if unknown:
        raise ValueError(f"unknown axis(es) {unknown}; axes: "
                         f"{', '.join(a.name for a in setup.axes)}")
    pose = {}
    for a in setup.axes:
        v = np.asarray(values.get(a.name, a.default), dtype=float)
        pose[a.name] = np.deg2rad(v) if a.rotary else v
    return {**pose, **setup.tool}


@dataclass(frozen=True)
class PoseIndices:
    """Closed-form Sobol indices of the first-order model at one pose.

    Attributes
    ----------
    indices : array (d, q)
        First-order = total index of each error (rows) for each output (columns); 0 for an
        output with no first-order term.
    first_order : array of bool (q,)
        The output has a first-order term at this pose
        (:func:`mtaccuracy.sensitivity.first_order_outputs`).
    sd : array (q,)
        Standard deviation of each output of the linear model (mm, rad).
    names, outputs : list of str
        Errors and outputs.
    """

    indices: np.ndarray
    first_order: np.ndarray
    sd: np.ndarray
    names: list
    outputs: list


def indices_at_pose(setup: MachineSetup, values: Mapping[str, float] | None = None, *,
                    position_um: float | None = None,
                    angular_arcsec: float | None = None) -> PoseIndices:
    """Closed-form Sobol indices of the first-order model at one pose.

    ``S_ki = J_ki^2 sd_i^2 / sum_j J_kj^2 sd_j^2`` (:func:`mtaccuracy.sensitivity.
    linear_indices`) with ``J`` the machine's closed-form Jacobian
    (``machine.jacobian``) and ``sd_i = h_i / sqrt(3)`` (uniform on ``+- h_i``).

    Parameters
    ----------
    setup : MachineSetup
        The machine.
    values : mapping of str to float, optional
        Pose in slider units (mm, deg); missing axes at their default.
    position_um, angular_arcsec : float, optional
        The range sliders (:func:`error_half_ranges`).

    Returns
    -------
    PoseIndices
    """
    sd = error_half_ranges(setup, position_um=position_um,
                           angular_arcsec=angular_arcsec) / np.sqrt(3.0)
    jac = setup.machine.jacobian(pose_of(setup, values))          # (1, q, d)
    idx = S.linear_indices(jac, sd=sd)[0]                                   # (d, q)
    first = S.first_order_outputs(jac, sd**2)[0]
    idx[:, ~first] = 0.0
    out_sd = np.sqrt((jac[0] ** 2 * sd**2).sum(-1))
    return PoseIndices(idx, first, out_sd, setup.names, setup.outputs)


def top_errors(result: PoseIndices) -> list[tuple[str, str, float]]:
    """The error with the largest index for each output with a first-order term.

    Ties within :func:`mtaccuracy.sensitivity.merge_ties`'s tolerance go to the first in the
    catalogue (as :func:`mtaccuracy.sensitivity.dominant_errors`).

    Parameters
    ----------
    result : PoseIndices
        Indices at a pose.

    Returns
    -------
    list of (str, str, float)
        ``(output, error, index)`` per output with a first-order term.
    """
    merged = S.merge_ties(result.indices)
    top = np.argmax(merged, axis=0)
    return [(o, result.names[top[k]], float(result.indices[top[k], k]))
            for k, o in enumerate(result.outputs) if result.first_order[k]]


@dataclass(frozen=True)
class DominantMap:
    """The error with the largest closed-form index over a grid of two axes.

    Attributes
    ----------
    axes : tuple of str
        The two axes: ``axes[0]`` across (columns), ``axes[1]`` up (rows).
    u, v : arrays (n,), (m,)
        Their grid values, in slider units (mm, deg).
    error : array of int (m, n, q)
        Column of the dominant error at each grid pose and output; -1 where the output has no
        first-order term.
    index : array (m, n, q)
        Its index (0 where ``error`` is -1).
    names, outputs : list of str
        Errors and outputs.
    """

    axes: tuple
    u: np.ndarray
    v: np.ndarray
    error: np.ndarray
    index: np.ndarray
    names: list
    outputs: list


def default_map_axes(setup: MachineSetup) -> tuple[str, str]:
    """The two axes the dominant-error map starts on.

    The last and first rotary axes when the machine has two (as notebook 06), else its first two
    axes (one axis: it twice).

    Parameters
    ----------
    setup : MachineSetup
        The machine.

    Returns
    -------
    tuple of str
    """
    rotary = [a.name for a in setup.axes if a.rotary]
    if len(rotary) >= 2:
        return rotary[-1], rotary[0]
    names = [a.name for a in setup.axes]
    return (names[0], names[1]) if len(names) > 1 else (names[0], names[0])


def dominant_map(setup: MachineSetup, values: Mapping[str, float] | None = None, *,
                 axes: Sequence[str] | None = None, steps: int = GRID_STEPS,
                 position_um: float | None = None,
                 angular_arcsec: float | None = None) -> DominantMap:
    """The dominant error over a ``steps x steps`` grid of two axes, the others fixed.

    One batched ``machine.jacobian`` call on all grid poses (a leading pose axis, no
    loop over them), then :func:`mtaccuracy.sensitivity.dominant_errors` (ties to the first in
    the catalogue; -1 for an output without a first-order term) and
    :func:`mtaccuracy.sensitivity.indices_at_poses` for the index shown.

    Parameters
    ----------
    setup : MachineSetup
        The machine.
    values : mapping of str to float, optional
        Pose in slider units; the two grid axes are overridden.
    axes : sequence of two str, optional
        The grid axes, each over its slider range (default :func:`default_map_axes`).
    steps : int
        Grid points per axis (>= 2).
    position_um, angular_arcsec : float, optional
        The range sliders (:func:`error_half_ranges`).

    Returns
    -------
    DominantMap
    """
    a1, a2 = axes if axes is not None else default_map_axes(setup)
    if isinstance(steps, bool) or not isinstance(steps, int | np.integer) or steps < 2:
        raise ValueError(f"steps must be an integer >= 2, got {steps!r}")
    r1, r2 = setup.axis(a1), setup.axis(a2)
    u = np.linspace(r1.low, r1.high, steps)
    v = np.linspace(r2.low, r2.high, steps)
    uu, vv = np.meshgrid(u, v, indexing="xy")                  # (m, n): rows follow v
    grid = {a.name: np.full(uu.size, values.get(a.name, a.default) if values else a.default,
                            dtype=float) for a in setup.axes}
    grid[a1] = uu.ravel()
    if a2 != a1:
        grid[a2] = vv.ravel()
    var = error_half_ranges(setup, position_um=position_um,
                            angular_arcsec=angular_arcsec) ** 2 / 3.0
    jac = setup.machine.jacobian(pose_of(setup, grid))            # (G, q, d)
    dom = S.dominant_errors(jac, var)                                    # (G, q)
    idx = S.indices_at_poses(jac, var=var)                                   # (G, d, q)
    top = np.take_along_axis(idx, np.maximum(dom, 0)[:, None, :], axis=1)[:, 0, :]
    top = np.where(dom >= 0, top, 0.0)
    shape = (steps, steps, len(setup.outputs))
    return DominantMap((a1, a2), u, v, dom.reshape(shape), top.reshape(shape), setup.names,
                       setup.outputs)


def slider_update(setup: MachineSetup, values: Mapping[str, float] | None = None, *,
                  axes: Sequence[str] | None = None, steps: int = GRID_STEPS,
                  position_um: float | None = None, angular_arcsec: float | None = None
                  ) -> tuple[PoseIndices, DominantMap]:
    """Everything one slider move of the Machine tab computes.

    The indices at the pose and the dominant-error map.

    Parameters
    ----------
    setup : MachineSetup
        The machine.
    values : mapping of str to float, optional
        Pose in slider units.
    axes : sequence of two str, optional
        The map's axes.
    steps : int
        Grid points per map axis.
    position_um, angular_arcsec : float, optional
        The range sliders.

    Returns
    -------
    PoseIndices, DominantMap
    """
    kw = dict(position_um=position_um, angular_arcsec=angular_arcsec)
    return (indices_at_pose(setup, values, **kw),
            dominant_map(setup, values, axes=axes, steps=steps, **kw))


def time_slider_update(setup: MachineSetup, *, repeat: int = 10, steps: int = GRID_STEPS
                       ) -> float:
    """The minimum wall time (s) of :func:`slider_update` at the default pose (``make bench``).

    Taken over ``repeat`` runs after one warm-up run.

    Parameters
    ----------
    setup : MachineSetup
        The machine.
    repeat : int
        Timed runs.
    steps : int
        Grid points per map axis.

    Returns
    -------
    float
        Seconds.
    """
    slider_update(setup, steps=steps)
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        slider_update(setup, steps=steps)
        best = min(best, time.perf_counter() - t0)
    return float(best)


# ------------------------------------------------------------------------------------------
# Spindle: what a probe layout does to each harmonic
# ------------------------------------------------------------------------------------------

#: Yang et al. 2021's four-point layout (Section 1.3): probes at samples 0, 14, 65, 116 of 128
#: per revolution, and their ``a3``, as notebook 05 declares them.
_YANG = yang2021.Parameters.defaults()
YANG_POSITIONS = tuple(int(v) for v in _YANG["probe_positions"])
YANG_SAMPLES, YANG_A3 = int(_YANG["n_samples"]), float(_YANG["a3"])


def yang_layout_deg() -> np.ndarray:
    """Yang et al. 2021's probe angles in degrees (0, 39.375, 182.8125, 326.25).

    Returns
    -------
    array (4,)
        deg.
    """
    return np.rad2deg(SP.probe_angles(list(YANG_POSITIONS), YANG_SAMPLES))


@dataclass(frozen=True)
class ProbeTransfer:
    """How a probe layout transfers each harmonic of the profile, for both estimators.

    Attributes
    ----------
    angles_deg : array (L,)
        Probe angles (deg).
    harmonics : array of int (K,)
        ``2..max_harmonic`` (the first is the motion's, never separable).
    weights : array (L,) or None
        The weighted method's weights (first probe's 1); None when no weights exist.
    weights_rule : str
        ``"optimal"`` (:func:`~mtaccuracy.spindle.probes.layout_weights`) or ``"eq5"``.
    q_least_squares, q_weighted : arrays (K,)
        Noise amplification ``q_k`` (:func:`~mtaccuracy.spindle.probes.noise_amplification`);
        inf where the harmonic is cancelled.
    gain_weighted : array (K,)
        ``|Lambda_k| / ||a||``: how much of harmonic k the weighted sum keeps (``1 / q_k``; 0:
        cancelled).
    cancelled : array of bool (K,)
        The layout cancels the harmonic: no estimator recovers it
        (:func:`~mtaccuracy.spindle.probes.layout_cancelled`).
    cancelled_by_weights : array of bool (K,)
        The weights cancel it though least squares recovers it.
    amplified_least_squares, amplified_weighted : arrays of bool (K,)
        ``q_k`` above ``amplified_above`` (finite).
    amplified_above : float
        The threshold (notebook 07's default: 3).
    """

    angles_deg: np.ndarray
    harmonics: np.ndarray
    weights: np.ndarray | None
    weights_rule: str
    q_least_squares: np.ndarray
    q_weighted: np.ndarray
    gain_weighted: np.ndarray
    cancelled: np.ndarray
    cancelled_by_weights: np.ndarray
    amplified_least_squares: np.ndarray
    amplified_weighted: np.ndarray
    amplified_above: float


def probe_transfer(angles_deg, *, max_harmonic: int = 20, weights: str = "optimal",
                   a3: float = YANG_A3, amplified_above: float = 3.0) -> ProbeTransfer:
    """What probes at ``angles_deg`` do to harmonics 2..``max_harmonic`` of the profile.

    Least squares: ``q_k^2 = [(A_k^H A_k)^-1]_00`` with ``A_k`` the design of harmonic k and
    the two motion components; the weighted multi-point method (Yang et al. 2021, Eqs. 14, 19):
    ``q_k^2 = sum a_l^2 / |Lambda_k|^2``, ``Lambda_k = sum a_l exp(i k phi_l)``.  Both from
    :func:`mtaccuracy.spindle.probes.noise_amplification`.

    Parameters
    ----------
    angles_deg : array (L,)
        Probe angles (deg), L >= 3, the first defining the x axis.
    max_harmonic : int
        The highest harmonic shown (>= 2).
    weights : {"optimal", "eq5"}
        The weighted method's weights: those minimising the worst ``q_k`` over the harmonics
        the layout does not cancel (:func:`~mtaccuracy.spindle.probes.layout_weights`), or
        Eq. 5 (= Eq. 15) with the free weight ``a3`` (four probes, the first at 0).
    a3 : float
        The free weight of Eq. 5.
    amplified_above : float
        ``q_k`` above this counts as amplified (> 1).

    Returns
    -------
    ProbeTransfer

    Raises
    ------
    ValueError
        With the library's message: fewer than three probes, two at one angle, a layout Eq. 5
        cannot serve.
    """

    phi = np.deg2rad(np.asarray(angles_deg, dtype=float))
    if isinstance(max_harmonic, bool) or not isinstance(max_harmonic, int | np.integer) \
            or max_harmonic < 2:
        raise ValueError(f"max_harmonic must be an integer >= 2, got {max_harmonic!r}")
    if not amplified_above > 1:
        raise ValueError(f"amplified_above must be > 1, got {amplified_above!r}")
    ks = np.arange(2, int(max_harmonic) + 1)
    cancelled_list = SP.layout_cancelled(phi, int(max_harmonic))
    cancelled = np.isin(ks, cancelled_list)
    q_ls = SP.noise_amplification(phi, ks)
    if weights == "optimal":
        keep = ks[~cancelled]
        w = SP.layout_weights(phi, keep) if keep.size else None
    elif weights == "eq5":
        if phi.shape != (4,):
            raise ValueError(f"Eq. 5 weights are for four probes, got {phi.shape[0]}")
        w = SP.full_weights(phi, a3)
    else:
        raise ValueError(f"weights must be 'optimal' or 'eq5', got {weights!r}")
    if w is None:
        q_w = np.full(ks.shape, np.inf)
    else:
        q_w = SP.noise_amplification(phi, ks, weights=w)
    q_w = np.where(cancelled, np.inf, q_w)
    with np.errstate(divide="ignore"):
        gain = np.where(np.isfinite(q_w), 1.0 / q_w, 0.0)
    return ProbeTransfer(
        np.rad2deg(phi), ks, None if w is None else np.asarray(w, dtype=float), weights,
        q_ls, q_w, gain, cancelled, ~cancelled & ~np.isfinite(q_w),
        np.isfinite(q_ls) & (q_ls > amplified_above),
        np.isfinite(q_w) & (q_w > amplified_above), float(amplified_above))


# ------------------------------------------------------------------------------------------
# Thermal: a train/test split of notebook 04
# ------------------------------------------------------------------------------------------

#: Notebook 04's declared defaults: its data, split, inputs, and the selection's settings.
_XU = xu2022.Parameters.defaults()


@dataclass(frozen=True)
class ThermalPrediction:
    """The thermal error of a test experiment predicted from its temperatures.

    Attributes
    ----------
    train : list of int
        Training experiments.
    test : int
        The test experiment.
    kind : str
        ``"mlr"`` or ``"svr"`` (the decoupled model, Xu et al. 2022, Eq. 9).
    inputs : dict
        ``{"k": [...], "b": [...]}``: the sensors of k (absolute temperatures) and b (rises).
    positions_mm : array (P,)
        Target positions (mm).
    time_min : array (n,)
        Time of each test measurement (min).
    measurement : array of int (n,)
        Measurement numbers.
    measured, predicted : arrays (n, P)
        Thermal positioning error (um).
    rmse : float
        Pooled over all positions and measurements (um, :func:`mtaccuracy.thermal.metrics`).
    max_residual : float
        Largest absolute residual (um).
    rmse_uncompensated : float
        RMSE of the measured error itself (no model, the plain baseline), um.
    """

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
    """The thermal measurements and whether they are the paper's reconstruction.

    Parameters
    ----------
    folder : path, optional
        A folder in the schema of ``data/thermal/README.md`` (default: notebook 04's declared
        ``data_dir``, the committed reconstruction); whether it holds the reconstruction is
        decided by content (:func:`mtaccuracy.papers.xu2022.reconstruction_seed`).

    Returns
    -------
    data : ThermalData
    reconstructed : bool
    """
    folder = input_path(_XU["data_dir"] if folder is None else folder, "data_dir")
    return thermal.read_measurements(folder), xu2022.reconstruction_seed(folder) is not None


def thermal_defaults(data, reconstructed: bool) -> dict:
    """Notebook 04's declared split and inputs on ``data``: what the Thermal tab starts with.

    Parameters
    ----------
    data : ThermalData
        The measurements.
    reconstructed : bool
        Whether they are the paper's reconstruction (``inputs="auto"`` then means the paper's
        sensitive points, else the selected ones: :func:`mtaccuracy.papers.xu2022.resolve_inputs`).

    Returns
    -------
    dict
        ``train``, ``test`` (:func:`mtaccuracy.papers.xu2022.resolve_split`) and ``inputs``.
    """
    train, test = xu2022.resolve_split(xu2022.Parameters.stem, data,
                                       train=_XU["train_experiments"], test=_XU["test_experiment"])
    return {"train": train, "test": test,
            "inputs": xu2022.resolve_inputs(_XU["inputs"], reconstructed)}


def thermal_prediction(data, *, train: Sequence[int], test: int, inputs: str = "published",
                       kind: str = "mlr", progress: Callable[[str], None] | None = None
                       ) -> ThermalPrediction:
    """Predict the test experiment's thermal error with the decoupled model (Eq. 9).

    The model is fitted on the training experiments: :func:`mtaccuracy.thermal.evaluate_split`, as
    notebook 04.

    Parameters
    ----------
    data : ThermalData
        All measurements.
    train : sequence of int
        Training experiments (>= 1; >= 2 for the SVR, whose cross-validation leaves one out).
    test : int
        The experiment predicted from its temperatures only.
    inputs : {"published", "selected"}
        The paper's sensitive points (:func:`mtaccuracy.papers.xu2022.published_inputs`), or
        those its procedure (fuzzy clustering, grey relational grade, notebook 04's declared
        ``n_clusters`` and ``rho``) selects on the training experiments.
    kind : {"mlr", "svr"}
        Linear regression, or the grouped SVR (hyperparameters by leave-one-experiment-out).
    progress : callable, optional
        Called with a short text as the fit goes (:func:`~mtaccuracy.thermal.evaluate_split`).

    Returns
    -------
    ThermalPrediction

    Raises
    ------
    ValueError
        For an experiment the data lack, a test experiment also trained on, too few training
        experiments, or a paper's sensor the data lack.
    """

    train = sorted({int(e) for e in train})
    test = int(test)
    absent = sorted(set(train + [test]) - set(data.experiments))
    if absent:
        raise ValueError(f"experiment(s) {absent} are not in the data; they have "
                         f"{data.experiments}")
    if test in train:
        raise ValueError(f"the test experiment {test} is also a training experiment")
    if kind not in ("mlr", "svr"):
        raise ValueError(f"kind must be 'mlr' or 'svr', got {kind!r}")
    need = 2 if kind == "svr" else 1
    if len(train) < need:
        raise ValueError(f"the {kind.upper()} needs at least {need} training experiment"
                         f"{'s (its cross-validation leaves one out)' if need > 1 else ''}, "
                         f"got {train}")
    if inputs == "published":
        sensors = xu2022.published_inputs()
        lacking = sorted({s for v in sensors.values() for s in v} - set(data.sensors))
        if lacking:
            raise ValueError(f"the data lack the paper's sensors {lacking}; use the selected "
                             f"inputs")
    elif inputs == "selected":
        sensors = None
    else:
        raise ValueError(f"inputs must be 'published' or 'selected', got {inputs!r}")
    res = thermal.evaluate_split(data, train=train, test=[test], kinds=(kind,), sensors=sensors,
                                 n_clusters=_XU["n_clusters"], rho=_XU["rho"], progress=progress,
                                 baselines=("uncompensated",))
    name = f"decoupled_{kind}"
    measured, predicted = res.measured, res.predictions[name]
    m = thermal.metrics(measured - predicted)
    te = data.subset(test)
    return ThermalPrediction(
        train, test, kind, {"k": list(res.inputs["k"]), "b": list(res.inputs["b"])},
        np.asarray(data.positions_mm, dtype=float), te.index.time_min.to_numpy(float),
        te.index.measurement.to_numpy(int), measured, predicted, float(m["rmse"]),
        float(m["max_residual"]), float(thermal.metrics(measured)["rmse"]))
