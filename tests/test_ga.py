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
    assert out.stdout.strip() == "['mtaccuracy', 'mtaccuracy.optimise', 'mtaccuracy.optimise.ga']"


@pytest.mark.parametrize("make, message", [
    (lambda: ga.BinaryEncoding(LO, HI, 31), "bits must be an integer from 2 to 30"),
    (lambda: ga.RealEncoding(HI, LO), "low < high"),
    (lambda: ga.RealEncoding(LO, HI, 0.0), "mutation_scale must be > 0"),
    (lambda: ga.run_ga(sphere, ga.RealEncoding(LO, HI), pop_size=7), "even"),
    (lambda: ga.run_ga(sphere, ga.RealEncoding(LO, HI), pm=2.0), "probabilities"),
    (lambda: ga.run_ga(sphere, ga.RealEncoding(LO, HI),
                       adaptive=dict(pc_max=0.5, pc_min=0.9, pm_max=0.1, pm_min=0.0)),
     "pc_min <= pc_max"),
    (lambda: ga.adaptive_rates(1.0, 1.0, 5, 4, pc_max=1, pc_min=0, pm_max=1, pm_min=0),
     "generation"),
])
def test_bad_arguments_are_refused(make, message):
    with pytest.raises(ValueError, match=message):
        make()
