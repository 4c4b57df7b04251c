"""Paper code of notebook 08 (a reader's own measurements of their machine; no paper).

The notebook's parameters (:class:`Parameters`: the machine as notebook 06 takes it, declared
once in :class:`.your_machine.MachineInputs`, and the two measurement files), the priors it
assumes, the conversions to the units a reader reads, its figures and their captions
(:data:`FIGURES`).  The maths is :mod:`mtaccuracy.measure`'s.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import param

from .. import sensitivity as S
from .figure import Caption, figures
from .parameters import InputFile, OutputFolder
from .your_machine import MachineInputs

__all__ = ["Parameters", "reader_units", "sobol_weights", "is_shipped_example",
           "positioning_figure", "circle_figure", "FIGURES"]

#: The shipped example files (simulated, ``data/measure/README.md`` states their truth).
EXAMPLE_FOLDER = Path(__file__).resolve().parents[3] / "data" / "measure"


class Parameters(MachineInputs):
    """Notebook 08: your own measurements, the tests that see each error, identification."""

    stem = "08_your_measurements"
    motion_degree = param.Integer(2, bounds=(0, 4),
                                  doc="Legendre degree of the linear axes' error motions")
    sigma_um = param.Number(0.5, bounds=(0.001, 100.0),
                            doc="noise of a simulated length reading (um)")
    shrink = param.Number(100.0, bounds=(1.0, 1e6), inclusive_bounds=(False, True),
                          doc="seen: the tests shrink a direction's prior variance this much")
    n_replicates = param.Integer(500, bounds=(50, 5000),
                                 doc="noisy replicates of the simulated plan (coverage)")
    positioning_file = InputFile("data/measure/positioning_X.csv",
                                 doc="ISO 230-2 file (data/measure/README.md)")
    circle_file = InputFile("data/measure/circle_XY.csv",
                            doc="ISO 230-4 file (data/measure/README.md)")
    output_dir = OutputFolder("figures/08_your_measurements",
                              doc="where figures and tables are written")

    def memory_bytes(self) -> float:
        # the plan's design (1.4k readings x 67 parameters) and the replicates' estimates:
        # 0.3 GB measured at the defaults, a replicate adds 10 kB
        return 5e8 + 1e4 * self.n_replicates


def reader_units(model) -> dict:
    """Each parameter's unit as a reader reads it: um for mm, urad for rad.

    Parameters
    ----------
    model : MotionModel
        The parameters.

    Returns
    -------
    dict of str to str
        Symbol -> ``"um"`` or ``"urad"`` (``units=`` of
        :func:`mtaccuracy.measure.identify.identify`).
    """
    return {n: {"mm": "um", "rad": "urad"}[u] for n, u in zip(model.names, model.units,
                                                            strict=True)}


def sobol_weights(machine, bounds, *, travels: dict, tool_length_mm: float, seed: int,
                  n_poses: int = 500) -> np.ndarray:
    """Each error's importance over the workspace, as notebook 06's atlas measures it.

    The closed-form (linear) Sobol index of each error (``sensitivity.indices_at_poses``,
    errors uniform on ``bounds``) averaged over ``n_poses`` random poses in
    the travels, the largest over the tool tip's Px, Py, Pz: the weights of
    :func:`mtaccuracy.measure.identifiability.next_test` (index a parameter's by
    ``MotionModel.column``).

    Parameters
    ----------
    machine : ChainMachine
        With tool offsets ``tool_x``, ``tool_y``, ``tool_z`` (:func:`.your_machine.read_machine`).
    bounds : (2, n_errors) array_like
        The errors' ranges, mm and rad.
    travels : dict
        Pose name -> (low, high), mm or rad.
    tool_length_mm : float
        The tool tip below the spindle nose, mm.
    seed : int
        Of the random poses.
    n_poses : int
        How many.

    Returns
    -------
    (n_errors,) ndarray
    """
    rng = np.random.default_rng(seed)
    where = {k: rng.uniform(lo, hi, n_poses) for k, (lo, hi) in travels.items()}
    where.update(tool_x=np.zeros(n_poses), tool_y=np.zeros(n_poses),
                 tool_z=np.full(n_poses, -float(tool_length_mm)))
    idx = np.asarray(S.indices_at_poses(machine.jacobian(where),
                                        var=S.uniform_moments(bounds)[1]))   # (P, D, 6)
    return idx[:, :, :3].mean(axis=0).max(axis=1)


def is_shipped_example(path, name: str) -> bool:
    """Whether ``path`` holds the shipped example ``name`` (by content, wherever it lies)."""
    try:
        return Path(path).read_bytes() == (EXAMPLE_FOLDER / name).read_bytes()
    except OSError:
        return False


def positioning_figure(result):
    """An ISO 230-2 test: the mean deviations up and down with their +-2s bands, per target.

    Parameters
    ----------
    result : Iso230_2Result
        :func:`mtaccuracy.measure.iso230_2.evaluate_iso230_2`.

    Returns
    -------
    matplotlib.figure.Figure
    """
    t = result.targets_mm
    fig, ax = plt.subplots(figsize=(7.5, 4))
    for k, (label, style) in enumerate((("approached in + (up)", "o-"),
                                        ("approached in - (down)", "s--"))):
        m, s = result.mean[:, k], result.s[:, k]
        line, = ax.plot(t, m, style, ms=4, label=label)
        ax.fill_between(t, m - 2 * s, m + 2 * s, color=line.get_color(), alpha=0.2, lw=0)
    ax.plot(t, result.mean[:, 2], "k-", lw=1, label="mean bidirectional")
    ax.set_xlabel(f"target position of {result.axis} (mm)")
    ax.set_ylabel("positional deviation (µm)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def circle_figure(data):
    """An ISO 230-4 test: both directions' deviations, on a polar plot and against the angle.

    The polar plot draws each deviation about a ring (twice the deviations' range), to scale.

    Parameters
    ----------
    data : CircleData
        :func:`mtaccuracy.measure.iso230_4.read_iso230_4`.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig = plt.figure(figsize=(11, 4.2))
    ax = fig.add_subplot(1, 2, 1, projection="polar")
    ax2 = fig.add_subplot(1, 2, 2)
    dev = data.deviation_um
    ring = 2.0 * max(np.ptp(dev), 1e-9)
    for run, label, style in ((True, "ccw", "-"), (False, "cw", "--")):
        i = np.flatnonzero(data.ccw == run)
        i = i[np.argsort(np.mod(data.angle_deg[i], 360.0), kind="stable")]
        th = np.deg2rad(np.mod(data.angle_deg[i], 360.0))
        ax.plot(np.append(th, th[0]), np.append(dev[i], dev[i][0]) + ring, style, lw=1,
                label=label)
        ax2.plot(np.rad2deg(th), dev[i], style, lw=1, label=label)
    full = np.linspace(0.0, 2 * np.pi, 361)
    ax.plot(full, np.full(full.size, ring), color="0.55", lw=0.7)
    ax.set_yticks([])
    ax.set_ylim(0, ring + dev.max() * 1.1)
    ax.set_title(f"{data.plane}: deviations about the grey ring, R = {data.radius_mm:g} mm "
                 "(µm, to scale)", fontsize=9)
    ax2.set_xlabel(f"angle from +{data.plane[0]} towards +{data.plane[1]} (°)")
    ax2.set_ylabel("radial deviation (µm)")
    ax2.set_xticks(range(0, 361, 45))
    ax2.legend(fontsize=8)
    fig.tight_layout()
    return fig


FIGURES = figures(
    Caption("test_status", "Figure 1",
            "Which standard test sees which parameter of the machine `{topology}` (error motions "
            "as Legendre polynomials of degree {degree} over the travels, {n_params} parameters; "
            "priors from {ranges_file}): seen (the tests shrink its prior variance at least "
            "{shrink:g}-fold), seen only in a combination with others, or blind. The last column "
            "is the whole plan of {n_tests} tests: rank {rank}, {n_seen} seen, {n_combination} in "
            "combinations, {n_blind} blind. Simulated designs, no measurement.", key=True),
    Caption("simulated_recovery", "Figure 2",
            "A simulated measurement of the whole plan (truth drawn from the priors, seed "
            "{seed}, noise {sigma:g} µm per reading): each seen parameter's estimate minus the "
            "truth, in standard uncertainties; over {n_replicates} noisy replicates the 95 % "
            "intervals covered the truth {coverage:.1%} of the time. Simulated data, not a "
            "measurement."),
    Caption("positioning", "Figure 3",
            "ISO 230-2 test of axis {axis} ({source_name}): mean unidirectional deviations "
            "approached in + and - with their ±2 s bands, and the mean bidirectional deviation. "
            "E = {E:.2f} µm, M = {M:.2f} µm, B = {B:.2f} µm, R = {R:.2f} µm, A = {A:.2f} µm. "
            "{source}"),
    Caption("circle", "Figure 4",
            "ISO 230-4 circular test in {plane} ({source_name}), R = {radius:g} mm at "
            "{feed:g} mm/min, both directions. G = {G_ccw:.2f} µm (ccw), {G_cw:.2f} µm (cw) about "
            "the least-squares centre; H = {H:.2f} µm; squareness {squareness:.1f} ± "
            "{u_squareness:.1f} µrad, scale mismatch {scale_mismatch:.1f} ± {u_scale:.1f} µm/m. "
            "{source}"),
)

#: How a caption names the data behind a figure.
SOURCES = {True: "Simulated data: the shipped example file, not a measurement.",
           False: "Data: the file given, not the shipped example."}
