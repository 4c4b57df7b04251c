"""A genetic algorithm batched over independent runs, for any vectorised objective.

The algorithm knows nothing of what it optimises: it takes an ``objective`` that maps genes
``(runs, population, d)`` (decoded into the search box) to values to minimise ``(runs,
population)``, a ``fitness`` that turns those values into non-negative selection weights, and an
*encoding* (:class:`RealEncoding`, :class:`BinaryEncoding`) that owns how genes are stored,
drawn, crossed and mutated.  Every step is an array over (runs, population); the only Python
loop is over generations.

The scheme: uniform initial population; roulette-wheel (fitness-proportional) selection;
consecutive selected parents paired and crossed with probability ``Pc`` per pair; every child
mutated with probability ``Pm`` per gene (real) or per bit (binary); elitism (the best so far
replaces the worst child).  The rates are fixed, or adaptive (:func:`adaptive_rates`: the rule of
Yang et al. 2021, Eqs. 22-23, with ``Pc`` per pair from the fitter parent and ``Pm`` per child
from its own parent).

Hand-written rather than taken from a library (DEAP, pymoo, scipy) because the adaptive rates are
what the paper contributes and because hundreds of independent runs must be batched, which those
libraries do one run at a time.  Ties (equal values in a population) go to the lowest index, so a
run is a function of its random numbers only.
"""

from __future__ import annotations

__all__ = ["GAResult", "RealEncoding", "BinaryEncoding", "adaptive_rates", "reciprocal_fitness",
           "run_ga"]

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .. import validate


@dataclass
class GAResult:
    """Runs of a genetic algorithm (or of differential evolution), batched over runs.

    Attributes
    ----------
    best_x : array (runs, d)
        Best genes found (decoded).
    best_h : array (runs,)
        Best objective.
    history : array (generations + 1, runs)
        Best-so-far objective; row 0 is the initial population.
    pc, pm : arrays (generations + 1,)
        Mean crossover and mutation probabilities used.
    evaluations_per_generation : int
        Objective evaluations per generation and run.
    label : str
        A name for tables and legends.
    """

    best_x: np.ndarray      # (runs, d) best genes found (decoded)
    best_h: np.ndarray      # (runs,) best objective
    history: np.ndarray     # (generations + 1, runs) best-so-far objective; row 0 = initial pop.
    pc: np.ndarray          # (generations + 1,) mean crossover probability used
    pm: np.ndarray          # (generations + 1,) mean mutation probability used
    evaluations_per_generation: int
    label: str = ""


def _box(lo, hi):
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    if lo.ndim != 1 or lo.shape != hi.shape or not np.all(np.isfinite(lo) & np.isfinite(hi)) \
            or np.any(lo >= hi):
        raise ValueError(f"the search box needs finite low < high per gene, got {lo}, {hi}")
    return lo, hi


def _reflect(x, lo, hi):
    w = hi - lo
    y = np.mod(x - lo, 2 * w)
    return lo + np.where(y > w, 2 * w - y, y)


