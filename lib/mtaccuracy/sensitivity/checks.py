"""The closed-form (linear) indices over a workspace, and checked against sampling.

Two uses of :mod:`.linear` that every study of a machine repeats:

* an **atlas**: the closed-form indices at many poses, summarised per error and output (the share
  of the poses where the error is *key*, its mean and largest index) and the *dominant* error at
  each pose (:func:`atlas_table`, :func:`dominant_errors`);
* a **check against sampling**: at a pose, Saltelli estimates of the exact model with their
  bootstrap half-widths beside the closed form and the nonlinear remainder
  (:func:`sample_at_pose`), and the comparison of all of them at once, with the half-widths widened
  to a family-wise level by Bonferroni (:func:`compare_with_sampling`).
"""

from __future__ import annotations

__all__ = ["atlas_table", "dominant_errors", "first_order_outputs", "SampledIndices",
           "sample_at_pose", "compare_with_sampling"]

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy import stats

from mtaccuracy import validate

from .bootstrap import sobol_bootstrap
from .inputs import Inputs
from .linear import indices_at_poses, nonlinear_remainder, uniform_moments
from .sobol import base_samples, sobol_estimate, sobol_evaluate
from .tie_rule import merge_ties

#: an output whose first-order variance is below this share of the largest one has no
#: first-order term (e.g. the change of a unit vector along itself): no closed form there
FIRST_ORDER_FLOOR = 1e-12


