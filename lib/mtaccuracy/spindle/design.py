"""Designing the probe layout (Yang et al. 2021, Section 2).

The objective ``H = q_k^2`` (Eqs. 19-20) of the genes ``x = (phi_1, phi_2, phi_3, a_3)``, its
bounds, the best ``a_3`` in closed form, and the canonical member of the 48 gene vectors that
describe one layout.

``H >= 1/4`` for four probes at every harmonic (Cauchy-Schwarz), reached for even ``k``;
:func:`optimal_a3` gives the best ``a_3`` for given angles in closed form.  ``H`` belongs to the
physical layout: the 48 gene vectors that describe one layout (:func:`equivalent_genes`:
reference probe, labels, mirror) share it, so a best layout is picked with ties (``H`` equal
within a relative tolerance) broken by the canonical member of the class (:func:`select_best`,
:func:`canonical_genes`).
"""

from __future__ import annotations

__all__ = ["PAPER_BOX", "FULL_BOX", "objective_H", "objective_worst", "optimal_a3",
           "genes_to_layout", "lower_bound_H", "weights_bound_H", "bound_layout",
           "worst_case_bound", "equivalent_genes", "canonical_genes", "select_best",
           "grid_layout"]

import numpy as np

from .. import validate
from .separation import (
    _DEGENERATE,
    TWO_PI,
    _check_n,
    _raw_weights,
    _split_phi,
    full_weights,
    probe_angles,
)

#: The search box the paper recommends (Section 3, end) and within which every Table 1 layout lies:
#: phi_1 in [0, pi/4], phi_2 in [pi/4, 3 pi/2], phi_3 in [3 pi/2, 2 pi]; a_3 is our assumption.
PAPER_BOX = ((0.0, np.pi / 4), (np.pi / 4, 1.5 * np.pi), (1.5 * np.pi, TWO_PI), (0.1, 3.0))


#: The whole circle for every probe.
FULL_BOX = ((0.0, TWO_PI), (0.0, TWO_PI), (0.0, TWO_PI), (0.1, 3.0))


def _genes(x):
    x = np.asarray(x, dtype=float)
    if x.ndim == 0 or x.shape[-1] != 4:
        raise ValueError(f"genes must be (..., 4) = phi_1, phi_2, phi_3, a_3; got shape {x.shape}")
    return x


def genes_to_layout(x):
    """Genes ``(phi_1, phi_2, phi_3, a_3)`` to the four probes' angles and weights (Eq. 15).

    Parameters
    ----------
    x : array (..., 4)
        Genes ``(phi_1, phi_2, phi_3, a_3)``, angles in rad.

    Returns
    -------
    phi : array (..., 4)
        Angles (rad), phi_0 = 0.
    w : array (..., 4)
        Weights, a0 = 1, a1 and a2 from Eq. 15 (inf for a degenerate layout).
    """
    x = _genes(x)
    a1, a2 = _raw_weights(x[..., :3], x[..., 3])
    phi = np.concatenate([np.zeros(x.shape[:-1] + (1,)), x[..., :3]], axis=-1)
    w = np.stack([np.ones_like(a1), a1, a2, x[..., 3]], axis=-1)
    return phi, w


def objective_H(x, k) -> np.ndarray:
    """``H = q_k^2`` (Eq. 20) of genes ``x`` at harmonic ``k``; inf for a degenerate layout.

    Parameters
    ----------
    x : array (..., 4)
        Genes ``(phi_1, phi_2, phi_3, a_3)``, angles in rad.
    k : int or array
        Harmonic order(s) >= 2, broadcast against ``x[..., 0]``.

    Returns
    -------
    array (...)
        H (dimensionless, >= 1/4), inf where the layout is degenerate or cancels ``k``.
    """
    x = _genes(x)
    k = np.asarray(k, dtype=float)
    if np.any(k < 2) or np.any(k != np.round(k)):
        raise ValueError("the harmonic order k must be an integer >= 2 (k = 1 is cancelled by "
                         "design: lambda_1 = mu_1 = 0)")
    a1, a2 = _raw_weights(x[..., :3], x[..., 3])
    a3 = x[..., 3]
    f1, f2, f3 = x[..., 0], x[..., 1], x[..., 2]
    with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
        lam = 1 + a1 * np.cos(k * f1) + a2 * np.cos(k * f2) + a3 * np.cos(k * f3)
        mu = a1 * np.sin(k * f1) + a2 * np.sin(k * f2) + a3 * np.sin(k * f3)
        h = (1 + a1 ** 2 + a2 ** 2 + a3 ** 2) / (lam ** 2 + mu ** 2)
    return np.where(np.isfinite(h), h, np.inf)


