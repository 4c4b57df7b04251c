import numpy as np
import pytest
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
