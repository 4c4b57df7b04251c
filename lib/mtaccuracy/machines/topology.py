"""The topology of a machine: its axes from the workpiece to the tool, as a string.

A machine is a serial chain of linear (X, Y, Z) and rotary (A, B, C) axes between the
workpiece and the tool, written in the spirit of ISO 10791-1 / ISO 230-1 as a string read from
the workpiece to the tool, with ``b`` for the bed (the machine's base)::

    "w C A b Y X Z t"     workpiece on C, C on A, A on the bed; bed carries Y, Y carries X,
                          X carries Z, Z carries the spindle and the tool (Zheng et al. 2024)
    "w Z b X Y t"         workpiece on the Z table; X column carrying the Y headstock (Rong)
    "w b X Y Z t"         every axis on the tool side, composed X, Y, Z from the workpiece:
                          the serial reading of Guo et al. 2016's Eq. 9
    "w C b X Y Z B t"     a swivel-head mill on a rotary table (notebook 06)

An optional ``s`` (spindle) before ``t`` is accepted and ignored.  :class:`Placement` says where
each error of a catalogue enters the chain.  Each axis ``K`` is the body
that moves along (or about) the coordinate direction ``k`` of the frame it rides on.
:func:`parse_topology` reads the string into a :class:`Topology`;
:class:`mtaccuracy.machines.chain.ChainMachine` builds the machine's chain from it.
"""

from __future__ import annotations

import re
from collections import Counter
from dataclasses import dataclass, field

LINEAR = "XYZ"
ROTARY = "ABC"
#: coordinate direction of each axis letter (A, B, C rotate about x, y, z)
DIRECTION = {"X": 0, "Y": 1, "Z": 2, "A": 0, "B": 1, "C": 2}


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
# Where each error goes (the placements of :class:`.chain.ChainMachine`)
# ------------------------------------------------------------------------------------------

#: error components of a block: translations along x, y, z, rotations about x, y, z
COMPONENTS = ("X", "Y", "Z", "A", "B", "C")
SLOTS = ("motion", "pre", "post", "tilt")


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
