"""A notebook's scorecard (:class:`Card`), the tolerance policy, and deterministic tables.

Each notebook scores the paper's printed numbers (read from ``data/papers`` with
:func:`mtaccuracy.papers.printed.published`) on one :class:`Card` and writes it as
``reproduction.csv`` (:data:`COLUMNS`); :mod:`mtaccuracy.compendium.scorecard` gathers the
cards.  :func:`write_table` writes every CSV byte-stable, with the tolerance a regeneration on
another machine is held to.
"""

from __future__ import annotations

import fnmatch
import hashlib
import io
import math
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from ..papers.printed import half_unit
from .provenance import write_atomic

COLUMNS = ["item", "quantity", "published", "reproduced", "unit", "tolerance", "verdict",
           "basis", "kind", "agreement", "note"]
VERDICTS = ("reproduced", "close", "differs", "not reproducible")
#: What a row scores, from the :class:`Card` method that made it: a printed ``number``
#: (:meth:`Card.number`, :meth:`Card.bracket`), a ``count``, a ``set`` of names, a
#: ``statement`` checked on our results, or a ``claim`` that cannot be checked.
KINDS = ("number", "count", "set", "statement", "claim")
#: What a ``reproduced`` number agrees within: the ``printed`` precision (half a unit of its
#: last digit), only the ``paper``'s stated agreement, or only our ``sampling`` error.
AGREEMENTS = ("printed", "paper", "sampling")

#: How a row's number was obtained: the one definition (README and the report quote it).
BASES = {
    "independent": "computed from the paper's stated inputs and our own stated assumptions, "
                   "with nothing chosen to match a published value",
    "fitted": "an input the paper omits was chosen to match published values, and this row is "
              "one of them: agreement shows the paper is consistent with that choice, not that "
              "the number was recovered",
    "constructed": "data, a calibration or a simulation whose inputs were set to published "
                   "values: agreement shows the construction worked",
    "internal": "the paper compared with itself: arithmetic on its printed numbers, or a "
                "reference derived from other published numbers (an input fitted to one "
                "published column, used to score another)",
    "simulated": "computed on simulated data standing in for the paper's measurements, with "
                 "no input set to a published value",
    "tautological": "a check that cannot fail: a claim true of every admissible model (every "
                    "rigid-body chain, every model linear in its errors), a count of what we "
                    "typed from the paper, or data generated and analysed under one "
                    "assumption: it reproduces nothing",
    "unchecked": "nothing was checked: the paper lacks what is needed, or the outcome was made "
                 "true by an assumption of ours (verdict 'not reproducible')",
}


class NonFiniteResult(ValueError):
    """A computed result is NaN or infinite: an error in the computation, never a verdict."""


def _finite(value, what: str) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise NonFiniteResult(f"{what} is not a number: {value!r}") from None
    if not math.isfinite(v):
        raise NonFiniteResult(f"{what} is {v}: a NaN or infinite result is an error in the "
                              f"computation (check the parameters and inputs), never a verdict")
    return v


# --- the scorecard API ---------------------------------------------------------------------

@dataclass(frozen=True)
class Input:
    """An input of a computation whose origin decides the basis of the rows that use it.

    ``kind``: ``fitted`` (an omitted input chosen to match ``targets``, published items),
    ``constructed`` (reconstructed data, a calibration, or a simulation whose inputs were set
    to published values; ``targets`` names them), ``simulated`` (a stand-in for a measurement,
    no input set to a published value), ``printed`` (the paper's own printed numbers, used as
    an input), ``assumed`` (an assumption of ours, such as a simulation parameter, that makes
    the rows it ``targets`` true by design) or ``tautological`` (a property of the model class
    or of what we typed that makes the rows it ``targets`` hold whatever the paper did).
    ``targets`` are patterns (:mod:`fnmatch`) matched against a row's ``item`` and against
    ``"item: quantity"``."""

    name: str
    kind: str
    targets: tuple[str, ...]
    how: str

    def matches(self, item: str, quantity: str) -> bool:
        return any(fnmatch.fnmatchcase(item, t) or fnmatch.fnmatchcase(f"{item}: {quantity}", t)
                   for t in self.targets)

    def describe(self, item: str = "", quantity: str = "") -> str:
        """What a row's note says of this input."""
        if self.kind == "simulated":
            return f"on simulated data: {self.name}"
        if self.kind == "printed":
            return f"{self.name} taken from the paper"
        if self.kind == "constructed":
            return (f"{self.name} was built to reproduce this number" if
                    self.matches(item, quantity) else
                    f"on {self.name}, whose inputs were set to published values")
        if self.kind == "assumed":
            return f"true by design: {self.name} ({self.how})"
        if self.kind == "tautological":
            return f"cannot fail: {self.name} ({self.how})"
        shown = ", ".join(self.targets[:3]) + (", ..." if len(self.targets) > 3 else "")
        if self.matches(item, quantity):
            return f"{self.name} fitted to {shown}"
        return (f"{self.name} fitted to {shown}: a reference derived from other published "
                f"numbers")


