"""Notebook 05 (Yang et al. 2021): the checks of its parameters, its analyses and its figures.

The method itself (four-point separation, the error transfer function, the GAs, the simulated
lathe experiment) is :mod:`mtaccuracy.spindle`; this package holds what serves the paper's
audit.  Its modules, each one concern (every name is also here, as ``yang2021.<name>``):

==============  ============================================================================
``analyses``    Table 1's consistency check, the GA settings study, Section 1.3 under every
                mapping, the printed Eq. 17 against its inverse, least squares
``scorecard``   the scorecard's inputs and texts
``figures``     the figures drawn here with their captions and :data:`FIGURES`, in the
                paper's order
==============  ============================================================================

and here, the notebook's declaration of its parameters (:class:`Parameters`).
"""

from __future__ import annotations

import param

from ..parameters import NotebookParameters, NumberList, OutputFolder, ParameterError
from .analyses import (
    NOISE_DECIMALS,
    eq17_sign_check,
    ga_settings_study,
    least_squares_vs_weighted,
    mappings_and_conventions,
    single_run_speedups,
    speed_trend_sources,
    table1_consistency,
)
from .figures import (
    FIG08,
    FIG09,
    FIG19,
    FIG20,
    FIG21,
    FIGURES,
    NOISE_TRANSFER,
    convergence_figure,
    fig21_figure,
    noise_transfer_figure,
    speed_curves_figure,
)
from .scorecard import (
    MAPPING_TEXT,
    difference_text,
    experiment_genes,
    experiment_inputs,
    fig10_readings,
    layout_text,
    ranges_statement,
    table1_consistency_texts,
)

__all__ = ["difference_text", "eq17_sign_check", "experiment_genes", "experiment_inputs",
           "ga_settings_study", "layout_text", "least_squares_vs_weighted",
           "mappings_and_conventions", "noise_transfer_figure", "ranges_statement",
           "single_run_speedups", "speed_curves_figure", "table1_consistency_texts",
           "convergence_figure", "FIG08", "FIG09", "table1_consistency", "fig21_figure",
           "FIG21", "MAPPING_TEXT", "NOISE_TRANSFER", "FIG19", "FIG20", "Parameters",
           "FIGURES", "NOISE_DECIMALS", "fig10_readings", "speed_trend_sources"]


