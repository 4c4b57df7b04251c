"""Which test sees which error: the identifiability of a :class:`~.design.Design`; the next test.

The readings ``y = A eps + N nu + e`` (``e ~ N(0, diag(sigma**2))``) are whitened by the noise
and the errors scaled by their prior standard deviations, ``z = eps / prior_sd`` (so a priori
``z ~ N(0, I)``), giving ``y~ = A~ z + N~ nu + e~`` with ``e~ ~ N(0, I)``.  The nuisances carry
no prior (a set-up's centre or bar length may be anything): they are projected out exactly,
``A_perp = (I - Q Q') A~`` with ``Q`` an orthonormal basis of the range of ``N~`` (its SVD).
With the SVD ``A_perp = U S V'``, the posterior covariance of ``z`` is
``V diag(1 / (1 + S**2)) V'``: along the direction ``v_i`` the data shrink the prior variance by
the factor ``1 + s_i**2``.

**Seen, by a stated factor.**  A direction is *seen* when the data shrink its prior variance by
at least ``shrink`` (default 100: its posterior standard deviation is at most a tenth of the
prior's), i.e. ``s_i**2 >= shrink - 1``.  The rank is the number of seen directions; the
condition number is ``s_max / s_min`` over the seen ones only (a singular plan's condition number
would be rounding noise).  Per error ``j``, with ``b_j`` the share of its prior variance lying in
the unseen directions (``b_j = 1 - ||V_seen[j]||**2``): *seen* when ``b_j <= 1 / shrink``;
*blind* when the data remove at most ``1 / shrink`` of its prior variance (``1 - posterior /
prior``; the test adds next to nothing about it); else *combination*: it is determined only
together with others, or only in part (its posterior standard deviation says how much).

**Naming a combination, canonically.**  The unseen subspace (the combinations of errors the plan
cannot tell from zero) has a unique basis in reduced row-echelon form over the errors in the
design's order: each basis vector has a leading coefficient 1 on its pivot error and 0 on the
other pivots.  In physical units, the vector ``(pivot: 1, k: c_k)`` means "moving the pivot error
by one of its units and error ``k`` by ``c_k`` of its units (the design's units, mm and rad, so
``c_k`` is in unit_k per unit_pivot) changes no reading by more than the noise can show".  A
*combination* error is named with every basis vector it appears in.  This choice is canonical
(independent of the SVD's signs and of how ties among singular values fall): it depends only on
the unseen subspace and the order of the errors.

**Observability indices** (Sun and Hollerbach 2008, doi:10.1109/ROBOT.2008.4543213, the five
indices FIGAROH reports), over the ``L`` seen singular values ``s_1 >= ... >= s_L`` of the
whitened, prior-scaled, nuisance-free Jacobian and ``m`` readings (the base, identifiable,
parameters, as FIGAROH computes them after removing the unidentifiable ones):
``O1 = (s_1 ... s_L)**(1/L) / sqrt(m)`` (Borm and Menq), ``O2 = s_L / s_1`` (Driels and Pathre),
``O3 = s_L`` (Nahvi), ``O4 = s_L**2 / s_1`` (noise amplification, Nahvi and Hollerbach),
``O5 = 1 / sum(1 / s_i)`` (Sun and Hollerbach).

Written by hand: the projection, the SVD and the reduced row-echelon form are a few lines of
numpy and scipy; no library names the combinations of a machine tool's errors.
"""

from __future__ import annotations

__all__ = ["Identifiability", "NextTest", "identifiability", "identifiability_table", "next_test",
           "plan_tests", "prior_vector"]

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy import linalg

from .design import Design, combine

#: Coefficients of a combination below this (in the prior-scaled coordinates, where the
#: unseen basis has entries of order one) are zero: far above rounding (1e-16), far below any
#: coupling a test produces.
_COEF_TOL = 1e-8