def objective_worst(x, harmonics) -> np.ndarray:
    """Worst case ``max_k q_k^2`` over ``harmonics`` (beyond the paper: it protects one ``k``).

    Parameters
    ----------
    x : array (..., 4)
        Genes ``(phi_1, phi_2, phi_3, a_3)``, angles in rad.
    harmonics : sequence of int
        The orders protected (each >= 2).

    Returns
    -------
    array (...)
        The largest H over ``harmonics``.
    """
    x = _genes(x)
    ks = np.asarray(harmonics)
    if ks.ndim != 1 or ks.size == 0 or np.any(ks < 2):
        raise ValueError("harmonics must be a non-empty list of orders >= 2")
    h = objective_H(x[..., None, :], ks)
    return h.max(axis=-1)


def optimal_a3(phi, k, a3_bounds=(-np.inf, np.inf)):
    """The ``a_3`` minimising ``H`` for given angles, in closed form, and that ``H``.

    ``a1, a2`` are affine in ``a3``, so ``H(a3)`` is a ratio of two quadratics; its stationary
    points solve a quadratic, and the minimum over an interval is at one of them or an end.

    Parameters
    ----------
    phi : array (..., 3)
        Angles phi_1..phi_3 (rad).
    k : int or array
        Harmonic order, broadcast against ``phi[..., 0]``.
    a3_bounds : (float, float)
        The interval of ``a_3`` searched.

    Returns
    -------
    a3, H : arrays (...)
        The best ``a_3`` and its H (inf where the angles are degenerate).
    """
    phi3 = _split_phi(phi)
    lo, hi = a3_bounds
    if not lo < hi:
        raise ValueError(f"a3_bounds must be (low, high) with low < high, got {a3_bounds!r}")
    k = np.asarray(k, dtype=float)
    # a = u + a3 v (a0..a3) with u = (1, u1, u2, 0), v = (0, v1, v2, 1) from Eq. 15;
    # H = (a.a) / |c.a|^2 with c_l = exp(i k phi_l), written out in real arithmetic
    f1, f2, f3 = phi3[..., 0], phi3[..., 1], phi3[..., 2]
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        sd = np.sin(f2 - f1)
        sd = np.where(np.abs(sd) < _DEGENERATE, np.nan, sd)
        u1, u2 = -np.sin(f2) / sd, np.sin(f1) / sd
        v1, v2 = np.sin(f3 - f2) / sd, -np.sin(f3 - f1) / sd
        c1, c2, c3 = np.cos(k * f1), np.cos(k * f2), np.cos(k * f3)
        s1, s2, s3 = np.sin(k * f1), np.sin(k * f2), np.sin(k * f3)
        cur, cui = 1 + u1 * c1 + u2 * c2, u1 * s1 + u2 * s2
        cvr, cvi = v1 * c1 + v2 * c2 + c3, v1 * s1 + v2 * s2 + s3
        p0, p1, p2 = 1 + u1 ** 2 + u2 ** 2, 2 * (u1 * v1 + u2 * v2), v1 ** 2 + v2 ** 2 + 1
        q0, q1, q2 = cur ** 2 + cui ** 2, 2 * (cur * cvr + cui * cvi), cvr ** 2 + cvi ** 2
        qa, qb, qc = p2 * q1 - p1 * q2, 2 * (p2 * q0 - p0 * q2), p1 * q0 - p0 * q1
        disc = np.sqrt(np.maximum(qb ** 2 - 4 * qa * qc, 0))
        roots = np.stack([(-qb + disc) / (2 * qa), (-qb - disc) / (2 * qa), -qc / qb], axis=-1)
    cands = np.concatenate([roots, np.broadcast_to(np.array([lo, hi], dtype=float),
                                                   roots.shape[:-1] + (2,))], axis=-1)
    cands = np.where(np.isfinite(cands) & (cands >= lo) & (cands <= hi), cands, np.nan)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        a = cands
        h = (p0[..., None] + p1[..., None] * a + p2[..., None] * a ** 2) / (
            q0[..., None] + q1[..., None] * a + q2[..., None] * a ** 2)
    h = np.where(np.isfinite(h) & (h > 0), h, np.inf)
    best = np.argmin(h, axis=-1)
    a3 = np.take_along_axis(a, best[..., None], -1)[..., 0]
    hb = np.take_along_axis(h, best[..., None], -1)[..., 0]
    return a3, hb


