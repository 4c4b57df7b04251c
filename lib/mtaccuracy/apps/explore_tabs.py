"""The explorer's Spindle and Thermal tabs (:mod:`mtaccuracy.apps.explore` serves them).

Spindle: per harmonic, what a probe layout does, for least squares and the weighted method.
Thermal: notebook 04's split, the decoupled model (MLR or SVR, fitted off the event loop with its
progress shown) against the measured error.  Every number from
:mod:`~mtaccuracy.apps.explore_model`.
"""

from __future__ import annotations

import asyncio
import html

import numpy as np
import panel as pn
import param
from bokeh import models as bm
from bokeh.palettes import Plasma256
from bokeh.plotting import figure

from .. import thermal
from ..compendium import provenance
from ..papers import xu2022, yang2021, your_spindle
from ..spindle import probefile
from . import explore_files as EF
from . import explore_model as M
from .explore_ui import (
    BLUE,
    ORANGE,
    RED,
    block,
    csv_button,
    error_html,
    file_box,
    file_status,
    guarded,
    new_figure,
    note,
    number_check,
    option_check,
    wrap,
)

# -- Spindle tab -----------------------------------------------------------------------------------

_PRESETS = {f"Yang et al. 2021 (samples {', '.join(map(str, M.YANG_POSITIONS))} of "
            f"{M.YANG_SAMPLES})": M.YANG_DEG,
            "four probes equally spaced": (0.0, 90.0, 180.0, 270.0)}
_YANG, _YOURS = yang2021.Parameters, your_spindle.Parameters


def _angle(i: int):
    return param.Number(M.YANG_DEG[i - 1], bounds=(M.ANGLE_BOUNDS[0], M.ANGLE_BOUNDS[1] - 0.1),
                        step=0.1, label=f"probe {i} angle (°)")