def tolerance_for(published, *, paper_rel: float | None = None, paper_abs: float | None = None,
                  sampling_se: float | None = None, k: float = 2.0) -> tuple[float, str]:
    """The tolerance policy: the largest of the justified tolerances, with its source.

    - ``printed``: half a unit of the published number's last printed digit (always);
    - ``paper``: the agreement the paper itself states (``paper_rel`` of the published value,
      or ``paper_abs``), e.g. Zheng's "< 5 % between methods";
    - ``sampling``: ``k`` standard errors of our own estimate (``sampling_se``, from a
      bootstrap or an analytic formula), ``k = 2`` for about 95 %.

    Returns ``(tolerance, source)``.  Nothing else widens a tolerance."""
    pub = _finite(published, "the published value")
    cands = [(half_unit(published), "printed")]
    if paper_rel is not None:
        cands.append((abs(paper_rel * pub), "paper"))
    if paper_abs is not None:
        cands.append((abs(paper_abs), "paper"))
    if sampling_se is not None:
        cands.append((k * _finite(sampling_se, "the sampling standard error"), "sampling"))
    for v, src in cands:
        if not (math.isfinite(v) and v >= 0):
            raise ValueError(f"a {src} tolerance must be finite and >= 0, got {v!r}")
    return max(cands, key=lambda c: c[0])


def _tolerance_text(value: float, source: str) -> str:
    return f"{value:.2g} ({source})"


def set_verdict(published, ours, ordered: bool = False) -> tuple[str, list, list]:
    """Verdict for a published set (or sequence, ``ordered``) against ours.

    Returned with the missing and extra elements.  ``reproduced`` when equal; ``close`` when at
    most one element is missing and at most one extra (one replaced) and they share at least 60 %
    of their union (Jaccard), so a one-for-one swap in a set of 4 or more; else ``differs``.  Extra
    elements count as much as missing ones."""
    pub, mine = [str(x) for x in published], [str(x) for x in ours]
    missing = [x for x in pub if x not in mine]
    extra = [x for x in mine if x not in pub]
    if not missing and not extra and (not ordered or pub == mine) and len(pub) == len(mine):
        return "reproduced", missing, extra
    union = set(pub) | set(mine)
    jaccard = len(set(pub) & set(mine)) / len(union) if union else 1.0
    if len(missing) <= 1 and len(extra) <= 1 and jaccard >= 0.6:
        return "close", missing, extra
    return "differs", missing, extra


