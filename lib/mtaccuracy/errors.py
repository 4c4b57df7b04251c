"""Error catalogues: paper symbols, ISO 230-1 codes, kinds and units.

A catalogue is an ordered tuple of :class:`ErrorSpec`; its order is the paper's order and
the column order of every ``(n, n_errors)`` error array.  The library works in mm and rad;
``paper_unit`` and ``to_library`` say how the paper's numbers convert.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np

#: The working map of paper symbols to ISO 230-1 codes: package data (``mtaccuracy/data/``),
#: read through :mod:`importlib.resources`, so that it is found in a checkout, an installed
#: wheel or a zip alike.
#:
#: :meta hide-value:
ISO230_NAMES = resources.files("mtaccuracy") / "data" / "iso230_names.csv"

#: Paper units -> library units (mm, rad).
UNIT_SCALE = {"um": 1e-3, "mm": 1.0, "rad": 1.0, "urad": 1e-6, "um/m": 1e-6,
              "arcsec": np.pi / 180 / 3600}

_ROT = {"x": "A", "y": "B", "z": "C"}

#: The six ISO 230-1 error components: translations along x, y, z, rotations about x, y, z.
ISO_COMPONENTS = "XYZABC"


def iso_code(component: str, axis: str, *, zero: bool = False) -> str:
    """The ISO 230-1 code of an error: ``E``, the component, ``0`` for an axis line, the axis.

    The library's one maker of codes (the catalogues here and :func:`mtaccuracy.machines.iso.
    iso_catalogue` use it; ``data/iso230_names.csv`` is checked against it by the tests).

    Parameters
    ----------
    component : str
        What the error displaces: ``X``, ``Y``, ``Z`` (a translation along it) or ``A``, ``B``,
        ``C`` (a rotation about x, y, z); lower case is accepted.
    axis : str
        The axis it belongs to (``X Y Z A B C``).
    zero : bool
        True for an error of the axis line itself (a squareness or location error), which ISO
        230-1 writes with a ``0`` (``EC0Y``: squareness of Y about z); False for an error motion.

    Returns
    -------
    str

    Examples
    --------
    >>> iso_code("x", "z"), iso_code("C", "Y", zero=True)
    ('EXZ', 'EC0Y')
    """
    c, a = str(component).upper(), str(axis).upper()
    if len(c) != 1 or c not in ISO_COMPONENTS or len(a) != 1 or a not in ISO_COMPONENTS:
        raise ValueError(f"an ISO 230-1 code needs a component and an axis among "
                         f"{ISO_COMPONENTS}, got {component!r}, {axis!r}")
    return f"E{c}{'0' if zero else ''}{a}"


def squareness_code(reference: str, axis: str) -> str:
    """The ISO 230-1 code of the squareness of linear ``axis`` to ``reference`` (``EC0Y``).

    The axis is tilted about the normal of the plane of the two axes.

    Parameters
    ----------
    reference, axis : str
        Two different linear axes (``X``, ``Y``, ``Z``); ``reference`` is the one taken as
        square.

    Returns
    -------
    str

    Examples
    --------
    >>> squareness_code("X", "Y"), squareness_code("Y", "Z"), squareness_code("X", "Z")
    ('EC0Y', 'EA0Z', 'EB0Z')
    """
    r, a = str(reference).upper(), str(axis).upper()
    if r == a or not {r, a} <= set("XYZ"):
        raise ValueError(f"squareness needs two different linear axes, got {reference!r}, "
                         f"{axis!r}")
    normal = 3 - "XYZ".index(r) - "XYZ".index(a)
    return iso_code("ABC"[normal], a, zero=True)


@dataclass(frozen=True)
class ErrorSpec:
    """One geometric error (ISO 230-1 vocabulary).

    Attributes
    ----------
    symbol : str
        The paper's symbol in ASCII (``dx(z)``: x-direction error of the Z axis).
    iso_code : str
        ISO 230-1 code (``EXZ``).
    kind : str
        positioning, straightness, angular, squareness or location.
    axis : str
        The moving axis it belongs to (for squareness: the pair, e.g. ``xy``).
    direction : str
        The coordinate it acts along (translations) or about (rotations).
    translational : bool
        True for a displacement (mm), False for an angle (rad).
    position_dependent : bool
        True for error motions, False for location errors (squareness).
    paper_unit : str
        The unit of the paper's ranges for this error.
    """

    symbol: str
    iso_code: str
    kind: str
    axis: str
    direction: str
    translational: bool
    position_dependent: bool
    paper_unit: str

    @property
    def to_library(self) -> float:
        """Factor that converts a value in ``paper_unit`` to mm or rad."""
        return UNIT_SCALE[self.paper_unit]


def _motion(kind: str, direction: str, axis: str, angular_unit: str) -> ErrorSpec:
    if kind == "angular":
        return ErrorSpec(f"e{direction}({axis})", iso_code(_ROT[direction], axis), kind,
                         axis, direction, False, True, angular_unit)
    return ErrorSpec(f"d{direction}({axis})", iso_code(direction, axis), kind, axis,
                     direction, True, True, "um")


def three_axis_catalogue(angular_unit: str = "rad") -> tuple[ErrorSpec, ...]:
    """The 21 errors of a three-axis machine in the order of Guo et al. 2016, Table 1.

    3 positioning, 6 straightness, 9 angular error motions, 3 squareness errors.  Squareness
    ``S_ij`` is the out-of-squareness of axes i and j, as an angle in um/m; its ISO 230-1 code
    follows :data:`ISO230_NAMES` (``S_xy`` -> EC0Y: Y to X about Z, X the reference).

    Parameters
    ----------
    angular_unit : str
        The unit recorded as ``paper_unit`` of the angular errors.

    Returns
    -------
    tuple of ErrorSpec (21,)

    Examples
    --------
    >>> cat = three_axis_catalogue()
    >>> len(cat), symbols(cat)[:3], symbols(cat)[-3:]
    (21, ['dx(x)', 'dy(y)', 'dz(z)'], ['S_xy', 'S_yz', 'S_xz'])
    >>> cat[0].iso_code, cat[0].paper_unit
    ('EXX', 'um')
    """
    cat = [_motion("positioning", a, a, angular_unit) for a in "xyz"]
    cat += [_motion("straightness", d, a, angular_unit)
            for a, d in (("x", "y"), ("x", "z"), ("y", "x"), ("y", "z"), ("z", "x"), ("z", "y"))]
    cat += [_motion("angular", d, a, angular_unit) for a in "xyz" for d in "xyz"]
    cat += [
        ErrorSpec("S_xy", squareness_code("X", "Y"), "squareness", "xy", "z", False, False,
                  "um/m"),
        ErrorSpec("S_yz", squareness_code("Y", "Z"), "squareness", "yz", "x", False, False,
                  "um/m"),
        ErrorSpec("S_xz", squareness_code("X", "Z"), "squareness", "xz", "y", False, False,
                  "um/m"),
    ]
    return tuple(cat)


def symbols(catalogue: tuple[ErrorSpec, ...]) -> list[str]:
    """Paper symbols of a catalogue, in order.

    Parameters
    ----------
    catalogue : tuple of ErrorSpec
        A catalogue (:func:`three_axis_catalogue`, a machine's ``catalogue``).

    Returns
    -------
    list of str
        The symbols in catalogue order: the column order of the error arrays.
    """
    return [e.symbol for e in catalogue]


def iso_names(path=None) -> dict[str, str]:
    """The working map paper symbol -> ISO 230-1 code from :data:`ISO230_NAMES`.

    That file writes the symbols as ``d_xz`` (x error of Z) and ``e_zx``; this returns them
    as given there.

    Parameters
    ----------
    path : path, optional
        Another map file with the columns ``paper_symbol`` and ``iso230_code`` (default the
        package's own, :data:`ISO230_NAMES`).

    Returns
    -------
    dict
        Paper symbol -> ISO 230-1 code.
    """
    path = ISO230_NAMES if path is None else Path(path)
    with path.open("r", newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    missing = {"paper_symbol", "iso230_code"} - set(rows[0] if rows else {})
    if missing:
        raise ValueError(f"{path}: missing columns {sorted(missing)}")
    return {r["paper_symbol"]: r["iso230_code"] for r in rows}


def uniform_bounds(catalogue: tuple[ErrorSpec, ...],
                   ranges: dict[str, tuple[float, float]]) -> np.ndarray:
    """Lower and upper bounds (2, n_errors) in library units from per-kind ranges.

    ``ranges`` maps each kind present in the catalogue (positioning, straightness, angular,
    squareness) to ``(low, high)`` in the paper's unit of that kind.

    Parameters
    ----------
    catalogue : tuple of ErrorSpec (d,)
        The errors.
    ranges : dict
        Kind -> (low, high) in the paper's unit.

    Returns
    -------
    array (2, d)
        Lower and upper bounds in mm and rad.
    """
    kinds = {e.kind for e in catalogue}
    unknown = set(ranges) - kinds
    if unknown:
        raise ValueError(f"unknown error kind(s) {sorted(unknown)}; allowed: {sorted(kinds)}")
    missing = kinds - set(ranges)
    if missing:
        raise ValueError(f"no range given for error kind(s) {sorted(missing)}")
    out = np.empty((2, len(catalogue)))
    for j, e in enumerate(catalogue):
        lo, hi = ranges[e.kind]
        if not hi > lo:
            raise ValueError(f"range for {e.kind} must have high > low, got ({lo}, {hi})")
        out[:, j] = lo * e.to_library, hi * e.to_library
    return out


def select(catalogue: tuple[ErrorSpec, ...], names) -> list[int]:
    """Column indices of the named errors; an unknown name raises with the allowed ones.

    Parameters
    ----------
    catalogue : tuple of ErrorSpec
        The errors.
    names : iterable of str
        Symbols wanted.

    Returns
    -------
    list of int
    """
    syms = symbols(catalogue)
    bad = [n for n in names if n not in syms]
    if bad:
        raise ValueError(f"unknown error name(s) {bad}; allowed: {', '.join(syms)}")
    return [syms.index(n) for n in names]


def five_axis_ac_catalogue() -> tuple[ErrorSpec, ...]:
    """The 41 errors of Zheng et al. 2024, Table 1, in its numbering (AC double turntable).

    30 error motions (6 per axis X, Y, Z, A, C), 3 squareness errors, 6 location errors of A
    with respect to the machine and 2 of C with respect to A.  Symbols as in
    ``data/papers/zheng2024_table1_errors.csv`` (``d_xc``: x error motion of C; ``a_AM``,
    ``b_AM``, ``g_AM``: alpha, beta, gamma of A); ISO 230-1 codes from :data:`ISO230_NAMES`.
    Translational errors are in um, angular ones in arcsec (the paper's ranges).

    Returns
    -------
    tuple of ErrorSpec (41,)
    """
    iso = iso_names()
    cat = []
    for axis in "xyzac":
        moving = axis.upper()
        trans = [axis, *[d for d in "xyz" if d != axis]] if axis in "xyz" else list("xyz")
        for d in trans:
            cat.append(ErrorSpec(f"d_{d}{axis}", iso[f"d_{d}{axis}"], "error motion", moving, d,
                                 True, True, "um"))
        for d in trans:
            cat.append(ErrorSpec(f"e_{d}{axis}", iso[f"e_{d}{axis}"], "error motion", moving, d,
                                 False, True, "arcsec"))
    for sym, d in (("S_xy", "z"), ("S_yz", "x"), ("S_xz", "y")):
        cat.append(ErrorSpec(sym, iso[sym], "squareness", "XYZ", d, False, False, "arcsec"))
    for sym, d, tr in (("d_xAM", "x", True), ("d_yAM", "y", True), ("d_zAM", "z", True),
                       ("a_AM", "x", False), ("b_AM", "y", False), ("g_AM", "z", False)):
        unit = "um" if tr else "arcsec"
        cat.append(ErrorSpec(sym, iso[sym], "location", "A", d, tr, False, unit))
    for sym, d, tr in (("d_yCA", "y", True), ("b_CA", "y", False)):
        unit = "um" if tr else "arcsec"
        cat.append(ErrorSpec(sym, iso[sym], "location", "C", d, tr, False, unit))
    return tuple(cat)