def lower_bound_H(n_probes: int = 4) -> float:
    """``H >= 1/n`` for ``n`` probes at every harmonic.

    ``|Lambda_k| = |sum a_l e^{i k phi_l}| <= sum |a_l| <= sqrt(n sum a_l^2)`` (triangle and
    Cauchy-Schwarz inequalities), so ``q_k^2 >= 1/n``; equality needs ``|a_l|`` all equal and
    ``a_l e^{i k phi_l}`` all in phase.  With four probes and ``sum a_l e^{i phi_l} = 0`` this is
    possible exactly when ``k`` is even (:func:`bound_layout`).

    Parameters
    ----------
    n_probes : int
        Number of probes n (>= 3).

    Returns
    -------
    float
        1 / n.
    """
    return 1.0 / validate.integer(n_probes, "n_probes", low=3)


def weights_bound_H(w, half_units=None) -> np.ndarray:
    """Lower bound of ``H = q_k^2`` from the weights alone, for every probe angle and harmonic.

    ``w``: weights ``a1..a3`` (last axis 3, ``a0 = 1`` exact) or ``a0..a3`` (last axis 4),
    batched over leading axes.  ``half_units`` (same shape, optional): half-widths of the
    intervals ``[w - half_units, w + half_units]`` the weights are only known to lie in (e.g. half
    a unit of their last printed digit); the bound then holds for every weight in those intervals.

    Proof.  ``Lambda_k = sum_l a_l exp(i k phi_l)``, so by the triangle inequality
    ``|Lambda_k| <= sum_l |a_l|`` whatever the angles, and therefore::

        H = sum_l a_l^2 / |Lambda_k|^2 >= sum_l a_l^2 / (sum_l |a_l|)^2 =: B(a),

    for every ``phi_1, phi_2, phi_3`` and every ``k`` (equality exactly when all ``a_l e^{i k
    phi_l}`` share one phase, e.g. ``k phi_l = 0 mod 2 pi`` with positive weights, so ``B`` is the
    infimum over unconstrained angles).  If ``a_l`` is only known to lie in ``[c_l - h_l, c_l +
    h_l]``, then ``a_l^2 >= m_l^2`` with ``m_l = max(|c_l| - h_l, 0)`` (the distance from 0 to the
    interval) and ``|a_l| <= |c_l| + h_l``, so ``B(a) >= sum m_l^2 / (sum (|c_l| + h_l))^2`` for
    every ``a`` in the intervals.  ``B(a) >= 1/4`` (Cauchy-Schwarz, :func:`lower_bound_H`), with
    equality for equal ``|a_l|``; the interval version can fall slightly below 1/4.  The bound
    does not use Eq. 15: it holds whether or not the weights cancel the first harmonic, and it
    ignores the signs of the weights (a sign lost in print does not change it).

    Parameters
    ----------
    w : array (..., 3) or (..., 4)
        Weights a1..a3 (a0 = 1) or a0..a3.
    half_units : array, optional
        Half-widths of the intervals the weights are known to lie in.

    Returns
    -------
    array (...)
        The bound B (dimensionless).
    """
    w = np.asarray(w, dtype=float)
    if w.ndim == 0 or w.shape[-1] not in (3, 4):
        raise ValueError("weights must be a1..a3 (last axis 3, a0 = 1) or a0..a3 (last axis 4); "
                         f"got shape {w.shape}")
    h = np.zeros_like(w) if half_units is None else np.broadcast_to(
        np.asarray(half_units, dtype=float), w.shape)
    if not (np.all(np.isfinite(w)) and np.all(np.isfinite(h))) or np.any(h < 0):
        raise ValueError("weights must be finite and half_units finite and >= 0")
    if w.shape[-1] == 3:
        w = np.concatenate([np.ones(w.shape[:-1] + (1,)), w], axis=-1)
        h = np.concatenate([np.zeros(h.shape[:-1] + (1,)), h], axis=-1)
    low = np.maximum(np.abs(w) - h, 0.0)
    high = np.abs(w) + h
    if np.any(high.sum(axis=-1) == 0):
        raise ValueError("all weights are zero: H is undefined")
    return (low ** 2).sum(axis=-1) / high.sum(axis=-1) ** 2


