"""One kinematic chain for every machine: a topology string, an error placement, a pose error.

A machine is a serial chain of linear (X, Y, Z) and rotary (A, B, C) axes between the
workpiece and the tool, written in the spirit of ISO 10791-1 / ISO 230-1 as a string read from
the workpiece to the tool, with ``b`` for the bed (the machine's base)::

    "w C A b Y X Z t"     workpiece on C, C on A, A on the bed; bed carries Y, Y carries X,
                          X carries Z, Z carries the spindle and the tool (Zheng et al. 2024)
    "w Z b X Y t"         workpiece on the Z table; X column carrying the Y headstock (Rong)
    "w b X Y Z t"         every axis on the tool side, composed X, Y, Z from the workpiece:
                          the serial reading of Guo et al. 2016's Eq. 9
    "w C b X Y Z B t"     a swivel-head mill on a rotary table (notebook 06)

An optional ``s`` (spindle) before ``t`` is accepted and ignored.  Each axis ``K`` is the body
that moves along (or about) the coordinate direction ``k`` of the frame it rides on.

The chain
---------
With ``F_1 ... F_n`` the factors of the tool side (bed outwards) and ``G_1 ... G_m`` those of
the workpiece side (bed outwards), the tool in the workpiece frame is

    g_wt = (G_1 ... G_m)^-1 (F_1 ... F_n T(tool offsets))

and each axis contributes, in this order, an optional *pre* location block (the location of
its axis relative to the body it rides on, ISO 230-7: before the motion), its nominal motion
(a translation ``s q d`` along its direction ``d``, which squareness errors may tilt, or a
rotation by ``s theta`` about its direction through its pivot), its block of six error motions
``D`` (ISO 230-1: EXK, EYK, EZK translations, EAK, EBK, ECK rotations, in the frame after the
motion) and an optional *post* location block (the location of the next body, after the
motion: the reading of Zheng et al.'s Eq. 9).  ``s`` is -1 for linear axes of the workpiece
side (the table moves by -q so that the tool moves by +q relative to the part, ISO 841) and +1
otherwise.

A block of errors ``(d, w)`` (translations and rotation parameters) is the rigid motion of its
``form``:

* ``euler``: ``[Rx(w_x) Ry(w_y) Rz(w_z) | d]``, six unit-twist exponentials in a row
  (Zheng et al.);
* ``screw``: the exponential of the twist ``(w, d)``: ``[exp([w]x) | V d]`` (Rong et al.);
* ``rodrigues``: ``[exp([w]x) | d]``;
* ``first_order``: ``[I + [w]x | d]``, the small-angle matrix the papers print (not a
  rotation: its inverse is taken exactly, ``(I - W + w w^T) / (1 + |w|^2)``).

All four agree to first order in the errors.  A squareness (direction) error ``w`` tilts a
linear axis' direction to ``exp([w]x) e_k`` (``tilt="exact"``) or ``e_k + w x e_k``
(``tilt="first_order"``).

Evaluation
----------
One batched path for every machine: the tool tip and the three tool-frame axes are carried as
rows (structure of arrays) through the factors, innermost first, in chunks of samples, with
every product written out in a fixed order (no BLAS call; the same rounding on every CPU).
:meth:`ChainMachine.jacobian` gives the exact first-order Jacobian at zero errors in
closed form (each error is a small twist in its frame: ``R_A (w x p_B + v)``), batched over
poses.  The kernels on rows (cos and sin, the exponential's coefficients, the blocks'
rotations and inverses) are :mod:`mtaccuracy.kinematics`'s.

The papers' machines are three descriptions in their modules (``ac_double_turntable``,
``horizontal_3axis``, ``vertical_xyfz``: a topology and a placement each); they reproduced the
hand-written chains they replace to 1e-12 (5e-13 measured) and the tests hold them to
independent formulations (4x4 products, the literal product of exponentials, sympy).
:func:`iso_machine` builds any topology with the ISO 230-1 catalogue generated from it and the
redundant location errors removed by a rank test (:func:`iso_catalogue`,
:func:`redundant_location_errors`).
"""

from __future__ import annotations

import os
import re
import warnings
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from .. import csvlines, validate
from .. import errors as _errors
from ..kinematics import (
    ROW_FORMS,
    cos_sin,
    cos_sin_into,
    cross_rows,
    exp_coefficients,
    homogeneous,
    inverse_rows,
    matmul3,
    motion_rows,
)
from . import units as _units
from .units import SuspectUnitWarning  # noqa: F401  (the readers' warning, here for readers)

LINEAR = "XYZ"
ROTARY = "ABC"
#: coordinate direction of each axis letter (A, B, C rotate about x, y, z)
DIRECTION = {"X": 0, "Y": 1, "Z": 2, "A": 0, "B": 1, "C": 2}
#: the forms of a block of errors: ``euler`` (elementary rotations, applied one by one) and
#: the forms of :func:`mtaccuracy.kinematics.motion_rows`
FORMS = ("euler", *ROW_FORMS)
#: error components of a block: translations along x, y, z, rotations about x, y, z
COMPONENTS = ("X", "Y", "Z", "A", "B", "C")
SLOTS = ("motion", "pre", "post", "tilt")
ORIENTATIONS = {"rotation_vector": ("Px", "Py", "Pz", "Rx", "Ry", "Rz"),
                "tool_axis": ("Px", "Py", "Pz", "Vx", "Vy", "Vz")}


# ------------------------------------------------------------------------------------------
# Topology
# ------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Topology:
    """A parsed topology: ``work`` and ``tool`` axes, each listed from the bed outwards.

    Attributes
    ----------
    text : str
        The topology as given.
    work, tool : tuple of str
        Axes on the workpiece side and on the tool side, each from the bed outwards.
    """

    text: str
    work: tuple[str, ...]
    tool: tuple[str, ...]

    @property
    def axes(self) -> tuple[str, ...]:
        """tuple of str: the workpiece-side then the tool-side axes, each from the bed out."""
        return self.work + self.tool

    def side(self, axis: str) -> int:
        """-1 for an axis of the workpiece side, +1 for one of the tool side.

        Parameters
        ----------
        axis : str
            An axis letter (``X Y Z A B C``).

        Returns
        -------
        int
            -1 if ``axis`` is on the workpiece side, else +1.
        """
        return -1 if axis in self.work else 1

    def describe(self) -> str:
        """The chain in words, e.g. ``workpiece <- C <- A <- bed -> Y -> X -> Z -> tool``.

        Returns
        -------
        str
            One line from the workpiece through the bed to the tool.
        """
        work = " <- ".join(["workpiece", *reversed(self.work), "bed"])
        return f"{work} -> " + " -> ".join([*self.tool, "tool"])


_GRAMMAR = ("a topology is read from the workpiece to the tool: 'w', the workpiece-side axes "
            "(the one carrying the workpiece first), 'b' (the bed), the tool-side axes (from "
            "the bed out), an optional 's' (spindle) and 't'; axes are X, Y, Z (linear) and "
            "A, B, C (rotary, about x, y, z), each at most once; e.g. 'w C A b Y X Z t'")
_TOKENS = frozenset((*LINEAR, *ROTARY, "w", "b", "s", "t"))
#: Size caps of a topology string.  The longest valid topology has 10 tokens (``w``, the six
#: axes, ``b``, ``s``, ``t``), 19 characters with single spaces, a few more with primes.  The
#: caps leave a wide margin for irregular spacing and refuse at once, before any parsing, a
#: string that cannot be a topology (a file's content or a repeated string pasted by mistake),
#: so that the parse and its messages stay small.
MAX_TOPOLOGY_CHARS = 200
MAX_TOPOLOGY_TOKENS = 64


def _excerpt(text: str, n: int = 60) -> str:
    """``repr`` of ``text``, or of its first ``n`` characters followed by ``...`` and its
    length: what an error message quotes of an input of any size."""
    if len(text) <= n:
        return repr(text)
    return f"{text[:n]!r}... ({len(text)} characters)"


def _listed(items, n: int = 10) -> str:
    """``['A', 'B']`` of the first ``n`` items (each cut to 20 characters), then how many
    more: a list of any length quoted in a message."""
    shown = [s if len(s) <= 20 else s[:20] + "..." for s in map(str, items[:n])]
    more = f" and {len(items) - n} more" if len(items) > n else ""
    return f"{shown}{more}"