class SpindleTab(param.Parameterized):
    """What a probe layout does to each harmonic, for both estimators."""

    layout = param.Selector(objects=[*_PRESETS, "custom"], label="Layout")
    probe2, probe3, probe4 = _angle(2), _angle(3), _angle(4)
    max_harmonic = param.Integer(_YANG.param["worst_k"].default, bounds=M.HARMONIC_BOUNDS,
                                 label="highest harmonic")
    weights = param.Selector(objects={"optimal (layout_weights)": "optimal",
                                      "Eq. 5 with a3": "eq5"}, default="optimal")
    a3 = param.Number(M.YANG_A3, bounds=_YANG.param["a3"].bounds, step=0.001, label="a3 (Eq. 5)")
    amplified_above = param.Number(_YOURS.param["amplified_above"].default,
                                   bounds=M.AMPLIFIED_BOUNDS, step=0.5,
                                   label="amplified when q_k above")
    refused = param.String("", doc="why the last value sent by the page was refused")
    file_error = param.String("", doc="the reader's message on the last probe file")
    file_read = param.String("", doc="what the last probe file gave")

    def refuse(self, message: str) -> None:
        """Show why a value from the page was refused ("": clear the message)."""
        self.refused = message

    def load_probes(self, names, contents) -> None:
        """A probe file uploaded: read as notebook 07 reads it; its layout shown (probe 1 at 0)."""
        p = _YOURS.defaults()
        up = EF.read_upload(names, contents, lambda path: probefile.read_probe_file(
            path, max_harmonic=p["max_harmonic"] or None, allow_cancelled=p["allow_cancelled"]))
        data, name = up.result, up.names[0] if up.names else "the file"
        error = up.message
        if not error and data.angles_deg.size != 4:
            error = (f"{name}: {data.angles_deg.size} probes; this tab shows four-probe layouts "
                     f"(notebook 07 separates any layout: make reproduce NB=07)")
        rel = None if error else (np.asarray(data.angles_deg, float) - data.angles_deg[0]) % 360
        if rel is not None and rel.max() > self.param.probe2.bounds[1]:
            error = (f"{name}: a probe at {rel.max():g} deg from probe 1, beyond this tab's "
                     f"{self.param.probe2.bounds[1]:g} deg")
        if error:
            self.param.update(file_error=error, file_read="")
            return
        k = int(min(max(data.max_harmonic, M.HARMONIC_BOUNDS[0]), M.HARMONIC_BOUNDS[1]))
        self.param.update(probe2=float(rel[1]), probe3=float(rel[2]), probe4=float(rel[3]),
                          max_harmonic=k, file_error="", file_read=(
                              f"{name}: probes at {', '.join(f'{a:g}' for a in data.angles_deg)}"
                              f" deg, {data.revolutions.size} revolution(s) of "
                              f"{data.sample_deg.size} samples; shown from probe 1 (at 0 deg)"
                              + "".join(f"; {w}" for w in up.warnings)))

    def transfer(self) -> M.ProbeTransfer:
        """The model at the controls' values (probe 1 at 0 deg); a ValueError if refused."""
        return M.probe_transfer([0.0, self.probe2, self.probe3, self.probe4],
                                self.max_harmonic, self.weights, self.a3, self.amplified_above)

    @param.depends("layout", watch=True)
    def _preset(self) -> None:
        if self.layout in _PRESETS:
            self.param.update(dict(zip(("probe2", "probe3", "probe4"), _PRESETS[self.layout][1:],
                                       strict=True)))

    @param.depends("probe2", "probe3", "probe4", watch=True)
    def _custom(self) -> None:
        now = (self.probe2, self.probe3, self.probe4)
        self.layout = next((n for n, a in _PRESETS.items() if np.allclose(a[1:], now, atol=1e-9)),
                           "custom")

    @param.depends("probe2", "probe3", "probe4", "max_harmonic", "weights", "a3",
                   "amplified_above")
    def plots(self):
        """The summary, ``q_k`` per harmonic and the probe directions; a bad layout: its message."""
        try:
            t = self.transfer()
        except ValueError as exc:
            return pn.pane.HTML(error_html(str(exc)), sizing_mode="stretch_width")
        ks = t.harmonics

        def fmt(q):
            return "inf (cancelled)" if not np.isfinite(q) else f"{q:.3f}"

        def status(j):
            if t.cancelled[j]:
                return "cancelled by the layout: no estimator recovers it"
            if t.cancelled_by_weights[j]:
                return "cancelled by the weights (least squares recovers it)"
            who = [n for n, a in (("least squares", t.amplified_least_squares[j]),
                                  ("weighted", t.amplified_weighted[j])) if a]
            return f"amplified ({', '.join(who)})" if who else ""

        common = dict(k=ks.tolist(), q_ls=[fmt(q) for q in t.q_least_squares],
                      q_w=[fmt(q) for q in t.q_weighted], gain=t.gain_weighted.tolist(),
                      status=[status(j) for j in range(ks.size)])
        finite = np.concatenate([t.q_least_squares[np.isfinite(t.q_least_squares)],
                                 t.q_weighted[np.isfinite(t.q_weighted)], [t.amplified_above]])
        top = float(finite.max()) * 1.6
        fig = new_figure("What the layout does to each harmonic", max_width=640,
                      height=400, y_axis_type="log", x_axis_label="harmonic k",
                      y_axis_label="noise amplification q_k",
                      y_range=bm.Range1d(float(finite.min()) / 1.6, top * 1.6))
        cut = np.flatnonzero(t.cancelled | t.cancelled_by_weights)
        cut_src = bm.ColumnDataSource(dict({c: [common[c][j] for j in cut] for c in common},
                                           x0=(ks[cut] - 0.5).tolist(),
                                           x1=(ks[cut] + 0.5).tolist(), y=[top] * cut.size))
        fig.vstrip(x0="x0", x1="x1", source=cut_src, fill_color=RED, fill_alpha=0.18,
                   line_color=None)
        hover = [fig.scatter(x="k", y="y", source=cut_src, marker="x", size=11, color=RED,
                             line_width=2, legend_label="cancelled")]
        for q, colour, marker, name in ((t.q_least_squares, BLUE, "circle", "least squares"),
                                        (t.q_weighted, ORANGE, "square",
                                         "weighted (Yang et al. 2021)")):
            src = bm.ColumnDataSource(dict(common, q=np.where(np.isfinite(q), q, np.nan).tolist()))
            fig.line(x="k", y="q", source=src, color=colour, line_width=1.5, legend_label=name)
            hover.append(fig.scatter(x="k", y="q", source=src, color=colour, size=6,
                                     marker=marker, legend_label=name))
        fig.add_layout(bm.Span(location=t.amplified_above, dimension="width",
                               line_dash="dashed", line_color="#555"))
        fig.select_one(bm.HoverTool).update(renderers=hover, tooltips=[
            ("k", "@k"), ("q least squares", "@q_ls"), ("q weighted", "@q_w"),
            ("weighted gain |Lambda_k|/||a||", "@gain{0.0000}"), ("", "@status")])
        fig.legend.update(orientation="horizontal", label_text_font_size="8pt")
        fig.add_layout(fig.legend[0], "below")

        phi = np.deg2rad(t.angles_deg)
        w = t.weights if t.weights is not None else np.full(phi.shape, np.nan)
        probes = bm.ColumnDataSource(dict(x=np.cos(phi), y=np.sin(phi), angle=t.angles_deg,
                                          weight=[f"{v:.4f}" for v in np.round(w, 4) + 0.0],
                                          name=[f"{i + 1}" for i in range(phi.size)]))
        dirs = figure(width=300, height=300, tools="hover", toolbar_location=None,
                      x_range=bm.Range1d(-1.35, 1.35), y_range=bm.Range1d(-1.35, 1.35),
                      title="Probe directions")
        dirs.circle(x=0, y=0, radius=1.0, fill_color=None, line_color="#999")
        dirs.segment(x0=0, y0=0, x1="x", y1="y", source=probes, line_width=2, color=BLUE)
        rp = dirs.scatter(x="x", y="y", source=probes, size=10, color=BLUE)
        dirs.text(x="x", y="y", text="name", source=probes, x_offset=6, y_offset=-4,
                  text_font_size="9pt")
        dirs.select_one(bm.HoverTool).update(renderers=[rp], tooltips=[
            ("probe", "@name"), ("angle", "@angle{0.000} deg"), ("weight", "@weight")])
        dirs.axis.visible = dirs.grid.visible = False

        def listed(mask):
            return ", ".join(str(int(k)) for k in ks[mask]) or "none"

        def worst(q):
            f = np.isfinite(q)
            return f"{q[f].max():.3f} at k = {int(ks[f][np.argmax(q[f])])}" if f.any() else "-"

        weights = ("none (every harmonic is cancelled)" if t.weights is None
                   else ", ".join(f"{v:.4f}" for v in np.round(t.weights, 4) + 0.0))
        summary = (
            f'<div class="mt-note" data-role="spindle-summary">'
            f"<b>Harmonics 2..{int(ks[-1])}.</b> Cancelled by the layout: "
            f"<b>{listed(t.cancelled)}</b>. Cancelled by the weights only: "
            f"{listed(t.cancelled_by_weights)}.<br>Amplified (q_k &gt; {t.amplified_above:g}): "
            f"least squares {listed(t.amplified_least_squares)}; weighted "
            f"{listed(t.amplified_weighted)}.<br>Worst q_k: least squares "
            f"{worst(t.q_least_squares)}; weighted {worst(t.q_weighted)}. Weights of "
            f"probes 1..{phi.size} (a_0..a_{phi.size - 1} in Yang et al.): {weights}.</div>")
        return wrap(block(pn.pane.HTML(summary, sizing_mode="stretch_width"), fig, basis=360),
                    block(dirs, note(
            "q_k: how much the separation multiplies white probe noise at harmonic k (the "
            "weighted method's error transfer function, Eqs. 14, 19; least squares: the "
            "Gauss-Markov variance). Red: the layout cancels the harmonic, no estimator "
            "recovers it.", width=300)))

    def view(self):
        """The tab: controls and the plots."""
        p, w = self.param, pn.widgets

        def guard(widget, name, *, integer=False, unit=""):
            par = p[name]
            return guarded(widget, number_check(par.label, *par.bounds, unit=unit,
                                                  integer=integer), self.refuse)

        def probe(i):          # a slider and a number box, the same parameter and bounds
            return pn.Row(
                guard(w.FloatSlider.from_param(p[f"probe{i}"], width=195,
                                               css_classes=[f"probe-{i}"]), f"probe{i}",
                      unit=" deg"),
                guard(w.FloatInput.from_param(p[f"probe{i}"], name="", width=85,
                                              css_classes=[f"probe-{i}-input"]),
                      f"probe{i}", unit=" deg"))

        layout = w.Select.from_param(p.layout, width=290)
        return wrap(pn.Column(
            guarded(layout, option_check(layout), self.refuse),
            pn.pane.HTML(p.refused.rx.pipe(error_html), width=290),
            note("Probe 1 sits at 0 deg: it defines the x axis."),
            *(probe(i) for i in (2, 3, 4)),
            guard(w.IntSlider.from_param(p.max_harmonic, width=280), "max_harmonic",
                  integer=True),
            pn.pane.HTML("<b>Weighted method</b>"),
            guarded(w.RadioButtonGroup.from_param(p.weights, width=280), lambda v: v,
                     self.refuse),
            guard(w.FloatSlider.from_param(p.a3, width=280, format="0.000",
                                           visible=p.weights.rx() == "eq5"), "a3"),
            guard(w.FloatSlider.from_param(p.amplified_above, width=280), "amplified_above"),
            csv_button("harmonics (CSV)", "spindle_harmonics.csv",
                       lambda: M.probe_table(self.transfer()), width=140),
            note("Your probe file (notebook 07's: revolution, angle_deg, probe_&lt;angle&gt;_um):"),
            file_box("probe-file", self.load_probes, self.refuse),
            pn.pane.HTML(pn.rx(file_status)(p.file_error, p.file_read), width=290),
            width=310), block(self.plots, basis=360, max_width=1000))


