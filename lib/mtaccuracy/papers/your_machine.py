"""Paper code of notebook 06 (a reader's own machine; no paper).

The drawing of the machine's chain and its caption, the numbers the notebook's conclusion rests
on, the notebook's parameters (:class:`Parameters`) and its figures' captions (:data:`FIGURES`).
"""

from __future__ import annotations

from typing import NamedTuple

import matplotlib.pyplot as plt
import numpy as np
import param

from ..machines import iso, readers
from ..machines.topology import LINEAR, ROTARY, parse_topology
from .figure import Caption, figures
from .parameters import InputFile, NotebookParameters, OutputFolder, ParameterError

__all__ = ["read_machine", "swept_axis", "chain_figure", "chain_caption", "conclusion_numbers"]


class ReaderMachine(NamedTuple):
    """A reader's machine as :func:`read_machine` builds it from the three inputs."""

    machine: object           # ChainMachine
    bounds: np.ndarray        # (2, n_errors) the errors' ranges, mm and rad
    travels: dict             # pose name -> (low, high), mm or rad
    pivots: dict              # rotary axis -> (3,) pivot, mm
    references: dict          # linear axis -> Abbe reference, mm


def read_machine(topology: str, axis_table, ranges_file, *, name: str = "your_machine"
                 ) -> ReaderMachine:
    """A reader's machine from its topology, axis table and ranges file (notebooks 06, 08).

    The axis table is checked against the topology, then the machine is built with its ISO
    230-1 catalogue (:func:`mtaccuracy.machines.iso.iso_machine`, tool offsets ``tool_x``,
    ``tool_y``, ``tool_z``), then the ranges file is checked against that catalogue: each
    refusal names its file and line (:mod:`mtaccuracy.machines.readers`).

    Parameters
    ----------
    topology : str
        The chain from the workpiece to the tool.
    axis_table, ranges_file : str or os.PathLike
        The two files (``data/machines/README.md``).
    name : str
        The machine's name.

    Returns
    -------
    ReaderMachine
        The machine, its errors' ranges, and the axis table's travels, pivots and references.
    """
    travels, pivots, references = readers.read_axis_table(axis_table, topology,
                                                          with_references=True)
    machine = iso.iso_machine(topology, pivots=pivots, travels=travels, references=references,
                              tool_offsets=("tool_x", "tool_y", "tool_z"), name=name)
    return ReaderMachine(machine, readers.read_ranges(ranges_file, machine), travels, pivots,
                         references)


def swept_axis(topology: str) -> str | None:
    """The axis panel (b) of :func:`chain_figure` sweeps: the first rotary axis on the tool side.

    Parameters
    ----------
    topology : str
        The topology string, read from the workpiece to the tool.

    Returns
    -------
    str or None
        ``"B"`` for ``w C b X Y Z B t``; None where no rotary axis carries the tool.
    """
    return next((a for a in parse_topology(topology).tool if a in ROTARY), None)


CHAIN = Caption(
    "chain", "Figure 1",
    "(a) The kinematic chain of the machine, topology `{topology}` ({bodies}): each body rides on "
    "the one towards the bed, each rotary axis with its pivot from the axis table {axis_table}. "
    "(b) The ideal {tool_length:g} mm tool (tip dots) at nine {sweep} angles from {low:g}° to "
    "{high:g}°, linear axes at mid-travel, in the workpiece frame's x-z plane, with the {sweep} "
    "pivot (+). The default inputs (a swivel head B over a rotary table C) are illustrative values "
    "from no paper and no measurement.")
#: :data:`CHAIN` for a machine without a rotary axis on the tool side: panel (b) is blank.
CHAIN_WITHOUT_SWEEP = Caption(
    "chain", "Figure 1",
    "The kinematic chain of the machine, topology `{topology}` ({bodies}): each body rides on the "
    "one towards the bed, each rotary axis with its pivot from the axis table {axis_table}. The "
    "right panel is blank: no rotary axis carries the tool.")


