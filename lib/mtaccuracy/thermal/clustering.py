"""Temperature-sensitive points (Xu et al. 2022, Section 3): fuzzy clustering and grey grades.

Fuzzy equivalence clustering (Eqs. 1-3) and Deng's grey relational grade (Eq. 4).  Written by
hand because it is the paper's method and neither scipy nor scikit-learn has it.  Arrays are
(n_samples, n_variables): rows are measurements, columns sensors.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from .. import validate

__all__ = [
    "similarity_matrix", "max_min_compose", "transitive_closure", "lambda_cut", "Clustering",
    "LEVEL_RTOL", "cut_levels", "cut_for", "fuzzy_clusters", "normalise_range",
    "grey_relational_grade", "Selection", "select_sensitive_points", "most_frequent",
]

# --------------------------------------------------------------------------------------------
# Temperature-sensitive points: fuzzy equivalence clustering and grey relational grade
# --------------------------------------------------------------------------------------------

def similarity_matrix(x: np.ndarray) -> np.ndarray:
    """Similarity of the temperature sequences (Xu et al. 2022, Eq. 1).

    ``r_ij = sum_k |x_i(k) - m_i| |x_j(k) - m_j| / (||x_i - m_i|| ||x_j - m_j||)``.  As printed,
    the numerator takes absolute deviations, so r_ij is in [0, 1] and blind to sign (a falling
    and a rising sensor can be similar).  The printed denominator has ``x_i(k) - mean_j`` under
    the second root, a typo for ``x_j(k)``.

    Parameters
    ----------
    x : array (n_samples, n_variables)
        The sequences, one per column (degC).

    Returns
    -------
    array (n_variables, n_variables)
        Symmetric, ones on the diagonal.
    """
    x = np.asarray(x, dtype=float)
    if x.ndim != 2 or x.shape[0] < 2:
        raise ValueError(f"need (n_samples >= 2, n_variables), got shape {x.shape}")
    d = x - x.mean(axis=0)
    norm = np.sqrt((d**2).sum(axis=0))
    flat = np.flatnonzero(norm == 0)
    if flat.size:
        raise ValueError(f"variable(s) {flat.tolist()} are constant; their similarity is "
                         f"undefined (drop them)")
    a = np.abs(d)
    # summed over the samples in a fixed order, not by BLAS: equal columns give bitwise-equal
    # rows and r is exactly symmetric on every machine, so ties stay ties for the lambda cut
    r = (a[:, :, None] * a[:, None, :]).sum(axis=0) / np.outer(norm, norm)
    np.fill_diagonal(r, 1.0)
    return np.clip(r, 0.0, 1.0)


def max_min_compose(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Fuzzy (max-min) composition: ``(a o b)_ij = max_k min(a_ik, b_kj)``.

    Parameters
    ----------
    a : array (n, m)
        A fuzzy relation: membership degrees in [0, 1].
    b : array (m, p)
        A fuzzy relation composed after ``a``.

    Returns
    -------
    array (n, p)
        The composed relation, every entry one of ``a``'s or ``b``'s.
    """
    return np.minimum(a[:, :, None], b[None, :, :]).max(axis=1)


def transitive_closure(r: np.ndarray, max_squarings: int = 64) -> tuple[np.ndarray, int]:
    """Transitive closure of a fuzzy similarity relation (Xu et al. 2022, Eq. 2).

    Squares R by max-min composition until ``R^(2^k) = R^(2^(k+1))``.  Max-min composition only
    ever picks existing entries, so the fixed point is reached exactly (at most ceil(log2 n)
    squarings for a reflexive n x n relation).

    Parameters
    ----------
    r : array (n, n)
        Reflexive, symmetric similarity (:func:`similarity_matrix`).
    max_squarings : int
        Give up (RuntimeError) after this many squarings; at least 0.

    Returns
    -------
    closure : array (n, n)
        t(R), a fuzzy equivalence relation.
    squarings : int
        k, the squarings it took.
    """
    max_squarings = validate.integer(max_squarings, "max_squarings", low=0)
    r = np.asarray(r, dtype=float)
    for k in range(max_squarings + 1):
        r2 = max_min_compose(r, r)
        if np.array_equal(r2, r):
            return r, k
        r = r2
    raise RuntimeError("transitive closure did not converge (is R reflexive?)")