def prior_vector(design: Design, prior_sd) -> np.ndarray:
    """The prior standard deviations as a vector in the design's error order, refused if bad.

    Parameters
    ----------
    design : Design
        The test or plan whose ``errors`` order the vector.
    prior_sd : (n_errors,) array_like or mapping of str to float
        Each error's prior standard deviation in the design's units (mm, rad): an array in the
        order of ``design.errors``, or a mapping naming every error (extra names refused).

    Returns
    -------
    (n_errors,) ndarray
        The prior standard deviations, each finite and > 0.
    """
    names = design.errors
    if isinstance(prior_sd, Mapping):
        missing = [e for e in names if e not in prior_sd]
        extra = [k for k in prior_sd if k not in names]
        if missing or extra:
            raise ValueError(f"prior_sd for design {design.name!r}: missing {missing[:5]}"
                             f"{' ...' if len(missing) > 5 else ''}, unknown {extra[:5]}: give "
                             "one value per error of the design")
        s = np.array([prior_sd[e] for e in names], dtype=float)
    else:
        s = np.asarray(prior_sd, dtype=float)
        if s.ndim == 0:
            s = np.full(len(names), float(s))
        if s.shape != (len(names),):
            raise ValueError(f"prior_sd must be ({len(names)},) for design {design.name!r} "
                             f"(one per error), got {s.shape}")
    bad = [names[i] for i in np.flatnonzero(~(np.isfinite(s) & (s > 0)))]
    if bad:
        raise ValueError(f"prior_sd must be finite and > 0 (mm, rad); not so for {bad[:5]}")
    return s


def _check_shrink(shrink: float) -> float:
    shrink = float(shrink)
    if not (np.isfinite(shrink) and shrink > 1):
        raise ValueError(f"shrink must be a finite factor > 1 (default 100), got {shrink}")
    return shrink


@dataclass(frozen=True)
class _Core:
    """The whitened, prior-scaled, nuisance-free model and its SVD (shared with identify)."""

    At: np.ndarray        # (n, p) whitened, prior-scaled A
    Nt: np.ndarray        # (n, m) whitened N
    Q: np.ndarray         # (n, rN) orthonormal basis of range(Nt)
    U: np.ndarray         # (n, r) left singular vectors of A_perp
    S: np.ndarray         # (p,) singular values, zero-padded to p, descending
    V: np.ndarray         # (p, p) right singular vectors (completed to a basis)
    k: int                # number of seen directions


def _nuisance_basis(Nt: np.ndarray) -> np.ndarray:
    """An orthonormal basis (n, rank) of the whitened nuisances' range (numerical rank)."""
    if not Nt.shape[1]:
        return np.zeros((Nt.shape[0], 0))
    Un, Sn, _ = np.linalg.svd(Nt, full_matrices=False)
    return Un[:, Sn > Sn[0] * max(Nt.shape) * np.finfo(float).eps]


def _core(design: Design, s: np.ndarray, shrink: float) -> _Core:
    """Whiten, scale, project out the nuisances and take the SVD (no loop over readings)."""
    w = 1.0 / design.sigma
    At = design.A * w[:, None] * s[None, :]
    Nt = design.N * w[:, None]
    Q = _nuisance_basis(Nt)
    Ap = At - Q @ (Q.T @ At)
    U, S, Vt = np.linalg.svd(Ap, full_matrices=False)
    p = At.shape[1]
    if Vt.shape[0] < p:                     # fewer readings than errors: complete the basis
        Vt = np.vstack([Vt, linalg.null_space(Vt).T])
        S = np.concatenate([S, np.zeros(p - S.size)])
    k = int(np.sum(S**2 >= shrink - 1.0))
    return _Core(At, Nt, Q, U, S, Vt.T, k)


def _rref(W: np.ndarray) -> tuple[np.ndarray, list[int]]:
    """Reduced row-echelon form of the rows of ``W`` (r, p), pivots in column order."""
    R = np.array(W, dtype=float)
    pivots, row = [], 0
    for c in range(R.shape[1]):            # a loop over errors (<= ~100), not over readings
        if row == R.shape[0]:
            break
        i = row + int(np.argmax(np.abs(R[row:, c])))
        if abs(R[i, c]) < _COEF_TOL:
            continue
        R[[row, i]] = R[[i, row]]
        R[row] /= R[row, c]
        others = np.arange(R.shape[0]) != row
        R[others] -= np.outer(R[others, c], R[row])
        pivots.append(c)
        row += 1
    R = R[:row]
    R[np.abs(R) < _COEF_TOL] = 0.0
    return R, pivots


def _format_term(c: float, name: str, first: bool) -> str:
    mag = f"{abs(c):.6g}"
    body = name if mag == "1" else f"{mag} {name}"
    if first:
        return body if c > 0 else f"-{body}"
    return f"{'+' if c > 0 else '-'} {body}"


