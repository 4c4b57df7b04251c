"""The one argument-check helper (issue 25 item 5): what it accepts, what it refuses, and that
its message names the argument, its range and the value."""

import numpy as np
import pytest

from mtaccuracy.validate import integer, probability, rng


@pytest.mark.parametrize("value, expected", [(3, 3), (np.int64(7), 7), (1e3, 1000), (2.0, 2)])
def test_integer_accepts_integral_values_and_returns_a_python_int(value, expected):
    out = integer(value, "n", low=2)
    assert out == expected and type(out) is int


@pytest.mark.parametrize("value", [True, np.bool_(True), 2.5, float("nan"), float("inf"), "3",
                                   None, [3]])
def test_integer_refuses_non_integers(value):
    with pytest.raises(ValueError, match=r"^k must be an integer >= 0, got "):
        integer(value, "k", low=0)


@pytest.mark.parametrize("low, high, value, words", [
    (2, 5, 1, r"folds must be an integer in \[2, 5\], got 1"),
    (2, 5, 6, r"folds must be an integer in \[2, 5\], got 6"),
    (None, 5, 6, r"folds must be an integer <= 5, got 6"),
    (2, None, 1, r"folds must be an integer >= 2, got 1")])
def test_integer_bounds_are_inclusive_and_named(low, high, value, words):
    with pytest.raises(ValueError, match=words):
        integer(value, "folds", low=low, high=high)
    for edge in (b for b in (low, high) if b is not None):
        assert integer(edge, "folds", low=low, high=high) == edge


def test_probability():
    assert probability(0, "pc") == 0.0 and probability(1, "pc") == 1.0
    for bad in (-0.1, 1.1, True, "0.5", float("nan")):
        with pytest.raises(ValueError, match=r"pc must be a probability in \[0, 1\]"):
            probability(bad, "pc")


def test_rng_continues_a_generator_and_seeds_reproducibly():
    g = np.random.default_rng(5)
    assert rng(g) is g
    assert rng(5).random() == np.random.default_rng(5).random()
    for bad in (True, -1, "x"):
        with pytest.raises(ValueError, match="seed must be"):
            rng(bad)


def test_file_bytes_refuses_what_is_not_a_regular_file(tmp_path):
    """A FIFO would hang open(), a link to /dev/zero would fill memory: both refused at once."""
    import os

    from mtaccuracy.validate import FileRefused, file_bytes
    fifo = tmp_path / "fifo.csv"
    os.mkfifo(fifo)
    zero = tmp_path / "zero.csv"
    zero.symlink_to("/dev/zero")
    dangling = tmp_path / "gone.csv"
    dangling.symlink_to(tmp_path / "nothing")
    cases = {fifo: "FIFO", zero: "character device", tmp_path: "directory",
             dangling: "not found"}
    for path, words in cases.items():
        with pytest.raises(FileRefused, match=words):
            file_bytes(path, max_bytes=100)
    big = tmp_path / "big.csv"
    big.write_bytes(b"x" * 101)
    with pytest.raises(FileRefused, match="101 bytes; files up to 100"):
        file_bytes(big, max_bytes=100)
    good = tmp_path / "link.csv"
    good.symlink_to(big)
    assert file_bytes(good, max_bytes=101) == b"x" * 101
