"""Rigid-body motion, batched over a leading sample axis.

Every function takes arrays whose *last* axes carry the geometry (3-vectors, 4x4 matrices)
and broadcasts over any leading axes, so ``(n, 3)`` error samples give ``(n, 4, 4)``
transforms without a Python loop.  Units: mm and rad.
"""

from __future__ import annotations

import numpy as np


def hat(w: np.ndarray) -> np.ndarray:
    """Skew-symmetric matrix ``[w]x`` of 3-vectors, so that ``[w]x v = w x v``.

    Parameters
    ----------
    w : array (..., 3)
        Vectors (any unit; rad for a rotation vector).

    Returns
    -------
    array (..., 3, 3)
    """
    w = np.asarray(w, dtype=float)
    z = np.zeros(w.shape[:-1])
    wx, wy, wz = w[..., 0], w[..., 1], w[..., 2]
    return np.stack(
        [
            np.stack([z, -wz, wy], axis=-1),
            np.stack([wz, z, -wx], axis=-1),
            np.stack([-wy, wx, z], axis=-1),
        ],
        axis=-2,
    )


def vee(m: np.ndarray) -> np.ndarray:
    """Inverse of :func:`hat`, applied to the skew-symmetric part of ``m``.

    Parameters
    ----------
    m : array (..., 3, 3)
        Matrices; for ``R - I`` of a small rotation R it returns the rotation vector to first
        order (rad).

    Returns
    -------
    array (..., 3)
    """
    m = np.asarray(m, dtype=float)
    s = 0.5 * (m - np.swapaxes(m, -1, -2))
    return np.stack([s[..., 2, 1], s[..., 0, 2], s[..., 1, 0]], axis=-1)


def rotation_exp(w: np.ndarray) -> np.ndarray:
    """Exact rotation matrix of rotation vectors (Rodrigues' formula).

    ``exp([w]x) = I + sin(t)/t [w]x + (1 - cos t)/t^2 [w]x^2`` with ``t = |w|`` (series below
    1e-8 rad).

    Parameters
    ----------
    w : array (..., 3)
        Rotation vectors (rad): axis times angle.

    Returns
    -------
    array (..., 3, 3)
    """
    w = np.asarray(w, dtype=float)
    theta = np.linalg.norm(w, axis=-1)[..., None, None]
    k = hat(w)
    small = theta < 1e-8
    safe = np.where(small, 1.0, theta)
    a = np.where(small, 1.0 - theta**2 / 6.0, np.sin(safe) / safe)
    b = np.where(small, 0.5 - theta**2 / 24.0, (1.0 - np.cos(safe)) / safe**2)
    return np.eye(3) + a * k + b * (k @ k)


def homogeneous(rotation: np.ndarray, translation: np.ndarray) -> np.ndarray:
    """Assemble homogeneous transforms ``[[R, t], [0, 1]]``.

    Parameters
    ----------
    rotation : array (..., 3, 3)
        Rotation matrices.
    translation : array (..., 3)
        Translations (mm); leading axes broadcast with those of ``rotation``.

    Returns
    -------
    array (..., 4, 4)
    """
    rotation = np.asarray(rotation, dtype=float)
    translation = np.asarray(translation, dtype=float)
    shape = np.broadcast_shapes(rotation.shape[:-2], translation.shape[:-1])
    t = np.zeros(shape + (4, 4))
    t[..., :3, :3] = rotation
    t[..., :3, 3] = translation
    t[..., 3, 3] = 1.0
    return t


def translation(v: np.ndarray) -> np.ndarray:
    """Pure translations ``[[I, v], [0, 1]]``.

    Parameters
    ----------
    v : array (..., 3)
        Translations (mm).

    Returns
    -------
    array (..., 4, 4)
    """
    v = np.asarray(v, dtype=float)
    return homogeneous(np.broadcast_to(np.eye(3), v.shape[:-1] + (3, 3)), v)


def error_transform(delta: np.ndarray, eps: np.ndarray, *, exact: bool = False) -> np.ndarray:
    """Transform of a small error motion: translation ``delta`` and rotation ``eps``.

    ``exact=False`` gives the first-order (small-angle) matrix that the papers print,
    ``[[1, -ez, ey, dx], [ez, 1, -ex, dy], [-ey, ex, 1, dz], [0, 0, 0, 1]]``;
    ``exact=True`` uses the exact rotation ``exp([eps]x)``.

    Parameters
    ----------
    delta : array (..., 3)
        Translational errors (mm).
    eps : array (..., 3)
        Angular errors about x, y, z (rad).
    exact : bool
        Exact rotation instead of the first-order matrix.

    Returns
    -------
    array (..., 4, 4)
    """
    delta = np.asarray(delta, dtype=float)
    eps = np.asarray(eps, dtype=float)
    rot = rotation_exp(eps) if exact else np.eye(3) + hat(eps)
    return homogeneous(rot, delta)