class RealEncoding:
    """Genes stored as their values in the box ``[lo, hi]`` (each (d,)).

    Crossover: arithmetic, ``c1 = b x1 + (1 - b) x2``, ``c2 = (1 - b) x1 + b x2`` with
    ``b ~ U(0, 1)`` per gene.  Mutation: a Gaussian step of ``mutation_scale`` x the gene's range,
    reflected into the box.

    Parameters
    ----------
    lo, hi : arrays (d,)
        Lower and upper bound of each gene (low < high, finite).
    mutation_scale : float
        Standard deviation of a mutation step, as a share of the gene's range.
    """

    def __init__(self, lo, hi, mutation_scale: float = 0.1):
        self.lo, self.hi = _box(lo, hi)
        if not mutation_scale > 0:
            raise ValueError(f"mutation_scale must be > 0, got {mutation_scale!r}")
        self.mutation_scale = float(mutation_scale)
        self.name = "real"

    @property
    def n_genes(self) -> int:
        """int: the number of genes d."""
        return self.lo.shape[0]

    def initial(self, rng, runs: int, pop: int) -> np.ndarray:
        """A uniformly random initial population, genes stored as values in the box.

        Parameters
        ----------
        rng : numpy.random.Generator
            The stream the population is drawn from.
        runs, pop : int
            Independent runs, and individuals per run.

        Returns
        -------
        (runs, pop, d) ndarray
            The genotypes.
        """
        return self.lo + rng.random((runs, pop, self.n_genes)) * (self.hi - self.lo)

    def decode(self, geno) -> np.ndarray:
        """Genotypes to gene values in the box.

        Parameters
        ----------
        geno : (..., d) array
            Genotypes as :meth:`initial` stores them.

        Returns
        -------
        (..., d) ndarray
            Gene values in ``[lo, hi]`` (the units of the box).
        """
        return geno

    def crossover(self, a, b, cross, *, rng):
        """Cross paired parents where ``cross`` holds: arithmetic crossover per gene.

        Parameters
        ----------
        a, b : (runs, pop // 2, d) array
            The paired parents' genotypes.
        cross : (runs, pop // 2, 1) array of bool
            Which pairs cross; the others are copied.
        rng : numpy.random.Generator
            The stream the crossover weights or cut points are drawn from.

        Returns
        -------
        c1, c2 : (runs, pop // 2, d) ndarray
            The children's genotypes.
        """
        beta = rng.random(a.shape)
        return (np.where(cross, beta * a + (1 - beta) * b, a),
                np.where(cross, (1 - beta) * a + beta * b, b))

    def mutate(self, child, pm, rng) -> np.ndarray:
        """Mutate children: per gene, with probability ``pm``, a Gaussian step (reflected).

        Parameters
        ----------
        child : (runs, pop, d) array
            The children's genotypes.
        pm : (runs, pop) array
            Mutation probability per individual.
        rng : numpy.random.Generator
            The stream the mutations are drawn from.

        Returns
        -------
        (runs, pop, d) ndarray
            The mutated genotypes.
        """
        mut = rng.random(child.shape) < pm[..., None]
        step = rng.normal(size=child.shape) * self.mutation_scale * (self.hi - self.lo)
        return _reflect(np.where(mut, child + step, child), self.lo, self.hi)