def lambda_cut(t: np.ndarray, lam: float) -> np.ndarray:
    """Classes of the Boolean relation ``t_ij >= lam`` (Xu et al. 2022, Eq. 3).

    Parameters
    ----------
    t : array (n, n)
        A fuzzy equivalence relation (:func:`transitive_closure`).
    lam : float
        The cut level: i and j share a class where ``t_ij >= lam``.

    Returns
    -------
    array of int (n,)
        Class labels 0, 1, ... numbered by first member.
    """
    n = len(t)
    labels = np.full(n, -1)
    nxt = 0
    for i in range(n):
        if labels[i] < 0:
            labels[(t[i] >= lam) & (labels < 0)] = nxt
            nxt += 1
    return labels


@dataclass
class Clustering:
    """Result of :func:`fuzzy_clusters`.

    Attributes
    ----------
    groups : list of list of str
        Variable names of each class at the cut.
    lam : float
        The cut level.
    labels : array of int (n,)
        Class of each variable.
    closure : array (n, n)
        t(R), the transitive closure the cut was taken of.
    squarings : int
        Squarings the closure took.
    gap : float
        Relative distance of the cut to the nearest other level (NaN if none).
    """

    groups: list[list[str]]
    lam: float
    labels: np.ndarray
    closure: np.ndarray
    squarings: int
    gap: float = np.nan


#: Levels of a transitive closure closer than this (relative) are one level.  Eq. 1 is
#: computed in closed form to about 1e-15; two levels that close are equal in exact arithmetic
#: (a sensor and a scaled copy of it, mirrored ones: Eq. 1 is blind to sign and scale) or
#: differ by nothing the data can resolve, and a cut between them would split classes by
#: rounding noise.
LEVEL_RTOL = 1e-9


def cut_levels(t: np.ndarray, rtol: float = LEVEL_RTOL) -> np.ndarray:
    """The distinct levels of a fuzzy equivalence relation, highest first.

    A run of levels closer than ``rtol`` (relative) counts once, at its lowest member (a cut
    there keeps the run together).

    Parameters
    ----------
    t : array (n, n)
        t(R), a fuzzy equivalence relation (:func:`transitive_closure`).
    rtol : float
        Relative tolerance of equal levels (:data:`LEVEL_RTOL`).

    Returns
    -------
    array (m,)
        The levels, descending.
    """
    levels = np.unique(t)[::-1]
    last_of_run = np.append(levels[:-1] - levels[1:] > rtol * np.abs(levels[:-1]), True)
    return levels[last_of_run]


def cut_for(t: np.ndarray, n_clusters: int, rtol: float = LEVEL_RTOL):
    """The cut of t(R) that gives ``n_clusters`` classes.

    The highest cut (levels from :func:`cut_levels`) with exactly ``n_clusters`` classes, or,
    where ties merge several classes at one level, the cut with the fewest classes above
    ``n_clusters``; where even the highest level has fewer classes (variables equal up to scale
    cannot be told apart), that level.

    Parameters
    ----------
    t : array (n, n)
        t(R), a fuzzy equivalence relation (:func:`transitive_closure`).
    n_clusters : int
        Classes wanted, at least 1.
    rtol : float
        Relative tolerance of equal levels (:data:`LEVEL_RTOL`).

    Returns
    -------
    lam : float
        The cut level.
    labels : array of int (n,)
        Classes at that cut (:func:`lambda_cut`).
    """
    n_clusters = validate.integer(n_clusters, "n_clusters", low=1)
    levels = cut_levels(t, rtol)
    best = (levels[0], lambda_cut(t, levels[0]))
    for lam in levels:  # from the highest level down, classes merge
        labels = lambda_cut(t, lam)
        n = labels.max() + 1
        if n >= n_clusters:
            best = (lam, labels)
        if n <= n_clusters:
            break
    return best