def screw_exp(w: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Exponential of a twist with angular part ``w`` and linear part ``u``, of any magnitude.

    ``[[exp([w]x), V u], [0, 1]]`` with ``V = I + (1 - cos t)/t^2 [w]x + (t - sin t)/t^3 [w]x^2``,
    ``t = |w|`` (series below 1e-6, so a pure translation, w = 0, gives V = I).

    Parameters
    ----------
    w : array (..., 3)
        Angular part (rad).
    u : array (..., 3)
        Linear part (mm).

    Returns
    -------
    array (..., 4, 4)
    """
    w = np.asarray(w, dtype=float)
    u = np.asarray(u, dtype=float)
    k = hat(w)
    t = np.linalg.norm(w, axis=-1)[..., None, None]
    small = t < 1e-6
    safe = np.where(small, 1.0, t)
    a = np.where(small, 0.5 - t**2 / 24.0, (1.0 - np.cos(safe)) / safe**2)
    b = np.where(small, 1.0 / 6.0 - t**2 / 120.0, (safe - np.sin(safe)) / safe**3)
    v = np.eye(3) + a * k + b * (k @ k)
    return homogeneous(rotation_exp(w), (v @ u[..., None])[..., 0])


def twist_exp(omega: np.ndarray, v: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Exponential of the twist (omega, v) times ``theta``: the screw motion of a joint.

    Parameters
    ----------
    omega : array (..., 3)
        Unit axis direction, or zero for a prismatic joint.
    v : array (..., 3)
        Linear part of the twist (for a revolute joint ``-omega x q``, q a point on the axis, mm;
        for a prismatic joint the unit direction).
    theta : array (...)
        Joint value (rad for revolute, mm for prismatic).

    Returns
    -------
    array (..., 4, 4)
    """
    theta = np.asarray(theta, dtype=float)[..., None]
    return screw_exp(np.asarray(omega, dtype=float) * theta, np.asarray(v, dtype=float) * theta)


def chain(*transforms: np.ndarray) -> np.ndarray:
    """Product of transforms from left to right, broadcasting leading axes.

    Parameters
    ----------
    *transforms : arrays (..., 4, 4)
        At least one.

    Returns
    -------
    array (..., 4, 4)
    """
    out = np.asarray(transforms[0], dtype=float)
    for t in transforms[1:]:
        out = out @ t
    return out


def apply(transform: np.ndarray, point: np.ndarray) -> np.ndarray:
    """Apply homogeneous transforms to points.

    Parameters
    ----------
    transform : array (..., 4, 4)
        Transforms.
    point : array (..., 3)
        Points (mm); leading axes broadcast.

    Returns
    -------
    array (..., 3)
        ``R p + t`` (mm).
    """
    point = np.asarray(point, dtype=float)
    return (transform[..., :3, :3] @ point[..., None])[..., 0] + transform[..., :3, 3]


def pose_difference(actual: np.ndarray, ideal: np.ndarray) -> np.ndarray:
    """Six-component pose error of ``actual`` against ``ideal``.

    ``[Px, Py, Pz]`` is the difference of the origins (mm); ``[Vx, Vy, Vz]`` is the small
    rotation vector ``vee(R_actual R_ideal^T)`` (rad, first order), both in the reference frame
    of the transforms.

    Parameters
    ----------
    actual, ideal : arrays (..., 4, 4)
        Transforms of the tool in the workpiece frame, with and without errors.

    Returns
    -------
    array (..., 6)
        ``Px, Py, Pz`` (mm), ``Vx, Vy, Vz`` (rad).

    Examples
    --------
    >>> import numpy as np
    >>> ideal = translation(np.array([10.0, 0.0, 0.0]))
    >>> actual = ideal @ error_transform(np.array([0.001, 0.0, 0.0]), np.array([0.0, 0.0, 2e-5]))
    >>> np.round(pose_difference(actual, ideal), 6).tolist()
    [0.001, 0.0, 0.0, 0.0, 0.0, 2e-05]
    """
    p = actual[..., :3, 3] - ideal[..., :3, 3]
    r = actual[..., :3, :3] @ np.swapaxes(ideal[..., :3, :3], -1, -2)
    return np.concatenate([p, vee(r)], axis=-1)


def matvec3(r: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Batched matrix-vector product, summed in a fixed order.

    No BLAS call, so the rounding is the same on every machine (and for 3x3 blocks it is
    faster than a BLAS call per matrix).

    Parameters
    ----------
    r : array (n, 3, 3)
        Matrices.
    v : array (n, 3)
        Vectors.

    Returns
    -------
    array (n, 3)
    """
    return r[:, :, 0] * v[:, None, 0] + r[:, :, 1] * v[:, None, 1] + r[:, :, 2] * v[:, None, 2]


def matmul3(r: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Batched matrix product, summed in a fixed order (see :func:`matvec3`).

    Parameters
    ----------
    r, s : arrays (n, 3, 3)
        Matrices.

    Returns
    -------
    array (n, 3, 3)
    """
    return (r[:, :, 0, None] * s[:, None, 0, :] + r[:, :, 1, None] * s[:, None, 1, :]
            + r[:, :, 2, None] * s[:, None, 2, :])