class BinaryEncoding:
    """Each gene a ``bits``-bit integer over its range (the classic GA of the toolboxes).

    The d genes form one string of ``d * bits`` bits, most significant first.  Crossover: single
    point on the string.  Mutation: each bit flipped with probability ``Pm``.  Genes are stored
    as the integers (runs, pop, d); random bits are drawn as the string and packed exactly (sums
    of powers of two below 2**53).

    Parameters
    ----------
    lo, hi : arrays (d,)
        Lower and upper bound of each gene (low < high, finite).
    bits : int
        Bits per gene, 2 to 30 (the resolution is ``(hi - lo) / (2**bits - 1)``).
    """

    def __init__(self, lo, hi, bits: int = 16):
        self.lo, self.hi = _box(lo, hi)
        self.bits = validate.integer(bits, "bits", low=2, high=30)
        self._pow2 = 2.0 ** np.arange(self.bits - 1, -1, -1)
        self.name = "binary"

    @property
    def n_genes(self) -> int:
        """int: the number of genes d."""
        return self.lo.shape[0]

    def _pack(self, bitstring):
        d = self.n_genes
        return (bitstring.reshape(bitstring.shape[:-1] + (d, self.bits)) @ self._pow2
                ).astype(np.int64)

    def initial(self, rng, runs: int, pop: int) -> np.ndarray:
        """A uniformly random initial population, genes stored as ``bits``-bit integers (int64).

        Parameters
        ----------
        rng : numpy.random.Generator
            The stream the population is drawn from.
        runs, pop : int
            Independent runs, and individuals per run.

        Returns
        -------
        (runs, pop, d) ndarray
            The genotypes.
        """
        return self._pack(rng.random((runs, pop, self.n_genes * self.bits)) < 0.5)

    def decode(self, geno) -> np.ndarray:
        """Genotypes to gene values in the box.

        Parameters
        ----------
        geno : (..., d) array
            Genotypes as :meth:`initial` stores them.

        Returns
        -------
        (..., d) ndarray
            Gene values in ``[lo, hi]`` (the units of the box).
        """
        return self.lo + (self.hi - self.lo) * geno / (2.0 ** self.bits - 1)

    def crossover(self, a, b, cross, *, rng):
        """Cross paired parents where ``cross`` holds: single point on the bit string.

        Parameters
        ----------
        a, b : (runs, pop // 2, d) array
            The paired parents' genotypes.
        cross : (runs, pop // 2, 1) array of bool
            Which pairs cross; the others are copied.
        rng : numpy.random.Generator
            The stream the crossover weights or cut points are drawn from.

        Returns
        -------
        c1, c2 : (runs, pop // 2, d) ndarray
            The children's genotypes.
        """
        d, bits = self.n_genes, self.bits
        cut = rng.integers(1, d * bits, size=a.shape[:-1] + (1,))
        # single-point crossover at bit `cut` of the string: the tail of gene i is its last
        # bits - clip(cut - i * bits, 0, bits) bits
        tail_bits = bits - np.clip(cut - np.arange(d) * bits, 0, bits)
        swap = np.where(cross, (np.int64(1) << tail_bits) - 1, 0)
        return (a & ~swap) | (b & swap), (b & ~swap) | (a & swap)

    def mutate(self, child, pm, rng) -> np.ndarray:
        """Mutate children: each bit of the string flipped with probability ``pm``.

        Parameters
        ----------
        child : (runs, pop, d) array
            The children's genotypes.
        pm : (runs, pop) array
            Mutation probability per individual.
        rng : numpy.random.Generator
            The stream the mutations are drawn from.

        Returns
        -------
        (runs, pop, d) ndarray
            The mutated genotypes.
        """
        flips = rng.random(child.shape[:-1] + (self.n_genes * self.bits,)) < pm[..., None]
        return child ^ self._pack(flips)


def adaptive_rates(f, f_mean, *, generation, max_generation, pc_max, pc_min, pm_max, pm_min,
                   eq23: str = "corrected"):
    """Adaptive crossover and mutation probabilities (Yang et al. 2021, Eqs. 22-23).

    ``Pc = Pc_max`` if ``F < F_mean``, else ``Pc_max - (Pc_max - Pc_min) alpha / alpha_max``;
    ``Pm = Pm_min`` if ``F < F_mean``, else, as printed (``eq23="printed"``),
    ``Pm_min - (Pm_max - Pm_min) alpha / alpha_max``, which falls from ``Pm_min`` and is negative
    once ``alpha / alpha_max > Pm_min / (Pm_max - Pm_min)`` (after 6 % of the run with the paper's
    bounds, ``mtaccuracy.spindle.PC_MAX`` ... ``PM_MIN``); or corrected (default),
    ``Pm_min + (Pm_max - Pm_min) alpha / alpha_max``, rising as the paper's text describes.
    Returns the raw values (:func:`run_ga` clips ``Pm`` to [0, 1]).

    Parameters
    ----------
    f : array
        Fitness of each individual (any shape).
    f_mean : array
        Mean fitness of its population, broadcasting against ``f``.
    generation : int or array of int
        The generation alpha, 0..max_generation; an array broadcasts against ``f``.
    max_generation : int
        The run's last generation alpha_max (>= 1).
    pc_max, pc_min, pm_max, pm_min : float
        Bounds of the crossover probability (per pair) and of the mutation probability (per
        gene or bit), ``0 <= min <= max <= 1``.
    eq23 : {"corrected", "printed"}
        Which Eq. 23.

    Returns
    -------
    pc, pm : arrays, the broadcast shape of ``f``, ``f_mean`` and ``generation``
        Crossover and mutation probabilities.

    Examples
    --------
    >>> pc, pm = adaptive_rates([1.0, 2.0], 1.5, generation=100, max_generation=200,
    ...                         pc_max=0.99, pc_min=0.4, pm_max=0.09, pm_min=0.005)
    >>> pc.round(4).tolist(), pm.round(4).tolist()
    ([0.99, 0.695], [0.005, 0.0475])
    """
    if eq23 not in ("corrected", "printed"):
        raise ValueError(f"eq23 must be 'corrected' or 'printed', got {eq23!r}")
    max_generation = validate.integer(max_generation, "max_generation", low=1)
    alpha = np.asarray(generation)
    if alpha.dtype.kind not in "iu" and not (alpha.dtype.kind == "f"
                                             and np.all(alpha == np.round(alpha))) \
            or np.any(alpha < 0) or np.any(alpha > max_generation):
        raise ValueError(f"generation must be an integer in [0, max_generation = "
                         f"{max_generation}], got {generation!r}")
    pc_max, pc_min, pm_max, pm_min = (validate.probability(v, n) for v, n in (
        (pc_max, "pc_max"), (pc_min, "pc_min"), (pm_max, "pm_max"), (pm_min, "pm_min")))
    if not (pc_min <= pc_max and pm_min <= pm_max):
        raise ValueError(f"need pc_min <= pc_max and pm_min <= pm_max, got pc {pc_min}, {pc_max}; "
                         f"pm {pm_min}, {pm_max}")
    f = np.asarray(f, dtype=float)
    above = f >= np.asarray(f_mean, dtype=float)
    frac = generation / max_generation
    pc = np.where(above, pc_max - (pc_max - pc_min) * frac, pc_max)
    sign = 1.0 if eq23 == "corrected" else -1.0
    pm = np.where(above, pm_min + sign * (pm_max - pm_min) * frac, pm_min)
    return pc, pm