def fuzzy_clusters(x: np.ndarray, names, n_clusters: int = 3) -> Clustering:
    """Fuzzy equivalence clustering of the columns of ``x`` (Xu et al. 2022, Eqs. 1-3).

    The cut ``lam`` is the largest level of t(R) at which the classes number exactly
    ``n_clusters`` (levels closer than :data:`LEVEL_RTOL` count as one, :func:`cut_for`).  Were
    that impossible (ties merging several classes at one level), the cut with the fewest classes
    above ``n_clusters`` is used, and ``len(groups)`` says so.

    Parameters
    ----------
    x : array (n_samples, n_variables)
        Sequences (degC).
    names : sequence of str
        Variable names, one per column.
    n_clusters : int
        Classes wanted, 1 to the number of variables (the paper: 3).

    Returns
    -------
    Clustering
        The classes at the cut, the cut and its distance to the nearest other level.
    """
    names = list(names)
    n_clusters = validate.integer(n_clusters, "n_clusters", low=1, high=len(names))
    x = np.asarray(x, dtype=float)
    flat = [names[j] for j in np.flatnonzero(np.ptp(x, axis=0) == 0)]
    if flat:
        raise ValueError(f"sensor(s) {flat} do not change over the data used for clustering; "
                         f"drop them")
    t, k = transitive_closure(similarity_matrix(x))
    lam, labels = cut_for(t, n_clusters)
    groups = [[names[i] for i in np.flatnonzero(labels == g)] for g in range(labels.max() + 1)]
    others = cut_levels(t)
    others = others[others != lam]
    gap = float(np.abs(others - lam).min() / lam) if others.size else np.nan
    return Clustering(groups, float(lam), labels, t, k, gap)


def normalise_range(x: np.ndarray) -> np.ndarray:
    """Scale every column to [0, 1] by its range (a constant column becomes 0).

    Parameters
    ----------
    x : array (n,) or (n, m)
        Values; each column is scaled on its own.

    Returns
    -------
    array, the shape of ``x``
        In [0, 1].
    """
    x = np.asarray(x, dtype=float)
    lo, span = x.min(axis=0), np.ptp(x, axis=0)
    return np.divide(x - lo, span, out=np.zeros_like(x), where=span > 0)


def grey_relational_grade(x0: np.ndarray, x: np.ndarray, rho: float = 0.5) -> np.ndarray:
    """Deng's grey relational grade of each column to a reference (Xu et al. 2022, Eq. 4).

    ``xi_i(k) = (min_i min_k D + rho max_i max_k D) / (D_i(k) + rho max_i max_k D)`` with
    ``D_i(k) = |x0(k) - x_i(k)|``; the grade is the mean of xi_i over k.  The sequences must
    already be comparable (normalised); the two-level min and max run over all m candidates
    together.

    Parameters
    ----------
    x0 : array (n,)
        The reference sequence (normalised error, k or b).
    x : array (n, m)
        Candidate sequences (normalised temperatures).
    rho : float
        Distinguishing coefficient in (0, 1] (the paper: 0.5).

    Returns
    -------
    array (m,)
        Grades in (0, 1].
    """
    if not 0 < rho <= 1:
        raise ValueError(f"rho must be in (0, 1], got {rho}")
    x0 = np.asarray(x0, dtype=float).ravel()
    x = np.asarray(x, dtype=float).reshape(len(x0), -1)
    d = np.abs(x - x0[:, None])
    dmin, dmax = d.min(), d.max()
    if dmax == 0:
        return np.ones(x.shape[1])
    return ((dmin + rho * dmax) / (d + rho * dmax)).mean(axis=0)


@dataclass
class Selection:
    """Sensitive points chosen by :func:`select_sensitive_points`.

    Attributes
    ----------
    clusters : list of list of str
        The sensors of every cluster.
    grades : Series
        Every sensor's grey relational grade to the target.
    selected : list of str
        The chosen sensor per cluster, in the order of the temperature columns.
    lam : float
        The clustering's cut.
    mirrored : list of str
        Sensors mirrored (1 - x) before grading (negatively correlated with the target).
    margins : dict
        How far each decision is from flipping: ``"level"`` the relative distance of the cut to
        the nearest other level, ``"grade"`` the smallest lead of a cluster's winner over its
        runner-up, ``"correlation"`` the smallest ``|correlation|`` that decided a mirroring (NaN
        where there is nothing to decide).
    """

    clusters: list[list[str]]
    grades: pd.Series
    selected: list[str]
    lam: float
    mirrored: list[str]
    margins: dict = field(default_factory=dict)