def chain_figure(machine, topology: str, *, travels: dict, pivots: dict, tool: dict,
                 tool_length_mm: float):
    """The machine's chain, in two panels.

    (a) Its bodies from the workpiece to the tool, each rotary axis with its pivot; (b) the ideal
    tool over the first rotary head axis's travel at the centre of the linear travels, computed
    from the chain with zero errors (blank without one).

    Parameters
    ----------
    machine : ChainMachine
        Built from ``topology`` (:func:`mtaccuracy.machines.iso.iso_machine`).
    topology : str
        The topology string, read from the workpiece to the tool.
    travels, pivots : dict
        As :func:`mtaccuracy.machines.readers.read_axis_table` returns them (mm, rad).
    tool : dict
        The tool offsets of every pose (``tool_x``, ``tool_y``, ``tool_z``, mm).
    tool_length_mm : float
        Drawn from the tip back to the spindle nose.

    Returns
    -------
    matplotlib.figure.Figure
    """
    topo = parse_topology(topology)
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(11, 3.6),
                                   gridspec_kw={"width_ratios": [2.2, 1]})
    labels = ["workpiece", *reversed(topo.work), "bed", *topo.tool, "tool"]
    colour = {"workpiece": "#8c564b", "bed": "#7f7f7f", "tool": "#2ca02c"}
    for i, lab in enumerate(labels):
        side = "table side" if lab in topo.work else "head side" if lab in topo.tool else ""
        c = colour.get(lab, "#1f77b4" if lab in topo.tool else "#ff7f0e")
        ax0.add_patch(plt.Rectangle((i - 0.38, -0.3), 0.76, 0.6, fc=c, alpha=0.25, ec=c))
        kind = "linear" if lab in LINEAR else "rotary"
        ax0.text(i, 0, lab if lab in colour else f"{lab}\n{kind}", ha="center", va="center",
                 fontsize=8)
        under = side + (f"\npivot {', '.join(f'{v:g}' for v in pivots[lab])} mm"
                        if lab in pivots else "")
        ax0.text(i, -0.38, under, ha="center", va="top", fontsize=7, color="0.3")
        if i:
            ax0.annotate("", xy=(i - 0.38, 0), xytext=(i - 0.62, 0),
                         arrowprops=dict(arrowstyle="<-" if i <= labels.index("bed") else "->"))
    ax0.set_xlim(-0.6, len(labels) - 0.4)
    ax0.set_ylim(-0.9, 0.6)
    ax0.axis("off")
    ax0.set_title(f"(a) {topology!r}: each body rides on the one towards the bed")
    centre = {a: 0.5 * (lo + hi) for a, (lo, hi) in travels.items()}
    sweep = swept_axis(topology)
    if not sweep:
        ax1.axis("off")
        return fig
    poses = {**{k: np.full(9, v) for k, v in {**centre, **tool}.items()},
             sweep: np.linspace(*travels[sweep], 9),
             **{a: np.zeros(9) for a in topo.work if a in ROTARY}}
    r, t = machine.relative(np.zeros((9, machine.n_errors)), poses, with_errors=False)
    back = t + r[:, :, 2] * tool_length_mm  # the tool: tip to spindle nose
    ax1.plot(np.c_[t[:, 0], back[:, 0]].T, np.c_[t[:, 2], back[:, 2]].T, "-", color="#2ca02c",
             lw=2)
    ax1.plot(t[:, 0], t[:, 2], "o", color="k", ms=3)
    if sweep in pivots:
        ax1.plot(pivots[sweep][0] + centre.get("x", 0), pivots[sweep][2] + centre.get("z", 0),
                 "+", color="r", ms=10, label=f"{sweep} pivot")
        ax1.legend(loc="lower left", fontsize=8)
    ax1.set(aspect="equal", xlabel="x in the workpiece frame (mm)", ylabel="z (mm)",
            title=f"(b) the tool over the {sweep} travel")
    return fig


def chain_caption(topology: str, travels: dict, *, tool_length_mm: float,
                  axis_table: str) -> Caption:
    """The caption of :func:`chain_figure`: :data:`CHAIN` (or :data:`CHAIN_WITHOUT_SWEEP`) filled.

    Parameters
    ----------
    topology : str
        The topology string, read from the workpiece to the tool.
    travels : dict
        As :func:`mtaccuracy.machines.readers.read_axis_table` returns them (mm, rad).
    tool_length_mm : float
        The tool drawn.
    axis_table : str
        The axis table's path, as the parameter gives it.

    Returns
    -------
    Caption
    """
    sweep = swept_axis(topology)
    shown = dict(topology=topology, bodies=parse_topology(topology).describe(),
                 axis_table=axis_table, tool_length=tool_length_mm)
    if sweep is None:
        return CHAIN_WITHOUT_SWEEP.format(**shown)
    low, high = np.rad2deg(travels[sweep])
    return CHAIN.format(**shown, sweep=sweep, low=low, high=high)


def conclusion_numbers(catalogue, removed, key_shares, *, centred_ratio: float,
                       check_ratio: float, half: float = 0.5) -> list[str]:
    """The lines the notebook prints before its conclusion, so that the markdown states no number.

    The catalogue's counts, the closed form's accuracy, the errors key over at least ``half`` of
    the workspace for each output (then the next four, and how many more are key somewhere), and
    the share of the allowance the sampled check used.

    Parameters
    ----------
    catalogue : DataFrame
        :func:`mtaccuracy.machines.readers.catalogue_table` (column ``kind``: every error that
        is not ``squareness`` or ``location`` is an error motion).
    removed : DataFrame
        The removed location errors (column ``symbol``).
    key_shares : DataFrame
        Share of the workspace where each error is key, errors by outputs.
    centred_ratio : float
        Largest centred remainder ratio at the centre of the travels.
    check_ratio : float
        Largest ``|sampled - closed form|`` over what is allowed.
    half : float
        The share above which an error is listed first.

    Returns
    -------
    list of str
    """
    n_sq, n_loc = ((catalogue.kind == k).sum() for k in ("squareness", "location"))
    lines = [f"catalogue: {len(catalogue)} errors ({len(catalogue) - n_sq - n_loc} error motions, "
             f"{n_sq} squareness, {n_loc} location); "
             f"{len(removed)} of {n_loc + len(removed)} location errors "
             f"removed as redundant ({', '.join(removed.symbol)})",
             f"closed form at the centre: the remainder is at most {centred_ratio:.0e} of an "
             f"output's spread, the indices hold to about {2 * centred_ratio:.0e}"]
    for o in key_shares.columns:
        s = key_shares[o][key_shares[o] > 0].sort_values(ascending=False, kind="stable")
        most = ", ".join(f"{k} {v:.0%}" for k, v in s[s >= half].items()) or "none"
        rest = s[s < half]
        nxt = ", ".join(f"{k} {v:.0%}" for k, v in rest.iloc[:4].items()) or "none"
        more = f" and {len(rest) - 4} more" if len(rest) > 4 else ""
        lines.append(f"{o}: key over >= {half:.0%} of the workspace: {most}; next: {nxt}{more}")
    never = [k for k in key_shares.index if not (key_shares.loc[k] > 0).any()]
    lines.append(f"never key: {', '.join(never) or 'none'}")
    lines.append(f"sampled check: the largest difference uses {check_ratio:.2f} of the allowance")
    return lines


