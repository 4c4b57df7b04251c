"""Machine topologies built from :mod:`mtaccuracy.kinematics`.

``build(name)`` returns a machine with ``.error_names`` (paper symbols, paper order),
``.catalogue`` (:class:`mtaccuracy.errors.ErrorSpec` per error), ``.axes``, ``.tool_offsets``
and ``.pose_error(errors, pose)``: an ``(n, n_errors)`` array (mm, rad) and a pose mapping
(axis and tool-offset names to mm or rad, scalars or ``(n,)`` arrays) to an ``(n, 6)`` array
``Px, Py, Pz`` (mm) and ``Vx, Vy, Vz`` (rad).
"""

from __future__ import annotations

from ._base import POSE_COMPONENTS, Machine
from .vertical_xyfz import VerticalXYFZ

_REGISTRY = {VerticalXYFZ.name: VerticalXYFZ}


def names() -> list[str]:
    """Names accepted by :func:`build`."""
    return sorted(_REGISTRY)


def build(name: str, **options) -> Machine:
    """Build the machine called ``name`` (see :func:`names`)."""
    try:
        cls = _REGISTRY[name]
    except KeyError:
        raise ValueError(f"unknown machine {name!r}; allowed: {', '.join(names())}") from None
    return cls(**options)


__all__ = ["Machine", "POSE_COMPONENTS", "build", "names", "VerticalXYFZ"]
