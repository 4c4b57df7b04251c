"""The compendium's side of notebook 02 (Rong et al.): checks of the sweep parameters, the
ranking precision of the 90 % rule, and the study of the key errors under two defensible
range sets (the paper's Table 2 is lost)."""

from __future__ import annotations

import numpy as np

from .parameters import ParameterError

__all__ = ["check_sweeps", "ranked", "half_widths_from_ranges", "range_path_study"]

#: Decimals at which the total indices are ranked by the 90 % rule and written to the tables.
RANK_DECIMALS = 6


def ranked(st, decimals: int = RANK_DECIMALS) -> np.ndarray:
    """Total indices as the 90 % rule ranks them, and as the tables write them: near-equal
    values merged (:func:`mtaccuracy.sensitivity.merge_ties`, rounding noise), then rounded to
    ``decimals``.  Values equal as written tie, and the rule's stable sort takes them in
    catalogue order, so a reader who sorts the saved table gets the rule's order.

    Errors that enter a component identically (the model's symmetry) have equal indices; a
    Sobol' estimate separates them by sampling noise only (about 1e-10 at a power-of-two
    base sample), which must neither decide the key set nor disagree with the saved table.

    Parameters
    ----------
    st : array (..., D, q)
        Total indices.
    decimals : int
        Rounding (1e-6 by default: far below sampling uncertainty, far above rounding noise).

    Returns
    -------
    array, the shape of ``st`` (``-0.0`` written as ``0``)
    """
    from ..sensitivity import merge_ties

    return np.round(merge_ties(np.asarray(st, dtype=float)), decimals) + 0.0


def half_widths_from_ranges(catalogue, position_mm: float, angular_rad: float) -> np.ndarray:
    """Half-widths (D,) of symmetric ranges of one size per kind: ``position_mm`` for the
    translational errors (positioning, straightness), ``angular_rad`` for every angular one
    (angular error motions and squareness), as Zheng et al. 2024 state theirs (+/-15 um,
    +/-10 arcsec, Section 3.1).

    Parameters
    ----------
    catalogue : sequence of ErrorSpec
        The machine's errors (``machine.catalogue``), each with ``translational``.
    position_mm, angular_rad : float
        The two half-widths (mm, rad), > 0.

    Returns
    -------
    array (D,) in mm and rad
    """
    if not (position_mm > 0 and angular_rad > 0):
        raise ValueError(f"half-widths must be > 0, got {position_mm!r} mm, {angular_rad!r} rad")
    return np.array([position_mm if e.translational else angular_rad for e in catalogue])


def range_path_study(machine, half_a, half_b, ts, *, unit_rows, workspace_mm, tool,
                     threshold: float, outputs=("Ex", "Ey", "Ez")):
    """The 90 % rule and the reduced model for error ranges between two sets: half-widths
    ``half_a**(1 - t) * half_b**t`` (geometric path; t = 0 is set a, t = 1 set b), errors
    uniform on +/- those, the tool tip uniform over the workspace.

    Per t: the key errors from the exact workspace-pooled indices of the linearised model
    (:func:`mtaccuracy.machines.horizontal_3axis.linear_sobol_indices`, ranked by
    :func:`ranked`) per output and their union, and the full and reduced model (non-key errors
    zero) on the same unit-cube rows, mapped to the ranges of that t.  A common factor on all
    ranges changes no count and no ratio; only the millimetres scale.

    Parameters
    ----------
    machine : Horizontal3Axis
    half_a, half_b : arrays (D,)
        Half-widths of the two sets (mm, rad), > 0.
    ts : array (T,)
        Path parameters.
    unit_rows : array (n, D + 3)
        Unit-cube samples: the D errors, then x, y, z.
    workspace_mm : sequence of 3 floats
        Travels of x, y, z (mm); the pose is uniform on [0, travel].
    tool : mapping
        Tool offsets (mm).
    threshold : float
        The rule's share.
    outputs : sequence of 3 str
        Output names.

    Returns
    -------
    DataFrame (T, ...)
        t, n_key per output, n_key (union), simplification_rate, full_maxabs_mm,
        residual_maxabs_mm, residual_relative (max |residual| / max |full|), key_errors.
    """
    import pandas as pd

    from .. import sensitivity as S
    from ..machines import horizontal_3axis as h3

    names, d = list(machine.error_names), machine.n_errors
    ha, hb = (np.asarray(h, dtype=float) for h in (half_a, half_b))
    if ha.shape != (d,) or hb.shape != (d,) or np.any(ha <= 0) or np.any(hb <= 0):
        raise ValueError(f"half-widths must be ({d},) arrays of positive values")
    if np.shape(unit_rows)[1:] != (d + 3,):
        raise ValueError(f"unit_rows must be (n, {d + 3}): the errors, then x, y, z")
    box = dict(zip(("x", "y", "z"), ((0.0, float(v)) for v in workspace_mm), strict=True))
    pose_b = np.array([[0.0, 0.0, 0.0], [float(v) for v in workspace_mm]])
    model = h3.errors_and_pose_model(machine, tool)
    rows = []
    for t in np.asarray(ts, dtype=float):
        h = ha ** (1 - t) * hb ** t
        _, st = h3.linear_sobol_indices(machine, np.vstack([-h, h]), pose=tool, pose_bounds=box)
        sets = S.key_errors_by_output(ranked(st), names, list(outputs), threshold)
        union = S.union_key_set(sets, names)
        x = S.from_unit_uniform(np.asarray(unit_rows), np.hstack([np.vstack([-h, h]), pose_b]))
        full = model(x)
        res = full - model(np.c_[S.zero_non_key(x[:, :d], union, names), x[:, d:]])
        rows.append(dict(t=float(t), **{f"n_key_{o}": ks.n_key for o, ks in sets.items()},
                         n_key=len(union), simplification_rate=S.simplification_rate(len(union), d),
                         full_maxabs_mm=float(np.abs(full).max()),
                         residual_maxabs_mm=float(np.abs(res).max()),
                         residual_relative=float(np.abs(res).max() / np.abs(full).max()),
                         key_errors=" ".join(union)))
    return pd.DataFrame(rows)