def select_sensitive_points(temperatures: pd.DataFrame, target, *, n_clusters: int = 3,
                            rho: float = 0.5, clustering: Clustering | None = None
                            ) -> Selection:
    """Temperature-sensitive points: one sensor per fuzzy cluster (Xu et al. 2022, Section 2).

    Clusters the temperature sequences (Eqs. 1-3), then keeps in every cluster the sensor with
    the highest grey relational grade to ``target`` (Eq. 4).  Normalisation (the paper does not
    state one): every sequence, the target included, is scaled to [0, 1] by its range;
    initial-value scaling is impossible for temperature rises, which start at 0.  A sensor that
    correlates negatively with the target is mirrored (1 - x) before grading: the grade
    compares shapes, and a heating that makes the error fall is as informative as one that makes
    it rise (Eq. 1 is blind to sign in the same way).

    Parameters
    ----------
    temperatures : DataFrame (n, S)
        One column per sensor (degC, absolute or rises).
    target : array (n,)
        The error at one position (um), or k (um/m) or b (um).
    n_clusters : int
        Clusters, so sensors selected (the paper: 3).
    rho : float
        Distinguishing coefficient of the grade, in (0, 1] (the paper: 0.5).
    clustering : Clustering, optional
        :func:`fuzzy_clusters` of these ``temperatures`` with ``n_clusters``, computed once and
        passed to every call that selects on the same temperatures for another target (the
        clusters do not depend on the target; :func:`mtaccuracy.thermal.evaluate_split` selects
        at every position): the result is the same as without it.

    Returns
    -------
    Selection
        The clusters, every sensor's grade, the sensor chosen per cluster and the margins.
    """
    names = list(temperatures.columns)
    x = temperatures.to_numpy(dtype=float)
    y = np.asarray(target, dtype=float).ravel()
    if len(y) != len(x):
        raise ValueError(f"target has {len(y)} values, temperatures {len(x)} rows")
    if clustering is None:
        cl = fuzzy_clusters(x, names, n_clusters)
    elif sorted(s for g in clustering.groups for s in g) != sorted(names):
        raise ValueError("clustering was computed for other sensors")
    else:
        cl = clustering
    xn = normalise_range(x)
    yn = normalise_range(y[:, None])[:, 0]
    corr = np.array([np.corrcoef(x[:, j], y)[0, 1] if np.ptp(x[:, j]) > 0 else 0.0
                     for j in range(x.shape[1])])
    flip = corr < 0
    xn[:, flip] = 1.0 - xn[:, flip]
    grades = pd.Series(grey_relational_grade(yn, xn, rho), index=names, name="grade")
    selected = sorted((max(g, key=lambda s: (grades[s], -names.index(s))) for g in cl.groups),
                      key=names.index)
    leads = [np.subtract(*np.sort(grades[g].to_numpy())[::-1][:2]) for g in cl.groups
             if len(g) > 1]
    margins = {"level": cl.gap, "grade": float(min(leads)) if leads else np.nan,
               "correlation": float(np.abs(corr[np.ptp(x, axis=0) > 0]).min())
               if (np.ptp(x, axis=0) > 0).any() else np.nan}
    return Selection(cl.groups, grades, selected, cl.lam,
                     [n for n, f in zip(names, flip, strict=True) if f], margins)


def most_frequent(selections, n: int = 3, order=None) -> list[str]:
    """The ``n`` sensors chosen most often over several selections (ties: sensor order).

    Parameters
    ----------
    selections : iterable of list of str
        The sensors chosen each time (one selection per position, Section 3.1).
    n : int
        How many to keep, at least 0.
    order : sequence of str, optional
        Sensor order for ties and for the result; default sorted names.

    Returns
    -------
    list of str
        In ``order``.
    """
    n = validate.integer(n, "n", low=0)
    counts = Counter(s for sel in selections for s in sel)
    order = list(order) if order is not None else sorted(counts)
    return sorted(sorted(counts, key=lambda s: (-counts[s], order.index(s)))[:n], key=order.index)
