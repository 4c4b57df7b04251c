"""The standard tests as models of a machine, each a :class:`Measurement`.

ISO 230-2 laser positioning, ISO 230-1 straightness and angular deviations, the ISO 230-4
circle, the five-axis ballbar with rotary motion (ISO 10791-6 type) and the R-test.  Every
test reads, at its poses ``q_k``, a point of the tool (the tool tip, or a point offset from it
in the tool frame: a reflector, a ball, a sensor nest) against the workpiece side:

    y_k = g_k' dp(q_k) + n_k' nu + e_k   (um; urad for the angular test),

``dp`` the point's position error (first order: the closed-form Jacobian of
:meth:`.motions.MotionModel.jacobian`), ``g_k`` the sensing direction, ``nu`` the set-up
nuisances each test names with its unit.  :meth:`Measurement.design` is that linear model (a
:class:`.design.Design`); :meth:`Measurement.readings` evaluates the exact chain
(:meth:`ChainMachine.relative <mtaccuracy.machines.chain.ChainMachine.relative>` with
per-pose errors) for simulated measurements.  Nominal poses that hold a point of the tool at a
place of the workpiece (a circle, a rotary test with the linear axes following) are found by
:func:`follow`: for fixed rotary axes the tool tip is an affine function of the linear axes.

Geometric errors only: servo mismatch, backlash and other dynamic effects of a circular test are
not in the chain (the cw and ccw traces of :func:`circle` read the same geometric deviations).
Frames: positions, ball and sphere centres are in the workpiece frame (mm); pivots are taken as
workpiece coordinates at rotary zeros (true when no linear axis lies between the workpiece and
the rotary axis; otherwise give the ball or sphere explicitly).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from .. import validate
from ..machines.chain import ChainMachine
from ..machines.topology import DIRECTION, LINEAR, ROTARY
from .design import Design
from .motions import MotionModel, motion_model

MODES = ("workpiece", "distance", "tool", "angle")
_E = np.eye(3)


@dataclass(frozen=True, eq=False)
class Measurement:
    """One test's readings as a model: poses, the point read, its sensing, its nuisances.

    Attributes
    ----------
    name : str
        The test ("circle XY r=100 mm").
    model : MotionModel
        The machine's errors (:func:`.motions.motion_model`).
    pose : dict of str to (P,) ndarray
        Axis positions (mm, rad) and tool offsets (mm) of each reading.
    offset : (P, 3) ndarray
        The point read, in the tool frame relative to the tool tip, mm.
    g : (P, 3) ndarray
        Sensing direction (unit): in the workpiece frame (``mode="workpiece"``), in the tool
        frame (``"tool"``: sensors on the spindle), of the rotation vector (``"angle"``);
        unused for ``"distance"`` (a bar's length change, along the bar).
    mode : str
        One of ``workpiece``, ``distance``, ``tool``, ``angle``.
    anchor : (P, 3) ndarray
        The workpiece-side point (mm, workpiece frame): the table ball (``distance``), the
        sphere (``tool``); unused otherwise.
    N : (P, n_nu) ndarray
        d(reading)/d(nuisance), units as ``nuisances`` name them.
    nuisances : tuple of str
        Nuisance names with units.
    labels : tuple of str
        One per reading.
    sigma : (P,) ndarray
        Noise standard deviation per reading, um (urad for ``angle``).
    """

    name: str
    model: MotionModel
    pose: dict
    offset: np.ndarray
    g: np.ndarray
    mode: str
    anchor: np.ndarray
    N: np.ndarray
    nuisances: tuple
    labels: tuple
    sigma: np.ndarray

    @property
    def n_obs(self) -> int:
        """int: the number of readings."""
        return len(self.labels)

    def design(self) -> Design:
        """The linear model of the readings (first order, closed-form Jacobian).

        Returns
        -------
        Design
            ``A`` in um per mm or rad (urad per mm or rad for ``angle``), columns the model's
            parameters (:attr:`MotionModel.names`).
        """
        jac = self.model.jacobian(self.pose)                       # (P, 6, m)
        _, _, ri, ti = self.model.frames(None, self.pose)
        dt, dr = jac[:, :3], jac[:, 3:]
        arm = np.einsum("nij,nj->ni", ri, self.offset)             # R_i o, workpiece frame
        p_i = ti + arm
        dp = dt + np.cross(dr, arm[:, :, None], axisa=1, axisb=1, axisc=1)
        if self.mode == "workpiece":
            a = np.einsum("ni,nim->nm", self.g, dp)
        elif self.mode == "distance":
            a = np.einsum("ni,nim->nm", _unit_rows(p_i - self.anchor), dp)
        elif self.mode == "tool":
            lever = p_i - self.anchor
            d = dp - np.cross(dr, lever[:, :, None], axisa=1, axisb=1, axisc=1)
            a = np.einsum("ni,nji,njm->nm", self.g, ri, d)
        else:
            a = np.einsum("ni,nim->nm", self.g, dr)
        return Design(self.name, 1000.0 * a if self.mode != "angle" else 1e6 * a, self.N,
                      self.sigma, self.model.names, self.nuisances, self.labels)

    def readings(self, eps, nu=None) -> np.ndarray:
        """The exact readings of the machine with parameters ``eps`` (no noise).

        Parameters
        ----------
        eps : (m,) array_like
            The model's parameters, mm or rad (:attr:`MotionModel.names`).
        nu : (n_nu,) array_like, optional
            The nuisances in their units (default zero).

        Returns
        -------
        (P,) ndarray
            Readings, um (urad for ``angle``): the exact chain evaluated with the error motions
            at each pose, plus ``N nu``.
        """
        ra, ta, ri, ti = self.model.frames(eps, self.pose)
        pa = ta + np.einsum("nij,nj->ni", ra, self.offset)
        p_i = ti + np.einsum("nij,nj->ni", ri, self.offset)
        if self.mode == "workpiece":
            y = 1000.0 * np.einsum("ni,ni->n", self.g, pa - p_i)
        elif self.mode == "distance":
            y = 1000.0 * (np.linalg.norm(pa - self.anchor, axis=1)
                          - np.linalg.norm(p_i - self.anchor, axis=1))
        elif self.mode == "tool":
            da = np.einsum("nji,nj->ni", ra, pa - self.anchor)
            di = np.einsum("nji,nj->ni", ri, p_i - self.anchor)
            y = 1000.0 * np.einsum("ni,ni->n", self.g, da - di)
        else:
            m = np.einsum("nij,nkj->nik", ra, ri)                  # R_a R_i^T
            rv = 0.5 * np.stack([m[:, 2, 1] - m[:, 1, 2], m[:, 0, 2] - m[:, 2, 0],
                                 m[:, 1, 0] - m[:, 0, 1]], axis=1)
            s = np.linalg.norm(rv, axis=1, keepdims=True)
            rv = rv * np.where(s > 0, np.arcsin(np.minimum(s, 1.0)) / np.where(s > 0, s, 1), 1)
            y = 1e6 * np.einsum("ni,ni->n", self.g, rv)
        if nu is not None:
            nu = np.asarray(nu, dtype=float)
            if nu.shape != (len(self.nuisances),):
                raise ValueError(f"{self.name}: nu must be {len(self.nuisances)} values "
                                 f"({', '.join(self.nuisances)}), got shape {nu.shape}")
            y = y + self.N @ nu
        return y


# ------------------------------------------------------------------------------------------
# Shared pieces
# ------------------------------------------------------------------------------------------

def _unit_rows(v):
    """Rows of ``v`` (n, 3) scaled to unit length."""
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def _as_model(machine) -> MotionModel:
    """A MotionModel as given, or the default one (degree 2) of a ChainMachine."""
    if isinstance(machine, MotionModel):
        return machine
    if isinstance(machine, ChainMachine):
        return motion_model(machine)
    raise TypeError(f"a test needs a ChainMachine or a MotionModel, got {type(machine).__name__}")


def _axis(model: MotionModel, axis: str, kinds) -> str:
    """The axis letter, checked: one of the machine's axes of the given kinds."""
    axis = str(axis).upper()
    if axis not in model.machine.topology.axes or axis not in kinds:
        have = [a for a in model.machine.topology.axes if a in kinds]
        raise ValueError(f"axis {axis!r} is not a {'linear' if kinds is LINEAR else 'rotary'} "
                         f"axis of {model.machine.name} (its axes of that kind: {have})")
    return axis


def _base(model: MotionModel, at, tool: float) -> dict:
    """The fixed part of a test's poses: linear axes at the middle of their travels, rotary
    axes at 0, the tool length ``tool`` (mm), each overridden by ``at``."""
    m = model.machine
    out = {}
    for a, name in m._axis_pose.items():
        lo, hi = m.travels.get(name, (0.0, 0.0))
        out[name] = 0.5 * (lo + hi) if a in LINEAR else 0.0
    if len(m.tool_offsets) == 1:
        out[m.tool_offsets[0]] = float(tool)
    elif len(m.tool_offsets) == 3:
        out.update(dict(zip(m.tool_offsets, (0.0, 0.0, float(tool)), strict=True)))
    at = dict(at or {})
    unknown = [k for k in at if k not in out]
    if unknown:
        raise ValueError(f"at: unknown pose name(s) {unknown} for {m.name}; allowed: "
                         f"{', '.join(out)}")
    out.update({k: float(v) for k, v in at.items()})
    return out


def _poses(base: dict, n: int, **moving) -> dict:
    """``base`` broadcast to ``n`` poses with the ``moving`` names set."""
    out = {k: np.full(n, v) for k, v in base.items()}
    out.update({k: np.asarray(v, dtype=float) for k, v in moving.items()})
    return out


def follow(machine, tip, *, pose: Mapping) -> dict:
    """The linear axes' positions that put the ideal tool tip at ``tip``.

    For fixed rotary axes the tool tip is an affine function of the linear axes (each is a
    translation between fixed rigid motions): three unit moves give its matrix, solved per
    pose (least squares with fewer than three linear axes; a reachable tip is required).

    Parameters
    ----------
    machine : ChainMachine or MotionModel
        The machine.
    tip : (P, 3) array_like
        The wanted tool-tip positions, workpiece frame, mm.
    pose : mapping of str to float or (P,) array
        The rotary axes (rad) and tool offsets (mm); linear values are ignored.

    Returns
    -------
    dict of str to (P,) ndarray
        ``pose`` with the linear axes set (mm).

    Raises
    ------
    ValueError
        If a tip cannot be reached by the linear axes (off their span by more than 1e-6 mm).
    """
    m = machine if isinstance(machine, ChainMachine) else _as_model(machine).machine
    tip = np.atleast_2d(np.asarray(tip, dtype=float))
    n = tip.shape[0]
    lin = [m._axis_pose[a] for a in m.topology.axes if a in LINEAR]
    base = {k: np.broadcast_to(np.asarray(v, dtype=float), (n,)) for k, v in pose.items()}
    base.update({a: np.zeros(n) for a in lin})
    stacked = {k: np.tile(v, len(lin) + 1) for k, v in base.items()}
    for j, a in enumerate(lin):
        stacked[a][(j + 1) * n:(j + 2) * n] = 100.0
    _, t = m.relative(np.zeros((n * (len(lin) + 1), m.n_errors)), stacked, with_errors=False)
    t = t.reshape(len(lin) + 1, n, 3)
    mat = np.moveaxis((t[1:] - t[0]) / 100.0, 0, 2)               # (n, 3, n_lin)
    q = np.einsum("nij,nj->ni", np.linalg.pinv(mat), tip - t[0])
    miss = np.abs(np.einsum("nij,nj->ni", mat, q) + t[0] - tip).max()
    if miss > 1e-6:
        raise ValueError(f"{m.name}: the linear axes {lin} cannot put the tool tip on the "
                         f"test's path (off by {miss:.3g} mm); choose a path in their span")
    out = dict(base)
    out.update({a: q[:, j] for j, a in enumerate(lin)})
    return out


def _sigma(sigma, name):
    sigma = float(sigma)
    if not (np.isfinite(sigma) and sigma > 0):
        raise ValueError(f"{name}: sigma must be a finite number > 0 (um), got {sigma!r}")
    return sigma


def _make(model, name, pose, offset, g, mode, anchor, N, nuisances, labels, sigma):
    n = len(labels)
    return Measurement(name, model, pose, np.broadcast_to(np.asarray(offset, float), (n, 3)),
                       np.broadcast_to(np.asarray(g, float), (n, 3)), mode,
                       np.broadcast_to(np.asarray(anchor, float), (n, 3)),
                       np.asarray(N, float).reshape(n, -1), tuple(nuisances), tuple(labels),
                       np.full(n, _sigma(sigma, name)))


def _targets(model, axis, targets, n_targets):
    m = model.machine
    name = m._axis_pose[axis]
    if targets is None:
        if name not in m.travels:
            raise ValueError(f"{m.name}: no travel of {name}; give targets= (mm) or the travels")
        lo, hi = m.travels[name]
        n_targets = validate.integer(n_targets, "n_targets", low=2)
        return np.linspace(lo, hi, n_targets)
    t = np.asarray(targets, dtype=float).ravel()
    if t.size < 2 or not np.isfinite(t).all():
        raise ValueError(f"targets of {name} must be at least 2 finite positions (mm)")
    return t


def _along(model, axis, targets, n_targets, at, tool):
    """A linear axis' test poses: its targets (mm), the fixed pose of the others, and the
    poses with the axis at each target (laser, straightness, angular)."""
    q = _targets(model, axis, targets, n_targets)
    base = _base(model, at, tool)
    return q, base, _poses(base, q.size, **{model.machine._axis_pose[axis]: q})


def _direction(model, base, axis):
    """The nominal direction of a linear axis' move in the workpiece frame at ``base``."""
    m = model.machine
    name = m._axis_pose[axis]
    p = _poses(base, 2, **{name: np.array([base[name], base[name] + 100.0])})
    _, t = m.relative(np.zeros((2, m.n_errors)), p, with_errors=False)
    return (t[1] - t[0]) / np.linalg.norm(t[1] - t[0])


# ------------------------------------------------------------------------------------------
# Linear axes: ISO 230-2 positioning, ISO 230-1 straightness and angular deviations
# ------------------------------------------------------------------------------------------

def laser_positioning(machine, *, axis: str, targets=None, n_targets: int = 11,
                      offset: Sequence[float] = (0.0, 0.0, 0.0), at=None, tool: float = 100.0,
                      sigma: float = 0.5) -> Measurement:
    """ISO 230-2 laser positioning along a linear axis.

    Reading: the displacement of a reflector, at ``offset`` from the tool tip (tool frame, mm),
    along the axis' nominal direction (workpiece frame), um.  Nuisance: ``laser zero (um)``
    (the interferometer is zeroed at an arbitrary point).  Sees the positioning error motion
    (all its terms but the constant, which is the laser's zero) and, through the beam's
    offsets, the pitch and yaw (Abbe); blind to roll (a rotation about the beam's direction
    moves no point along it).

    Parameters
    ----------
    machine : ChainMachine or MotionModel
        The machine (a ChainMachine gets :func:`.motions.motion_model`'s default).
    axis : str
        The linear axis (``X``, ``Y``, ``Z``).
    targets : (n,) array_like, optional
        Target positions, mm (default ``n_targets`` evenly over the travel).
    n_targets : int
        Targets when ``targets`` is not given.
    offset : (3,) sequence of float
        The reflector's offset from the tool tip in the tool frame, mm.
    at : mapping, optional
        The other axes' positions (mm, rad) and tool offsets (default: middle of the travels,
        rotary axes 0, the tool ``tool``).
    tool : float
        Tool length, mm.
    sigma : float
        Noise standard deviation per reading, um.

    Returns
    -------
    Measurement
    """
    model = _as_model(machine)
    axis = _axis(model, axis, LINEAR)
    q, base, poses = _along(model, axis, targets, n_targets, at, tool)
    g = _direction(model, base, axis)
    labels = [f"laser {axis} {v:g} mm" for v in q]
    return _make(model, f"laser {axis}", poses, offset, g, "workpiece", 0.0, np.ones(q.size),
                 ("laser zero (um)",), labels, sigma)


def straightness(machine, *, axis: str, direction: str, targets=None, n_targets: int = 11,
                 offset: Sequence[float] = (0.0, 0.0, 0.0), at=None, tool: float = 100.0,
                 sigma: float = 0.5) -> Measurement:
    """ISO 230-1 straightness of a linear axis' motion, across it along ``direction``.

    Reading: the deviation of the point at ``offset`` (tool frame, mm) along the nominal
    direction of the linear axis ``direction`` made perpendicular to the moved one (workpiece
    frame), um.  Nuisances: the reference straight line, ``reference offset (um)`` and
    ``reference slope (urad)`` (the slope about the middle of the targets): the squareness
    between this axis and another is invisible without a square.

    Parameters
    ----------
    machine : ChainMachine or MotionModel
        The machine.
    axis : str
        The moved linear axis.
    direction : str
        The linear axis along which the deviation is read (another of ``X``, ``Y``, ``Z``).
    targets, n_targets, offset, at, tool, sigma
        As :func:`laser_positioning`.

    Returns
    -------
    Measurement
    """
    model = _as_model(machine)
    axis = _axis(model, axis, LINEAR)
    direction = str(direction).upper()
    if direction not in LINEAR or direction == axis:
        raise ValueError(f"straightness of {axis}: direction must be another linear axis "
                         f"letter (X, Y, Z), got {direction!r}")
    q, base, poses = _along(model, axis, targets, n_targets, at, tool)
    e_a = _direction(model, base, axis)
    g = _E[DIRECTION[direction]] if direction not in model.machine.topology.axes \
        else _direction(model, base, direction)
    g = g - (g @ e_a) * e_a
    g = g / np.linalg.norm(g)
    mid = 0.5 * (q.min() + q.max())
    N = np.stack([np.ones(q.size), 1e-3 * (q - mid)], axis=1)
    labels = [f"straightness E{direction}{axis} {v:g} mm" for v in q]
    return _make(model, f"straightness {axis} in {direction.lower()}", poses, offset, g,
                 "workpiece", 0.0, N,
                 ("reference offset (um)", "reference slope (urad)"), labels, sigma)


def angular(machine, *, axis: str, about: str, targets=None, n_targets: int = 11, at=None,
            tool: float = 100.0, sigma: float = 1.0) -> Measurement:
    """ISO 230-1 angular deviation of a linear axis' motion (laser angular optics, a level).

    Reading: the tool's rotation about the workpiece frame's ``about`` axis, urad.  Nuisance:
    ``angular zero (urad)``.  The readings of this test are in urad (every other test's in um).

    Parameters
    ----------
    machine : ChainMachine or MotionModel
        The machine.
    axis : str
        The moved linear axis.
    about : str
        ``x``, ``y`` or ``z``: roll, pitch or yaw depending on the axis.
    targets, n_targets, at, tool
        As :func:`laser_positioning`.
    sigma : float
        Noise standard deviation per reading, urad.

    Returns
    -------
    Measurement
    """
    model = _as_model(machine)
    axis = _axis(model, axis, LINEAR)
    about = str(about).lower()
    if about not in ("x", "y", "z"):
        raise ValueError(f"angular test of {axis}: about must be x, y or z, got {about!r}")
    q, _, poses = _along(model, axis, targets, n_targets, at, tool)
    labels = [f"angular {axis} about {about} {v:g} mm" for v in q]
    return _make(model, f"angular {axis} about {about}", poses, 0.0, _E["xyz".index(about)],
                 "angle", 0.0, np.ones(q.size),
                 ("angular zero (urad)",), labels, sigma)


# ------------------------------------------------------------------------------------------
# ISO 230-4 circle, rotary ballbar, R-test
# ------------------------------------------------------------------------------------------

def circle(machine, *, plane: str = "XY", radius: float = 100.0, centre=None,
           n_points: int = 72, directions: Sequence[str] = ("ccw", "cw"), angles_deg=None,
           at=None, tool: float = 100.0, sigma: float = 0.2) -> Measurement:
    """ISO 230-4 circular test (a ballbar) in the plane of two linear axes, both directions.

    The tool ball follows a circle of ``radius`` about the table ball at ``centre``; angle
    ``theta`` from the plane's first axis towards its second (``XY``: from +x towards +y;
    ``ccw`` is increasing theta).  Reading: the bar's length change, um (exact: the distance of
    the actual tool ball from the table ball, minus the radius).  Nuisances: ``centre <a>
    (um)``, ``centre <b>`` (the table ball's position in the plane; ISO 230-4 evaluates about
    the least-squares centre) and ``bar length (um)``.  Sees the difference of the two scales
    and the squareness (second harmonics); blind to the mean scale (bar length) and to the
    axes' zeros (centre).  Signs: a squareness ``alpha`` that turns the second axis towards
    ``-`` the first (``EC0Y > 0`` on a tool-side Y) gives ``-R alpha sin(2 theta) / 2``.

    Parameters
    ----------
    machine : ChainMachine or MotionModel
        The machine.
    plane : str
        Two linear axes, ``XY``, ``YZ``, ``ZX`` (or reversed).
    radius : float
        Bar length, mm.
    centre : (3,) array_like, optional
        The table ball, workpiece frame, mm (default: the tool tip at the middle of the
        travels).
    n_points : int
        Readings per direction, evenly from 0 (when ``angles_deg`` is not given).
    directions : sequence of {"ccw", "cw"}
        The traces, in order.
    angles_deg : (n,) array_like, optional
        The readings' angles theta of every trace, deg (a file's; default ``n_points`` evenly).
    at, tool, sigma
        As :func:`laser_positioning`; ``at`` sets the rotary axes.

    Returns
    -------
    Measurement

    Examples
    --------
    A squareness of 20 urad between X and Y seen by a 100 mm bar: -R alpha sin(2 theta) / 2,
    1 um at 45 degrees.

    >>> import numpy as np
    >>> from mtaccuracy.machines.iso import iso_machine
    >>> from mtaccuracy.measure.motions import motion_model
    >>> m = iso_machine("w b X Y Z t", travels={"x": (-300.0, 300.0), "y": (-200.0, 200.0),
    ...                                         "z": (-250.0, 250.0)})
    >>> model = motion_model(m)
    >>> t = circle(model, plane="XY", radius=100.0, n_points=8, directions=("ccw",))
    >>> eps = np.zeros(model.n_params)
    >>> eps[model.names.index("EC0Y")] = 20e-6                      # rad
    >>> t.readings(eps).round(4).tolist()                            # um
    [0.0, -1.0, 0.0, 1.0, 0.0, -1.0, 0.0, 1.0]
    >>> t.design().nuisances
    ('centre x (um)', 'centre y (um)', 'bar length (um)')
    """
    model = _as_model(machine)
    plane = str(plane).upper()
    if len(plane) != 2 or plane[0] == plane[1] or not set(plane) <= set(LINEAR):
        raise ValueError(f"circle: plane must be two linear axes (XY, YZ, ZX), got {plane!r}")
    radius = float(radius)
    if not (np.isfinite(radius) and radius > 0):
        raise ValueError(f"circle: radius must be a finite number > 0 (mm), got {radius!r}")
    if angles_deg is None:
        n_points = validate.integer(n_points, "n_points", low=4)
        th = 2 * np.pi * np.arange(n_points) / n_points
    else:
        th = np.deg2rad(np.asarray(angles_deg, dtype=float).ravel())
        if th.size < 4 or not np.isfinite(th).all():
            raise ValueError("circle: angles_deg must be at least 4 finite angles (deg)")
    dirs = tuple(directions)
    if not dirs or any(d not in ("ccw", "cw") for d in dirs):
        raise ValueError(f"circle: directions must be 'ccw' and/or 'cw', got {dirs}")
    base = _base(model, at, tool)
    m = model.machine
    if centre is None:
        _, c = m.relative(np.zeros((1, m.n_errors)), base, with_errors=False)
        c = c[0]
    else:
        c = np.asarray(centre, dtype=float).reshape(3)
    u, v = _E[DIRECTION[plane[0]]], _E[DIRECTION[plane[1]]]
    theta = np.concatenate([th if d == "ccw" or angles_deg is not None else -th % (2 * np.pi)
                            for d in dirs])
    tip = c + radius * (np.cos(theta)[:, None] * u + np.sin(theta)[:, None] * v)
    pose = follow(m, tip, pose={k: val for k, val in base.items()})
    g = tip - c
    N = np.stack([-(g @ u) / radius, -(g @ v) / radius, np.ones(theta.size)], axis=1)
    labels = [f"circle {plane} {d} {np.rad2deg(t):.6g} deg"
              for d, block in zip(dirs, np.split(theta, len(dirs)), strict=True) for t in block]
    return _make(model, f"circle {plane} r={radius:g} mm", pose, 0.0, 0.0, "distance", c, N,
                 (f"centre {plane[0].lower()} (um)", f"centre {plane[1].lower()} (um)",
                  "bar length (um)"), labels, sigma)


def _rotary_frame(model: MotionModel, axis: str):
    """The rotary axis' direction, a radial and a tangential unit (workpiece frame at rotary
    zeros) and its pivot (mm)."""
    k = DIRECTION[axis]
    a = _E[k]
    radial = _E[next(i for i in range(3) if i != k)]
    return a, radial, np.cross(a, radial), model.machine.pivots.get(axis, np.zeros(3))


def _sweep(model, axis, angles, n_angles):
    m = model.machine
    if angles is None:
        lo, hi = m.travels.get(axis, (0.0, 2 * np.pi))
        n_angles = validate.integer(n_angles, "n_angles", low=3)
        full = np.isclose(hi - lo, 2 * np.pi)
        return np.linspace(lo, hi, n_angles, endpoint=not full)
    t = np.asarray(angles, dtype=float).ravel()
    if t.size < 3 or not np.isfinite(t).all():
        raise ValueError(f"angles of {axis} must be at least 3 finite values (rad)")
    return t


def rotary_ballbar(machine, *, axis: str, mode: str = "radial", radius: float = 150.0,
                   height: float = 100.0, bar_length: float = 100.0, ball=None, bar=None,
                   angles=None, n_angles: int = 36, at=None, tool: float = 100.0,
                   sigma: float = 0.3) -> Measurement:
    """A ballbar test with rotary motion (ISO 10791-6 type).

    The rotary axis turns, the linear axes follow, the two balls stand still relative to each
    other.
    The table ball at ``ball`` (workpiece frame, mm; default for a workpiece-side axis: at
    ``radius`` from the axis line and ``height`` along it, from its pivot) and the tool ball
    (the tool tip) at ``ball + bar`` (default ``bar_length`` along the ``mode`` direction:
    ``radial``, ``tangential`` or ``axial``, relative to the axis).  For a tool-side (head)
    axis the default tool ball is the tool tip at the middle of the travels and
    ``ball = tip - bar``.  Reading: the bar's length change, um.  Nuisance: ``bar length
    (um)`` (the ball positions are set by the machine at the start: their errors there are the
    datum).  One trace gives a first harmonic and a constant: the axis' offset from the linear
    axes' zeros and its tilt times the height appear only in combination.  For a table C
    (notebook 06's ``"w C b X Y Z B t"``, where the zeros of x and y stand for C's line,
    ``EX0C``, ``EY0C``) a radial or tangential trace at height h sees ``EXX[0] - h EB0C`` and
    ``EYY[0] + h EA0C``, not the four apart; C's own error motions (constant in the table's
    frame) and its zero move the workpiece and are blind (``tests/test_measure_models.py``).
    Several set-ups (heights, an R-test off the axis) are needed.

    Parameters
    ----------
    machine : ChainMachine or MotionModel
        The machine.
    axis : str
        The rotary axis (``A``, ``B``, ``C``).
    mode : {"radial", "tangential", "axial"}
        The bar's direction relative to the axis.
    radius, height, bar_length : float
        mm.
    ball, bar : (3,) array_like, optional
        Explicit table ball and bar vector (workpiece frame, mm).
    angles : (n,) array_like, optional
        The rotary positions, rad (default ``n_angles`` over its travel, or a full turn).
    n_angles : int
        Positions when ``angles`` is not given.
    at, tool, sigma
        As :func:`laser_positioning` (``at`` sets the other rotary axes).

    Returns
    -------
    Measurement
    """
    model = _as_model(machine)
    axis = _axis(model, axis, ROTARY)
    if mode not in ("radial", "tangential", "axial"):
        raise ValueError(f"rotary ballbar: mode must be radial, tangential or axial, "
                         f"got {mode!r}")
    a, rad, tan, piv = _rotary_frame(model, axis)
    direction = {"radial": rad, "tangential": tan, "axial": a}[mode]
    bar = float(bar_length) * direction if bar is None else np.asarray(bar, float).reshape(3)
    base = _base(model, at, tool)
    m = model.machine
    if ball is None:
        if m.topology.side(axis) < 0:
            ball = piv + float(radius) * rad + float(height) * a
        else:
            _, t = m.relative(np.zeros((1, m.n_errors)), base, with_errors=False)
            ball = t[0] - bar
    ball = np.asarray(ball, dtype=float).reshape(3)
    th = _sweep(model, axis, angles, n_angles)
    base = {k: v for k, v in base.items() if k != axis}
    pose = follow(m, np.broadcast_to(ball + bar, (th.size, 3)), pose={**base, axis: th})
    labels = [f"rotary ballbar {axis} {mode} {np.rad2deg(t):.6g} deg" for t in th]
    where = ", ".join(f"{v:g}" for v in np.round(ball, 6))
    return _make(model, f"rotary ballbar {axis} {mode} ball ({where}) mm", pose, 0.0,
                 0.0, "distance", ball, np.ones(th.size), ("bar length (um)",), labels, sigma)


def r_test(machine, *, axis: str, radius: float = 0.0, height: float = 100.0, sphere=None,
           angles=None, n_angles: int = 36, at=None, tool: float = 100.0,
           sigma: float = 0.3) -> Measurement:
    """The R-test: a sphere on the table, three displacement sensors on the spindle.

    The sphere at ``sphere`` (workpiece frame, mm; default for a workpiece-side axis: at
    ``radius`` from the axis line, 0 on the axis, and ``height`` along it, from its pivot; for
    a head axis the tool tip at the middle of the travels, ``radius`` and ``height`` unused:
    the tool length places the sphere relative to the head's pivot); the rotary axis turns and the
    linear axes keep the sensor nest (the tool tip) on the sphere.  Readings: three per
    position, the nest's displacement relative to the sphere along the tool frame's x, y, z
    (the sensing directions), um.  Nuisances: ``sphere x/y/z (um)``, the sphere's offset from
    its nominal place in the workpiece frame (a first harmonic in the readings of a table
    axis); the sensors' zeros are the nest's place on the spindle, a tool offset (calibrated,
    the chain's datum).  A table axis' constant error motions move the workpiece with the
    sphere and are absorbed by it.  On the axis the offset of the axis line from the linear
    axes' zeros and its tilt times the height are confounded (the same readings): for a table
    C at height h, ``EXX[0] - h EB0C`` and ``EYY[0] + h EA0C``; a second height, or the
    sphere off the axis, separates them.

    Parameters
    ----------
    machine : ChainMachine or MotionModel
        The machine.
    axis : str
        The rotary axis.
    radius, height : float
        The sphere's place relative to the axis, mm.
    sphere : (3,) array_like, optional
        The sphere's centre, workpiece frame, mm.
    angles, n_angles, at, tool, sigma
        As :func:`rotary_ballbar`.

    Returns
    -------
    Measurement
    """
    model = _as_model(machine)
    axis = _axis(model, axis, ROTARY)
    a, rad, _, piv = _rotary_frame(model, axis)
    base = _base(model, at, tool)
    m = model.machine
    if sphere is None:
        if m.topology.side(axis) < 0:
            sphere = piv + float(radius) * rad + float(height) * a
        else:
            _, t = m.relative(np.zeros((1, m.n_errors)), base, with_errors=False)
            sphere = t[0]
    sphere = np.asarray(sphere, dtype=float).reshape(3)
    th = _sweep(model, axis, angles, n_angles)
    base = {k: v for k, v in base.items() if k != axis}
    pose = follow(m, np.broadcast_to(sphere, (th.size, 3)), pose={**base, axis: th})
    pose = {k: np.repeat(v, 3) for k, v in pose.items()}           # x, y, z per position
    g = np.tile(_E, (th.size, 1))
    _, _, ri, _ = model.frames(None, pose)
    N = -ri.transpose(0, 2, 1)[np.arange(3 * th.size), np.tile(np.arange(3), th.size)]
    labels = [f"R-test {axis} {np.rad2deg(t):.6g} deg {c}" for t in th for c in "xyz"]
    where = ", ".join(f"{v:g}" for v in np.round(sphere, 6))
    return _make(model, f"R-test {axis} sphere ({where}) mm", pose,
                 0.0, g, "tool", sphere, N,
                 ("sphere x (um)", "sphere y (um)", "sphere z (um)"), labels, sigma)


# ------------------------------------------------------------------------------------------
# A standard plan
# ------------------------------------------------------------------------------------------

def standard_plan(machine, *, tool: float = 100.0, beam_offset: float = 50.0,
                  sigma: float = 0.5) -> list[Measurement]:
    """What a metrology engineer would run on the machine, given its axes.

    Per linear axis: ISO 230-2 laser positioning (the beam ``beam_offset`` mm off the tool
    point across the axis in both other directions), ISO 230-1 straightness in the two other
    directions and the three angular deviations; per plane of two linear axes an ISO 230-4
    circle (radius 40 % of the smaller half travel, both directions); per rotary axis a
    rotary ballbar radial, tangential and axial and R-tests: for a table axis on the axis at two
    heights (100 and 250 mm) and off it (radius 150 mm), for a head axis at two tool lengths
    (``tool`` and ``tool + 150`` mm).

    Parameters
    ----------
    machine : ChainMachine or MotionModel
        The machine (its travels give the targets and radii).
    tool : float
        Tool length, mm.
    beam_offset : float
        The laser reflector's offset across the axis, mm.
    sigma : float
        Noise of a length reading, um (angular readings: 1 urad).

    Returns
    -------
    list of Measurement
        Combine their designs with :func:`.design.combine`.
    """
    model = _as_model(machine)
    m = model.machine
    lin = [a for a in m.topology.axes if a in LINEAR]
    plan = []
    for a in lin:
        off = beam_offset * (1.0 - _E[DIRECTION[a]])
        plan.append(laser_positioning(model, axis=a, offset=off, tool=tool, sigma=sigma))
        plan += [straightness(model, axis=a, direction=d, tool=tool, sigma=sigma)
                 for d in LINEAR if d != a]
        plan += [angular(model, axis=a, about=c, tool=tool) for c in "xyz"]
    for i, a in enumerate(lin):
        for b in lin[i + 1:]:
            half = min(np.diff(m.travels.get(m._axis_pose[x], (-250.0, 250.0)))[0] / 2
                       for x in (a, b))
            plan.append(circle(model, plane=a + b, radius=0.4 * half, tool=tool, sigma=sigma))
    for r in (a for a in m.topology.axes if a in ROTARY):
        plan += [rotary_ballbar(model, axis=r, mode=mo, tool=tool, sigma=sigma)
                 for mo in ("radial", "tangential", "axial")]
        if m.topology.side(r) < 0:
            plan += [r_test(model, axis=r, radius=rr, height=h, tool=tool, sigma=sigma)
                     for rr, h in ((0.0, 100.0), (0.0, 250.0), (150.0, 100.0))]
        else:                       # a head axis: the sphere at two tool lengths
            plan += [r_test(model, axis=r, tool=t, sigma=sigma) for t in (tool, tool + 150.0)]
    return plan
