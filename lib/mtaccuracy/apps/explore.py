"""An interactive explorer of the compendium's three topics, in the browser, on 127.0.0.1.

``make explore`` (``EXPLORE_ARGS="--port N"``) or ``python -m mtaccuracy.apps.explore [--port N]
[--show]`` serves it on 127.0.0.1 only (port 0, the default: a free one), prints the URL and runs
until Ctrl-C; ``binder/explore.ipynb`` shows it on Binder (Panel's Jupyter server extension,
``?urlpath=panel-preview/render/binder/explore.ipynb``).  Each tab is a ``param.Parameterized``:
its parameters are the controls (Panel builds the widgets), its ``@param.depends`` methods
redraw; every start is a notebook's declared default (``Parameters``, :mod:`mtaccuracy.papers`);
the numbers come from :mod:`mtaccuracy.apps.explore_model`.

Machine: a paper's machine or a typed topology; the closed-form Sobol indices at the pose of the
sliders (heat map, top error per output) and the dominant error over two chosen axes, redrawn in
place at every move (``make bench``, row ``explore_update``).  Spindle: per harmonic, what a probe
layout cancels and amplifies, for least squares and the weighted method.  Thermal: notebook 04's
split, the decoupled model (MLR or SVR, fitted off the event loop with its progress shown)
against the measured error.

The server listens on 127.0.0.1 only (:func:`check_address`), its websocket accepts pages from
``127.0.0.1:<port>`` and ``localhost:<port>`` only, and Panel serves its own JavaScript and CSS.
Every value the page sends is checked on the server before Panel applies it (:func:`_guarded`,
the bounds of :mod:`~mtaccuracy.apps.explore_model`): a refused one is shown as a message.
"""

from __future__ import annotations

import argparse
import asyncio
import html
import io
import os
import shlex
import socket
import sys
import time

import numpy as np
import panel as pn
import param
from bokeh import models as bm
from bokeh.palettes import Plasma256, Viridis256
from bokeh.plotting import figure

from ..compendium import provenance
from ..compendium.plotting import category_colours, unit_symbol
from ..papers import xu2022, yang2021, your_spindle
from . import explore_model as M

#: The only address the explorer listens on.
LOOPBACK = "127.0.0.1"
#: A blue, the figures' orange of published values, a red: cancelled, a grey: no first order.
BLUE, ORANGE, RED, GREY = "#1b6ca8", "#d95f02", "#b2182b", "#cccccc"
_CSS = """
.mt-note {font-size: 12px; color: #555; line-height: 1.35;}
.mt-error {background: #fde8e8; border: 1px solid #b2182b; color: #7a1020; padding: 6px 9px;
           border-radius: 4px; font-size: 12.5px; white-space: pre-wrap;}
table.mt-top {border-collapse: collapse; font-size: 12.5px;}
table.mt-top td, table.mt-top th {padding: 2px 8px; border-bottom: 1px solid #e3e3e3;
                                  text-align: left;}
"""


def _note(text: str, **kw):
    return pn.pane.HTML(f'<div class="mt-note">{text}</div>', **kw)


def _error_html(message: str) -> str:
    return f'<div class="mt-error" data-role="error">{html.escape(message)}</div>' \
        if message else ""


def _prompt(widget):
    """Act on the widget's changes after 5 ms, not Panel's 50: the Machine tab's update is fast."""
    widget._debounce = 5
    return widget


def _guarded(widget, check, refuse):
    """``widget`` whose browser values pass ``check`` on the server before Panel applies them.

    A message from the page (or a crafted one) setting ``value`` goes through ``check`` first
    (:func:`mtaccuracy.apps.explore_model.checked_number` and the like): a refused value is never
    applied, ``refuse`` gets the message to show in the app (no traceback on the server) and the
    page gets the server's value back; an accepted one calls ``refuse("")`` (clears it).
    """
    process = widget._process_events

    def guarded(events):
        events = dict(events)
        try:
            for key in ("value", "value_throttled"):
                if key in events:
                    events[key] = check(events[key])
            if "active" in events:             # a button or check box group: option indices
                n, active = len(widget.options), events["active"]
                many = isinstance(active, list | tuple)
                if not all(isinstance(i, int) and not isinstance(i, bool) and 0 <= i < n
                           for i in (active if many else [active])):
                    raise ValueError(f"{widget.name or 'a choice'}: {active!r} is not a "
                                     f"choice of 0..{n - 1}")
        except ValueError as exc:
            refuse(str(exc))
            widget.param.trigger("value")           # the page shows the server's value again
            return
        refuse("")
        process(events)

    widget._process_events = guarded
    return widget