class Parameters(NotebookParameters):
    """Notebook 05: Yang et al. 2021, four-point spindle error separation and the GA."""

    stem = "05_yang2021_spindle_four_point_ga"
    seed = param.Integer(2021, bounds=(0, 4294967295), doc="seed of every random draw")
    n_samples = param.Integer(128, bounds=(32, 1024),
                              doc="samples per revolution, Section 1.3 (paper: 128)")
    probe_positions = NumberList([0, 14, 65, 116], item_type=int, bounds=(4, 4),
                                 item_bounds=(0, 1023),
                                 doc="probe sample positions p_0..p_3 (paper: 0 14 65 116)")
    a3 = param.Number(1.953, bounds=(-10.0, 10.0),
                      doc="a3 of Section 1.3 (paper: 1.953); a1, a2 follow from Eq. 5")
    mapping = param.Selector(default="radial", objects=["radial", "radial_reversed", "x_only"],
                             doc="scalar rotation error to (dx, dy), not stated in the paper")
    first_harmonic = param.Selector(default="radial", objects=["radial", "eccentricity"],
                                    doc="how the first harmonic is split from the motion")
    noise_um = param.Number(0.1, bounds=(0.0, 10.0), doc="sensor noise sd of the noise study (µm)")
    n_noise_trials = param.Integer(2000, bounds=(50, 20000),
                                   doc="Monte Carlo trials of the noise study")
    harmonic_k = param.Integer(20, bounds=(2, 200),
                               doc="harmonic order of Figs. 8-9 (paper: 20)")
    n_ga_runs = param.Integer(64, bounds=(30, 1024), doc="runs per algorithm for Figs. 8-9")
    pop_size = param.Integer(50, bounds=(4, 500), doc="GA population size, even (not stated)")
    generations = param.Integer(200, bounds=(20, 2000),
                                doc="generations alpha_max (not stated in the paper)")
    encoding = param.Selector(default="binary", objects=["binary", "real"],
                              doc="GA encoding (not stated in the paper)")
    traditional_pc = param.Number(0.8, bounds=(0.0, 1.0),
                                  doc="crossover probability of the traditional GA (not stated)")
    traditional_pm = param.Number(0.05, bounds=(0.0, 1.0),
                                  doc="mutation probability of the traditional GA (not stated)")
    n_study_runs = param.Integer(32, bounds=(8, 1024),
                                 doc="runs per setting of the GA settings study (Section 6)")
    study_generations = NumberList([120, 200, 300], item_type=int, item_bounds=(20, 2000),
                                   doc="generation counts of the settings study")
    study_pc = NumberList([0.6, 0.8, 0.99], item_type=float, item_bounds=(0.0, 1.0),
                          doc="crossover probabilities of the settings study")
    study_pm = NumberList([0.005, 0.01, 0.05, 0.09], item_type=float, item_bounds=(0.0, 1.0),
                          doc="mutation probabilities of the settings study")
    converge_tol = param.Number(0.01, bounds=(0.0, 1.0), inclusive_bounds=(False, True),
                                doc="converged: best H within this fraction of the best known")
    a3_max = param.Number(3.0, bounds=(0.1, 100.0), inclusive_bounds=(False, True),
                          doc="a3 is searched in [0.1, a3_max] (not stated in the paper)")
    k_sweep_max = param.Integer(80, bounds=(80, 200),
                                doc="Table 1 and Figs. 10-12 cover k from 2 to this")
    n_sweep_runs = param.Integer(8, bounds=(1, 32),
                                 doc="improved-GA runs per harmonic order in the sweep")
    worst_k = param.Integer(20, bounds=(3, 511),
                            doc="the worst-case objective protects harmonics 2 to this")
    exp_n_samples = param.Integer(128, bounds=(32, 1024),
                                  doc="samples per revolution of the simulated experiment")
    mandrel_roundness_um = param.Number(3.0, bounds=(0.0, 100.0), inclusive_bounds=(False, True),
                                        doc="roundness of the simulated mandrel (paper: 3 µm)")
    exp_noise_um = param.Number(0.1, bounds=(0.0, 10.0),
                                doc="probe noise sd per sample, simulated experiment (µm)")
    async_um = param.Number(0.2, bounds=(0.0, 10.0),
                            doc="rms asynchronous error motion per axis at 600 r/min (µm)")
    async_exponent = param.Number(1.0, bounds=(0.0, 4.0),
                                  doc="asynchronous motion grows as (speed / 600) ** this")
    duration_s = param.Number(1.0, bounds=(0.0, 60.0), inclusive_bounds=(False, True),
                              doc="acquisition time of one measurement (s)")
    interleave = param.Integer(2, bounds=(1, 16),
                               doc="revolutions per full set of angles (Eqs. 1-2)")
    lowpass_harmonic = param.Integer(50, bounds=(2, 512),
                                     doc="low-pass FFT filter: harmonics above this removed")
    n_measurements = param.Integer(20, bounds=(3, 500),
                                   doc="repeated measurements per speed and layout")
    n_random_layouts = param.Integer(3, bounds=(1, 20),
                                     doc="random probe layouts of Fig. 21 (paper: 3)")
    exp_layout = param.Selector(default="paper", objects=["paper", "ours"],
                                doc="layout of the simulated experiment: the paper's or ours")
    output_dir = OutputFolder("figures/05_yang2021_spindle_four_point_ga",
                              doc="where figures and tables go")

    def memory_bytes(self) -> float:
        # libraries and figures, the noise study (8 arrays of 4 N (trials + 4 N) numbers), the
        # binary GA's random bits (4 arrays of 64 per individual and run), the GA histories, the
        # simulated experiment; 0.47 GB at the defaults, 0.33 GB measured
        runs = max(self.n_ga_runs, (self.k_sweep_max - 1) * self.n_sweep_runs)
        histories = (self.k_sweep_max - 1) * self.n_sweep_runs + 7 * self.n_ga_runs
        experiment = self.n_measurements * (self.duration_s * 50 + self.interleave)
        return (3e8 + 8 * 4 * self.n_samples * (self.n_noise_trials + 4 * self.n_samples) * 8
                + 8 * 64 * self.pop_size * runs * 4
                + 8 * (self.generations + 1) * histories * 2
                + 8 * 16 * experiment * self.exp_n_samples)

    def check(self) -> None:
        stem, n, n_exp = self.stem, self.n_samples, self.exp_n_samples
        positions = self.probe_positions
        if len(positions) != 4 or positions[0] != 0 or max(positions) >= n \
                or len(set(positions)) != 4:
            raise ParameterError(f"{stem}: probe_positions must be 4 distinct sample indices in "
                                 f"0..{n - 1} starting with 0, got {positions}")
        if self.lowpass_harmonic > n_exp // 2 or n_exp % self.interleave:
            raise ParameterError(f"{stem}: need lowpass_harmonic <= exp_n_samples / 2 and "
                                 f"interleave dividing exp_n_samples, got "
                                 f"{self.lowpass_harmonic}, {self.interleave}, {n_exp}")
        if self.worst_k >= min(n, n_exp) // 2:
            raise ParameterError(f"{stem}: worst_k must stay below N/2 = {min(n, n_exp) // 2}")
        if self.harmonic_k > self.k_sweep_max or self.pop_size % 2:
            raise ParameterError(f"{stem}: need harmonic_k <= k_sweep_max (the sweep supplies the "
                                 f"GA's best run at harmonic_k) and an even pop_size (parents are "
                                 f"paired), got {self.harmonic_k}, {self.k_sweep_max}, "
                                 f"{self.pop_size}")
