"""Paper code of notebook 02 (Rong et al.): the paper's study on the horizontal machine.

The model of the Sobol' study (errors and tool-tip position as inputs), the exact Sobol indices
of its linearised model (the reference the sampled estimates converge to), the tools of the
tool-length study, the grids of the sweep parameters (one rule for the check and the sweep), the
ranking precision of the 90 % rule, the study of the key errors under two defensible range sets
(the paper's Table 2 is lost), the notebook's parameters (:class:`Parameters`) and its figures'
captions (:data:`FIGURES`).  The machine itself is
:class:`mtaccuracy.machines.horizontal_3axis.Horizontal3Axis`.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pandas as pd
import param

from .. import sensitivity as S
from .figure import Caption, figures
from .parameters import InputFile, NotebookParameters, NumberList, OutputFolder, ParameterError

__all__ = ["sweep_grid", "threshold_grid", "tool_length_grid", "leading_errors", "ranked",
           "half_widths_from_ranges", "range_path_study",
           "linear_sobol_indices", "linear_sobol_indices_batch", "linear_indices_at_poses",
           "errors_and_pose_model", "errors_at_poses_model", "tool_length_offsets",
           "range_bracket_figure", "tool_length_figure"]

#: Decimals at which the total indices are ranked by the 90 % rule and written to the tables.
RANK_DECIMALS = 6


def ranked(st, decimals: int = RANK_DECIMALS) -> np.ndarray:
    """Total indices as the 90 % rule ranks them, and as the tables write them.

    Near-equal values are merged (:func:`mtaccuracy.sensitivity.merge_ties`, rounding noise),
    then rounded to ``decimals``.  Values equal as written tie, and the rule's stable sort takes
    them in catalogue order, so a reader who sorts the saved table gets the rule's order.

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
    return np.round(S.merge_ties(np.asarray(st, dtype=float)), decimals) + 0.0


def half_widths_from_ranges(catalogue, position_mm: float, angular_rad: float) -> np.ndarray:
    """Half-widths (D,) of symmetric ranges of one size per kind of error (translational, angular).

    ``position_mm`` for the translational errors (positioning, straightness), ``angular_rad``
    for every angular one (angular error motions and squareness), as Zheng et al. 2024 state
    theirs (+/-15 um, +/-10 arcsec, Section 3.1).

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
    """The 90 % rule and the reduced model for error ranges between two sets of half-widths.

    Half-widths ``half_a**(1 - t) * half_b**t`` (geometric path; t = 0 is set a, t = 1 set b),
    errors uniform on +/- those, the tool tip uniform over the workspace.
    Per t: the key errors from the exact workspace-pooled indices of the linearised model
    (:func:`linear_sobol_indices`, ranked by :func:`ranked`) per output and their union, and
    the full and reduced model (non-key errors zero) on the same unit-cube rows, mapped to the
    ranges of that t.  A common factor on all ranges changes no count and no ratio; only the
    millimetres scale.

    Parameters
    ----------
    machine : Horizontal3Axis
        The machine whose D errors are studied (its layout and tool convention).
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
    names, d = list(machine.error_names), machine.n_errors
    ha, hb = (np.asarray(h, dtype=float) for h in (half_a, half_b))
    if ha.shape != (d,) or hb.shape != (d,) or np.any(ha <= 0) or np.any(hb <= 0):
        raise ValueError(f"half-widths must be ({d},) arrays of positive values")
    if np.shape(unit_rows)[1:] != (d + 3,):
        raise ValueError(f"unit_rows must be (n, {d + 3}): the errors, then x, y, z")
    box = dict(zip(("x", "y", "z"), ((0.0, float(v)) for v in workspace_mm), strict=True))
    pose_b = np.array([[0.0, 0.0, 0.0], [float(v) for v in workspace_mm]])
    model = errors_and_pose_model(machine, tool)
    rows = []
    for t in np.asarray(ts, dtype=float):
        h = ha ** (1 - t) * hb ** t
        _, st = linear_sobol_indices(machine, np.vstack([-h, h]), pose=tool, pose_bounds=box)
        sets = S.key_errors_by_output(ranked(st), names=names, outputs=list(outputs),
                                      threshold=threshold)
        union = S.union_key_set(sets, names)
        x = S.Inputs.from_bounds(np.hstack([np.vstack([-h, h]), pose_b])).from_unit(
            np.asarray(unit_rows))
        full = model(x)
        res = full - model(np.c_[S.zero_non_key(x[:, :d], union, names), x[:, d:]])
        rows.append(dict(t=float(t), **{f"n_key_{o}": ks.n_key for o, ks in sets.items()},
                         n_key=len(union), simplification_rate=S.simplification_rate(len(union), d),
                         full_maxabs_mm=float(np.abs(full).max()),
                         residual_maxabs_mm=float(np.abs(res).max()),
                         residual_relative=float(np.abs(res).max() / np.abs(full).max()),
                         key_errors=" ".join(union)))
    return pd.DataFrame(rows)


