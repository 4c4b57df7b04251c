"""sensitivity.spearman: one randomness helper (validate.rng), keyword-only arguments after the
data, and argument checks through mtaccuracy.validate."""

import numpy as np
import pytest

from mtaccuracy import sensitivity as S
from mtaccuracy import validate

BOUNDS = np.array([[0.0, -1.0, 10.0], [1.0, 1.0, 20.0]])


def test_as_generator_is_gone_and_a_generator_continues_the_callers_stream():
    assert not hasattr(S, "as_generator")
    a, b = np.random.default_rng(5), np.random.default_rng(5)
    first = S.latin_hypercube(8, BOUNDS, a)
    second = S.latin_hypercube(8, BOUNDS, a)           # the stream goes on: a new design
    assert not np.array_equal(first, second)
    assert np.array_equal(first, S.latin_hypercube(8, BOUNDS, validate.rng(b)))
    assert np.array_equal(S.latin_hypercube(8, BOUNDS, 5), first)  # an int seeds the same way


def test_a_latin_hypercube_has_one_sample_per_stratum_of_every_input():
    x = S.latin_hypercube(10, BOUNDS, 3)
    u = (x - BOUNDS[0]) / (BOUNDS[1] - BOUNDS[0])
    assert np.array_equal(np.sort(np.floor(u * 10), axis=0), np.repeat(np.arange(10.0)[:, None],
                                                                       3, axis=1))


@pytest.mark.parametrize("call, message", [
    (lambda: S.latin_hypercube(1, BOUNDS, 0), "n must be an integer >= 2, got 1"),
    (lambda: S.latin_hypercube(4.5, BOUNDS, 0), "n must be an integer >= 2, got 4.5"),
    (lambda: S.latin_hypercube(4, BOUNDS, True), "seed must be None"),
    (lambda: S.repeated_latin_hypercube(4, BOUNDS, repeats=0, seed=1),
     "repeats must be an integer >= 1, got 0"),
    (lambda: S.lhs_rank_eigenvalues(2, 3, designs=5, seed=0), "n must be an integer >= 3, got 2"),
    (lambda: S.lhs_rank_eigenvalues(5, 1, designs=5, seed=0), "k must be an integer >= 2, got 1"),
    (lambda: S.lhs_rank_eigenvalues(5, 3, designs=0.5, seed=0),
     "designs must be an integer >= 1, got 0.5"),
    (lambda: S.spearman_over_poses(None, np.zeros((4, 2)), {"x": np.zeros(3)}, chunk=0),
     "chunk must be an integer >= 1, got 0"),
])
def test_bad_counts_are_refused_in_the_words_of_validate(call, message):
    with pytest.raises(ValueError, match=message):
        call()


def test_integral_floats_are_counts_as_a_notebook_may_write_them():
    assert S.latin_hypercube(1e1, BOUNDS, 0).shape == (10, 3)
    assert S.repeated_latin_hypercube(5, BOUNDS, repeats=2.0, seed=1).shape == (2, 5, 3)


class _Linear:
    """pose_error of a toy machine: Px = e0 + x e1, Py = e1, the rest zero."""

    def pose_error(self, errors, pose):
        out = np.zeros((errors.shape[0], 6))
        out[:, 0] = errors[:, 0] + pose["x"] * errors[:, 1]
        out[:, 1] = errors[:, 1]
        return out


def test_spearman_over_poses_takes_keywords_after_the_data_and_chunks_change_nothing():
    x = S.latin_hypercube(50, np.array([[0.0, 0.0], [1.0, 1.0]]), 2)
    poses = {"x": np.array([0.0, 1.0, 100.0])}
    with pytest.raises(TypeError):
        S.spearman_over_poses(_Linear(), x, poses, S.position_outputs)
    with pytest.raises(TypeError):
        S.repeated_latin_hypercube(4, BOUNDS, 2, 1)
    one = S.spearman_over_poses(_Linear(), x, poses, chunk=1)
    assert np.array_equal(one, S.spearman_over_poses(_Linear(), x, poses, chunk=64),
                          equal_nan=True)                # Ez is constant: NaN
    # at x = 0, Ex ranks exactly like e0 and Ey like e1: coefficients of 1
    assert one[0, 0, 0] == pytest.approx(1.0) and one[0, 1, 1] == pytest.approx(1.0)
    assert abs(one[2, 1, 0]) > abs(one[2, 0, 0])            # far out, e1 drives Ex
