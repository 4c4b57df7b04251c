"""Machine topologies built from :mod:`mtaccuracy.kinematics`.

``build(name)`` returns a machine with ``.error_names`` (paper symbols, paper order),
``.catalogue`` (:class:`mtaccuracy.errors.ErrorSpec` per error), ``.axes``, ``.tool_offsets``
and ``.pose_error(errors, pose)``: an ``(n, n_errors)`` array (mm, rad) and a pose mapping
(axis and tool-offset names to mm or rad, scalars or ``(n,)`` arrays) to an ``(n, 6)`` array
``Px, Py, Pz`` (mm) and the orientation error (rad), named by ``machine.components``: a rotation
vector ``Rx, Ry, Rz`` (the three-axis machines) or the change of the tool-axis direction
``Vx, Vy, Vz`` (the five-axis machine).  Every machine is a :class:`.chain.ChainMachine`: a
topology (:mod:`.topology`) and an error placement (see :mod:`.chain`; :func:`.iso.iso_machine`
builds any other topology with its ISO 230-1 catalogue, :mod:`.readers` reads a reader's
machine from files).

One module per machine; the registry imports it on first use.
"""

from __future__ import annotations

import importlib
import importlib.util

from .chain import ChainMachine

#: machine name -> (module, class)
_REGISTRY = {
    "vertical_xyfz": ("vertical_xyfz", "VerticalXYFZ"),          # Guo et al. 2016
    "ac_double_turntable": ("ac_double_turntable", "ACDoubleTurntable"),  # Zheng et al. 2024
    "horizontal_3axis": ("horizontal_3axis", "Horizontal3Axis"),  # Rong et al.
}


def _available() -> dict[str, tuple[str, str]]:
    spec = importlib.util.find_spec
    return {k: v for k, v in _REGISTRY.items() if spec(f"{__name__}.{v[0]}") is not None}


def names() -> list[str]:
    """Names accepted by :func:`build`.

    Returns
    -------
    list of str
    """
    return sorted(_available())


def build(name: str, **options) -> ChainMachine:
    """Build the machine called ``name`` (see :func:`names`).

    Parameters
    ----------
    name : str
        One of :func:`names`.
    **options
        Passed to the machine's constructor (e.g. ``layout`` of the horizontal machine: a
        named layout or a topology).

    Returns
    -------
    ChainMachine
        Its ``pose_error(errors, pose)`` maps ``(n, n_errors)`` errors (mm, rad) and a pose
        to the ``(n, 6)`` pose error (mm, rad).

    Raises
    ------
    ValueError
        If ``name`` is not one of :func:`names`.

    Examples
    --------
    Rong et al.'s horizontal machine: a 1 um positioning error of X moves the tool tip 1 um
    along x.

    >>> import numpy as np
    >>> m = build("horizontal_3axis")
    >>> m.n_errors, m.error_names[:3], m.axes
    (21, ['dx(x)', 'dy(y)', 'dz(z)'], ('x', 'y', 'z'))
    >>> e = np.zeros((4, m.n_errors))
    >>> e[:, 0] = 0.001                                         # dx(x), mm
    >>> pe = m.pose_error(e, {"x": 100.0, "y": 50.0, "z": 20.0})
    >>> pe.shape
    (4, 6)
    >>> pe[0, :3].round(6).tolist()                             # Px, Py, Pz (mm)
    [0.001, 0.0, 0.0]
    """
    if name not in _available():
        raise ValueError(f"unknown machine {name!r}; allowed: {', '.join(names())}")
    module, cls = _REGISTRY[name]
    return getattr(importlib.import_module(f"{__name__}.{module}"), cls)(**options)


__all__ = ["ChainMachine", "build", "names"]
