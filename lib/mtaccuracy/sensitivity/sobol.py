"""Sobol first-order and total indices from A, B and AB_i blocks, drawn and evaluated in blocks.

The estimators are SALib's (``SALib.analyze.sobol`` with ``calc_second_order=False``):
Saltelli et al. 2010 for the first order, Jansen 1999 for the total index, on outputs
standardised over all N(D+2) runs. SALib's sampler materialises every run at once (at D=41,
N=2^17, ``make bench`` measures 75 s of sampling and a 4.1 GB peak). Here :func:`sobol_indices`
takes the base rows :data:`BASE_ROWS` at a time: given a :class:`SobolDesign` it draws them
block by block through :meth:`~mtaccuracy.sensitivity.Inputs.sample_blocks`, the package's one
sampler (the Monte Carlo stream and the Sobol' sequence continue exactly where the previous
block ended), builds and evaluates each AB_i block chunk by chunk, and keeps per-block sums, so
the model sees one batched call per chunk and memory is flat in N; with ``n_boot=`` it
accumulates the bootstrap intervals the same way (:mod:`~mtaccuracy.sensitivity.bootstrap`, the
Poisson bootstrap). A test checks these numbers against SALib's at small N.

Layout: ``ya``, ``yb`` are (N, q); ``yab`` is (D, N, q) with ``yab[i]`` the model on AB_i (A
with column i taken from B); indices are (D, q), inputs by outputs.  Given an
:class:`~mtaccuracy.sensitivity.Inputs` (``SobolDesign(n, inputs, ...)``), the designs are
drawn through its laws and :func:`sobol_indices` labels its result (:class:`SobolIndices`,
``.to_df()``) with the input names.
"""

from __future__ import annotations

__all__ = ["base_samples", "base_blocks", "BASE_ROWS", "BOOT_FLOATS", "SobolDesign",
           "SobolIndices", "sobol_evaluate", "sobol_estimate", "sobol_indices", "FLOAT_NOISE"]

import copy
from collections.abc import Callable, Iterator, Sequence
from dataclasses import KW_ONLY, dataclass, field

import numpy as np
import pandas as pd

from ..validate import integer
from ..validate import rng as _rng
from .bootstrap import StreamedBootstrap, ci_half_width
from .inputs import Inputs

#: Base rows (of A and of B) drawn and run at a time by :func:`sobol_indices`.  Peak memory
#: is that of one block whatever N (``make bench``: about 210 MB above the imports at D = 41,
#: q = 6, plus the model's own temporaries on one batch).  A design of at most this many rows
#: is one block, computed with exactly the arithmetic of the whole-array estimate (the
#: notebooks' N <= 1e5 are).
BASE_ROWS = 2**17

def _check_method(n, method):
    n = integer(n, "n", low=2)
    if method not in ("mc", "lhs", "sobol"):
        raise ValueError(f"unknown sampling method {method!r}; allowed: mc, lhs, sobol")
    return n


def _dim(d) -> tuple[int, Inputs | None]:
    """(D, inputs) of a ``d`` given as a number of inputs or as an :class:`Inputs`."""
    if isinstance(d, Inputs):
        return d.dim, d
    return integer(d, "d", low=1), None


def _skip_ahead(rng: np.random.Generator, draws: int) -> np.random.Generator:
    """A copy of ``rng`` standing ``draws`` float64 draws further on, ``rng`` untouched.

    PCG64 (``default_rng``'s) and PCG64DXSM spend one 64-bit output per float64 and jump there
    in O(log draws) (``advance``); any other bit generator draws and discards, a block at a
    time (time O(draws), memory flat)."""
    out = copy.deepcopy(rng)
    bg = out.bit_generator
    if isinstance(bg, (np.random.PCG64, np.random.PCG64DXSM)):
        bg.advance(draws)
        return out
    left = draws
    while left:
        k = min(left, 2**22)
        out.random(k)
        left -= k
    return out