class Card:
    """A notebook's scorecard: one row per published number, set, count or claim.

    Each row has its verdict and its basis (:data:`BASES`); the card is written by :meth:`write`.

    The basis is decided by the inputs a row declares it ``uses`` (:meth:`fitted`,
    :meth:`constructed`, :meth:`simulated`, :meth:`printed`, :meth:`assumed`), never typed,
    and a row can never be ``independent`` or ``simulated`` while it uses a fitted reference or
    a constructed input:

    1. a row using a ``constructed`` input is ``constructed`` (whether or not it was one of
       the construction's targets: a simulation whose inputs were set to published values
       cannot reproduce anything independently);
    2. a row using a ``fitted`` input is ``fitted`` when it is one of the fit's targets, and
       ``internal`` otherwise: its reference was derived from other published numbers, so
       the row compares the paper with itself, whatever the route;
    3. else one using ``simulated`` data is ``simulated``; one using only ``printed`` inputs
       is ``internal``; a row using nothing is ``independent``.

    A row that uses an ``assumed`` input among whose targets it is was made true by design:
    it is scored ``not reproducible`` (basis ``unchecked``) whatever our number says, with the
    assumption in its note.  The tolerance follows :func:`tolerance_for`; no verdict is
    computed anywhere else.  The methods that add a row return nothing (a notebook cell ending
    with one shows no ``Out[]``); the row is the last of :attr:`rows`.

    >>> card = Card()
    >>> pose = card.fitted("pose", to=["Table 2"], how="least squares on the printed indices")
    >>> card.number("Table 2", "S_T of d_ya", "0.0797", 0.0766, uses=[pose])
    >>> card.rows[-1]["basis"]
    'fitted'
    """

    def __init__(self):
        self.rows: list[dict] = []
        self.inputs: dict[str, Input] = {}

    # -- inputs --------------------------------------------------------------------------------
    def _input(self, name, kind, targets, how) -> Input:
        if not str(how).strip():
            raise ValueError(f"input {name!r}: say how it was obtained (how=...)")
        if isinstance(targets, str):
            targets = [targets]
        inp = Input(str(name), kind, tuple(str(t) for t in targets or ()), str(how))
        if name in self.inputs and self.inputs[name] != inp:
            raise ValueError(f"input {name!r} declared twice, differently")
        self.inputs[name] = inp
        return inp

    def fitted(self, name: str, to, how: str) -> Input:
        """An input the paper omits, chosen to match the published items ``to``."""
        if not to:
            raise ValueError(f"fitted input {name!r}: name the published items it matches (to=)")
        return self._input(name, "fitted", to, how)

    def constructed(self, name: str, targets, how: str) -> Input:
        """Reconstructed data, a calibration, or a simulation with inputs set to published values.

        ``targets``: the published items it was built to reproduce or whose values it took.
        Every row using it is ``constructed``."""
        if not targets:
            raise ValueError(f"constructed input {name!r}: name its published targets")
        return self._input(name, "constructed", targets, how)

    def simulated(self, name: str, how: str) -> Input:
        """Simulated data standing in for a measurement the paper made.

        None of its inputs is set to a published value (otherwise declare it
        :meth:`constructed`)."""
        return self._input(name, "simulated", (), how)

    def assumed(self, name: str, settles, how: str) -> Input:
        """An assumption of ours that makes the rows matching ``settles`` true by design.

        E.g. a simulated error set equal at every speed, then "confirmed" equal.  Those rows are
        scored ``not reproducible``, never ``reproduced``."""
        if not settles:
            raise ValueError(f"assumed input {name!r}: name the rows it settles (settles=)")
        return self._input(name, "assumed", settles, how)

    def tautology(self, name: str, settles, how: str) -> Input:
        """What makes the rows matching ``settles`` hold whatever the paper did.

        A claim true of every admissible model (every rigid-body chain, every model linear in
        its errors), a count of what we typed from the paper, data generated and analysed under
        one assumption.  Those rows keep their verdict but take the basis ``tautological``:
        never an independent reproduction."""
        if not settles:
            raise ValueError(f"tautology {name!r}: name the rows it settles (settles=)")
        return self._input(name, "tautological", settles, how)

    def printed(self, name: str, how: str = "printed in the paper") -> Input:
        """The paper's own printed numbers used as an input.

        Rows using only these are ``internal``: checks of the paper."""
        return self._input(name, "printed", (), how)

    # -- rows ----------------------------------------------------------------------------------
    def _basis(self, item: str, quantity: str, uses) -> tuple[str, str, bool]:
        """``(basis, what the note says of the inputs, made true by an assumption)``."""
        uses = list(uses or ())
        for u in uses:
            if not isinstance(u, Input) or self.inputs.get(u.name) != u:
                raise ValueError(f"{item}: {quantity}: uses {u!r}, not an input of this card")
        by_design = any(u.kind == "assumed" and u.matches(item, quantity) for u in uses)
        cannot_fail = any(u.kind == "tautological" and u.matches(item, quantity) for u in uses)
        uses = [u for u in uses if u.kind != "tautological" or u.matches(item, quantity)]
        kinds = {u.kind for u in uses} - {"assumed", "tautological"}
        said = "; ".join(u.describe(item, quantity) for u in uses if u.kind != "printed")
        fits = [u for u in uses if u.kind == "fitted"]
        if cannot_fail:
            basis = "tautological"
        elif "constructed" in kinds:
            basis = "constructed"
        elif any(u.matches(item, quantity) for u in fits):
            basis = "fitted"
        elif fits or kinds == {"printed"}:
            basis = "internal"
            if not fits:
                said = "; ".join(u.describe() for u in uses
                                 if u.kind not in ("assumed", "tautological"))
        elif "simulated" in kinds:
            basis = "simulated"
        else:
            basis = "independent"
        return basis, said, by_design

    def _add(self, item, quantity, published, reproduced, unit, tolerance, verdict_, uses,
             note, measured=False, *, kind: str, agreement: str = "") -> None:
        item, quantity = str(item), str(quantity)
        if measured:
            quantity = f"{quantity} {MEASURED_MARK}"
        if any(r["item"] == item and r["quantity"] == quantity for r in self.rows):
            raise ValueError(f"scorecard row {item}: {quantity} added twice")
        basis, said, by_design = self._basis(item, quantity, uses)
        if by_design:
            verdict_ = "not reproducible"
        if verdict_ == "not reproducible":
            basis = "unchecked"
        note = "; ".join(x for x in (str(note).strip(), said) if x)
        if verdict_ != "reproduced":
            agreement = ""
        row = dict(item=item, quantity=quantity, published=published, reproduced=reproduced,
                   unit=unit, tolerance=tolerance, verdict=verdict_, basis=basis, kind=kind,
                   agreement=agreement, note=note)
        _check_row_numbers([row])
        self.rows.append(row)

    def number(self, item, quantity, published, ours, unit: str = "", *, uses=(),
               paper_rel=None, paper_abs=None, sampling_se=None, conclusion: str = "",
               holds: bool | None = None, digits: int | None = None, note: str = "",
               measured: bool = False, kind: str = "number") -> None:
        """A published number against ours.

        ``reproduced`` within the tolerance of :func:`tolerance_for`; outside it ``close`` only
        when a stated ``conclusion`` (the paper's, in words) ``holds`` for our number, else
        ``differs``.  ``published`` is the string printed in the paper (its digits give the printed
        precision)."""
        tol, src = tolerance_for(published, paper_rel=paper_rel, paper_abs=paper_abs,
                                 sampling_se=sampling_se)
        pub = _finite(published, f"{item}: {quantity}: published")
        mine = _finite(ours, f"{item}: {quantity}: reproduced")
        if holds is not None and not conclusion.strip():
            raise ValueError(f"{item}: {quantity}: 'holds' needs the conclusion in words")
        agreement = "printed" if abs(pub - mine) <= half_unit(published) * (1 + 1e-12) else src
        if abs(pub - mine) <= tol * (1 + 1e-12):
            v = "reproduced"
        else:
            v = "close" if holds else "differs"
            if conclusion:
                note = "; ".join(x for x in (note, f"{'same' if holds else 'not the same'} "
                                                   f"conclusion: {conclusion}") if x)
        if isinstance(ours, int | np.integer) and not isinstance(ours, bool):
            mine = int(ours)
        elif digits is not None:
            mine = round(mine, digits)
        self._add(item, quantity, str(published), mine, unit, _tolerance_text(tol, src), v,
                  uses, note, measured, kind=kind, agreement=agreement)

    def count(self, item, quantity, published, ours: int, *, uses=(), conclusion: str = "",
              holds: bool | None = None, note: str = "") -> None:
        """A published count against ours: ``reproduced`` only when equal."""
        if int(ours) != ours or int(float(published)) != float(published):
            raise ValueError(f"{item}: {quantity}: a count must be an integer")
        self.number(item, quantity, str(int(float(published))), int(ours), uses=uses,
                    conclusion=conclusion, holds=holds, note=note, kind="count")

    def set(self, item, quantity, published, ours, *, uses=(), ordered: bool = False,
            note: str = "") -> None:
        """A published set (or sequence) of names against ours (:func:`set_verdict`).

        The note lists the missing and the extra elements."""
        pub, mine = list(published), list(ours)
        v, missing, extra = set_verdict(pub, mine, ordered)
        said = [f"missing: {', '.join(missing)}" if missing else "",
                f"extra: {', '.join(extra)}" if extra else "",
                "same elements, other order" if v != "reproduced" and not missing
                and not extra else ""]
        note = "; ".join(x for x in (note, *said) if x)
        join = (lambda xs: " ".join(map(str, xs))) if ordered else \
            (lambda xs: " ".join(sorted(map(str, xs))))
        self._add(item, quantity, join(pub), join(mine) or "(none)", "",
                  "ordered, exact" if ordered else "exact set", v, uses, note, kind="set")

    def statement(self, item, quantity, published: str, ours: str, holds: bool, *, uses=(),
                  note: str = "", measured: bool = False) -> None:
        """A claim of the paper in words, checked on our results.

        ``reproduced`` when it ``holds``, else ``differs``."""
        self._add(item, quantity, str(published), str(ours), "", "claim",
                  "reproduced" if holds else "differs", uses, note, measured,
                  kind="statement")

    def bracket(self, item, quantity, published, low, high, unit: str = "", *, why: str,
                uses=(), digits: int | None = None, paper_rel=None, paper_abs=None,
                sampling_se=None) -> None:
        """A published number that rests on an input the paper omits.

        It is scored against ours at the two ends of the defensible values of that input (``low``,
        ``high``, either order).  Inside the bracket the missing input decides it: ``not
        reproducible``, ours shown as ``low-high``.  Outside, every defensible input disagrees: a
        :meth:`number` against the nearer end (``differs`` unless within its tolerance, which
        ``paper_rel``, ``paper_abs`` and ``sampling_se``, the nearer end's standard error, widen
        as in :meth:`number`).  ``why`` says what is missing and what the two ends are."""
        if not str(why).strip():
            raise ValueError(f"{item}: {quantity}: say what is missing (why=...)")
        lo, hi = sorted((_finite(low, f"{item}: {quantity}: low"),
                         _finite(high, f"{item}: {quantity}: high")))
        pub = _finite(published, f"{item}: {quantity}: published")
        fmt = (lambda v: f"{v:.{digits}f}") if digits is not None else (lambda v: f"{v:g}")
        if lo <= pub <= hi:
            self._add(item, quantity, str(published), f"{fmt(lo)}-{fmt(hi)}", unit, "",
                      "not reproducible", (), f"{why}; the published value lies inside",
                      kind="number")
            return
        near = lo if abs(pub - lo) <= abs(pub - hi) else hi
        self.number(item, quantity, published, near, unit, uses=uses, digits=digits,
                    paper_rel=paper_rel, paper_abs=paper_abs, sampling_se=sampling_se,
                    note=f"{why}; the published value lies outside {fmt(lo)}-{fmt(hi)}")

    def claim(self, item, quantity, published: str, why: str, ours="", unit: str = "") -> None:
        """A published number or claim that cannot be checked: ``not reproducible``.

        ``why`` says what is missing.  ``ours``: a value we computed all the same (shown, not
        scored), e.g. for a figure whose data the paper does not give."""
        if not str(why).strip():
            raise ValueError(f"{item}: {quantity}: say what the paper lacks (why=...)")
        if isinstance(ours, int | float | np.integer | np.floating) \
                and not isinstance(ours, bool):
            raise ValueError(f"{item}: {quantity}: our number exists ({ours!r}): score it with "
                             f"number(), or with bracket() when an omitted input decides it; "
                             f"claim() is for what cannot be computed")
        self._add(item, quantity, str(published), ours, unit, "", "not reproducible", (), why,
                  kind="claim")

    # -- output --------------------------------------------------------------------------------
    def frame(self, measured: bool = False) -> pd.DataFrame:
        """The rows (without the ``(measured)`` ones unless ``measured``)."""
        df = pd.DataFrame(self.rows, columns=COLUMNS)
        if not measured:
            df = df[~df["quantity"].str.contains(MEASURED_MARK, regex=False)]
        return df.reset_index(drop=True)

    def tally(self) -> pd.DataFrame:
        """Verdict x basis counts of the scored rows (the measured ones left out)."""
        return crosstab(self.frame())


