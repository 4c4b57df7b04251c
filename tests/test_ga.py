"""The generic genetic algorithm (mtaccuracy.optimise.ga): any vectorised objective, two
encodings, fixed or adaptive rates, no knowledge of what it optimises."""

import subprocess
import sys

import numpy as np
import pytest

from mtaccuracy.optimise import ga

LO, HI = np.full(3, -2.0), np.full(3, 3.0)


def sphere(x):                       # (runs, pop, 3) -> (runs, pop); minimum 0 at (1, 1, 1)
    return ((x - 1.0) ** 2).sum(-1) + 1e-12


@pytest.mark.parametrize("encoding", [ga.RealEncoding(LO, HI, 0.05), ga.BinaryEncoding(LO, HI, 20)])
@pytest.mark.parametrize("adaptive", [None, dict(pc_max=0.99, pc_min=0.4, pm_max=0.09,
                                                 pm_min=0.005)])
def test_it_minimises_a_function_it_knows_nothing_about(encoding, adaptive):
    r = ga.run_ga(sphere, encoding, n_runs=4, pop_size=40, generations=150, seed=1,
                  adaptive=adaptive, pm=0.05)
    assert r.best_x.shape == (4, 3) and r.history.shape == (151, 4)
    assert np.all(np.diff(r.history, axis=0) <= 0)             # elitism: never worse
    assert np.all(r.best_h < 2e-2) and np.abs(r.best_x - 1).max() < 0.15
    again = ga.run_ga(sphere, encoding, n_runs=4, pop_size=40, generations=150, seed=1,
                      adaptive=adaptive, pm=0.05)
    assert np.array_equal(again.best_x, r.best_x)              # a function of the seed only


def test_binary_decoding_spans_the_box_and_genes_stay_inside():
    enc = ga.BinaryEncoding(LO, HI, 8)
    assert np.allclose(enc.decode(np.array([0, 255, 128])), [-2.0, 3.0, -2.0 + 5 * 128 / 255])
    r = ga.run_ga(lambda x: -x.sum(-1) + 100, ga.RealEncoding(LO, HI), n_runs=2, pop_size=10,
                  generations=20, seed=0)
    assert np.all((r.best_x >= LO) & (r.best_x <= HI))


def test_the_module_does_not_import_any_application():
    code = ("import sys, mtaccuracy.optimise.ga; "
            "print(sorted(m for m in sys.modules if m.startswith('mtaccuracy')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == ("['mtaccuracy', 'mtaccuracy.optimise', 'mtaccuracy.optimise.ga', "
                                  "'mtaccuracy.validate']")     # the argument checks only


RATES = dict(pc_max=0.9, pc_min=0.5, pm_max=0.2, pm_min=0.1)


def test_adaptive_rates_branch_on_the_mean_fitness_and_broadcast_the_generation():
    f = np.array([[0.5], [1.0], [2.0]])                        # below, at and above the mean
    pc, pm = ga.adaptive_rates(f, 1.0, generation=np.array([0, 5, 10]), max_generation=10,
                               **RATES)
    assert pc.shape == pm.shape == (3, 3)
    assert np.allclose(pc[0], 0.9) and np.allclose(pm[0], 0.1)     # below the mean: max Pc, min Pm
    assert np.allclose(pc[1:], [0.9, 0.7, 0.5]) and np.allclose(pm[1:], [0.1, 0.15, 0.2])
    _, printed = ga.adaptive_rates(2.0, 1.0, generation=10, max_generation=10, eq23="printed",
                                   **RATES)
    assert printed == pytest.approx(0.0)                        # 0.1 - (0.2 - 0.1) * 1


def test_the_crossover_takes_its_random_stream_by_keyword():
    enc = ga.RealEncoding(LO, HI)
    a, b = np.zeros((1, 2, 3)), np.ones((1, 2, 3))
    with pytest.raises(TypeError):
        enc.crossover(a, b, np.ones((1, 2, 1), bool), np.random.default_rng(0))
    c1, c2 = enc.crossover(a, b, np.ones((1, 2, 1), bool), rng=np.random.default_rng(0))
    assert np.allclose(c1 + c2, a + b)                          # arithmetic crossover keeps sums


@pytest.mark.parametrize("make, message", [
    (lambda: ga.BinaryEncoding(LO, HI, 31), r"bits must be an integer in \[2, 30\], got 31"),
    (lambda: ga.BinaryEncoding(LO, HI, 8.5), r"bits must be an integer in \[2, 30\], got 8.5"),
    (lambda: ga.RealEncoding(HI, LO), "low < high"),
    (lambda: ga.RealEncoding(LO, HI, 0.0), "mutation_scale must be > 0"),
    (lambda: ga.run_ga(sphere, ga.RealEncoding(LO, HI), pop_size=7), "even"),
    (lambda: ga.run_ga(sphere, ga.RealEncoding(LO, HI), pm=2.0),
     r"pm must be a probability in \[0, 1\], got 2.0"),
    (lambda: ga.run_ga(sphere, ga.RealEncoding(LO, HI), pop_size=2),
     "pop_size must be an integer >= 4, got 2"),
    (lambda: ga.run_ga(sphere, ga.RealEncoding(LO, HI), seed=True), "seed must be"),
    (lambda: ga.run_ga(sphere, ga.RealEncoding(LO, HI),
                       adaptive=dict(pc_max=1.5, pc_min=0.9, pm_max=0.1, pm_min=0.0)),
     r"pc_max must be a probability in \[0, 1\], got 1.5"),
    (lambda: ga.run_ga(sphere, ga.RealEncoding(LO, HI),
                       adaptive=dict(pc_max=0.5, pc_min=0.9, pm_max=0.1, pm_min=0.0)),
     "pc_min <= pc_max"),
    (lambda: ga.adaptive_rates(1.0, 1.0, generation=5, max_generation=4, pc_max=1, pc_min=0,
                               pm_max=1, pm_min=0), r"generation must be an integer in \[0, "),
    (lambda: ga.adaptive_rates(1.0, 1.0, generation=0, max_generation=0, **RATES),
     "max_generation must be an integer >= 1, got 0"),
])
def test_bad_arguments_are_refused(make, message):
    with pytest.raises(ValueError, match=message):
        make()
