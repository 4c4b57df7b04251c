"""The compendium's side of notebook 06 (a reader's own machine).

The drawing of the machine's chain and the numbers the notebook's conclusion rests on."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

from ..machines.topology import LINEAR, ROTARY, parse_topology

__all__ = ["chain_figure", "conclusion_numbers"]


def chain_figure(machine, topology: str, *, travels: dict, pivots: dict, tool: dict,
                 tool_length_mm: float):
    """The machine's chain, in two panels.

    (a) Its bodies from the workpiece to the tool, each rotary axis with its pivot; (b) the ideal
    tool over the first rotary head axis's travel at the centre of the linear travels, computed
    from the chain with zero errors (blank without one).

    Parameters
    ----------
    machine : ChainMachine
        Built from ``topology`` (:func:`mtaccuracy.machines.chain.iso_machine`).
    topology : str
        The topology string, read from the workpiece to the tool.
    travels, pivots : dict
        As :func:`mtaccuracy.machines.chain.read_axis_table` returns them (mm, rad).
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
    sweep = next((a for a in topo.tool if a in ROTARY), None)  # the first rotary head axis
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


def conclusion_numbers(catalogue, removed, key_shares, *, centred_ratio: float,
                       check_ratio: float, half: float = 0.5) -> list[str]:
    """The lines the notebook prints before its conclusion, so that the markdown states no number.

    The catalogue's counts, the closed form's accuracy, the errors key over at least ``half`` of
    the workspace for each output (then the next four, and how many more are key somewhere), and
    the share of the allowance the sampled check used.

    Parameters
    ----------
    catalogue : DataFrame
        :func:`mtaccuracy.machines.chain.catalogue_table` (column ``kind``: every error that
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
