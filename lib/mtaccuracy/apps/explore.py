"""An interactive explorer of the compendium's three topics, in the browser, on 127.0.0.1.

``make explore`` (``EXPLORE_ARGS="--port N"``) or ``python -m mtaccuracy.apps.explore [--port N]
[--show]`` serves it on 127.0.0.1 only (port 0, the default: a free one), prints the URL and runs
until Ctrl-C; ``binder/explore.ipynb`` shows it on Binder (Panel's Jupyter server extension,
``?urlpath=panel-preview/render/binder/explore.ipynb``).  Each tab is a ``param.Parameterized``:
its parameters are the controls (Panel builds the widgets), its ``@param.depends`` methods
redraw; every start is a notebook's declared default (``Parameters``, :mod:`mtaccuracy.papers`);
the numbers come from :mod:`mtaccuracy.apps.explore_model`; the Spindle and Thermal tabs live in
:mod:`~mtaccuracy.apps.explore_tabs`, the shared pieces in :mod:`~mtaccuracy.apps.explore_ui`.

Machine: a paper's machine or a typed topology; the closed-form Sobol indices at the pose of the
sliders (heat map, top error per output) and the dominant error over two chosen axes, redrawn in
place at every move (``make bench``, rows ``explore_update`` and ``explore_browser``, the
latter in Chromium: :mod:`~mtaccuracy.apps.explore_bench`).  Spindle: per harmonic, what a probe
layout cancels and amplifies, for least squares and the weighted method.  Thermal: notebook 04's
split, the decoupled model (MLR or SVR, fitted off the event loop with its progress shown)
against the measured error.

Machine-tab ranges: a table of every error's half range (µm, arcsec), seeded from the notebook's
declarations, typed in or read from the reader's own ranges file; the reader's probe file
(Spindle) and thermal measurements (Thermal) too, through the notebooks' own readers
(:mod:`~mtaccuracy.apps.explore_files`).

The server listens on 127.0.0.1 only (:func:`check_address`) and needs its token (printed in the
URL at start; ``--token`` sets it), serves at most
:data:`~mtaccuracy.apps.explore_server.MAX_SESSIONS` sessions at once, its websocket accepts
pages from ``127.0.0.1:<port>`` and ``localhost:<port>`` only (whatever
``BOKEH_ALLOW_WS_ORIGIN`` says), and Panel serves its own JavaScript and CSS.
Every value the page sends is checked on the server before Panel applies it
(:func:`~mtaccuracy.apps.explore_ui.guarded`, the bounds of
:mod:`~mtaccuracy.apps.explore_model`): a refused one is shown as a message.
"""

from __future__ import annotations

import argparse
import html
import os
import shlex
import socket
import sys
import time

import numpy as np
import panel as pn
import param
from bokeh import models as bm
from bokeh.palettes import Viridis256

from ..compendium.plotting import category_colours, unit_symbol
from . import explore_files as EF
from . import explore_model as M
from . import explore_server as ES
from . import explore_state as EU
from .explore_tabs import SpindleTab, ThermalTab
from .explore_ui import (
    CSS,
    GREY,
    block,
    csv_button,
    error_html,
    file_box,
    file_status,
    guarded,
    guarded_table,
    new_figure,
    note,
    number_check,
    option_check,
    prompt,
    wrap,
)

