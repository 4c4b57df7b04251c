"""ISO 230-2:2014 positioning accuracy and repeatability of one axis, by the standard's definitions.

**The file**: a CSV ``axis,target_mm,cycle,direction,deviation_um``, one row per reading: the
axis's name (one axis per file), the target position P_i (mm), the cycle j (1, 2, ...), the
approach direction (``+``: the target approached moving in the positive direction, ISO's
up-arrow; ``-``: the negative direction, the down-arrow) and the positional deviation
x_ij = P_ij - P_i (um, the actual position reached minus the target).  :func:`read_iso230_2`
refuses, before any evaluation, every problem with its line and the fix;
:func:`evaluate_iso230_2` evaluates a file or a DataFrame of the same columns.

**The definitions** (ISO 230-2:2014 clause 3; i the target, j the cycle, n_i the cycles of
that target and direction, up = ``+``, down = ``-``)::

    mean unidirectional deviation     xbar_i_up = (1/n) sum_j x_ij_up        (and down)
    mean bidirectional deviation      xbar_i = (xbar_i_up + xbar_i_down) / 2
    reversal value at a position      B_i = xbar_i_up - xbar_i_down
    standard uncertainty estimator    s_i_up = sqrt(sum_j (x_ij_up - xbar_i_up)**2 / (n - 1))
    unidirectional repeatability      R_i_up = 4 s_i_up                       (and down)
    bidirectional repeatability       R_i = max(2 s_i_up + 2 s_i_down + |B_i|, R_i_up, R_i_down)
    reversal value of the axis        B = max_i |B_i|;  mean reversal  B_mean = (1/m) sum_i B_i
    repeatability of the axis         R_up = max_i R_i_up, R_down = max_i R_i_down, R = max_i R_i
    systematic positional deviation   E_up = max_i xbar_i_up - min_i xbar_i_up   (and down)
                                      E = max(xbar_i_up, xbar_i_down) - min(same)
    mean bidirectional range          M = max_i xbar_i - min_i xbar_i
    accuracy                          A_up = max_i(xbar_i_up + 2 s_i_up)
                                             - min_i(xbar_i_up - 2 s_i_up)   (and down)
                                      A = max over both directions of (xbar + 2 s)
                                          - min over both directions of (xbar - 2 s)

Means are over a target's cycles (never over the targets), B_i is up minus down, and the
evaluation is batched (``numpy.bincount`` over target x direction groups).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import pandas as pd

from .files import BelowStandardWarning, MeasurementFileError, Problems, Rows, read_rows

__all__ = ["read_iso230_2", "evaluate_iso230_2", "PositioningData", "Iso230_2Result",
           "COLUMNS", "QUANTITIES", "STANDARD_TARGETS", "STANDARD_CYCLES"]

COLUMNS = ("axis", "target_mm", "cycle", "direction", "deviation_um")
#: The axis quantities, in the order of :meth:`Iso230_2Result.to_df` (all in um).
QUANTITIES = ("E", "E_up", "E_down", "M", "B", "B_mean", "R", "R_up", "R_down", "A", "A_up",
              "A_down")
#: The standard's test: at least 5 targets and 5 per metre of travel, 5 cycles each direction;
#: a smaller test is evaluated with a :class:`~mtaccuracy.measure.files.BelowStandardWarning`.
STANDARD_TARGETS, STANDARD_CYCLES = 5, 5
_WHAT = "an ISO 230-2 file"
_DIRECTIONS = {"+": 0, "-": 1}


@dataclass(frozen=True)
class PositioningData:
    """The checked readings of one axis's ISO 230-2 test.

    Attributes
    ----------
    axis : str
        The axis's name.
    target_mm : (n,) ndarray
        Each reading's target position P_i, mm.
    cycle : (n,) ndarray of int
        Each reading's cycle j.
    up : (n,) ndarray of bool
        True for a reading approached in the positive direction (``+``).
    deviation_um : (n,) ndarray
        Each reading's positional deviation x_ij, um.
    source : str
        The file (or "DataFrame") the readings came from.
    """

    axis: str
    target_mm: np.ndarray
    cycle: np.ndarray
    up: np.ndarray
    deviation_um: np.ndarray
    source: str


def _check(rows: Rows) -> PositioningData:
    """The readings of ``rows``, or every problem with its line and the fix."""
    problems = Problems(rows.path)
    lines = rows.lines
    target = rows.numbers("target_mm", problems, unit="mm")
    dev = rows.numbers("deviation_um", problems, unit="um")
    cyc = rows.numbers("cycle", problems, unit="cycles")
    bad = np.isfinite(cyc) & ((cyc != np.round(cyc)) | (cyc < 1))
    for k in np.flatnonzero(bad):
        problems.add(lines[k], f"cycle is {rows.text['cycle'][k]!r}: number the cycles 1, 2, ...")
    dirs = np.array([_DIRECTIONS.get(d, -1) for d in rows.text["direction"]])
    for k in np.flatnonzero(dirs < 0):
        d = rows.text["direction"][k]
        hint = {"up": "+", "down": "-", "pos": "+", "neg": "-", "positive": "+",
                "negative": "-", "↑": "+", "↓": "-"}.get(d.lower())
        problems.add(lines[k], (
            f"direction is {d!r}: write '+' (approached moving in the positive direction) or "
            f"'-' (in the negative direction)" + (f"; here '{hint}'?" if hint else "")))
    axes = list(dict.fromkeys(rows.text["axis"]))
    if "" in axes:
        for k in np.flatnonzero(np.array(rows.text["axis"]) == ""):
            problems.add(lines[k], "axis is empty: write the axis's name (X, Y, Z, ...)")
        axes.remove("")
    if len(axes) > 1:
        firsts = [int(lines[rows.text["axis"].index(a)]) for a in axes]
        problems.add(firsts[1], (
            f"axis {axes[1]!r} here, {axes[0]!r} on line {firsts[0]}: an ISO 230-2 file holds "
            f"one axis; split the file, one axis per file"))
    problems.raise_if_any()
    up = dirs == 0
    # duplicates: one reading per (target, cycle, direction)
    key = pd.DataFrame({"t": target, "c": cyc, "u": up})
    dup = key.duplicated(keep=False).to_numpy()
    if dup.any():
        first = key[dup].groupby(["t", "c", "u"], sort=False).ngroup().to_numpy()
        seen = {}
        for k, g in zip(np.flatnonzero(dup), first, strict=True):
            if g in seen:
                problems.add(lines[k], (
                    f"target {rows.text['target_mm'][k]} mm, cycle {int(cyc[k])}, direction "
                    f"{rows.text['direction'][k]!r} again (first on line {seen[g]}): keep one "
                    f"reading per target, cycle and direction"))
            else:
                seen[g] = int(lines[k])
    targets, ti = np.unique(target, return_inverse=True)
    counts = np.bincount(2 * ti + (~up), minlength=2 * targets.size).reshape(-1, 2)
    first_line = np.full(targets.size, np.iinfo(int).max)
    np.minimum.at(first_line, ti, lines)
    for i in np.flatnonzero((counts < 2).any(axis=1)):
        where = ", ".join(f"{n} reading(s) in direction '{s}'"
                          for n, s in zip(counts[i], "+-", strict=True) if n < 2)
        problems.add(first_line[i], (
            f"target {targets[i]:g} mm has {where}: ISO 230-2 needs every target approached "
            f"in both directions ('+' and '-'), at least 2 cycles each (5 in the standard)"))
    problems.raise_if_any()
    need = max(STANDARD_TARGETS, int(np.ceil(STANDARD_TARGETS * np.ptp(targets) / 1000.0)))
    if counts.min() < STANDARD_CYCLES or targets.size < need:
        warnings.warn(
            f"{rows.path}: {targets.size} targets over {np.ptp(targets):g} mm, "
            f"{counts.min()} to {counts.max()} cycles per target and direction; ISO 230-2 asks "
            f"for {need} targets here (at least {STANDARD_TARGETS}, {STANDARD_TARGETS} per "
            f"metre) and {STANDARD_CYCLES} cycles: evaluated by its definitions, with s_i, R "
            f"and A less certain", BelowStandardWarning, stacklevel=3)
    return PositioningData(axes[0], target, cyc.astype(int), up, dev, rows.path)


def read_iso230_2(path) -> PositioningData:
    """Read an ISO 230-2 file, refusing every problem before any work.

    Refused, each with its line and the fix: what :func:`mtaccuracy.measure.files.read_rows`
    refuses (not a file, not UTF-8, missing columns, ragged rows, no data), a target, cycle or
    deviation that is not a finite number, a cycle that is not 1, 2, ..., a direction other
    than ``+`` / ``-``, an empty axis or more than one axis, a reading repeated (same target,
    cycle and direction), a target without both directions or with fewer than 2 cycles in
    one.

    Parameters
    ----------
    path : str or os.PathLike
        The CSV file ``axis,target_mm,cycle,direction,deviation_um``.

    Returns
    -------
    PositioningData
        The readings, in the file's order.

    Raises
    ------
    MeasurementFileError
        Listing every problem found.

    Warns
    -----
    BelowStandardWarning
        When the test is smaller than ISO 230-2's: fewer than :data:`STANDARD_CYCLES` cycles
        in a target and direction, or fewer than :data:`STANDARD_TARGETS` targets (and 5 per
        metre of the targets' span).
    """
    return _check(read_rows(path, columns=COLUMNS, what=_WHAT))


def _from_frame(df: pd.DataFrame) -> PositioningData:
    """A DataFrame's readings, checked as a file's (row k reported as line k + 2: a header on
    line 1, as ``df.to_csv(index=False)`` writes it)."""
    missing = [c for c in COLUMNS if c not in df.columns]
    if missing:
        raise MeasurementFileError("DataFrame", [(None, f"missing column(s) {missing}; the "
                                                        f"columns are {', '.join(COLUMNS)}")])
    text = {c: [str(v).strip() for v in df[c].tolist()] for c in COLUMNS}
    return _check(Rows("DataFrame", 1, np.arange(len(df)) + 2, text))


@dataclass(frozen=True)
class Iso230_2Result:
    """The ISO 230-2:2014 evaluation of one axis (every value in um).

    Attributes
    ----------
    axis : str
        The axis's name.
    targets_mm : (m,) ndarray
        The target positions P_i, ascending, mm.
    cycles : (m, 2) ndarray of int
        The cycles n of each target, per direction (column 0: ``+``, column 1: ``-``).
    mean : (m, 3) ndarray
        Per target: xbar_i_up, xbar_i_down and the bidirectional xbar_i, um.
    s : (m, 2) ndarray
        Per target: s_i_up, s_i_down, um.
    values : dict of str to float
        The axis quantities :data:`QUANTITIES`, um.
    source : str
        The file evaluated.
    """

    axis: str
    targets_mm: np.ndarray
    cycles: np.ndarray
    mean: np.ndarray
    s: np.ndarray
    values: dict
    source: str

    def per_target(self) -> pd.DataFrame:
        """The per-target table.

        Returns
        -------
        DataFrame
            One row per target: ``target_mm``, ``n_up``, ``n_down``, ``mean_up_um``,
            ``mean_down_um``, ``mean_um`` (bidirectional), ``B_i_um``, ``s_up_um``,
            ``s_down_um``, ``R_up_um``, ``R_down_um``, ``R_i_um``.
        """
        up, down, bi = self.mean.T
        s_up, s_down = self.s.T
        b = up - down
        return pd.DataFrame({
            "target_mm": self.targets_mm, "n_up": self.cycles[:, 0],
            "n_down": self.cycles[:, 1], "mean_up_um": up, "mean_down_um": down,
            "mean_um": bi, "B_i_um": b, "s_up_um": s_up, "s_down_um": s_down,
            "R_up_um": 4 * s_up, "R_down_um": 4 * s_down,
            "R_i_um": np.maximum(2 * s_up + 2 * s_down + np.abs(b),
                                 np.maximum(4 * s_up, 4 * s_down))})

    def to_df(self) -> pd.DataFrame:
        """The axis quantities, the table ``iso230_2.csv``.

        Returns
        -------
        DataFrame
            Columns ``quantity, value, unit``: one row per name of :data:`QUANTITIES`, in um.
        """
        return pd.DataFrame({"quantity": list(QUANTITIES),
                             "value": [float(self.values[q]) for q in QUANTITIES],
                             "unit": "um"})


def evaluate_iso230_2(data) -> Iso230_2Result:
    """Evaluate an axis's positioning test by ISO 230-2:2014's definitions.

    See the module's docstring for the definitions; the cycles may differ between targets
    and directions (each mean and s_i over that group's own n), the targets' count m is
    independent of the cycles'.

    Parameters
    ----------
    data : PositioningData, str, os.PathLike or DataFrame
        Read readings, a file (:func:`read_iso230_2`), or a DataFrame with the file's columns
        (checked as a file, row k as line k + 2).

    Returns
    -------
    Iso230_2Result
        Per target means, s_i, B_i, R_i; per axis E, E_up, E_down, M, B, B_mean, R, R_up,
        R_down, A, A_up, A_down (um).

    Raises
    ------
    MeasurementFileError
        When the readings break the schema (every problem listed).

    Warns
    -----
    BelowStandardWarning
        When a file or DataFrame holds a smaller test than ISO 230-2's (:func:`read_iso230_2`).
    """
    if isinstance(data, pd.DataFrame):
        data = _from_frame(data)
    elif not isinstance(data, PositioningData):
        data = read_iso230_2(data)
    targets, ti = np.unique(data.target_mm, return_inverse=True)
    m = targets.size
    group = 2 * ti + (~data.up)                                  # (n,): target x direction
    n = np.bincount(group, minlength=2 * m).astype(float)
    x = data.deviation_um
    mean = np.bincount(group, weights=x, minlength=2 * m) / n    # (2m,)
    ss = np.bincount(group, weights=(x - mean[group]) ** 2, minlength=2 * m)
    s = np.sqrt(ss / (n - 1)).reshape(m, 2)                      # s_i_up, s_i_down
    mean = mean.reshape(m, 2)                                    # xbar_i_up, xbar_i_down
    bi = mean.mean(axis=1)
    b_i = mean[:, 0] - mean[:, 1]
    r_dir = 4 * s
    r_i = np.maximum(2 * s.sum(axis=1) + np.abs(b_i), r_dir.max(axis=1))
    hi, lo = mean + 2 * s, mean - 2 * s
    values = {
        "E": mean.max() - mean.min(),
        "E_up": np.ptp(mean[:, 0]), "E_down": np.ptp(mean[:, 1]),
        "M": np.ptp(bi),
        "B": np.abs(b_i).max(), "B_mean": b_i.mean(),
        "R": r_i.max(), "R_up": r_dir[:, 0].max(), "R_down": r_dir[:, 1].max(),
        "A": hi.max() - lo.min(),
        "A_up": hi[:, 0].max() - lo[:, 0].min(), "A_down": hi[:, 1].max() - lo[:, 1].min(),
    }
    return Iso230_2Result(data.axis, targets, n.reshape(m, 2).astype(int),
                          np.column_stack([mean, bi]), s,
                          {k: float(v) for k, v in values.items()}, data.source)
