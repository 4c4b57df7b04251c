"""Table 3 under Section 3.1's per-position reading: each position's error joins the clustering.

Section 3.1 of Xu et al. 2022 (doi:10.19650/j.cnki.cjsi.J2209628) says "对各点的热误差数据分别聚类"
(the thermal error data of each point clustered separately) and prints the result per position
(Table 3).  Section 1.1's Eqs. 1-3 compare temperature sequences, which the 14 positions share; the
one input that changes from position to position is that position's error.  The reading the text
supports is therefore: at every position, Eqs. 1-3 take the position's error sequence as one more
variable beside the S temperature sequences, the lambda cut is taken where the *temperatures* fall
into ``n_clusters`` groups (Section 1.1: the number of clusters is the number of model inputs),
and Eq. 4 keeps the best-graded sensor of each group.  The error links, at the cut, every class of
the temperatures whose similarity to it reaches the cut: a position's partition is the shared
single-linkage partition of the temperatures with the classes its error touches merged.  So on
every dataset a row's partition may differ from its neighbour's, and any row of ``n_clusters``
distinct sensors can come from it (:func:`witness`, a constructive example).

:func:`per_position_clusters` clusters all positions at once (numpy, batched over positions);
:func:`per_position_selections` adds the grades (the library's
:func:`mtaccuracy.thermal.select_sensitive_points`, given each position's clusters).  Kept here,
not in :mod:`mtaccuracy.thermal`: it is a reading of this paper's Table 3, not a method a reader
of their own data would choose (it lets the target reshape the clusters it is graded in).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ... import validate
from ...thermal import LEVEL_RTOL, Clustering, select_sensitive_points, similarity_matrix

__all__ = ["per_position_clusters", "per_position_selections", "witness"]


def _eq1_to(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Eq. 1 between every column of ``y`` (n, P) and every column of ``x`` (n, S): (P, S)."""
    dx, dy = x - x.mean(axis=0), y - y.mean(axis=0)
    nx, ny = np.sqrt((dx**2).sum(axis=0)), np.sqrt((dy**2).sum(axis=0))
    # summed over the samples in a fixed order (as thermal.similarity_matrix): deterministic
    num = (np.abs(dy)[:, :, None] * np.abs(dx)[:, None, :]).sum(axis=0)
    return np.clip(num / np.outer(ny, nx), 0.0, 1.0)


