import numpy as np
import pytest
from scipy.linalg import expm
from scipy.spatial.transform import Rotation

from mtaccuracy import kinematics as K

RNG = np.random.default_rng(0)


def test_hat_vee_roundtrip_and_cross_product():
    w, v = RNG.normal(size=(5, 3)), RNG.normal(size=(5, 3))
    assert np.allclose(K.vee(K.hat(w)), w)
    assert np.allclose((K.hat(w) @ v[..., None])[..., 0], np.cross(w, v))


def test_rotation_exp_matches_scipy_including_tiny_angles():
    w = np.vstack([RNG.normal(size=(6, 3)), [[1e-10, -2e-10, 0.0]], [[0.0, 0.0, 0.0]]])
    assert np.allclose(K.rotation_exp(w), Rotation.from_rotvec(w).as_matrix(), atol=1e-14)


def test_small_angle_error_transform_is_first_order_of_exact():
    d = RNG.normal(size=(4, 3)) * 1e-3
    for scale in (1e-4, 1e-5):
        e = RNG.normal(size=(4, 3)) * scale
        gap = np.abs(K.error_transform(d, e) - K.error_transform(d, e, exact=True)).max()
        assert 0.01 * scale**2 < gap < 10 * scale**2  # second order, and not zero


def test_twist_exp_prismatic_and_revolute():
    t = K.twist_exp([0, 0, 0], [0, 1, 0], np.array([2.0, -3.0]))
    assert np.allclose(t[:, :3, 3], [[0, 2, 0], [0, -3, 0]])
    assert np.allclose(t[:, :3, :3], np.eye(3))
    # Revolute about z through q: exp = T(q) R T(-q); twist v = -omega x q.
    q, omega, theta = np.array([1.0, 2.0, 0.5]), np.array([0.0, 0.0, 1.0]), 0.7
    expected = (K.translation(q) @ K.homogeneous(K.rotation_exp(omega * theta), np.zeros(3))
                @ K.translation(-q))
    assert np.allclose(K.twist_exp(omega, -np.cross(omega, q), theta), expected)


def test_pose_difference_and_broadcasting():
    a = K.error_transform(np.zeros((3, 3)), np.zeros((3, 3)))
    assert K.pose_difference(a, a).shape == (3, 6)
    assert not K.pose_difference(a, a).any()
    b = K.chain(K.translation([1.0, 2.0, 3.0]), K.error_transform([0, 0, 0], [1e-6, 0, 0]))
    diff = K.pose_difference(b, K.translation([1.0, 2.0, 3.0]))
    assert np.allclose(diff, [0, 0, 0, 1e-6, 0, 0])


def test_homogeneous_rejects_nothing_silently():
    with pytest.raises(ValueError):
        K.homogeneous(np.eye(3)[None].repeat(2, 0), np.zeros((3, 3)))


@pytest.mark.parametrize("bound", [5e-5, 5e-4, 0.3])
def test_cos_sin_branches_agree_with_numpy(bound):
    x = np.random.default_rng(7).uniform(-bound, bound, (3, 4001))
    c, s, x2 = np.empty_like(x), np.empty_like(x), np.empty_like(x)
    K.cos_sin_into(x, c, s, x2)
    c2, s2 = K.cos_sin(x)
    for cc, ss in ((c, s), (c2, s2)):
        assert np.abs(cc - np.cos(x)).max() <= 2.3e-16          # one ulp of 1
        assert np.all(np.abs(ss - np.sin(x)) <= 3e-16 * np.abs(x))


def test_exponential_coefficients_series_and_closed_form_agree():
    t = np.array([0.0, 1e-6, 9.99e-4, 1e-3, 1.01e-3, 0.3, 2.0])
    a, b, c = K.exp_coefficients(t**2)
    with np.errstate(invalid="ignore", divide="ignore"):
        ref = (np.sin(t) / t, (1 - np.cos(t)) / t**2, (t - np.sin(t)) / t**3)
    for got, want, at0 in zip((a, b, c), ref, (1.0, 0.5, 1 / 6), strict=True):
        assert got[0] == at0
        assert np.allclose(got[3:], want[3:], rtol=1e-9, atol=0)  # closed form is exact there
        assert np.allclose(got[1:3], [at0, want[2]], rtol=1e-6)
    # a scalar takes the branch of its size, as an array entry does
    for i in (1, 5):
        assert K.exp_coefficients(t[i] ** 2) == (a[i], b[i], c[i])


def _rows(a):
    """(n, 3) -> 3 rows."""
    return [a[:, i] for i in range(3)]


def _matrix(rows):
    """(n, 3, 3) from a 3x3 of rows (scalar entries broadcast)."""
    flat = np.broadcast_arrays(*[x for r in rows for x in r])
    return np.stack(flat, axis=-1).reshape(flat[0].shape + (3, 3))


@pytest.mark.parametrize("scale", [1e-5, 0.5])   # the series and the closed form
def test_row_kernels_agree_with_the_matrix_forms(scale):
    rng = np.random.default_rng(7)                  # its own draws, whatever runs before it
    w, d = rng.normal(0, scale, (50, 3)), rng.normal(0, 1.0, (50, 3))
    assert np.allclose(_matrix(K.rotation_rows(_rows(w), form="rodrigues")),
                       K.rotation_exp(w), rtol=0, atol=1e-15)
    assert np.array_equal(_matrix(K.rotation_rows(_rows(w), form="first_order")),
                          np.eye(3) + K.hat(w))
    r, t = K.motion_rows(_rows(d), _rows(w), form="screw")
    xi = np.zeros((50, 4, 4))                       # the twist (w, d) as a 4x4 matrix
    xi[:, :3, :3], xi[:, :3, 3] = K.hat(w), d
    want = expm(xi)                                 # (screw_exp loses ~1e-11 at |w| ~ 1e-5)
    # entries of order 1: a few units in the last place apart (expm's own rounding)
    assert np.allclose(_matrix(r), want[:, :3, :3], rtol=0, atol=1e-14)
    assert np.allclose(np.stack(t, -1), want[:, :3, 3], rtol=0, atol=1e-14)
    assert np.allclose(np.stack(K.cross_rows(_rows(w), _rows(d)), -1), np.cross(w, d),
                       rtol=0, atol=1e-15)


@pytest.mark.parametrize("form", K.ROW_FORMS)
def test_inverse_rows_undoes_the_motion_of_every_form(form):
    w, d = RNG.normal(0, 0.3, (20, 3)), RNG.normal(0, 5.0, (20, 3))
    r, t = K.motion_rows(_rows(d), _rows(w), form=form)
    ri, ti = K.inverse_rows(r, t, _rows(w), form=form)
    g = K.homogeneous(_matrix(r), np.stack(t, -1))
    gi = K.homogeneous(_matrix(ri), np.stack(ti, -1))
    assert np.allclose(gi @ g, np.eye(4), rtol=0, atol=1e-13)   # first_order too: exact inverse
    with pytest.raises(ValueError, match="unknown form 'euler'"):
        K.motion_rows(_rows(d), _rows(w), form="euler")
