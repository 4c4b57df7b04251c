"""The explorer's shared pieces: styles, messages, guarded widgets, CSV buttons, figures.

:mod:`mtaccuracy.apps.explore` and its tabs (:mod:`~mtaccuracy.apps.explore_tabs`) build on
these; :func:`guarded` is the server-side gate every value from the page passes (the bounds of
:mod:`~mtaccuracy.apps.explore_model`).
"""

from __future__ import annotations

import html
import io

import panel as pn
from bokeh.plotting import figure

from . import explore_files as EF
from . import explore_model as M

#: A blue, the figures' orange of published values, a red: cancelled, a grey: no first order.
BLUE, ORANGE, RED, GREY = "#1b6ca8", "#d95f02", "#b2182b", "#cccccc"
CSS = """
.mt-note {font-size: 12px; color: #555; line-height: 1.35;}
.mt-error {background: #fde8e8; border: 1px solid #b2182b; color: #7a1020; padding: 6px 9px;
           border-radius: 4px; font-size: 12.5px; white-space: pre-wrap;}
table.mt-top {border-collapse: collapse; font-size: 12.5px; max-width: 100%;}
.mt-scroll {overflow-x: auto; max-width: 100%;}
table.mt-top td, table.mt-top th {padding: 2px 8px; border-bottom: 1px solid #e3e3e3;
                                  text-align: left;}
"""


def note(text: str, **kw):
    return pn.pane.HTML(f'<div class="mt-note">{text}</div>', **kw)


def error_html(message: str) -> str:
    return f'<div class="mt-error" data-role="error">{html.escape(message)}</div>' \
        if message else ""


def prompt(widget):
    """Act on the widget's changes after 5 ms, not Panel's 50: the Machine tab's update is fast."""
    widget._debounce = 5
    return widget


def guarded(widget, check, refuse):
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


def guarded_table(table, column: str, check, refuse):
    """``table`` (a Tabulator) whose edits from the page pass ``check`` on the server first.

    Every change of the table's data the page sends (an edited cell, or a crafted message with
    any columns and rows) reaches Panel only as ``column``, and only once ``check`` (called with
    that column's values, in row order) accepts it; the other columns are never taken from the
    page.  A refused change is never applied: ``refuse`` gets the message and the page gets the
    server's table back; an accepted one calls ``refuse("")``.
    """
    process = table._process_data

    def guarded_data(data):
        try:
            if column not in data:
                raise ValueError(f"the table's edit has no column {column!r}")
            values = data[column]
            if isinstance(values, dict):            # a patch: {row: value}
                values = [v for _, v in sorted(values.items(), key=lambda kv: int(kv[0]))]
            values = list(values)
            check(values)
        except (ValueError, TypeError) as exc:
            refuse(str(exc))
            table.param.trigger("value")
            return
        refuse("")
        process({column: values})

    table._process_data = guarded_data
    return table


def file_box(css: str, on_file, refuse, *, multiple: bool = False):
    """A ``.csv`` upload (Panel's FileInput) whose file(s) go to ``on_file(names, contents)``.

    What the page sends passes :func:`~mtaccuracy.apps.explore_files.checked_base64` first
    (:func:`guarded`: a refused upload's message goes to ``refuse``).
    """
    box = pn.widgets.FileInput(accept=".csv", multiple=multiple, css_classes=[css], width=290)
    box.param.watch(lambda *events: box.value and on_file(box.filename, box.value),
                    ["value", "filename"])                 # one call for both (one message)
    return guarded(box, EF.checked_base64, refuse)


def file_status(error: str, told: str) -> str:
    """The reader's message (an error box), else what was read (a note)."""
    return error_html(error) if error else (
        f'<div class="mt-note" data-role="file-read">{html.escape(told)}</div>' if told else "")


def number_check(name: str, low: float, high: float, *, unit: str = "",
                  integer: bool = False):
    def check(value):
        return M.checked_number(value, name, low=low, high=high, unit=unit, integer=integer)
    return check


def option_check(widget):
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


def csv_button(label: str, filename: str, frame, **kw):
    """A download of ``frame()`` (a DataFrame, computed at the click) as ``filename``."""
    return pn.widgets.FileDownload(callback=lambda: io.StringIO(M.to_csv(frame())),
                                   filename=filename, label=label, embed=False, **kw)


def block(*objects, basis: int = 340, max_width: int = 640):
    """A column that shares a row when there is room, else takes the row (``wrap``).

    Its width grows from ``basis`` px to ``max_width``; it may shrink below ``basis`` on a
    narrow screen (CSS ``min-width: 0``): nothing in it is wider than the screen.
    """
    return pn.Column(*objects, sizing_mode="stretch_width", max_width=max_width,
                     styles={"flex": f"1 1 {basis}px", "min-width": "0"})


def wrap(*objects):
    """Blocks side by side on a wide screen, one under another on a narrow one."""
    return pn.FlexBox(*objects, flex_wrap="wrap", sizing_mode="stretch_width")


def new_figure(title: str, **kw):
    kw.setdefault("sizing_mode", "stretch_width")        # the block's width, on any screen
    kw.setdefault("min_width", 280)
    return figure(title=title, tools="hover,save", toolbar_location="above", **kw)
