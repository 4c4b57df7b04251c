"""An interactive explorer of the compendium's three topics, in the browser, on 127.0.0.1.

Run ``make explore`` (``EXPLORE_ARGS="--port N"``) or ``python -m mtaccuracy.apps.explore
[--port N] [--show/--no-show]``: it serves the app on ``127.0.0.1`` only (port 0, the default,
picks a free one), prints the URL and runs until Ctrl-C.  Every starting value (error ranges,
poses, probe layout, data, split) is the default its notebook declares (``Parameters`` in
:mod:`mtaccuracy.papers`).  Three tabs:

Machine
    One of the papers' three machines (Zheng et al. 2024's AC double turntable, Rong et al.'s
    horizontal machining centre, Guo et al. 2016's vertical XYFZ) or any topology typed in
    (:func:`mtaccuracy.machines.iso.iso_machine`; a topology the library refuses shows the
    library's message).  Sliders set the pose and the two error ranges; the closed-form Sobol
    indices of the first-order model at that pose (errors x outputs, a heat map) and the
    error with the largest index over a 25 x 25 grid of two chosen axes update at every slider
    move: 9-23 ms of computing on the 2-core machine, batched over the grid (``make bench``,
    row ``explore_update``), and about 50-70 ms from the key press to the new numbers in the
    page (Panel's 50 ms server-side debounce is cut to :data:`DEBOUNCE_MS` for these
    widgets).
Spindle
    Probe angles (notebook 05's, Yang et al. 2021's four-point layout) and, per harmonic, the
    noise amplification of the two estimators of :mod:`mtaccuracy.spindle.probes` (least
    squares, and the weighted multi-point method), the harmonics the layout cancels and those
    it amplifies.
Thermal
    Notebook 04's train/test split on its ``data_dir``: the decoupled model of Xu et al. 2022
    (Eq. 9, MLR or SVR) predicts the test experiment's thermal error, shown against the
    measured one with its RMSE; the SVR (about 2 s) shows a spinner and its progress.

What is computed is in :mod:`mtaccuracy.apps.explore_model` (plain functions, tested
without a browser); this module only draws it.

Why Panel (HoloViz): it is a standard app framework of the Jupyter ecosystem; an app is a
plain Python module served with ``pn.serve`` (here) or ``panel serve``; the same app runs
inside a Jupyter server, and so on Binder, through Panel's Jupyter server extension
(``panel-preview``: ``?urlpath=panel-preview/render/binder/explore.ipynb``, the notebook
``binder/explore.ipynb`` calls :func:`create_app`); and its plots are Bokeh's, which show the
values under the mouse (hover) natively.  Panel serves its own JavaScript and CSS: the page
loads nothing from outside 127.0.0.1.

Safety: the server listens on ``127.0.0.1`` only (:func:`check_address` refuses any other
address, ``0.0.0.0`` included) and accepts websocket connections only from pages served at
``127.0.0.1:<port>`` or ``localhost:<port>``.

Local imports: Panel and Bokeh (seconds to import) are imported by the functions that build
the app, so that the model, the bench and the tests import this module at once.
"""

from __future__ import annotations

import argparse
import asyncio
import functools
import html
import os
import shlex
import socket
import sys
import time

import numpy as np

from ..compendium import provenance
from ..compendium.plotting import unit_symbol
from ..papers import xu2022
from . import explore_model as M

#: The only address the explorer listens on.
LOOPBACK = "127.0.0.1"
#: Colours: a blue, the figures' orange of published values (``plotting.PUBLISHED``), a red for
#: what a layout cancels, a grey for no first-order term.
BLUE, ORANGE, RED, GREY = "#1b6ca8", "#d95f02", "#b2182b", "#cccccc"
_CSS = """
.mt-note {font-size: 12px; color: #555; line-height: 1.35;}
.mt-error {background: #fde8e8; border: 1px solid #b2182b; color: #7a1020; padding: 6px 9px;
           border-radius: 4px; font-size: 12.5px; white-space: pre-wrap;}
table.mt-top {border-collapse: collapse; font-size: 12.5px;}
table.mt-top td, table.mt-top th {padding: 2px 8px; border-bottom: 1px solid #e3e3e3;
                                  text-align: left;}
"""


def _palette(n: int) -> list[str]:
    from bokeh.palettes import Category20

    base = Category20[20][0::2] + Category20[20][1::2]     # ten distinct hues first
    return [base[i % 20] for i in range(n)]


def _note(text: str, **kw):
    import panel as pn

    return pn.pane.HTML(f'<div class="mt-note">{text}</div>', **kw)


#: Milliseconds Panel waits after a widget's change reaches the server before it acts on it
#: (``Syncable._debounce``, 50 ms by default, to gather a burst of changes).  The Machine tab's
#: widgets use 5 ms: its update takes 10-40 ms, during which further changes gather anyway.
DEBOUNCE_MS = 5


def _prompt(widget):
    """Act on ``widget``'s changes after :data:`DEBOUNCE_MS` instead of Panel's 50 ms."""
    widget._debounce = DEBOUNCE_MS
    return widget


def _unlocked(method):
    """Run a widget callback inside ``pn.io.unlocked()``: it changes Bokeh models (sources,
    ranges), which Bokeh allows only under the document's lock, and Panel runs some callbacks
    without it (a text input's Enter key); outside a server it does nothing."""
    @functools.wraps(method)
    def run(*args, **kwargs):
        import panel as pn

        with pn.io.unlocked():
            return method(*args, **kwargs)
    return run


