"""One kinematic chain for every machine: a topology, an error placement, a pose error.

A machine is a serial chain of linear (X, Y, Z) and rotary (A, B, C) axes between the
workpiece and the tool, given as a topology string read from the workpiece to the tool
(:mod:`.topology`: ``"w C A b Y X Z t"`` is Zheng et al. 2024's machine, ``b`` the bed), and
a placement of each error of its catalogue in that chain (:class:`Placement`).

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
:func:`.iso.iso_machine` builds any topology with the ISO 230-1 catalogue generated from it
and the redundant location errors removed by a rank test; :mod:`.readers` reads a reader's
machine (travels, pivots, error ranges) from files.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from .. import errors as _errors
from .. import validate
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
from .topology import (  # noqa: F401  (COMPONENTS, Placement: re-exported, their old home)
    COMPONENTS,
    DIRECTION,
    LINEAR,
    ROTARY,
    SLOTS,
    Placement,
    _Block,
    _check_placements,
    parse_topology,
)

#: the forms of a block of errors: ``euler`` (elementary rotations, applied one by one) and
#: the forms of :func:`mtaccuracy.kinematics.motion_rows`
FORMS = ("euler", *ROW_FORMS)
ORIENTATIONS = {"rotation_vector": ("Px", "Py", "Pz", "Rx", "Ry", "Rz"),
                "tool_axis": ("Px", "Py", "Pz", "Vx", "Vy", "Vz")}


# ------------------------------------------------------------------------------------------
# The machine
# ------------------------------------------------------------------------------------------

def _check_references(topology, references) -> dict:
    """The Abbe references of :class:`ChainMachine`, checked: linear axes, finite mm."""
    out = {}
    for a, r in dict(references or {}).items():
        if a not in topology.axes or a not in LINEAR:
            raise ValueError(f"reference given for {a!r}, not a linear axis of the topology "
                             f"{topology.text!r}")
        if isinstance(r, bool) or not isinstance(r, int | float | np.floating | np.integer) \
                or not np.isfinite(r):
            raise ValueError(f"reference of {a} must be a finite number (mm), got {r!r}")
        out[a] = float(r)
    return out


class ChainMachine:
    """A machine built from a topology and an error placement (see the module docstring).

    Every machine of the library is one (the papers' machines are subclasses that only fix
    the description).  Its ``pose_error(errors, pose)`` maps ``(n, n_errors)`` errors and a pose
    to the ``(n, 6)`` pose error; ``error_names``, ``catalogue``, ``axes`` and ``tool_offsets``
    name the columns and the pose.

    Parameters
    ----------
    topology : str
        The chain from the workpiece to the tool (:func:`.topology.parse_topology`).
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
    references : mapping of str to float, optional
        Linear axis (``X Y Z``) -> its Abbe reference ``r``, mm: the position on its travel
        to which its error motions are referred (default 0, every axis).  See Notes.

    Notes
    -----
    The error motions are ISO 230-1's (six per axis, in the frame after the motion), the
    location errors ISO 230-7's (the axis average line; before the motion, or after it in
    Zheng et al.'s reading of their Eq. 9).

    **Abbe references.**  Every error block is referred to one point of the machine, the
    reference point ``c = sum_J r_J e_J`` over the tool-side linear axes J (where the tool
    carriage stands when they are at their references ``r_J``).  A block acts about the point
    of its body that stands at ``c`` in the reference state (linear axes at their references,
    rotary axes at 0): in its frame ``a = c - sum_J s_J r_J e_J`` over the linear axes J from
    the bed to the block (same side, its own axis included), and it enters as ``T(a) D
    T(-a)``: its translations are those of that point, its rotations turn about it.  So a head
    axis (s = +1) turns the tool about its own carriage (the arm: the tool's offsets and the
    axes beyond it), a table axis (s = -1) about its point under the tool carriage (the Abbe
    arm of a pitch at q is ``q - r`` along the axis), and a rotary axis' error motions and
    location errors about its point at the reference point.  A tilted direction ``d'``
    (squareness errors) is followed from the reference, the move is ``s (r e_K + (q - r)
    d')``.  With every ``r = 0`` (the default) the chain is exactly the one without
    references.  Shifting an axis' zero and its reference by the same amount, and the pivots
    given in the coordinates that shift with it, leaves every pose error unchanged
    (``tests/test_machine_abbe.py``).  Pre and post location blocks of a linear axis (the
    papers' machines) are not referred.

    Examples
    --------
    A quill (one Z axis carrying the tool) with two errors: a positioning error EZZ of 1 um,
    and an angular error EAZ of 10 urad seen through a 100 mm tool (Abbe offset: 1 um in y).

    >>> import numpy as np
    >>> from mtaccuracy.errors import ErrorSpec
    >>> ezz = ErrorSpec("EZZ", "EZZ", "positioning", "Z", "z", True, True, "um")
    >>> eaz = ErrorSpec("EAZ", "EAZ", "angular", "Z", "x", False, True, "urad")
    >>> m = ChainMachine("w b Z t", [ezz, eaz], {"EZZ": Placement("Z", "motion", 2),
    ...                                          "EAZ": Placement("Z", "motion", 3)}, name="quill")
    >>> m.describe()
    'quill: workpiece <- bed -> Z -> tool (2 errors)'
    >>> pe = m.pose_error(np.array([[0.001, 0.0], [0.0, 1e-5]]), {"z": 50.0, "L": 100.0})
    >>> pe.round(9).tolist()                       # Px, Py, Pz (mm), Rx, Ry, Rz (rad)
    [[0.0, 0.0, 0.001, 0.0, 0.0, 0.0], [0.0, -0.001, -5e-09, 1e-05, 0.0, 0.0]]
    """

    def __init__(self, topology: str, catalogue: Sequence, placements: Mapping[str, Placement],
                 *, name: str = "chain", form: str = "euler", tilt: str = "exact",
                 tool_offsets: Sequence[str] = ("L",), orientation: str = "rotation_vector",
                 pivots: Mapping[str, Sequence[float]] | None = None,
                 travels: Mapping[str, tuple[float, float]] | None = None, chunk: int = 4096,
                 axis_names: Sequence[str] | None = None,
                 references: Mapping[str, float] | None = None):
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
        self.references = _check_references(self.topology, references)
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
        self._about = self._reference_points()
        self._factors = self._build_factors()
        self._plan = self._build_plan()

    # -- description -----------------------------------------------------------------------
    def describe(self) -> str:
        """One line: the machine's name, its chain (:meth:`.topology.Topology.describe`), errors.

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

    def _reference_points(self) -> dict:
        """(axis, slot) -> the point ``a`` (3,) about which that error block acts, in its
        frame (class Notes); only where it is not 0.

        Every error block is referred to one point of the machine, ``c = sum_J r_J e_J`` over
        the tool-side linear axes J: where the tool carriage stands when they are at their
        references.  A block acts about the point of its body that stands at ``c`` in the
        reference state (every linear axis at its reference, every rotary axis at 0, where its
        motion is the identity, so that all frames are parallel): ``a = c - sum_J s_J r_J e_J``
        over the linear axes J from the bed to the block (same side, the block's own axis
        included).  Linear axes: their error motions; rotary axes: their error motions and
        their location blocks (the papers' pre and post blocks of linear axes stay as they
        are)."""
        c = np.zeros(3)
        for axis in self.topology.tool:
            if axis in LINEAR:
                c[DIRECTION[axis]] += self.references.get(axis, 0.0)
        out = {}
        for side_axes in (self.topology.work, self.topology.tool):
            a = c.copy()
            for axis in side_axes:                  # from the bed outwards
                if axis in LINEAR:
                    a = a.copy()
                    a[DIRECTION[axis]] -= (self.topology.side(axis)
                                           * self.references.get(axis, 0.0))
                slots = ("motion",) if axis in LINEAR else ("pre", "motion", "post")
                if np.any(a != 0.0):
                    out.update({(axis, slot): a for slot in slots})
        return out

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
                r = self.references.get(axis, 0.0)
                if r != 0.0 and self._blocks[(axis, "tilt")].cols:   # s (r e + (q - r) d')
                    sr, i0 = -r if side < 0 else r, DIRECTION[axis]
                    t = [(d[i] * (sq - sr) + (sr if i == i0 else 0.0))
                         if t[i] is not None else None for i in range(3)]
                ops = [("t", t)]
                return [("t", [None if ti is None else -ti for ti in t])] if side < 0 else ops
            c, sn = cos_sin(q)
            piv = self.pivots.get(axis)
            ops = [("r", DIRECTION[axis], c, -sn if side < 0 else sn)]
            if piv is not None:
                ops = [("t", [-piv[i] for i in range(3)]), *ops, ("t", [piv[i] for i in range(3)])]
            return ops
        if (axis, slot) in self._about:                # T(a) D T(-a): about the reference
            a = self._about[(axis, slot)]
            inner = self._ops(e, p, side, axis, "@" + slot, k, trig)
            return [("t", [-a[i] for i in range(3)]), *inner, ("t", [a[i] for i in range(3)])
                    ] if inner else []
        b = self._blocks[(axis, slot.removeprefix("@"))]
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
        about = np.zeros((m, 3))                   # the point its rotations turn about
        ref = np.zeros(m)                          # tilts: the reference of their axis
        for j, pl in enumerate(self.placements):
            i, side = where[(pl.axis, pl.slot)]
            pos[j] = i
            if (pl.axis, pl.slot) in self._about:
                about[j] = self._about[(pl.axis, pl.slot)]
            if pl.slot == "tilt":
                ref[j] = self.references.get(pl.axis, 0.0)
            unit[j, pl.component % 3] = 1.0
            scale[j] = pl.sign * side
            if pl.slot == "tilt":
                kind[j] = 2
                ek[j, DIRECTION[pl.axis]] = 1.0
                tilt_axis[j] = pl.axis
                scale[j] = pl.sign * side * side    # the move is by s q, s = side for linear
            else:
                kind[j] = 0 if pl.component < 3 else 1
        return pos, kind, unit, ek, scale, tilt_axis, about, ref

    def jacobian(self, pose: Mapping, *, step: float | None = None) -> np.ndarray:
        """The Jacobian d(pose error)/d(errors) at zero errors: exact, in closed form.

        (P, 6, n) for pose arrays of length P.  An error block is a small twist ``(v, w)`` in its
        frame; with ``R_A`` the rotation of the factors before it (output order) and ``p_B``,
        ``a_B`` the tool tip and tool axis carried through the factors after it, it moves the
        tip by ``R_A (w x p_B + v)`` and turns the tool by ``R_A w`` (the tool axis by
        ``R_A (w x a_B)``), with the opposite sign on the workpiece side (the inverse of I + xi
        is I - xi to first order).  A tilt ``w`` of a linear axis moved by ``s q`` is the
        translation ``s (q - r) (w x e_k)``; the rotations of a referred block turn about its
        point ``a_K``, ``w x (p_B - a_K)`` (Abbe references, class Notes).  All forms agree to
        first order.

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
        pos, kind, unit, ek, scale, tilt_axis, about, ref = self._plan
        ra = np.stack(before)                                     # (F, n, 3, 3)
        aft = np.stack(after)                                     # (F, 2, 3, n)
        tip, ax = aft[pos, 0], aft[pos, 1]                        # (E, 3, n)
        u = unit[:, :, None]                                      # (E, 3, 1)
        dp = np.where(kind[:, None, None] == 0, u, 0.0)           # translations
        rotn = kind[:, None, None] == 1
        dp = np.where(rotn, np.cross(u, tip - about[:, :, None], axis=1), dp)
        q = np.stack([p[self._axis_pose[a_]] if a_ else np.zeros(n) for a_ in tilt_axis]) \
            - ref[:, None]                                        # (q - r) (w x e_k)
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
