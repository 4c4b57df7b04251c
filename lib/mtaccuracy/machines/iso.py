"""A machine of any topology with its ISO 230-1 / ISO 230-7 error catalogue.

:func:`iso_catalogue` generates the errors of a topology (:mod:`.topology`): per axis its six
error motions (ISO 230-1), the squareness errors of the linear axes and the location errors of
the rotary axes (ISO 230-7).  :func:`redundant_location_errors` finds, by a rank test, the
location errors that cannot be told apart from the axes' zeros, the set-up of the workpiece
and the tool offset, and :func:`iso_machine` builds the :class:`.chain.ChainMachine` without
them (notebook 06).
"""

from __future__ import annotations

import itertools

import numpy as np

from .. import errors as _errors
from .. import validate
from .chain import COMPONENTS, ChainMachine, Placement
from .topology import DIRECTION, LINEAR, ROTARY, parse_topology


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
        The chain (:func:`.topology.parse_topology`).

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
    at all.  Travels that large are not a machine (:func:`.readers.read_axis_table` refuses
    them), and the rank test of columns mixing such entries with ordinary ones is not
    meaningful; the scaling only keeps the arithmetic finite.
    """
    return [(s, why) for s, why, _ in _redundant(machine, n_poses=n_poses, seed=seed, rtol=rtol)]


def _redundant(machine: ChainMachine, *, n_poses: int, seed, rtol: float):
    """:func:`redundant_location_errors` with, per error, the datums that absorb it in plain
    words (:func:`_absorbed`): ``(symbol, reason, absorbed_by)`` triples."""
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
    nuisance, labels, plain = [], [], []
    for j, pl in enumerate(machine.placements):   # an axis' zero: its own-direction error
        own = DIRECTION[pl.axis] + (3 if pl.axis in ROTARY else 0)
        if pl.slot == "motion" and pl.component == own:
            nuisance.append(jac[:, :, j])
            labels.append(f"the zero of {machine._axis_pose[pl.axis]}")
            plain.append(f"the zero of {pl.axis} (its home or reference position)")
    unit = np.eye(3)
    for c in range(3):
        nuisance.append(as_error(-np.broadcast_to(unit[c], tt.shape), np.zeros_like(tt)))
        labels.append(f"the workpiece set-up along {'xyz'[c]}")
        plain.append(f"the work offset (G54) in {'xyz'[c]}")
    for c in range(3):
        u = np.broadcast_to(unit[c], tt.shape)
        nuisance.append(as_error(-np.cross(u, tt), -u))
        labels.append(f"the workpiece set-up about {'xyz'[c]}")
        plain.append(f"a rotation of the work offset about {'xyz'[c]} (the part's alignment)")
    for c in range(3):
        nuisance.append(as_error(rt[:, :, c], np.zeros_like(tt)))
        labels.append(f"the tool offset along {'xyz'[c]}")
        # the chain's tool axis is the tool frame's z (the tool-axis orientation output)
        plain.append("the tool length offset (gauge line to tip, along the tool axis)" if c == 2
                     else f"the tool tip's offset along the tool frame's {'xyz'[c]}, across the "
                          f"tool axis (a pivot calibration finds it with the length)")
    basis, names_b, datums = [], [], []
    for col, lab, words in zip(nuisance, labels, plain, strict=True):
        vec = _unit(col.reshape(-1))
        if vec is not None:
            basis.append(vec)
            names_b.append(lab)
            datums.append((vec, words))
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
            out.append((spec.symbol, "no effect on the pose error", "nothing (no effect)"))
            continue
        res, used = explain(vec)
        if res < rtol:
            out.append((spec.symbol, _same_effect(used), _absorbed(vec, datums, rtol)))
            continue
        basis.append(vec)
        names_b.append(spec.symbol)
    return out


def _absorbed(vec, datums, rtol: float) -> str:
    """Which datums a redundant error's column equals or combines with, in a machine user's
    words: the fewest datum columns (one, then two, then three) whose span holds ``vec``,
    every such set (``or`` between alternatives), or, when three do not suffice, that the
    datums together with location errors already kept absorb it.  Derived from the chain's
    columns (``datums``: (unit column, plain words) pairs), never from the error's name."""
    # a calibration datum (tool, work offset) named before an axis zero that does the same
    datums = sorted(datums, key=lambda d: d[1].startswith("the zero of"))
    cols = [d for d, _ in datums]
    for size in (1, 2, 3):
        found = []
        for idx in itertools.combinations(range(len(cols)), size):
            m = np.stack([cols[i] for i in idx], 1)
            coef, *_ = np.linalg.lstsq(m, vec, rcond=None)
            if np.linalg.norm(vec - m @ coef) < rtol and np.all(np.abs(coef) > 1e-6):
                found.append(" + ".join(datums[i][1] for i in idx))
        if found:
            how = "absorbed by " if size == 1 else "absorbed by a combination of "
            return how + " or by ".join(found)
    return "absorbed by the datums together with location errors already kept"


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
        The chain (:func:`.topology.parse_topology`).
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
        With ``machine.removed``: the (symbol, reason) of every removed location error, and
        ``machine.absorbed_by``: symbol -> the datum(s) that absorb it, in the words of a
        machine's user (the tool length offset, the work offset G54, an axis zero ...; the
        fewest datum columns of the chain whose combination equals its column).
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
    found = [] if keep_redundant else _redundant(full, n_poses=64, seed=0, rtol=1e-9)
    removed = [(s, why) for s, why, _ in found]
    drop = {s for s, _ in removed}
    if drop:
        cat = tuple(e for e in cat if e.symbol not in drop)
        full = ChainMachine(topology, cat, {s: placements[s] for s in (e.symbol for e in cat)},
                            name=name, **options)
    full.removed = removed
    full.absorbed_by = {s: words for s, _, words in found}
    return full