def base_blocks(n: int, d: int | Inputs, *, method: str, seed, rows: int = BASE_ROWS
                ) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """The A and B of :func:`base_samples`, drawn ``rows`` base rows at a time.

    Yields ``(a, b)`` blocks, (m, d) each with m <= rows, as they are needed; their
    concatenation is bitwise :func:`base_samples`' A and B (same arguments).

    Every design is drawn by :meth:`Inputs.sample_blocks` (the package's one sampler); this
    function only pairs them.  ``mc``: A and B are two successive designs of one generator
    ``numpy.random.default_rng(seed)``; B, which the whole draw takes after all of A, comes
    from a copy of the generator advanced by ``n d`` draws (PCG64's ``advance``), so both
    stream.  ``lhs``: two successive Latin hypercubes of the generator, each drawn whole
    (2 n d floats, 16 d bytes per row) and handed out in blocks.  ``sobol``: one scrambled
    2d-dimensional Sobol' sequence split in halves, as SALib's Saltelli sampler does, drawn
    block by block.  A generator passed as ``seed`` ends where :func:`base_samples` leaves it
    once every block is drawn.  Given an :class:`Inputs` for ``d``, the designs are of its
    laws; given a number, of :meth:`Inputs.unit` (the unit cube itself, bitwise).

    Parameters
    ----------
    n : int
        Base rows N (>= 2).
    d : int or Inputs
        The number of inputs D, or the inputs themselves (blocks in their units).
    method : {"mc", "lhs", "sobol"}
        The design.
    seed : None, int, SeedSequence or numpy.random.Generator
        The randomness (:func:`mtaccuracy.validate.rng`).
    rows : int
        Rows per block (>= 1).

    Yields
    ------
    a, b : arrays (m, D)
        In [0, 1) (or the inputs' units, given an :class:`Inputs`).
    """
    n = _check_method(n, method)
    rows = integer(rows, "rows", low=1)
    d, inputs = _dim(d)
    return _pairs(n, inputs if inputs is not None else Inputs.unit(d), method, _rng(seed), rows)


