"""Table 3 against the paper's own method (Section 1.1, steps 1-4): a check on printed numbers.

Can one partition of the sensors produce the printed per-position sensitive points?
:func:`partition_fits` enumerates the assignments, :func:`table3_consistency` sums them up,
:func:`rows_fitted_by` checks a given partition (e.g. one of Table 6's).
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from ... import validate

__all__ = ["MAX_ASSIGNMENTS", "partition_fits", "table3_consistency", "rows_fitted_by"]


#: Largest number of labelled assignments :func:`partition_fits` enumerates (3**14).
MAX_ASSIGNMENTS = 3 ** 14


def partition_fits(rows, sensors, n_clusters: int = 3):
    """Which printed sensor sets each assignment of ``sensors`` to clusters can produce.

    Section 1.1's rule: one sensor, the best graded, from every one of ``n_clusters`` clusters.
    Xu et al. 2022 cluster the *temperatures* (Eqs. 1-3: similarities between temperature
    sequences) and only then grade each cluster's sensors against the target (Eq. 4).  Table
    3's 14 positions share their temperatures, so they share one partition; whatever the
    grades, a position's sensitive points then lie one in each cluster.  A printed set
    ``row`` fits an assignment when its sensors carry pairwise different labels and cover
    all ``n_clusters`` labels.  Written by hand: it is the paper's rule, enumerated
    exhaustively (numpy, no Python loop over assignments).

    Parameters
    ----------
    rows : sequence of sequence of str
        The printed sets (e.g. Table 3's 14 rows), each of ``n_clusters`` sensor names.
    sensors : sequence of str
        Every sensor that may be clustered (``S`` names, e.g. T1-T12).
    n_clusters : int
        Clusters of the partition (the paper: 3).

    Returns
    -------
    numpy.ndarray of bool, shape (n_clusters ** S, R)
        ``fits[a, r]``: row ``r`` is producible under assignment ``a``, where assignment
        ``a`` gives sensor ``s`` the label ``(a // n_clusters ** s) % n_clusters``.  Every
        partition into ``n_clusters`` non-empty clusters appears ``n_clusters!`` times.
    """
    sensors = list(sensors)
    n_clusters = validate.integer(n_clusters, "n_clusters", low=1)
    if n_clusters ** len(sensors) > MAX_ASSIGNMENTS:
        raise ValueError(f"{n_clusters}**{len(sensors)} assignments: more than the "
                         f"{MAX_ASSIGNMENTS} this exhaustive check enumerates")
    index = []
    for r in rows:
        r = list(r)
        unknown = [s for s in r if s not in sensors]
        if unknown or len(set(r)) != n_clusters or len(r) != n_clusters:
            raise ValueError(f"row {' '.join(r)}: needs {n_clusters} different sensors out of "
                             f"{' '.join(sensors)}" + (f" (unknown: {unknown})" if unknown else ""))
        index.append([sensors.index(s) for s in r])
    a = np.arange(n_clusters ** len(sensors), dtype=np.int64)
    labels = ((a[:, None] // n_clusters ** np.arange(len(sensors))) % n_clusters).astype(np.int8)
    lab = labels[:, np.array(index, dtype=np.intp).reshape(len(index), n_clusters)]  # (A, R, n)
    # a row of n sensors is producible when its labels are 0..n-1, one per cluster
    return (np.sort(lab, axis=-1) == np.arange(n_clusters)).all(axis=-1)


def table3_consistency(rows, sensors, n_clusters: int = 3) -> dict:
    """How much of Table 3 one partition of the sensors can produce, and which rows none can.

    Table 3 is a per-position table of sensitive points; :func:`partition_fits` enumerates the
    partitions; the smallest set of rows that no partition produces is returned too.

    Parameters
    ----------
    rows : sequence of sequence of str
        The printed sets, one per position.
    sensors : sequence of str
        Every sensor that may be clustered.
    n_clusters : int
        Clusters of the partition.

    Returns
    -------
    dict
        ``assignments`` (``n_clusters ** S``), ``best`` (most rows one assignment fits),
        ``best_assignments`` and ``best_partitions`` (how many attain it, labelled and as
        partitions: labelled / ``n_clusters!``), ``missed`` (for every row, in how many best
        assignments it is not fitted), ``best_partition`` (the canonical best: the smallest
        assignment index, as lists of sensors in cluster-label order), ``conflict`` (row
        indices of the smallest set of rows no assignment fits, the first in lexicographic
        order among the smallest; empty if every row set fits), ``fits`` (the array of
        :func:`partition_fits`).
    """
    sensors = list(sensors)
    fits = partition_fits(rows, sensors, n_clusters)
    count = fits.sum(axis=1)
    best = int(count.max())
    at_best = count == best
    first = int(np.flatnonzero(at_best)[0])
    label = (first // n_clusters ** np.arange(len(sensors))) % n_clusters
    conflict: tuple[int, ...] = ()
    if best < fits.shape[1]:
        for size in range(1, fits.shape[1] + 1):
            conflict = next((c for c in itertools.combinations(range(fits.shape[1]), size)
                             if not fits[:, list(c)].all(axis=1).any()), ())
            if conflict:
                break
    return {"assignments": int(fits.shape[0]), "best": best,
            "best_assignments": int(at_best.sum()),
            "best_partitions": int(at_best.sum()) // math.factorial(n_clusters) if best else 0,
            "missed": (~fits[at_best]).sum(axis=0), "conflict": list(conflict),
            "best_partition": sorted(([s for s, lab in zip(sensors, label, strict=True) if lab == c]
                                      for c in range(n_clusters)), key=lambda g: sensors.index(g[0])
                                     if g else len(sensors)),
            "fits": fits}


def rows_fitted_by(rows, clusters) -> list[bool]:
    """Whether each printed set takes exactly one sensor from every cluster of ``clusters``.

    A sensor in no cluster fits nowhere.

    Parameters
    ----------
    rows : sequence of sequence of str
        The printed sets.
    clusters : sequence of sequence of str
        A partition (e.g. one of Table 6's).

    Returns
    -------
    list of bool
        One entry per row.
    """
    where = {s: i for i, g in enumerate(clusters) for s in g}
    return [len(r) == len(clusters) and all(s in where for s in r)
            and len({where[s] for s in r}) == len(clusters) for r in rows]
