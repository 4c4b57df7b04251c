"""A standard test's file as readings of a machine's model: what the identification takes.

:mod:`.iso230_2` and :mod:`.iso230_4` evaluate a file by the standards' definitions.  To identify
a machine's geometric errors from the same file, its readings are matched to the test's model
(:mod:`.instruments`) at the file's own targets or angles, after the effects that are not
geometric are averaged out:

* **positioning** (ISO 230-2): the mean bidirectional deviation ``xbar_i`` of each target.  The
  reversal ``B_i`` (lost motion, not a geometric error) cancels in it; a constant is the laser's
  zero (a nuisance of the model).  Its standard uncertainty is that of a mean of the cycles,
  ``sqrt(s_up**2 / n_up + s_down**2 / n_down) / 2``.
* **circle** (ISO 230-4): the mean of the ccw and cw deviations at each angle.  The servo
  mismatch and the backlash flip sign with the direction and cancel to first order (their
  signatures, :func:`.iso230_4.signatures`, are odd in the direction); the centre and the bar
  length stay nuisances.  Its standard uncertainty is the residual scatter of the ISO 230-4
  fit over ``sqrt(2)``.

What the average cannot remove stays in the readings and shows in the identification's
chi-square: a screw's cyclic error, a drift between cycles, a misfit of the model.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from .instruments import Measurement, circle, laser_positioning
from .iso230_2 import evaluate_iso230_2
from .iso230_4 import evaluate_iso230_4, read_iso230_4


def positioning_readings(model, data, *, offset: Sequence[float] = (0.0, 0.0, 0.0),
                         tool: float = 100.0) -> tuple[Measurement, np.ndarray]:
    """An ISO 230-2 test's readings as a laser measurement of ``model`` at its targets.

    Parameters
    ----------
    model : MotionModel or ChainMachine
        The machine (:func:`.motions.motion_model`).
    data : PositioningData, path or DataFrame
        The test (:func:`.iso230_2.read_iso230_2`); its axis must be a linear axis of the
        machine and its targets within the axis' travel.
    offset : (3,) sequence of float
        The reflector's offset from the tool tip in the tool frame, mm (the file does not
        say; default the tool tip).
    tool : float
        Tool length, mm.

    Returns
    -------
    (Measurement, (m,) ndarray)
        The test at the file's targets (one reading per target, ``sigma`` the standard
        uncertainty of its mean, um) and the readings ``xbar_i``, um.
    """
    res = evaluate_iso230_2(data)
    axis = res.axis.upper()
    meas = laser_positioning(model, axis=axis, targets=res.targets_mm, offset=offset,
                             tool=tool)
    lo, hi = meas.model.machine.travels.get(meas.model.machine._axis_pose[axis], (-np.inf,
                                                                                 np.inf))
    t = res.targets_mm
    if t.min() < lo - 1e-9 or t.max() > hi + 1e-9:
        raise ValueError(f"{res.source}: targets of {axis} from {t.min():g} to {t.max():g} mm, "
                         f"outside the machine's travel {lo:g} to {hi:g} mm: the file is not "
                         "of this machine, or the axis table's travel is wrong")
    sd = np.sqrt(res.s[:, 0] ** 2 / res.cycles[:, 0] + res.s[:, 1] ** 2 / res.cycles[:, 1]) / 2
    sd = np.maximum(sd, 1e-3)                   # a perfectly repeated reading: 1 nm floor
    return replace(meas, sigma=sd), res.mean[:, 2].copy()


def circle_readings(model, data, *, tool: float = 100.0) -> tuple[Measurement, np.ndarray]:
    """An ISO 230-4 test's readings, both directions averaged, as a ballbar circle of ``model``.

    Parameters
    ----------
    model : MotionModel or ChainMachine
        The machine.
    data : CircleData, path or DataFrame
        The test (:func:`.iso230_4.read_iso230_4`), read at the same angles in both directions.
    tool : float
        Tool length, mm.

    Returns
    -------
    (Measurement, (n,) ndarray)
        The circle at the file's angles (one trace, ``ccw``; ``sigma`` the fit's residual
        scatter over ``sqrt(2)``) and the mean of the two directions' deviations, um.
    """
    d = data if hasattr(data, "ccw") else read_iso230_4(data)
    res = evaluate_iso230_4(d)
    a = np.mod(d.angle_deg, 360.0)
    ccw, cw = (np.argsort(a[np.flatnonzero(d.ccw == s)], kind="stable") for s in (True, False))
    a_ccw, a_cw = a[d.ccw][ccw], a[~d.ccw][cw]
    if a_ccw.shape != a_cw.shape or not np.allclose(a_ccw, a_cw, atol=1e-9):
        raise ValueError(f"{d.source}: the ccw and cw readings are not at the same angles: "
                         "the two directions are averaged angle by angle to cancel the servo "
                         "mismatch and the backlash; read both at the same angles")
    y = 0.5 * (d.deviation_um[d.ccw][ccw] + d.deviation_um[~d.ccw][cw])
    meas = circle(model, plane=d.plane, radius=d.radius_mm, angles_deg=a_ccw,
                  directions=("ccw",), tool=tool)
    sd = max(res.residual_rms_um / np.sqrt(2.0), 1e-3)
    return replace(meas, sigma=np.full(y.size, sd)), y
