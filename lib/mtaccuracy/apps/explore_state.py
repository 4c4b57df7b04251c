"""The explorer's state in its URL, and the book chapter that matches what it shows.

:class:`UrlState` holds, as text, what a reload or a shared link restores: the tab, the machine
(or typed topology), the pose, the map's axes and output, every error's half range (only when
they differ from the notebook's) and the probe angles.  Panel's ``pn.state.location.sync`` keeps
it in the URL's query (the token stays); :meth:`UrlState.apply` reads a link through the same
checks as the controls (:mod:`~mtaccuracy.apps.explore_model`): a bad part is named in a message
and skipped, the rest applied.  :func:`chapter_url` links the chapter of the book that matches
the tab (the book's address from ``CITATION.cff``'s ``url``).
"""

from __future__ import annotations

import re

import numpy as np
import param

from ..compendium.notebook import ROOT
from . import explore_model as M

#: Each tab's chapter: Machine by machine (a typed topology: notebook 06), Spindle, Thermal.
CHAPTERS = {"ac_double_turntable": "01_zheng2024_pce_sobol_41_errors",
            "horizontal_3axis": "02_rong_sobol_21_errors",
            "vertical_xyfz": "03_guo2016_spearman_21_errors",
            M.TOPOLOGY: "06_your_machine", "spindle": "05_yang2021_spindle_four_point_ga",
            "probe file": "07_your_spindle", "thermal": "04_xu2022_thermal_mlr_svr"}
#: The tabs, in order.
TABS = ("machine", "spindle", "thermal")
#: The longest query value read (a 41-error ranges list is about 900 characters).
MAX_VALUE_CHARS = 2000


def book_url(citation=None) -> str:
    """The book's address: ``CITATION.cff``'s ``url`` (ends with ``/``), or "" if none."""
    path = ROOT / "CITATION.cff" if citation is None else citation
    try:
        text = path.read_text(encoding="utf-8")
    except OSError:
        return ""
    found = re.search(r"^url:\s*[\"']?(https?://[^\"'\s]+)", text, re.M)
    return (found.group(1).rstrip("/") + "/") if found else ""


def chapter_url(key: str, citation=None) -> str:
    """The book chapter of ``key`` (a :data:`CHAPTERS` key), or "" without a book address."""
    base = book_url(citation)
    return f"{base}chapters/{CHAPTERS[key]}.html" if base and key in CHAPTERS else ""


def _numbers(text: str, what: str, count: int | None = None) -> list[float]:
    parts = text.split(",")
    if count is not None and len(parts) != count:
        raise ValueError(f"the link's {what} has {len(parts)} values, {count} expected")
    try:
        return [float(p) for p in parts]
    except ValueError:
        raise ValueError(f"the link's {what} holds a value that is not a number: "
                         f"{text[:60]!r}") from None


class UrlState(param.Parameterized):
    """What the URL holds, as text (Panel syncs each parameter with one query parameter)."""

    tab = param.String("")
    machine = param.String("")
    topology = param.String("")
    pose = param.String("")
    view = param.String("")
    ranges = param.String("")
    probes = param.String("")

    def read(self, tabs) -> None:
        """Write the tabs' state into the parameters (and so into the URL)."""
        m, s = tabs["machine"], tabs["spindle"]
        notebook = np.array_equal(m.half_range, m.setup.half_range)
        self.param.update(
            machine=m.setup.key if m.setup.key != M.TOPOLOGY else M.TOPOLOGY,
            topology=m.topology if m.setup.key == M.TOPOLOGY else "",
            pose=",".join(f"{k}:{v!r}" for k, v in m.pose_values().items()),
            view=f"{m.across},{m.up},{m.output}",
            ranges="" if notebook else ",".join(
                repr(float(v)) for v in M.ranges_table(m.setup, m.half_range).half_range),
            probes=",".join(repr(float(v)) for v in (s.probe2, s.probe3, s.probe4)))

    def apply(self, tabs, active=None) -> list[str]:
        """Restore the tabs from the parameters (a link); the messages of the parts refused.

        ``active``: a callable taking the tab's index.  Every value goes through the bounds
        of the controls; a refused part is skipped, the others applied.
        """
        m, s, problems = tabs["machine"], tabs["spindle"], []

        def part(name, work):
            text = getattr(self, name)
            if not text:
                return
            try:
                if len(text) > MAX_VALUE_CHARS:
                    raise ValueError(f"the link's {name} is longer than {MAX_VALUE_CHARS} "
                                     "characters")
                work(text)
            except ValueError as exc:
                problems.append(f"{name}: {exc}")

        def machine(text):
            if text == M.TOPOLOGY:
                setup = M.topology_setup(self.topology)
                m._load(setup)
                m.param.update(topology=self.topology, machine=M.TOPOLOGY)
            elif text in M.MACHINES:
                m.machine = text
            else:
                raise ValueError(f"{text[:40]!r} is not one of {', '.join(M.MACHINES)}, "
                                 f"{M.TOPOLOGY}")

        def pose(text):
            values = {}
            for item in text.split(","):
                axis, _, value = item.partition(":")
                values[axis] = _numbers(value, f"pose ({axis})", 1)[0]
            M.pose_of(m.setup, values)                     # every bound, before any change
            with param.parameterized.batch_call_watchers(m.pose):
                m.pose.param.update(values)

        def view(text):
            across, up, output = (text.split(",") + ["", "", ""])[:3]
            names = [a.name for a in m.setup.axes]
            if across not in names or up not in names or output not in m.setup.outputs:
                raise ValueError(f"{text[:60]!r} is not two axes of {', '.join(names)} and an "
                                 f"output of {', '.join(m.setup.outputs)}")
            m.param.update(across=across, up=up, output=output)

        def ranges(text):
            values = _numbers(text, "ranges", len(m.setup.names))
            m.set_half_ranges(M.checked_half_ranges(m.setup, values, in_table_units=True))

        def probes(text):
            angles = _numbers(text, "probes", 3)
            high = s.param.probe2.bounds[1]
            for i, a in enumerate(angles, start=2):
                M.checked_number(a, f"probe {i} angle", low=0.0, high=high, unit=" deg")
            s.param.update(probe2=angles[0], probe3=angles[1], probe4=angles[2])

        part("machine", machine)
        for name, work in (("pose", pose), ("view", view), ("ranges", ranges),
                           ("probes", probes)):
            part(name, work)
        if self.tab:
            if self.tab in TABS and active is not None:
                active(TABS.index(self.tab))
            elif self.tab not in TABS:
                problems.append(f"tab: {self.tab[:40]!r} is not one of {', '.join(TABS)}")
        return problems