#: The only address the explorer listens on.
LOOPBACK = "127.0.0.1"


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
    half_range = param.Array(np.zeros(0), doc="every error's half range (mm, rad), the table's")
    file_error = param.String("", doc="the reader's message on the last ranges file")
    file_read = param.String("", doc="what the last ranges file gave")

    def __init__(self, **params):
        super().__init__(**params)
        self.ranges = guarded_table(pn.widgets.Tabulator(
            M.ranges_table(M.machine_setup(self.machine)), show_index=False, height=260,
            width=290, layout="fit_data_table", selectable=False, sortable=False,
            css_classes=["error-ranges"], editors={
                "error": None, "unit": None, "notebook": None, "half_range": {
                    "type": "number", "min": M.ERROR_RANGE_BOUNDS[0],
                    "max": M.ERROR_RANGE_BOUNDS[1], "step": 0.1}},
            titles={"half_range": "± half range", "notebook": "notebook's"},
            formatters={c: {"type": "money", "precision": 4, "symbol": ""}
                        for c in ("half_range", "notebook")}),
            "half_range", lambda v: M.checked_half_ranges(self.setup, v, in_table_units=True),
            self.refuse)
        self.ranges.param.watch(self._table_edited, "value")
        self.top = pn.pane.HTML("", sizing_mode="stretch_width", css_classes=["mt-scroll"])
        self.status = pn.pane.HTML("", width=290)
        self.result = None                     # the last PoseIndices shown (the CSV exports)
        self.on_update = []                    # called after each redraw (the URL's state)
        self.moves = 0
        # heat map: errors (rows) x outputs (columns)
        self.heat_src = bm.ColumnDataSource(dict(error=[], output=[], index=[], label=[],
                                                 text_color=[], note=[]))
        self.heat_colours = bm.LinearColorMapper(palette=Viridis256, low=0.0, high=1.0,
                                                 nan_color=GREY)
        self.heat = new_figure("Sobol indices at the pose (closed form)", x_range=bm.FactorRange(),
                            y_range=bm.FactorRange(), max_width=460, height=700,
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
        self.dmap = new_figure("", max_width=600, height=430, x_range=bm.Range1d(0, 1),
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
                          output=setup.outputs[0], half_range=setup.half_range.copy(),
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

    @param.depends("position_um", watch=True)
    def _scale_position(self) -> None:
        self._scale(True, self.position_um)

    @param.depends("angular_arcsec", watch=True)
    def _scale_angular(self) -> None:
        self._scale(False, self.angular_arcsec)

    def _scale(self, translational: bool, largest: float) -> None:
        """A group slider moved: its group's half ranges scaled, their ratios kept."""
        try:
            new = M.scaled_group(self.setup, self.half_range, translational=translational,
                                 largest=largest)
        except ValueError as exc:
            self.refused = str(exc)
            return
        if not np.array_equal(new, self.half_range):
            self.half_range = new

    def _table_edited(self, event) -> None:
        """A half range typed in the table (checked by the table's guard, and again here)."""
        try:
            new = M.checked_half_ranges(self.setup, event.new["half_range"].to_numpy(),
                                        in_table_units=True)
        except (ValueError, KeyError) as exc:
            self.refused = str(exc)
            return
        if new.shape == self.half_range.shape and not np.array_equal(new, self.half_range):
            self.set_half_ranges(new)

    def load_ranges(self, names, contents) -> None:
        """A ranges file uploaded: read as notebook 06 reads it, against this machine."""
        up = EF.read_upload(names, contents, lambda path: M.ranges_from_file(self.setup, path))
        if up.message:
            self.param.update(file_error=up.message, file_read="")
            return
        self.set_half_ranges(up.result)
        self.param.update(file_error="", file_read=f"{up.names[0]}: {len(up.result)} ranges "
                          f"read for {self.setup.label}" + "".join(
                              f"; {w}" for w in up.warnings))

    def set_half_ranges(self, half_range) -> None:
        """Every error's half range (mm, rad; checked), the group sliders at their largest."""
        half = M.checked_half_ranges(self.setup, half_range)
        per = np.where(self.setup.translational, 1e-3, M.ARCSEC)
        sliders = {}
        for name, group in (("position_um", self.setup.translational),
                            ("angular_arcsec", ~self.setup.translational)):
            top = float((half[group] / per[group]).max()) if group.any() else 0.0
            if M.RANGE_BOUNDS[0] <= top <= M.RANGE_BOUNDS[1]:
                sliders[name] = top
        self.half_range = half
        self.param.update(sliders)            # scaled to their own largest: no change

    @param.depends("half_range", watch=True)
    def _show_ranges(self) -> None:
        table = M.ranges_table(self.setup, self.half_range)
        if not table.equals(self.ranges.value):
            self.ranges.value = table

    @param.depends("pose", "half_range", "across", "up", "output", watch=True)
    def update(self, *events) -> None:
        """Recompute the indices and the map at the sliders' values and redraw both in place."""
        t0 = time.perf_counter()
        pose, setup = self.pose_values(), self.setup
        try:                                   # every bound checked again before the work
            res, dmap = M.slider_update(setup, pose, axes=(self.across, self.up),
                                        half_range=self.half_range)
        except ValueError as exc:
            self.refused = str(exc)
            return
        ms = (time.perf_counter() - t0) * 1e3
        self.result = res
        top = {o: (e, v) for o, e, v in M.top_errors(res)}
        table = '<table class="mt-top"><tr><th>output</th><th>top error (every ' \
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
        # the numbers first (a small message the page shows at once), then the plots
        with pn.io.unlocked():  # some callbacks (a text input's Enter) lack the doc's lock
            self.top.object = table                     # its own message, sent at once
        with pn.io.unlocked():
            self._draw_heat(res)
            self._draw_map(dmap, pose)
        self.moves += 1                       # the status changes at every move (make bench)
        self.status.object = f'<div class="mt-note" data-role="timing" data-move=' \
            f'"{self.moves}">computed in {ms:.0f} ms (server side)</div>'
        for callback in self.on_update:
            callback()

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
        changed = dict(
            index=flat, label=["" if not np.isfinite(v) or v < 0.01 else f"{v:.2f}" for v in flat],
            text_color=["black" if np.isfinite(v) and v > 0.6 * high else "white" for v in flat],
            note=["" if res.first_order[k] else "no first-order term at this pose"
                  for _ in range(d) for k in range(q)])
        error, output = np.repeat(res.names, q).tolist(), list(res.outputs) * d
        old = self.heat_src.data
        if old.get("error") == error and old.get("output") == output:
            old.update(changed)               # only the columns a move changes are sent
        else:
            self.heat_src.data = dict(error=error, output=output, **changed)

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
        changed = dict(index=dmap.index[:, :, k].ravel(),
                       error=label[np.searchsorted(present, err)].tolist())
        old = self.map_src.data
        if np.array_equal(old.get("u", []), uu.ravel()) and \
                np.array_equal(old.get("v", []), vv.ravel()):
            old.update(changed)               # the grid is the same: not sent again
        else:
            self.map_src.data = dict(u=uu.ravel(), v=vv.ravel(), **changed)
        a1, a2 = (self.setup.axis(a) for a in dmap.axes)
        self.here.data = dict(u=[pose[a1.name]], v=[pose[a2.name]])
        self.dmap.x_range.update(start=dmap.u[0] - du / 2, end=dmap.u[-1] + du / 2)
        self.dmap.y_range.update(start=dmap.v[0] - dv / 2, end=dmap.v[-1] + dv / 2)
        self.dmap.xaxis.axis_label = f"{a1.name} ({unit_symbol(a1.unit)})"
        self.dmap.yaxis.axis_label = f"{a2.name} ({unit_symbol(a2.unit)})"
        self.dmap.title.text = f"Dominant error for {dmap.outputs[k]}"

    @param.depends("setup")
    def _notes(self):
        return note("<br>".join(html.escape(n) for n in self.setup.notes), width=290)

    @param.depends("pose")
    def _sliders(self):
        """A slider and a number box per axis, the same parameter and bounds."""
        rows = []
        for a in self.setup.axes:
            check = number_check(f"axis {a.name}", a.low, a.high, unit=f" {a.unit}")
            rows.append(pn.Row(
                guarded(prompt(pn.widgets.FloatSlider.from_param(
                    self.pose.param[a.name], width=195, css_classes=[f"pose-{a.name}"])),
                    check, self.refuse),
                guarded(pn.widgets.FloatInput.from_param(
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
            return guarded(widget, option_check(widget), self.refuse)

        def text(value):
            if not isinstance(value, str) or len(value) > M.MAX_TOPOLOGY_CHARS:
                raise ValueError(f"a topology is a text of at most {M.MAX_TOPOLOGY_CHARS} "
                                 "characters, such as 'w C b X Y Z B t'")
            return value

        ranges = [guarded(prompt(w.FloatSlider.from_param(p[n], width=280)), number_check(
            p[n].label, *M.RANGE_BOUNDS, unit=unit), self.refuse)
            for n, unit in (("position_um", " µm"), ("angular_arcsec", " arcsec"))]
        controls = pn.Column(
            choice(w.Select.from_param(p.machine, width=290)),
            guarded(w.TextInput.from_param(p.topology, placeholder="w C b X Y Z B t",
                                            width=290), text, self.refuse),
            pn.pane.HTML(p.error.rx.pipe(error_html), width=290),
            pn.pane.HTML(p.refused.rx.pipe(error_html), width=290), self._notes,
            pn.pane.HTML("<b>Pose</b>"), self._sliders,
            pn.pane.HTML("<b>Error ranges</b> (uniform on ± the half range)"),
            *ranges,
            note("Each slider sets the largest half range of its group; the others keep "
                 "their ratio to it. Type any error's own half range in the table (µm or "
                 "arcsec, 0 to 10 000); the notebook's is beside it."),
            self.ranges,
            pn.Row(w.Button(label="notebook's ranges", width=140, on_click=lambda e:
                            self.set_half_ranges(self.setup.half_range)),
                   csv_button("ranges (CSV)", "error_ranges.csv",
                              lambda: M.ranges_table(self.setup, self.half_range), width=140)),
            note("Your ranges file (notebook 06's: symbol, low, high, unit; one row per error "
                 "of this machine):"),
            file_box("ranges-file", self.load_ranges, self.refuse),
            pn.pane.HTML(pn.rx(file_status)(p.file_error, p.file_read), width=290),
            pn.Row(*(choice(prompt(w.Select.from_param(p[n], width=90)))
                     for n in ("across", "up", "output"))),
            self.status, pn.Row(
                csv_button("top errors (CSV)", "top_errors.csv", lambda: self._csv("top"),
                            width=140),
                csv_button("indices (CSV)", "indices.csv", lambda: self._csv("indices"),
                            width=140)), width=310)
        return wrap(controls, block(self.top, self.heat, max_width=480), block(note(
            "Dominant error: the error with the largest closed-form index at each pose of a "
            "25 x 25 grid over the two axes chosen, the other axes at their slider values; "
            "grey: the output has no first-order term there; the circle marks the pose of the "
            "sliders.", sizing_mode="stretch_width"), self.dmap, basis=360))


# -- The app and the server ------------------------------------------------------------------------

def create_app():
    """The explorer's three tabs, a new independent app per call (one per browser session)."""
    pn.extension("tabulator", raw_css=[CSS])
    tabs = {"machine": MachineTab(), "spindle": SpindleTab(), "thermal": ThermalTab()}
    header = pn.pane.HTML(
        "<h2 style='margin:4px 0'>mtaccuracy explorer</h2><div class='mt-note'>Closed-form "
        "sensitivity of the papers' machines, what a probe layout does to each harmonic, and "
        "the thermal model of notebook 04. Hover over a plot for its values.</div>")
    views = pn.Tabs(*((k.capitalize(), t.view()) for k, t in tabs.items()), dynamic=True)
    state, problems = EU.UrlState(), pn.pane.HTML("", sizing_mode="stretch_width")
    chapter = pn.pane.HTML("", sizing_mode="stretch_width")
    machine, spindle = tabs["machine"], tabs["spindle"]

    def show_chapter(*_):
        tab = EU.TABS[views.active]
        key = machine.setup.key if tab == "machine" else (
            "probe file" if tab == "spindle" and spindle.file_read else tab)
        url = EU.chapter_url(key)
        chapter.object = (f'<div class="mt-note">What this tab shows, in the book: <a '
                          f'data-role="chapter" href="{html.escape(url)}" target="_blank" '
                          f'rel="noopener">{html.escape(EU.CHAPTERS[key])}</a> (online once '
                          f'the repository is published; make book builds it here)</div>'
                          if url else "")

    location = pn.state.location if pn.state.curdoc is not None else None
    if location is not None:                 # a served session: the link's state, checked
        location.sync(state, {n: n for n in ("tab", "machine", "topology", "pose", "view",
                                             "ranges", "probes")})
        refused = state.apply(tabs, active=lambda i: setattr(views, "active", i))
        problems.object = error_html("The link's state was not all applied: " + "; ".join(
            refused)) if refused else ""

    def remember(*_):
        state.read(tabs)
        state.tab = EU.TABS[views.active]
        show_chapter()
    machine.on_update.append(remember)
    spindle.param.watch(remember, ["probe2", "probe3", "probe4", "file_read"])
    views.param.watch(remember, "active")
    remember()
    app = pn.Column(header, problems, chapter, views, sizing_mode="stretch_width")
    app.tabs, app.url_state, app.views = tabs, state, views
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


def _too_many():
    return pn.pane.HTML(f"<p>The explorer serves {ES.MAX_SESSIONS} sessions at once: close "
                        "another tab, then reload this one.</p>")


def serve(*, port: int = 0, address: str = LOOPBACK, show: bool = False,
          token: str | None = None, max_sessions: int = ES.MAX_SESSIONS):
    """A server of :func:`create_app` on 127.0.0.1 (port 0: a free one) and its URL, not started.

    Every request needs ``token`` (None: a random one; :mod:`~mtaccuracy.apps.explore_server`),
    which the URL returned carries; at most ``max_sessions`` sessions at once; the websocket
    takes the server's own origins only, whatever ``BOKEH_ALLOW_WS_ORIGIN`` says.
    """
    check_address(address)
    if isinstance(port, bool) or not isinstance(port, int) or not 0 <= port <= 65535:
        raise ValueError(f"port must be an integer in 0..65535, got {port!r}")
    token = ES.new_token() if token is None else ES.checked_token(token)
    ES.own_origins()
    app = ES.SessionCap(max_sessions).gate(create_app, _too_many)
    for attempt in range(5):
        chosen = port or free_port()
        try:
            server = pn.serve(app, port=chosen, address=LOOPBACK,
                              websocket_origin=[f"{LOOPBACK}:{chosen}", f"localhost:{chosen}"],
                              show=False, start=False, verbose=False,
                              title="mtaccuracy explorer", auth_provider=ES.TokenAuth(
                                  token, chosen),
                              websocket_max_message_size=2 * EF.MAX_UPLOAD_BYTES)
            break
        except OSError:
            if port or attempt == 4:       # a port asked for is taken; or no luck, 5 times
                raise
    url = f"http://{LOOPBACK}:{chosen}/?token={token}"
    if show:
        import webbrowser  # only with --show
        server.io_loop.add_callback(webbrowser.open, url)
    return server, url


def main(argv=None) -> int:
    """``python -m mtaccuracy.apps.explore [--port N] [--token T] [--show] [--from-env]``."""
    ap = argparse.ArgumentParser(prog="python -m mtaccuracy.apps.explore",
                                 description="Serve the mtaccuracy explorer on 127.0.0.1.")
    ap.add_argument("--port", type=int, default=0,
                    help="port on 127.0.0.1 (default 0: a free one)")
    ap.add_argument("--show", action=argparse.BooleanOptionalAction, default=False,
                    help="open the page in the default browser (default: --no-show)")
    ap.add_argument("--token", default=None,
                    help="the token every request needs (16 to 128 letters, digits, - or _; "
                         "default: a random one, printed in the URL)")
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
        server, url = serve(port=args.port, show=args.show, token=args.token)
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