def parse_topology(text: str) -> Topology:
    """Parse a topology string (ISO 10791-1 spirit; see the module docstring).

    Parameters
    ----------
    text : str
        The machine from the workpiece to the tool: ``w``, the workpiece-side axes (the one
        carrying the workpiece first), ``b`` (the bed), the tool-side axes (from the bed out),
        an optional ``s`` and ``t``; axes ``X Y Z`` (linear) and ``A B C`` (rotary about x, y,
        z), each at most once, separated by spaces (or written without spaces, ``wCAbYXZt``);
        a trailing prime (``C'``) is allowed and ignored.  At most
        :data:`MAX_TOPOLOGY_CHARS` characters and :data:`MAX_TOPOLOGY_TOKENS` tokens.

    Returns
    -------
    Topology
        ``work`` and ``tool`` axes, each listed from the bed outwards.

    Raises
    ------
    TypeError
        When ``text`` is not a string.
    ValueError
        For a string longer than the caps, an unknown letter, a missing or repeated ``w``,
        ``b`` or ``t``, a repeated axis or no axis, with the grammar in the message; a
        message quotes at most the first 60 characters of ``text``.

    Examples
    --------
    >>> topo = parse_topology("w C A b Y X Z t")
    >>> topo.work, topo.tool
    (('A', 'C'), ('Y', 'X', 'Z'))
    >>> topo.describe()
    'workpiece <- C <- A <- bed -> Y -> X -> Z -> tool'
    """
    if not isinstance(text, str):
        raise TypeError(f"topology must be a string, got {type(text).__name__}; {_GRAMMAR}")
    shown = _excerpt(text)
    if len(text) > MAX_TOPOLOGY_CHARS:
        raise ValueError(f"topology {shown} is longer than {MAX_TOPOLOGY_CHARS} characters; a "
                         f"machine has at most six axes; {_GRAMMAR}")
    stripped = text.strip()
    tokens = stripped.split() if re.search(r"\s", stripped) else list(stripped)
    if len(tokens) > MAX_TOPOLOGY_TOKENS:
        raise ValueError(f"topology {shown} has {len(tokens)} tokens, more than "
                         f"{MAX_TOPOLOGY_TOKENS}; a machine has at most six axes; {_GRAMMAR}")
    tokens = [t.rstrip("'") for t in tokens]
    if not tokens:
        raise ValueError(f"empty topology; {_GRAMMAR}")
    bad = list(dict.fromkeys(t for t in tokens if t not in _TOKENS))
    if bad:
        raise ValueError(f"unknown axis letter(s) {_listed(bad)} in topology {shown}; "
                         f"{_GRAMMAR}")
    count = Counter(tokens)
    if tokens[0] != "w" or tokens[-1] != "t" or count["w"] != 1 or count["t"] != 1:
        raise ValueError(f"topology {shown} must start with 'w' and end with 't'; {_GRAMMAR}")
    if count["b"] != 1:
        raise ValueError(f"topology {shown} must contain the bed 'b' exactly once; {_GRAMMAR}")
    if count["s"] and (count["s"] != 1 or tokens[-2] != "s"):
        raise ValueError(f"topology {shown}: 's' (spindle) may only come just before 't'")
    body = [t for t in tokens[1:-1] if t != "s"]
    cut = body.index("b")
    work, tool = tuple(reversed(body[:cut])), tuple(body[cut + 1:])
    axes = work + tool
    if not axes:
        raise ValueError(f"topology {shown} has no axis; {_GRAMMAR}")
    dup = sorted(a for a, k in Counter(axes).items() if k > 1)
    if dup:
        raise ValueError(f"axis {dup} appears more than once in topology {shown}")
    return Topology(text, work, tool)


# ------------------------------------------------------------------------------------------
# Where each error goes
# ------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Placement:
    """Where one error column enters the chain: an axis, a slot, a component and a sign.

    ``axis``, ``slot`` (``motion``: the axis' error-motion block; ``pre``/``post``: its location
    block before/after the motion; ``tilt``: a rotation of its direction of motion),
    ``component`` (0-2 translation along x, y, z; 3-5 rotation about x, y, z) and ``sign`` (+1,
    or -1 where a paper defines the error the other way).

    Attributes
    ----------
    axis : str
        The axis whose block the error enters.
    slot : {"motion", "pre", "post", "tilt"}
        Which block.
    component : int
        0-2 translation along x, y, z (mm); 3-5 rotation about x, y, z (rad).
    sign : float
        +1 or -1.
    """

    axis: str
    slot: str
    component: int
    sign: float = 1.0


@dataclass
class _Block:
    cols: list = field(default_factory=list)     # error columns
    comps: list = field(default_factory=list)    # their components 0-5
    signs: list = field(default_factory=list)


def _check_placements(topology: Topology, catalogue, placements) -> list[Placement]:
    syms = [e.symbol for e in catalogue]
    missing = [s for s in syms if s not in placements]
    if missing:
        raise ValueError(f"no placement for error(s) {missing}")
    extra = [s for s in placements if s not in syms]
    if extra:
        raise ValueError(f"placement for unknown error(s) {extra}; the catalogue has {syms}")
    out, seen = [], {}
    for s in syms:
        p = placements[s]
        if p.axis not in topology.axes:
            raise ValueError(f"error {s} is placed on axis {p.axis!r}, which is not in the "
                             f"topology {topology.text!r} (axes {', '.join(topology.axes)})")
        if p.slot not in SLOTS:
            raise ValueError(f"error {s}: unknown slot {p.slot!r}; allowed: {', '.join(SLOTS)}")
        if not 0 <= p.component <= 5 or (p.slot == "tilt" and p.component < 3):
            raise ValueError(f"error {s}: component {p.component} not allowed in slot "
                             f"{p.slot!r} (0-5; a tilt is a rotation, 3-5)")
        if p.slot == "tilt" and p.axis not in LINEAR:
            raise ValueError(f"error {s}: only a linear axis has a direction to tilt, not "
                             f"{p.axis}")
        key = (p.axis, p.slot, p.component)
        if key in seen:
            raise ValueError(f"errors {seen[key]} and {s} both occupy component "
                             f"{COMPONENTS[p.component]} of the {p.slot} slot of {p.axis}")
        seen[key] = s
        out.append(p)
    return out


# ------------------------------------------------------------------------------------------
# The machine
# ------------------------------------------------------------------------------------------