def _error_html(message: str) -> str:
    return f'<div class="mt-error" data-role="error">{html.escape(message)}</div>'


# ------------------------------------------------------------------------------------------
# Machine tab
# ------------------------------------------------------------------------------------------

class MachineTab:
    """Closed-form Sobol indices at a pose and the dominant-error map of a machine."""

    def __init__(self):
        import panel as pn
        from bokeh.models import (
            CategoricalColorMapper,
            ColorBar,
            ColumnDataSource,
            FactorRange,
            HoverTool,
            LinearColorMapper,
            Range1d,
        )
        from bokeh.palettes import Viridis256
        from bokeh.plotting import figure

        self._quiet = False
        self.setup = M.machine_setup("ac_double_turntable")
        options = {label: key for key, label in M.MACHINES.items()}
        options["a topology typed below"] = M.TOPOLOGY
        self.machine = pn.widgets.Select(label="Machine", options=options,
                                         value="ac_double_turntable", width=290)
        self.topology = pn.widgets.TextInput(
            label="Topology (workpiece to tool, then Enter)", placeholder="w C b X Y Z B t",
            width=290)
        self.error = pn.pane.HTML("", width=290, visible=False)
        self.notes = pn.pane.HTML("", width=290)
        self.pose_box = pn.Column(width=300)
        self.position = pn.widgets.FloatSlider(label="position-error half range (µm)",
                                               start=0.1, end=100.0, step=0.1, width=280,
                                               css_classes=["range-position"])
        self.angular = pn.widgets.FloatSlider(label="angular-error half range (arcsec)",
                                              start=0.1, end=100.0, step=0.1, width=280,
                                              css_classes=["range-angular"])
        self.map_u = pn.widgets.Select(label="map: axis across", width=90)
        self.map_v = pn.widgets.Select(label="axis up", width=90)
        self.map_out = pn.widgets.Select(label="output", width=90)
        self.status = pn.pane.HTML("", width=290)
        self.top = pn.pane.HTML("", width=460)

        # heat map: errors (rows) x outputs (columns)
        self.heat_src = ColumnDataSource(dict(error=[], output=[], index=np.zeros(0), label=[],
                                              text_color=[], note=[]))
        self.mapper = mapper = LinearColorMapper(palette=Viridis256, low=0.0, high=1.0,
                                                 nan_color=GREY)
        self.heat = figure(x_range=FactorRange(), y_range=FactorRange(), width=430, height=700,
                           tools="hover,save", toolbar_location="above",
                           title="Sobol indices at the pose (closed form)",
                           x_axis_location="above")
        r = self.heat.rect(x="output", y="error", width=0.96, height=0.92, source=self.heat_src,
                           fill_color={"field": "index", "transform": mapper},
                           line_color=None)
        self.heat.text(x="output", y="error", text="label", source=self.heat_src,
                       text_align="center", text_baseline="middle", text_font_size="7.5pt",
                       text_color="text_color")
        self.heat.select_one(HoverTool).update(
            renderers=[r], tooltips=[("error", "@error"), ("output", "@output"),
                                     ("index", "@index{0.0000}"), ("", "@note")])
        self.heat.add_layout(ColorBar(color_mapper=mapper, width=10, title="index"), "right")
        self.heat.grid.visible = False
        self.heat.axis.major_tick_line_color = None
        self.heat.yaxis.major_label_text_font_size = "8pt"

        # dominant-error map
        # numbers go as numpy arrays (binary on the websocket), colours by a mapper
        self.map_src = ColumnDataSource(dict(u=np.zeros(0), v=np.zeros(0), error=[],
                                             index=np.zeros(0)))
        self.colours = CategoricalColorMapper(factors=["-"], palette=[GREY])
        self.dmap = figure(width=560, height=430, tools="hover,save", toolbar_location="above",
                           x_range=Range1d(0, 1), y_range=Range1d(0, 1))
        rm = self.dmap.rect(x="u", y="v", width=1.0, height=1.0, source=self.map_src,
                            fill_color={"field": "error", "transform": self.colours},
                            line_color=None, legend_field="error")
        self.map_glyph = rm.glyph
        self.dmap.select_one(HoverTool).update(
            renderers=[rm], tooltips=[("error", "@error"), ("index", "@index{0.0000}"),
                                      ("at", "@u{0.0}, @v{0.0}")])
        self.here = ColumnDataSource(dict(u=[], v=[]))
        self.dmap.scatter(x="u", y="v", source=self.here, marker="circle_x", size=14,
                          fill_color="white", fill_alpha=0.6, line_color="black", line_width=1.5)
        self.dmap.add_layout(self.dmap.legend[0], "right")
        self.dmap.legend.label_text_font_size = "8pt"
        self.dmap.legend.glyph_height = 12
        self.dmap.legend.spacing = 0
        self.dmap.grid.visible = False

        self.machine.param.watch(self._on_machine, "value")
        self.topology.param.watch(self._on_topology, "value")
        for w in (self.position, self.angular, self.map_u, self.map_v, self.map_out):
            _prompt(w)
            w.param.watch(self._on_change, "value")
        self._load(self.setup)

        controls = pn.Column(
            self.machine, self.topology, self.error, self.notes,
            pn.pane.HTML("<b>Pose</b>"), self.pose_box,
            pn.pane.HTML("<b>Error ranges</b> (uniform)"), self.position, self.angular,
            _note("Each slider sets the largest half range of its group; the errors the "
                  "notebook gives smaller ranges keep their ratio to it."),
            pn.Row(self.map_u, self.map_v, self.map_out), self.status, width=310)
        self.view = pn.Row(
            controls,
            pn.Column(self.top, self.heat),
            pn.Column(_note("Dominant error: the error with the largest closed-form index at "
                            "each pose of a 25 x 25 grid over the two axes chosen, the other "
                            "axes at their slider values; grey: the output has no first-order "
                            "term there; the circle marks the pose of the sliders.", width=540),
                      self.dmap))

    # -- building ----------------------------------------------------------------------------
    def _load(self, setup: M.MachineSetup) -> None:
        """Show ``setup``: new pose sliders, the notebook's ranges, the map's choices."""
        import panel as pn

        self.setup = setup
        self._quiet = True
        try:
            sliders = []
            for a in setup.axes:
                step = 1.0 if a.rotary or a.high - a.low > 50 else 0.1
                s = pn.widgets.FloatSlider(label=f"{a.name} ({unit_symbol(a.unit)})",
                                           start=a.low, end=a.high, value=a.default,
                                           step=step, width=280, css_classes=[f"pose-{a.name}"])
                _prompt(s)
                s.param.watch(self._on_change, "value")
                sliders.append(s)
            self.sliders = sliders
            self.pose_box.objects = sliders
            self.position.value = min(max(setup.position_um, 0.1), 100.0)
            self.angular.value = min(max(setup.angular_arcsec, 0.1), 100.0)
            names = [a.name for a in setup.axes]
            u, v = M.default_map_axes(setup)
            self.map_u.options, self.map_v.options = names, names
            self.map_u.value, self.map_v.value = u, v
            self.map_out.options = setup.outputs
            self.map_out.value = setup.outputs[0]
            self.notes.object = ('<div class="mt-note">' + "<br>".join(
                html.escape(n) for n in setup.notes) + "</div>")
            rows = list(reversed(setup.names))
            self.heat.y_range.factors = rows
            self.heat.x_range.factors = setup.outputs
            self.heat.height = 110 + 15 * len(rows)
        finally:
            self._quiet = False
        self.update()

    @_unlocked
    def _on_machine(self, event) -> None:
        if self._quiet:
            return
        if event.new == M.TOPOLOGY:
            if self.topology.value.strip():
                self._on_topology(None)
            return
        self.error.visible = False
        self._load(M.machine_setup(event.new))

    @_unlocked
    def _on_topology(self, event) -> None:
        text = self.topology.value
        if not text.strip():
            return
        try:
            setup = M.topology_setup(text)
        except Exception as exc:     # the library's message, never a traceback
            message = str(exc) if isinstance(exc, ValueError | TypeError) \
                else f"{type(exc).__name__}: {exc}"
            self.error.object = _error_html(message)
            self.error.visible = True
            return
        self.error.visible = False
        self._quiet = True
        self.machine.value = M.TOPOLOGY
        self._quiet = False
        self._load(setup)

    @_unlocked
    def _on_change(self, event) -> None:
        if not self._quiet:
            self.update()

    # -- computing and drawing ---------------------------------------------------------------
    def pose_values(self) -> dict:
        """The pose sliders' values (mm, deg) by axis name."""
        return {a.name: float(s.value) for a, s in zip(self.setup.axes, self.sliders,
                                                        strict=True)}

    def update(self) -> None:
        """Recompute the indices and the map at the sliders' values and redraw both."""
        t0 = time.perf_counter()
        setup = self.setup
        axes = (self.map_u.value, self.map_v.value)
        res, dmap = M.slider_update(setup, self.pose_values(), axes=axes,
                                    position_um=self.position.value,
                                    angular_arcsec=self.angular.value)
        t_compute = time.perf_counter() - t0
        self._draw_heat(res)
        self._draw_map(dmap)
        self._draw_top(res)
        ms = (time.perf_counter() - t0) * 1e3
        self.status.object = (f'<div class="mt-note" data-role="timing">computed in '
                              f'{t_compute * 1e3:.0f} ms, drawn in {ms:.0f} ms (server side)'
                              f'</div>')

    def _draw_heat(self, res: M.PoseIndices) -> None:
        d, q = res.indices.shape
        idx = res.indices.astype(float).copy()
        idx[:, ~res.first_order] = np.nan
        flat = idx.ravel()                                          # error-major
        errors = np.repeat(res.names, q).tolist()
        outputs = list(res.outputs) * d
        high = max(float(np.nanmax(flat, initial=0.0)), 0.05)
        self.mapper.high = high                    # the colours span the indices at this pose
        label = ["" if not np.isfinite(v) or v < 0.01 else f"{v:.2f}" for v in flat]
        colour = ["black" if np.isfinite(v) and v > 0.6 * high else "white" for v in flat]
        note = ["no first-order term at this pose" if not res.first_order[k] else ""
                for _ in range(d) for k in range(q)]
        self.heat_src.data = dict(error=errors, output=outputs, index=flat,
                                  label=label, text_color=colour, note=note)

    def _draw_map(self, dmap: M.DominantMap) -> None:
        k = dmap.outputs.index(self.map_out.value) if self.map_out.value in dmap.outputs else 0
        err = dmap.error[:, :, k].ravel()
        present = np.unique(err)                               # sorted: catalogue order
        label = np.array([dmap.names[j] if j >= 0 else "no first-order term"
                          for j in present])
        colours = _palette(int((present >= 0).sum()))
        self.colours.update(factors=label.tolist(),
                            palette=([GREY] if present[0] < 0 else []) + colours)
        uu, vv = np.meshgrid(dmap.u, dmap.v, indexing="xy")
        du = (dmap.u[-1] - dmap.u[0]) / (len(dmap.u) - 1)
        dv = (dmap.v[-1] - dmap.v[0]) / (len(dmap.v) - 1)
        if dmap.axes[0] == dmap.axes[1]:
            dv = du
        self.map_glyph.update(width=du, height=dv)
        self.map_src.data = dict(u=uu.ravel(), v=vv.ravel(),
                                 error=label[np.searchsorted(present, err)].tolist(),
                                 index=dmap.index[:, :, k].ravel())
        a1, a2 = (self.setup.axis(a) for a in dmap.axes)
        pose = self.pose_values()
        self.here.data = dict(u=[pose[a1.name]], v=[pose[a2.name]])     # the pose itself
        self.dmap.x_range.update(start=dmap.u[0] - du / 2, end=dmap.u[-1] + du / 2)
        self.dmap.y_range.update(start=dmap.v[0] - dv / 2, end=dmap.v[-1] + dv / 2)
        self.dmap.xaxis.axis_label = f"{a1.name} ({unit_symbol(a1.unit)})"
        self.dmap.yaxis.axis_label = f"{a2.name} ({unit_symbol(a2.unit)})"
        self.dmap.title.text = f"Dominant error for {dmap.outputs[k]}"

    def _draw_top(self, res: M.PoseIndices) -> None:
        rows = []
        top = {o: (e, v) for o, e, v in M.top_errors(res)}
        for o in res.outputs:
            if o in top:
                e, v = top[o]
                rows.append(f'<tr data-role="top-error" data-output="{o}" data-error='
                            f'"{html.escape(e)}" data-index="{v:.6f}"><td>{o}</td>'
                            f'<td><b>{html.escape(e)}</b></td><td>{v:.4f}</td></tr>')
            else:
                rows.append(f'<tr data-role="top-error" data-output="{o}" data-error="" '
                            f'data-index=""><td>{o}</td><td colspan="2">no first-order term '
                            f'at this pose</td></tr>')
        self.top.object = ('<table class="mt-top"><tr><th>output</th><th>top error</th>'
                           '<th>index</th></tr>' + "".join(rows) + "</table>")