def _number_check(name: str, low: float, high: float, *, unit: str = "",
                  integer: bool = False):
    def check(value):
        return M.checked_number(value, name, low=low, high=high, unit=unit, integer=integer)
    return check


def _option_check(widget):
    """Accept only one of ``widget``'s labels (a list of them for a multiple choice)."""
    def check(value):
        labels = [str(v) for v in (widget.labels if hasattr(widget, "labels")
                                   else widget.options)]
        many = isinstance(value, list | tuple)
        if not all(isinstance(v, str) and v in labels for v in (value if many else [value])):
            raise ValueError(f"{widget.name or 'a choice'}: {value!r} is not one of "
                             f"{', '.join(labels)}")
        return value
    return check


def _csv_button(label: str, filename: str, frame, **kw):
    """A download of ``frame()`` (a DataFrame, computed at the click) as ``filename``."""
    return pn.widgets.FileDownload(callback=lambda: io.StringIO(M.to_csv(frame())),
                                   filename=filename, label=label, embed=False, **kw)


def _figure(title: str, **kw):
    return figure(title=title, tools="hover,save", toolbar_location="above", **kw)


# -- Machine tab -----------------------------------------------------------------------------------

class MachineTab(param.Parameterized):
    """Closed-form Sobol indices at a pose and the dominant-error map of a machine."""

    machine = param.Selector(objects={**{v: k for k, v in M.MACHINES.items()},
                                      "a topology typed below": M.TOPOLOGY},
                             default="ac_double_turntable", label="Machine")
    topology = param.String("", label="Topology (workpiece to tool, then Enter)")
    position_um = param.Number(1.0, bounds=M.RANGE_BOUNDS, step=0.1,
                               label="position-error half range (µm)")
    angular_arcsec = param.Number(1.0, bounds=M.RANGE_BOUNDS, step=0.1,
                                  label="angular-error half range (arcsec)")
    across = param.Selector(objects=[], label="map: axis across")
    up = param.Selector(objects=[], label="axis up")
    output = param.Selector(objects=[], label="output")
    setup = param.Parameter(doc="the machine shown (explore_model.MachineSetup)")
    pose = param.Parameter(doc="the pose sliders: a Parameterized with one number per axis")
    error = param.String("", doc="the library's message on the last topology typed")
    refused = param.String("", doc="why the last value sent by the page was refused")

    def __init__(self, **params):
        super().__init__(**params)
        self.top, self.status = pn.pane.HTML("", width=460), pn.pane.HTML("", width=290)
        self.result = None                     # the last PoseIndices shown (the CSV exports)
        # heat map: errors (rows) x outputs (columns)
        self.heat_src = bm.ColumnDataSource(dict(error=[], output=[], index=[], label=[],
                                                 text_color=[], note=[]))
        self.heat_colours = bm.LinearColorMapper(palette=Viridis256, low=0.0, high=1.0,
                                                 nan_color=GREY)
        self.heat = _figure("Sobol indices at the pose (closed form)", x_range=bm.FactorRange(),
                            y_range=bm.FactorRange(), width=430, height=700,
                            x_axis_location="above")
        r = self.heat.rect(x="output", y="error", width=0.96, height=0.92, line_color=None,
                           source=self.heat_src,
                           fill_color={"field": "index", "transform": self.heat_colours})
        self.heat.text(x="output", y="error", text="label", source=self.heat_src,
                       text_align="center", text_baseline="middle", text_font_size="7.5pt",
                       text_color="text_color")
        self.heat.select_one(bm.HoverTool).update(
            renderers=[r], tooltips=[("error", "@error"), ("output", "@output"),
                                     ("index", "@index{0.0000}"), ("", "@note")])
        self.heat.add_layout(bm.ColorBar(color_mapper=self.heat_colours, width=10, title="index"),
                             "right")
        self.heat.grid.visible, self.heat.axis.major_tick_line_color = False, None
        self.heat.yaxis.major_label_text_font_size = "8pt"
        # dominant-error map: numbers as arrays (binary on the websocket), colours by a mapper
        self.map_src = bm.ColumnDataSource(dict(u=[], v=[], error=[], index=[]))
        self.map_colours = bm.CategoricalColorMapper(factors=["-"], palette=[GREY])
        self.dmap = _figure("", width=560, height=430, x_range=bm.Range1d(0, 1),
                            y_range=bm.Range1d(0, 1))
        rm = self.dmap.rect(x="u", y="v", width=1.0, height=1.0, source=self.map_src,
                            fill_color={"field": "error", "transform": self.map_colours},
                            line_color=None, legend_field="error")
        self.map_glyph = rm.glyph
        self.dmap.select_one(bm.HoverTool).update(
            renderers=[rm], tooltips=[("error", "@error"), ("index", "@index{0.0000}"),
                                      ("at", "@u{0.0}, @v{0.0}")])
        self.here = bm.ColumnDataSource(dict(u=[], v=[]))      # the pose of the sliders
        self.dmap.scatter(x="u", y="v", source=self.here, marker="circle_x", size=14,
                          fill_color="white", fill_alpha=0.6, line_color="black", line_width=1.5)
        self.dmap.add_layout(self.dmap.legend[0], "right")
        self.dmap.legend.update(label_text_font_size="8pt", glyph_height=12, spacing=0)
        self.dmap.grid.visible = False
        self._load(M.machine_setup(self.machine))

    def _load(self, setup: M.MachineSetup) -> None:
        """Show ``setup``: new pose sliders, the notebook's ranges, the map's choices."""
        names = [a.name for a in setup.axes]
        self.param.across.objects, self.param.up.objects = names, list(names)
        self.param.output.objects = setup.outputs
        pose = param.parameterized_class("Pose", {a.name: param.Number(
            a.default, bounds=(a.low, a.high), label=f"{a.name} ({unit_symbol(a.unit)})",
            step=1.0 if a.rotary or a.high - a.low > 50 else 0.1) for a in setup.axes})()
        pose.param.watch(self.update, [a.name for a in setup.axes])
        across, up = M.default_map_axes(setup)
        self.param.update(setup=setup, pose=pose, error="", across=across, up=up,
                          output=setup.outputs[0],
                          position_um=min(max(setup.position_um, M.RANGE_BOUNDS[0]),
                                          M.RANGE_BOUNDS[1]),
                          angular_arcsec=min(max(setup.angular_arcsec, M.RANGE_BOUNDS[0]),
                                             M.RANGE_BOUNDS[1]))

    @param.depends("machine", watch=True)
    def _chosen(self) -> None:
        if self.machine != M.TOPOLOGY:
            self._load(M.machine_setup(self.machine))
        elif self.setup.key != M.TOPOLOGY:
            self._typed()

    @param.depends("topology", watch=True)
    def _typed(self) -> None:
        if not self.topology.strip():
            return
        try:
            setup = M.topology_setup(self.topology)
        except Exception as exc:     # the library's message, never a traceback
            self.error = str(exc) if isinstance(exc, ValueError) else f"{type(exc).__name__}: {exc}"
            return
        self._load(setup)
        self.machine = M.TOPOLOGY

    def refuse(self, message: str) -> None:
        """Show why a value from the page was refused ("": clear the message)."""
        self.refused = message

    def pose_values(self) -> dict:
        """The pose sliders' values (mm, deg) by axis."""
        return {a.name: float(getattr(self.pose, a.name)) for a in self.setup.axes}

    @param.depends("pose", "position_um", "angular_arcsec", "across", "up",
                   "output", watch=True)
    def update(self, *events) -> None:
        """Recompute the indices and the map at the sliders' values and redraw both in place."""
        t0 = time.perf_counter()
        pose, setup = self.pose_values(), self.setup
        try:                                   # every bound checked again before the work
            res, dmap = M.slider_update(setup, pose, axes=(self.across, self.up),
                                        position_um=self.position_um,
                                        angular_arcsec=self.angular_arcsec)
        except ValueError as exc:
            self.refused = str(exc)
            return
        ms = (time.perf_counter() - t0) * 1e3
        self.result = res
        with pn.io.unlocked():  # some callbacks (a text input's Enter) lack the doc's lock
            self._draw_heat(res)
            self._draw_map(dmap, pose)
        top = {o: (e, v) for o, e, v in M.top_errors(res)}
        self.top.object = '<table class="mt-top"><tr><th>output</th><th>top error (every ' \
            'tie)</th><th>index</th></tr>' + "".join(
                f'<tr data-role="top-error" data-output="{o}" '
                f'data-error="{html.escape(", ".join(top[o][0]))}" '
                f'data-ties="{len(top[o][0])}" data-index="{top[o][1]:.6f}"><td>{o}</td><td>'
                + ", ".join(f"<b>{html.escape(e)}</b>" for e in top[o][0])
                + (f" ({len(top[o][0])} tied)" if len(top[o][0]) > 1 else "")
                + f'</td><td>{top[o][1]:.4f}</td></tr>' if o in top else
                f'<tr data-role="top-error" data-output="{o}" data-error="" data-index="">'
                f'<td>{o}</td><td colspan="2">no first-order term at this pose</td></tr>'
                for o in res.outputs) + "</table>"
        self.status.object = f'<div class="mt-note" data-role="timing">computed in {ms:.0f} ms ' \
            '(server side)</div>'

    def _draw_heat(self, res: M.PoseIndices) -> None:
        d, q = res.indices.shape
        idx = res.indices.astype(float).copy()
        idx[:, ~res.first_order] = np.nan
        flat = idx.ravel()                                          # error-major
        high = max(float(np.nanmax(flat, initial=0.0)), 0.05)
        self.heat_colours.high = high              # the colours span the indices at this pose
        self.heat.y_range.factors = list(reversed(res.names))
        self.heat.x_range.factors = list(res.outputs)
        self.heat.height = 110 + 15 * d
        self.heat_src.data = dict(
            error=np.repeat(res.names, q).tolist(), output=list(res.outputs) * d, index=flat,
            label=["" if not np.isfinite(v) or v < 0.01 else f"{v:.2f}" for v in flat],
            text_color=["black" if np.isfinite(v) and v > 0.6 * high else "white" for v in flat],
            note=["" if res.first_order[k] else "no first-order term at this pose"
                  for _ in range(d) for k in range(q)])

    def _draw_map(self, dmap: M.DominantMap, pose: dict) -> None:
        k = dmap.outputs.index(self.output) if self.output in dmap.outputs else 0
        err = dmap.error[:, :, k].ravel()
        present = np.unique(err)                               # sorted: catalogue order
        label = np.array([dmap.names[j] if j >= 0 else "no first-order term" for j in present])
        # the notebooks' palette (Tol's, distinguishable under deuteranopia), one place
        colours = category_colours(present.tolist(), none=-1)
        self.map_colours.update(factors=label.tolist(),
                                palette=[colours[j] for j in present.tolist()])
        uu, vv = np.meshgrid(dmap.u, dmap.v, indexing="xy")
        du = (dmap.u[-1] - dmap.u[0]) / (len(dmap.u) - 1)
        dv = du if dmap.axes[0] == dmap.axes[1] else (dmap.v[-1] - dmap.v[0]) / (len(dmap.v) - 1)
        self.map_glyph.update(width=du, height=dv)
        self.map_src.data = dict(u=uu.ravel(), v=vv.ravel(), index=dmap.index[:, :, k].ravel(),
                                 error=label[np.searchsorted(present, err)].tolist())
        a1, a2 = (self.setup.axis(a) for a in dmap.axes)
        self.here.data = dict(u=[pose[a1.name]], v=[pose[a2.name]])
        self.dmap.x_range.update(start=dmap.u[0] - du / 2, end=dmap.u[-1] + du / 2)
        self.dmap.y_range.update(start=dmap.v[0] - dv / 2, end=dmap.v[-1] + dv / 2)
        self.dmap.xaxis.axis_label = f"{a1.name} ({unit_symbol(a1.unit)})"
        self.dmap.yaxis.axis_label = f"{a2.name} ({unit_symbol(a2.unit)})"
        self.dmap.title.text = f"Dominant error for {dmap.outputs[k]}"

    @param.depends("setup")
    def _notes(self):
        return _note("<br>".join(html.escape(n) for n in self.setup.notes), width=290)

    @param.depends("pose")
    def _sliders(self):
        """A slider and a number box per axis, the same parameter and bounds."""
        rows = []
        for a in self.setup.axes:
            check = _number_check(f"axis {a.name}", a.low, a.high, unit=f" {a.unit}")
            rows.append(pn.Row(
                _guarded(_prompt(pn.widgets.FloatSlider.from_param(
                    self.pose.param[a.name], width=195, css_classes=[f"pose-{a.name}"])),
                    check, self.refuse),
                _guarded(pn.widgets.FloatInput.from_param(
                    self.pose.param[a.name], name="", width=85, start=a.low, end=a.high,
                    format="0[.]00000", css_classes=[f"pose-{a.name}-input"]),
                    check, self.refuse)))
        return pn.Column(*rows)

    def _csv(self, kind: str):
        r = self.result
        return M.top_errors_table(r) if kind == "top" else M.indices_table(r)

    def view(self):
        """The tab: controls, the top errors and the heat map, the dominant-error map."""
        p, w = self.param, pn.widgets

        def choice(widget):
            return _guarded(widget, _option_check(widget), self.refuse)

        def text(value):
            if not isinstance(value, str) or len(value) > M.MAX_TOPOLOGY_CHARS:
                raise ValueError(f"a topology is a text of at most {M.MAX_TOPOLOGY_CHARS} "
                                 "characters, such as 'w C b X Y Z B t'")
            return value

        ranges = [_guarded(_prompt(w.FloatSlider.from_param(p[n], width=280)), _number_check(
            p[n].label, *M.RANGE_BOUNDS, unit=unit), self.refuse)
            for n, unit in (("position_um", " µm"), ("angular_arcsec", " arcsec"))]
        controls = pn.Column(
            choice(w.Select.from_param(p.machine, width=290)),
            _guarded(w.TextInput.from_param(p.topology, placeholder="w C b X Y Z B t",
                                            width=290), text, self.refuse),
            pn.pane.HTML(p.error.rx.pipe(_error_html), width=290),
            pn.pane.HTML(p.refused.rx.pipe(_error_html), width=290), self._notes,
            pn.pane.HTML("<b>Pose</b>"), self._sliders,
            pn.pane.HTML("<b>Error ranges</b> (uniform)"),
            *ranges,
            _note("Each slider sets the largest half range of its group; the errors the "
                  "notebook gives smaller ranges keep their ratio to it."),
            pn.Row(*(choice(_prompt(w.Select.from_param(p[n], width=90)))
                     for n in ("across", "up", "output"))),
            self.status, pn.Row(
                _csv_button("top errors (CSV)", "top_errors.csv", lambda: self._csv("top"),
                            width=140),
                _csv_button("indices (CSV)", "indices.csv", lambda: self._csv("indices"),
                            width=140)), width=310)
        return pn.Row(controls, pn.Column(self.top, self.heat), pn.Column(_note(
            "Dominant error: the error with the largest closed-form index at each pose of a "
            "25 x 25 grid over the two axes chosen, the other axes at their slider values; "
            "grey: the output has no first-order term there; the circle marks the pose of the "
            "sliders.", width=540), self.dmap))


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

    def refuse(self, message: str) -> None:
        """Show why a value from the page was refused ("": clear the message)."""
        self.refused = message

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
            return pn.pane.HTML(_error_html(str(exc)), width=560)
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
        fig = _figure("What the layout does to each harmonic of the profile", width=640,
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
        return pn.Row(pn.Column(pn.pane.HTML(summary, width=560), fig), pn.Column(dirs, _note(
            "q_k: how much the separation multiplies white probe noise at harmonic k (the "
            "weighted method's error transfer function, Eqs. 14, 19; least squares: the "
            "Gauss-Markov variance). Red: the layout cancels the harmonic, no estimator "
            "recovers it.", width=300)))

    def view(self):
        """The tab: controls and the plots."""
        p, w = self.param, pn.widgets

        def guard(widget, name, *, integer=False, unit=""):
            par = p[name]
            return _guarded(widget, _number_check(par.label, *par.bounds, unit=unit,
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
        return pn.Row(pn.Column(
            _guarded(layout, _option_check(layout), self.refuse),
            pn.pane.HTML(p.refused.rx.pipe(_error_html), width=290),
            _note("Probe 1 sits at 0 deg: it defines the x axis."),
            *(probe(i) for i in (2, 3, 4)),
            guard(w.IntSlider.from_param(p.max_harmonic, width=280), "max_harmonic",
                  integer=True),
            pn.pane.HTML("<b>Weighted method</b>"),
            _guarded(w.RadioButtonGroup.from_param(p.weights, width=280), lambda v: v,
                     self.refuse),
            guard(w.FloatSlider.from_param(p.a3, width=280, format="0.000",
                                           visible=p.weights.rx() == "eq5"), "a3"),
            guard(w.FloatSlider.from_param(p.amplified_above, width=280), "amplified_above"),
            _csv_button("harmonics (CSV)", "spindle_harmonics.csv",
                        lambda: M.probe_table(self.transfer()), width=140),
            width=310), self.plots)


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

    def refuse(self, message: str) -> None:
        """Show why a value from the page was refused ("": clear the message)."""
        self.refused = message

    def _csv(self):
        if not isinstance(self.result, M.ThermalPrediction):
            raise ValueError("no prediction to export")
        return M.thermal_table(self.result)

    def __init__(self, **params):
        super().__init__(**params)
        self.data, self.reconstructed = M.thermal_data()
        exps = [int(e) for e in self.data.experiments]
        self.param.train.objects, self.param.test.objects = exps, exps
        self.param.update(M.thermal_defaults(self.data, self.reconstructed))  # notebook 04's

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
            return pn.pane.HTML(_error_html(r or ""), width=560)
        n, p = r.measured.shape
        src = bm.ColumnDataSource(dict(
            x=np.tile(r.positions_mm, n), y=r.measured.ravel(), pred=r.predicted.ravel(),
            res=(r.measured - r.predicted).ravel(), t=np.repeat(r.time_min, p),
            m=np.repeat(r.measurement, p)))
        colours = {"field": "t", "transform": bm.LinearColorMapper(
            palette=Plasma256[:220], low=float(r.time_min.min()),
            high=float(r.time_min.max()) + 1e-9)}
        curves = _figure("Test experiment: measured (dots), predicted (lines)", width=560,
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
        scatter = _figure("Predicted against measured", width=380, height=380,
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
        return pn.Column(pn.pane.HTML(summary, width=620), pn.Row(curves, scatter))

    def view(self):
        """The tab: controls, status, and the prediction against the measurement."""
        p, w = self.param, pn.widgets
        source = html.escape(provenance.shown(self.data.source))
        test = w.Select.from_param(p.test, width=140)

        def accept(value):
            return value
        return pn.Row(pn.Column(
            pn.pane.HTML("<b>Training experiments</b>"),
            _guarded(w.CheckBoxGroup.from_param(p.train, inline=True), accept, self.refuse),
            _guarded(test, _option_check(test), self.refuse),
            pn.pane.HTML(p.refused.rx.pipe(_error_html), width=290),
            pn.pane.HTML("<b>Model inputs</b> (Eq. 9: k from temperatures, b from rises)"),
            _guarded(w.RadioButtonGroup.from_param(p.inputs, width=290), accept, self.refuse),
            pn.pane.HTML("<b>Decoupled model</b> (Xu et al. 2022, Eq. 9)"),
            _guarded(w.RadioButtonGroup.from_param(p.kind, width=290), accept, self.refuse),
            _csv_button("prediction (CSV)", "thermal_prediction.csv", self._csv, width=140),
            pn.Row(pn.indicators.LoadingSpinner(value=p.busy, visible=p.busy, size=22),
                   pn.pane.HTML(p.status.rx.pipe(lambda s: f'<div class="mt-note">'
                                                 f'{html.escape(s)}</div>'), width=260)),
            _note(f"Data: {source}" + (
                " - the paper's reconstruction (data/thermal/README.md), not measurements."
                if self.reconstructed else " - not the paper's reconstruction: no comparison "
                "with the paper.")), width=310),
            self.plots)


# -- The app and the server ------------------------------------------------------------------------

def create_app():
    """The explorer's three tabs, a new independent app per call (one per browser session)."""
    pn.extension(raw_css=[_CSS])
    tabs = {"machine": MachineTab(), "spindle": SpindleTab(), "thermal": ThermalTab()}
    header = pn.pane.HTML(
        "<h2 style='margin:4px 0'>mtaccuracy explorer</h2><div class='mt-note'>Closed-form "
        "sensitivity of the papers' machines, what a probe layout does to each harmonic, and "
        "the thermal model of notebook 04. Hover over a plot for its values.</div>")
    app = pn.Column(header, pn.Tabs(*((k.capitalize(), t.view()) for k, t in tabs.items())),
                    sizing_mode="stretch_width")
    app.tabs = tabs
    return app


def check_address(address: str) -> str:
    """Refuse any address but 127.0.0.1 (``0.0.0.0``, ``::``, a name, a LAN address)."""
    if address != LOOPBACK:
        raise ValueError(f"the explorer listens on {LOOPBACK} only, not {address!r}: reach it "
                         f"from elsewhere through an SSH tunnel")
    return address


def free_port() -> int:
    """A port free on 127.0.0.1 right now (the system picks it)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind((LOOPBACK, 0))
        return int(s.getsockname()[1])


def serve(*, port: int = 0, address: str = LOOPBACK, show: bool = False):
    """A server of :func:`create_app` on 127.0.0.1 (port 0: a free one) and its URL, not started."""
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
    """``python -m mtaccuracy.apps.explore [--port N] [--show/--no-show] [--from-env]``."""
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