class MachineInputs(NotebookParameters):
    """A reader's machine as notebooks 06 and 08 take it: declared once, here."""

    seed = param.Integer(2026, bounds=(0, None), doc="seed of every random draw")
    topology = param.String("w C b X Y Z B t",
                            doc="the machine from the workpiece to the tool (README: Machines)")
    axis_table = InputFile("data/machines/swivel_head_axes.csv",
                           doc="travels and rotary pivots of every axis")
    ranges_file = InputFile("data/machines/swivel_head_ranges.csv",
                            doc="error ranges: symbol, low, high, unit")
    tool_length_mm = param.Number(120.0, bounds=(0.0, 1000.0),
                                  doc="tool tip below the spindle nose along the tool axis (mm)")

    def check(self) -> None:
        # the topology alone; the axis table and the range file are checked against it when read
        try:
            parse_topology(self.topology)
        except (TypeError, ValueError) as exc:
            raise ParameterError(f"{self.stem}: {exc}") from None


class Parameters(MachineInputs):
    """Notebook 06: your own machine's error atlas."""

    stem = "06_your_machine"
    n_atlas = param.Integer(10000, bounds=(100, 200000),
                            doc="random poses in the travels for the workspace atlas")
    key_share = param.Number(0.05, bounds=(0.0, 1.0), inclusive_bounds=(False, False),
                             doc="an error is key where its index is at least this")
    map_steps = param.Integer(37, bounds=(5, 181),
                              doc="grid points per rotary axis of the dominant-error maps")
    n_check_poses = param.Integer(3, bounds=(1, 10),
                                  doc="poses of the sampled check: the centre, then random")
    n_mcs = param.Integer(4096, bounds=(256, 65536),
                          doc="base sample size N of the sampled Sobol' check")
    n_boot = param.Integer(200, bounds=(20, 2000),
                           doc="bootstrap resamples for the sampled indices' half-widths")
    output_dir = OutputFolder("figures/06_your_machine", doc="where figures and tables are written")

    def memory_bytes(self) -> float:
        # the atlas (Jacobians, factor products and indices: 12.7 kB per pose, measured), the
        # maps (the same per grid point), the sampled check (16 kB per base sample, measured)
        return 3e8 + 1.3e4 * self.n_atlas + 1.3e4 * self.map_steps ** 2 + 1.7e4 * self.n_mcs


# --- the chapter's figures, in the order the notebook shows them -----------------------------

FIGURES = figures(
    CHAIN,
    Caption("atlas_dominant_error_map", "Figure 2",
            "The error with the largest closed-form (linear) Sobol index for each output, tool-tip "
            "position Px, Py, Pz and tool-axis direction Vx, Vy, Vz, on a {steps} × {steps} grid "
            "over {a1} ({low1:g}° to {high1:g}°) and {a2} ({low2:g}° to {high2:g}°), linear axes "
            "at the centre of their travels. How many errors dominate each output somewhere on "
            "the grid: {distinct}. Grey: no first-order term ({blank}). Errors uniform on the "
            "ranges of {ranges_file}, which set how much each error weighs."),
    Caption("atlas_key_errors", "Figure 3",
            "The share of {n_atlas:,} random poses in the travels at which each error is key "
            "(closed-form index at least {key_share:g}), per output; only errors key somewhere "
            "are listed ({n_shown} of {n_errors}; never key: {never}). Key everywhere: "
            "{everywhere}. The shares depend on the ranges of {ranges_file}."),
    Caption("sobol_check", "Figure 4",
            "Sampled total Sobol indices of the exact chain (Saltelli, N = {n_mcs}, 95 % bootstrap "
            "half-widths) against the closed form at {poses}: pose 0 at the centre of the "
            "travels ({centre}), any others random; indices above 0.01, errors uniform on the "
            "ranges of {ranges_file}. The largest difference uses {worst:.2f} of its family-wise "
            "95 % allowance: {within}. Outputs with no first-order term ({blank}) have their "
            "closed form set to 0 and are not compared: their points lie on the vertical axis."),
)
