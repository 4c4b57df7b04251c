"""Notebook 04's figures drawn here, each with its caption, and the chapter's captions in order.

The prediction figures (:func:`prediction_figure`: Figs. 11, 15, 17) and the slope and
intercept figures (:func:`kb_figure`: Figs. 14, 16), beside their captions; :data:`FIGURES`,
every caption of the chapter in the book's order, and :func:`caption`, one of them with its
numbers (:mod:`.caption_fields`) and a sentence on what the data are.
"""

from __future__ import annotations

import numpy as np

from ..figure import Caption, figures

__all__ = ["PLOT_DECIMALS", "prediction_figure", "kb_figure", "FIG11", "FIG14", "FIG15",
           "FIG16", "FIG17", "FIGURES", "ON_RECONSTRUCTION", "ON_OWN_DATA", "caption"]


#: Decimals (um, um/m) of the values the prediction figures draw: 1e-4 um is a few thousandths
#: of a pixel there (about 0.03 um a pixel).  Below it a model's predictions carry rounding
#: that another CPU changes (another BLAS kernel: about 1e-14 um for the MLR, 1e-10 um for the
#: SVR), and the PNG's antialiased pixels changed from it; drawn to 1e-4 um the figures are
#: the same on any CPU unless a value lies within that noise of a rounding edge.
PLOT_DECIMALS = 4


def _plotted(values):
    """Values as the figures draw them: to :data:`PLOT_DECIMALS` decimals."""
    return np.round(np.asarray(values, dtype=float), PLOT_DECIMALS) + 0.0


def prediction_figure(positions_mm, index, measured, predicted, *, title: str):
    """Measured (solid) and predicted (dashed) errors along the axis, and the residuals.

    Figs. 11, 15 and 17 (:data:`FIG11`, :data:`FIG15`, :data:`FIG17`), drawn to
    :data:`PLOT_DECIMALS` decimals.

    Parameters
    ----------
    positions_mm : array (P,)
        Target positions.
    index : pandas.DataFrame
        The test measurements (``time_min`` labels the curves).
    measured, predicted : array (n, P)
        Errors (µm).
    title : str
        The figure's title.

    Returns
    -------
    matplotlib.figure.Figure
        Two panels: the errors, and their residuals.
    """
    import matplotlib.pyplot as plt  # heavy (a GUI backend): loaded only to draw

    measured, predicted = _plotted(measured), _plotted(predicted)
    resid = measured - predicted
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    cm = plt.get_cmap("plasma")(np.linspace(0, 0.85, len(index)))
    for c, (_, r), y, yp in zip(cm, index.iterrows(), measured, predicted, strict=True):
        axes[0].plot(positions_mm, y, "o-", ms=3, color=c, label=f"{r.time_min:g} min")
        axes[0].plot(positions_mm, yp, "--", color=c)
        axes[1].plot(positions_mm, y - yp, "o-", ms=3, color=c)
    axes[0].set_title("measured (solid) and predicted (dashed)")
    axes[1].set_title(f"residual: {resid.min():.1f} .. {resid.max():.1f} µm")
    for ax in axes:
        ax.set_xlabel("position (mm)")
        ax.set_ylabel("error (µm)")
    if len(index) <= 24:
        axes[0].legend(fontsize=6, ncol=2)
    fig.suptitle(title)
    fig.tight_layout()
    return fig


FIG11 = Caption(
    "fig11_point_by_point_prediction", "Fig. 11",
    "Point-by-point MLR (Eq. 8): one regression per target on the temperature rises of {points}, "
    "trained on experiments {train} and predicting experiment {test} from its temperatures. "
    "Left: measured (solid) and predicted (dashed) error per measurement. Right: the residual, "
    "{pbp_lo} to {pbp_hi} µm; RMSE {pbp_rmse} µm{pbp_paper}. {data}",
    rows=("Table 4", "Section 3.1"))
FIG15 = Caption(
    "fig15_mlr_error_prediction", "Fig. 15",
    "The error of experiment {test} recombined from the MLR-predicted k and b (Eq. 7). Left: "
    "measured (solid) and predicted (dashed) per measurement. Right: the residual, {mlr_lo} to "
    "{mlr_hi} µm, against position; RMSE {mlr_rmse} µm{mlr_paper}, against {pbp_rmse} µm for "
    "the point-by-point model of Fig. 11. {data}",
    rows=("Table 7", "Section 3.2: decoupled_mlr*"))