def _combinations(core: _Core, s: np.ndarray, names: Sequence[str]):
    """The canonical basis of the unseen subspace, in physical units, and its strings."""
    Wb = core.V[:, core.k:].T                              # (p - k, p), z coordinates
    if not Wb.shape[0]:
        return np.zeros((0, len(names))), [], []
    R, pivots = _rref(Wb)
    phys = R * s[None, :] / s[np.asarray(pivots)][:, None]   # coefficient k: unit_k / unit_piv
    text = []
    for row in phys:
        nz = np.flatnonzero(row)
        text.append(" ".join(_format_term(row[j], names[j], i == 0) for i, j in enumerate(nz)))
    return phys, pivots, text


@dataclass(frozen=True)
class Identifiability:
    """What a test or plan sees of each error (:func:`identifiability`).

    Attributes
    ----------
    design : str
        The design's name.
    errors : tuple of str
        The error symbols, in the design's order.
    status : tuple of str
        Per error: ``"seen"``, ``"combination"`` or ``"blind"``.
    combination : tuple of str
        Per error: the unseen combination(s) it appears in ("" when seen or blind),
        ``"; "``-joined,
        in the canonical form of the module's docstring.
    prior_sd, posterior_sd : (n_errors,) ndarray
        The prior and posterior standard deviations, design units (mm, rad); the posterior is
        the Gaussian one with the prior and flat nuisances.
    unseen_share : (n_errors,) ndarray
        ``b_j``: the share of each error's prior variance in the unseen directions, in [0, 1].
    basis : (n_unseen, n_errors) ndarray
        The unseen combinations in physical units (rows in reduced row-echelon form).
    singular_values : (n_errors,) ndarray
        Of the whitened, prior-scaled, nuisance-free Jacobian, descending (zero-padded).
    rank : int
        The number of seen directions.
    shrink : float
        The factor a direction's prior variance must shrink by to be seen.
    n_obs : int
        The number of readings.
    nuisance_rank : int
        The rank of the nuisance matrix (the dimensions projected out).
    """

    design: str
    errors: tuple
    status: tuple
    combination: tuple
    prior_sd: np.ndarray
    posterior_sd: np.ndarray
    unseen_share: np.ndarray
    basis: np.ndarray
    singular_values: np.ndarray
    rank: int
    shrink: float
    n_obs: int
    nuisance_rank: int

    @property
    def condition_number(self) -> float:
        """``s_max / s_min`` over the seen directions (1 for one, nan for none)."""
        sv = self.singular_values[:self.rank]
        return float(sv[0] / sv[-1]) if sv.size else float("nan")

    @property
    def observability(self) -> dict:
        """The indices O1-O5 (Sun and Hollerbach 2008) over the seen singular values."""
        sv = self.singular_values[:self.rank]
        if not sv.size:
            return {f"O{i}": 0.0 for i in range(1, 6)}
        return {"O1": float(np.exp(np.mean(np.log(sv))) / np.sqrt(self.n_obs)),
                "O2": float(sv[-1] / sv[0]), "O3": float(sv[-1]),
                "O4": float(sv[-1] ** 2 / sv[0]), "O5": float(1.0 / np.sum(1.0 / sv))}

    def summary(self) -> dict:
        """The plan's figures in one mapping.

        Returns
        -------
        dict
            ``design``, ``n_obs``, ``n_errors``, ``nuisance_rank``, ``rank``, ``n_seen``,
            ``n_combination``, ``n_blind``, ``condition_number`` and ``O1``-``O5``.
        """
        st = np.asarray(self.status)
        return {"design": self.design, "n_obs": self.n_obs, "n_errors": len(self.errors),
                "nuisance_rank": self.nuisance_rank, "rank": self.rank,
                "n_seen": int(np.sum(st == "seen")),
                "n_combination": int(np.sum(st == "combination")),
                "n_blind": int(np.sum(st == "blind")),
                "condition_number": self.condition_number, **self.observability}

    def to_df(self) -> pd.DataFrame:
        """One row per error, in the design's order.

        Returns
        -------
        pandas.DataFrame
            Columns ``symbol``, ``status``, ``combination``, ``prior_sd``, ``posterior_sd``
            (design units, mm or rad) and ``unseen_share``.
        """
        return pd.DataFrame({"symbol": list(self.errors), "status": list(self.status),
                             "combination": list(self.combination),
                             "prior_sd": self.prior_sd, "posterior_sd": self.posterior_sd,
                             "unseen_share": self.unseen_share})


def _learned(core: _Core) -> np.ndarray:
    """Per error, the share of its prior variance the data remove: ``1 - posterior / prior``."""
    return np.clip(1.0 - np.sum(core.V**2 / (1.0 + core.S**2)[None, :], axis=1), 0.0, 1.0)


