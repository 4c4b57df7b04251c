"""Notebook 07: a reader's own spindle probe file, separated and evaluated.

The separation and the evaluation are :mod:`mtaccuracy.spindle` (``probes``, ``errormotion``) and
:mod:`mtaccuracy.roundness`; this module holds what serves the chapter: recognising the shipped
simulated example by its content (:func:`shipped_example`), the captions of its figures
(:data:`FIGURES`, filled by the run with what it read and computed) and the notebook's
declaration of its parameters (:class:`Parameters`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import param

from ..spindle import example
from .figure import Caption, figures
from .parameters import InputFile, NotebookParameters, NumberList, OutputFolder

__all__ = ["profile_caption_fields", "shipped_example"]

#: ``data/spindle/`` of the repository this library was imported from: the shipped simulated
#: example (:func:`mtaccuracy.spindle.example.write_example`), its truth and its record.
EXAMPLE_FOLDER = Path(__file__).resolve().parents[3] / "data" / "spindle"

#: The last sentence of every caption: where the data come from.
SOURCES = {True: "Simulated data: the shipped example file, not a measurement.",
           False: "Data: the probe file given, not the shipped example."}

#: The centres of the ISO 230-7 polar plots and values, as a caption names them.
CENTRES = {"LSC": "least-squares centre", "MRS": "minimum radial separation centre"}


def shipped_example(path, *, folder=EXAMPLE_FOLDER, on_read=None):
    """The truth the shipped example was built from, when ``path`` holds the example's content.

    Recognised by content, whatever the file's name or place: its SHA-256 against the one
    recorded in the folder's ``provenance.json``
    (:func:`mtaccuracy.spindle.example.match_example`).

    Parameters
    ----------
    path : str or Path
        The probe file read.
    folder : str or Path
        The folder of the shipped example, its truth and its record (default
        :data:`EXAMPLE_FOLDER`).
    on_read : callable, optional
        Called with the truth file's path once it is read (a run's ``track``, for its
        provenance); not called for any other probe file.

    Returns
    -------
    pandas.DataFrame or None
        The truth (``revolution, angle_deg, profile_um, x_um, y_um``), or None when the file is
        not the shipped example.

    Raises
    ------
    ValueError
        The file is the example but the truth beside it is missing or not the recorded one.
    """
    truth = example.match_example(path, folder)
    if truth is not None and on_read is not None:
        on_read(Path(folder) / example.EXAMPLE_FILES["truth"])
    return truth


def profile_caption_fields(methods, roundness, noise) -> dict:
    """The numbers the separated profile's caption states, with the truth where there is one.

    Parameters
    ----------
    methods : pandas.DataFrame
        The profiles about their least-squares circles (um): ``least_squares_um``,
        ``weighted_um``, ``difference_um`` and, for the shipped example, ``true_um``.
    roundness : pandas.DataFrame
        ``profile`` (``"least squares"``, ``"weighted"``, perhaps ``"true (simulated)"``),
        ``lsc_um``, ``mz_um``.
    noise : pandas.DataFrame
        ``estimator`` (``least_squares``, ``weighted``) and ``profile_noise_um``, the rms error
        the probes' noise predicts in each profile.

    Returns
    -------
    dict
        ``largest`` (the largest difference drawn, um), ``lsc`` and ``mz`` (the least-squares
        profile's roundness, um), and the texts ``truth_left``, ``truth_right``, ``rms`` and
        ``true_roundness``: empty without a truth, else what it shows.
    """
    simulated = "true_um" in methods
    curves = [methods.difference_um]
    if simulated:
        curves += [methods[f"{m}_um"] - methods.true_um for m in ("least_squares", "weighted")]
    ro = roundness.set_index("profile")
    fields = dict(largest=max(float(np.abs(c).max()) for c in curves),
                  lsc=float(ro.lsc_um["least squares"]), mz=float(ro.mz_um["least squares"]),
                  truth_left="", truth_right="", rms="", true_roundness="")
    if simulated:
        rms = [float(np.sqrt((c ** 2).mean())) for c in curves[1:]]
        predicted = noise.set_index("estimator").profile_noise_um
        fields.update(
            truth_left=", with the true simulated profile in grey",
            truth_right=", and each minus the truth",
            rms=f"; rms errors {rms[0]:.4f} and {rms[1]:.4f} µm, where the noise predicts "
                f"{predicted['least_squares']:.4f} and {predicted['weighted']:.4f} µm",
            true_roundness=f" against the true {ro.lsc_um['true (simulated)']:.3f} and "
                           f"{ro.mz_um['true (simulated)']:.3f} µm")
    return fields


class Parameters(NotebookParameters):
    """Notebook 07: your own spindle's probe file, separated and evaluated."""

    stem = "07_your_spindle"
    probe_file = InputFile("data/spindle/example_probes.csv",
                           doc="probe file (schema: data/spindle/README.md)")
    max_harmonic = param.Integer(0, bounds=(0, 8191),
                                 doc="highest harmonic separated; 0: all the sampling resolves")
    allow_cancelled = param.Boolean(False, doc="drop the harmonics the layout cannot see")
    report_probes = NumberList([], item_type=float, item_bounds=(-360.0, 360.0),
                               doc="mounting angles (°) of the fixed directions; empty: all")
    rotating_direction_deg = param.Number(0.0, bounds=(-360.0, 360.0),
                                          doc="the rotating sensitive direction at angle 0 (°)")
    centre = param.Selector(default="LSC", objects=["LSC", "MRS"],
                            doc="centre of the ISO 230-7 polar plots and values")
    rotation = param.Selector(default="cw", objects=["cw", "ccw"],
                              doc="cw: probe at phi reads r(theta + phi); ccw: r(phi - theta)")
    max_upr = param.Number(0.0, bounds=(0.0, 100000.0),
                           doc="Gaussian low-pass cutoff (undulations per revolution); 0: none")
    amplified_above = param.Number(3.0, bounds=(1.0, 1000.0), inclusive_bounds=(False, True),
                                   doc="amplified: the layout multiplies noise by more than this")
    output_dir = OutputFolder("figures/07_your_spindle", doc="where figures and tables are written")

    def memory_bytes(self) -> float:
        # 0.22 GB measured at the defaults; the file drives memory and the reader's limits keep a
        # run below 0.8 GB (0.57 GB measured for 500 000 rows of 16 probes)
        return 8e8


# --- the chapter's figures, in the notebook's order ------------------------------------------

FIGURES = figures(
    Caption("probe_readings", "Figure 1",
            "Readings (µm) of the {n_probes} probes, mounted at {angles}, against the spindle "
            "angle ({n_samples} samples per revolution): the first revolution as a line and the "
            "band of all {n_revolutions} revolutions. Each reading mixes the artefact's profile "
            "at its probe's angle, the motion along its axis and a zero offset. {source}"),
    Caption("layout_harmonics", "Figure 2",
            "Noise amplification q_k of each harmonic k = {k_min} to {k_max} for the probe layout "
            "{angles} ({off_grid} of the probes off the sample grid), by least squares over all "
            "probes and by the weighted multi-point method of Yang et al. 2021 with weights "
            "{weights} chosen for these angles; dotted: the threshold {threshold:g}. Cancelled "
            "harmonics: {cancelled}. The largest q_k is {worst_least_squares:.2f} by least "
            "squares and {worst_weighted:.2f} by the weighted method, which exceed {threshold:g} "
            "at {amplified_least_squares} and {amplified_weighted} harmonics. {source}"),
    Caption("separated_profile", "Figure 3",
            "Left: the artefact's profile separated by least squares and by the weighted method, "
            "about its least-squares circle (µm, to scale on an arbitrary base circle)"
            "{truth_left}. Right: weighted minus least squares{truth_right}, against angle: all "
            "within ±{largest:.2g} µm{rms}. Roundness of the least-squares profile: LSC "
            "{lsc:.3f} µm and MZ {mz:.3f} µm{true_roundness}. {source}"),
    Caption("radial_error_motion_polar", "Figure 4",
            "ISO 230-7 polar plots of the spindle's radial error motion (µm, {centre}) for fixed "
            "sensitive directions along the axes of the probes at {fixed} and one rotating "
            "direction ({rotating:g}° at spindle angle 0): synchronous plot in colour, band of "
            "the {n_revolutions} revolutions in grey, dashed circles about the centre just "
            "containing the synchronous plot. Titles give the synchronous and asynchronous "
            "values, e.g. {synchronous:.3f} and {asynchronous:.3f} µm along {direction:g}°"
            "{truth}. {source}"),
    Caption("error_motion", "Figure 5",
            "The separated radial error motion x and y (µm, in the probes' frame) of every sample "
            "over the {n_revolutions} revolutions as one record ({filter}), with the synchronous "
            "motion (the mean of the revolutions at each angle) repeated in each revolution: what "
            "error_motion.csv holds. Their difference is the asynchronous motion, largest spread "
            "{asynchronous:.3f} µm along {direction:g}°. {source}"),
    Caption("asynchronous_spectrum", "Figure 6",
            "Amplitude spectrum of the asynchronous radial error motion (the motion less its mean "
            "over the revolutions, one continuous record of {n_revolutions} revolutions; single-"
            "sided amplitude of the motion vector, sqrt(Ax² + Ay²), µm) against frequency in "
            "cycles per revolution, resolution 1/{n_revolutions}; {filter}. Dotted: the "
            "frequencies of the largest synchronous harmonics ({marked}), where the asynchronous "
            "amplitude is zero by construction. Largest peak {peak:.4f} µm at {peak_cpr:g} "
            "cycles per revolution. {source}"),
)