def per_position_clusters(temperatures, errors, *, n_clusters: int = 3,
                          rtol: float = LEVEL_RTOL) -> dict:
    """Fuzzy equivalence clustering of the temperatures together with each position's error.

    For every position p, Eq. 1 on the S temperature sequences and the error sequence of p
    (an (S + 1) x (S + 1) similarity), its transitive closure by max-min squaring (Eq. 2), and
    the lambda cut (Eq. 3) at the highest level of the closure at which the S temperatures fall
    into exactly ``n_clusters`` classes (where ties jump past it: the fewest classes above
    ``n_clusters``); the error's own membership is dropped.  Levels closer than ``rtol``
    (relative) count as one, as in :func:`mtaccuracy.thermal.cut_levels`.

    Parameters
    ----------
    temperatures : array (n, S)
        The temperature sequences (degC; the paper: rises for Table 3), one column per sensor.
    errors : array (n, P)
        The error sequence at each of P positions (um).
    n_clusters : int
        Classes of the temperatures at the cut, 1 to S (the paper: 3).
    rtol : float
        Relative tolerance of equal levels.

    Returns
    -------
    dict
        ``labels`` int array (P, S): class of every sensor at every position, numbered by first
        member; ``lam`` (P,): the cut; ``closure`` (P, S + 1, S + 1): t(R), the error last;
        ``gap`` (P,): relative distance of the cut to the nearest other level (NaN if none);
        ``squarings``: the squarings the slowest position took.

    Raises
    ------
    ValueError
        Shapes that disagree, a constant sequence (Eq. 1 is undefined), ``n_clusters`` outside
        1..S.
    """
    x = np.asarray(temperatures, dtype=float)
    y = np.asarray(errors, dtype=float)
    if x.ndim != 2 or y.ndim != 2 or len(x) != len(y) or len(x) < 2:
        raise ValueError(f"temperatures (n, S) and errors (n, P) with the same n >= 2 rows; got "
                         f"{x.shape} and {y.shape}")
    s, p = x.shape[1], y.shape[1]
    n_clusters = validate.integer(n_clusters, "n_clusters", low=1, high=s)
    flat = np.flatnonzero(np.ptp(y, axis=0) == 0)
    if flat.size:
        raise ValueError(f"error column(s) {flat.tolist()} are constant: Eq. 1 is undefined for "
                         "them (such a position has nothing to cluster)")
    r = np.empty((p, s + 1, s + 1))
    r[:, :s, :s] = similarity_matrix(x)          # refuses constant temperature columns
    r[:, s, :s] = r[:, :s, s] = _eq1_to(x, y)
    r[:, s, s] = 1.0
    squarings = 0
    while True:                                   # at most ceil(log2(S + 1)) + 1 rounds
        r2 = np.minimum(r[:, :, :, None], r[:, None, :, :]).max(axis=2)
        if np.array_equal(r2, r):
            break
        r, squarings = r2, squarings + 1
    t = r[:, :s, :s]                              # sensors linked directly or through the error
    levels = r.reshape(p, -1)                     # (P, K): every level is a candidate cut
    same = t[:, None] >= (levels * (1.0 - rtol))[:, :, None, None]     # (P, K, S, S)
    first = ~np.tril(same, k=-1).any(axis=-1)     # no earlier sensor in its class
    count = first.sum(axis=-1)                    # (P, K): classes of the temperatures
    # the fewest classes >= n_clusters, then the highest such level
    key = np.where(count >= n_clusters, count, np.iinfo(np.int64).max // 2)
    best = key.min(axis=1, keepdims=True)
    pick = np.where(key == best, levels, -np.inf).argmax(axis=1)
    lam = levels[np.arange(p), pick]
    chosen = same[np.arange(p), pick]             # (P, S, S)
    lead = chosen.argmax(axis=-1)                 # first member of every sensor's class
    labels = np.cumsum(first[np.arange(p), pick], axis=1)[np.arange(p)[:, None], lead] - 1
    other = np.where(np.abs(levels - lam[:, None]) > rtol * lam[:, None], levels, np.nan)
    with np.errstate(invalid="ignore"):
        gap = np.nanmin(np.abs(other - lam[:, None]), axis=1, initial=np.inf) / lam
    gap[~np.isfinite(gap)] = np.nan
    return {"labels": labels, "lam": lam, "closure": r, "gap": gap, "squarings": squarings}


def per_position_selections(temperatures: pd.DataFrame, errors, *, n_clusters: int = 3,
                            rho: float = 0.5) -> list:
    """Table 3 under the per-position reading: every position's clusters and sensitive points.

    :func:`per_position_clusters`, then in every class the sensor with the highest grey grade
    to that position's error (:func:`mtaccuracy.thermal.select_sensitive_points`, with its
    normalisation and mirroring; only the clusters differ from the shared reading).

    Parameters
    ----------
    temperatures : DataFrame (n, S)
        One column per sensor (degC; Table 3: the rises of the training experiments).
    errors : array (n, P)
        The error at each position (um).
    n_clusters : int
        Classes, so sensors per position (the paper: 3).
    rho : float
        Distinguishing coefficient of the grade, in (0, 1] (the paper: 0.5).

    Returns
    -------
    list of Selection
        One per position, as :func:`mtaccuracy.thermal.select_sensitive_points` returns them.
    """
    names = list(temperatures.columns)
    y = np.asarray(errors, dtype=float)
    cl = per_position_clusters(temperatures.to_numpy(dtype=float), y, n_clusters=n_clusters)
    out = []
    for i in range(y.shape[1]):                   # over the positions (the grades: per target)
        lab = cl["labels"][i]
        groups = [[names[j] for j in np.flatnonzero(lab == g)] for g in range(lab.max() + 1)]
        c = Clustering(groups, float(cl["lam"][i]), lab, cl["closure"][i, :-1, :-1],
                       cl["squarings"], float(cl["gap"][i]))
        out.append(select_sensitive_points(temperatures, y[:, i], n_clusters=n_clusters,
                                           rho=rho, clustering=c))
    return out


def witness(rows, sensors, *, block: int = 4) -> tuple[pd.DataFrame, np.ndarray]:
    """Data on which the per-position reading gives exactly ``rows``: a constructive example.

    Each sensor is the indicator of a block of its own (``block`` samples at 1, the rest 0): the
    temperatures are pairwise dissimilar (Eq. 1 about 0.24).  For a row {a, b, c, ...} of
    ``m`` sensors the position's error is 0 on the blocks of the first ``m - 1`` sensors (the
    error's mean, so Eq. 1 sees no deviation there), and on every other sensor's block
    alternately +w and -w, with w = 1.5 for the row's last sensor and 1 elsewhere: the error is
    more similar to each of those sensors than any two temperatures are to each other, so it
    merges them into one class; the first ``m - 1`` stay single, and the last one wins its class
    on the grade.  The sequences are not temperatures of a machine: they show that the
    per-position reading constrains no row of ``m`` distinct sensors, whatever the data.

    Parameters
    ----------
    rows : sequence of sequence of str
        The sets wanted, one per position, each of ``m`` distinct sensors (``m`` the same).
    sensors : sequence of str
        Every sensor (S names), at least ``m + 2``.
    block : int
        Samples per sensor's block, at least 2.

    Returns
    -------
    (DataFrame (S * block, S), array (S * block, P))
        Temperatures (one column per sensor) and the error at each position.
    """
    sensors = list(sensors)
    block = validate.integer(block, "block", low=2)
    rows = [list(r) for r in rows]
    m = len(rows[0]) if rows else 0
    for r in rows:
        if len(r) != m or len(set(r)) != m or not set(r) <= set(sensors) or m < 1:
            raise ValueError(f"row {' '.join(r)}: needs {m or 'at least 1'} different sensors of "
                             f"{' '.join(sensors)}")
    if len(sensors) < m + 2:
        raise ValueError(f"{len(sensors)} sensors: the example needs at least {m + 2} (the row's "
                         "first sensors single, two or more in the merged class)")
    s = len(sensors)
    ind = np.repeat(np.eye(s), block, axis=0)     # (S * block, S): sensor j is block j
    errors = np.zeros((s * block, len(rows)))
    for p, r in enumerate(rows):                  # over the P positions (construction only)
        alone = [sensors.index(v) for v in r[:-1]]
        rest = [j for j in range(s) if j not in alone]
        amp = np.where(np.array(rest) == sensors.index(r[-1]), 1.5, 1.0)
        sign = np.where(np.arange(len(rest)) % 2 == 0, 1.0, -1.0)
        level = amp * sign
        errors[:, p] = ind[:, rest] @ (level - level.mean())
    return pd.DataFrame(ind, columns=sensors), errors