def reciprocal_fitness(h) -> np.ndarray:
    """Selection weights ``F = 1/h`` of values to minimise; 0 where ``h`` is not finite and > 0.

    The default of :func:`run_ga`; for a layout's ``H`` it is Yang et al. 2021, Eq. 21.

    Parameters
    ----------
    h : array
        Objective values (any shape); smaller is better.

    Returns
    -------
    array
        F, the shape of ``h``.
    """
    h = np.asarray(h, dtype=float)
    with np.errstate(divide="ignore"):
        return np.where(np.isfinite(h) & (h > 0), 1.0 / h, 0.0)


def _roulette(f, rng, rows):
    """Fitness-proportional selection per run: ``(runs, pop)`` indices, by a batched binary
    search of ``u`` in the cumulative probabilities (a uniform choice where all fitness is 0)."""
    s, p = f.shape
    total = f.sum(axis=1, keepdims=True)
    prob = np.where(total > 0, f / np.where(total > 0, total, 1), 1.0 / p)
    cum = np.cumsum(prob, axis=1)
    u = rng.random((s, p))
    low_i = np.zeros((s, p), dtype=np.int64)
    high_i = np.full((s, p), p, dtype=np.int64)
    for _ in range(int(np.ceil(np.log2(p))) + 1):
        mid = (low_i + high_i) // 2
        below = cum[rows, np.minimum(mid, p - 1)] < u
        active = low_i < high_i
        low_i = np.where(active & below, mid + 1, low_i)
        high_i = np.where(active & ~below, mid, high_i)
    return np.minimum(low_i, p - 1)


