"""Samplers and sensitivity measures, batched over samples (and over repeats).

Spearman ranking (Guo et al. 2016) lives here; Sobol estimators, sparse polynomial chaos and
key-error rules join it with the later papers.  Latin hypercube sampling is scipy's
``scipy.stats.qmc.LatinHypercube``; ranks are ``scipy.stats.rankdata``.
"""

from __future__ import annotations

__all__ = ["as_generator", "latin_hypercube", "repeated_latin_hypercube", "spearman",
           "rank_by_magnitude", "below_group_mean", "position_outputs", "spearman_over_poses"]

import numpy as np
from scipy import stats
from scipy.stats import qmc


def as_generator(seed) -> np.random.Generator:
    """A ``numpy.random.Generator`` from a seed, SeedSequence or Generator."""
    if isinstance(seed, np.random.Generator):
        return seed
    return np.random.default_rng(seed)


def latin_hypercube(n: int, bounds: np.ndarray, seed) -> np.ndarray:
    """``n`` Latin hypercube samples (n, d) of independent uniforms on ``bounds`` (2, d).

    Uses ``scipy.stats.qmc.LatinHypercube`` (random placement within strata).
    """
    bounds = np.asarray(bounds, dtype=float)
    if bounds.ndim != 2 or bounds.shape[0] != 2:
        raise ValueError(f"bounds must have shape (2, d), got {bounds.shape}")
    if int(n) != n or n < 2:
        raise ValueError(f"n must be an integer >= 2, got {n!r}")
    u = qmc.LatinHypercube(d=bounds.shape[1], rng=as_generator(seed)).random(int(n))
    return bounds[0] + u * (bounds[1] - bounds[0])


def repeated_latin_hypercube(n: int, bounds: np.ndarray, repeats: int, seed) -> np.ndarray:
    """``repeats`` independent Latin hypercube designs, (repeats, n, d).

    Each design gets its own child of ``numpy.random.SeedSequence(seed)``, so design ``r`` is
    the same whatever ``repeats`` is.
    """
    if int(repeats) != repeats or repeats < 1:
        raise ValueError(f"repeats must be an integer >= 1, got {repeats!r}")
    children = np.random.SeedSequence(seed).spawn(int(repeats))
    return np.stack([latin_hypercube(n, bounds, np.random.default_rng(c)) for c in children])


def spearman(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Spearman rank correlation of every column of ``x`` with every column of ``y``.

    ``x`` (..., n, p) and ``y`` (..., n, q) share the sample axis ``-2``; leading axes
    broadcast (e.g. repeats or poses).  Returns (..., p, q).  Ties get average ranks (Eq. 15
    of Guo et al. 2016 is Pearson's correlation of the ranks).
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if x.shape[-2] != y.shape[-2]:
        raise ValueError(f"x and y need the same number of samples, got {x.shape} and {y.shape}")
    rx = stats.rankdata(x, axis=-2)
    ry = stats.rankdata(y, axis=-2)
    rx = rx - rx.mean(axis=-2, keepdims=True)
    ry = ry - ry.mean(axis=-2, keepdims=True)
    num = np.swapaxes(rx, -1, -2) @ ry
    den = np.sqrt((rx**2).sum(axis=-2))[..., :, None] * np.sqrt((ry**2).sum(axis=-2))[..., None, :]
    with np.errstate(invalid="ignore", divide="ignore"):
        return num / den


def rank_by_magnitude(values: np.ndarray, names: list[str]) -> list[tuple[str, float]]:
    """(name, value) pairs sorted by decreasing ``|value|``, ties broken by name order."""
    values = np.asarray(values, dtype=float)
    order = sorted(range(len(names)), key=lambda j: (-abs(values[j]), j))
    return [(names[j], float(values[j])) for j in order]


def below_group_mean(coefficients: np.ndarray) -> np.ndarray:
    """Guo et al.'s weak-error rule: True where ``|rho|`` is below the mean ``|rho|`` of its
    output column for every output.  ``coefficients`` is (p, q); returns (p,) booleans."""
    a = np.abs(np.asarray(coefficients, dtype=float))
    return np.all(a < a.mean(axis=0, keepdims=True), axis=1)


def position_outputs(pose_error: np.ndarray) -> np.ndarray:
    """Ex, Ey, Ez and Et = sqrt(Ex^2 + Ey^2 + Ez^2) (Guo et al. Eq. 14) from (..., 6) pose
    errors, as (..., 4)."""
    p = np.asarray(pose_error)[..., :3]
    return np.concatenate([p, np.linalg.norm(p, axis=-1, keepdims=True)], axis=-1)


def spearman_over_poses(machine, samples: np.ndarray, poses: dict, outputs=position_outputs,
                        chunk: int = 64) -> np.ndarray:
    """Spearman coefficients of every error with every output, at many poses.

    ``samples`` (n, d) is one error design reused at every pose (common random numbers);
    ``poses`` maps pose names to (P,) arrays.  Returns (P, d, q).  Poses are evaluated in
    chunks of ``chunk`` poses, each chunk as one batched model call over chunk * n rows.
    """
    samples = np.asarray(samples, dtype=float)
    n = samples.shape[0]
    sizes = {np.size(v) for v in poses.values()}
    if len(sizes) != 1:
        raise ValueError(f"pose arrays must have one common length, got {sorted(sizes)}")
    n_poses = sizes.pop()
    out = []
    for start in range(0, n_poses, chunk):
        stop = min(start + chunk, n_poses)
        k = stop - start
        pose = {name: np.repeat(np.asarray(v, dtype=float)[start:stop], n)
                for name, v in poses.items()}
        y = outputs(machine.pose_error(np.tile(samples, (k, 1)), pose)).reshape(k, n, -1)
        out.append(spearman(np.broadcast_to(samples, (k,) + samples.shape), y))
    return np.concatenate(out, axis=0)
