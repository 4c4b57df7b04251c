"""The compendium's side of notebook 02 (Rong et al.): checks of the sweep parameters."""

from __future__ import annotations

__all__ = ["check_sweeps"]


def check_sweeps(workspace_mm, tool_offset_mm, sweep_thresholds, tool_lengths_mm, n_plot: int,
                 n_base: int) -> int:
    """Refuse sweep parameters the notebook cannot run (a clear message each); returns the
    number of thresholds of the sweep."""
    if len(workspace_mm) != 3 or len(tool_offset_mm) != 3:
        raise ValueError("workspace_mm and tool_offset_mm need three values (x, y, z)")
    if len(sweep_thresholds) != 3 or not 0 < sweep_thresholds[0] <= sweep_thresholds[1] < 1 \
            or sweep_thresholds[2] <= 0:
        raise ValueError("sweep_thresholds = [first, last, step] with 0 < first <= last < 1, "
                         "step > 0")
    if len(tool_lengths_mm) != 3 or tool_lengths_mm[0] > tool_lengths_mm[1] \
            or tool_lengths_mm[2] <= 0:
        raise ValueError("tool_lengths_mm = [first, last, step] with first <= last and step > 0")
    if int((tool_lengths_mm[1] - tool_lengths_mm[0]) / tool_lengths_mm[2] + 1e-9) + 1 > 200:
        raise ValueError("tool_lengths_mm gives more than 200 tool lengths (raise the step)")
    if n_plot > n_base:
        raise ValueError(f"n_plot = {n_plot} must be at most n_base = {n_base}")
    n_sweep = int((sweep_thresholds[1] - sweep_thresholds[0]) / sweep_thresholds[2] + 1e-9) + 1
    if n_sweep > 200:
        raise ValueError(f"sweep_thresholds gives {n_sweep} thresholds; at most 200 (raise the "
                         f"step)")
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
