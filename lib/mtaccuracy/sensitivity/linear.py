"""Closed-form Sobol indices of the first-order (linear) error model, for any machine.

Geometric errors are small, so a machine's pose error is ``y = J(pose) e`` to first order,
with ``J`` the (q, d) Jacobian at zero errors (a machine's ``jacobian``).  For independent
inputs ``e_i`` (any distributions) with means ``m_i`` and variances ``var_i`` the Sobol
indices of that model need no sampling:

* at a fixed pose, ``S1 = ST = J_ki^2 var_i / sum_j J_kj^2 var_j`` (output k, input i);
* with the pose random too, independent of the errors,
  ``V_k = sum_i E_pose[J_ki^2] var_i + Var_pose(sum_i J_ki m_i)``,
  ``S1_ki = E_pose[J_ki]^2 var_i / V_k``, ``ST_ki = E_pose[J_ki^2] var_i / V_k``
  (``E[y | e_i]`` is ``E_pose[J_ki] e_i`` plus a constant; given every input but ``e_i``,
  ``y`` still varies by ``J_ki(pose) e_i``).

These are the numbers the sampled (Saltelli/Jansen) estimates of the first-order model
converge to; the exact model differs from it by the second-order terms, whose size
:func:`nonlinear_remainder` measures.  Written by hand because it is a few lines of algebra
on the paper's own model (no library computes Sobol indices from a Jacobian).

Layout: Jacobians are (P, q, d) with a leading pose axis; indices are returned (P, d, q)
(inputs by outputs, as the sampling estimators), except :func:`linear_indices`, which keeps
the Jacobian's (..., q, d).

The inputs' spread: an :class:`~mtaccuracy.sensitivity.Inputs` (its moments), or bare arrays
named by keyword, ``sd=`` (standard deviations) or ``var=`` (variances), so that one can never
be taken for the other.  The arithmetic follows what was given: ``(J sd)^2`` from standard
deviations, ``J^2 var`` from variances (equal to rounding); an ``Inputs`` gives its standard
deviations to :func:`linear_indices` and its variances to :func:`indices_at_poses` and
:func:`pose_box_indices` (the forms their callers have always passed, so the numbers are the
same to the bit).
"""

from __future__ import annotations

__all__ = ["LinearIndices", "linear_indices", "uniform_moments", "gauss_legendre_unit",
           "PoseBoxIndices", "pose_box_indices", "indices_at_poses", "Remainder",
           "nonlinear_remainder"]

from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import NamedTuple

import numpy as np
import pandas as pd

from ..validate import integer
from .inputs import Inputs
from .results import IndexArray, labels


def _shares(v: np.ndarray) -> np.ndarray:
    """``v / v.sum(-1)``, with zeros where the sum is zero."""
    tot = v.sum(axis=-1, keepdims=True)
    return np.divide(v, tot, out=np.zeros_like(v), where=tot > 0)


def _spread(inputs, sd, var, d, prefer: str) -> tuple[str, np.ndarray]:
    """``("sd", sd)`` or ``("var", var)``, (d,), from an :class:`Inputs` or one keyword array."""
    given = [k for k, v in (("inputs", inputs), ("sd", sd), ("var", var)) if v is not None]
    if len(given) != 1:
        raise ValueError("give the inputs' spread once: an Inputs, or sd= (standard "
                         f"deviations), or var= (variances); got {given or 'none'}")
    if inputs is not None:
        if not isinstance(inputs, Inputs):
            raise TypeError(f"inputs must be an Inputs (bare arrays go by keyword, sd= or "
                            f"var=), got {type(inputs).__name__}")
        kind, v = prefer, (inputs.sd if prefer == "sd" else inputs.var)
    else:
        kind, v = ("sd", sd) if sd is not None else ("var", var)
    v = np.asarray(v, dtype=float)
    if v.shape != (d,):
        raise ValueError(f"{kind} must be ({d},) for {d} inputs, got {v.shape}")
    if np.any(v < 0) or not np.all(np.isfinite(v)):
        raise ValueError(f"{kind} must be finite and >= 0")
    return kind, v


def _squares(c: np.ndarray, kind: str, v: np.ndarray) -> np.ndarray:
    """``(c sd)^2`` or ``c^2 var``: each input's share of the variance, unnormalised."""
    return (c * v) ** 2 if kind == "sd" else c**2 * v