def _statuses(b: np.ndarray, learned: np.ndarray, shrink: float) -> np.ndarray:
    return np.where(b <= 1.0 / shrink, "seen", np.where(learned <= 1.0 / shrink, "blind",
                                                         "combination"))


def identifiability(design: Design, *, prior_sd, shrink: float = 100.0) -> Identifiability:
    """Per error: seen, seen only in a named combination, or blind; rank, condition, O1-O5.

    Parameters
    ----------
    design : Design
        A test or a plan (:func:`~.design.combine`).
    prior_sd : (n_errors,) array_like or mapping of str to float
        Each error's prior standard deviation, design units (mm, rad): e.g. a uniform range's
        half-width over sqrt(3).
    shrink : float, default 100
        A direction is seen when the data shrink its prior variance by at least this factor
        (100: posterior standard deviation at most a tenth of the prior's); > 1.

    Returns
    -------
    Identifiability
        The labelled result (``.to_df()``, ``.summary()``); see the module's docstring for the
        definitions.

    Examples
    --------
    A ballbar circle of radius 100 mm on an XY stage with axis scales ``EXX``, ``EYY``
    (mm/mm) and squareness ``EC0Y`` (rad); centre and bar length are nuisances:

    >>> import numpy as np
    >>> from mtaccuracy.measure.design import Design
    >>> th = np.linspace(0, 2 * np.pi, 72, endpoint=False)
    >>> c, s = np.cos(th), np.sin(th)
    >>> d = Design("circle", 1e5 * np.c_[c * c, s * s, -s * c], -1e3 * np.c_[c, s, 1 + 0 * c],
    ...            0.1, ("EXX", "EYY", "EC0Y"), ("cx", "cy", "dL"), tuple(map(str, th)))
    >>> r = identifiability(d, prior_sd=[1e-5, 1e-5, 1e-5])
    >>> r.status, r.combination[0], r.rank
    (('combination', 'combination', 'seen'), 'EXX + EYY', 2)
    """
    s = prior_vector(design, prior_sd)
    shrink = _check_shrink(shrink)
    core = _core(design, s, shrink)
    Vs = core.V[:, :core.k]
    b = np.clip(1.0 - np.sum(Vs**2, axis=1), 0.0, 1.0)
    post = np.sqrt(np.sum(core.V**2 / (1.0 + core.S**2)[None, :], axis=1)) * s
    status = _statuses(b, _learned(core), shrink)
    phys, pivots, text = _combinations(core, s, design.errors)
    comb = []
    for j, st in enumerate(status):
        if st != "combination" or not len(text):
            comb.append("")
        else:
            comb.append("; ".join(t for t, row in zip(text, phys, strict=True) if row[j] != 0))
    return Identifiability(design.name, design.errors, tuple(status.tolist()), tuple(comb), s,
                           post, b, phys, core.S, core.k, shrink, design.n_obs,
                           core.Q.shape[1])


def identifiability_table(designs: Sequence[Design], *, prior_sd,
                          shrink: float = 100.0) -> pd.DataFrame:
    """The test x error table: each error's status in each test alone and in the whole plan.

    Parameters
    ----------
    designs : sequence of Design
        The tests of a plan, of the same machine.
    prior_sd : (n_errors,) array_like or mapping of str to float
        Each error's prior standard deviation, design units (mm, rad).
    shrink : float, default 100
        The factor of :func:`identifiability`.

    Returns
    -------
    pandas.DataFrame
        Indexed by error symbol; one column per test (its name) holding ``"seen"``,
        ``"combination"`` or ``"blind"``, then ``plan`` (all tests together,
        :func:`~.design.combine`) and ``plan_combination`` (the plan's named combinations).
    """
    designs = list(designs)
    plan = identifiability(combine(designs), prior_sd=prior_sd, shrink=shrink)
    out = pd.DataFrame(index=pd.Index(plan.errors, name="symbol"))
    for d in designs:
        out[d.name] = identifiability(d, prior_sd=prior_sd, shrink=shrink).status
    out["plan"] = plan.status
    out["plan_combination"] = plan.combination
    return out


def _information(design: Design, s: np.ndarray) -> np.ndarray:
    """``A_perp' A_perp`` (n_errors, n_errors) in the prior-scaled coordinates."""
    core = _core(design, s, 2.0)
    return (core.V * core.S**2) @ core.V.T