def crosstab(cards: pd.DataFrame) -> pd.DataFrame:
    """Verdict x basis counts (bases as rows, verdicts as columns, with totals)."""
    t = pd.crosstab(cards["basis"], cards["verdict"]) if len(cards) else pd.DataFrame()
    t = t.reindex(index=[b for b in BASES if b in set(cards["basis"])],
                  columns=list(VERDICTS), fill_value=0)
    t["total"] = t.sum(axis=1)
    t.loc["total"] = t.sum(axis=0)
    t.index.name, t.columns.name = "basis", None
    return t.astype(int)


MEASURED_MARK = "(measured)"
MEASURED_CARD = "reproduction_measured.csv"


def _is_missing(value) -> bool:
    return value is None or (isinstance(value, str) and value.strip() == "")


def _check_row_numbers(rows: list[dict]) -> None:
    """A row's ``reproduced`` is a finite number or text; empty only when the row is ``not
    reproducible``; NaN and infinity (as floats or as text) are errors, never verdicts."""
    for i, r in enumerate(rows):
        where = f"scorecard row {i + 1} ({r.get('item', '')}: {r.get('quantity', '')})"
        v = r.get("reproduced")
        if _is_missing(v):
            if r.get("verdict") != "not reproducible":
                raise NonFiniteResult(f"{where}: no reproduced value, but verdict "
                                      f"{r.get('verdict')!r}")
            continue
        if isinstance(v, str):
            if v.strip().lower().lstrip("+-") in ("nan", "inf", "infinity"):
                _finite(float(v), f"{where}: reproduced")
            continue
        if isinstance(v, int | float | np.integer | np.floating):
            _finite(v, f"{where}: reproduced")