class LinearIndices(IndexArray):
    """Closed-form Sobol indices of the first-order model, ``(..., d, q)``, labelled.

    What :func:`linear_indices` and :func:`indices_at_poses` return: the array of indices
    (indexed and computed with as any array; what is computed from it is a plain array) that
    also knows its input and output names.  For a linear model the first-order and the total
    index are one number, so :meth:`to_df` writes it as both ``S1`` and ``ST``: the table of
    a sampled estimate (``SobolIndices.to_df()``), to set beside it.

    >>> LinearIndices([[0.8], [0.2]], names=["ex", "ey"]).to_df().values.tolist()
    [['y1', 'ex', 0.8, 0.8], ['y1', 'ey', 0.2, 0.2]]

    Parameters
    ----------
    values : (..., d, q) array_like
        The indices, inputs by outputs, after any leading axes (poses).
    names : sequence of str (d,), optional
        Input names (default ``x1`` ... ``xd``).
    outputs : sequence of str (q,), optional
        Output names (default ``y1`` ... ``yq``).
    lead : sequence of str, optional
        Names of the leading axes (default ``axis0``, ...).
    """

    columns = ("S1", "ST")


def _pose_axes(ndim: int) -> tuple[str, ...]:
    """Names of the leading (pose) axes of a Jacobian of ``ndim`` axes: ``pose`` or ``pose0``..."""
    k = ndim - 2
    return ("pose",) if k == 1 else tuple(f"pose{i}" for i in range(k))


def linear_indices(jacobian: np.ndarray, inputs: Inputs | None = None, *, sd=None, var=None,
                   outputs: Sequence[str] | None = None) -> LinearIndices:
    """Sobol indices of a linear model with independent inputs (first-order = total).

    For input i and output k, ``J_ki^2 sd_i^2 / sum_j J_kj^2 sd_j^2`` (any distribution).
    ``jacobian`` (..., q, d); the spread of the inputs as an :class:`Inputs` or, by keyword,
    ``sd=`` or ``var=`` (d,).  An output with zero variance gets zeros.  The indices come
    input by output, ``(..., d, q)``, as every index array of this package.

    Parameters
    ----------
    jacobian : array (..., q, d)
        Output sensitivities (e.g. ``machine.jacobian(pose)``: mm or rad per error unit).
    inputs : Inputs, optional
        The inputs (their standard deviations are used).
    sd : array (d,), optional
        Standard deviations of the inputs (mm, rad), instead of ``inputs``.
    var : array (d,), optional
        Variances of the inputs (mm^2, rad^2), instead of ``inputs``.
    outputs : sequence of str (q,), optional
        Output names (default ``y1`` ... ``yq``), labels of the result (the inputs' are
        ``inputs.names``, else ``x1`` ... ``xd``).

    Returns
    -------
    LinearIndices (..., d, q)
        Indices; each output's column sums to 1 (0 for a zero-variance output).  Leading axes
        are named ``pose`` (one) or ``pose0``, ``pose1``... in ``.to_df()``.

    Raises
    ------
    ValueError
        Unless exactly one of ``inputs``, ``sd``, ``var`` is given, (d,), finite, >= 0.

    Examples
    --------
    >>> import numpy as np
    >>> linear_indices(np.array([[1.0, 2.0]]), sd=np.array([2.0, 1.0])).tolist()
    [[0.5], [0.5]]
    """
    c = np.asarray(jacobian, dtype=float)
    kind, v = _spread(inputs, sd, var, c.shape[-1], "sd")
    return LinearIndices(np.ascontiguousarray(np.swapaxes(_shares(_squares(c, kind, v)), -1, -2)),
                         names=_input_names(inputs), outputs=outputs, lead=_pose_axes(c.ndim))


def _input_names(inputs) -> tuple[str, ...] | None:
    return inputs.names if isinstance(inputs, Inputs) else None