@dataclass(frozen=True)
class NextTest:
    """The candidate tests ranked by what they add to a plan (:func:`next_test`).

    Attributes
    ----------
    plan : str
        The name of the plan the candidates are added to.
    candidates : tuple of str
        The candidates' names, best first.
    logdet_gain : (n_candidates,) ndarray
        ``log det(F + F_c) - log det(F)``, ``F = I + A_perp' A_perp`` of the plan in the
        (weighted) prior-scaled coordinates, ``F_c`` the candidate's; nats, best first.
    rank_after : (n_candidates,) ndarray of int
        The rank of the plan with the candidate added.
    changes : tuple of str
        Per candidate, the errors whose status changes (``"EYY: combination -> seen"``).
    before : Identifiability
        The plan's identifiability before any candidate.
    scale : (n_errors,) ndarray
        The weights' factors on the prior standard deviations, ``sqrt(w / max(w))`` (ones
        without weights).
    """

    plan: str
    candidates: tuple
    logdet_gain: np.ndarray
    rank_after: np.ndarray
    changes: tuple
    before: Identifiability = field(repr=False)
    scale: np.ndarray = field(repr=False, default=None)

    @property
    def best(self) -> str:
        """The name of the best candidate."""
        return self.candidates[0]

    def to_df(self) -> pd.DataFrame:
        """One row per candidate, best first.

        Returns
        -------
        pandas.DataFrame
            Columns ``test``, ``logdet_gain`` (nats), ``rank_before``, ``rank_after`` and
            ``changes``.
        """
        return pd.DataFrame({"test": list(self.candidates), "logdet_gain": self.logdet_gain,
                             "rank_before": self.before.rank, "rank_after": self.rank_after,
                             "changes": list(self.changes)})


def next_test(design: Design, candidates: Sequence[Design], *, prior_sd, weights=None,
              shrink: float = 100.0) -> NextTest:
    """D-optimal choice of the next test: each candidate's log-det gain and what it changes.

    The D-criterion of a plan is ``log det(I + A_perp' A_perp)`` in the prior-scaled
    coordinates (the log of the prior-to-posterior volume ratio); a candidate's gain is the
    criterion of the plan with it (its own nuisances, :func:`~.design.combine`) minus the
    plan's.  ``weights`` (e.g. the errors' Sobol total indices) scale the prior standard
    deviations by ``sqrt(w / max(w))`` for the criterion only, so an important error counts
    more; the statuses use the unweighted prior.  Gains within 1e-9 nats are ties, kept in the
    candidates' order (the greedy step of an exchange algorithm; call again with the best
    test added for the next one).

    Parameters
    ----------
    design : Design
        The plan so far (one test or :func:`~.design.combine` of several).
    candidates : sequence of Design
        The candidate tests, of the same machine (the same errors in the same order).
    prior_sd : (n_errors,) array_like or mapping of str to float
        The errors' prior standard deviations, design units (mm, rad).
    weights : (n_errors,) array_like or mapping of str to float, optional
        Non-negative importance weights (not all zero).
    shrink : float, default 100
        The factor of :func:`identifiability`.

    Returns
    -------
    NextTest
        The candidates ranked (``.to_df()``, ``.best``).
    """
    candidates = list(candidates)
    if not candidates:
        raise ValueError("next_test needs at least one candidate test")
    for c in candidates:
        if c.errors != design.errors:
            raise ValueError(f"candidate {c.name!r} has other errors than the plan "
                             f"{design.name!r}: every test must be of the same machine")
    s = prior_vector(design, prior_sd)
    shrink = _check_shrink(shrink)
    sw = s
    if weights is not None:
        if isinstance(weights, Mapping):
            w = np.array([weights.get(e, np.nan) for e in design.errors], dtype=float)
        else:
            w = np.asarray(weights, dtype=float)
        if w.shape != s.shape or not np.all(np.isfinite(w) & (w >= 0)) or not w.max() > 0:
            raise ValueError(f"weights must give ({len(s)},) finite values >= 0, not all zero, "
                             "one per error of the design")
        sw = s * np.sqrt(w / w.max())
    F0 = np.eye(len(s)) + _information(design, sw)
    ld0 = np.linalg.slogdet(F0)[1]
    gains = np.array([np.linalg.slogdet(F0 + _information(c, sw))[1] - ld0 for c in candidates])
    before = identifiability(design, prior_sd=s, shrink=shrink)
    order = sorted(range(len(candidates)), key=lambda i: (-np.round(gains[i], 9), i))
    ranks, changes = [], []
    for i in order:
        after = identifiability(combine([design, candidates[i]]), prior_sd=s, shrink=shrink)
        ranks.append(after.rank)
        changes.append("; ".join(f"{e}: {a} -> {b}" for e, a, b in
                                 zip(design.errors, before.status, after.status, strict=True)
                                 if a != b))
    return NextTest(design.name, tuple(candidates[i].name for i in order), gains[order],
                    np.array(ranks), tuple(changes), before, sw / s)