def card_frame(rows: list[dict]) -> pd.DataFrame:
    """Check a scorecard's rows and return them as a table with :data:`COLUMNS`.

    Parameters
    ----------
    rows : list of dict
        The rows of a :class:`Card`.

    Returns
    -------
    pandas.DataFrame
        The rows, ``(measured)`` ones included.

    Raises
    ------
    NonFiniteResult
        A NaN or infinite reproduced value.
    ValueError
        A missing column, an unknown verdict or basis, or ``not reproducible`` without
        ``unchecked`` (or the reverse).
    """
    _check_row_numbers(rows)
    df = pd.DataFrame(rows)
    missing = [c for c in COLUMNS if c not in df.columns]
    if missing:
        raise ValueError(f"scorecard rows lack column(s) {missing}")
    bad = sorted(set(df["verdict"]) - set(VERDICTS))
    if bad:
        raise ValueError(f"unknown verdict(s) {bad}; allowed: {', '.join(VERDICTS)}")
    bad = sorted(set(df["basis"]) - set(BASES))
    if bad:
        raise ValueError(f"unknown basis {bad}; allowed: {', '.join(BASES)}")
    bad = sorted(set(df["kind"]) - set(KINDS))
    if bad:
        raise ValueError(f"unknown kind(s) {bad}; allowed: {', '.join(KINDS)}")
    bad = sorted(set(df["agreement"]) - {"", *AGREEMENTS})
    if bad:
        raise ValueError(f"unknown agreement(s) {bad}; allowed: {', '.join(AGREEMENTS)}")
    odd = df[(df["verdict"] == "not reproducible") != (df["basis"] == "unchecked")]
    if len(odd):
        r = odd.iloc[0]
        raise ValueError(f"scorecard row {r['item']}: {r['quantity']}: verdict "
                         f"{r['verdict']!r} with basis {r['basis']!r}; 'not reproducible' "
                         f"and 'unchecked' go together")
    return df[COLUMNS]