#: At most this many thresholds in the threshold sweep, and tool lengths in the tool study.
MAX_SWEEP = 200


def sweep_grid(first: float, last: float, step: float, *, what: str, unit: str,
               decimals: int) -> np.ndarray:
    """The values ``first, first + step, ...`` up to ``last`` of a sweep parameter.

    The one rule of the sweeps of notebook 02: :meth:`Parameters.check` refuses what it refuses,
    and the notebook sweeps what it returns.

    Parameters
    ----------
    first, last, step : float
        The sweep: ``first <= last``, ``step > 0``.
    what : str
        The parameter's name, for the message (``tool_lengths_mm``).
    unit : str
        What the values are, plural, for the message (``tool lengths``).
    decimals : int
        The values are rounded to this many decimals (no ``0.30000000000000004``).

    Returns
    -------
    array (n,)
        ``n = floor((last - first) / step) + 1`` values (a value within 1e-9 of a step past
        ``last`` counts as ``last``), none beyond ``last``.

    Raises
    ------
    ValueError
        If ``first > last``, ``step <= 0`` or there would be more than :data:`MAX_SWEEP` values.
    """
    if not (first <= last and step > 0):
        raise ValueError(f"{what} = [first, last, step] with first <= last and step > 0")
    n = int((last - first) / step + 1e-9) + 1
    if n > MAX_SWEEP:
        raise ValueError(f"{what} gives {n} {unit}; at most {MAX_SWEEP} (raise the step)")
    return np.round(np.arange(first, last + step / 2, step)[:n], decimals)


def threshold_grid(sweep_thresholds) -> np.ndarray:
    """The thresholds of the notebook's threshold sweep (``[first, last, step]``).

    Parameters
    ----------
    sweep_thresholds : sequence of 3 floats
        ``[first, last, step]`` with ``0 < first <= last < 1`` and ``step > 0``.

    Returns
    -------
    array (n,)
        :func:`sweep_grid`, rounded to 1e-10.

    Raises
    ------
    ValueError
        Naming the rule broken: the order, a share outside (0, 1), or more than
        :data:`MAX_SWEEP` thresholds.
    """
    first, last, step = sweep_thresholds
    if not 0 < first <= last < 1:
        raise ValueError("sweep_thresholds = [first, last, step] with 0 < first <= last < 1, "
                         "step > 0")
    return sweep_grid(first, last, step, what="sweep_thresholds", unit="thresholds", decimals=10)


def tool_length_grid(tool_lengths_mm) -> np.ndarray:
    """The tool lengths (mm) of the notebook's tool-length study (``[first, last, step]``).

    Parameters
    ----------
    tool_lengths_mm : sequence of 3 floats
        ``[first, last, step]`` in mm with ``first <= last`` and ``step > 0``.

    Returns
    -------
    array (n,)
        :func:`sweep_grid`, rounded to 1e-9 mm.

    Raises
    ------
    ValueError
        Naming the rule broken: the order, the step, or more than :data:`MAX_SWEEP` lengths.
    """
    first, last, step = tool_lengths_mm
    return sweep_grid(first, last, step, what="tool_lengths_mm", unit="tool lengths", decimals=9)


