"""Error motions that vary with position: Legendre polynomials over each linear axis' travel.

A :class:`~mtaccuracy.machines.chain.ChainMachine` holds constant errors.  A scale error or a
straightness is a function of the axis position ``q``: here every error motion of a linear axis
K (ISO 230-1: EXK, EYK, EZK, EAK, EBK, ECK) is

    E(q) = sum_k c_k P_k(u),   u = (2 q - low - high) / (high - low)  in [-1, 1],

``P_k`` the Legendre polynomial of degree k (0..d) over K's travel; the location and
squareness errors and the rotary axes' error motions stay constant (one parameter each, the
chain's own symbol).  A coefficient is named ``"EXX[1]"`` (error symbol, degree); its unit is
the error's (mm or rad): ``EXX[1]`` is the positioning error at the end of the travel relative
to its middle, the scale error (dimensionless) is ``EXX[1] / ((high - low) / 2)``.

First order, the Jacobian column of coefficient k at pose q is the chain's column of the error
times ``P_k(u(q))`` (:meth:`MotionModel.jacobian`); the exact pose error evaluates
:meth:`~mtaccuracy.machines.chain.ChainMachine.pose_error` with per-pose errors
(:meth:`MotionModel.chain_errors`).

Datum choices (why some terms are never identifiable)
-----------------------------------------------------
* A constant positioning error ``EXX[0]`` is the axis' zero (its home): every test reads
  positions relative to a set-up it makes itself (a laser's zero, a circle's centre), so on a
  machine without rotary axes it is a datum, listed in :attr:`MotionModel.datums`.  With
  rotary axes the linear zeros stand for the rotary axis lines' positions the catalogue
  removed as redundant (``machine.absorbed_by``: ``EX0C`` is the zero of x) and are seen by
  the rotary tests.  The zero of the rotary axis carrying the workpiece (``ECC`` of a table
  C next to the workpiece) is the workpiece's alignment: a datum.
* The degree-1 term of a straightness (``EYX[1]``, a constant slope of X's path in y) is a
  squareness: ISO 230-1 evaluates straightness about a reference straight line (its slope
  removed) and assigns the slope between two axes' reference lines to the squareness
  (``EC0Y``), and the slope against the workpiece is the workpiece's alignment.  The term is
  dropped (:attr:`MotionModel.dropped`).
* A constant straightness (``EYX[0]``) shifts the carriage across its travel: the zero of the
  axis along that direction when the machine has one; not dropped, but only seen in
  combination with that zero.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numpy.polynomial import legendre

from .. import validate
from ..machines.chain import ChainMachine
from ..machines.topology import DIRECTION, LINEAR, ROTARY
from ..sensitivity.linear import uniform_moments


class MotionModel:
    """The errors of a machine as parameters: Legendre coefficients and constants.

    Build with :func:`motion_model`.

    Attributes
    ----------
    machine : ChainMachine
        The machine (its catalogue, travels, pose names).
    degree : int
        The highest Legendre degree of a linear axis' error motion.
    names : tuple of str
        The parameters: ``"EXX[k]"`` for a coefficient, the chain's symbol for a constant.
    column : (m,) ndarray of int
        The chain error (catalogue column) each parameter belongs to.
    order : (m,) ndarray of int
        Its Legendre degree (0 for a constant).
    units : tuple of str
        ``"mm"`` or ``"rad"`` per parameter.
    datums : dict of str to str
        Parameters that are datum choices (never identifiable), with the reason.
    dropped : dict of str to str
        Terms left out of the parameters, with the reason.
    """

    def __init__(self, machine: ChainMachine, degree: int):
        self.machine = machine
        self.degree = degree
        names, column, order, units, pose_of = [], [], [], [], []
        rotary = any(a in ROTARY for a in machine.topology.axes)
        work = machine.topology.work
        innermost = work[-1] if work and work[-1] in ROTARY else None
        self.datums, self.dropped = {}, {}
        for j, (spec, pl) in enumerate(zip(machine.catalogue, machine.placements, strict=True)):
            unit = "mm" if pl.component < 3 else "rad"
            own = pl.slot == "motion" and pl.component == DIRECTION[pl.axis] + (
                3 if pl.axis in ROTARY else 0)
            if pl.slot == "motion" and pl.axis in LINEAR and degree > 0:
                straight = pl.component < 3 and not own
                for k in range(degree + 1):
                    name = f"{spec.symbol}[{k}]"
                    if straight and k == 1:
                        self.dropped[name] = (
                            "a straightness' slope is a squareness (ISO 230-1 assigns the slope "
                            "between reference lines to the squareness, against the workpiece to "
                            "its alignment)")
                        continue
                    names.append(name)
                    column.append(j)
                    order.append(k)
                    units.append(unit)
                    pose_of.append(machine._axis_pose[pl.axis])
                    if own and k == 0 and not rotary:
                        self.datums[name] = (f"the zero of {machine._axis_pose[pl.axis]} (a "
                                             f"constant positioning error is the axis' home)")
                continue
            names.append(spec.symbol)
            column.append(j)
            order.append(0)
            units.append(unit)
            pose_of.append(None)
            if own and (pl.axis in LINEAR and not rotary or pl.axis == innermost):
                self.datums[spec.symbol] = (
                    f"the zero of {machine._axis_pose[pl.axis]}"
                    + (" (the workpiece's alignment)" if pl.axis in ROTARY else ""))
        self.names = tuple(names)
        self.column = np.array(column, dtype=int)
        self.order = np.array(order, dtype=int)
        self.units = tuple(units)
        self._pose_of = pose_of
        self._span = {}
        for name in {p for p in pose_of if p is not None}:
            if name not in machine.travels:
                raise ValueError(
                    f"{machine.name}: no travel of {name}; a position-dependent error motion "
                    f"(degree {degree}) is a polynomial over the travel: give travels={{"
                    f"{name!r}: (low, high)}} (mm) to the machine, or degree=0")
            lo, hi = (float(v) for v in machine.travels[name])
            if not (np.isfinite(lo) and np.isfinite(hi) and hi > lo):
                raise ValueError(f"{machine.name}: the travel {(lo, hi)} of {name} must be "
                                 f"finite with low < high (mm)")
            self._span[name] = (lo, hi)
        # the same chain with the orientation as a rotation vector: the Jacobian of any point
        # of the tool (a beam's reflector, a sensor nest) needs the whole rotation
        m = machine
        self._rv = m if m.orientation == "rotation_vector" else ChainMachine(
            m.topology.text, m.catalogue, dict(zip(m.error_names, m.placements, strict=True)),
            name=m.name, form=m.form, tilt=m.tilt, tool_offsets=m.tool_offsets,
            orientation="rotation_vector", pivots=m.pivots, travels=m.travels,
            axis_names=m.axes, references=m.references)

    @property
    def n_params(self) -> int:
        """int: the number of parameters."""
        return len(self.names)

    def __repr__(self) -> str:
        return (f"<MotionModel of {self.machine.name!r}: degree {self.degree}, "
                f"{self.n_params} parameters>")

    def basis(self, pose: Mapping) -> np.ndarray:
        """The value of each parameter's polynomial at the poses.

        Parameters
        ----------
        pose : mapping of str to float or (P,) array
            Axis positions (mm, rad) and tool offsets (mm).

        Returns
        -------
        (P, m) ndarray
            ``P_k(u)`` of each coefficient at each pose, 1 for a constant (dimensionless).
        """
        vals = {k: np.atleast_1d(np.asarray(v, dtype=float)) for k, v in pose.items()}
        n = max((v.shape[0] for v in vals.values()), default=1)
        p = self.machine.check_pose(vals, n)
        out = np.ones((n, self.n_params))
        for name, (lo, hi) in self._span.items():
            cols = np.array([i for i, a in enumerate(self._pose_of) if a == name])
            u = (2.0 * p[name] - lo - hi) / (hi - lo)
            out[:, cols] = legendre.legvander(u, self.degree)[:, self.order[cols]]
        return out

    def check_params(self, params) -> np.ndarray:
        """``params`` as a float vector of the model's length.

        Parameters
        ----------
        params : (m,) array_like
            Parameter values, mm or rad (:attr:`units`), in the order of :attr:`names`.

        Returns
        -------
        (m,) ndarray

        Raises
        ------
        ValueError
            If ``params`` is not a finite vector of length m.
        """
        e = np.asarray(params, dtype=float)
        if e.shape != (self.n_params,) or not np.isfinite(e).all():
            raise ValueError(f"parameters of {self.machine.name} must be {self.n_params} finite "
                             f"values (mm, rad) in the order {', '.join(self.names[:4])}, ...; "
                             f"got shape {e.shape}")
        return e

    def prior_sd(self, bounds) -> np.ndarray:
        """Each parameter's prior standard deviation: its error's uniform range over sqrt(12).

        Every Legendre coefficient of an error motion takes its error's range (a range is
        given for an error, not for its shape along the travel: a scale term ``EXX[1]``, the
        deviation at the end of the travel from the middle, as large as the positioning
        error).

        Parameters
        ----------
        bounds : (2, n_errors) array_like
            The chain errors' uniform ranges, lows then highs, mm or rad, catalogue order (as
            :func:`mtaccuracy.machines.readers.read_ranges` or
            :func:`mtaccuracy.errors.uniform_bounds` returns them); checked by
            :func:`mtaccuracy.sensitivity.uniform_moments`.

        Returns
        -------
        (n_params,) ndarray
            mm or rad, one per :attr:`names`.
        """
        uniform_moments(bounds, self.machine.n_errors)          # the check, one place
        b = np.asarray(bounds, dtype=float)
        return (b[1] - b[0])[self.column] / np.sqrt(12.0)

    def chain_errors(self, params, pose: Mapping) -> np.ndarray:
        """The chain's errors at each pose: every error motion evaluated at its axis' position.

        Parameters
        ----------
        params : (m,) array_like
            Parameter values, mm or rad.
        pose : mapping of str to float or (P,) array
            Axis positions (mm, rad) and tool offsets (mm).

        Returns
        -------
        (P, n_errors) ndarray
            Rows for :meth:`ChainMachine.pose_error` (mm, rad), catalogue order.
        """
        e = self.check_params(params)
        terms = self.basis(pose) * e                               # (P, m)
        out = np.zeros((terms.shape[0], self.machine.n_errors))
        np.add.at(out.T, self.column, terms.T)
        return out

    def jacobian(self, pose: Mapping) -> np.ndarray:
        """d(pose error)/d(parameters) at zero errors, first order (closed form).

        Parameters
        ----------
        pose : mapping of str to float or (P,) array
            Axis positions (mm, rad) and tool offsets (mm).

        Returns
        -------
        (P, 6, m) ndarray
            Rows ``Px Py Pz`` (mm per mm or rad) then the rotation vector of the tool frame in
            the workpiece frame (rad per mm or rad), whatever the machine's ``orientation``.
        """
        jac = self._rv.jacobian(pose)                              # (P, 6, n_errors)
        return jac[:, :, self.column] * self.basis(pose)[:, None, :]

    def frames(self, params, pose: Mapping):
        """The actual and the ideal tool frame in the workpiece frame.

        Parameters
        ----------
        params : (m,) array_like or None
            Parameter values, mm or rad (None: the ideal frame twice).
        pose : mapping of str to float or (P,) array
            Axis positions (mm, rad) and tool offsets (mm).

        Returns
        -------
        (R_actual, t_actual, R_ideal, t_ideal) : (P, 3, 3), (P, 3), (P, 3, 3), (P, 3)
            Rotations and tool-tip positions (mm).
        """
        vals = {k: np.atleast_1d(np.asarray(v, dtype=float)) for k, v in pose.items()}
        n = max((v.shape[0] for v in vals.values()), default=1)
        zero = np.zeros((n, self.machine.n_errors))
        ri, ti = self.machine.relative(zero, vals, with_errors=False)
        if params is None:
            return ri, ti, ri, ti
        ra, ta = self.machine.relative(self.chain_errors(params, vals), vals)
        return ra, ta, ri, ti


def motion_model(machine: ChainMachine, *, degree: int = 2) -> MotionModel:
    """The errors of ``machine`` with its linear axes' error motions as Legendre polynomials.

    Parameters
    ----------
    machine : ChainMachine
        The machine; with ``degree > 0`` every linear axis needs its travel
        (``machine.travels``, mm).
    degree : int
        Highest Legendre degree of a linear axis' error motion (0: the chain's constants,
        named by their symbols).

    Returns
    -------
    MotionModel
        Its ``names``, ``datums`` (never identifiable: axis zeros) and ``dropped`` (a
        straightness' slope, which ISO 230-1 calls a squareness).

    Raises
    ------
    ValueError
        If ``degree`` is negative or a linear axis has no finite travel.

    Examples
    --------
    >>> from mtaccuracy.machines.iso import iso_machine
    >>> m = iso_machine("w b X t", travels={"x": (-100.0, 100.0)})
    >>> mm = motion_model(m, degree=2)
    >>> mm.names
    ('EXX[0]', 'EXX[1]', 'EXX[2]', 'EYX[0]', 'EYX[2]', 'EZX[0]', 'EZX[2]', 'EAX[0]', 'EAX[1]', \
'EAX[2]', 'EBX[0]', 'EBX[1]', 'EBX[2]', 'ECX[0]', 'ECX[1]', 'ECX[2]')
    >>> sorted(mm.datums), sorted(mm.dropped)
    (['EXX[0]'], ['EYX[1]', 'EZX[1]'])
    """
    if not isinstance(machine, ChainMachine):
        raise TypeError(f"a motion model needs a ChainMachine, got {type(machine).__name__}")
    degree = validate.integer(degree, "degree", low=0)
    return MotionModel(machine, degree)