@dataclass(frozen=True)
class Tolerance:
    """How closely a float column regenerated on another machine must match the committed one.

    The printed precision (one unit in the last digit written) is always allowed on top, so a
    last-digit rounding flip never fails; ``abs`` and ``rel`` add what the quantity's own numerical
    uncertainty justifies, and ``why`` says what that is (an optimiser's stopping tolerance, a
    solver's conditioning, ...).  Text and integer columns are always compared exactly."""

    rel: float = 0.0
    abs: float = 0.0
    why: str = "deterministic arithmetic: equal to the printed precision"

    def __post_init__(self):
        for name in ("rel", "abs"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise ValueError(f"Tolerance.{name} must be finite and >= 0, got {v!r}")
        if not self.why.strip():
            raise ValueError("a Tolerance needs its reason (why=...)")

    def allows(self, a: np.ndarray, b: np.ndarray, unit: np.ndarray) -> np.ndarray:
        """Elementwise: ``|a - b| <= max(abs, rel * max(|a|, |b|)) + unit``.

        ``unit``: the last printed digit's place of the two strings."""
        scale = np.maximum(np.abs(a), np.abs(b))
        return np.abs(a - b) <= np.maximum(self.abs, self.rel * scale) + unit * (1 + 1e-9)


#: The default for float columns: deterministic arithmetic, equal to the printed precision.
PRINTED = Tolerance()


def _tolerance_map(df: pd.DataFrame, tolerance) -> dict[str, dict]:
    """``{column: Tolerance as dict}`` for every float column of ``df``."""
    if tolerance is None:
        tolerance = {}
    if isinstance(tolerance, Tolerance):
        tolerance = {"*": tolerance}
    unknown = [c for c in tolerance if c != "*" and c not in df.columns]
    if unknown:
        raise ValueError(f"tolerance for unknown column(s) {unknown}; columns: "
                         f"{list(df.columns)}")
    for c, t in tolerance.items():
        if not isinstance(t, Tolerance):
            raise TypeError(f"tolerance[{c!r}] must be a reproduction.Tolerance, got {t!r}")
    out = {}
    for c in df.columns:
        t = tolerance.get(c, tolerance.get("*", PRINTED))
        if c in tolerance or pd.api.types.is_float_dtype(df[c]):
            out[str(c)] = asdict(t)
    return out


def write_table(df: pd.DataFrame, path, *, float_format: str = "%.6g", tolerance=None,
                measured: bool = False) -> dict:
    """Write a CSV deterministically; return its entry for the folder's ``provenance.json``.

    Fixed float format, '\\n' line ends, no index.

    Parameters
    ----------
    df : pandas.DataFrame
        The table.
    path : Path
        The file.
    float_format : str
        Format of float cells.
    tolerance : Tolerance or dict, optional
        How closely a regeneration on another machine must match: a :class:`Tolerance` for
        every float column, or ``{column: Tolerance}`` (key ``"*"`` for the others); default
        :data:`PRINTED`.
    measured : bool
        The whole table is a measurement of the machine (wall-clock times): no hash, never
        compared.

    Returns
    -------
    dict
        ``{"sha256": ..., "tolerance": {column: ...}}``, or ``{"measured": True}``.

    Raises
    ------
    NonFiniteResult
        An infinite value (NaN is written as an empty cell).
    """
    path = Path(path)
    num = df.select_dtypes(include="number")
    if not num.empty and np.isinf(num.to_numpy(dtype=float)).any():
        cols = [c for c in num.columns if np.isinf(num[c].to_numpy(dtype=float)).any()]
        raise NonFiniteResult(f"{path.name}: infinite value(s) in column(s) {cols}")
    tol = _tolerance_map(df, tolerance)
    path.parent.mkdir(parents=True, exist_ok=True)
    buf = io.StringIO()
    df.to_csv(buf, index=False, float_format=float_format, lineterminator="\n")
    data = buf.getvalue().encode("utf-8")
    write_atomic(path, data)
    if measured:
        return {"measured": True}
    return {"sha256": hashlib.sha256(data).hexdigest(), **({"tolerance": tol} if tol else {})}
