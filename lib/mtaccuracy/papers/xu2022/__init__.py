"""Notebook 04's paper code (Xu et al. 2022): published values, the reconstruction, the figures.

The thermal science (:mod:`mtaccuracy.thermal`) takes arrays and tables and never reads
``data/papers/`` or knows the repository's folders; this package does that for notebook 04.
Its modules, each one concern (every name is also here, as ``xu2022.<name>``):

==================  ========================================================================
``data``            the published tables the reconstruction is built from (the seeded
                    generator is :mod:`mtaccuracy.papers.xu2022_reconstruction`), whether a
                    folder holds the committed reconstruction (:func:`reconstruction_seed`),
                    :func:`regenerate` and its command
``checks``          the notebook's checks of its split and data, and scorecard helpers
``caption_fields``  the numbers the captions state, every one computed by the run
``figures``         the figures drawn here with their captions and :data:`FIGURES`, in the
                    book's order; :func:`caption` fills one in
``table3``          Table 3 against the paper's own method: can one partition of the sensors
                    produce it?
``per_position``    Table 3 under Section 3.1's per-position reading (each position's error
                    joins the clustering), and data on which it gives any printed rows
``__main__``        the command below
==================  ========================================================================

and here, the notebook's parameters (:class:`Parameters`).

A normal run of the notebook only reads its ``data_dir``.  Rewriting ``data/thermal`` is a
command of its own, :func:`regenerate`::

    python -m mtaccuracy.papers.xu2022 regenerate [FOLDER] [--seed S]
"""

from __future__ import annotations

import param

from ..parameters import InputFolder, NotebookParameters, NumberList, OutputFolder
from .caption_fields import data_fields, loeo_fields, model_fields, pooled_fields
from .checks import (
    ERROR,
    METHODS,
    METRIC_NAMES,
    RECONSTRUCTED_LABEL,
    Progress,
    beats,
    check_data,
    check_experiments,
    reader_notes,
    resolve_inputs,
    resolve_split,
    sampling_se,
    stated,
)
from .data import (
    DATA,
    DATA_FILES,
    calibrate,
    data_origin,
    main,
    noise_replicates,
    published_inputs,
    published_metrics,
    published_models,
    published_targets,
    reconstruct,
    reconstruction_seed,
    regenerate,
)
from .figures import (
    FIG11,
    FIG14,
    FIG15,
    FIG16,
    FIG17,
    FIGURES,
    ON_OWN_DATA,
    ON_RECONSTRUCTION,
    PLOT_DECIMALS,
    caption,
    kb_figure,
    prediction_figure,
)
from .per_position import per_position_clusters, per_position_selections, witness
from .table3 import MAX_ASSIGNMENTS, partition_fits, rows_fitted_by, table3_consistency

__all__ = [
    "DATA", "DATA_FILES", "published_targets", "published_models", "published_inputs",
    "published_metrics", "reconstruct", "noise_replicates", "calibrate", "reconstruction_seed",
    "regenerate", "data_origin", "resolve_split", "resolve_inputs", "check_experiments",
    "check_data", "reader_notes", "Progress", "sampling_se", "stated", "beats",
    "prediction_figure", "kb_figure", "data_fields", "model_fields", "loeo_fields",
    "pooled_fields", "caption", "FIGURES", "partition_fits", "table3_consistency",
    "rows_fitted_by", "per_position_clusters", "per_position_selections", "witness", "main",
    "RECONSTRUCTED_LABEL", "ERROR", "METRIC_NAMES", "METHODS", "PLOT_DECIMALS", "FIG11",
    "FIG14", "FIG15", "FIG16", "FIG17", "ON_RECONSTRUCTION", "ON_OWN_DATA", "MAX_ASSIGNMENTS",
    "Parameters",
]


class Parameters(NotebookParameters):
    """Notebook 04: Xu et al. 2022, thermal error decoupling, MLR and SVR."""

    stem = "04_xu2022_thermal_mlr_svr"
    # a normal run only reads data_dir; on the reconstruction (decided by content) another seed
    # builds the reconstruction with it in memory; on a reader's own data the seed does not apply
    seed = param.Integer(2022, bounds=(0, 4294967295),
                         doc="seed of the reconstruction's noise (data/thermal: 2022)")
    # at the reader's limits (1000 measurements x 100 sensors x 500 positions) a run takes about
    # 8 min on 2 cores, one split about 50 s
    data_dir = InputFolder("data/thermal",
                           doc="temperatures.csv and errors.csv (data/thermal/README.md)")
    train_experiments = NumberList([], item_type=int, item_bounds=(1, None),
                                   doc="experiments fitted; empty: all but the test one")
    test_experiment = param.Integer(0, bounds=(0, 1000000),
                                    doc="experiment predicted; 0: the last one (paper: 4)")
    inputs = param.Selector(default="auto", objects=["auto", "published", "selected"],
                            doc="sensitive points: the paper's, selected, or auto")
    ambient_sensor = param.String("T10", doc="the sensor reading the workshop air (Fig. 3)")
    n_clusters = param.Integer(3, bounds=(1, 100),
                               doc="clusters of the fuzzy equivalence clustering (paper: 3)")
    rho = param.Number(0.5, bounds=(0.0, 1.0), inclusive_bounds=(False, True),
                       doc="distinguishing coefficient of the grey grade (paper: 0.5)")
    leave_one_out = param.Boolean(True, doc="also hold out every experiment in turn")
    # SVR refits cost about 40 ms each
    n_replicates = param.Integer(20, bounds=(2, 200),
                                 doc="noise realisations behind the sampling standard errors")
    output_dir = OutputFolder("figures/04_xu2022_thermal_mlr_svr",
                              doc="where figures and tables are written")

    def check(self) -> None:
        """Refuse a split that contradicts itself, before any data are read."""
        if self.train_experiments:
            check_experiments(self.stem, list(self.train_experiments),
                              self.test_experiment or None)

    def memory_bytes(self) -> float:
        """Peak bytes of a run: the data drive memory, not the parameters."""
        # 0.28 GB measured at the defaults; the data drive memory, and the reader's limits (100
        # sensors, 500 positions, 1000 measurements) keep them below 0.7 GB (0.58 GB measured)
        return 7e8