def plan_tests(design: Design, candidates: Sequence[Design], *, prior_sd, n: int,
               weights=None, shrink: float = 100.0) -> pd.DataFrame:
    """D-optimal choice of ``n`` tests to add: greedy steps, then a Fedorov exchange.

    The criterion is :func:`next_test`'s, ``log det(I + sum of the tests' A_perp' A_perp)`` in
    the (weighted) prior-scaled coordinates; the tests' information adds because each has its
    own nuisances.  Greedy: ``n`` times the candidate of largest gain.  Exchange: swap a chosen
    test for an unchosen one while the criterion grows by more than 1e-9 nats (the best swap
    first).  Ties (within 1e-9 nats) go to the earlier candidate.

    Parameters
    ----------
    design : Design
        The plan so far.
    candidates : sequence of Design
        The candidate tests, of the same machine; each may be chosen once.
    prior_sd : (n_errors,) array_like or mapping of str to float
        The errors' prior standard deviations, design units (mm, rad).
    n : int
        How many tests to add (1 to the number of candidates).
    weights : (n_errors,) array_like or mapping of str to float, optional
        Non-negative importance weights (:func:`next_test`).
    shrink : float, default 100
        The factor of :func:`identifiability`.

    Returns
    -------
    pandas.DataFrame
        One row per chosen test, in the order of their gains: ``step``, ``test``,
        ``logdet_gain`` (nats, given the tests above it), ``logdet_total`` (nats over the plan
        alone), ``rank_after`` and ``changes`` (the status changes that test brings).
    """
    candidates = list(candidates)
    if not (isinstance(n, int | np.integer) and 1 <= n <= len(candidates)):
        raise ValueError(f"n must be an int from 1 to {len(candidates)} (the candidates)")
    first = next_test(design, candidates, prior_sd=prior_sd, weights=weights, shrink=shrink)
    s = first.before.prior_sd
    sw = s * first.scale
    F0 = np.eye(len(s)) + _information(design, sw)
    Fc = [_information(c, sw) for c in candidates]

    def crit(chosen):
        return np.linalg.slogdet(F0 + sum((Fc[i] for i in chosen), np.zeros_like(F0)))[1]

    chosen: list[int] = []
    for _ in range(n):                      # greedy
        rest = [i for i in range(len(candidates)) if i not in chosen]
        vals = np.array([crit(chosen + [i]) for i in rest])
        chosen.append(rest[int(np.flatnonzero(vals >= vals.max() - 1e-9)[0])])
    best = crit(chosen)
    while True:                             # exchange
        swaps = [(crit([c for c in chosen if c != i] + [j]), k, j)
                 for k, i in enumerate(chosen) for j in range(len(candidates))
                 if j not in chosen]
        if not swaps:
            break
        val, k, j = max(swaps, key=lambda t: (t[0], -t[1], -t[2]))
        if val <= best + 1e-9:
            break
        chosen[k], best = j, val
    order, rows, before = [], [], first.before
    ld0 = np.linalg.slogdet(F0)[1]
    while len(order) < n:                   # the chosen tests in the order of their gains
        rest = sorted(i for i in chosen if i not in order)
        vals = np.array([crit(order + [i]) for i in rest])
        i = rest[int(np.flatnonzero(vals >= vals.max() - 1e-9)[0])]
        gain = vals.max() - crit(order)
        order.append(i)
        after = identifiability(combine([design, *(candidates[j] for j in order)]),
                                prior_sd=s, shrink=shrink)
        rows.append({"step": len(order), "test": candidates[i].name, "logdet_gain": gain,
                     "logdet_total": crit(order) - ld0, "rank_after": after.rank,
                     "changes": "; ".join(f"{e}: {a} -> {b}" for e, a, b in zip(
                         design.errors, before.status, after.status, strict=True) if a != b)})
        before = after
    return pd.DataFrame(rows)