def first_order_outputs(jacobian: np.ndarray, var: np.ndarray) -> np.ndarray:
    """(..., q) True where the output has a first-order term (a closed form exists there).

    An output has one when its linear variance ``sum_i J_ki^2 var_i`` is above
    :data:`FIRST_ORDER_FLOOR` of the largest among the outputs of its kind at that pose
    (outputs in triples of one unit, positions then orientations, when q is a multiple of 3;
    else all together).

    Parameters
    ----------
    jacobian : array (..., q, d)
        First-order Jacobians of the q outputs in the d errors, at each pose.
    var : array (d,)
        Error variances (mm^2, rad^2).

    Returns
    -------
    array of bool (..., q)
        True where the output has a first-order term.
    """
    v = (np.asarray(jacobian) ** 2 * var).sum(-1)                    # (..., q)
    q = v.shape[-1]
    g = v.reshape(v.shape[:-1] + ((q // 3, 3) if q % 3 == 0 else (1, q)))
    return (g > FIRST_ORDER_FLOOR * g.max(axis=-1, keepdims=True)).reshape(v.shape)


def atlas_table(indices: np.ndarray, *, names: Sequence[str], outputs: Sequence[str],
                key_share: float) -> pd.DataFrame:
    """Per error and output over P poses: the share of poses where it is key, mean and max index.

    Parameters
    ----------
    indices : array (P, d, q)
        Closed-form indices at P poses, as :func:`~mtaccuracy.sensitivity.indices_at_poses`
        returns.
    names : sequence of str (d,)
        Error names, in the order of axis 1.
    outputs : sequence of str (q,)
        Output names, in the order of axis 2.
    key_share : float
        The index from which an error counts as key at a pose, in (0, 1).

    Returns
    -------
    DataFrame (q d, 5)
        Columns ``symbol, output, key_share`` (the share of the poses where the error is key),
        ``mean_index, max_index``; outputs outermost.
    """
    idx = np.asarray(indices, dtype=float)
    if idx.ndim != 3 or idx.shape[1:] != (len(names), len(outputs)):
        raise ValueError(f"indices must be (P, {len(names)}, {len(outputs)}), got {idx.shape}")
    if not 0 < key_share < 1:  # an open interval: validate.probability allows 0 and 1
        raise ValueError(f"key_share must be in (0, 1), got {key_share!r}")
    key = (idx >= key_share).mean(0)
    return pd.DataFrame([dict(symbol=s, output=o, key_share=key[i, k],
                              mean_index=idx[:, i, k].mean(), max_index=idx[:, i, k].max())
                         for k, o in enumerate(outputs) for i, s in enumerate(names)])


def dominant_errors(jacobian: np.ndarray, var) -> np.ndarray:
    """(P, q) the error with the largest closed-form index at each pose and output.

    Errors whose indices tie within :func:`~mtaccuracy.sensitivity.merge_ties`' tolerance
    (errors that enter identically) go to the first in the catalogue, so the answer does not
    depend on rounding.

    Parameters
    ----------
    jacobian : array (P, q, d)
        First-order Jacobians at P poses.
    var : array (d,)
        Error variances (mm^2, rad^2).

    Returns
    -------
    array of int (P, q)
        The error's column, -1 where the output has no first-order term.
    """
    jac = np.asarray(jacobian, dtype=float)
    var = np.asarray(var, dtype=float)
    idx = indices_at_poses(jac, var=var)                                  # (P, d, q)
    p, d, q = idx.shape
    merged = merge_ties(idx.transpose(1, 0, 2).reshape(d, -1)).reshape(d, p, q)
    dom = np.argmax(merged, axis=0)
    dom[~first_order_outputs(jac, var)] = -1
    return dom


@dataclass
class SampledIndices:
    """Total indices of the exact model at one pose, sampled, beside the closed form.

    Attributes
    ----------
    st : array (d, q)
        Saltelli/Jansen estimate of the total indices.
    half_width : array (d, q)
        95 % bootstrap half-width.
    closed_form : array (d, q)
        Linear (closed-form) indices.
    centred_remainder : array (q,)
        Std of the nonlinear remainder over the std of the output.
    first_order : array of bool (q,)
        The output has a first-order term.
    """

    st: np.ndarray                # (d, q) Saltelli/Jansen estimate
    half_width: np.ndarray        # (d, q) 95 % bootstrap half-width
    closed_form: np.ndarray       # (d, q) linear indices
    centred_remainder: np.ndarray  # (q,) std of the nonlinear remainder / std of the output
    first_order: np.ndarray       # (q,) the output has a first-order term


def sample_at_pose(model: Callable[[np.ndarray], np.ndarray], jacobian: np.ndarray, *, bounds,
                   n: int, n_boot: int, seed) -> SampledIndices:
    """Sampled total indices of the exact model at one pose, beside the closed form.

    Saltelli/Jansen estimates with independent uniform errors (an "mc" design), their
    bootstrap half-widths, the closed form from ``jacobian`` and the nonlinear remainder on the
    A design.

    Parameters
    ----------
    model : callable
        ``(m, d) -> (m, q)``, the exact model at the pose; must not modify its input.
    jacobian : array (q, d)
        Its first-order Jacobian there.
    bounds : array (2, d)
        Lower and upper bounds of the uniform errors (mm, rad).
    n : int
        Base rows N of the design (the model sees N (d + 2) rows).
    n_boot : int
        Bootstrap resamples of the half-widths.
    seed : int
        Seed of the design; the bootstrap uses ``seed + 10``.

    Returns
    -------
    SampledIndices
        The estimates, half-widths, closed form, remainder and first-order flags.
    """
    n = validate.integer(n, "n", low=2)
    n_boot = validate.integer(n_boot, "n_boot", low=1)
    bounds = np.asarray(bounds, dtype=float)
    a, b = base_samples(n, Inputs.from_bounds(bounds), method="mc", seed=seed)
    ya, yb, yab = sobol_evaluate(model, a, b)
    _, st = sobol_estimate(ya, yb, yab)
    _, half = sobol_bootstrap(ya, yb, yab, n_boot=n_boot, seed=seed + 10)
    _, var = uniform_moments(bounds)
    jac = np.asarray(jacobian, dtype=float)
    rem = nonlinear_remainder(model, jac, a)
    return SampledIndices(st, half, indices_at_poses(jac[None], var=var)[0], rem.centred_ratio,
                          first_order_outputs(jac, var))


def compare_with_sampling(checks: Sequence[SampledIndices], *, names: Sequence[str],
                          outputs: Sequence[str], level: float = 0.95
                          ) -> tuple[pd.DataFrame, pd.DataFrame, float, int]:
    """Compare every sampled total index with the closed form, all at once.

    Parameters
    ----------
    checks : sequence of :class:`SampledIndices`
        One per pose (:func:`sample_at_pose`).
    names : sequence of str (d,)
        Error names, the ``symbol`` column of the tables.
    outputs : sequence of str (q,)
        Output names, the ``output`` column.
    level : float
        The family-wise confidence level, in (0, 1), of all compared indices at once.

    Returns
    -------
    rows : DataFrame
        Per pose, output and input: the sampled index, its half-width, the closed form and the
        difference.
    summary : DataFrame
        Per pose and output: the largest difference and half-width, the centred remainder, the
        largest ratio of difference to allowance, and the sum of the sampled indices (1 for a
        linear model; its spread is the sampling error of the variance, common to all indices
        of the output).
    widen : float
        The factor on the 95 % half-widths.
    m : int
        The number of indices compared.

    Notes
    -----
    A difference is allowed its 95 % bootstrap half-width widened to a family-wise ``level``
    over the m compared indices (Bonferroni: ``z(1 - (1 - level) / 2 / m) / z(0.975)``), plus
    twice the centred remainder of its output, the first-order bound on what the linear model
    misses.  Outputs without a first-order term at a pose are not compared.
    """
    if not 0 < level < 1:  # an open interval: validate.probability allows 0 and 1
        raise ValueError(f"level must be in (0, 1), got {level!r}")
    m = len(names) * sum(int(c.first_order.sum()) for c in checks)
    widen = stats.norm.ppf(1 - (1 - level) / 2 / max(m, 1)) / stats.norm.ppf(0.975)
    rows, summary = [], []
    for p_i, c in enumerate(checks):
        diff = c.st - c.closed_form
        allow = widen * c.half_width + 2 * c.centred_remainder[None, :]
        for k, o in enumerate(outputs):
            for i, s in enumerate(names):
                rows.append(dict(pose=p_i, output=o, symbol=s, st_sampled=c.st[i, k],
                                 half_width=c.half_width[i, k], st_closed_form=c.closed_form[i, k],
                                 difference=diff[i, k]))
            first = bool(c.first_order[k])
            ratio = np.abs(diff[:, k]) / np.maximum(allow[:, k], 1e-300)
            summary.append(dict(pose=p_i, output=o, first_order=first,
                                max_abs_difference=np.abs(diff[:, k]).max(),
                                max_half_width=c.half_width[:, k].max(),
                                centred_remainder=c.centred_remainder[k] if first else np.nan,
                                largest_ratio_to_allowed=ratio.max() if first else np.nan,
                                sum_st_sampled=c.st[:, k].sum()))
    return pd.DataFrame(rows), pd.DataFrame(summary), widen, m
