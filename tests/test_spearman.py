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


# --- one result shape: the coefficients labelled, with to_df (the ranking) ---------------------

def test_spearman_returns_the_coefficients_labelled_and_ranked():
    from scipy import stats

    rng = np.random.default_rng(2)
    x = rng.random((60, 3))
    y = np.c_[x[:, 0] - 3 * x[:, 2], np.exp(x[:, 1]) + 0.1 * rng.random(60)]
    rho = S.spearman(x, y, names=["a", "b", "c"], outputs=["f", "g"])
    assert isinstance(rho, S.SpearmanCoefficients) and isinstance(rho, np.ndarray)
    ref = stats.spearmanr(np.c_[x, y]).statistic[:3, 3:]            # scipy, independently
    assert np.allclose(rho, ref, rtol=0, atol=1e-14)
    # what is computed from it is a plain array: no label can name a wrong axis
    for derived in (rho[:, 0], rho[[0, 1], [1, 0]], np.abs(rho), rho - ref, rho.T @ rho,
                    rho.std(axis=0)):
        assert type(derived) is np.ndarray
    df = rho.to_df()
    assert list(df.columns) == ["output", "input", "rho", "rank"]
    assert list(df.output) == ["f"] * 3 + ["g"] * 3 and list(df.input) == ["a", "b", "c"] * 2
    # the rank column is the ranking by |rho| of rank_by_magnitude
    for o, k in (("f", 0), ("g", 1)):
        ranked = [n for n, _ in S.rank_by_magnitude(rho[:, k], ["a", "b", "c"])]
        assert df[df.output == o].sort_values("rank").input.tolist() == ranked
    assert df.rho.tolist() == rho.T.ravel().tolist()
    # defaults, leading axes, bad names
    rep = S.spearman(np.stack([x, x[::-1]]), np.stack([y, y[::-1]]))
    assert rep.names == ("x1", "x2", "x3") and rep.outputs == ("y1", "y2")
    assert rep.to_df().axis0.tolist() == [0] * 6 + [1] * 6
    with pytest.raises(ValueError, match="input names must be 3 distinct"):
        S.spearman(x, y, names=["a", "a", "c"])


def test_spearman_over_poses_names_the_errors_outputs_and_poses():
    from mtaccuracy.machines import build

    m = build("vertical_xyfz")
    b = np.array([[0.0] * m.n_errors, [1e-3] * m.n_errors])
    x = S.latin_hypercube(40, b, 1)
    poses = dict(x=np.array([0.0, 100.0]), y=np.array([50.0, 20.0]), z=np.array([10.0, 30.0]))
    rho = S.spearman_over_poses(m, x, poses)
    assert rho.names == tuple(m.error_names) and rho.outputs == S.POSITION_OUTPUTS
    at_one = S.spearman(x, S.position_outputs(m.pose_error(x, {k: v[1] for k, v in poses.items()})))
    assert np.array_equal(rho[1], at_one)
    df = rho.to_df()
    assert df.columns[0] == "pose" and len(df) == 2 * m.n_errors * 4
    assert df.pose.tolist() == [0] * (m.n_errors * 4) + [1] * (m.n_errors * 4)


def test_an_index_array_keeps_its_labels_only_on_itself():
    import pickle

    a = S.IndexArray(np.arange(8.0).reshape(2, 2, 2), names=["p", "q"], outputs=["u", "v"],
                     lead=["pose"])
    assert a.copy().names == ("p", "q") and pickle.loads(pickle.dumps(a)).outputs == ("u", "v")
    square = a[0]                                   # (inputs, outputs) 2 x 2: a transpose of it
    assert type(square) is np.ndarray and a.swapaxes(1, 2).names is None   # would be mislabelled
    with pytest.raises(ValueError, match="no labels"):
        a.swapaxes(1, 2).to_df()
    with pytest.raises(ValueError, match="1 names for 0 leading axes"):
        S.IndexArray(np.zeros((2, 2)), lead=["pose"])
    with pytest.raises(ValueError, match=r"\(..., d, q\)"):
        S.IndexArray(np.zeros(3))