FIG17 = Caption(
    "fig17_svr_error_prediction", "Fig. 17",
    "The error of experiment {test} recombined from the SVR-predicted k and b: measured (solid) "
    "and predicted (dashed), and the residual, {svr_lo} to {svr_hi} µm, against position. RMSE "
    "{svr_rmse} µm{svr_paper}, against {mlr_rmse} µm{mlr_paper} for the decoupled MLR of "
    "Fig. 15. {data}",
    rows=("Table 8", "Section 3.2: decoupled_svr*", "Section 5"), key=True)


def kb_figure(measurement, measured_kb, predicted_kb, *, title: str, colour):
    """Slope k and intercept b of every test measurement: decoupled and predicted.

    Figs. 14 and 16 (:data:`FIG14`, :data:`FIG16`): k and b decoupled from the data
    (circles), and predicted from the temperatures (squares), drawn to :data:`PLOT_DECIMALS`
    decimals.

    Parameters
    ----------
    measurement : array (n,)
        The test measurements' numbers.
    measured_kb, predicted_kb : (array (n,), array (n,))
        (k, b) decoupled from the data, and predicted.
    title : str
        The figure's title.
    colour : str
        Colour of the decoupled values.

    Returns
    -------
    matplotlib.figure.Figure
        Two panels: k and b.
    """
    import matplotlib.pyplot as plt  # heavy (a GUI backend): loaded only to draw

    measured_kb = [_plotted(v) for v in measured_kb]
    predicted_kb = [_plotted(v) for v in predicted_kb]
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.6))
    for ax, meas, pred, lab in ((axes[0], measured_kb[0], predicted_kb[0], "slope k (µm/m)"),
                                (axes[1], measured_kb[1], predicted_kb[1], "intercept b (µm)")):
        ax.plot(measurement, meas, "o-", color=colour, label="decoupled from the data")
        ax.plot(measurement, pred, "s--", color="k", label="predicted from temperatures")
        ax.set_xlabel("measurement")
        ax.set_ylabel(lab)
        ax.set_title(f"largest residual {np.abs(meas - pred).max():.2f}")
    axes[0].legend(fontsize=7)
    fig.suptitle(title)
    fig.tight_layout()
    return fig


FIG14 = Caption(
    "fig14_mlr_slope_intercept", "Fig. 14",
    "Slope k and intercept b of experiment {test}, decoupled from the data (circles) and "
    "predicted from its temperatures by the decoupled MLR of Eq. 9 (squares): k from the "
    "absolute temperatures of {k_points}, b from the rises of {b_points} ({kb_how}), trained on "
    "experiments {train}. Largest residuals {mlr_k_max} µm/m and {mlr_b_max} µm{mlr_kb_paper}. "
    "{data}",
    rows=("Eq. 9", "Table 7: decoupled_mlr, slope k*", "Table 7: decoupled_mlr, intercept b*"))
FIG16 = Caption(
    "fig16_svr_slope_intercept", "Fig. 16",
    "As Fig. 14, with support vector regression (inputs and target standardised, "
    "hyperparameters chosen by leave-one-experiment-out cross-validation on experiments "
    "{train}, which picks {kernels}): k and b of experiment {test}, decoupled (circles) and "
    "predicted (squares). Largest residuals {svr_k_max} µm/m and {svr_b_max} µm{svr_kb_paper}. "
    "{data}",
    rows=("Table 8: decoupled_svr, slope k*", "Table 8: decoupled_svr, intercept b*"))

#: What Figs. 5-9 show is scored by these rows.
_ERROR_ROWS = ("Table 5", "Eq. 8", "Section 3.2: largest error*")