# ------------------------------------------------------------------------------------------
# Spindle tab
# ------------------------------------------------------------------------------------------

class SpindleTab:
    """What a probe layout does to each harmonic, for both estimators."""

    PRESETS = {(f"Yang et al. 2021 (samples {', '.join(map(str, M.YANG_POSITIONS))} of "
                f"{M.YANG_SAMPLES})"): tuple(M.yang_layout_deg()),
               "four probes equally spaced": (0.0, 90.0, 180.0, 270.0)}

    def __init__(self):
        import panel as pn
        from bokeh.models import ColumnDataSource, HoverTool, Range1d, Span
        from bokeh.plotting import figure

        self._quiet = False
        first = next(iter(self.PRESETS))
        self.preset = pn.widgets.Select(label="Layout", options=list(self.PRESETS) + ["custom"],
                                        value=first, width=290)
        self.angles = [pn.widgets.EditableFloatSlider(
            label=f"probe {i + 1} angle (°)", start=0.0, end=359.9, step=0.1,
            value=float(self.PRESETS[first][i]), width=280, css_classes=[f"probe-{i + 1}"])
            for i in range(1, 4)]
        self.max_k = pn.widgets.IntSlider(label="highest harmonic", start=3, end=100, value=20,
                                          width=280)
        self.rule = pn.widgets.RadioButtonGroup(
            label="weights", options={"optimal (layout_weights)": "optimal",
                                      "Eq. 5 with a3": "eq5"}, value="optimal", width=280)
        self.a3 = pn.widgets.FloatSlider(label="a3 (Eq. 5)", start=-10.0, end=10.0, step=0.001,
                                         value=M.YANG_A3, width=280, visible=False,
                                         format="0.000")
        self.above = pn.widgets.FloatSlider(label="amplified when q_k above", start=1.5, end=20.0,
                                            step=0.5, value=3.0, width=280)
        self.error = pn.pane.HTML("", width=290, visible=False)
        self.summary = pn.pane.HTML("", width=560)

        self.ls_src = ColumnDataSource(dict(k=[], q=[], q_ls=[], q_w=[], gain=[], status=[]))
        self.w_src = ColumnDataSource(dict(k=[], q=[], q_ls=[], q_w=[], gain=[], status=[]))
        self.cut_src = ColumnDataSource(dict(k=[], x0=[], x1=[], y=[], status=[], q_ls=[],
                                                q_w=[], gain=[]))
        self.fig = figure(width=640, height=400, y_axis_type="log", tools="hover,save",
                          y_range=Range1d(0.1, 10.0),
                          toolbar_location="above", x_axis_label="harmonic k",
                          y_axis_label="noise amplification q_k",
                          title="What the layout does to each harmonic of the profile")
        self.fig.vstrip(x0="x0", x1="x1", source=self.cut_src, fill_color=RED, fill_alpha=0.18,
                        line_color=None)
        rc = self.fig.scatter(x="k", y="y", source=self.cut_src, marker="x", size=11,
                              color=RED, line_width=2, legend_label="cancelled")
        self.fig.line(x="k", y="q", source=self.ls_src, color=BLUE, line_width=1.5,
                      legend_label="least squares")
        c1 = self.fig.scatter(x="k", y="q", source=self.ls_src, color=BLUE, size=6,
                              legend_label="least squares")
        self.fig.line(x="k", y="q", source=self.w_src, color=ORANGE, line_width=1.5,
                      legend_label="weighted (Yang et al. 2021)")
        c2 = self.fig.scatter(x="k", y="q", source=self.w_src, color=ORANGE, size=6,
                              marker="square", legend_label="weighted (Yang et al. 2021)")
        self.span = Span(location=3.0, dimension="width", line_dash="dashed", line_color="#555")
        self.fig.add_layout(self.span)
        self.fig.select_one(HoverTool).update(
            renderers=[c1, c2, rc],
            tooltips=[("k", "@k"), ("q least squares", "@q_ls"), ("q weighted", "@q_w"),
                      ("weighted gain |Lambda_k|/||a||", "@gain{0.0000}"), ("", "@status")])
        self.fig.legend.orientation = "horizontal"
        self.fig.legend.label_text_font_size = "8pt"
        self.fig.add_layout(self.fig.legend[0], "below")

        self.probe_src = ColumnDataSource(dict(x=[], y=[], x0=[], y0=[], angle=[], weight=[],
                                               name=[]))
        self.layout_fig = figure(width=300, height=300, tools="hover", toolbar_location=None,
                                 x_range=Range1d(-1.35, 1.35), y_range=Range1d(-1.35, 1.35),
                                 title="Probe directions")
        self.layout_fig.circle(x=0, y=0, radius=1.0, fill_color=None, line_color="#999")
        self.layout_fig.segment(x0="x0", y0="y0", x1="x", y1="y", source=self.probe_src,
                                line_width=2, color=BLUE)
        rp = self.layout_fig.scatter(x="x", y="y", source=self.probe_src, size=10, color=BLUE)
        self.layout_fig.text(x="x", y="y", text="name", source=self.probe_src, x_offset=6,
                             y_offset=-4, text_font_size="9pt")
        self.layout_fig.select_one(HoverTool).update(
            renderers=[rp], tooltips=[("probe", "@name"), ("angle", "@angle{0.000} deg"),
                                      ("weight", "@weight")])
        self.layout_fig.axis.visible = False
        self.layout_fig.grid.visible = False

        self.preset.param.watch(self._on_preset, "value")
        for w in (*self.angles, self.max_k, self.rule, self.a3, self.above):
            w.param.watch(self._on_change, "value")
        self.update()

        controls = pn.Column(
            self.preset, _note("Probe 1 sits at 0 deg: it defines the x axis."), *self.angles,
            self.max_k, pn.pane.HTML("<b>Weighted method</b>"), self.rule, self.a3, self.above,
            self.error, width=310)
        self.view = pn.Row(controls, pn.Column(self.summary, self.fig),
                           pn.Column(self.layout_fig, _note(
                               "q_k: how much the separation multiplies white probe noise "
                               "at harmonic k (the weighted method's error transfer "
                               "function, Eqs. 14, 19; least squares: the Gauss-Markov "
                               "variance). Red: the layout cancels the harmonic, no "
                               "estimator recovers it.", width=300)))

    @_unlocked
    def _on_preset(self, event) -> None:
        if event.new not in self.PRESETS:
            return
        self._quiet = True
        for s, v in zip(self.angles, self.PRESETS[event.new][1:], strict=True):
            s.value = float(v)
        self._quiet = False
        self.update()

    @_unlocked
    def _on_change(self, event) -> None:
        if self._quiet:
            return
        if event.obj in self.angles:
            now = tuple(float(s.value) for s in self.angles)
            match = next((n for n, p in self.PRESETS.items()
                          if np.allclose(p[1:], now, atol=1e-9)), "custom")
            self._quiet = True
            self.preset.value = match
            self._quiet = False
        self.a3.visible = self.rule.value == "eq5"
        self.update()

    def update(self) -> None:
        """Recompute the transfer of every harmonic and redraw."""
        self.span.location = float(self.above.value)
        angles = [0.0] + [float(s.value) for s in self.angles]
        try:
            t = M.probe_transfer(angles, max_harmonic=int(self.max_k.value),
                                 weights=self.rule.value, a3=float(self.a3.value),
                                 amplified_above=float(self.above.value))
        except ValueError as exc:
            self.error.object = _error_html(str(exc))
            self.error.visible = True
            for src in (self.ls_src, self.w_src, self.cut_src):
                src.data = {k: [] for k in src.data}
            self.summary.object = ""
            return
        self.error.visible = False
        ks = t.harmonics

        def fmt(q):
            return "inf (cancelled)" if not np.isfinite(q) else f"{q:.3f}"

        status = []
        for j in range(ks.size):
            if t.cancelled[j]:
                status.append("cancelled by the layout: no estimator recovers it")
            elif t.cancelled_by_weights[j]:
                status.append("cancelled by the weights (least squares recovers it)")
            elif t.amplified_least_squares[j] or t.amplified_weighted[j]:
                who = [n for n, a in (("least squares", t.amplified_least_squares[j]),
                                      ("weighted", t.amplified_weighted[j])) if a]
                status.append(f"amplified ({', '.join(who)})")
            else:
                status.append("")
        common = dict(k=ks.tolist(), q_ls=[fmt(q) for q in t.q_least_squares],
                      q_w=[fmt(q) for q in t.q_weighted], gain=t.gain_weighted.tolist(),
                      status=status)
        self.ls_src.data = dict(common, q=np.where(np.isfinite(t.q_least_squares),
                                                   t.q_least_squares, np.nan).tolist())
        self.w_src.data = dict(common, q=np.where(np.isfinite(t.q_weighted), t.q_weighted,
                                                  np.nan).tolist())
        finite = np.concatenate([t.q_least_squares[np.isfinite(t.q_least_squares)],
                                 t.q_weighted[np.isfinite(t.q_weighted)], [t.amplified_above]])
        top = float(finite.max()) * 1.6
        self.fig.y_range.update(start=float(finite.min()) / 1.6, end=top * 1.6)
        cut = np.flatnonzero(t.cancelled | t.cancelled_by_weights)
        self.cut_src.data = dict({c: [common[c][j] for j in cut] for c in common},
                                 x0=(ks[cut] - 0.5).tolist(), x1=(ks[cut] + 0.5).tolist(),
                                 y=[top] * cut.size)
        phi = np.deg2rad(t.angles_deg)
        w = t.weights if t.weights is not None else np.full(phi.shape, np.nan)
        self.probe_src.data = dict(x=np.cos(phi).tolist(), y=np.sin(phi).tolist(),
                                   x0=[0.0] * phi.size, y0=[0.0] * phi.size,
                                   angle=t.angles_deg.tolist(),
                                   weight=[f"{v:.4f}" for v in np.round(w, 4) + 0.0],
                                   name=[f"{i + 1}" for i in range(phi.size)])

        def listed(mask):
            return ", ".join(str(int(k)) for k in ks[mask]) or "none"

        def worst(q):
            f = np.isfinite(q)
            return f"{q[f].max():.3f} at k = {int(ks[f][np.argmax(q[f])])}" if f.any() else "-"

        weights = ("none (every harmonic is cancelled)" if t.weights is None
                   else ", ".join(f"{v:.4f}" for v in np.round(t.weights, 4) + 0.0))
        self.summary.object = (
            f'<div class="mt-note" data-role="spindle-summary">'
            f"<b>Harmonics 2..{int(ks[-1])}.</b> Cancelled by the layout: "
            f"<b>{listed(t.cancelled)}</b>. Cancelled by the weights only: "
            f"{listed(t.cancelled_by_weights)}.<br>"
            f"Amplified (q_k &gt; {t.amplified_above:g}): least squares "
            f"{listed(t.amplified_least_squares)}; weighted {listed(t.amplified_weighted)}.<br>"
            f"Worst q_k: least squares {worst(t.q_least_squares)}; weighted "
            f"{worst(t.q_weighted)}. Weights a_0..a_{phi.size - 1}: {weights}.</div>")


