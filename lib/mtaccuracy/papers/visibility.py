"""Which test sees which error: a status table per test and plan, and its matrix figure.

The papers name the errors that matter (Zheng et al. 2024's key errors, Table 2; Guo et al.
2016's Spearman ranking, Fig. 3) and stop there; the next question is which measurement would
see them.  :func:`visibility_table` asks :func:`mtaccuracy.measure.identifiability.identifiability`
of every test of a plan, and of the plan as a whole, what it sees of each named error: *seen*,
seen only in a named *combination*, or *blind* (the definitions, with the noise and the priors,
are that module's); :func:`per_error_summary` condenses it per error and
:func:`status_matrix_figure` draws it.  Shared by notebook 01
(:mod:`mtaccuracy.papers.zheng2024.measurement`) and notebook 03
(:mod:`mtaccuracy.papers.guo2016_measurement`), so that neither chapter imports the other.

``prior_sd=None`` asks for the test's *structure* (:func:`structural_prior_sd`): each error's
prior is the size at which it alone would move the readings, beyond what the nuisances absorb,
a million times their noise, so the status no longer depends on units or sizes: an error is
seen whenever the readings depend on it in a way no nuisance and no other error can mimic,
blind when the nuisances absorb all of it, else in a named combination.  That is what the test
can confirm at all, noise-free.  With the priors of a paper's ranges the status says what the
test confirms at those sizes and the stated noise.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd

from ..measure.design import Design, combine
from ..measure.identifiability import Identifiability, identifiability

__all__ = ["STATUSES", "STRUCTURAL_GAIN", "structural_prior_sd", "visibility_table",
           "per_error_summary", "status_matrix_figure"]

#: The statuses, in the order of the figure's legend.
STATUSES = ("seen", "combination", "blind")
#: The structural prior moves the readings this many times their noise
#: (:func:`structural_prior_sd`): two errors whose effects differ by less than about 1e-5 of
#: their size count as one combination.
STRUCTURAL_GAIN = 1e6
#: An error whose effect left after the nuisances is below this share of its effect is absorbed
#: by them (far above rounding, 1e-16; far below any real effect).
_ABSORBED = 1e-9


def _order(design: Design, symbols: Sequence[str]) -> list[int]:
    symbols = list(symbols)
    unknown = [s for s in symbols if s not in design.errors]
    if unknown or not symbols:
        raise ValueError(f"visibility_table: the errors {unknown} are not errors of the tests "
                         f"(their errors: {', '.join(design.errors[:8])} ...); name at least one "
                         "of them" if unknown else "visibility_table: name at least one error")
    if len(set(symbols)) != len(symbols):
        raise ValueError(f"visibility_table: errors named twice in {symbols}")
    return [design.errors.index(s) for s in symbols]


def structural_prior_sd(design: Design) -> np.ndarray:
    """Priors that make the status a property of the test alone: column-equilibrated, large.

    Error ``j``'s prior is ``STRUCTURAL_GAIN / ||P a_j / sigma||``, with ``a_j`` its column of
    readings, ``P`` the projection off the nuisances' range (least squares, numpy) and
    ``sigma`` the noise: alone, it would move the readings :data:`STRUCTURAL_GAIN` times their
    noise.  The prior-scaled columns then all have the same length, so which errors share a
    combination depends only on the directions of their effects (the support of the null
    space does not change with a column's scale), not on units (mm against rad) or sizes.  An
    error the nuisances absorb (``||P a_j|| <= 1e-9 ||a_j||``) gets a prior of 1 (mm or rad):
    blind at any size.

    Parameters
    ----------
    design : Design
        One test or a plan.

    Returns
    -------
    (n_errors,) ndarray
        mm or rad, each finite and > 0.
    """
    w = 1.0 / design.sigma
    A = design.A * w[:, None]
    N = design.N * w[:, None]
    if N.shape[1]:
        A = A - N @ np.linalg.lstsq(N, A, rcond=None)[0]
    left = np.linalg.norm(A, axis=0)
    whole = np.linalg.norm(design.A * w[:, None], axis=0)
    absorbed = left <= _ABSORBED * whole
    return np.where(absorbed, 1.0, STRUCTURAL_GAIN / np.where(absorbed, 1.0, left))


def visibility_table(designs: Sequence[Design], *, symbols: Sequence[str], prior_sd=None,
                     shrink: float = 100.0,
                     plan: str = "plan") -> tuple[pd.DataFrame, Identifiability]:
    """Each test's, and the whole plan's, status of each named error, with its combination.

    Parameters
    ----------
    designs : sequence of Design
        The tests (:meth:`mtaccuracy.measure.instruments.Measurement.design`), of one machine,
        each with its own name (none named ``plan``).
    symbols : sequence of str
        The errors to report (e.g. a paper's key errors), in the order wanted; each an error
        of the designs.
    prior_sd : (n_errors,) array_like or mapping of str to float, optional
        Each error's prior standard deviation, design units (mm, rad); ``None`` for the
        structural status (:func:`structural_prior_sd` of each test and of the plan).
    shrink : float, default 100
        The factor of :func:`~mtaccuracy.measure.identifiability.identifiability`.
    plan : str
        The name of the row block of all the tests together.

    Returns
    -------
    table : pandas.DataFrame
        One row per test (in the order given, then ``plan``) and error (in ``symbols``'
        order): ``test``, ``symbol``, ``status`` (one of :data:`STATUSES`) and
        ``combination`` (the unseen combinations that error is in, for that test; ``""`` when
        seen or blind).
    plan : Identifiability
        The whole plan's result (``.summary()``: its rank, condition number, O1-O5).
    """
    designs = list(designs)
    if not designs:
        raise ValueError("visibility_table needs at least one test")
    seen = [d.name for d in designs] + [plan]
    twice = sorted({n for n in seen if seen.count(n) > 1})
    if twice:
        raise ValueError(f"visibility_table: tests named twice {twice} (the plan is {plan!r}): "
                         "give each test its own name")
    idx = _order(designs[0], symbols)
    rows, whole = [], None
    for d in [*designs, combine(designs, name=plan)]:
        prior = structural_prior_sd(d) if prior_sd is None else prior_sd
        r = identifiability(d, prior_sd=prior, shrink=shrink)
        rows += [{"test": d.name, "symbol": r.errors[j], "status": r.status[j],
                  "combination": r.combination[j]} for j in idx]
        whole = r
    return pd.DataFrame(rows), whole


def _kind(test: str) -> str:
    """A test's kind without its set-up: ``"circle YZ"``, ``"R-test C"``."""
    for cut in (" r=", " ball (", " sphere ("):
        test = test.split(cut)[0]
    return test


def per_error_summary(table: pd.DataFrame, *, plan: str = "plan") -> pd.DataFrame:
    """Per error: the plan's status and combination, and which tests see it, alone or not.

    Parameters
    ----------
    table : pandas.DataFrame
        As :func:`visibility_table` returns.
    plan : str
        The name of the plan's row block.

    Returns
    -------
    pandas.DataFrame
        Indexed by symbol (the table's order): ``status`` and ``combination`` in the plan,
        ``n_tests`` (the tests that, alone, see it or a combination it is in) and ``tests``
        (their kinds, without set-ups, ``", "``-joined in the plan's order).
    """
    whole = table[table.test == plan].set_index("symbol")[["status", "combination"]].copy()
    if whole.empty:
        raise ValueError(f"per_error_summary: no rows of the plan {plan!r} in the table")
    some = table[(table.test != plan) & (table.status != "blind")]
    whole["n_tests"] = some.groupby("symbol").size().reindex(whole.index, fill_value=0)
    kinds = {s: ", ".join(dict.fromkeys(_kind(t) for t in g.test))
             for s, g in some.groupby("symbol", sort=False)}
    whole["tests"] = [kinds.get(s, "") for s in whole.index]
    return whole


def status_matrix_figure(table: pd.DataFrame, *, colours: Mapping[str, str], title: str,
                         rows: str = "symbol", columns: str = "test", highlight=(),
                         width: float | None = None):
    """The statuses as a matrix: one cell per row (error) and column (test), coloured by status.

    Each cell also carries a letter (``s`` seen, ``c`` combination, none for blind; ``-`` for a
    term a model does not have, or a cell the table lacks), so the figure reads without
    colour.

    Parameters
    ----------
    table : pandas.DataFrame
        With the columns named by ``rows`` and ``columns`` and ``status`` (one of
        :data:`STATUSES`, or ``"n/a"`` for a cell the model does not have), as
        :func:`visibility_table` returns.
    colours : mapping of str to str
        A colour per status (the compendium's colour-blind-safe ``plotting.CATEGORICAL``, blind
        its pale grey); ``"n/a"`` is drawn white.
    title : str
        The figure's title.
    rows, columns : str
        The table's columns giving the matrix' rows and columns (kept in order of appearance).
    highlight : iterable of str
        Row labels to set in bold (e.g. the errors a paper ranks highest).
    width : float, optional
        The figure's width, inches (default from the number of columns).

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt  # the compendium extra: only the notebooks draw
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    missing = [s for s in STATUSES if s not in colours]
    if missing:
        raise ValueError(f"status_matrix_figure: colours needs a colour for {missing}")
    kinds = (*STATUSES, "n/a")
    bad = sorted(set(table.status) - set(kinds))
    if bad:
        raise ValueError(f"status_matrix_figure: unknown status {bad}; allowed: {kinds}")
    r_lab = list(dict.fromkeys(table[rows]))
    c_lab = list(dict.fromkeys(table[columns]))
    grid = (table.assign(code=[kinds.index(s) for s in table.status])
            .pivot(index=rows, columns=columns, values="code").loc[r_lab, c_lab]
            .fillna(kinds.index("n/a")))
    codes = grid.to_numpy(dtype=float)
    cmap = ListedColormap([colours[s] for s in STATUSES] + ["#FFFFFF"])
    fig, ax = plt.subplots(figsize=(width or max(5.0, 1.6 + 0.32 * len(c_lab)),
                                    1.6 + 0.27 * len(r_lab) + 0.055 * max(map(len, c_lab))))
    ax.pcolormesh(np.arange(len(c_lab) + 1), np.arange(len(r_lab) + 1), codes, cmap=cmap,
                  vmin=-0.5, vmax=3.5, edgecolors="white", linewidth=0.6)
    letter = {0: "s", 1: "c", 2: "", 3: "-"}
    for (i, j), v in np.ndenumerate(codes):
        ax.text(j + 0.5, i + 0.5, letter[int(v)], ha="center", va="center", fontsize=7,
                color="white" if v in (0, 1) else "black")
    ax.set_xticks(np.arange(len(c_lab)) + 0.5, c_lab, rotation=90, fontsize=7)
    ax.set_yticks(np.arange(len(r_lab)) + 0.5, r_lab, fontsize=8)
    for t in ax.get_yticklabels():
        if t.get_text() in set(highlight):
            t.set_fontweight("bold")
    ax.invert_yaxis()
    ax.grid(False)
    ax.set_title(title, fontsize=9)
    present = [s for s in kinds if kinds.index(s) in set(codes.ravel().astype(int))]
    ax.legend([Patch(facecolor=cmap(kinds.index(s)), edgecolor="0.5") for s in present],
              [f"{s} ({letter[kinds.index(s)] or 'empty'})" for s in present],
              loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    fig.tight_layout()
    return fig
