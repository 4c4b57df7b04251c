"""Thermal positioning error of a linear axis (Xu et al. 2022): data, sensitive points, models.

=================  ========================================================================
``data``           :class:`ThermalData`, the measurements of one axis; :func:`rises_of`
``schema``         the CSV schema of ``data/thermal/README.md``: file names, limits,
                   :class:`DataFormatError` and the readers' warnings
``labexport``      a lab export (a logger and a laser file per experiment):
                   :func:`read_lab_export`, :func:`layout`, :func:`experiment_number`
``io``             :func:`read_measurements` (either layout; each file by its own reader),
                   :func:`write_measurements`, :func:`save_csv`; the checks of the schema
                   are ``checks``, the reading of one CSV file ``csvfile``
``clustering``     fuzzy equivalence clustering (Eqs. 1-3), grey relational grade (Eq. 4),
                   :func:`select_sensitive_points`
``models``         :func:`decouple` (Eq. 6), :func:`compose` (Eq. 7), and scikit-learn
                   estimators: :class:`PointByPointRegressor` (Eqs. 5, 8),
                   :class:`DecoupledRegressor` (Eq. 9), MLR by default
``svr``            :class:`StandardisedSVR`, :class:`GroupedSVR` (hyperparameters by
                   ``GroupKFold``), :func:`svr_search` and its tie rule
``validation``     :func:`metrics` (the one RMSE: pooled over positions and measurements),
                   :data:`POOLED_RMSE_SCORER`, :func:`evaluate_split`,
                   :func:`leave_one_experiment_out`, :func:`replicate_split`
``baselines``      no compensation and :class:`GroupedRidge` on all sensors, against which the
                   paper's selected models are judged; :func:`pool_metrics`
=================  ========================================================================

The seeded reconstruction of the paper's dataset, calibrated to its printed tables, is paper
code: :mod:`mtaccuracy.papers.xu2022_reconstruction`.

Everything public in ``data``, ``schema``, ``io``, ``labexport``, ``clustering``, ``models``,
``svr``, ``validation`` and ``baselines`` is importable from here.
Units: positions in mm, errors in um, slopes k in um/m (so ``k * x_mm / 1000`` is um),
temperatures in degrees Celsius.  The position axis is shifted to start at 0 (the paper models
185..445 mm as 0..260 mm so that the intercept b is the error at the first target).

Example: the decoupled MLR on arrays, composed with scikit-learn's model selection::

    from sklearn.linear_model import LinearRegression
    from sklearn.model_selection import GroupKFold, cross_val_score
    model = DecoupledRegressor(offsets_mm, k_columns=[0, 1], b_columns=[2],
                               k_estimator=LinearRegression(), b_estimator=LinearRegression())
    cross_val_score(model, X, errors, groups=experiment, cv=GroupKFold(4),
                    scoring=POOLED_RMSE_SCORER)   # RMSE over all positions and measurements
"""

from . import (  # noqa: F401
    baselines,
    checks,
    clustering,
    csvfile,
    data,
    io,
    labexport,
    models,
    schema,
    svr,
    validation,
)
from .baselines import *  # noqa: F403
from .clustering import *  # noqa: F403
from .data import *  # noqa: F403
from .io import *  # noqa: F403
from .labexport import *  # noqa: F403
from .models import *  # noqa: F403
from .schema import *  # noqa: F403
from .svr import *  # noqa: F403
from .validation import *  # noqa: F403

__all__ = [*data.__all__, *schema.__all__, *io.__all__, *labexport.__all__, *clustering.__all__,
           *models.__all__, *svr.__all__, *validation.__all__, *baselines.__all__]