def leading_errors(sob: pd.DataFrame, output: str, n: int = 3) -> str:
    """The errors with the largest total index of one output, in words (for a caption).

    The ``n`` largest, and any tied with the ``n``-th; consecutive errors of one kind are
    named together: ``"the angular errors ez(z), ex(z) (ST 0.57, 0.29), then the straightness
    errors dy(x), dy(z) (ST 0.054, 0.054)"``.

    Parameters
    ----------
    sob : DataFrame
        The table of Figs. 2-4: ``output``, ``symbol``, ``kind`` and ``ST`` (as ranked,
        :func:`ranked`), the errors in catalogue order.
    output : str
        ``Ex``, ``Ey`` or ``Ez``.
    n : int
        How many errors at least.

    Returns
    -------
    str
    """
    d = sob[sob.output == output].sort_values("ST", ascending=False, kind="stable")
    d = d[d.ST >= d.ST.iloc[min(n, len(d)) - 1]]
    groups, parts = [], []
    for kind, symbol, st in zip(d.kind, d.symbol, d.ST, strict=True):
        if groups and groups[-1][0] == kind:
            groups[-1][1].append((symbol, st))
        else:
            groups.append((kind, [(symbol, st)]))
    for kind, rows in groups:
        plural = "s" if len(rows) > 1 else ""
        parts.append(f"the {kind} error{plural} {', '.join(s for s, _ in rows)} "
                     f"(ST {', '.join(f'{v:.2g}' for _, v in rows)})")
    return ", then ".join(parts)


RANGE_BRACKET = Caption(
    "fig_range_bracket", "Beyond the paper",
    "Key errors and the reduced model between two defensible error-range sets, since the paper's "
    "Table 2 is lost: half-widths h_a^(1−t) h_b^t, with t = 0 the borrowed ranges (±"
    "{range_factor:g} × the acceptance values in {ranges_file}; by default Guo's GB/T 20957.2 "
    "values) and t = 1 the ranges the same group states in Zheng et al. 2024 ({zheng}). Exact "
    "linearised indices, tool tip uniform over the workspace, {threshold:g} % rule; the reduced "
    "model is evaluated on the {n_base} rows of Figs. 5-7. Left: key errors per component and "
    "their union ({n_min} to {n_max}; dots mark the two sourced sets), with the published "
    "{n_key_pub} dashed and the {n_kept_by_rate} implied by the published {rate_pub:g} % dotted. "
    "Right: max |residual| / max |full model| (%), with the paper's {residual_pub:g} / "
    "{full_pub:g} mm dashed and its text's {residual_pct} % dotted. Only the two ends are "
    "sourced.", key=True)


