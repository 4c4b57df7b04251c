"""Rigid-body motion, batched over a leading sample axis.

Every function takes arrays whose *last* axes carry the geometry (3-vectors, 4x4 matrices)
and broadcasts over any leading axes, so ``(n, 3)`` error samples give ``(n, 4, 4)``
transforms without a Python loop.  Units: mm and rad.

The kernels of :class:`mtaccuracy.machines.chain.ChainMachine` use the transposed layout
(*rows*, a structure of arrays): a 3-vector is a list of its three coordinates, each a scalar
or an array of samples, and a 3x3 matrix a nested list of three rows of three; every product
is written out in a fixed order (no BLAS call, so the same rounding on every CPU), and a
scalar coordinate (one pose for every sample) keeps the arithmetic cheap.  They are
:func:`cos_sin` (:func:`cos_sin_into` in place), :func:`exp_coefficients`,
:func:`cross_rows`, :func:`rotation_rows`, :func:`motion_rows` and :func:`inverse_rows`;
the last three take the ``form`` of a block of small errors (``screw``, ``rodrigues``,
``first_order``: see :mod:`mtaccuracy.machines.chain`).  They are not :func:`rotation_exp`
and :func:`screw_exp` rewritten: their series hold up to 1e-3 rad (those two switch to the
closed form at 1e-8 and 1e-6 rad, where ``(1 - cos t) / t^2`` loses digits to cancellation:
about 1e-11 of ``|d|`` in the translation of :func:`screw_exp` at 1e-5 rad) and they sum in
another order, so the two agree closely, not bit for bit.
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


# ------------------------------------------------------------------------------------------
# Kernels on rows (structure of arrays): a 3-vector is a list of 3 rows, a 3x3 a list of 3 x 3
# ------------------------------------------------------------------------------------------

#: The forms of a block of errors the row kernels take (the chain's ``euler`` form is applied
#: as elementary rotations instead, :class:`mtaccuracy.machines.chain.ChainMachine`).
ROW_FORMS = ("screw", "rodrigues", "first_order")


def cos_sin_into(x: np.ndarray, cos: np.ndarray, sin: np.ndarray,
                 scratch: np.ndarray) -> None:
    """Cosine and sine of ``x`` into the buffers ``cos`` and ``sin``, in place.

    No temporaries the size of ``x``.  Below 1e-3 rad (every geometric error) by Taylor
    polynomials whose truncation error is under half an ulp: to x^2 and x^3 below 1e-4 rad
    (errors < x^4/24 < 5e-18 and x^5/120 < 1e-22), to x^4 and x^5 below 1e-3 rad (< x^6/720 and
    x^7/5040): plain arithmetic, so the same rounding on every CPU (unlike vectorised sin and
    cos), and several times faster; numpy's ``cos`` and ``sin`` when any ``|x|`` reaches
    1e-3.

    Parameters
    ----------
    x : ndarray of float
        Angles (rad), any shape; left unchanged.
    cos, sin : ndarray of float
        Buffers of ``x``'s shape that receive the cosines and the sines.
    scratch : ndarray of float
        A buffer of ``x``'s shape, overwritten.
    """
    m = max(x.max(initial=0.0), -x.min(initial=0.0))
    if m >= 1e-3:
        np.cos(x, out=cos)
        np.sin(x, out=sin)
        return
    x2 = scratch
    np.multiply(x, x, out=x2)
    if m < 1e-4:                       # c = 1 - x^2/2, s = x (1 - x^2/6)
        np.multiply(x2, -0.5, out=cos)
        cos += 1.0
        np.multiply(x2, -1.0 / 6.0, out=sin)
        sin += 1.0
        sin *= x
        return
    # c = 1 - (x^2/2)(1 - x^2/12), s = x (1 - (x^2/6)(1 - x^2/20))
    np.divide(x2, 12.0, out=cos)
    np.subtract(1.0, cos, out=cos)
    np.divide(x2, 20.0, out=sin)
    np.subtract(1.0, sin, out=sin)
    np.multiply(x2, 0.5, out=x2)
    cos *= x2
    np.subtract(1.0, cos, out=cos)
    np.multiply(x, x, out=x2)
    np.divide(x2, 6.0, out=x2)
    sin *= x2
    np.subtract(1.0, sin, out=sin)
    sin *= x


def cos_sin(x):
    """Cosine and sine of ``x`` by :func:`cos_sin_into`, into new arrays.

    Parameters
    ----------
    x : float or array_like
        Angles (rad).

    Returns
    -------
    cos, sin : float or ndarray
        Python floats for a scalar ``x`` (the operations of one pose then multiply by
        scalars, the fast case), else arrays of ``x``'s shape (at least 1-d).

    Examples
    --------
    >>> c, s = cos_sin(1e-5)
    >>> c, s
    (0.99999999995, 9.999999999833334e-06)
    """
    a = np.atleast_1d(np.asarray(x, dtype=float))
    c, s, x2 = np.empty_like(a), np.empty_like(a), np.empty_like(a)
    cos_sin_into(a, c, s, x2)
    return (float(c[0]), float(s[0])) if np.ndim(x) == 0 else (c, s)


def exp_coefficients(theta_sq):
    """The coefficients of the exponentials of rotations and twists, from the squared angle.

    ``a = sin t / t``, ``b = (1 - cos t) / t^2`` and ``c = (t - sin t) / t^3`` of ``t^2 =
    theta_sq``: Rodrigues' ``exp([w]x) = I + a [w]x + b [w]x^2`` and the twist's ``V = I + b
    [w]x + c [w]x^2`` (:func:`screw_exp`).  Series to t^6 below t = 1e-3 (error < 1e-29),
    numpy's sin and cos above.

    Parameters
    ----------
    theta_sq : float or array_like
        Squared rotation angles, rad^2 (non-negative).

    Returns
    -------
    a, b, c : ndarray or numpy float
        Of ``theta_sq``'s shape (numpy floats for a scalar).
    """
    t2 = np.asarray(theta_sq, dtype=float)
    if t2.ndim == 0:
        a, b, c = exp_coefficients(t2[None])
        return a[0], b[0], c[0]
    a = 1.0 - t2 / 6.0 * (1.0 - t2 / 20.0 * (1.0 - t2 / 42.0))
    b = 0.5 - t2 / 24.0 * (1.0 - t2 / 30.0 * (1.0 - t2 / 56.0))
    c = 1.0 / 6.0 - t2 / 120.0 * (1.0 - t2 / 42.0 * (1.0 - t2 / 72.0))
    large = t2 >= 1e-6
    if np.any(large):
        t = np.sqrt(t2[large])
        s, co = np.sin(t), np.cos(t)
        a[large], b[large], c[large] = s / t, (1.0 - co) / t2[large], (t - s) / (t2[large] * t)
    return a, b, c


def cross_rows(u, v) -> list:
    """Cross product ``u x v`` of two 3-vectors given as rows.

    Parameters
    ----------
    u, v : sequence of 3 floats or arrays
        The coordinates of each vector (rows broadcast with one another).

    Returns
    -------
    list of 3 floats or arrays
        The coordinates of ``u x v``.
    """
    return [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]


def _check_form(form: str) -> None:
    if form not in ROW_FORMS:
        raise ValueError(f"unknown form {form!r}; allowed: {', '.join(ROW_FORMS)}")


def rotation_rows(w, *, form: str) -> list:
    """The rotation of a block of small errors with rotation parameters ``w``, as rows.

    ``first_order``: the small-angle matrix ``I + [w]x`` the papers print (not a rotation);
    ``rodrigues`` and ``screw``: ``exp([w]x) = (1 - b t^2) I + a [w]x + b w w^T``, ``t = |w|``
    (:func:`exp_coefficients`).

    Parameters
    ----------
    w : sequence of 3 floats or arrays
        Rotation parameters about x, y, z (rad).
    form : {"screw", "rodrigues", "first_order"}
        The form of the block (:data:`ROW_FORMS`).

    Returns
    -------
    list of 3 lists of 3 floats or arrays
        The matrix, row by row.

    Raises
    ------
    ValueError
        For an unknown ``form``.
    """
    _check_form(form)
    wx, wy, wz = w
    if form == "first_order":
        return [[1.0, -wz, wy], [wz, 1.0, -wx], [-wy, wx, 1.0]]
    t2 = wx * wx + wy * wy + wz * wz
    a, b, _ = exp_coefficients(t2)
    ww = [[wx * wx, wx * wy, wx * wz], [wy * wx, wy * wy, wy * wz], [wz * wx, wz * wy, wz * wz]]
    hat = [[0.0, -wz, wy], [wz, 0.0, -wx], [-wy, wx, 0.0]]
    diag = 1.0 - b * t2
    return [[(diag if i == j else 0.0) + a * hat[i][j] + b * ww[i][j] for j in range(3)]
            for i in range(3)]


def motion_rows(d, w, *, form: str) -> tuple[list, list]:
    """The rigid motion ``(R, t)`` of a block of small errors, as rows.

    ``R`` is :func:`rotation_rows`; ``t`` is ``d`` (``rodrigues``, ``first_order``) or, for
    ``screw`` (the exponential of the twist ``(w, d)``), ``V d = d + b w x d + c w x (w x d)``
    (:func:`exp_coefficients`).

    Parameters
    ----------
    d : sequence of 3 floats or arrays
        Translations along x, y, z (mm).
    w : sequence of 3 floats or arrays
        Rotation parameters about x, y, z (rad).
    form : {"screw", "rodrigues", "first_order"}
        The form of the block (:data:`ROW_FORMS`).

    Returns
    -------
    R : list of 3 lists of 3 floats or arrays
        The rotation, row by row.
    t : list of 3 floats or arrays
        The translation (mm).

    Raises
    ------
    ValueError
        For an unknown ``form``.
    """
    r = rotation_rows(w, form=form)
    if form != "screw":
        return r, d
    _, b, c = exp_coefficients(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
    wxd = cross_rows(w, d)
    wwxd = cross_rows(w, wxd)
    return r, [d[i] + b * wxd[i] + c * wwxd[i] for i in range(3)]


def inverse_rows(rotation, translation, w, *, form: str) -> tuple[list, list]:
    """The inverse ``(R', t')`` of the motion ``(R, t)`` of a block (:func:`motion_rows`).

    ``R' = R^T`` for the rigid forms; for ``first_order``, whose ``I + [w]x`` is not a
    rotation, ``(I + [w]x)^-1 = (I - [w]x + w w^T) / (1 + |w|^2)`` exactly; ``t' = -R' t``.

    Parameters
    ----------
    rotation : list of 3 lists of 3 floats or arrays
        ``R``, row by row.
    translation : sequence of 3 floats or arrays
        ``t`` (mm).
    w : sequence of 3 floats or arrays
        The block's rotation parameters (rad), used by ``first_order``.
    form : {"screw", "rodrigues", "first_order"}
        The form of the block (:data:`ROW_FORMS`).

    Returns
    -------
    R' : list of 3 lists of 3 floats or arrays
        The inverse rotation, row by row.
    t' : list of 3 floats or arrays
        The inverse translation (mm).

    Raises
    ------
    ValueError
        For an unknown ``form``.

    Examples
    --------
    >>> r, t = motion_rows([1.0, 2.0, 3.0], [0.0, 0.0, 0.5], form="screw")
    >>> ri, ti = inverse_rows(r, t, [0.0, 0.0, 0.5], form="screw")
    >>> back = [sum(ri[i][j] * t[j] for j in range(3)) + ti[i] for i in range(3)]
    >>> [round(float(x), 12) for x in back]
    [0.0, 0.0, 0.0]
    """
    _check_form(form)
    r, t = rotation, translation
    if form == "first_order":
        wx, wy, wz = w
        den = 1.0 + wx * wx + wy * wy + wz * wz
        ww = [[wx * wx, wx * wy, wx * wz], [wy * wx, wy * wy, wy * wz],
              [wz * wx, wz * wy, wz * wz]]
        minus_w = [[0.0, wz, -wy], [-wz, 0.0, wx], [wy, -wx, 0.0]]
        ri = [[((1.0 if i == j else 0.0) + minus_w[i][j] + ww[i][j]) / den for j in range(3)]
              for i in range(3)]
    else:
        ri = [[r[j][i] for j in range(3)] for i in range(3)]
    ti = [-(ri[i][0] * t[0] + ri[i][1] * t[1] + ri[i][2] * t[2]) for i in range(3)]
    return ri, ti