# -- Thermal tab -----------------------------------------------------------------------------------

class ThermalTab(param.Parameterized):
    """The decoupled model (Eq. 9) fitted on chosen experiments, predicting another."""

    train = param.ListSelector(default=[], objects=[], label="training experiments")
    test = param.Selector(objects=[], label="test experiment")
    inputs = param.Selector(objects={"paper's sensors": "published",
                                     "selected on training data": "selected"})
    kind = param.Selector(objects={"MLR": "mlr", "SVR (about 2 s)": "svr"}, default="mlr")
    status = param.String("", doc="what the fit is doing")
    busy = param.Boolean(False, doc="a fit runs")
    result = param.Parameter(doc="the last prediction, or the library's message")
    refused = param.String("", doc="why the last value sent by the page was refused")
    file_error = param.String("", doc="the reader's message on the last thermal files")
    source = param.String("", doc="where the data shown come from, in words")

    def refuse(self, message: str) -> None:
        """Show why a value from the page was refused ("": clear the message)."""
        self.refused = message

    def _use(self, data, reconstructed: bool) -> None:
        """Show ``data``: notebook 04's split when it applies, else the last experiment tested."""
        self.data, self.reconstructed = data, reconstructed
        exps = [int(e) for e in data.experiments]
        try:
            start = M.thermal_defaults(data, reconstructed)          # notebook 04's
        except ValueError:
            start = {"train": exps[:-1], "test": exps[-1], "inputs": "published"}
        self.param.train.objects, self.param.test.objects = exps, exps
        shown = html.escape(provenance.shown(data.source))
        self.param.update(start, source=f"Data: {shown}" + (
            " - the paper's reconstruction (data/thermal/README.md), not measurements."
            if reconstructed else " - not the paper's reconstruction: no comparison with the "
            "paper."))

    def load_files(self, names, contents) -> None:
        """Thermal files uploaded together: read as notebook 04 reads its ``data_dir``."""
        up = EF.read_upload(names, contents, thermal.read_measurements, folder=True)
        if up.message:
            self.file_error = up.message
            return
        self.file_error = ""
        self._use(up.result, False)

    def _csv(self):
        if not isinstance(self.result, M.ThermalPrediction):
            raise ValueError("no prediction to export")
        return M.thermal_table(self.result)

    def __init__(self, **params):
        super().__init__(**params)
        self._use(*M.thermal_data())

    @param.depends("train", "test", "inputs", "kind", watch=True)
    async def _fit(self) -> None:
        """Refit off the event loop (the SVR takes seconds); only the latest request is drawn."""
        ticket, doc = object(), pn.state.curdoc
        self._ticket = ticket

        def show(**values):     # from the loop or the fitting thread: under the document's lock
            def apply():
                if self._ticket is ticket:
                    self.param.update(values)
            if doc is not None and doc.session_context is not None:
                doc.add_next_tick_callback(apply)
            else:
                apply()
        show(busy=True, status="fitting...")
        try:
            r = await asyncio.to_thread(M.thermal_prediction, self.data, train=self.train,
                                        test=self.test, inputs=self.inputs, kind=self.kind,
                                        progress=lambda text: show(status=text))
        except ValueError as exc:
            r = str(exc)
        show(result=r, busy=False, status="" if isinstance(r, str) else "done")

    @param.depends("result")
    def plots(self):
        """The prediction against the measurement, with its RMSE; the library's message."""
        r = self.result
        if r is None or isinstance(r, str):
            return pn.pane.HTML(error_html(r or ""), sizing_mode="stretch_width")
        n, p = r.measured.shape
        src = bm.ColumnDataSource(dict(
            x=np.tile(r.positions_mm, n), y=r.measured.ravel(), pred=r.predicted.ravel(),
            res=(r.measured - r.predicted).ravel(), t=np.repeat(r.time_min, p),
            m=np.repeat(r.measurement, p)))
        colours = {"field": "t", "transform": bm.LinearColorMapper(
            palette=Plasma256[:220], low=float(r.time_min.min()),
            high=float(r.time_min.max()) + 1e-9)}
        curves = new_figure("Measured (dots), predicted (lines)", max_width=600,
                         height=380, x_axis_label="position (mm)",
                         y_axis_label="thermal error (µm)")
        curves.multi_line(xs="xs", ys="ys", line_width=1.6, line_color=colours,
                          source=bm.ColumnDataSource(dict(xs=[r.positions_mm] * n,
                                                       ys=list(r.predicted), t=r.time_min)))
        rm = curves.scatter(x="x", y="y", source=src, size=6, color=colours)
        curves.select_one(bm.HoverTool).update(renderers=[rm], tooltips=[
            ("measurement", "@m"), ("time", "@t{0} min"), ("position", "@x mm"),
            ("measured", "@y{0.000} µm"), ("predicted", "@pred{0.000} µm"),
            ("residual", "@res{0.000} µm")])
        scatter = new_figure("Predicted against measured", max_width=400, height=380,
                          x_axis_label="measured (µm)", y_axis_label="predicted (µm)")
        lo = float(min(r.measured.min(), r.predicted.min()))
        hi = float(max(r.measured.max(), r.predicted.max()))
        scatter.line(x=[lo, hi], y=[lo, hi], color="#777", line_dash="dashed")
        rs = scatter.scatter(x="y", y="pred", source=src, size=5, alpha=0.8, color=colours)
        scatter.select_one(bm.HoverTool).update(renderers=[rs], tooltips=[
            ("measurement", "@m"), ("position", "@x mm"), ("measured", "@y{0.000} µm"),
            ("predicted", "@pred{0.000} µm")])
        label = xu2022.RECONSTRUCTED_LABEL if self.reconstructed else ""
        summary = (
            f'<div class="mt-note" data-role="thermal-summary" data-rmse="{r.rmse:.6f}">'
            f"Decoupled {r.kind.upper()} trained on experiment(s) "
            f"{', '.join(map(str, r.train))}, predicting experiment {r.test}: "
            f"<b>RMSE {r.rmse:.3f} µm</b> (pooled over {n} measurements x {p} positions), "
            f"largest residual {r.max_residual:.3f} µm; without compensation the RMSE is "
            f"{r.rmse_uncompensated:.3f} µm.<br>Inputs: k from {', '.join(r.inputs['k'])} "
            f"(temperatures), b from {', '.join(r.inputs['b'])} (rises from the first "
            f"measurement)." + (f'<br><span style="color:{RED};font-weight:bold">{label}</span>'
                                if label else "") + "</div>")
        return pn.Column(pn.pane.HTML(summary, sizing_mode="stretch_width"),
                         wrap(block(curves, basis=360), block(scatter, basis=300, max_width=420)),
                         sizing_mode="stretch_width")

    def view(self):
        """The tab: controls, status, and the prediction against the measurement."""
        p, w = self.param, pn.widgets
        test = w.Select.from_param(p.test, width=140)

        def accept(value):
            return value
        return wrap(pn.Column(
            pn.pane.HTML("<b>Training experiments</b>"),
            guarded(w.CheckBoxGroup.from_param(p.train, inline=True), accept, self.refuse),
            guarded(test, option_check(test), self.refuse),
            pn.pane.HTML(p.refused.rx.pipe(error_html), width=290),
            pn.pane.HTML("<b>Model inputs</b> (Eq. 9: k from temperatures, b from rises)"),
            guarded(w.RadioButtonGroup.from_param(p.inputs, width=290), accept, self.refuse),
            pn.pane.HTML("<b>Decoupled model</b> (Xu et al. 2022, Eq. 9)"),
            guarded(w.RadioButtonGroup.from_param(p.kind, width=290), accept, self.refuse),
            csv_button("prediction (CSV)", "thermal_prediction.csv", self._csv, width=140),
            pn.Row(pn.indicators.LoadingSpinner(value=p.busy, visible=p.busy, size=22),
                   pn.pane.HTML(p.status.rx.pipe(lambda s: f'<div class="mt-note">'
                                                 f'{html.escape(s)}</div>'), width=260)),
            pn.pane.HTML(p.source.rx.pipe(lambda s: f'<div class="mt-note">{s}</div>'),
                         width=290),
            note("Your measurements (notebook 04's data_dir: temperatures.csv and errors.csv, "
                 "experiments.csv if any; choose them together):"),
            file_box("thermal-files", self.load_files, self.refuse, multiple=True),
            pn.pane.HTML(p.file_error.rx.pipe(error_html), width=290), width=310),
            block(self.plots, basis=360, max_width=1100))