def run_ga(objective: Callable[[np.ndarray], np.ndarray], encoding, *, n_runs: int = 32,
           pop_size: int = 50, generations: int = 200, seed=0,
           fitness: Callable[[np.ndarray], np.ndarray] | None = None,
           adaptive: dict | None = None, pc: float = 0.8, pm: float = 0.05,
           label: str = "") -> GAResult:
    """Minimise ``objective`` with ``n_runs`` independent runs of a genetic algorithm at once.

    Parameters
    ----------
    objective : callable
        Decoded genes ``(runs, pop, d)`` to the values to minimise ``(runs, pop)``.
    encoding : RealEncoding or BinaryEncoding
        Or any object with ``initial(rng, runs, pop)``, ``decode(geno)``,
        ``crossover(a, b, cross, *, rng)`` and ``mutate(child, pm, rng)``.
    n_runs, pop_size, generations : int
        Independent runs (>= 1), individuals per run (even, >= 4: parents are paired),
        generations (>= 1).
    seed : None, int, SeedSequence or numpy.random.Generator
        Seeds one generator for everything (:func:`mtaccuracy.validate.rng`; a Generator is used
        as it is).
    fitness : callable, optional
        Selection weights from the values (default :func:`reciprocal_fitness`, ``1 / value``
        where finite and positive, else 0).
    adaptive : dict, optional
        None for the fixed rates ``pc``, ``pm``; else the keyword arguments of
        :func:`adaptive_rates` (``pc_max, pc_min, pm_max, pm_min, eq23``): ``Pc`` per pair from
        the fitter parent, ``Pm`` per child from its own parent (Yang et al. 2021, Eqs. 22-23).
    pc, pm : float
        The fixed crossover probability per pair and mutation probability per gene or bit.
    label : str
        The result's name in tables and legends.

    Returns
    -------
    GAResult
        The best decoded genes ``(runs, d)`` and values ``(runs,)``, the best-so-far history
        ``(generations + 1, runs)`` and the mean rates used per generation.
    """
    n_runs = validate.integer(n_runs, "n_runs", low=1)
    pop_size = validate.integer(pop_size, "pop_size", low=4)
    generations = validate.integer(generations, "generations", low=1)
    if pop_size % 2:
        raise ValueError(f"pop_size must be even (parents are paired), got {pop_size}")
    pc, pm = validate.probability(pc, "pc"), validate.probability(pm, "pm")
    if adaptive is not None:
        adaptive_rates(1.0, 1.0, generation=0, max_generation=1, **adaptive)   # validates once
    if fitness is None:
        fitness = reciprocal_fitness
    rng = validate.rng(seed)
    s, p = n_runs, pop_size
    geno = encoding.initial(rng, s, p)
    h = objective(encoding.decode(geno))
    ar = np.arange(s)
    rows = ar[:, None]
    ib = np.argmin(h, axis=1)
    best_g, best_h = geno[ar, ib], h[ar, ib]
    hist = [best_h.copy()]
    pcs = [pc if adaptive is None else adaptive["pc_max"]]
    pms = [pm if adaptive is None else adaptive["pm_min"]]
    for g in range(1, generations + 1):
        f = fitness(h)
        idx = _roulette(f, rng, rows)
        par, fpar = geno[rows, idx], f[rows, idx]
        a, b = par[:, 0::2], par[:, 1::2]                    # (s, p/2, genes)
        fa, fb = fpar[:, 0::2], fpar[:, 1::2]
        if adaptive is not None:
            fmean = f.mean(axis=1, keepdims=True)
            at = dict(generation=g, max_generation=generations, **adaptive)
            pc_pair, _ = adaptive_rates(np.maximum(fa, fb), fmean, **at)
            _, pm_ind = adaptive_rates(np.concatenate([fa, fb], 1), fmean, **at)
            pm_ind = np.clip(pm_ind, 0.0, 1.0)
        else:
            pc_pair = np.full((s, p // 2), pc)
            pm_ind = np.full((s, p), pm)
        cross = (rng.random((s, p // 2)) < pc_pair)[..., None]
        c1, c2 = encoding.crossover(a, b, cross, rng=rng)
        geno = encoding.mutate(np.concatenate([c1, c2], axis=1), pm_ind, rng)
        h = objective(encoding.decode(geno))
        # elitism: the best so far replaces the worst child; ties go to the lowest index
        iw = np.argmax(h, axis=1)
        geno[ar, iw] = best_g
        h[ar, iw] = best_h
        ib = np.argmin(h, axis=1)
        better = h[ar, ib] < best_h
        best_g = np.where(better[:, None], geno[ar, ib], best_g)
        best_h = np.where(better, h[ar, ib], best_h)
        hist.append(best_h.copy())
        pcs.append(float(pc_pair.mean()))
        pms.append(float(pm_ind.mean()))
    return GAResult(best_x=encoding.decode(best_g), best_h=best_h, history=np.array(hist),
                    pc=np.array(pcs), pm=np.array(pms), evaluations_per_generation=p,
                    label=label)