def check_sweeps(workspace_mm, tool_offset_mm, sweep_thresholds, tool_lengths_mm, n_plot: int,
                 n_base: int) -> int:
    """Refuse sweep parameters the notebook cannot run (a clear message each); returns the
    number of thresholds of the sweep.  Raises
    :class:`~mtaccuracy.compendium.parameters.ParameterError`."""
    if len(workspace_mm) != 3 or len(tool_offset_mm) != 3:
        raise ParameterError("workspace_mm and tool_offset_mm need three values (x, y, z)")
    if len(sweep_thresholds) != 3 or not 0 < sweep_thresholds[0] <= sweep_thresholds[1] < 1 \
            or sweep_thresholds[2] <= 0:
        raise ParameterError("sweep_thresholds = [first, last, step] with 0 < first <= last < 1, "
                             "step > 0")
    if len(tool_lengths_mm) != 3 or tool_lengths_mm[0] > tool_lengths_mm[1] \
            or tool_lengths_mm[2] <= 0:
        raise ParameterError("tool_lengths_mm = [first, last, step] with first <= last and "
                             "step > 0")
    if int((tool_lengths_mm[1] - tool_lengths_mm[0]) / tool_lengths_mm[2] + 1e-9) + 1 > 200:
        raise ParameterError("tool_lengths_mm gives more than 200 tool lengths (raise the step)")
    if n_plot > n_base:
        raise ParameterError(f"n_plot = {n_plot} must be at most n_base = {n_base}")
    n_sweep = int((sweep_thresholds[1] - sweep_thresholds[0]) / sweep_thresholds[2] + 1e-9) + 1
    if n_sweep > 200:
        raise ParameterError(f"sweep_thresholds gives {n_sweep} thresholds; at most 200 "
                             f"(raise the step)")
    return n_sweep


def tool_length_figure(t_len, tool_study, key_tool, names, outputs, no_effect, n_key_pub: int,
                       threshold: float, published_colour):
    """Key errors against the tool length: the counts per output and their union beside the
    published count, the largest total index of the errors that need an arm (with the RMS
    tool-tip error, dotted), and the key set at every length."""
    import matplotlib.pyplot as plt

    step = t_len[1] - t_len[0] if len(t_len) > 1 else 1.0
    d = len(names)
    fig, axes = plt.subplots(1, 3, figsize=(14, 3.8), gridspec_kw={"width_ratios": [1.1, 1.1, 1.6]})
    for o in outputs:
        axes[0].step(t_len, tool_study[f"n_key_{o}"], where="mid", lw=1, label=o)
    axes[0].step(t_len, tool_study.n_key, where="mid", color="k", lw=2, label="union")
    axes[0].axhline(n_key_pub, color=published_colour, ls="--", lw=1,
                    label=f"published: {n_key_pub}")
    axes[0].set_ylabel("number of key errors")
    axes[0].legend(fontsize=7)
    for s in no_effect:
        axes[1].plot(t_len, tool_study[f"ST_max_{s}"], "-o", ms=3, label=s)
    ax2 = axes[1].twinx()
    ax2.plot(t_len, tool_study.rms_error_mm * 1e3, "k:", lw=1)
    ax2.set_ylabel("RMS tool-tip error (µm), dotted")
    ax2.grid(False)
    axes[1].set_ylabel("largest ST over Ex, Ey, Ez")
    axes[1].set_title("the errors without an arm at length 0\n(ey(x) and ey(y) coincide: both "
                      "pitch the tool, arm = L)", fontsize=8)
    axes[1].legend(fontsize=7)
    for ax in axes[:2]:
        ax.set_xlabel("tool length (mm, along -z)")
    axes[2].imshow(key_tool.T, aspect="auto", cmap="Greens", vmin=0, vmax=1.6,
                   interpolation="nearest",
                   extent=[t_len[0] - step / 2, t_len[-1] + step / 2, d - 0.5, -0.5])
    axes[2].set_yticks(range(d), names, fontsize=6)
    axes[2].set_xlabel("tool length (mm)")
    axes[2].set_title(f"key errors (union, {threshold:.0%} rule): filled = key", fontsize=8)
    axes[2].grid(False)
    fig.suptitle("Key errors vs tool length (tool tip uniform over the workspace; exact "
                 "linearised indices)")
    fig.tight_layout()
    return fig