def range_bracket_figure(path, *, outputs, n_key_pub: int, n_kept_by_rate: int, rate_pub: float,
                         residual_mm_pub: float, full_mm_pub: float, residual_pct_text,
                         threshold: float, published_colour: str, reproduced_colour: str):
    """The figure of the key errors between two range sets (notebook 02, Section 8).

    Two panels along the path of :func:`range_path_study`: the counts per output and their
    union (the two sourced sets, its first and last rows, marked and annotated) beside the
    published count and the count the published rate implies; and the relative residual of
    the reduced model beside the published ratio (``residual_mm_pub / full_mm_pub``) and the
    text's percentage.

    Parameters
    ----------
    path : DataFrame (T, ...)
        :func:`range_path_study`'s table: ``t``, ``n_key_<output>``, ``n_key`` and
        ``residual_relative`` (a ratio).
    outputs : list of str
        The output names (``Ex Ey Ez``).
    n_key_pub : int
        The published number of key errors.
    n_kept_by_rate : int
        The number of key errors the published simplification rate implies.
    rate_pub : float
        The published simplification rate (%).
    residual_mm_pub : float
        The published bound of the reduced model's residual (mm).
    full_mm_pub : float
        The published largest absolute full-model prediction (mm).
    residual_pct_text : str or float
        The text's bound of the relative residual (%), drawn as printed.
    threshold : float
        The share of the 90 % rule (title).
    published_colour, reproduced_colour : str
        Colours of the published values and of the two sourced sets.

    Returns
    -------
    matplotlib Figure
    """
    import matplotlib.pyplot as plt  # the compendium extra, an optional heavy dependency

    ends = path.iloc[[0, -1]]
    fig, axes = plt.subplots(1, 2, figsize=(12, 3.8))
    for o in outputs:
        axes[0].step(path.t, path[f"n_key_{o}"], where="mid", lw=1, label=o)
    axes[0].step(path.t, path.n_key, where="mid", color="k", lw=2, label="union")
    axes[0].plot(ends.t, ends.n_key, "o", ms=8, color=reproduced_colour,
                 label="the two sourced sets")
    for t, n in zip(ends.t, ends.n_key, strict=True):
        axes[0].annotate(f"{n}", (t, n), textcoords="offset points", xytext=(8 - 22 * t, 4))
    axes[0].axhline(n_key_pub, color=published_colour, ls="--", lw=1,
                    label=f"published: {n_key_pub}")
    axes[0].axhline(n_kept_by_rate, color=published_colour, ls=":", lw=1,
                    label=f"implied by the published {rate_pub:g} %: {n_kept_by_rate}")
    axes[0].set_ylabel("number of key errors")
    axes[1].plot(path.t, 100 * path.residual_relative, "-o", ms=3, color="k", label="ours")
    axes[1].axhline(100 * (residual_mm_pub / full_mm_pub), color=published_colour, ls="--", lw=1,
                    label=f"published {residual_mm_pub:g} / {full_mm_pub:g} mm")
    axes[1].axhline(float(residual_pct_text), color=published_colour, ls=":", lw=1,
                    label=f"text: within {residual_pct_text} %")
    axes[1].set_ylabel("max |residual| / max |full model| (%)")
    for ax in axes:
        ax.set_xlabel("t: 0 = borrowed ranges (GB/T 20957.2), 1 = Zheng 2024's (±15 µm, ±10″)")
        ax.legend(fontsize=7)
    fig.suptitle(f"Key errors ({threshold:.0%} rule) and reduced-model residual between two "
                 "defensible range sets (tool tip uniform over the workspace)")
    fig.tight_layout()
    return fig


TOOL_LENGTH = Caption(
    "fig_tool_offset_key_errors", "Beyond the paper",
    "Key errors against the tool length, {first:g} to {last:g} mm in steps of {step:g} mm along "
    "−z (the horizontal spindle), tool tip uniform over the workspace, exact linearised indices. "
    "Left: the number of key errors per component and their union ({n_min} to {n_max}; the "
    "published {n_key_pub}, dashed, {published_at}). Middle: the largest total index of the "
    "{n_no_effect} errors that have no Abbe arm at length 0 (ey(x) and ey(y) coincide), with the "
    "RMS tool-tip error (µm, dotted, right axis). Right: which errors are key (filled) at each "
    "length.")


def tool_length_figure(t_len, tool_study, key_tool, *, names, outputs, no_effect,
                       n_key_pub: int, threshold: float, published_colour):
    """The figure of the key errors against the tool length (notebook 02, Section 8).

    Three panels: the counts per output and their union beside the published count, the
    largest total index of the errors that need an arm (with the RMS tool-tip error, dotted),
    and the key set at every length.

    Parameters
    ----------
    t_len : array (T,)
        Tool lengths (mm), evenly spaced.
    tool_study : DataFrame (T, ...)
        The notebook's table: ``n_key_<output>``, ``n_key``, ``rms_error_mm`` and
        ``ST_max_<symbol>`` of every symbol of ``no_effect``.
    key_tool : array (T, D)
        1 where an error is key at that length (union), else 0.
    names : list of str
        The D error symbols.
    outputs : list of str
        The output names (``Ex Ey Ez``).
    no_effect : list of str
        The errors without an arm at length 0.
    n_key_pub : int
        The published number of key errors.
    threshold : float
        The share of the 90 % rule (titles).
    published_colour : str
        Colour of the published values.

    Returns
    -------
    matplotlib Figure
    """
    import matplotlib.pyplot as plt  # the compendium extra, an optional heavy dependency

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


