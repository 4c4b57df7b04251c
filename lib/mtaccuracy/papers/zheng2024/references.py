"""The Fig. 4 test points and the indices at a test point: closed-form, sampled Sobol', PCE.

The workspace diagonals' test points (:func:`diagonal_test_points`); the closed-form linear
indices laid out as Table 2 (:func:`table_indices`) and Table 2's normalisation
(:func:`normalise`); the sampled MCS and LHS references (:func:`sobol_reference`); the sparse PCE
fits (:func:`pce_indices`) and how sparse they came out (:func:`pce_fit_quality`).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ... import sensitivity as S
from ...machines.ac_double_turntable import TRAVELS
from ...validate import integer

__all__ = ["diagonal_test_points", "table_indices", "normalise", "sobol_reference",
           "pce_indices", "pce_fit_quality"]


# --------------------------------------------------------------------------------------
# The test points of Fig. 4
# --------------------------------------------------------------------------------------

def diagonal_test_points(n_per_diagonal: int = 5, rotary: str = "sweep") -> dict[str, np.ndarray]:
    """Test points equally spaced on the four body diagonals of the X-Y-Z workspace (Fig. 4).

    Each diagonal runs from one corner of the travel box (``ac_double_turntable.TRAVELS``) to
    the opposite one; ``n_per_diagonal`` points split it into equal parts, ends included, so
    every diagonal passes through the centre.  The rotary axes are not given by Fig. 4:
    ``rotary="sweep"`` moves A and C with the same fraction of their travel as the linear
    axes, ``rotary="zero"`` keeps A = C = 0.

    Parameters
    ----------
    n_per_diagonal : int
        Points per diagonal, ends included (at least 2; the paper's Fig. 4 shows 5).
    rotary : {"sweep", "zero"}
        The rule for A and C, which Fig. 4 does not give.

    Returns
    -------
    dict of str to array (4 n_per_diagonal,)
        x, y, z (mm), A, C (rad), ``diagonal`` (0-3) and ``fraction`` (0..1 along it).
    """
    n_per_diagonal = integer(n_per_diagonal, "n_per_diagonal", low=2)
    if rotary not in ("sweep", "zero"):
        raise ValueError(f"unknown rotary rule {rotary!r}; allowed: sweep, zero")
    f = np.linspace(0.0, 1.0, n_per_diagonal)
    signs = [(1, 1, 1), (-1, 1, 1), (1, -1, 1), (1, 1, -1)]
    out = {k: [] for k in ("x", "y", "z", "A", "C", "diagonal", "fraction")}
    for k, s in enumerate(signs):
        for fr in f:
            for ax, sg in zip("xyz", s, strict=True):
                lo, hi = TRAVELS[ax]
                u = fr if sg > 0 else 1.0 - fr
                out[ax].append(lo + u * (hi - lo))
            for ax in "AC":
                lo, hi = TRAVELS[ax]
                out[ax].append(lo + fr * (hi - lo) if rotary == "sweep" else 0.0)
            out["diagonal"].append(k)
            out["fraction"].append(fr)
    return {k: np.asarray(v) for k, v in out.items()}


def table_indices(jacobian, *, sd) -> np.ndarray:
    """Closed-form indices as the paper's Table 2 lays them out: components by errors.

    The library's index arrays are input by output, ``(..., d, q)``
    (:func:`mtaccuracy.sensitivity.linear_indices`); the paper's tables, this notebook's
    ``rows, cols`` and its figures read a component's row of 41 errors.

    Parameters
    ----------
    jacobian : array (..., 6, 41)
        ``machine.jacobian(pose)``.
    sd : array (41,)
        Standard deviations of the errors (mm, rad).

    Returns
    -------
    array (..., 6, 41)
    """
    return np.swapaxes(S.linear_indices(jacobian, sd=sd), -1, -2)


def normalise(st):
    """Table 2's normalised total indices: ``st`` clipped at 0, over their sum.

    Parameters
    ----------
    st : array (..., d)
        Total indices of the d errors (a sampled estimate may be slightly negative).

    Returns
    -------
    array (..., d)
        Non-negative, summing to 1 over the last axis.
    """
    st = np.clip(st, 0, None)
    return st / st.sum(axis=-1, keepdims=True)


def sobol_reference(machine, pose, sd, method: str, n: int, rng_seed: int, progress=False):
    """Sampled Sobol' indices (s1, st) of the six pose-error components at ``pose``.

    Errors normal with standard deviations ``sd``: ``method`` "mc" or "lhs" designs of ``n``
    base rows, streamed (``sensitivity.sobol_indices`` on a ``SobolDesign``: base rows drawn
    block by block, the AB runs reduced to per-error sums as they come, never stored).

    Parameters
    ----------
    machine : ACDoubleTurntable
        The machine (its ``pose_error``).
    pose : mapping
        x, y, z (mm), A, C (rad).
    sd : array (41,)
        Error standard deviations (mm, rad).
    method : {"mc", "lhs"}
        Independent uniforms, or two Latin hypercubes.
    n : int
        Base sample size N (43 N model runs).
    rng_seed : int
        Seed of the design.
    progress : bool
        Print a line per quarter of the runs.

    Returns
    -------
    s1, st : array (41, 6)
        First-order and total indices, errors by components.
    """
    design = S.SobolDesign(n, S.Inputs.normal(0.0, sd), method=method, seed=rng_seed)
    marks = set()

    def report(done, total):
        q = int(4 * done / total)
        if progress and q not in marks:
            marks.add(q)
            print(f"  {method.upper()}: {done:,} / {total:,} model runs", flush=True)

    # an LHS design is held whole: see sensitivity.SobolDesign
    return S.sobol_indices(lambda x: machine.pose_error(x, pose), design, chunk=250_000,
                           progress=report)


def pce_indices(machine, pose, sd, n: int, degree: int, rng_seed: int, q_norm: float = 1.0,
                comps=tuple(range(6))) -> dict:
    """Sparse PCE fits of the pose-error components ``comps`` at ``pose``.

    ``sensitivity.fit_pce_outputs`` on a Latin hypercube of ``n`` standard normals (errors =
    xi * sd).

    Parameters
    ----------
    machine : ACDoubleTurntable
        The machine (its ``pose_error``).
    pose : mapping
        x, y, z (mm), A, C (rad).
    sd : array (41,)
        Error standard deviations (mm, rad).
    n : int
        Design size.
    degree : int
        Total degree of the Hermite basis.
    rng_seed : int
        Seed of the Latin hypercube.
    q_norm : float
        Hyperbolic truncation of the basis (1: the full total-degree basis).
    comps : sequence of int
        The components fitted (0-5: Px, Py, Pz, Vx, Vy, Vz).

    Returns
    -------
    dict of int to PCE fit
        ``{component: fit}``.
    """
    u = S.base_samples(n, 41, method="lhs", seed=rng_seed)[0]
    xi = S.Inputs.normal(0.0, np.ones(41)).from_unit(u)
    y = machine.pose_error(xi * sd, pose)
    fits = S.fit_pce_outputs(xi, y[:, list(comps)], degree=degree, q_norm=q_norm)
    return dict(zip(comps, fits, strict=True))


def pce_fit_quality(fits, comps) -> pd.DataFrame:
    """How sparse each component's PCE came out: terms kept of the basis, and its corrected LOO.

    Parameters
    ----------
    fits : mapping of int to PCE fit
        ``{component index: fit}`` (:func:`pce_indices`); a fit has ``coef``, ``n_candidates``
        and ``loo``.
    comps : sequence of str
        Names of the components, in the order of ``range(len(comps))``.

    Returns
    -------
    pandas.DataFrame
        One row per component: ``component``, ``terms_kept`` (terms the OMP path chose),
        ``basis_size`` (terms of the full basis) and ``corrected_LOO`` (relative error).
    """
    k = range(len(comps))
    return pd.DataFrame({"component": list(comps), "terms_kept": [len(fits[i].coef) for i in k],
                         "basis_size": [fits[i].n_candidates for i in k],
                         "corrected_LOO": [fits[i].loo for i in k]})