# ------------------------------------------------------------------------------------------
# Thermal tab
# ------------------------------------------------------------------------------------------

class ThermalTab:
    """The decoupled model (Eq. 9) fitted on chosen experiments, predicting another."""

    def __init__(self):
        import panel as pn
        from bokeh.models import ColumnDataSource, HoverTool, LinearColorMapper
        from bokeh.palettes import Plasma256
        from bokeh.plotting import figure

        self.data, self.reconstructed = M.thermal_data()
        self._doc = pn.state.curdoc          # the session's document (None outside a server)
        self.label = xu2022.RECONSTRUCTED_LABEL if self.reconstructed else ""
        exps = [int(e) for e in self.data.experiments]
        start = M.thermal_defaults(self.data, self.reconstructed)  # notebook 04's declaration
        self._generation = 0
        self.train = pn.widgets.CheckBoxGroup(label="training experiments", options=exps,
                                              value=start["train"], inline=True)
        self.test = pn.widgets.Select(label="test experiment", options=exps,
                                      value=start["test"], width=140)
        self.inputs = pn.widgets.RadioButtonGroup(
            label="inputs", options={"paper's sensors": "published",
                                    "selected on training data": "selected"},
            value=start["inputs"], width=290)
        self.kind = pn.widgets.RadioButtonGroup(
            label="model", options={"MLR": "mlr", "SVR (about 2 s)": "svr"}, value="mlr",
            width=290)
        self.spinner = pn.indicators.LoadingSpinner(value=False, size=22, visible=False)
        self.status = pn.pane.HTML("", width=260)
        self.error = pn.pane.HTML("", width=290, visible=False)
        self.summary = pn.pane.HTML("", width=620)

        self.mapper = LinearColorMapper(palette=Plasma256[:220], low=0, high=1)
        self.meas_src = ColumnDataSource(dict(x=[], y=[], pred=[], res=[], t=[], m=[]))
        self.pred_src = ColumnDataSource(dict(xs=[], ys=[], t=[], m=[]))
        self.curves = figure(width=560, height=380, tools="hover,save", toolbar_location="above",
                             x_axis_label="position (mm)", y_axis_label="thermal error (µm)",
                             title="Test experiment: measured (dots), predicted (lines)")
        self.curves.multi_line(xs="xs", ys="ys", source=self.pred_src, line_width=1.6,
                               line_color={"field": "t", "transform": self.mapper})
        rm = self.curves.scatter(x="x", y="y", source=self.meas_src, size=6,
                                 color={"field": "t", "transform": self.mapper})
        self.curves.select_one(HoverTool).update(
            renderers=[rm], tooltips=[("measurement", "@m"), ("time", "@t{0} min"),
                                      ("position", "@x mm"), ("measured", "@y{0.000} µm"),
                                      ("predicted", "@pred{0.000} µm"),
                                      ("residual", "@res{0.000} µm")])
        self.scatter = figure(width=380, height=380, tools="hover,save", toolbar_location="above",
                              x_axis_label="measured (µm)", y_axis_label="predicted (µm)",
                              title="Predicted against measured")
        self.diag = ColumnDataSource(dict(x=[0, 1], y=[0, 1]))
        self.scatter.line(x="x", y="y", source=self.diag, color="#777", line_dash="dashed")
        rs = self.scatter.scatter(x="y", y="pred", source=self.meas_src, size=5, alpha=0.8,
                                  color={"field": "t", "transform": self.mapper})
        self.scatter.select_one(HoverTool).update(
            renderers=[rs], tooltips=[("measurement", "@m"), ("position", "@x mm"),
                                      ("measured", "@y{0.000} µm"),
                                      ("predicted", "@pred{0.000} µm")])

        for w in (self.train, self.test, self.inputs, self.kind):
            w.param.watch(self._on_change, "value")
        self._fit_now()

        controls = pn.Column(
            pn.pane.HTML("<b>Training experiments</b>"), self.train, self.test,
            pn.pane.HTML("<b>Model inputs</b> (Eq. 9: k from temperatures, b from rises)"),
            self.inputs, pn.pane.HTML("<b>Decoupled model</b> (Xu et al. 2022, Eq. 9)"),
            self.kind, pn.Row(self.spinner, self.status), self.error,
            _note(f"Data: {html.escape(provenance.shown(self.data.source))}"
                  + (" - the paper's reconstruction (data/thermal/README.md), not "
                     "measurements." if self.reconstructed else " - not the paper's "
                     "reconstruction: no comparison with the paper.")), width=310)
        self.view = pn.Row(controls, pn.Column(self.summary, pn.Row(self.curves,
                                                                    self.scatter)))

    def _args(self) -> dict:
        return dict(train=list(self.train.value), test=int(self.test.value),
                    inputs=self.inputs.value, kind=self.kind.value)

    def _fit_now(self) -> None:
        try:
            self._show(M.thermal_prediction(self.data, **self._args()))
        except ValueError as exc:
            self._fail(str(exc))

    def _fail(self, message: str) -> None:
        self.error.object = _error_html(message)
        self.error.visible = True
        self.summary.object = ""
        self.meas_src.data = {k: [] for k in self.meas_src.data}
        self.pred_src.data = {k: [] for k in self.pred_src.data}

    async def _on_change(self, event) -> None:
        """Refit off the event loop (the SVR takes seconds) with a spinner and its progress;
        only the latest request is drawn."""
        self._generation += 1
        gen = self._generation
        args = self._args()
        self.spinner.visible, self.spinner.value = True, True
        self.status.object = '<div class="mt-note">fitting...</div>'

        def progress(text):
            if gen == self._generation:
                self.status.object = f'<div class="mt-note">{html.escape(text)}</div>'
        try:
            res = await asyncio.to_thread(M.thermal_prediction, self.data, progress=progress,
                                          **args)
        except ValueError as exc:
            self._in_document(gen, self._fail, str(exc), "")
            return
        self._in_document(gen, self._show, res, "done")

    def _in_document(self, gen: int, draw, arg, status: str) -> None:
        """Draw the result of request ``gen`` (if it is still the latest) holding the
        document's lock: Bokeh models may change only in a callback the document runs."""
        def run():
            if gen == self._generation:
                draw(arg)
                self._done(status)
        doc = self._doc
        if doc is not None and doc.session_context is not None:
            doc.add_next_tick_callback(run)
        else:
            run()

    def _done(self, text: str) -> None:
        self.spinner.value, self.spinner.visible = False, False
        self.status.object = f'<div class="mt-note">{text}</div>' if text else ""

    def _show(self, r: M.ThermalPrediction) -> None:
        self.error.visible = False
        n, p = r.measured.shape
        t = np.repeat(r.time_min, p)
        self.mapper.update(low=float(r.time_min.min()), high=float(r.time_min.max()) + 1e-9)
        self.meas_src.data = dict(x=np.tile(r.positions_mm, n).tolist(),
                                  y=r.measured.ravel().tolist(),
                                  pred=r.predicted.ravel().tolist(),
                                  res=(r.measured - r.predicted).ravel().tolist(),
                                  t=t.tolist(), m=np.repeat(r.measurement, p).tolist())
        self.pred_src.data = dict(xs=[r.positions_mm.tolist()] * n,
                                  ys=r.predicted.tolist(), t=r.time_min.tolist(),
                                  m=r.measurement.tolist())
        lo = float(min(r.measured.min(), r.predicted.min()))
        hi = float(max(r.measured.max(), r.predicted.max()))
        self.diag.data = dict(x=[lo, hi], y=[lo, hi])
        self.summary.object = (
            f'<div class="mt-note" data-role="thermal-summary" data-rmse="{r.rmse:.6f}">'
            f"Decoupled {r.kind.upper()} trained on experiment(s) "
            f"{', '.join(map(str, r.train))}, predicting experiment {r.test}: "
            f"<b>RMSE {r.rmse:.3f} µm</b> (pooled over {n} measurements x {p} positions), "
            f"largest residual {r.max_residual:.3f} µm; without compensation the RMSE is "
            f"{r.rmse_uncompensated:.3f} µm.<br>Inputs: k from "
            f"{', '.join(r.inputs['k'])} (temperatures), b from {', '.join(r.inputs['b'])} "
            f"(rises from the first measurement)."
            + (f'<br><span style="color:{RED};font-weight:bold">{self.label}</span>'
               if self.label else "") + "</div>")