#: The chapter's captions, in the paper's order (the book's).  ``{data}`` is what the figure's
#: data are (:func:`caption`); every other field is a number the run computed
#: (:func:`data_fields`, :func:`model_fields`, :func:`loeo_fields`, :func:`pooled_fields`).
FIGURES = figures(
    Caption("fig03_ambient_temperature", "Fig. 3",
            "Ambient temperature (sensor {air}, °C) over the {measurements} ({times}) of each "
            "of the {experiments}{feeds}. {data}", rows=("Table 1",)),
    Caption("fig05_error_vs_position", "Fig. 5",
            "Thermal positioning error (µm) of the axis at the {positions}, one curve per "
            "measurement ({first_times}) of experiment {first}{first_feed}; the laser is "
            "zeroed only at the first measurement. The largest error is {first_extreme}. "
            "{data}", rows=_ERROR_ROWS),
    Caption("fig06_error_vs_time", "Fig. 6",
            "The errors of Fig. 5 (experiment {first}) against time, one curve per target "
            "position from {pos_first} to {pos_last} mm. Over the {duration} minutes each target "
            "drifts by {drift} (the range of its readings). {data}", rows=_ERROR_ROWS),
    Caption("fig07_error_surface", "Fig. 7",
            "The errors of Figs. 5 and 6 as one surface over position ({pos_first} to "
            "{pos_last} mm) and time ({first_times}), experiment {first} (µm). {data}",
            rows=_ERROR_ROWS),
    Caption("fig08_error_zeroed", "Fig. 8",
            "The errors of Fig. 5 zeroed at the first target ({pos_first} mm) of every "
            "measurement, as a conventional measurement would show them (experiment {first}, "
            "µm). The paper's point is that zeroing hides the drift: the zeroed curves lie "
            "within {zeroed} µm of each other at every target, against a drift of {drift} in "
            "Figs. 5 and 6. {data}", rows=_ERROR_ROWS),
    Caption("fig09_error_other_experiments", "Fig. 9",
            "Thermal positioning error (µm) against position for experiments "
            "{others}{others_feeds}, one curve per measurement. {farthest} {data}",
            rows=_ERROR_ROWS),
    Caption("fig10_temperatures", "Fig. 10",
            "Temperatures (°C) of the {sensors} over experiment {first}{first_feed}. Warmest on "
            "average: {warmest}; smallest change: {steadiest}. {data}",
            rows=("Table 6", "Section 3.1: three most frequent sensitive points "
                             "(point-by-point inputs)")),
    FIG11,
    Caption("fig12_slope_intercept", "Fig. 12",
            "Slope k (µm/m) and intercept b (µm) of the straight line fitted to every "
            "measurement (Eq. 6), positions counted from the first target, {experiments} of "
            "{measurements} each; lines ours. {data}", rows=("Table 5",)),
    FIG14, FIG15, FIG16, FIG17,
    Caption("beyond_leave_one_experiment_out", "Beyond the paper",
            "RMSE of the error (µm, pooled over positions and measurements) when each "
            "experiment in turn is predicted from models trained on the others: point-by-point "
            "MLR, decoupled MLR and decoupled SVR, {panels}. {wins} {data}"),
    Caption("beyond_selection_vs_baselines", "Beyond the paper",
            "The same held-out experiments against two baselines, no compensation and a ridge "
            "regression of k and b on all {all_sensors}, beside the paper's three models "
            "{with_points}; the last group pools every held-out experiment. Pooled RMSE (µm): "
            "{pooled}. {data}"),
)

#: ``{data}`` of a caption on the paper's reconstruction (default: the first entry).
ON_RECONSTRUCTION = {
    "": "Reconstructed data, not the paper's measurements.",
    "fig03_ambient_temperature":
        "Reconstructed data, not the paper's measurements: the generator moves the air "
        "monotonically across Table 1's ambient range of each experiment, up in experiments 1 "
        "and 2 and down in 3 and 4, so the minima and maxima match Table 1 by construction.",
    "fig05_error_vs_position":
        "Reconstructed data, not the paper's measurements: built so that each measurement's "
        "straight-line fit is Table 5's. The scorecard's largest-error row concerns experiment "
        "{test} (Fig. 9).",
    "fig10_temperatures":
        "Reconstructed data, not the paper's measurements, the sensors at the locations of the "
        "paper's Table 2 (screw sleeve, sliders, bearing seat, motor housing and interior, bed, "
        "nut, air); the sensitive points chosen from such histories of the training experiments "
        "are scored against the paper's Tables 3 and 6.",
    "fig12_slope_intercept":
        "Diamonds: the paper's Table 5. They agree by construction: the reconstructed data were "
        "built from Table 5's lines, so this checks the pipeline, not the paper.",
    "fig15_mlr_error_prediction":
        "Reconstructed data, built so that the printed Eq. 9 misses experiment 4 by Table 7's "
        "residuals.",
    "beyond_leave_one_experiment_out":
        "Reconstructed data, not the paper's measurements, built around the paper's points.",
}
#: ``{data}`` of a caption on any other data.
ON_OWN_DATA = ("Measured data from data_dir, not the paper's reconstruction: nothing here is "
               "compared with the paper.")


def caption(name: str, reconstructed: bool, **values) -> Caption:
    """A figure's caption (:data:`FIGURES`) with its fields filled, saying what the data are.

    Parameters
    ----------
    name : str
        The figure's file name (a key of :data:`FIGURES`).
    reconstructed : bool
        Whether the data are the paper's reconstruction (:data:`ON_RECONSTRUCTION`), or any
        other (:data:`ON_OWN_DATA`).
    **values
        The caption's numbers (:func:`data_fields`, :func:`model_fields`, ...); unused ones are
        ignored.

    Returns
    -------
    Caption
        Ready for ``run.figure``.
    """
    note = (ON_RECONSTRUCTION.get(name, ON_RECONSTRUCTION[""]) if reconstructed
            else ON_OWN_DATA).format(**values)
    return FIGURES[name].format(**{**values, "data": note})
