"""Notebook 01's measurement question: which standard tests see Zheng et al. 2024's key errors.

The status table and its figure are :mod:`mtaccuracy.papers.visibility`'s (re-exported here
for the notebook); this module adds what is particular to the AC double turntable's answer:
:func:`workpiece_motion_residual`, which shows why the key errors every test is blind to are
blind (each moves the workpiece rigidly), and the figure's caption :data:`MEASURE`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd

from ..figure import Caption
from ..visibility import (
    STATUSES,
    STRUCTURAL_GAIN,
    per_error_summary,
    status_matrix_figure,
    structural_prior_sd,
    visibility_table,
)

__all__ = ["STATUSES", "STRUCTURAL_GAIN", "structural_prior_sd", "visibility_table",
           "per_error_summary", "workpiece_motion_residual", "status_matrix_figure",
           "MEASURE"]

MEASURE = Caption(
    "beyond_key_errors_by_test", "Beyond the paper",
    "Which standard test sees each of the paper's key errors (Table 2), with the paper's 41 "
    "constant errors (degree 0) and their priors from the ranges of Section 1 (sd {sd_text}), "
    "each reading's noise {sigma:g} µm, tool length {tool:g} mm: seen (the data shrink its prior "
    "variance {shrink:g} times), seen only in combination with other errors (named in "
    "key_errors_by_test.csv), or blind. Columns: the {n_tests} tests of the standard plan "
    "(ISO 230-2 lasers, ISO 230-1 straightness and angular tests, ISO 230-4 circles, rotary "
    "ballbar and R-tests on A and C), then the plan together (rank {rank} of 41).")


def workpiece_motion_residual(machine, *, symbols: Sequence[str],
                              pose: Mapping) -> pd.DataFrame:
    """How far each error's effect on the tool tip is from a rigid motion of the workpiece.

    An error whose first-order effect at every pose is ``dp = t + w x p`` (``p`` the nominal
    tool tip in the workpiece frame, ``t`` and ``w`` the same at every pose) moves the
    workpiece rigidly: any artefact fixed to the workpiece moves with it, so no test of the
    tool against the workpiece side sees it (it is the workpiece's set-up, a datum).  Least
    squares for ``(t, w)`` over the poses (numpy), the residual relative to the effect.

    Parameters
    ----------
    machine : ChainMachine
        The machine (:meth:`~mtaccuracy.machines.chain.ChainMachine.jacobian`, closed form).
    symbols : sequence of str
        The errors to check.
    pose : mapping of str to (P,) array_like
        At least three poses not on one line (mm, rad), with the tool offsets.

    Returns
    -------
    pandas.DataFrame
        Indexed by symbol: ``effect`` (``max |dp|`` over the poses and components, mm per mm
        or per rad; 0 when the error never moves the tool tip) and ``residual`` (``max
        |residual| / max |dp|``: 0 for a rigid motion, to rounding; about 1 for an effect
        nothing rigid explains; 0 when there is no effect).
    """
    cols = [machine.error_names.index(s) if s in machine.error_names else -1 for s in symbols]
    if -1 in cols:
        raise ValueError(f"workpiece_motion_residual: unknown errors "
                         f"{[s for s, c in zip(symbols, cols, strict=True) if c < 0]}")
    J = machine.jacobian(pose)[:, :3, :][:, :, cols]                     # (P, 3, k) mm/unit
    n = J.shape[0]
    _, tip = machine.relative(np.zeros((n, machine.n_errors)), pose, with_errors=False)
    skew = np.zeros((n, 3, 3))                                            # w x p = -[p]x w
    skew[:, 0, 1], skew[:, 0, 2], skew[:, 1, 2] = tip[:, 2], -tip[:, 1], tip[:, 0]
    skew[:, 1, 0], skew[:, 2, 0], skew[:, 2, 1] = -tip[:, 2], tip[:, 1], -tip[:, 0]
    M = np.concatenate([np.tile(np.eye(3), (n, 1, 1)), skew], axis=2).reshape(3 * n, 6)
    y = J.reshape(3 * n, len(cols))
    res = y - M @ np.linalg.lstsq(M, y, rcond=None)[0]
    scale = np.abs(y).max(axis=0)
    return pd.DataFrame({"effect": scale,
                         "residual": np.abs(res).max(axis=0) / np.where(scale > 0, scale, 1.0)},
                        index=pd.Index(list(symbols), name="symbol"))