def _pairs(n, inputs, method, rng, rows):
    """(A, B) blocks of :func:`base_blocks`, every design drawn by ``Inputs.sample_blocks``.

    Nothing here keeps a block while the caller holds it (no loop variable, no ``zip``, whose
    reused result tuple would hold the last pair): a block's memory goes when the caller drops
    it."""
    d = inputs.dim
    count = -(-n // rows)
    if method == "sobol":
        seq = Inputs.unit(2 * d).sample_blocks(n, method="sobol", seed=rng, rows=rows)
        for _ in range(count):
            yield _halves(inputs, next(seq), d)
        return
    rng_b = _skip_ahead(rng, n * d) if method == "mc" else rng
    a = inputs.sample_blocks(n, method=method, seed=rng, rows=rows)
    b = inputs.sample_blocks(n, method=method, seed=rng_b, rows=rows)
    for _ in range(count):
        yield next(a), next(b)
    if method == "mc":
        rng.bit_generator.state = rng_b.bit_generator.state   # where the whole draw ends


def _halves(inputs, u, d):
    """The A and B halves of a block of the 2d-dimensional Sobol' sequence, through ``inputs``."""
    return inputs.from_unit(u[:, :d]), inputs.from_unit(u[:, d:])


def base_samples(n: int, d: int | Inputs, *, method: str, seed) -> tuple[np.ndarray, np.ndarray]:
    """Two independent (n, d) designs on the unit hypercube (or of the inputs): A and B.

    method ``mc``: independent uniforms; ``lhs``: two independent Latin hypercubes
    (scipy.qmc); ``sobol``: one scrambled 2d-dimensional Sobol' sequence split in halves, as
    SALib's Saltelli sampler does (n should be a power of 2).  :func:`base_blocks` draws the
    same numbers a block of rows at a time.  Given an :class:`Inputs` for ``d``, A and B are
    mapped through its laws (the same unit-cube points, :meth:`Inputs.from_unit`).

    Parameters
    ----------
    n : int
        Base rows N (>= 2).
    d : int or Inputs
        The number of inputs D, or the inputs themselves (designs in their units).
    method : {"mc", "lhs", "sobol"}
        The design.
    seed : None, int, SeedSequence or numpy.random.Generator
        The randomness (:func:`mtaccuracy.validate.rng`).

    Returns
    -------
    a, b : arrays (n, D)
        In [0, 1) (or the inputs' units, given an :class:`Inputs`).
    """
    n = _check_method(n, method)
    (a, b), = base_blocks(n, d, method=method, seed=seed, rows=n)   # to the end: a Generator too
    return a, b


@dataclass(frozen=True)
class SobolDesign:
    """The A and B designs of a Sobol' estimate, described instead of held.

    :func:`sobol_indices` draws them a block of base rows at a time (:func:`base_blocks`), so
    its memory does not grow with N.

    ``SobolDesign(n, inputs, method=, seed=)`` with an :class:`Inputs` draws the designs through
    its laws and names the inputs of the result; ``SobolDesign(n, d, ..., to_inputs=f)`` maps
    the unit cube with any row-by-row ``f`` (the two are the same numbers when ``f`` is
    :meth:`Inputs.from_unit`).

    Attributes
    ----------
    n : int
        Base rows N (N (D + 2) model runs).
    d : int or Inputs
        Inputs D, or the inputs themselves (then ``d`` becomes D and :attr:`inputs` holds them).
    method : {"mc", "lhs", "sobol"}
        The design on the unit cube (``lhs`` is held whole: see :func:`base_blocks`).
    seed : None, int, SeedSequence or numpy.random.Generator
        The randomness (:func:`mtaccuracy.validate.rng`).
    to_inputs : callable, optional
        Unit-cube rows (m, d) to model inputs (m, d), row by row (e.g.
        ``lambda u: sd * scipy.special.ndtri(u)``); default: through :attr:`inputs`, else the
        unit cube itself.
    inputs : Inputs or None
        Set from ``d`` (not an argument); their names label :func:`sobol_indices`' result.
    """

    n: int
    d: int
    _: KW_ONLY
    method: str = "sobol"
    seed: object = None
    to_inputs: Callable[[np.ndarray], np.ndarray] | None = None
    inputs: Inputs | None = field(init=False, default=None)

    def __post_init__(self):
        d, inputs = _dim(self.d)
        if inputs is not None and self.to_inputs is not None:
            raise ValueError("give either inputs or to_inputs, not both")
        object.__setattr__(self, "d", d)
        object.__setattr__(self, "inputs", inputs)

    def blocks(self, rows: int = BASE_ROWS) -> Iterator[tuple[np.ndarray, np.ndarray]]:
        """``(a, b)`` blocks of at most ``rows`` rows, mapped to the model's inputs.

        Parameters
        ----------
        rows : int
            Rows per block.

        Yields
        ------
        a, b : arrays (m, d)
        """
        if self.to_inputs is None:      # the inputs' own designs (or the unit cube's)
            d = self.inputs if self.inputs is not None else self.d
            yield from base_blocks(self.n, d, method=self.method, seed=self.seed, rows=rows)
            return
        f = self.to_inputs
        for ua, ub in base_blocks(self.n, self.d, method=self.method, seed=self.seed, rows=rows):
            a = np.asarray(f(ua), dtype=float)
            del ua              # the unit-cube block is not kept beside the inputs
            b = np.asarray(f(ub), dtype=float)
            del ub
            yield a, b
            del a, b            # nor this block beside the next one

    def arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """The whole A and B, (N, D) each, mapped to the model's inputs.

        Returns
        -------
        a, b : arrays (N, D)
        """
        (a, b), = self.blocks(rows=self.n)
        return a, b


def _model_runs(model, n, d, chunk, progress):
    """``run(x)``: ``model`` on the (m, D) array x as an (m, q) float array, ``chunk`` rows
    per call, counting the runs against the N(D+2) of a Sobol design for ``progress``."""
    total = n * (d + 2)
    done = 0

    def run(x):
        nonlocal done
        out = []
        for s in range(0, x.shape[0], chunk):
            y = np.asarray(model(x[s:s + chunk]), dtype=float)
            out.append(y[:, None] if y.ndim == 1 else y)
            done += out[-1].shape[0]
            if progress:
                progress(done, total)
        return out[0] if len(out) == 1 else np.concatenate(out)
    return run


def _ab_blocks(a: np.ndarray, b: np.ndarray, chunk: int):
    """Yields ``(i0, i1, x)``: x the rows of AB_i0 ... AB_i(1-1) stacked, ((i1 - i0) N, D).

    As many AB blocks as fit in ``chunk`` rows go together (one block when N > chunk).  The
    blocks live in one buffer filled with A once: each step puts back the A columns the
    previous step replaced and takes the new ones from B, so a step writes 2 N values per
    block instead of copying A (N D values).  The model must not keep or modify its input."""
    n, d = a.shape
    rows = max(1, min(d, chunk // n))
    buf = np.repeat(a[None], rows, axis=0)                      # (rows, N, D)
    prev = []
    for i0 in range(0, d, rows):
        i1 = min(i0 + rows, d)
        for k, i in enumerate(prev):
            buf[k, :, i] = a[:, i]
        prev = list(range(i0, i1))
        for k, i in enumerate(prev):
            buf[k, :, i] = b[:, i]
        yield i0, i1, buf[:i1 - i0].reshape(-1, d)


def _check_ab(a, b):
    if isinstance(a, SobolDesign):
        if b is not None:
            raise ValueError("give either a SobolDesign or the arrays A and B, not both")
        a, b = a.arrays()
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    if a.shape != b.shape or a.ndim != 2:
        raise ValueError(f"A and B must be (N, D) arrays of one shape, got {a.shape}, {b.shape}")
    return a, b


def sobol_evaluate(model: Callable[[np.ndarray], np.ndarray], a, b: np.ndarray | None = None,
                   *, chunk: int = 200_000, progress: Callable[[int, int], None] | None = None
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Run ``model`` on A, B and every AB_i: ``ya`` (N, q), ``yb`` (N, q) and ``yab`` (D, N, q).

    ``model`` maps an (m, D) array to (m, q) (or (m,)) outputs, and must not modify its
    input.  Runs are batched ``chunk`` rows at a time: N(D+2) model runs in about
    N(D+2)/chunk calls.  ``progress(done, total)`` is called after each call with the number
    of runs done.  ``yab`` holds D N q floats: when only the indices are wanted,
    :func:`sobol_indices` gives them without it.

    Parameters
    ----------
    model : callable
        ``(m, D) -> (m, q)`` or ``(m,)``.
    a : array (N, D) or SobolDesign
        The design A, or a :class:`SobolDesign` (then drawn whole; ``b`` is not given).
    b : array (N, D), optional
        The design B.
    chunk : int
        Model runs per call (>= 1).
    progress : callable, optional
        ``progress(done, total)`` after each call.

    Returns
    -------
    ya, yb : arrays (N, q)
        The outputs on A and on B.
    yab : array (D, N, q)
        The outputs on every AB_i.
    """
    chunk = integer(chunk, "chunk", low=1)
    a, b = _check_ab(a, b)
    n, d = a.shape
    run = _model_runs(model, n, d, chunk, progress)
    ya, yb = run(a), run(b)
    yab = np.empty((d, n, ya.shape[1]))
    for i0, i1, x in _ab_blocks(a, b, chunk):
        yab[i0:i1] = run(x).reshape(i1 - i0, n, -1)
    return ya, yb, yab


#: floats per temporary in :func:`sobol_estimate` (inputs are taken a few at a time)
_ESTIMATE_BLOCK = 2**21


def sobol_estimate(ya: np.ndarray, yb: np.ndarray, yab: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray]:
    """First-order (Saltelli 2010) and total (Jansen) indices, each (D, q), as SALib computes them.

    On outputs standardised over all runs as SALib does.  Works on leading bootstrap axes
    too: ``ya`` (..., N, q), ``yab`` (..., D, N, q).

    The inputs are taken a few at a time, so the temporaries stay near ``_ESTIMATE_BLOCK``
    floats whatever D and N (the estimate of every input is the same expression).

    Parameters
    ----------
    ya, yb : arrays (..., N, q)
        Outputs on A and B.
    yab : array (..., D, N, q)
        Outputs on every AB_i.

    Returns
    -------
    s1, st : arrays (..., D, q)
        First-order and total indices, inputs by outputs.
    """
    ya, yb, yab = (np.asarray(v, dtype=float) for v in (ya, yb, yab))
    n, d = ya.shape[-2], yab.shape[-3]
    mu = (ya.sum(-2) + yb.sum(-2) + yab.sum((-3, -2))) / (n * (d + 2))
    var = np.var(np.concatenate([ya, yb], axis=-2), axis=-2)[..., None, :]
    w = (yb - mu[..., None, :])[..., None, :, :]
    s1 = np.empty(yab.shape[:-2] + ya.shape[-1:])
    st = np.empty_like(s1)
    step = max(1, _ESTIMATE_BLOCK // max(1, yab[..., :1, :, :].size))
    for i0 in range(0, d, step):
        diff = yab[..., i0:i0 + step, :, :] - ya[..., None, :, :]
        s1[..., i0:i0 + step, :] = np.mean(w * diff, axis=-2)
        np.square(diff, out=diff)
        st[..., i0:i0 + step, :] = 0.5 * np.mean(diff, axis=-2)
    return s1 / var, st / var


def _row_blocks(a, b, rows, cap=None):
    """(n, d, inputs, iterator of (a, b) row blocks) of a :class:`SobolDesign` or arrays A, B;
    ``cap(d)``, when given, bounds the rows of a block."""
    rows = integer(rows, "rows", low=1)
    if isinstance(a, SobolDesign):
        if b is not None:
            raise ValueError("give either a SobolDesign or the arrays A and B, not both")
        _check_method(a.n, a.method)
        rows = rows if cap is None else min(rows, cap(int(a.d)))
        return int(a.n), int(a.d), a.inputs, a.blocks(rows)
    a, b = _check_ab(a, b)
    n = a.shape[0]
    rows = rows if cap is None else min(rows, cap(a.shape[1]))
    return n, a.shape[1], None, ((a[s:s + rows], b[s:s + rows]) for s in range(0, n, rows))


#: Floats of the bootstrap weights of one block (``n_boot`` per base row) in
#: :func:`sobol_indices`: 32 MB.
BOOT_FLOATS = 2**22


def _sum(terms):
    """Left-to-right sum of a list of arrays (one term: that term, bitwise)."""
    out = terms[0]
    for t in terms[1:]:
        out = out + t
    return out


def sobol_indices(model: Callable[[np.ndarray], np.ndarray], a, b: np.ndarray | None = None,
                  *, chunk: int = 200_000, progress: Callable[[int, int], None] | None = None,
                  rows: int = BASE_ROWS, outputs: Sequence[str] | None = None,
                  n_boot: int | None = None, seed=None, conf: float = 0.95) -> SobolIndices:
    """First-order and total Sobol indices of ``model``, streaming over base rows and AB runs.

    The estimators are Saltelli et al. 2010 (first order) and Jansen 1999 (total), on outputs
    standardised over all N (D + 2) runs, as SALib's ``sobol.analyze``; the numbers equal
    :func:`sobol_estimate` on :func:`sobol_evaluate` within rounding (a test checks 1e-12)
    without ever holding ``yab`` (D N q floats: 200 MB for 41 inputs, N = 1e5, six outputs).
    Given a :class:`SobolDesign`, the base rows are drawn ``rows`` at a time too, and memory is
    that of one block whatever N (``lhs`` designs excepted, see :func:`base_blocks`).

    With ``n_boot``, the result carries bootstrap intervals too, streamed like the indices: the
    Poisson bootstrap of :mod:`~mtaccuracy.sensitivity.bootstrap` (every row's count in every
    resample an independent Poisson(1) draw of ``seed``, drawn with its block, so the resamples
    do not depend on the blocks), whose weighted sums are accumulated block by block
    (:class:`~mtaccuracy.sensitivity.StreamedBootstrap`): memory flat in N (about 0.2 GB at
    D = 41, q = 6, n_boot = 500, whatever N; the held bootstrap of :func:`sobol_evaluate` and
    :func:`~mtaccuracy.sensitivity.sobol_bootstrap_samples` needs 16 kB per base row).  A block
    then holds at most ``min(rows, chunk // D, BOOT_FLOATS // n_boot)`` base rows (all its AB
    runs in one model call, its weights at most :data:`BOOT_FLOATS` floats), so with more than
    that many rows the indices differ from those without ``n_boot`` by rounding (pooled blocks).
    The resamples are not those of :func:`~mtaccuracy.sensitivity.sobol_bootstrap` (which
    draws N rows with replacement): the half-widths agree to their Monte Carlo noise.

    Parameters
    ----------
    model : callable
        ``(m, D)`` inputs to ``(m, q)`` (or ``(m,)``) outputs; must not modify its input (the
        AB blocks share one buffer).
    a : SobolDesign or array (N, D)
        The design, drawn block by block; or the design A (:func:`base_samples`, mapped to the
        input laws), taken block by block.
    b : array (N, D), optional
        The design B, with an array ``a``.
    chunk : int
        Model runs per call.
    progress : callable, optional
        ``progress(done, total)`` after each call, counting runs.
    rows : int
        Base rows per block (:data:`BASE_ROWS`).  With N <= ``rows`` (and no ``n_boot``) the
        result is bitwise that of a whole-array pass; with more blocks it differs by rounding
        only.
    outputs : sequence of str (q,), optional
        Names of the model's outputs (default ``y1`` ... ``yq``), for :meth:`SobolIndices.to_df`.
    n_boot : int, optional
        Bootstrap resamples (>= 2) of the intervals; none by default.
    seed : None, int, SeedSequence or numpy.random.Generator
        The randomness of the resampling (:func:`mtaccuracy.validate.rng`), with ``n_boot``.
    conf : float
        Confidence level of the intervals, in (0, 1).

    Returns
    -------
    SobolIndices
        Unpacks as ``s1, st``, (D, q) arrays of first-order and total indices; labelled with
        the design's input names (a :class:`SobolDesign` of an :class:`Inputs`; else ``x1``
        ... ``xD``) and ``outputs``.  With ``n_boot``: the half-widths ``s1_ci``, ``st_ci``
        (normal quantile times the bootstrap standard deviation, as SALib's) and the
        re-estimates ``s1_boot``, ``st_boot`` (n_boot, D, q) (e.g. for
        :func:`~mtaccuracy.sensitivity.key_set_bootstrap`).

    Notes
    -----
    Each block k of m_k base rows runs A and B, then each AB_i batch, which adds its per-input
    sums of ``yab_i - ya``, ``(yb - c_k)(yab_i - ya)`` and ``(yab_i - ya)^2`` and is dropped;
    ``c_k`` is the block's mean of ``ya`` and ``yb``.  At the end the overall mean ``mu`` enters
    (``sum((yb - mu) d) = sum((yb - c_k) d) - (mu - c_k) sum(d)``, without cancellation because
    the outputs are centred) and the block variances are pooled exactly
    (``sum_k w_k (var_k + (c_k - c)^2)``, ``w_k = m_k / N``).  Memory: one block of A and B, one
    batch of ``chunk`` runs, its ``ya`` and ``yb``, and three (D, q) sums per block.
    """
    chunk = integer(chunk, "chunk", low=1)
    cap = None
    if n_boot is not None:
        n_boot = integer(n_boot, "n_boot", low=2)
        if not 0 < conf < 1:    # an open interval: validate.probability allows 0 and 1
            raise ValueError(f"conf must be in (0, 1), got {conf!r}")

        def cap(d):
            return max(1, min(chunk // d, BOOT_FLOATS // n_boot))
    n, d, inputs, blocks = _row_blocks(a, b, rows, cap)
    boot = None if n_boot is None else StreamedBootstrap(n_boot, seed, d=d)
    run = _model_runs(model, n, d, chunk, progress)
    parts = []
    for ab, bb in blocks:
        m = ab.shape[0]
        ya, yb = run(ab), run(bb)
        q = ya.shape[1]
        both = np.concatenate([ya, yb])
        centre, var = both.mean(0), both.var(0)
        ybc = yb - centre
        total = both.sum(0)
        if boot is not None:
            w = boot.weights(m)
            boot.add_base(w, ya, yb)
        sd_, sbd, sd2 = np.empty((d, q)), np.empty((d, q)), np.empty((d, q))
        for i0, i1, x in _ab_blocks(ab, bb, chunk):
            y = run(x).reshape(i1 - i0, m, q)
            total += y.sum((0, 1))
            diff = y - ya                   # a new array: y may be a view of the model's input
            sd_[i0:i1] = diff.sum(1)
            sbd[i0:i1] = np.einsum("inq,nq->iq", diff, ybc)
            sd2[i0:i1] = np.einsum("inq,inq->iq", diff, diff)
            if boot is not None:
                boot.add_inputs(w, i0, i1, diff, ya, yb)
        parts.append((m / n, centre, var, total, sd_, sbd, sd2))
        del ab, bb, x, ya, yb, both, ybc, y, diff   # before the next block is drawn
        w = None
    w, centre, var, total, sd_, sbd, sd2 = zip(*parts, strict=True)
    mu = _sum(total) / (n * (d + 2))
    c = _sum([wk * ck for wk, ck in zip(w, centre, strict=True)])
    var = _sum([wk * (vk + (ck - c) ** 2) for wk, vk, ck in zip(w, var, centre, strict=True)])
    num = _sum([sb - (mu - ck) * s for sb, ck, s in zip(sbd, centre, sd_, strict=True)])
    names = inputs.names if inputs is not None else None
    if boot is None:
        return SobolIndices(num / (n * var), 0.5 * _sum(sd2) / (n * var), names=names,
                            outputs=outputs)
    s1_boot, st_boot = boot.estimates()
    return SobolIndices(num / (n * var), 0.5 * _sum(sd2) / (n * var), names=names,
                        outputs=outputs, s1_ci=ci_half_width(s1_boot, conf),
                        st_ci=ci_half_width(st_boot, conf), conf=conf, s1_boot=s1_boot,
                        st_boot=st_boot)


class SobolIndices(tuple):
    """First-order and total indices (D, q) labelled by input and output, with their intervals.

    A pair ``(s1, st)`` (it unpacks and indexes as the tuple the estimators always returned)
    that also knows the input and output names and, when given, the half-widths of the
    confidence intervals (:func:`sobol_bootstrap`, :func:`ci_half_width`); :meth:`to_df` is
    the long table SALib's ``to_df()`` gives, so a notebook does not rebuild it in a loop.

    >>> r = SobolIndices(np.array([[0.6], [0.3]]), np.array([[0.7], [0.3]]), names=["a", "b"])
    >>> r.to_df().to_dict("list")
    {'output': ['y1', 'y1'], 'input': ['a', 'b'], 'S1': [0.6, 0.3], 'ST': [0.7, 0.3]}

    One output's indices may be given as (D,) arrays (:func:`~mtaccuracy.sensitivity.pce_sobol`
    returns them so): they stay (D,), and the table has one output.

    Parameters
    ----------
    s1, st : (D, q) or (D,) array_like
        First-order and total indices, inputs by outputs.
    names : sequence of str (D,), optional
        Input names (default ``x1`` ... ``xD``).
    outputs : sequence of str (q,), optional
        Output names (default ``y1`` ... ``yq``).
    s1_ci, st_ci : array_like, the shape of ``s1``, optional
        Half-widths of their ``conf`` confidence intervals.
    conf : float
        The confidence level of the half-widths (names their columns: ``S1_ci95``).
    s1_boot, st_boot : (n_boot, D, q) array_like, optional
        The bootstrap re-estimates the half-widths come from (e.g. for
        :func:`~mtaccuracy.sensitivity.key_set_bootstrap`).

    Raises
    ------
    ValueError
        If the arrays are not (D, q) (or (D,)) of one shape or the names do not match it.
    """

    def __new__(cls, s1, st, *, names: Sequence[str] | None = None,
                outputs: Sequence[str] | None = None, s1_ci=None, st_ci=None,
                conf: float = 0.95, s1_boot=None, st_boot=None) -> SobolIndices:
        s1, st = np.asarray(s1, dtype=float), np.asarray(st, dtype=float)
        if s1.ndim not in (1, 2) or st.shape != s1.shape:
            raise ValueError(f"s1 and st must be (D, q) arrays of one shape, got {s1.shape}, "
                             f"{st.shape}")
        d, q = s1.shape if s1.ndim == 2 else (s1.shape[0], 1)
        cis = [None if c is None else np.asarray(c, dtype=float) for c in (s1_ci, st_ci)]
        if any(c is not None and c.shape != s1.shape for c in cis):
            raise ValueError(f"s1_ci and st_ci must be {s1.shape} like the indices")
        names = tuple(f"x{i + 1}" for i in range(d)) if names is None else tuple(names)
        outputs = tuple(f"y{k + 1}" for k in range(q)) if outputs is None else tuple(outputs)
        if len(names) != d or len(outputs) != q:
            raise ValueError(f"{len(names)} input and {len(outputs)} output names for "
                             f"indices of {d} inputs and {q} outputs")
        boots = [None if x is None else np.asarray(x, dtype=float) for x in (s1_boot, st_boot)]
        if any(x is not None and (x.ndim != s1.ndim + 1 or x.shape[1:] != s1.shape)
               for x in boots):
            shape = ", ".join(map(str, s1.shape))
            raise ValueError(f"s1_boot and st_boot must be (n_boot, {shape})")
        self = super().__new__(cls, (s1, st))
        self.names, self.outputs, self.conf = names, outputs, float(conf)
        self.s1_ci, self.st_ci = cis
        self.s1_boot, self.st_boot = boots
        return self

    @property
    def s1(self) -> np.ndarray:
        """(D, q) (or (D,)) ndarray: the first-order indices."""
        return self[0]

    @property
    def st(self) -> np.ndarray:
        """(D, q) (or (D,)) ndarray: the total indices."""
        return self[1]

    def to_df(self) -> pd.DataFrame:
        """The indices as a long table: one row per (output, input), outputs outermost.

        Returns
        -------
        pandas.DataFrame
            Columns ``output``, ``input``, ``S1``, ``ST``, and with intervals ``S1_ci95``
            after ``S1`` and ``ST_ci95`` after ``ST`` (the level in the name: half-widths).
        """
        d, q = len(self.names), len(self.outputs)
        cols = {"output": np.repeat(self.outputs, d).tolist(), "input": list(self.names) * q}
        tag = f"_ci{100 * self.conf:g}"
        for key, val, ci in (("S1", self.s1, self.s1_ci), ("ST", self.st, self.st_ci)):
            cols[key] = val.T.ravel()
            if ci is not None:
                cols[key + tag] = ci.T.ravel()
        return pd.DataFrame(cols)


# --------------------------------------------------------------------------------------------
# Floating-point resolution of the estimates (the tie rule built on it: tie_rule.ties).
# --------------------------------------------------------------------------------------------

#: Absolute floating-point resolution declared for Sobol indices estimated from model outputs
#: of a few hundredths of a mm computed from poses of hundreds of mm.  Such an output carries a
#: rounding error of about eps x 1000 mm = 2e-13 mm (measured across OpenBLAS kernels:
#: 2.3e-13 mm), 5e-12 of its standard deviation.  S1 is a mean over N rows of (yb - mu) times
#: the difference of two outputs, divided by the variance: each term carries 5e-12, so the
#: index carries at most 5e-12 (all terms of one sign) and typically 5e-12 / sqrt(N) = 6e-14
#: at N = 8192 (measured across kernels: 5e-14).  ST is a mean of squared differences: its
#: rounding is smaller still.  1e-11 is twice the worst case.  The sampling uncertainty (the
#: bootstrap half-widths, 1e-3 for the leading indices) is a different, far larger thing.
FLOAT_NOISE = 1e-11

# The tie rule built on this resolution (``TIE_REL``, ``TIE_ABS``, ``merge_ties``) is a key-set
# rule: it lives in :mod:`.tie_rule` (imported by :mod:`.screening`), which imports this module,
# never the reverse.