def linear_sobol_indices(machine, bounds, *, pose: Mapping | None = None,
                         pose_bounds: Mapping | None = None, components: int = 3
                         ) -> tuple[np.ndarray, np.ndarray]:
    """Exact Sobol indices (S1, ST), each (21, components), of the *first-order* model.

    Errors are independent uniforms on ``bounds`` (2, 21).  Either one ``pose`` (a mapping of
    scalars; then S1 = ST), or ``pose_bounds`` mapping some pose names to ``(low, high)``: those
    coordinates are uniform in the box (the others fixed by ``pose``) and independent of the
    errors.  The first-order coefficients are affine in the pose, so the pose expectations of
    their squares are exact with 2-point Gauss-Legendre quadrature per coordinate.  This is the
    reference the Monte Carlo (Saltelli) estimates converge to, up to the second-order terms of
    the full model (about 1e-4 of the error here).  Errors that enter identically (same
    coefficients, same range) get bitwise-equal indices.  One case of
    :func:`linear_sobol_indices_batch`.

    Parameters
    ----------
    machine : Horizontal3Axis
        The machine; its ``jacobian`` gives the coefficients.
    bounds : array (2, 21)
        Uniform error ranges (mm, rad).
    pose : mapping, optional
        Fixed pose coordinates (mm), scalars: axes not in ``pose_bounds`` and tool offsets.
    pose_bounds : mapping, optional
        Pose name -> (low, high) in mm: that coordinate uniform on the interval.
    components : int
        Output rows kept (3: the position error Ex, Ey, Ez; 6: with the orientation).

    Returns
    -------
    s1, st : arrays (21, components)

    Raises
    ------
    ValueError
        If a value of ``pose`` is not a scalar (use :func:`linear_sobol_indices_batch`).
    """
    base = {k: np.atleast_1d(np.asarray(v, dtype=float)) for k, v in (pose or {}).items()}
    if any(v.shape != (1,) for v in base.values()):
        raise ValueError("linear_sobol_indices takes one pose (scalars); "
                         "use linear_sobol_indices_batch for many")
    s1, st, _ = linear_sobol_indices_batch(machine, bounds, poses=base, pose_bounds=pose_bounds,
                                           components=components)
    return s1[0], st[0]