def bound_layout(k: int, m: int = 1) -> np.ndarray:
    """Genes of a layout reaching ``H = 1/4`` at even ``k``: two diametral pairs of probes.

    ``phi = (0, 2 pi m / k, pi, pi + 2 pi m / k)``, ``a = (1, 1, 1, 1)`` (for k = 2:
    ``(0, pi/2, pi, 3 pi/2)``, ``a = (1, -1, 1, -1)``).  It also cancels every odd harmonic:
    ``Lambda_j = (1 + e^{i j pi})(1 + e^{i j phi_1})``.

    Parameters
    ----------
    k : int
        An even harmonic order (>= 2).
    m : int
        Which of the layouts: the second pair turned by ``2 pi m / k``, ``0 < 2 m < k``
        (ignored for k = 2).

    Returns
    -------
    array (4,)
        Genes ``(phi_1, phi_2, phi_3, a_3)``.
    """
    k = validate.integer(k, "k", low=2)
    if k % 2:
        raise ValueError(f"H = 1/4 is reachable only at even k >= 2 (got {k!r}); for odd k the "
                         "infimum is larger, see reference_optimum")
    if k == 2:   # phi_1 = 2 pi m / k would fall on probe 2; use a1 = a3 = -1 at pi/2, 3pi/2
        return np.array([np.pi / 2, np.pi, 1.5 * np.pi, -1.0])
    m = validate.integer(m, "m", low=1, high=(k - 1) // 2)      # 0 < 2 m < k
    f1 = TWO_PI * m / k
    return np.array([f1, np.pi, np.pi + f1, 1.0])


def worst_case_bound(n_samples: int) -> float:
    """Lower bound of ``max_{k=2..N-2} q_k^2`` for probes on the sampling grid: ``(N - 3) / N``.

    Parseval: ``sum_{k=0}^{N-1} |Lambda_k|^2 = N sum a_l^2`` for distinct positions; with
    ``Lambda_1 = Lambda_{N-1} = 0`` the smallest of the other ``N - 3`` terms is at most
    ``N sum a_l^2 / (N - 3)``.

    Parameters
    ----------
    n_samples : int
        Samples per revolution N (>= 8).

    Returns
    -------
    float
        ``(N - 3) / N``.
    """
    n = _check_n(n_samples)
    return (n - 3) / n


def _box(bounds):
    b = np.asarray(bounds, dtype=float)
    if b.shape != (4, 2) or not np.all(np.isfinite(b)) or np.any(b[:, 0] >= b[:, 1]):
        raise ValueError("bounds must be four (low, high) pairs with low < high for "
                         f"phi_1, phi_2, phi_3, a_3; got {bounds!r}")
    return b[:, 0], b[:, 1]


def equivalent_genes(x) -> np.ndarray:
    """Every gene vector describing the same physical layout as ``x``: ``(..., 48, 4)``.

    ``H`` (Eq. 20), at every harmonic, and the worst case over harmonics are unchanged when
    (a) another probe is taken as the reference (all angles turned by ``-phi_j``; the weights
    divided by ``a_j``, so ``a_0`` stays 1: ``|Lambda_k|`` is turned, and ``H`` is a ratio
    invariant under scaling the weights), (b) the three other probes are relabelled (six
    orders; ``a_3`` is the weight of whichever comes last), and (c) the layout is mirrored
    (``phi -> -phi``: ``Lambda_k -> conj(Lambda_k)``, Eq. 15's weights unchanged).  That is
    4 x 6 x 2 = 48 gene vectors per layout, computed here (angles in ``[0, 2 pi)``; NaN rows
    where a relabelling is degenerate, ``a_j = 0`` or ``sin(phi_2 - phi_1) = 0``).  Member 0 is
    ``x`` itself (angles taken modulo ``2 pi``).

    Parameters
    ----------
    x : array (..., 4)
        Genes ``(phi_1, phi_2, phi_3, a_3)``.

    Returns
    -------
    array (..., 48, 4)
        The members; NaN rows where a relabelling is degenerate.
    """
    x = _genes(x)
    phi, w = genes_to_layout(x)                                 # (..., 4) each
    out = []
    perms = ((0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0))
    for mirror in (1.0, -1.0):
        for j in range(4):
            others = [i for i in range(4) if i != j]
            with np.errstate(divide="ignore", invalid="ignore"):
                scale = 1.0 / w[..., j]
            for perm in perms:
                idx = [others[i] for i in perm]
                ang = np.mod(mirror * (phi[..., idx] - phi[..., j:j + 1]), TWO_PI)
                ang = np.where(ang >= TWO_PI, ang - TWO_PI, ang)
                a3 = w[..., idx[2]] * scale
                g = np.concatenate([ang, a3[..., None]], axis=-1)
                bad = (~np.isfinite(a3)) | (np.abs(np.sin(ang[..., 1] - ang[..., 0]))
                                            < _DEGENERATE) | (np.abs(w[..., j]) < _DEGENERATE)
                out.append(np.where(bad[..., None], np.nan, g))
    return np.stack(out, axis=-2)


def _lexicographic_first(keys, valid):
    """Index (over axis -2) of the lexicographically smallest row of ``keys`` (..., M, 4)
    among ``valid``; keys are compared rounded to 1e-9 so that two rows equal up to round-off
    are a tie decided by the next key (and finally by the lower index)."""
    q = np.where(valid[..., None], np.round(keys, 9), np.inf)
    order = np.broadcast_to(np.arange(q.shape[-2]), q.shape[:-1]).copy()
    for c in range(q.shape[-1] - 1, -1, -1):
        v = np.take_along_axis(q[..., c], order, axis=-1)
        order = np.take_along_axis(order, np.argsort(v, axis=-1, kind="stable"), axis=-1)
    return order[..., 0]


def canonical_genes(x, bounds=None) -> np.ndarray:
    """The canonical member of the symmetry class of ``x`` (:func:`equivalent_genes`).

    The lexicographically smallest ``(phi_1, phi_2, phi_3, a_3)`` among the members inside
    ``bounds`` (``x`` itself counts as inside; angles within 1e-12 of a bound are put on it, and
    an angle 0 counts as 2 pi where only that is inside).  ``bounds=None``: all members.

    Parameters
    ----------
    x : array (..., 4)
        Genes ``(phi_1, phi_2, phi_3, a_3)``, angles in rad.
    bounds : sequence of 4 (low, high), optional
        The box the canonical member must lie in.

    Returns
    -------
    array (..., 4)
        The canonical genes.
    """
    x = _genes(x)
    members = equivalent_genes(x)
    members = np.concatenate([x[..., None, :], members], axis=-2)
    valid = np.all(np.isfinite(members), axis=-1)
    if bounds is not None:
        lo, hi = _box(bounds)
        wrap = np.r_[TWO_PI, TWO_PI, TWO_PI, 0.0]
        alt = members + wrap
        members = np.where((members < lo - 1e-12) & (alt <= hi + 1e-12), alt, members)
        inside = np.all((members >= lo - 1e-12) & (members <= hi + 1e-12), axis=-1)
        members = np.clip(members, lo, hi)
        valid &= inside
        valid[..., 0] = True
    first = _lexicographic_first(members, valid)
    return np.take_along_axis(members, first[..., None, None], axis=-2)[..., 0, :]


def select_best(h, x, *, bounds=None, rel_tol: float = 1e-9):
    """The best of several candidate layouts, with canonical tie-breaking.

    ``h`` (..., M) objective values (smaller is better), ``x`` (..., M, 4) their genes.  The
    candidates whose ``H`` is within ``rel_tol`` of the smallest are ties (two optimisers, or
    two round-off orders, that found the same optimum or symmetric copies of it); among them
    the one whose canonical genes (:func:`canonical_genes` in ``bounds``) are lexicographically
    smallest wins.  Returns ``(index, canonical genes)`` of shapes (...) and (..., 4).

    Parameters
    ----------
    h : array (..., M)
        Objective values of M candidates (smaller is better).
    x : array (..., M, 4)
        Their genes.
    bounds : sequence of 4 (low, high), optional
        Box of the canonical genes.
    rel_tol : float
        Relative tie window.

    Returns
    -------
    index : array of int (...)
        The winner among the M candidates.
    genes : array (..., 4)
        Canonical genes of the winner.
    """
    h = np.asarray(h, dtype=float)
    x = _genes(x)
    if h.shape != x.shape[:-1] or h.shape[-1] < 1:
        raise ValueError(f"h {h.shape} and x {x.shape} must be (..., M) and (..., M, 4)")
    if not rel_tol >= 0:
        raise ValueError(f"rel_tol must be >= 0, got {rel_tol!r}")
    hmin = np.min(h, axis=-1, keepdims=True)
    tied = h <= hmin + rel_tol * np.abs(hmin)
    canon = canonical_genes(x, bounds)
    first = _lexicographic_first(canon, tied)
    return first, np.take_along_axis(canon, first[..., None, None], axis=-2)[..., 0, :]


def grid_layout(x, n_samples: int):
    """The layout of genes ``x`` on a sampling grid of ``n_samples`` per revolution.

    The matrix method shifts by whole samples: the probe positions ``p`` (4,) with ``p_0 = 0``
    and each angle rounded to the nearest sample, their angles ``2 pi p / N`` and the weights
    ``a_0..a_3`` of Eq. 15 for those angles and ``a_3``.

    Parameters
    ----------
    x : array (4,)
        Genes ``(phi_1, phi_2, phi_3, a_3)``, angles in rad.
    n_samples : int
        Samples per revolution N (>= 8).

    Returns
    -------
    positions : array of int (4,)
        Probe positions p (sample indices), p_0 = 0.
    phi : array (4,)
        Their angles ``2 pi p / N`` (rad).
    w : array (4,)
        Weights a0..a3.
    """
    x = _genes(x)
    if x.ndim != 1:
        raise ValueError(f"grid_layout takes one gene vector (4,), got shape {x.shape}")
    n = _check_n(n_samples)
    p = np.r_[0, np.round(np.asarray(x[:3]) * n / TWO_PI).astype(int) % n]
    phi = probe_angles(p, n)
    return p, phi, full_weights(phi, x[3])
