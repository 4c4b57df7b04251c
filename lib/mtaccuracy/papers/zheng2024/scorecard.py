"""The scorecard's helpers: tables tidied, numbers printed, Fig. 7's convergence as text.

Tables rounded before they are saved (:func:`tidy`) and numbers as the notebook prints them
(:func:`fmt`); where a sampled method converged under either reading of Eq. 24
(:func:`converged_at`) and the texts that state it (:data:`READINGS`, :func:`both_sizes`,
:func:`convergence_text`, :func:`fluctuation_text`).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

__all__ = ["tidy", "fmt", "converged_at", "READINGS", "both_sizes", "convergence_text",
           "fluctuation_text"]


def tidy(df: pd.DataFrame) -> pd.DataFrame:
    """Floats rounded to 6 decimals, and a rounded -0 written as 0 (its sign is rounding noise).

    Parameters
    ----------
    df : pandas.DataFrame
        A table about to be saved.

    Returns
    -------
    pandas.DataFrame
        The same table, its float columns rounded; other columns unchanged.
    """
    return df.apply(lambda s: s.round(6) + 0.0 if s.dtype.kind == "f" else s)


def fmt(v: float) -> str:
    """One decimal for values above 0.1 in magnitude, four below (poses, misfits).

    Parameters
    ----------
    v : float
        The value printed.

    Returns
    -------
    str
        ``"102.5"``, ``"0.0046"``.
    """
    return f"{v:.1f}" if abs(v) > 0.1 else f"{v:.4f}"


def converged_at(g, r_max: float = 3.0, assign: str = "larger"):
    """The first sample size from which the fluctuation R (Eq. 24) stays small; NaN if never.

    R is ``g.R_percent``, the change from the previous size (so NaN at the first); "small" is
    at or below ``r_max`` percent; ``g.n`` ascending.

    Eq. 24, R = |S_(l+1) - S_l| / S_l, does not say to which of the two sizes R belongs:
    ``assign="larger"`` gives it to size l+1 (the reading under which the largest size of a
    series can be the one that converges, as the paper says of MCS and LHS at 1e5),
    ``assign="smaller"`` to size l (Eq. 24 literally; the largest size then has no R).

    Parameters
    ----------
    g : pandas.DataFrame
        One series: ``n`` (ascending) and ``R_percent``.
    r_max : float
        The criterion (percent).
    assign : {"larger", "smaller"}
        The size R belongs to.

    Returns
    -------
    int or float
        The sample size, or NaN if R does not stay small within the sizes run.
    """
    if assign not in ("larger", "smaller"):
        raise ValueError(f"assign must be 'larger' or 'smaller', got {assign!r}")
    r = g.R_percent.to_numpy(dtype=float)[1:]
    n = g.n.to_numpy()
    n = n[:-1] if assign == "smaller" else n[1:]   # "smaller": R of step l -> l+1 is size l's
    fails = np.flatnonzero(~(r <= r_max))
    first = fails[-1] + 1 if fails.size else 0     # from here on R stays small
    return int(n[first]) if first < len(n) else np.nan


#: The two readings of a sample size in Fig. 7: base samples N, or model runs 43 N.
READINGS = ("base samples", "model runs")


def both_sizes(larger, smaller) -> str:
    """A Fig. 7 result under both readings of Eq. 24: R given to the larger or the smaller size.

    Parameters
    ----------
    larger, smaller : str
        The result with R given to the larger of the two sizes, and to the smaller.

    Returns
    -------
    str
        ``"<larger> (R at the larger size), <smaller> (at the smaller)"``.
    """
    return f"{larger} (R at the larger size), {smaller} (at the smaller)"


def convergence_text(conv_txt: pd.DataFrame, *, method: str, symbol: str,
                     readings=READINGS) -> str:
    """Where a sampled method converged in Fig. 7, under each reading of the sample size.

    Parameters
    ----------
    conv_txt : pandas.DataFrame
        Indexed by (method, reading, symbol), two columns: the converged size as text with R
        given to the larger size, then to the smaller (:func:`converged_at`).
    method : str
        "MCS" or "LHS".
    symbol : str
        The error whose index converges.
    readings : sequence of str
        Readings of a sample size, each a level of the index (:data:`READINGS`).

    Returns
    -------
    str
        ``"<reading>: <both sizes>"`` per reading (:func:`both_sizes`), joined by ``"; "``.
    """
    return "; ".join(f"{rd}: {both_sizes(*conv_txt.loc[(method, rd, symbol)])}"
                     for rd in readings)


def fluctuation_text(r_steps: pd.DataFrame, *, method: str, sizes=(1000, 2000),
                     readings=READINGS) -> str:
    """The range of Fig. 7's fluctuation R (percent) over the errors at one sample size.

    R at a size is read both ways (Eq. 24): the step that ends there (R at the larger size,
    column ``sizes[0]``) and the step that starts there (R at the smaller, column
    ``sizes[1]``, the next size).

    Parameters
    ----------
    r_steps : pandas.DataFrame
        R (percent) indexed by (method, reading, symbol), one column per sample size.
    method : str
        "MCS" or "LHS".
    sizes : (int, int)
        The size and the next one run.
    readings : sequence of str
        Readings of a sample size, each a level of the index (:data:`READINGS`).

    Returns
    -------
    str
        ``"<reading>: <min> to <max> % (R at the larger size), <min> to <max> % (at the
        smaller)"`` per reading, one decimal, joined by ``"; "``.
    """
    def span(v):
        return f"{v.min():.1f} to {v.max():.1f} %"

    return "; ".join(f"{rd}: " + both_sizes(*(span(r_steps.loc[(method, rd)][n]) for n in sizes))
                     for rd in readings)