# ------------------------------------------------------------------------------------------
# The app and the server
# ------------------------------------------------------------------------------------------

def create_app():
    """The explorer: three tabs (Machine, Spindle, Thermal).

    Returns
    -------
    panel.viewable.Viewable
        Serve it (:func:`serve`, ``panel serve``) or show it in a notebook; each call builds a
        new, independent app (one per browser session).
    """
    import panel as pn

    pn.extension(raw_css=[_CSS])
    machine, spindle, thermal = MachineTab(), SpindleTab(), ThermalTab()
    header = pn.pane.HTML(
        "<h2 style='margin:4px 0'>mtaccuracy explorer</h2><div class='mt-note'>Closed-form "
        "sensitivity of the papers' machines, what a probe layout does to each harmonic, and "
        "the thermal model of notebook 04. Hover over a plot for its values.</div>")
    tabs = pn.Tabs(("Machine", machine.view), ("Spindle", spindle.view),
                   ("Thermal", thermal.view), dynamic=False)
    app = pn.Column(header, tabs, sizing_mode="stretch_width")
    app.tabs = {"machine": machine, "spindle": spindle, "thermal": thermal}
    return app


def check_address(address: str) -> str:
    """Refuse any address but 127.0.0.1: the explorer serves this machine only.

    Never ``0.0.0.0``, ``::``, a host name or a LAN address.

    Parameters
    ----------
    address : str
        The address asked for.

    Returns
    -------
    str
        ``"127.0.0.1"``.

    Raises
    ------
    ValueError
        For any other address.
    """
    if address != LOOPBACK:
        raise ValueError(f"the explorer listens on {LOOPBACK} only, not {address!r}: reach it "
                         f"from elsewhere through an SSH tunnel")
    return address