def uniform_moments(bounds, d: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Means and variances ``((low + high) / 2, (high - low)^2 / 12)``, each (d,), of uniforms.

    Of independent uniforms on ``bounds`` (2, d) (the moments of ``Inputs.from_bounds(bounds)``
    for symmetric bounds, to the bit).  ``d``, when given, is the required width.

    Raises ValueError unless ``bounds`` is (2, d), finite, with high > low in every column.

    Parameters
    ----------
    bounds : array (2, d)
        Lower and upper bounds (mm, rad).
    d : int, optional
        The required number of inputs.

    Returns
    -------
    mean, var : arrays (d,)
    """
    b = np.asarray(bounds, dtype=float)
    want = d if d is not None else (b.shape[1] if b.ndim == 2 else "d")
    if (b.ndim != 2 or b.shape[0] != 2 or (d is not None and b.shape[1] != d)
            or not np.all(np.isfinite(b)) or np.any(b[1] <= b[0])):
        raise ValueError(f"bounds must be (2, {want}) with high > low (finite), "
                         f"got shape {b.shape}")
    return b.mean(0), (b[1] - b[0]) ** 2 / 12.0


def gauss_legendre_unit(nodes: int) -> tuple[np.ndarray, np.ndarray]:
    """The ``nodes``-point Gauss-Legendre rule on [0, 1]: points and weights (summing to 1).

    Exact for polynomials of degree <= 2 nodes - 1.  The 2-point rule is written in closed
    form, ``1/2 -+ 1/(2 sqrt 3)`` with weights 1/2 (numpy's ``leggauss(2)`` is one ulp off
    at one node), so its points are symmetric to the last bit; the others are numpy's.

    Parameters
    ----------
    nodes : int
        Points of the rule (>= 1).

    Returns
    -------
    points, weights : arrays (nodes,)
    """
    nodes = integer(nodes, "nodes", low=1)
    if nodes == 2:
        return 0.5 + np.array([-1.0, 1.0]) / (2.0 * np.sqrt(3.0)), np.array([0.5, 0.5])
    x, w = np.polynomial.legendre.leggauss(int(nodes))
    return 0.5 + x / 2.0, w / 2.0


def _interval(name, value) -> tuple[float, float]:
    lo_hi = np.asarray(value, dtype=float)
    if lo_hi.shape != (2,) or not np.all(np.isfinite(lo_hi)) or lo_hi[1] <= lo_hi[0]:
        raise ValueError(f"pose_bounds[{name!r}] must be (low, high) with high > low, "
                         f"got {value!r}")
    lo, hi = value
    return float(lo), float(hi)


def _moments(mean, var) -> tuple[np.ndarray, np.ndarray]:
    mean, var = np.asarray(mean, dtype=float), np.asarray(var, dtype=float)
    if mean.ndim != 1 or mean.shape != var.shape:
        raise ValueError(f"mean and var must be (d,) arrays of one shape, got {mean.shape}, "
                         f"{var.shape}")
    if np.any(var < 0) or not np.all(np.isfinite(var)):
        raise ValueError("var must be finite and >= 0")
    return mean, var


def _rows(jac: np.ndarray, components) -> np.ndarray:
    """The output rows ``components`` of (M, q, d): all (None), the first k (an int), or the
    listed rows (a sequence)."""
    if components is None:
        return jac
    if isinstance(components, int | np.integer):
        return jac[:, :components]
    return jac[:, list(components)]


class PoseBoxIndices(tuple):
    """First-order and total indices ``(T, d, q)`` and output variances ``(T, q)``, labelled.

    What :func:`pose_box_indices` returns: the triple ``s1, st, var`` it has always returned
    (it unpacks and indexes as that tuple), with the input and output names and
    :meth:`to_df`.

    Parameters
    ----------
    s1, st : (T, d, q) array_like
        First-order and total indices of T cases, inputs by outputs.
    var : (T, q) array_like
        The output variance of each case, pooled over the box.
    names : sequence of str (d,), optional
        Input names (default ``x1`` ... ``xd``).
    outputs : sequence of str (q,), optional
        Output names (default ``y1`` ... ``yq``).

    Raises
    ------
    ValueError
        If the shapes do not agree or the names do not match them.
    """

    def __new__(cls, s1, st, var, *, names: Sequence[str] | None = None,
                outputs: Sequence[str] | None = None) -> PoseBoxIndices:
        s1, st, var = (np.asarray(v, dtype=float) for v in (s1, st, var))
        if s1.ndim != 3 or st.shape != s1.shape or var.shape != s1.shape[::2]:
            raise ValueError(f"s1, st must be (T, d, q) and var (T, q), got {s1.shape}, "
                             f"{st.shape}, {var.shape}")
        self = super().__new__(cls, (s1, st, var))
        self.names = labels(names, s1.shape[1], "x", "input")
        self.outputs = labels(outputs, s1.shape[2], "y", "output")
        return self

    @property
    def s1(self) -> np.ndarray:
        """(T, d, q) ndarray: the first-order indices."""
        return self[0]

    @property
    def st(self) -> np.ndarray:
        """(T, d, q) ndarray: the total indices."""
        return self[1]

    @property
    def var(self) -> np.ndarray:
        """(T, q) ndarray: the output variances, pooled over the box."""
        return self[2]

    def to_df(self) -> pd.DataFrame:
        """The indices as a long table: one row per (case, output, input).

        Returns
        -------
        pandas.DataFrame
            Columns ``case`` (position along T), ``output``, ``input``, ``S1``, ``ST`` and
            ``var`` (the output's variance in that case); cases outermost, then outputs.
        """
        t, d, q = self.s1.shape
        return pd.DataFrame({
            "case": np.repeat(np.arange(t), d * q),
            "output": np.tile(np.repeat(self.outputs, d), t).tolist(),
            "input": list(self.names) * (q * t),
            "S1": np.swapaxes(self.s1, 1, 2).ravel(),
            "ST": np.swapaxes(self.st, 1, 2).ravel(),
            "var": np.repeat(self.var.ravel(), d)})


def pose_box_indices(jacobian_fn: Callable[[dict[str, np.ndarray]], np.ndarray],
                     inputs: Inputs | None = None, *, mean=None, var=None,
                     poses: Mapping | None = None, pose_bounds: Mapping | None = None,
                     components: int | Sequence[int] | None = None, nodes: int = 2,
                     names: Iterable[str] | None = None, required: Iterable[str] = (),
                     outputs: Sequence[str] | None = None) -> PoseBoxIndices:
    """Exact Sobol indices of the first-order model with part of the pose uniform in a box.

    ``jacobian_fn(flat_poses)``: the (M, q_all, d) Jacobians at M poses given as a mapping of
    names to (M,) arrays (e.g. ``machine.jacobian``).  ``inputs``: the inputs (their means
    and variances), or by keyword ``mean=``, ``var=`` (d,) (:func:`uniform_moments` for
    uniforms; any independent laws).
    ``poses`` maps pose names to scalars or (T,) arrays: T cases (e.g. T tool lengths).
    ``pose_bounds`` maps some pose names to ``(low, high)``: those coordinates are independent
    uniforms on the box (the same for every case; a name in both takes the box), independent
    of the errors.  ``components``: the output rows kept (the first k for an int, or a list;
    None: all).  ``names``: the allowed pose names, ``required``: those that must be given
    (checked when passed; a machine wrapper passes its axes).

    Returns ``S1``, ``ST`` (T, d, q) and the output variance ``V`` (T, q), pooled over the box,
    by the formulas of the module docstring, with the pose expectations taken by a tensor
    Gauss-Legendre rule of ``nodes`` points per box coordinate: one batched ``jacobian_fn``
    call on T x nodes^k poses (k box coordinates).  An output with zero variance gets zeros.

    Exactness: the integrands are ``J``, ``J^2`` and ``(J m)^2``, of degree 2p in a
    coordinate in which ``J`` is a polynomial of degree p; the n-point rule is exact up to
    degree 2n - 1, so ``nodes = 2`` is exact when ``J`` is affine in each box coordinate --
    true of every linear axis of a serial machine whose rotary axes stay fixed (the three-axis
    machines: Abbe arms grow linearly with the travels).  A rotary axis enters through its
    cosine and sine, which no polynomial rule integrates exactly: the result then converges
    as ``nodes`` grows (geometrically, the integrand being analytic), and ``nodes`` must be
    chosen by checking that doubling it does not change the indices at the precision wanted.
    With 2 nodes the weights are powers of two, so equal-coefficient inputs get bitwise-equal
    indices and the sums equal plain means to the bit.

    Parameters
    ----------
    jacobian_fn : callable
        ``flat_poses -> (M, q_all, d)`` Jacobians.
    inputs : Inputs, optional
        The inputs (their means and variances are used).
    mean, var : arrays (d,), optional
        Means and variances of the inputs (mm, rad and their squares), instead of ``inputs``.
    poses : mapping, optional
        Pose name -> scalar or (T,) array (mm, rad).
    pose_bounds : mapping, optional
        Pose name -> (low, high): uniform over the box.
    components : int or sequence of int, optional
        Output rows kept.
    nodes : int
        Gauss-Legendre points per box coordinate.
    names : iterable of str, optional
        Allowed pose names.
    required : iterable of str
        Pose names that must be given.
    outputs : sequence of str (q,), optional
        Names of the output rows kept (default ``y1`` ... ``yq``), labels of the result (the
        inputs' are ``inputs.names``, else ``x1`` ... ``xd``).

    Returns
    -------
    PoseBoxIndices
        Unpacks as ``S1, ST`` (T, d, q), the first-order and total indices, and ``V`` (T, q),
        the output variance pooled over the box.
    """
    if inputs is not None and mean is not None:
        raise ValueError("give the inputs once: an Inputs, or mean= and var=")
    if inputs is None and (mean is None or var is None):
        raise ValueError("give the inputs: an Inputs, or both mean= and var=")
    if inputs is not None:
        mean, var = inputs.mean, inputs.var
    mean, var = _moments(mean, var)
    u, w = gauss_legendre_unit(nodes)
    base = {k: np.atleast_1d(np.asarray(v, dtype=float)) for k, v in (poses or {}).items()}
    if any(v.ndim != 1 for v in base.values()):
        raise ValueError("pose values must be scalars or 1-d arrays")
    sizes = {v.shape[0] for v in base.values()} - {1}
    if len(sizes) > 1:
        raise ValueError(f"pose arrays of different lengths {sorted(sizes)}")
    n_cases = sizes.pop() if sizes else 1
    box = {k: _interval(k, b) for k, b in (pose_bounds or {}).items()}
    if names is not None:
        allowed = set(names)
        unknown = [k for k in [*box, *base] if k not in allowed]
        if unknown:
            raise ValueError(f"unknown pose name(s) {unknown}")
    missing = [a for a in required if a not in base and a not in box]
    if missing:
        raise ValueError(f"pose lacks axis value(s) {missing}")
    keys = list(box)
    if keys:
        grid = np.array(np.meshgrid(*[u] * len(keys), indexing="ij")).reshape(len(keys), -1)
        weight = np.prod(np.array(np.meshgrid(*[w] * len(keys), indexing="ij"))
                         .reshape(len(keys), -1), axis=0)
    else:
        grid, weight = np.zeros((0, 1)), np.ones(1)
    n_nodes = grid.shape[1]
    flat = {k: np.repeat(np.broadcast_to(v, (n_cases,)), n_nodes) for k, v in base.items()}
    for k, x in zip(keys, grid, strict=True):
        lo, hi = box[k]
        flat[k] = np.tile(lo + x * (hi - lo), n_cases)
    jac = np.asarray(jacobian_fn(flat), dtype=float)
    if jac.ndim != 3 or jac.shape[0] != n_cases * n_nodes or jac.shape[2] != mean.shape[0]:
        raise ValueError(f"jacobian_fn must return (M, q, {mean.shape[0]}) with M = "
                         f"{n_cases * n_nodes} poses, got {jac.shape}")
    c = _rows(jac, components)
    c = c.reshape(n_cases, n_nodes, *c.shape[1:])              # (T, G, q, d)
    wc = weight[:, None, None]
    ec, ec2 = (wc * c).sum(1), (wc * c**2).sum(1)              # (T, q, d)
    mean_part = (c * mean).sum(-1)                             # (T, G, q)
    centred = mean_part - (weight[:, None] * mean_part).sum(1)[:, None]
    v = (ec2 * var).sum(-1) + (weight[:, None] * (centred * centred)).sum(1)   # (T, q)
    vv = v[..., None]
    s1 = np.divide(ec**2 * var, vv, out=np.zeros_like(ec), where=vv > 0)
    st = np.divide(ec2 * var, vv, out=np.zeros_like(ec), where=vv > 0)
    return PoseBoxIndices(np.swapaxes(s1, 1, 2), np.swapaxes(st, 1, 2), v,
                          names=_input_names(inputs), outputs=outputs)


def indices_at_poses(jacobian: np.ndarray, inputs: Inputs | None = None, *, sd=None, var=None,
                     outputs: Sequence[str] | None = None) -> LinearIndices:
    """Sobol indices (first order = total) of the first-order model at each of P poses.

    Parameters
    ----------
    jacobian : (P, q, d) array
        d(outputs)/d(inputs) at zero inputs, per pose (e.g. ``machine.jacobian``).
    inputs : Inputs, optional
        The independent inputs (any laws; their variances are used).
    sd : (d,) array, optional
        Standard deviations of the inputs, instead of ``inputs``.
    var : (d,) array, optional
        Variances of the inputs, instead of ``inputs``.
    outputs : sequence of str (q,), optional
        Output names (default ``y1`` ... ``yq``), labels of the result (the inputs' are
        ``inputs.names``, else ``x1`` ... ``xd``).

    Returns
    -------
    LinearIndices (P, d, q)
        ``J_ki^2 var_i / sum_j J_kj^2 var_j``; an output with no variance at a pose gets zeros.
        The kernel of a pose atlas: one batched expression, no loop over poses.
    """
    c = np.asarray(jacobian, dtype=float)
    if c.ndim != 3:
        raise ValueError(f"jacobian must be (P, q, d), got {c.shape}")
    kind, v = _spread(inputs, sd, var, c.shape[-1], "var")
    return LinearIndices(np.swapaxes(_shares(_squares(c, kind, v)), 1, 2),
                         names=_input_names(inputs), outputs=outputs, lead=("pose",))


class Remainder(NamedTuple):
    """What the first-order model misses at one pose, per output (q,).

    Attributes
    ----------
    ratio : array (q,)
        RMS of ``model(e) - model(0) - J e`` over the samples, divided by the std of model(e).
    centred_ratio : array (q,)
        The same with the remainder centred (its mean moves no index): <= ``ratio``.
    max_abs : array (q,)
        Largest absolute remainder over the samples (output units).
    """

    #: RMS of ``model(e) - model(0) - J e`` over the samples, divided by the std of model(e)
    ratio: np.ndarray
    #: the same with the remainder centred (its mean moves no index): <= ``ratio``
    centred_ratio: np.ndarray
    #: largest absolute remainder over the samples (output units)
    max_abs: np.ndarray


def nonlinear_remainder(model: Callable[[np.ndarray], np.ndarray], jacobian: np.ndarray,
                        errors: np.ndarray) -> Remainder:
    """The size of the part of the exact model the linear model misses, at one pose.

    ``model(errors)``: the exact chain at that pose, (n, d) -> (n, q) (or (n,));
    ``jacobian`` (q, d) its first-order Jacobian there; ``errors`` (n, d) samples of the
    inputs.  With ``r = model(e) - model(0) - e J^T``, returns per output
    ``ratio = RMS(r) / std(model(e))``, ``centred_ratio = std(r) / std(model(e))`` and
    ``max_abs = max |r|`` (a :class:`Remainder`).

    Why it matters: write ``y = l + r`` with ``l`` linear.  Every variance in a Sobol index
    moves from that of ``l`` by ``2 Cov(., r) + Var(r)``, and ``|Cov(l, r)| <= sd(l) sd(r)``,
    so to first order the sampled indices of the exact model can differ from the closed form
    of this module by about twice ``centred_ratio`` (at most) beyond their sampling noise;
    ``ratio`` (which also counts the mean of ``r``, moving no index) is a looser bound.  An
    output with zero spread gets ratio 0 when its remainder is zero too, else inf.

    Parameters
    ----------
    model : callable
        ``(n, d) -> (n, q)`` (or (n,)): the exact chain at the pose.
    jacobian : array (q, d)
        Its first-order Jacobian there.
    errors : array (n, d)
        Samples of the inputs (mm, rad).

    Returns
    -------
    Remainder
    """
    e = np.asarray(errors, dtype=float)
    jac = np.asarray(jacobian, dtype=float)
    if e.ndim != 2 or jac.ndim != 2 or jac.shape[1] != e.shape[1]:
        raise ValueError(f"errors must be (n, d) and jacobian (q, d), got {e.shape}, "
                         f"{jac.shape}")

    def run(x):
        y = np.asarray(model(x), dtype=float)
        return y[:, None] if y.ndim == 1 else y

    y = run(e)
    if y.shape != (e.shape[0], jac.shape[0]):
        raise ValueError(f"model must return ({e.shape[0]}, {jac.shape[0]}), got {y.shape}")
    r = y - run(np.zeros((1, e.shape[1]))) - e @ jac.T
    sd = y.std(0)

    def over_sd(num):
        out = np.where(num > 0, np.inf, 0.0)
        return np.divide(num, sd, out=out, where=sd > 0)

    return Remainder(over_sd(np.sqrt(np.mean(r * r, axis=0))), over_sd(r.std(0)),
                     np.abs(r).max(0))