def linear_sobol_indices_batch(machine, bounds, *, poses: Mapping | None = None,
                               pose_bounds: Mapping | None = None, components: int = 3
                               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`linear_sobol_indices` for T cases at once (e.g. T tool lengths), with the variance.

    ``poses`` maps pose names to scalars or (T,) arrays, ``pose_bounds`` as there (the same box
    for every case).  All from one batched Jacobian over the T x 2^k quadrature poses.

    Parameters
    ----------
    machine : Horizontal3Axis
        The machine; its ``jacobian`` gives the coefficients.
    bounds : array (2, 21)
        Uniform error ranges (mm, rad).
    poses : mapping, optional
        Pose name -> scalar or (T,) array (mm): axes not in ``pose_bounds`` and tool offsets.
    pose_bounds : mapping, optional
        Pose name -> (low, high) in mm: that coordinate uniform on the interval.
    components : int
        Output rows kept (3: the position error Ex, Ey, Ez; 6: with the orientation).

    Returns
    -------
    s1, st : arrays (T, 21, components)
    variance : array (T, components)
        The output variance in mm^2, pooled over the box.
    """
    mean, var = S.uniform_moments(bounds, machine.n_errors)
    return S.pose_box_indices(machine.jacobian, mean=mean, var=var, poses=poses,
                              pose_bounds=pose_bounds, components=components, nodes=2,
                              names=machine.axes + machine.tool_offsets, required=machine.axes)


def linear_indices_at_poses(machine, bounds, *, poses: Mapping, components: int = 3
                            ) -> np.ndarray:
    """Exact Sobol indices (S1 = ST) of the first-order model at each of P fixed poses.

    The same numbers as :func:`linear_sobol_indices` with ``pose=`` one at a time, in one
    batched call.  A component with no variance at a pose gets zeros.

    Parameters
    ----------
    machine : Horizontal3Axis
        The machine; its ``jacobian`` gives the coefficients.
    bounds : array (2, 21)
        Uniform error ranges (mm, rad).
    poses : mapping
        Pose name -> scalar or (P,) array (mm): the axes and, optionally, tool offsets.
    components : int
        Output rows kept (3: the position error Ex, Ey, Ez; 6: with the orientation).

    Returns
    -------
    array (P, 21, components)
    """
    _, var = S.uniform_moments(bounds, machine.n_errors)
    return S.indices_at_poses(machine.jacobian(poses)[:, :components], var=var)


def tool_length_offsets(tool_lengths, base=(0.0, 0.0, 0.0)) -> dict[str, np.ndarray]:
    """Tool offsets (``tool_x, tool_y, tool_z``, (T,) arrays, mm) of tools of the given lengths.

    The notebook's tool-length study (its Section 8; the paper states no tool): on the
    horizontal spindle the tip sits ``length`` mm from the carriages' reference point towards
    the workpiece, i.e. along -z (ISO 841: +z points from the workpiece to the tool), on top of
    the ``base`` offsets.

    Parameters
    ----------
    tool_lengths : array (T,)
        Tool lengths (mm, >= 0).
    base : sequence of 3 floats
        Offsets added (mm): the tool tip of a tool of length 0 (``tool_offset_mm``).

    Returns
    -------
    dict of str to array (T,)
        ``tool_x``, ``tool_y``, ``tool_z`` (mm), a pose mapping of
        :class:`~mtaccuracy.machines.horizontal_3axis.Horizontal3Axis`.

    Raises
    ------
    ValueError
        If a length is negative or not finite, or ``tool_lengths`` is not one-dimensional.
    """
    lengths = np.atleast_1d(np.asarray(tool_lengths, dtype=float))
    if lengths.ndim != 1 or np.any(lengths < 0) or not np.all(np.isfinite(lengths)):
        raise ValueError(f"tool lengths must be finite and >= 0, got {tool_lengths!r}")
    bx, by, bz = (float(v) for v in base)
    return {"tool_x": np.full(lengths.shape, bx), "tool_y": np.full(lengths.shape, by),
            "tool_z": bz - lengths}


def errors_and_pose_model(machine, tool: Mapping):
    """The model of Rong et al.'s Sobol' study: errors and tool-tip position as inputs.

    Parameters
    ----------
    machine : Horizontal3Axis
        The machine (D errors).
    tool : mapping
        Tool offsets ``{name: value}`` (mm), the same for every run.

    Returns
    -------
    callable
        ``model(X)``: ``X`` (m, D + 3), the D errors (mm, rad) then the pose x, y, z (mm), to
        the tool-tip position error ``Ex, Ey, Ez`` (m, 3) in mm.
    """
    d = machine.n_errors

    def model(x):
        return machine.position_error(x[:, :d], dict(x=x[:, d], y=x[:, d + 1], z=x[:, d + 2],
                                                     **tool))
    return model


def errors_at_poses_model(machine, poses_xyz, tool: Mapping):
    """The model of the errors alone, each row at its own pose (the poses of a design kept).

    Parameters
    ----------
    machine : Horizontal3Axis
        The machine (D errors).
    poses_xyz : array (m, 3)
        The pose x, y, z (mm) of each row.
    tool : mapping
        Tool offsets (mm).

    Returns
    -------
    callable
        ``model(E)``: errors ``E`` (m, D) to ``Ex, Ey, Ez`` (m, 3) in mm.
    """
    full = errors_and_pose_model(machine, tool)
    poses_xyz = np.asarray(poses_xyz, dtype=float)

    def model(e):
        return full(np.c_[e, poses_xyz])
    return model


class Parameters(NotebookParameters):
    """Notebook 02: Rong et al., Sobol' indices of 21 errors and the 90 % rule."""

    stem = "02_rong_sobol_21_errors"
    seed = param.Integer(2022, bounds=(0, None), doc="seed of every random draw")
    # N(D + 5) model runs; memory and time grow as N (2^17 takes minutes and about 3 GB); a
    # size that is not a power of 2 is allowed (scipy's balance warning is then reported)
    n_base = param.Integer(8192, bounds=(64, 131072),
                           doc="base sample size N of the Saltelli design (paper: 10000)")
    n_boot = param.Integer(500, bounds=(20, 10000),
                           doc="bootstrap resamples (95 % intervals, key-set stability)")
    layout = param.Selector(default="z/xy", objects=["z/xy", "x/zy", "zx/y", "xz/y"],
                            doc="machine layout: workpiece axes/tool axes, from the bed out")
    ranges_file = InputFile("data/rong/error_ranges.csv",
                            doc="acceptance band (low, high, unit) of each error")
    range_factor = param.Number(2.0, bounds=(0.0, 100.0), inclusive_bounds=(False, True),
                                doc="errors uniform on +/- this x acceptance value (paper: 2)")
    workspace_mm = NumberList([700.0, 600.0, 500.0], item_type=float, bounds=(3, 3),
                              item_bounds=(0.0, 5000.0), item_inclusive=(False, True),
                              doc="travel of x, y, z in mm (paper: 700 x 600 x 500)")
    tool_offset_mm = NumberList([0.0, 0.0, 0.0], item_type=float, bounds=(3, 3),
                                item_bounds=(-1000.0, 1000.0),
                                doc="tool tip from the carriages' reference point (mm)")
    threshold = param.Number(0.9, bounds=(0.0, 1.0), inclusive_bounds=(False, False),
                             doc="key errors: smallest top set above this share (paper: 0.9)")
    tie_tol = param.Number(0.1, bounds=(0.0, 1.0), inclusive_bounds=(True, False),
                           doc="variant: also keep errors within this of the last one kept")
    sweep_thresholds = NumberList([0.8, 0.99, 0.01], item_type=float, bounds=(3, 3),
                                  item_bounds=(0.0, 1.0), item_inclusive=(False, False),
                                  doc="first, last and step of the threshold sweep")
    # along the horizontal spindle towards the workpiece, on top of tool_offset_mm
    tool_lengths_mm = NumberList([0.0, 300.0, 25.0], item_type=float, bounds=(3, 3),
                                 item_bounds=(0.0, 1000.0),
                                 doc="first, last and step of the tool lengths (mm)")
    grid_points = param.Integer(5, bounds=(2, 20),
                                doc="poses per axis of the single-pose grid")
    n_plot = param.Integer(150, bounds=(10, 2000),
                           doc="samples drawn as lines in Figs. 5-7, at most n_base")
    salib_check = param.Boolean(True, doc="also run SALib's own sample/analyze as a check")
    output_dir = OutputFolder("figures/02_rong_sobol_21_errors",
                              doc="where figures and tables are written")

    def memory_bytes(self) -> float:
        # measured 0.44 GB at the defaults and 0.74 GB at n_base = 32768 (12 kB per base
        # sample: Saltelli outputs, bootstrap terms, SALib's design and resamples)
        return 4e8 + 20000 * self.n_base + 1e4 * self.n_boot + 1e4 * self.grid_points ** 3

    def check(self) -> None:
        if self.n_plot > self.n_base:
            raise ParameterError(f"{self.stem}: n_plot = {self.n_plot} must be at most n_base = "
                                 f"{self.n_base}")
        try:
            threshold_grid(self.sweep_thresholds)
            tool_length_grid(self.tool_lengths_mm)
        except ValueError as exc:
            raise ParameterError(f"{self.stem}: {exc}") from None


# --- the chapter's figures, in the paper's order ---------------------------------------------

FIGURES = figures(
    Caption("fig02_ex_sobol_indices", "Fig. 2",
            "First-order (S1) and total (ST) Sobol indices of the 21 geometric errors for the "
            "tool-tip error Ex of the horizontal machining centre (layout {layout}, tool offset "
            "{tool} mm), tool tip uniform over the {workspace} mm workspace; N = {n_base}, bars "
            "95 % bootstrap intervals, black ticks the exact linearised indices. Errors uniform "
            "on ±{range_factor:g} × the acceptance values in {ranges_file} (by default borrowed "
            "from Guo et al. 2016: the paper's Table 2 is lost). Largest: {leading}. The paper's "
            "figure is lost too: nothing published is drawn."),
    Caption("fig03_ey_sobol_indices", "Fig. 3",
            "As Fig. 2, for Ey: S1 and ST of the 21 errors with 95 % bootstrap intervals and the "
            "exact indices of the linearised model, tool tip uniform over the workspace, N = "
            "{n_base}, the error ranges of Fig. 2. Largest: {leading}. The paper's figure is lost "
            "in the extracted text, so no published values are shown."),
    Caption("fig04_ez_sobol_indices", "Fig. 4",
            "As Fig. 2, for Ez: S1 and ST of the 21 errors with 95 % bootstrap intervals and the "
            "exact indices of the linearised model, tool tip uniform over the workspace, N = "
            "{n_base}, the error ranges of Fig. 2. Largest: {leading}; ST exceeds S1 for an "
            "angular error whose Abbe arm changes with the pose. The paper's figure is lost in "
            "the extracted text, so no published values are shown."),
    Caption("fig05_ex_prediction", "Fig. 5",
            "Full model against the reduced model that keeps only the {n_key} key errors of the "
            "{threshold:g} % rule (others set to zero), for Ex on the same {n_base} samples (tool "
            "tip uniform over the workspace, the error ranges of Fig. 2). Left: the first "
            "{n_plot} samples. Middle: the residual, full minus reduced, of every sample, "
            "published band ±{band} mm dashed. Right: reduced against full. The residual stays "
            "within ±{residual} mm on a full model spanning {low} to {high} mm (paper: {low_pub} "
            "to {high_pub} mm), i.e. {relative:.0f} % of the largest |full model| (paper: "
            "{relative_pub:.0f} %). The notebook's Section 8 "
            "(the range-bracket figure) computes that ratio with the ranges of Zheng et al. 2024 "
            "and between the two range sets."),
    Caption("fig06_ey_prediction", "Fig. 6",
            "As Fig. 5, for Ey: the full model against the reduced model with {n_key} key errors "
            "on the same {n_base} samples (first {n_plot} samples, the residual of every sample "
            "against the published band ±{band} mm, and reduced against full). The residual stays "
            "within ±{residual} mm on a full model of {low} to {high} mm ({relative:.0f} % of its "
            "largest absolute value; paper: {relative_pub:.0f} %). A common factor on the ranges "
            "would scale both, not their ratio."),
    Caption("fig07_ez_prediction", "Fig. 7",
            "As Fig. 5, for Ez: the full model against the reduced model with {n_key} key errors "
            "on the same {n_base} samples (first {n_plot} samples, the residual of every sample "
            "against the published band ±{band} mm, and reduced against full). The residual stays "
            "within ±{residual} mm on a full model of {low} to {high} mm ({relative:.0f} % of its "
            "largest absolute value; paper: {relative_pub:.0f} %)."),
    Caption("fig_threshold_sweep", "Beyond the paper",
            "The reduced model as the key-error threshold runs from {first:g} % to {last:g} % in "
            "steps of {step:g} %, the key sets recomputed from the same total indices and "
            "evaluated on the same samples. Left: the largest |residual| (µm) of Ex, Ey, Ez. "
            "Middle: RMS of the residual over RMS of the full model, √(1 − threshold) dashed. "
            "Right: the number of key errors (union over the components), the published "
            "{n_key_pub} dashed, the rule's {threshold:g} % dotted. Fewer key errors cost "
            "accuracy step by step; {n_key_pub} appear {published_at}."),
    Caption("fig_pose_dependence", "Beyond the paper",
            "Key errors pose by pose instead of pooled over the workspace: at each of the "
            "{n_poses} poses of a {g} × {g} × {g} grid over the workspace, the exact linearised "
            "indices and the {threshold:g} % rule give a key set. Left: the share of the poses at "
            "which each error is key for Ex, Ey, Ez. Right: histogram of the number of key errors "
            "(union) per pose, {n_min} to {n_max}, with the workspace-pooled {n_pooled} and the "
            "published {n_key_pub} marked; {n_key_pub} occurs at {published_share:.0f} % of the "
            "poses."),
    TOOL_LENGTH,
    RANGE_BRACKET,
)