def free_port() -> int:
    """A port free on 127.0.0.1 right now (the system picks it).

    Returns
    -------
    int
    """
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind((LOOPBACK, 0))
        return int(s.getsockname()[1])


def serve(*, port: int = 0, address: str = LOOPBACK, show: bool = False):
    """A Bokeh/Panel server of :func:`create_app` on 127.0.0.1, not yet started.

    The websocket accepts only pages from ``127.0.0.1:<port>`` and ``localhost:<port>``.

    Parameters
    ----------
    port : int
        0..65535; 0 picks a free port.
    address : str
        Must be ``"127.0.0.1"`` (:func:`check_address`).
    show : bool
        Open the page in the default browser once the server runs.

    Returns
    -------
    server : bokeh.server.server.Server
        ``server.start(); server.io_loop.start()`` runs it.
    url : str
        ``http://127.0.0.1:<port>/``.
    """
    import panel as pn

    check_address(address)
    if isinstance(port, bool) or not isinstance(port, int) or not 0 <= port <= 65535:
        raise ValueError(f"port must be an integer in 0..65535, got {port!r}")
    for attempt in range(5):
        chosen = port or free_port()
        try:
            server = pn.serve(create_app, port=chosen, address=LOOPBACK,
                              websocket_origin=[f"{LOOPBACK}:{chosen}", f"localhost:{chosen}"],
                              show=show, start=False, verbose=False,
                              title="mtaccuracy explorer")
            break
        except OSError:
            if port or attempt == 4:       # a port asked for is taken; or no luck, 5 times
                raise
    return server, f"http://{LOOPBACK}:{chosen}/"


