"""Notebook 01's paper code (Zheng et al. 2024): the pose behind Table 2, its checks, figures.

The paper prints Sobol' indices of the AC double turntable (Table 2, Figs. 5-6) computed at a
pose it does not state: it shows test points on the four body diagonals of the workspace
(Fig. 4) but not which point, or which aggregate, Table 2 reports, nor where the rotary axes
stand at those points.  The pose is what the paper omits, so this package searches for it,
written by hand for this paper.  Its modules, each one concern (every name is also here, as
``zheng2024.<name>``):

==================  ========================================================================
``pose_search``     the symmetry group of the normalised linear indices, the canonical
                    ranking of an optimiser's minima, the search for the pose (or the two
                    poses whose mean) behind Table 2
``references``      the Fig. 4 test points; the closed-form, sampled (MCS, LHS) and PCE
                    indices at a test point
``checks``          ratios the model fixes at every pose, Table 2 against them; Section 3.2's
                    group shares, Section 3.3's relative differences
``scorecard``       tables tidied, numbers printed, Fig. 7's convergence as text
``figures``         the figures drawn here with their captions (:data:`FIG04`,
                    :data:`FIG05`, :data:`FIG06`) and :data:`FIGURES`, in the book's order
``measurement``     which standard test sees each key error (:func:`visibility_table`), its
                    status matrix (:func:`status_matrix_figure`, caption :data:`MEASURE`)
==================  ========================================================================

and here, the notebook's parameters (:class:`Parameters`).

The methods are in :mod:`mtaccuracy.sensitivity` (:mod:`~mtaccuracy.sensitivity.posefit`: the
pose search shared with notebook 03; :mod:`~mtaccuracy.sensitivity.linear`: the closed-form
indices) and the machine in :mod:`mtaccuracy.machines.ac_double_turntable`.
"""

from __future__ import annotations

import param

from ..parameters import NotebookParameters, NumberList, OutputFolder
from .checks import (
    fixed_ratio_checks,
    group_head,
    group_label,
    group_shares,
    index_invariants,
    key_relative_difference,
    published_relative_difference,
    ratio_interval,
    relative_scatter,
)
from .figures import FIG04, FIG05, FIG06, FIGURES, bars_figure, fig04_figure
from .measurement import (
    MEASURE,
    STATUSES,
    STRUCTURAL_GAIN,
    per_error_summary,
    status_matrix_figure,
    structural_prior_sd,
    visibility_table,
    workpiece_motion_residual,
)
from .pose_search import (
    POSE_SYMMETRIES,
    canonical_pose,
    fit_pose_average_to_indices,
    fit_pose_to_indices,
    pose_orbit,
    rank_poses,
)
from .references import (
    diagonal_test_points,
    normalise,
    pce_fit_quality,
    pce_indices,
    sobol_reference,
    table_indices,
)
from .scorecard import (
    READINGS,
    both_sizes,
    converged_at,
    convergence_text,
    fluctuation_text,
    fmt,
    tidy,
)

__all__ = ["POSE_SYMMETRIES", "pose_orbit", "canonical_pose", "rank_poses",
           "fit_pose_to_indices", "fit_pose_average_to_indices", "index_invariants",
           "ratio_interval", "diagonal_test_points", "table_indices",
           "tidy", "fmt", "normalise", "sobol_reference", "pce_indices", "group_label",
           "fixed_ratio_checks", "group_head", "converged_at", "bars_figure",
           "fig04_figure", "group_shares", "relative_scatter", "pce_fit_quality",
           "key_relative_difference", "published_relative_difference", "READINGS",
           "both_sizes", "convergence_text", "fluctuation_text",
           "FIG04", "FIG05", "FIG06", "FIGURES", "Parameters",
           "MEASURE", "STATUSES", "STRUCTURAL_GAIN", "per_error_summary", "status_matrix_figure",
           "structural_prior_sd", "visibility_table", "workpiece_motion_residual"]