class ChainMachine:
    """A machine built from a topology and an error placement (see the module docstring).

    Every machine of the library is one (the papers' machines are subclasses that only fix
    the description).  Its ``pose_error(errors, pose)`` maps ``(n, n_errors)`` errors and a pose
    to the ``(n, 6)`` pose error; ``error_names``, ``catalogue``, ``axes`` and ``tool_offsets``
    name the columns and the pose.

    Parameters
    ----------
    topology : str
        The chain from the workpiece to the tool (:func:`parse_topology`).
    catalogue : sequence of :class:`mtaccuracy.errors.ErrorSpec`
        The errors; their order is the column order of every ``(n, n_errors)`` error array.
    placements : mapping of str to :class:`Placement`
        Where each error (by symbol) enters the chain.
    name : str
        The machine's name.
    form : {"euler", "screw", "rodrigues", "first_order"}
        The rigid motion of a block of errors ``(d, w)``: ``[Rx Ry Rz | d]``, ``exp`` of the
        twist, ``[exp([w]x) | d]`` or ``[I + [w]x | d]``.
    tilt : {"exact", "first_order"}
        How a squareness error ``w`` tilts a linear axis' direction: ``exp([w]x) e_k`` or
        ``e_k + w x e_k``.
    tool_offsets : sequence of str
        Pose names of the tool offset: one (along the tool axis z) or three (x, y, z in the
        last tool-side frame), mm.
    orientation : {"rotation_vector", "tool_axis"}
        The orientation part of the pose error: ``vee(R_actual R_ideal^T)`` (columns
        ``Rx Ry Rz``) or the change of the tool-axis direction (``Vx Vy Vz``), rad.
    pivots : mapping of str to (3,) array, optional
        Rotary axis -> a point its axis line passes through, mm, in the frame it rides on
        (default: the origin).
    travels : mapping of str to (float, float), optional
        Pose name (``x y z`` lower case, ``A B C``) -> (low, high), mm or rad.
    chunk : int
        Samples per batch (4096: every row of a batch stays in cache; the batch buffers are
        allocated once per call).
    axis_names : sequence of str, optional
        The order of the axes' pose names (messages, tables); default the topology's.

    Notes
    -----
    The error motions are ISO 230-1's (six per axis, in the frame after the motion), the
    location errors ISO 230-7's (the axis average line; before the motion, or after it in
    Zheng et al.'s reading of their Eq. 9).
    """

    def __init__(self, topology: str, catalogue: Sequence, placements: Mapping[str, Placement],
                 *, name: str = "chain", form: str = "euler", tilt: str = "exact",
                 tool_offsets: Sequence[str] = ("L",), orientation: str = "rotation_vector",
                 pivots: Mapping[str, Sequence[float]] | None = None,
                 travels: Mapping[str, tuple[float, float]] | None = None, chunk: int = 4096,
                 axis_names: Sequence[str] | None = None):
        self.topology = parse_topology(topology)
        if form not in FORMS:
            raise ValueError(f"unknown block form {form!r}; allowed: {', '.join(FORMS)}")
        if tilt not in ("exact", "first_order"):
            raise ValueError(f"unknown tilt {tilt!r}; allowed: exact, first_order")
        if orientation not in ORIENTATIONS:
            raise ValueError(f"unknown orientation {orientation!r}; allowed: "
                             f"{', '.join(ORIENTATIONS)}")
        tool_offsets = tuple(tool_offsets)
        if len(tool_offsets) not in (0, 1, 3):
            raise ValueError(f"tool_offsets must name 1 (along z) or 3 (x, y, z) pose values, "
                             f"got {tool_offsets}")
        self.name, self.form, self.tilt, self.orientation = name, form, tilt, orientation
        self.components = ORIENTATIONS[orientation]
        self.catalogue = tuple(catalogue)
        names = tuple(a.lower() if a in LINEAR else a for a in self.topology.axes)
        self._axis_pose = dict(zip(self.topology.axes, names, strict=True))
        if axis_names is not None:
            if sorted(axis_names) != sorted(names):
                raise ValueError(f"axis_names {tuple(axis_names)} must order the pose names "
                                 f"{names} of the topology")
            names = tuple(axis_names)
        self.axes = names
        self.tool_offsets = tool_offsets
        clash = set(tool_offsets) & set(self.axes)
        if clash:
            raise ValueError(f"tool offset name(s) {sorted(clash)} clash with axis names")
        self.placements = _check_placements(self.topology, self.catalogue, placements)
        pivots = dict(pivots or {})
        for a, p in pivots.items():
            if a not in self.topology.axes or a not in ROTARY:
                raise ValueError(f"pivot given for {a!r}, not a rotary axis of the topology")
            if np.shape(p) != (3,) or not np.all(np.isfinite(p)):
                raise ValueError(f"pivot of {a} must be 3 finite numbers (mm), got {p!r}")
        self.pivots = {a: np.asarray(p, dtype=float) for a, p in pivots.items()}
        self.travels = dict(travels or {})
        unknown = [k for k in self.travels if k not in self.axes]
        if unknown:
            raise ValueError(f"travels given for {unknown}, not pose names of the axes "
                             f"({', '.join(self.axes)})")
        self.chunk = validate.integer(chunk, "chunk", low=1)
        self._blocks = {(a, s): _Block() for a in self.topology.axes for s in SLOTS}
        for j, p in enumerate(self.placements):
            b = self._blocks[(p.axis, p.slot)]
            b.cols.append(j)
            b.comps.append(p.component)
            b.signs.append(float(p.sign))
        self._euler_angles = sorted(
            j for (_, slot), b in self._blocks.items() if form == "euler" and slot != "tilt"
            for j, c in zip(b.cols, b.comps, strict=True) if c >= 3)
        self._factors = self._build_factors()
        self._plan = self._build_plan()

    # -- description -----------------------------------------------------------------------
    def describe(self) -> str:
        """One line: the machine's name, its chain (:meth:`Topology.describe`), its errors.

        Returns
        -------
        str
            ``"<name>: <chain> (<n_errors> errors)"``.
        """
        return f"{self.name}: {self.topology.describe()} ({self.n_errors} errors)"

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.name!r}: {self.n_errors} errors, axes {self.axes}>"

    @property
    def error_names(self) -> list[str]:
        """list of str: the error symbols in catalogue order (the columns of an error array)."""
        return _errors.symbols(self.catalogue)

    @property
    def n_errors(self) -> int:
        """int: the number of errors of the catalogue."""
        return len(self.catalogue)

    def check_errors(self, errors) -> np.ndarray:
        """Validate an error array against the catalogue.

        Parameters
        ----------
        errors : (n, n_errors) array_like
            Error values in mm and rad, columns in catalogue order (:attr:`error_names`).

        Returns
        -------
        (n, n_errors) ndarray of float
            ``errors`` as a float array.

        Raises
        ------
        ValueError
            If ``errors`` is not two-dimensional with ``n_errors`` columns.
        """
        e = np.asarray(errors, dtype=float)
        if e.ndim != 2 or e.shape[1] != self.n_errors:
            raise ValueError(
                f"errors for {self.name} must have shape (n, {self.n_errors}) "
                f"(columns: {', '.join(self.error_names)}), got {e.shape}"
            )
        return e

    def check_pose(self, pose: Mapping, n: int) -> dict[str, np.ndarray]:
        """Validate a pose mapping; axes are required, tool offsets default to 0.

        Parameters
        ----------
        pose : mapping of str to float or (n,) array
            Axis positions (linear axes mm, rotary axes rad) by pose name (:attr:`axes`)
            and, optionally, tool offsets (mm, :attr:`tool_offsets`).
        n : int
            The number of samples every value is broadcast to.

        Returns
        -------
        dict of str to (n,) ndarray
            Every axis and tool offset name, each broadcast to ``(n,)`` (read-only views).

        Raises
        ------
        TypeError
            If ``pose`` is not a mapping.
        ValueError
            If a name is unknown, an axis is missing or a value is neither a scalar nor of
            shape ``(n,)`` (or ``(1,)``).
        """
        if not isinstance(pose, Mapping):
            raise TypeError(f"pose must be a mapping of {self.axes + self.tool_offsets}")
        allowed = self.axes + self.tool_offsets
        unknown = [k for k in pose if k not in allowed]
        if unknown:
            raise ValueError(f"unknown pose name(s) {unknown} for {self.name}; "
                             f"allowed: {', '.join(allowed)}")
        missing = [a for a in self.axes if a not in pose]
        if missing:
            raise ValueError(f"pose for {self.name} lacks axis value(s) {missing}")
        out = {}
        for k in allowed:
            v = np.asarray(pose.get(k, 0.0), dtype=float)
            if v.ndim > 1 or (v.ndim == 1 and v.shape[0] not in (1, n)):
                raise ValueError(f"pose[{k!r}] must be a scalar or have shape ({n},), "
                                 f"got {v.shape}")
            out[k] = np.broadcast_to(v, (n,))
        return out

    def factors(self) -> list[tuple[int, str, str]]:
        """The chain's factors in output order.

        The workpiece side inverted (its factors outermost-last), then the tool side.

        Returns
        -------
        list of (int, str, str)
            ``(side, axis, slot)`` per factor: side -1 (workpiece) or +1 (tool), the axis
            letter, and the slot (``pre``, ``move`` -- the nominal motion --, ``motion``,
            ``post``).
        """
        return list(self._factors)

    def _build_factors(self):
        seq = []
        for a in self.topology.axes:
            steps = ["pre", "move", "motion", "post"]
            seq.append([(self.topology.side(a), a, s) for s in steps])
        work = [f for a, fs in zip(self.topology.axes, seq, strict=True)
                if a in self.topology.work for f in fs]
        tool = [f for a, fs in zip(self.topology.axes, seq, strict=True)
                if a in self.topology.tool for f in fs]
        return list(reversed(work)) + tool

    # -- evaluation ------------------------------------------------------------------------
    def _direction(self, e, axis, k):
        """The (possibly tilted) direction of a linear axis: 3 rows or scalars."""
        unit = [0.0, 0.0, 0.0]
        unit[DIRECTION[axis]] = 1.0
        b = self._blocks[(axis, "tilt")]
        if not b.cols:
            return unit
        w = [np.zeros(k) for _ in range(3)]
        for j, c, s in zip(b.cols, b.comps, b.signs, strict=True):
            w[c - 3] = e[j] if s == 1.0 else s * e[j]
        wxe = cross_rows(w, unit)
        if self.tilt == "first_order":
            return [unit[i] + wxe[i] for i in range(3)]
        a, bb, _ = exp_coefficients(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
        wwxe = cross_rows(w, wxe)
        return [unit[i] + a * wxe[i] + bb * wwxe[i] for i in range(3)]

    def _ops(self, e, p, side, axis, slot, k, trig=None):
        """The factor as operations on the carried rows, in the order they apply: ``("t",
        [3 rows or None])`` adds to the point, ``("r", i, c, s)`` rotates about coordinate i,
        ``("m", R)`` multiplies by a 3x3 of rows; inverted for the workpiece side.  ``trig``:
        error column -> (cos, sin) rows of every euler-block angle."""
        if slot == "move":
            q = p[self._axis_pose[axis]]
            if axis in LINEAR:
                d = self._direction(e, axis, k)
                sq = -q if side < 0 else q
                t = [None if (np.ndim(di) == 0 and di == 0.0) else di * sq for di in d]
                ops = [("t", t)]
                return [("t", [None if ti is None else -ti for ti in t])] if side < 0 else ops
            c, sn = cos_sin(q)
            piv = self.pivots.get(axis)
            ops = [("r", DIRECTION[axis], c, -sn if side < 0 else sn)]
            if piv is not None:
                ops = [("t", [-piv[i] for i in range(3)]), *ops, ("t", [piv[i] for i in range(3)])]
            return ops
        b = self._blocks[(axis, slot)]
        if not b.cols:
            return []
        d, w = [None] * 3, [None] * 3
        for j, c, sg in zip(b.cols, b.comps, b.signs, strict=True):
            val = e[j] if sg == 1.0 else sg * e[j]
            if c < 3:
                d[c] = val
            else:
                w[c - 3] = val
        if self.form == "euler":      # [Rx Ry Rz | d]: Rz first, then Ry, Rx, then + d
            rots = []
            for j, c, sg in zip(b.cols, b.comps, b.signs, strict=True):
                if c >= 3:
                    cj, sj = trig[j]
                    rots.append((c - 3, ("r", c - 3, cj, sj if sg == 1.0 else -sj)))
            rots = [op for _, op in sorted(rots, key=lambda t: -t[0])]
            if side > 0:
                return [*rots, ("t", d)]
            return [("t", [None if di is None else -di for di in d]),
                    *[(o, i, c, -sn) for o, i, c, sn in reversed(rots)]]
        zero = np.zeros(k)
        dd = [zero if di is None else di for di in d]
        ww = [zero if wi is None else wi for wi in w]
        r, t = motion_rows(dd, ww, form=self.form)
        if side > 0:
            return [("m", r), ("t", t)]
        ri, _ = inverse_rows(r, t, ww, form=self.form)
        return [("t", [-ti for ti in t]), ("m", ri)]

    @staticmethod
    def _run(v, ops, scratch):
        """Apply operations to ``v``, a list of the three coordinate rows (each (m, k): the
        point and the directions), in place where the operation allows (``scratch``: two
        arrays of the rows' shape)."""
        for op in ops:
            if op[0] == "t":
                for i, ti in enumerate(op[1]):
                    if ti is not None:
                        v[i][0] += ti
            elif op[0] == "r":             # in place, with two scratch rows: no allocation
                _, ax, c, sn = op
                vi, vj = v[(ax + 1) % 3], v[(ax + 2) % 3]
                t0, t1 = scratch
                np.multiply(vi, sn, out=t0)
                np.multiply(vj, sn, out=t1)
                vi *= c
                vj *= c
                vi -= t1                   # c vi - s vj
                vj += t0                   # s vi + c vj
            else:
                r = op[1]
                v0, v1, v2 = v
                v[:] = [r[i][0] * v0 + r[i][1] * v1 + r[i][2] * v2 for i in range(3)]
        return v

    def _propagate(self, e, p, vecs, work: dict):
        """Carry ``vecs`` (m, 3, k) (row 0 a point, the others directions) through g_wt;
        ``e`` (k, n_errors) is read as contiguous rows, one per error.  ``work``: the buffers
        of one call, by chunk size (allocated once, not per chunk)."""
        k = e.shape[0]
        cols = self._euler_angles
        if k not in work:
            work[k] = (np.empty((self.n_errors, k)),
                       *(np.empty((len(cols), k)) for _ in range(4)))
        e_t, ang, c_all, s_all, x2 = work[k]
        e_t[...] = e.T
        v = [np.ascontiguousarray(vecs[:, i]) for i in range(3)]
        if v[0].shape[-1] != k:
            v = [np.ascontiguousarray(np.broadcast_to(r, (r.shape[0], k))) for r in v]
        scratch = (np.empty_like(v[0]), np.empty_like(v[0]))
        # cos and sin of every angle of an euler block at once (one call, not one per angle)
        trig = {}
        if cols:
            np.take(e_t, cols, axis=0, out=ang, mode="clip")
            cos_sin_into(ang, c_all, s_all, x2)
            trig = {j: (c_all[i], s_all[i]) for i, j in enumerate(cols)}
        for side, axis, slot in reversed(self.factors()):
            self._run(v, self._ops(e_t, p, side, axis, slot, k, trig), scratch)
        return np.stack(v, axis=1)

    def _start(self, p, k):
        """Tool tip and tool-frame axes before the tool-side factors: (4, 3, k)."""
        v = np.zeros((4, 3, k))
        v[1, 0] = v[2, 1] = v[3, 2] = 1.0
        if len(self.tool_offsets) == 1:
            v[0, 2] = p[self.tool_offsets[0]]
        elif len(self.tool_offsets) == 3:
            for i, name in enumerate(self.tool_offsets):
                v[0, i] = p[name]
        return v

    def relative(self, errors, pose: Mapping, with_errors: bool = True):
        """The tool frame in the workpiece frame, with or without the errors.

        Parameters
        ----------
        errors : (n, n_errors) array
            Error values in mm and rad, columns in catalogue order.
        pose : mapping of str to float or (n,) array
            Axis positions (mm, rad) and tool offsets (mm).
        with_errors : bool
            False: the ideal chain (``errors`` then only sets ``n``).

        Returns
        -------
        R : (n, 3, 3) ndarray
            Rotation of the tool frame.
        t : (n, 3) ndarray
            Position of the tool tip, mm.
        """
        e = self.check_errors(errors)
        n = e.shape[0]
        p = self.check_pose(pose, n)
        if not with_errors:
            e = np.zeros_like(e)
        r = np.empty((n, 3, 3))
        t = np.empty((n, 3))
        work = {}
        for s0 in range(0, n, self.chunk):
            sl = slice(s0, s0 + self.chunk)
            es = e[sl]
            ps = {key: val[sl] for key, val in p.items()}
            v = self._propagate(es, ps, self._start(ps, es.shape[0]), work)
            t[sl] = v[0].T
            r[sl] = np.moveaxis(v[1:], 2, 0).transpose(0, 2, 1)
        return r, t

    def pose_error(self, errors, pose: Mapping) -> np.ndarray:
        """The pose error of the tool in the workpiece frame, actual minus ideal.

        Parameters
        ----------
        errors : (n, n_errors) array
            Error values in mm and rad, columns in catalogue order.
        pose : mapping of str to float or (n,) array
            Axis positions (mm, rad) and tool offsets (mm); a pose the same for every sample
            is evaluated once for the ideal chain.

        Returns
        -------
        (n, 6) array
            Tool-tip position error ``Px, Py, Pz`` (mm), then the orientation error (rad): the
            rotation vector ``vee(R_actual R_ideal^T)`` or the change of the tool-axis
            direction, as ``self.components`` names them.
        """
        e = self.check_errors(errors)
        n = e.shape[0]
        p = self.check_pose(pose, n)
        out = np.empty((n, 6))
        work = {}
        want_frame = self.orientation == "rotation_vector"
        # one pose for every sample: scalars (cheaper operations) and the ideal chain once
        one = n > 0 and all(bool((val == val[0]).all()) for val in p.values())
        if one:
            p = {key: float(val[0]) for key, val in p.items()}
            start = self._start(p, 1)
            if not want_frame:
                start = start[[0, 3]]
            ide = self._propagate(np.zeros((1, e.shape[1])), p, start, work)
        for s0 in range(0, n, self.chunk):
            sl = slice(s0, s0 + self.chunk)
            es = e[sl]
            k = es.shape[0]
            ps = p if one else {key: val[sl] for key, val in p.items()}
            start = self._start(ps, k)
            if not want_frame:
                start = start[[0, 3]]
            act = self._propagate(es, ps, start, work)
            if not one:
                ide = self._propagate(np.zeros_like(es), ps, start, work)
            out[sl, :3] = (act[0] - ide[0]).T
            if want_frame:
                # vee of the skew part of R_a R_i^T = sum_j a_j i_j^T (a_j, i_j the columns)
                m = [[sum(act[1 + j, r_] * ide[1 + j, c_] for j in range(3)) for c_ in range(3)]
                     for r_ in range(3)]
                out[sl, 3] = 0.5 * (m[2][1] - m[1][2])
                out[sl, 4] = 0.5 * (m[0][2] - m[2][0])
                out[sl, 5] = 0.5 * (m[1][0] - m[0][1])
            else:
                out[sl, 3:] = (act[1] - ide[1]).T
        return out

    def transforms(self, errors, pose: Mapping):
        """The actual and the ideal tool frame in the workpiece frame as 4x4 transforms.

        Parameters
        ----------
        errors : (n, n_errors) array
            Error values in mm and rad, columns in catalogue order.
        pose : mapping of str to float or (n,) array
            Axis positions (mm, rad) and tool offsets (mm).

        Returns
        -------
        actual, ideal : (n, 4, 4) ndarray
            Homogeneous transforms of :meth:`relative` with and without the errors (mm).
        """
        return (homogeneous(*self.relative(errors, pose)),
                homogeneous(*self.relative(errors, pose, with_errors=False)))

    def _difference_jacobian(self, pose: Mapping, step: float) -> np.ndarray:
        """d(pose error)/d(errors) at zero errors by central differences (``jacobian(step=)``).

        Parameters
        ----------
        pose : mapping of str to float or (P,) array
            Axis positions (mm, rad) and tool offsets (mm) of P poses.
        step : float
            Central-difference step, mm or rad; the model is smooth, so the result is exact
            to about ``step**2``.

        Returns
        -------
        (P, 6, n_errors) ndarray
            Row ``[p, i, j]`` is d(pose error component i)/d(error j) at pose p
            (``(1, 6, n_errors)`` for a scalar pose); translational errors give
            dimensionless coefficients, angular errors mm per rad.
        """
        vals = {k: np.atleast_1d(np.asarray(v, dtype=float)) for k, v in pose.items()}
        n_poses = max(v.shape[0] for v in vals.values())
        d = self.n_errors
        eye = np.eye(d) * step
        e = np.concatenate([eye, -eye])                                   # (2d, d)
        rows = np.tile(e, (n_poses, 1))
        rep = {k: np.repeat(np.broadcast_to(v, (n_poses,)), 2 * d) for k, v in vals.items()}
        pe = self.pose_error(rows, rep).reshape(n_poses, 2, d, 6)
        return np.swapaxes((pe[:, 0] - pe[:, 1]) / (2 * step), 1, 2)

    # -- first order ------------------------------------------------------------------------
    def _build_plan(self):
        """Per error, for :meth:`jacobian`: the position of its factor in
        :meth:`factors`, its kind (0 translation, 1 rotation, 2 tilt), the unit vector of its
        component, the direction of its axis (tilts), sign x side, and the axis (tilts)."""
        seq = self.factors()
        where = {}
        for i, (side, axis, slot) in enumerate(seq):
            where[(axis, "tilt" if slot == "move" else slot)] = (i, side)
        m = self.n_errors
        pos, kind = np.zeros(m, dtype=int), np.zeros(m, dtype=int)
        unit, ek, scale = np.zeros((m, 3)), np.zeros((m, 3)), np.zeros(m)
        tilt_axis = [""] * m
        for j, pl in enumerate(self.placements):
            i, side = where[(pl.axis, pl.slot)]
            pos[j] = i
            unit[j, pl.component % 3] = 1.0
            scale[j] = pl.sign * side
            if pl.slot == "tilt":
                kind[j] = 2
                ek[j, DIRECTION[pl.axis]] = 1.0
                tilt_axis[j] = pl.axis
                scale[j] = pl.sign * side * side    # the move is by s q, s = side for linear
            else:
                kind[j] = 0 if pl.component < 3 else 1
        return pos, kind, unit, ek, scale, tilt_axis

    def jacobian(self, pose: Mapping, *, step: float | None = None) -> np.ndarray:
        """The Jacobian d(pose error)/d(errors) at zero errors: exact, in closed form.

        (P, 6, n) for pose arrays of length P.  An error block is a small twist ``(v, w)`` in its
        frame; with ``R_A`` the rotation of the factors before it (output order) and ``p_B``,
        ``a_B`` the tool tip and tool axis carried through the factors after it, it moves the
        tip by ``R_A (w x p_B + v)`` and turns the tool by ``R_A w`` (the tool axis by
        ``R_A (w x a_B)``), with the opposite sign on the workpiece side (the inverse of I + xi
        is I - xi to first order).  A tilt ``w`` of a linear axis moved by ``s q`` is the
        translation ``s q (w x e_k)``.  All forms agree to first order.

        Parameters
        ----------
        pose : mapping of str to float or (P,) array
            Axis positions (mm, rad) and tool offsets (mm) of P poses.
        step : float, optional
            None (default): the closed form.  A step (mm or rad) gives central differences of
            :meth:`pose_error` instead, an independent check of the closed form (exact to about
            ``step**2``; tests and notebook 01 compare the two).

        Returns
        -------
        (P, 6, n_errors) ndarray
            d(pose error component)/d(error) at zero errors, per pose: dimensionless for
            translational errors, mm per rad for angular ones (position rows).
        """
        if step is not None:
            return self._difference_jacobian(pose, step)
        vals = {k: np.atleast_1d(np.asarray(v, dtype=float)) for k, v in pose.items()}
        n = max((v.shape[0] for v in vals.values()), default=1)
        p = self.check_pose(vals, n)
        zero_e = np.zeros((self.n_errors, n))        # errors as rows, one per error
        seq = self.factors()
        # forward: rotation of everything before each factor, (n, 3, 3); only the rotary
        # motions turn (every other factor is a translation or, at zero errors, identity):
        # their rotation is their operations applied to the three basis vectors
        before = []
        rot = np.broadcast_to(np.eye(3), (n, 3, 3))
        for side, axis, slot in seq:
            before.append(rot)
            if slot == "move" and axis in ROTARY:
                basis = [np.zeros((4, n)) for _ in range(3)]    # row 0 a point, 1-3 the axes
                for i in range(3):
                    basis[i][1 + i] = 1.0
                scratch = (np.empty((4, n)), np.empty((4, n)))
                self._run(basis, self._ops(zero_e, p, side, axis, slot, n), scratch)
                rot = matmul3(rot, np.stack([b[1:] for b in basis]).transpose(2, 0, 1))  # [i, j]
        # backward: tip and tool axis after each factor (in that factor's frame); only the
        # motions move them at zero errors
        after = [None] * len(seq)
        start = self._start(p, n)[[0, 3]]
        v = [np.ascontiguousarray(start[:, i]) for i in range(3)]
        scratch = (np.empty_like(v[0]), np.empty_like(v[0]))
        for i in range(len(seq) - 1, -1, -1):
            after[i] = np.stack(v, axis=1)
            side, axis, slot = seq[i]
            if slot == "move":
                self._run(v, self._ops(zero_e, p, side, axis, slot, n), scratch)
        pos, kind, unit, ek, scale, tilt_axis = self._plan
        ra = np.stack(before)                                     # (F, n, 3, 3)
        aft = np.stack(after)                                     # (F, 2, 3, n)
        tip, ax = aft[pos, 0], aft[pos, 1]                        # (E, 3, n)
        u = unit[:, :, None]                                      # (E, 3, 1)
        dp = np.where(kind[:, None, None] == 0, u, 0.0)           # translations
        rotn = kind[:, None, None] == 1
        dp = np.where(rotn, np.cross(u, tip, axis=1), dp)
        q = np.stack([p[self._axis_pose[a_]] if a_ else np.zeros(n) for a_ in tilt_axis])
        dp = np.where(kind[:, None, None] == 2, np.cross(u, ek[:, :, None], axis=1)
                      * q[:, None, :], dp)
        dr = (np.cross(u, ax, axis=1) if self.orientation == "tool_axis"
              else np.broadcast_to(u, dp.shape))
        dr = np.where(rotn, dr, 0.0)
        r_e = ra[pos]                                             # (E, n, 3, 3)
        jac = np.empty((n, 6, self.n_errors))
        jac[:, :3] = np.einsum("enij,ejn->nie", r_e, dp) * scale
        jac[:, 3:] = np.einsum("enij,ejn->nie", r_e, dr) * scale
        return jac + 0.0


# ------------------------------------------------------------------------------------------
# ISO 230-1 catalogue from a topology
# ------------------------------------------------------------------------------------------

def _motion_specs(axis: str) -> list[tuple[_errors.ErrorSpec, Placement]]:
    out = []
    for c, comp in enumerate(COMPONENTS):
        code = _errors.iso_code(comp, axis)
        translational = c < 3
        if axis in LINEAR:
            kind = ("positioning" if c == DIRECTION[axis] else "straightness") if c < 3 \
                else "angular"
        else:
            kind = "error motion"
        spec = _errors.ErrorSpec(code, code, kind, axis, "xyz"[c % 3], translational, True,
                                 "um" if translational else "urad")
        out.append((spec, Placement(axis, "motion", c)))
    return out


def iso_catalogue(topology: str):
    """The ISO 230-1 / 230-7 errors of a topology, before redundancy is removed.

    Per axis K its six error motions EXK, EYK, EZK, EAK, EBK, ECK (block after the motion); for
    the linear axes the squareness errors with the first of X, Y, Z present as reference (the
    second tilted about the normal of their plane, e.g. EC0Y; the third about both others, e.g.
    EA0Z, EB0Z); per rotary axis K its four location errors (ISO 230-7): the two positions and
    two orientations of its axis line perpendicular to k (e.g. for C: EX0C, EY0C, EA0C, EB0C),
    as a block before its motion.  Returns ``(catalogue, placements)``.

    Parameters
    ----------
    topology : str
        The chain (:func:`parse_topology`).

    Returns
    -------
    catalogue : tuple of ErrorSpec
        Every error, in chain order.
    placements : dict of str to Placement
        Where each enters the chain.
    """
    topo = parse_topology(topology)
    specs = []
    for a in topo.axes:
        specs += _motion_specs(a)
    linear = [a for a in LINEAR if a in topo.axes]
    for rank, a in enumerate(linear):
        for b in linear[:rank]:
            about = 3 - DIRECTION[a] - DIRECTION[b]            # the normal of the a-b plane
            code = _errors.squareness_code(b, a)
            spec = _errors.ErrorSpec(code, code, "squareness", f"{b}{a}", "xyz"[about], False,
                                     False, "urad")
            specs.append((spec, Placement(a, "tilt", 3 + about)))
    for a in topo.axes:
        if a not in ROTARY:
            continue
        perp = [c for c in range(3) if c != DIRECTION[a]]
        for c in perp:
            code = _errors.iso_code(COMPONENTS[c], a, zero=True)
            specs.append((_errors.ErrorSpec(code, code, "location", a, "xyz"[c], True, False,
                                            "um"), Placement(a, "pre", c)))
        for c in perp:
            code = _errors.iso_code(COMPONENTS[3 + c], a, zero=True)
            specs.append((_errors.ErrorSpec(code, code, "location", a, "xyz"[c], False, False,
                                            "urad"), Placement(a, "pre", 3 + c)))
    return tuple(s for s, _ in specs), {s.symbol: p for s, p in specs}


def redundant_location_errors(machine: ChainMachine, *, n_poses: int = 64, seed=0,
                              rtol: float = 1e-9) -> list[tuple[str, str]]:
    """Location errors that cannot be told apart from other errors (a rank test).

    Those whose effect on the pose error, over random poses, is a combination of the effects of
    the axes' zero positions (the columns of their own-direction error motions, EXX, ..., ECC),
    of the workpiece and tool set-up (a constant rigid shift of the workpiece, a constant offset
    of the tool) and of the location errors before them: they cannot be told apart from those
    and are not separate errors.  Returns (symbol, reason) pairs, in catalogue order.  The test is
    a rank test of the stacked Jacobian columns (least-squares residual of the unit column below
    ``rtol``).

    Parameters
    ----------
    machine : ChainMachine
        A machine with its full catalogue (:func:`iso_catalogue`).
    n_poses : int
        Random poses stacked in the rank test.
    seed : int
        Seed of the poses.
    rtol : float
        Relative least-squares residual below which a column is a combination of others.

    Returns
    -------
    list of (str, str)
        (symbol, reason) of every redundant location error; a reason is never blank.

    Raises
    ------
    ValueError
        When a travel is not finite, or the tool position or the Jacobian at the sampled poses
        is not (travels, pivots or tool offsets beyond the range of floating point).

    Notes
    -----
    Each column is scaled by its largest entry before it is normalised: the squares of a
    column with entries above about 1e154 (a travel of 1e300 mm) overflow, its norm is then
    infinite and the unit column all zeros, which the least-squares fit explains with no term
    at all.  Travels that large are not a machine (:func:`read_axis_table` refuses them), and
    the rank test of columns mixing such entries with ordinary ones is not meaningful; the
    scaling only keeps the arithmetic finite.
    """
    n_poses = validate.integer(n_poses, "n_poses", low=1)
    rng = validate.rng(seed)
    pose = {}
    for a, name in machine._axis_pose.items():
        lo, hi = machine.travels.get(name, (-300.0, 300.0) if a in LINEAR else (-np.pi, np.pi))
        if not np.isfinite(float(hi) - float(lo)):
            raise ValueError(f"{machine.name}: the travel {(lo, hi)} of {name} is not finite "
                             f"(or its width overflows); no poses can be drawn from it")
        pose[name] = rng.uniform(lo, hi, n_poses)
    for t in machine.tool_offsets:
        pose[t] = rng.uniform(50.0, 150.0, n_poses)
    jac = machine.jacobian(pose)                      # (P, 6, n)
    zero = np.zeros((n_poses, machine.n_errors))
    rt, tt = machine.relative(zero, pose, with_errors=False)
    if not (np.all(np.isfinite(jac)) and np.all(np.isfinite(tt))):
        raise ValueError(f"{machine.name}: the tool position or the first-order effects of the "
                         f"errors are not finite at the sampled poses; check the travels, "
                         f"pivots and tool offsets (travels {machine.travels})")
    axis_out = machine.orientation == "tool_axis"

    def as_error(dt, dr):
        """Pose-error columns of a first-order change: tip dt, rotation vector dr (n, 3)."""
        col = np.zeros((n_poses, 6))
        col[:, :3] = dt
        col[:, 3:] = np.cross(dr, rt[:, :, 2]) if axis_out else dr
        return col

    # effects that are not errors: the zero of each axis, a rigid set-up error of the
    # workpiece (6 dof, in the workpiece frame) and a tool offset error (along the tool
    # frame's axes)
    nuisance, labels = [], []
    for j, pl in enumerate(machine.placements):   # an axis' zero: its own-direction error
        own = DIRECTION[pl.axis] + (3 if pl.axis in ROTARY else 0)
        if pl.slot == "motion" and pl.component == own:
            nuisance.append(jac[:, :, j])
            labels.append(f"the zero of {machine._axis_pose[pl.axis]}")
    unit = np.eye(3)
    for c in range(3):
        nuisance.append(as_error(-np.broadcast_to(unit[c], tt.shape), np.zeros_like(tt)))
        labels.append(f"the workpiece set-up along {'xyz'[c]}")
    for c in range(3):
        u = np.broadcast_to(unit[c], tt.shape)
        nuisance.append(as_error(-np.cross(u, tt), -u))
        labels.append(f"the workpiece set-up about {'xyz'[c]}")
    for c in range(3):
        nuisance.append(as_error(rt[:, :, c], np.zeros_like(tt)))
        labels.append(f"the tool offset along {'xyz'[c]}")
    basis, names_b = [], []
    for col, lab in zip(nuisance, labels, strict=True):
        vec = _unit(col.reshape(-1))
        if vec is not None:
            basis.append(vec)
            names_b.append(lab)
    out = []

    def explain(vec):
        """(residual, names of the basis columns the least-squares fit uses)."""
        m = np.stack(basis, 1)
        coef, *_ = np.linalg.lstsq(m, vec, rcond=None)
        used = [names_b[i] for i in np.flatnonzero(np.abs(coef) > 1e-6)]
        return np.linalg.norm(vec - m @ coef), used

    for j, spec in enumerate(machine.catalogue):
        if spec.position_dependent:
            continue
        vec = _unit(jac[:, :, j].reshape(-1))
        if vec is None:
            out.append((spec.symbol, "no effect on the pose error"))
            continue
        res, used = explain(vec)
        if res < rtol:
            out.append((spec.symbol, _same_effect(used)))
            continue
        basis.append(vec)
        names_b.append(spec.symbol)
    return out


def _unit(vec):
    """``vec`` scaled to unit length, or None when it is zero.  Scaled by its largest entry
    first: the squares in the norm of a vector with entries above about 1e154 overflow (its
    norm is then infinite and ``vec / norm`` all zeros)."""
    big = np.max(np.abs(vec), initial=0.0)
    if big == 0.0:
        return None
    vec = vec / big
    return vec / np.linalg.norm(vec)


def _same_effect(used) -> str:
    """The reason given for a redundant error: the effects its column is a combination of,
    or, when the fit names none, that in words (never a blank reason)."""
    if not used:
        return ("same effect as a combination of the other effects, none of which could be "
                "named (check the travels, pivots and tool offsets for extreme values)")
    return "same effect as " + " + ".join(used)


def iso_machine(topology: str, *, name: str = "iso_machine", keep_redundant: bool = False,
                **options) -> ChainMachine:
    """A machine of any topology with its ISO 230-1 / 230-7 catalogue.

    Parameters
    ----------
    topology : str
        The chain (:func:`parse_topology`).
    name : str
        The machine's name.
    keep_redundant : bool
        Keep the location errors :func:`redundant_location_errors` finds (default: removed).
    **options
        Passed to :class:`ChainMachine` (``form`` default ``"euler"``; ``orientation``
        default ``"tool_axis"`` when the topology has a rotary axis, else
        ``"rotation_vector"``; ``pivots``, ``travels``, ``tool_offsets`` ...).

    Returns
    -------
    ChainMachine
        With ``machine.removed``: the (symbol, reason) of every removed location error.
        Location errors sit before their axis' motion (ISO 230-7), squareness errors tilt the
        directions of the linear axes (:func:`iso_catalogue`).

    Examples
    --------
    A three-axis machine with every axis on the tool side: a positioning error EXX of 1 um,
    and an angular error EBX of 10 urad seen through a 200 mm tool (Abbe offset: 2 um).

    >>> import numpy as np
    >>> m = iso_machine("w b X Y Z t")
    >>> m.n_errors, m.axes, m.tool_offsets
    (21, ('x', 'y', 'z'), ('L',))
    >>> e = np.zeros((2, m.n_errors))
    >>> e[0, m.error_names.index("EXX")] = 0.001               # mm
    >>> e[1, m.error_names.index("EBX")] = 1e-5                # rad
    >>> pe = m.pose_error(e, {"x": 100.0, "y": 0.0, "z": 0.0, "L": 200.0})
    >>> pe.shape
    (2, 6)
    >>> pe[:, 0].round(6).tolist(), round(float(pe[1, 4]), 9)  # Px (mm), Ry (rad)
    ([0.001, 0.002], 1e-05)
    """
    cat, placements = iso_catalogue(topology)
    topo = parse_topology(topology)
    options.setdefault("orientation", "tool_axis" if any(a in ROTARY for a in topo.axes)
                       else "rotation_vector")
    full = ChainMachine(topology, cat, placements, name=name, **options)
    removed = [] if keep_redundant else redundant_location_errors(full)
    drop = {s for s, _ in removed}
    if drop:
        cat = tuple(e for e in cat if e.symbol not in drop)
        full = ChainMachine(topology, cat, {s: placements[s] for s in (e.symbol for e in cat)},
                            name=name, **options)
    full.removed = removed
    return full


# ------------------------------------------------------------------------------------------
# A reader's machine from files: the axis table and the error ranges, checked before any work
# ------------------------------------------------------------------------------------------

AXIS_TABLE_COLUMNS = ("axis", "low", "high", "unit", "pivot_x_mm", "pivot_y_mm", "pivot_z_mm")
RANGE_COLUMNS = ("symbol", "low", "high", "unit")
#: Size caps of the input files, checked before (bytes) and while (rows) they are parsed.  An
#: axis table has one row per axis (at most six); a range file one per error of the catalogue
#: (51 for six axes with ISO 230-1/230-7: 36 error motions, 3 squareness errors, 12 location
#: errors).  1000 data rows leave a margin of twenty times that (a range file may hold up to
#: twice its machine's catalogue when that is larger); 2 MiB, 2000 rows of 1000 characters,
#: leaves ample room for comments.  A larger file is not a machine's description (a wrong
#: file, a log, a data dump) and is refused at once, naming the file and the limit.
MAX_TABLE_BYTES = 2 * 1024 * 1024
MAX_TABLE_ROWS = 1000
#: Bounds of a travel and of a pivot in the axis table.  The longest axes of machine tools
#: (gantry mills for ship hulls and aircraft spars) travel a few tens of metres, so no
#: coordinate of a linear axis or a pivot exceeds 100 m (1e5 mm).  A rotary axis repeats every
#: turn; ten turns either way (3600 deg) leave room for a multi-turn count.  Values far beyond
#: these are not a machine: from about 1e154 mm the squares in the rank test of
#: :func:`redundant_location_errors` overflow.
MAX_LINEAR_MM = 1e5
MAX_ROTARY_DEG = 3600.0
#: At most this many :class:`SuspectUnitWarning` per file, one per row, then one naming the
#: lines of the rest (a file written wholly in another unit would otherwise give one per row).
MAX_UNIT_WARNINGS = 5


@dataclass(frozen=True)
class _Row:
    """One data record of a CSV file: its first and last physical line (1-based, as an
    editor numbers them; a quoted field may span lines) and its values by column."""

    first: int
    last: int
    values: dict

    @property
    def where(self) -> str:
        return f"line {self.first}" if self.first == self.last else \
            f"lines {self.first}-{self.last}"


@dataclass(frozen=True)
class _Table:
    """A checked CSV file: its header line, its data records and where they stand."""

    header_line: int
    rows: list

    def span(self) -> str:
        """Where the header and the rows stand, for a message about a missing entry."""
        if not self.rows:
            return f"header on line {self.header_line}, no data rows"
        return (f"header on line {self.header_line}, rows on lines {self.rows[0].first}-"
                f"{self.rows[-1].last}")


def _read_csv(path, columns, what, max_rows=None) -> _Table:
    """Read a small CSV file with the physical line of every record, checked.

    ``#`` starts a comment (outside quotes) and lines left blank are skipped, like
    ``pandas.read_csv(comment="#", skip_blank_lines=True, skipinitialspace=True)``; records
    whose fields are all empty are skipped too.  Values are stripped strings; a short record
    is padded with empty strings.  The file must be UTF-8 (a byte-order mark is allowed).
    Refused before parsing: more than :data:`MAX_TABLE_BYTES` bytes or ``10 * max_rows``
    lines; while parsing: more than ``max_rows`` data rows (default
    :data:`MAX_TABLE_ROWS`)."""
    path = str(path)
    max_rows = MAX_TABLE_ROWS if max_rows is None else max_rows
    try:
        size = os.path.getsize(path)
    except FileNotFoundError:
        raise FileNotFoundError(f"{what} {path!r} not found") from None
    if size > MAX_TABLE_BYTES:
        raise ValueError(f"{what} {path!r} is {size} bytes, more than the {MAX_TABLE_BYTES} "
                         f"bytes allowed; it should hold a few dozen rows (is it the right "
                         f"file?)")
    with open(path, "rb") as handle:
        raw = handle.read(MAX_TABLE_BYTES + 1)
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ValueError(f"{what} {path!r}, line {csvlines.bad_byte_line(raw, exc)}: not UTF-8 "
                         f"text ({exc.reason})") from None
    flat = text.replace("\r\n", "\n").replace("\r", "\n")  # as an editor counts lines
    n_lines = flat.count("\n") + (not flat.endswith("\n"))
    if n_lines > 10 * max_rows:
        raise ValueError(f"{what} {path!r} has {n_lines} lines, more than the {10 * max_rows} "
                         f"allowed ({max_rows} data rows, with comments); it should hold a few "
                         f"dozen rows (is it the right file?)")
    header, index, rows = None, {}, []
    found = csvlines.records(text, comment="#")
    while True:
        try:
            first, last, fields = next(found)
        except StopIteration:
            break
        except csvlines.CSVLineError as exc:
            raise ValueError(f"{what} {path!r}, line {exc.line}: {exc.reason}") from None
        if header is None:
            header = [h.strip() for h in fields]
            header_line = first
            where = f"{what} {path!r}, line {first} (the header)"
            twice = sorted(c for c in columns if header.count(c) > 1)
            if twice:
                raise ValueError(f"{where}: column(s) {twice} given more than once")
            missing = [c for c in columns if c not in header]
            if missing:
                raise ValueError(f"{where}: lacks column(s) {missing}; it needs "
                                 f"{', '.join(columns)}")
            index = {c: header.index(c) for c in columns}
            continue
        if not "".join(fields).strip():
            continue
        if len(rows) == max_rows:
            raise ValueError(f"{what} {path!r}, line {first}: more than {max_rows} data rows; "
                             f"it should hold one row per "
                             f"{'axis' if what == 'axis table' else 'error'} (is it the right "
                             f"file?)")
        row = _Row(first, last, {c: fields[i].strip() if i < len(fields) else ""
                                 for c, i in index.items()})
        if len(fields) > len(header) and any(f.strip() for f in fields[len(header):]):
            raise ValueError(f"{what} {path!r}, {row.where}: {len(fields)} fields, but the "
                             f"header (line {header_line}) names {len(header)} columns")
        rows.append(row)
    if header is None:
        raise ValueError(f"{what} {path!r} has no header line (it is empty or all comments); "
                         f"it needs the columns {', '.join(columns)}")
    return _Table(header_line, rows)


def _at(groups, n: int = 5) -> str:
    """Where entries stand, from ``(name, [lines])`` pairs: ``line 7 (A)``, ``lines 3 and 8
    (X)``, ... at most ``n`` names and ``n`` lines each, then how many more."""
    parts = []
    for name, lines in groups[:n]:
        name = "empty" if not name else name if len(name) <= 20 else name[:20] + "..."
        if len(lines) == 1:
            parts.append(f"line {lines[0]} ({name})")
        elif len(lines) == 2:
            parts.append(f"lines {lines[0]} and {lines[1]} ({name})")
        else:
            more = f", ... ({len(lines)} lines)" if len(lines) > n else ""
            parts.append(f"lines {', '.join(map(str, lines[:n]))}{more} ({name})")
    if len(groups) > n:
        parts.append(f"... ({len(groups) - n} more)")
    return ", ".join(parts)


def _check_entries(table: _Table, column: str, wanted):
    """How the entries of ``column`` fail to name each of ``wanted`` exactly once: the
    unknown entries (in file order) and the repeated ones (sorted), each as ``(name, [lines
    where it stands])``, and the missing names (in ``wanted``'s order).  Linear in the rows
    (one dictionary of lines per name; no ``list.count`` per row)."""
    lines: dict[str, list[int]] = {}
    for row in table.rows:
        lines.setdefault(row.values[column], []).append(row.first)
    allowed = set(wanted)
    unknown = [(s, ls) for s, ls in lines.items() if s not in allowed]
    dup = sorted((s, ls) for s, ls in lines.items() if len(ls) > 1 and s in allowed)
    missing = [s for s in wanted if s not in lines]
    return unknown, dup, missing


def _in_unit(lim: _units.Limits, v, unit: str) -> str:
    """``; `` and what a row written in a unit the file does not take says: another spelling
    of an accepted unit, or its numbers in an accepted unit (:func:`.units.in_unit`); or
    ``""``."""
    canon = _units.canonical(unit)
    if canon in lim.accepted:
        return f"; {unit!r} is written {canon!r}"
    try:
        lo, hi = float(v["low"]), float(v["high"])
    except ValueError:
        return ""
    if not (np.isfinite(lo) and np.isfinite(hi) and hi > lo):
        return ""
    text = _units.in_unit(lim, lo, hi, unit=unit)
    return f"; {text}" if text else ""


def _warn_rows(where: str, found: list) -> None:
    """Emit the :class:`SuspectUnitWarning` of ``found`` (``(row, message)`` pairs): one per row
    up to :data:`MAX_UNIT_WARNINGS`, then one naming the lines of the rest.  Attributed to the
    reader's caller (a notebook cell shows them under it)."""
    for _, message in found[:MAX_UNIT_WARNINGS]:
        warnings.warn(message, _units.SuspectUnitWarning, stacklevel=3)
    rest = found[MAX_UNIT_WARNINGS:]
    if rest:
        warnings.warn(f"{where}: {len(rest)} more row(s) with a value that suggests another "
                      f"unit, at {', '.join(r.where for r, _ in rest[:20])}"
                      + (", ..." if len(rest) > 20 else ""),
                      _units.SuspectUnitWarning, stacklevel=3)


def read_axis_table(path, topology: str) -> tuple[dict, dict]:
    """The travels and rotary pivots of a topology's axes from a CSV file, checked.

    Parameters
    ----------
    path : str or Path
        A CSV with the columns ``axis, low, high, unit, pivot_x_mm, pivot_y_mm, pivot_z_mm``
        (:data:`AXIS_TABLE_COLUMNS`; others are ignored, ``#`` starts a comment, blank lines
        are skipped): one row per axis of the topology; the travel in ``mm`` (linear, within
        +-:data:`MAX_LINEAR_MM`) or ``deg`` (rotary, within +-:data:`MAX_ROTARY_DEG`); for a
        rotary axis a point its axis line passes through, mm, in the frame of the body it
        rides on (empty: the origin; must be empty for a linear axis).  At most
        :data:`MAX_TABLE_BYTES` bytes and :data:`MAX_TABLE_ROWS` rows.
    topology : str
        The machine's topology (:func:`parse_topology`).

    Returns
    -------
    travels : dict
        Pose name (``x y z``, ``A B C``) -> (low, high) in mm or rad.
    pivots : dict
        Rotary axis letter -> (3,) point, mm.

    Raises
    ------
    ValueError
        Naming the file and the line (1-based, as an editor numbers them) of the offending
        row, for a missing or extra axis, a repeated axis (both lines), a wrong unit (with the
        travel converted, when the unit is one of another name), a travel that is not finite
        with low < high or beyond the bounds, a travel no machine tool has in the unit written
        (a linear span below 1 mm, a rotary span below 5 deg, or below 15 deg with ends that
        read as radians: :func:`.units.check`, naming the likely unit and the numbers to
        write), a pivot on a linear axis, half a pivot, a pivot beyond the bound, a missing
        column (the header's line), a file too large or with too many rows, a malformed CSV.
    FileNotFoundError
        When the file does not exist.

    Warns
    -----
    SuspectUnitWarning
        Once per row (at most :data:`MAX_UNIT_WARNINGS`, then one for the rest) whose travel
        only a rare machine has in the unit written (a linear span of 1-10 mm, a rotary span
        of 5-15 deg), naming the file, the line, the limit and the likely unit; the travel is
        used as written.  Emitted after the whole file is checked (a refused file warns of
        nothing).
    """
    topo = parse_topology(topology)
    table = _read_csv(path, AXIS_TABLE_COLUMNS, "axis table")
    where = f"axis table {str(path)!r}"
    unknown, dup, missing = _check_entries(table, "axis", topo.axes)
    if unknown:
        raise ValueError(f"{where}, {_at(unknown)}: axis/axes {_listed([s for s, _ in unknown])}"
                         f" not in the topology {topology!r} (its axes: "
                         f"{', '.join(topo.axes)})")
    if dup:
        raise ValueError(f"{where}, {_at(dup)}: axis/axes {_listed([s for s, _ in dup])} given "
                         f"more than once")
    if missing:
        raise ValueError(f"{where} ({table.span()}): no row for axis/axes {missing} of the "
                         f"topology {topology!r}")
    travels, pivots, suspect = {}, {}, []
    for row in table.rows:
        v = row.values
        a = v["axis"]
        line = f"{where}, {row.where} ({a})"
        unit = v["unit"]
        want = "mm" if a in LINEAR else "deg"
        lim = _units.LINEAR_TRAVEL if a in LINEAR else _units.ROTARY_TRAVEL
        if unit != want:
            kind = "linear" if a in LINEAR else "rotary"
            raise ValueError(f"{line}: unit must be {want!r} for a {kind} axis, got "
                             f"{_excerpt(unit, 20)}" + _in_unit(lim, v, unit))
        try:
            lo, hi = float(v["low"]), float(v["high"])
        except ValueError:
            raise ValueError(f"{line}: low and high must be numbers, got "
                             f"{_excerpt(v['low'], 20)}, {_excerpt(v['high'], 20)}") from None
        if not (np.isfinite(lo) and np.isfinite(hi) and hi > lo):
            raise ValueError(f"{line}: the travel must be finite with high > low, got "
                             f"({lo}, {hi})")
        bound = MAX_LINEAR_MM if a in LINEAR else MAX_ROTARY_DEG
        if max(-lo, hi) > bound:
            why = ("no machine axis travels more than 100 m" if a in LINEAR
                   else "a rotary axis repeats every turn; ten turns either way at most")
            hint = _units.suggest(lim, lo, hi, unit=unit, sure=False)
            raise ValueError(f"{line}: the travel ({lo:g}, {hi:g}) {unit} goes beyond "
                             f"+-{bound:g} {unit} ({why})" + (f"; {hint}" if hint else ""))
        found = _units.check(lim, lo, hi, unit=unit)
        if found is not None and found.refuse:
            raise ValueError(f"{line}: {found.message}")
        if found is not None:
            suspect.append((row, f"{line}: {found.message}"))
        scale = 1.0 if a in LINEAR else np.pi / 180.0
        name = a.lower() if a in LINEAR else a
        travels[name] = (lo * scale, hi * scale)
        piv = [v["pivot_x_mm"], v["pivot_y_mm"], v["pivot_z_mm"]]
        given = [p != "" for p in piv]
        if a in LINEAR:
            if any(given):
                raise ValueError(f"{line}: a linear axis has no pivot; leave pivot_*_mm empty")
            continue
        if any(given) and not all(given):
            raise ValueError(f"{line}: give all three pivot_*_mm or none")
        if all(given):
            try:
                point = np.array([float(p) for p in piv])
            except ValueError:
                raise ValueError(f"{line}: pivot_*_mm must be numbers, got "
                                 f"{[_excerpt(p, 20) for p in piv]}") from None
            if not np.all(np.isfinite(point)):
                raise ValueError(f"{line}: pivot_*_mm must be finite, got {piv}")
            if np.abs(point).max() > MAX_LINEAR_MM:
                raise ValueError(f"{line}: the pivot {point.tolist()} mm lies beyond "
                                 f"+-{MAX_LINEAR_MM:g} mm (no machine is larger than 100 m)")
            pivots[a] = point
    _warn_rows(where, suspect)
    return travels, pivots


def read_ranges(path, machine: ChainMachine) -> np.ndarray:
    """Uniform error ranges of a machine from a CSV file, checked against its catalogue.

    Parameters
    ----------
    path : str or Path
        A CSV with the columns ``symbol, low, high, unit`` (:data:`RANGE_COLUMNS`; others are
        ignored, ``#`` starts a comment, blank lines are skipped): one row per error of the
        catalogue; units ``um``, ``mm`` for translations and ``urad``, ``rad``, ``arcsec``,
        ``um/m`` for angles.  At most :data:`MAX_TABLE_BYTES` bytes and
        :data:`MAX_TABLE_ROWS` rows (or twice the catalogue, when that is more).
    machine : ChainMachine
        Whose catalogue the rows must match.

    Returns
    -------
    (2, n_errors) array
        Low and high bounds in mm and rad, columns in catalogue order.

    Raises
    ------
    ValueError
        Naming the file and the line (1-based, as an editor numbers them) of the offending
        row, for: an error the catalogue lacks (with why, when it is a redundant location
        error the catalogue removed), a repeated error (both lines), an unknown unit (with
        the units of the error's kind, and the range converted when the unit is a known one
        the file does not take: ``deg``, ``mrad``, ``mm/m``, ``nm``, ``m``, ``µm``) or one of
        the wrong kind (naming the units of its kind), a range that is not finite with low <
        high, a range no machine tool has (a translation beyond 10 mm, an angle beyond 0.01
        rad: :func:`.units.check`, naming the likely unit and the numbers to write); and for
        a missing error, a missing column (the header's line), a file too large or with too
        many rows, a malformed CSV.
    FileNotFoundError
        When the file does not exist.

    Warns
    -----
    SuspectUnitWarning
        Once per row (at most :data:`MAX_UNIT_WARNINGS`, then one for the rest) whose range
        only a rare machine has in the unit written (a translation beyond 1 mm or below 0.1
        nm, an angle beyond 1e-3 rad or below 1e-9 rad), naming the file, the line, the
        limit and the likely unit; the range is used as written.  Emitted after the whole
        file is checked.
    """
    names = machine.error_names
    table = _read_csv(path, RANGE_COLUMNS, "range file",
                      max_rows=max(MAX_TABLE_ROWS, 2 * len(names)))
    where = f"range file {str(path)!r}"
    column = {s: j for j, s in enumerate(names)}
    removed = dict(getattr(machine, "removed", []))
    unknown, dup, missing = _check_entries(table, "symbol", names)
    if unknown:
        shown = [s for s, _ in unknown]
        why = [f"{s} (removed: {removed[s]})" for s in shown[:10] if s in removed]
        raise ValueError(f"{where}, {_at(unknown)}: error(s) {_listed(shown)} not in the "
                         f"catalogue of {machine.name}"
                         + (f"; {'; '.join(why)}" if why else "")
                         + f"; its errors: {', '.join(names)}")
    if dup:
        raise ValueError(f"{where}, {_at(dup)}: error(s) {_listed([s for s, _ in dup])} given "
                         f"more than once")
    if missing:
        raise ValueError(f"{where} ({table.span()}): no range for error(s) {missing}")
    bounds, suspect = np.empty((2, len(names))), []
    for row in table.rows:
        v = row.values
        s = v["symbol"]
        line = f"{where}, {row.where} ({s})"
        unit = v["unit"]
        spec = machine.catalogue[column[s]]
        what = "a translation" if spec.translational else "an angle"
        lim = _units.TRANSLATION_ERROR if spec.translational else _units.ANGULAR_ERROR
        takes = f"{', '.join(lim.accepted[:-1])} or {lim.accepted[-1]}"
        if unit not in _errors.UNIT_SCALE:
            raise ValueError(f"{line}: unknown unit {_excerpt(unit, 20)}; allowed: "
                             f"{', '.join(_errors.UNIT_SCALE)}; {s} is {what} ({spec.kind}): "
                             f"write it in {takes}" + _in_unit(lim, v, unit))
        if spec.translational != (unit in _units.TRANSLATION_ERROR.accepted):
            length = "" if spec.translational else \
                "; a deviation over a length is an angle: divide by the length, um/m"
            raise ValueError(f"{line}: {s} is {what}, unit {unit!r} is not ({spec.kind}: write "
                             f"it in {takes}){length}")
        try:
            lo, hi = float(v["low"]), float(v["high"])
        except ValueError:
            raise ValueError(f"{line}: low and high must be numbers, got "
                             f"{_excerpt(v['low'], 20)}, {_excerpt(v['high'], 20)}") from None
        if not (np.isfinite(lo) and np.isfinite(hi) and hi > lo):
            raise ValueError(f"{line}: the range must be finite with high > low, got ({lo}, {hi})")
        found = _units.check(lim, lo, hi, unit=unit)
        if found is not None and found.refuse:
            raise ValueError(f"{line}: {found.message}")
        if found is not None:
            suspect.append((row, f"{line}: {found.message}"))
        scale = _errors.UNIT_SCALE[unit]
        bounds[:, column[s]] = lo * scale, hi * scale
    _warn_rows(where, suspect)
    return bounds


_SLOT_TEXT = {"motion": "error motion (after the motion)", "pre": "location (before the motion)",
              "post": "location (after the motion)", "tilt": "squareness (tilts the direction)"}


def catalogue_table(machine: ChainMachine, bounds=None):
    """A machine's errors as a table (a pandas DataFrame), with their ranges when given.

    Symbol, kind, the axis it belongs to, where it enters the chain and its component (``X Y Z``
    translations, ``A B C`` rotations), with the ``bounds`` (2, n) of uniform ranges in um and
    urad when given.

    Parameters
    ----------
    machine : ChainMachine
        The machine.
    bounds : array (2, n), optional
        Uniform ranges (mm, rad) of its errors.

    Returns
    -------
    DataFrame (n, 5 or 8)
        symbol, kind, axis, enters (where in the chain), component and, with ``bounds``, low,
        high and unit (um, urad).
    """
    table = pd.DataFrame({
        "symbol": machine.error_names, "kind": [e.kind for e in machine.catalogue],
        "axis": [p.axis for p in machine.placements],
        "enters": [_SLOT_TEXT[p.slot] for p in machine.placements],
        "component": [COMPONENTS[p.component] for p in machine.placements]})
    if bounds is not None:
        b = np.asarray(bounds, dtype=float)
        if b.shape != (2, machine.n_errors):
            raise ValueError(f"bounds must be (2, {machine.n_errors}), got {b.shape}")
        scale = np.where([e.translational for e in machine.catalogue], 1e-3, 1e-6)
        table["low"], table["high"] = b[0] / scale, b[1] / scale
        table["unit"] = ["um" if e.translational else "urad" for e in machine.catalogue]
    return table