def main(argv=None) -> int:
    """``python -m mtaccuracy.apps.explore [--port N] [--show/--no-show]``.

    Parameters
    ----------
    argv : list of str, optional
        Arguments (default ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit status.
    """
    ap = argparse.ArgumentParser(prog="python -m mtaccuracy.apps.explore",
                                 description="Serve the mtaccuracy explorer on 127.0.0.1.")
    ap.add_argument("--port", type=int, default=0,
                    help="port on 127.0.0.1 (default 0: a free one)")
    ap.add_argument("--show", action=argparse.BooleanOptionalAction, default=False,
                    help="open the page in the default browser (default: --no-show)")
    ap.add_argument("--from-env", action="store_true",
                    help="take further arguments from $EXPLORE_ARGS (make explore), split like "
                         "a shell would, never evaluated by one")
    argv = list(sys.argv[1:] if argv is None else argv)
    if "--from-env" in argv:
        try:
            argv += shlex.split(os.environ.get("EXPLORE_ARGS", ""))
        except ValueError as exc:
            print(f"explore: EXPLORE_ARGS cannot be split: {exc}", file=sys.stderr)
            return 2
    args = ap.parse_args(argv)
    try:
        server, url = serve(port=args.port, show=args.show)
    except (ValueError, OSError) as exc:
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else exc
        print(f"explore: cannot serve on {LOOPBACK}:{args.port}: {reason}", file=sys.stderr)
        return 2
    print(f"mtaccuracy explorer: {url}  (127.0.0.1 only; Ctrl-C stops it)", flush=True)
    server.start()
    try:
        server.io_loop.start()
    except KeyboardInterrupt:
        pass
    print("explore: stopped", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