class Parameters(NotebookParameters):
    """Notebook 01: Zheng et al. 2024, sparse PCE against MCS and LHS Sobol' indices."""

    stem = "01_zheng2024_pce_sobol_41_errors"
    seed = param.Integer(2024, bounds=(0, None), doc="seed of every random draw")
    position_range_um = param.Number(15.0, bounds=(0.0, 1000.0), inclusive_bounds=(False, True),
                                     doc="translational errors: +/- this range (paper: 15 µm)")
    angular_range_arcsec = param.Number(10.0, bounds=(0.0, 3600.0),
                                        inclusive_bounds=(False, True),
                                        doc="angular errors: +/- this (paper: 10 arcsec)")
    range_in_sigmas = param.Number(3.0, bounds=(0.5, 10.0),
                                   doc="the range is this many sd (not stated in the paper)")
    # its design matrix has n_pce x 13244 entries at degree 3
    n_pce = param.Integer(1000, bounds=(50, 5000), doc="PCE design size (paper: 1000)")
    # degree 4 has 148995 terms: minutes per fit
    pce_degree = param.Integer(3, bounds=(1, 4), doc="total degree of the PCE basis (paper: 3)")
    # 43 N model runs each, streamed in blocks of 131072 base rows (an LHS design, 1.6 kB a row,
    # is held whole)
    n_reference = param.Integer(100000, bounds=(100, 1000000),
                                doc="MCS and LHS base sample size N (paper: 1e5)")
    n_per_diagonal = param.Integer(5, bounds=(2, 50),
                                   doc="test points per workspace diagonal (paper: 5, Fig. 4)")
    search_starts = param.Integer(32, bounds=(1, 2000),
                                  doc="random starts of the Table 2 pose search")
    check_poses = param.Integer(200, bounds=(10, 100000),
                                doc="random poses checking the ratios the model fixes")
    average_starts = param.Integer(6, bounds=(1, 200),
                                   doc="random starts of the two-pose mean search")
    # the sample sizes of Fig. 7 (paper: up to 1e5); the help is short so that the parameters
    # cell's line stays within 100 characters
    convergence_sizes = NumberList([100, 200, 500, 1000, 2000, 5000, 10000, 20000, 50000,
                                    100000], item_type=int, item_bounds=(10, 100000),
                                   doc="Fig. 7")
    # above the paper's 1000, so that R at 1000 exists under both readings of Eq. 24
    pce_convergence_max = param.Integer(2000, bounds=(100, 5000),
                                        doc="largest PCE design in Fig. 7")
    select_degrees = NumberList([1, 2, 3], item_type=int, item_bounds=(1, 3),
                                doc="degrees tried by the corrected-LOO selection")
    select_q_norms = NumberList([0.5, 0.75, 1.0], item_type=float, item_bounds=(0.0, 1.0),
                                item_inclusive=(False, True),
                                doc="q-norms tried by the corrected-LOO selection")
    bench_n_ishigami = param.Integer(300, bounds=(50, 5000),
                                     doc="samples of the Ishigami benchmark")
    bench_max_degree = param.Integer(14, bounds=(1, 20),
                                     doc="highest degree tried on the Ishigami benchmark")
    bench_n_g = param.Integer(1000, bounds=(100, 5000),
                              doc="samples of the 41-input G-function benchmark")
    # the paper omits the tool length: Section 3.2's position claims are read at 0 and at this
    tool_length_max_mm = param.Number(200.0, bounds=(0.0, 1000.0),
                                      doc="longest tool read (paper: not stated)")
    # more random designs under the model-run reading of "1e5 samples" (Section 3.3's rows)
    extra_designs = param.Integer(3, bounds=(0, 50),
                                  doc="more designs at 1e5 model runs (Section 3.3)")
    key_threshold = param.Number(0.05, bounds=(0.0, 1.0), inclusive_bounds=(False, False),
                                 doc="key error: normalised total index above this (paper: 0.05)")
    # Section 9: the standard tests on the paper's machine (its tool length is not stated)
    measure_tool_mm = param.Number(100.0, bounds=(0.0, 1000.0),
                                   doc="tool length of the standard tests (mm)")
    measure_noise_um = param.Number(0.5, bounds=(0.0, 100.0), inclusive_bounds=(False, True),
                                    doc="noise of one length reading (µm; angular: 1 µrad)")
    output_dir = OutputFolder("figures/01_zheng2024_pce_sobol_41_errors",
                              doc="where figures and tables are written")

    def memory_bytes(self) -> float:
        # libraries and figures, then the larger of the Sobol runs (one block of at most 131072
        # base rows: inputs, 41 x 6 outputs and the estimator's temporaries, about 8 kB a row;
        # plus the whole LHS design) and the PCE fits (five copies of the design matrix: 13244
        # columns at degree 3, 11.25 times more at degree 4; the G-function benchmark: three)
        sobol = 8000 * min(max(self.n_reference, 100000), 131072) + 1600 * self.n_reference
        pce = (40 * 13244 * max(self.n_pce, self.pce_convergence_max)
               * max(1.0, 11.25 ** (self.pce_degree - 3)))
        return 4e8 + max(sobol, pce, 24 * 13244 * self.bench_n_g)
