"""One result shape for the analysers: the numbers as before, labelled, with ``to_df()``.

Every analyser of this package returns what its callers have always indexed or unpacked, and
also knows the names of its inputs and outputs and gives itself as a long table (``to_df()``),
as SALib's results do:

* a pair or triple of arrays is a tuple subclass that unpacks as before
  (:class:`~mtaccuracy.sensitivity.SobolIndices`: ``s1, st = ...``;
  :class:`~mtaccuracy.sensitivity.PoseBoxIndices`: ``s1, st, var = ...``);
* a single array of values per input and output, ``(..., d, q)`` with any leading axes (poses,
  repeated designs), is an :class:`IndexArray`: a numpy array whose last two axes are labelled
  (:class:`~mtaccuracy.sensitivity.SpearmanCoefficients`,
  :class:`~mtaccuracy.sensitivity.LinearIndices`);
* a set of key errors per output is a dict subclass
  (:class:`~mtaccuracy.sensitivity.KeySets`).

Only the analyser's own result carries labels: anything computed from an :class:`IndexArray`
(an element or a slice, arithmetic, a reduction, a numpy function) is a plain ``ndarray``, so a
label can never name the wrong axis after a transpose or a slice.  Long tables put outputs
outermost, then inputs, as ``SobolIndices.to_df()`` always has.
"""

from __future__ import annotations

__all__ = ["IndexArray"]

from collections.abc import Sequence

import numpy as np
import pandas as pd


def labels(given: Sequence[str] | None, n: int, prefix: str, what: str) -> tuple[str, ...]:
    """``n`` names: ``given`` (checked: n distinct non-empty strings) or ``prefix1 .. prefixn``.

    Parameters
    ----------
    given : sequence of str (n,), optional
        The names.
    n : int
        How many.
    prefix : str
        Of the default names (``x``: ``x1`` ... ``xn``).
    what : str
        What they name, for the error message (``input``, ``output``).

    Returns
    -------
    tuple of str (n,)

    Raises
    ------
    ValueError
        If ``given`` has not n distinct non-empty strings.
    """
    if given is None:
        return tuple(f"{prefix}{k + 1}" for k in range(n))
    out = tuple(given)
    if len(out) != n or not all(isinstance(s, str) and s for s in out) or len(set(out)) != n:
        raise ValueError(f"{what} names must be {n} distinct non-empty strings, got {out!r}")
    return out


def _plain(x):
    """``x`` with every :class:`IndexArray` in it (nested in tuples and lists) a plain array."""
    if isinstance(x, IndexArray):
        return x.view(np.ndarray)
    if type(x) in (tuple, list):
        return type(x)(_plain(v) for v in x)
    if isinstance(x, tuple) and hasattr(x, "_fields"):       # a named tuple (EighResult)
        return type(x)(*(_plain(v) for v in x))
    return x


class IndexArray(np.ndarray):
    """Values per input and output, ``(..., d, q)``: a numpy array whose last two axes are named.

    It is the array the analyser has always returned (same shape, same numbers, indexed and
    computed with as before) with the names of its inputs (axis -2), outputs (axis -1) and
    leading axes, and :meth:`to_df`.  What is computed from it is a plain ``ndarray``
    (see the module docstring); methods that return a view of it (``reshape``, ``.T``) give an
    unlabelled one.

    >>> a = IndexArray([[0.25, 0.5], [0.75, 0.5]], names=["ex", "ey"], outputs=["X", "Y"])
    >>> a.to_df().values.tolist()
    [['X', 'ex', 0.25], ['X', 'ey', 0.75], ['Y', 'ex', 0.5], ['Y', 'ey', 0.5]]
    >>> type(a[0]).__name__, float(a.sum())
    ('ndarray', 2.0)

    Parameters
    ----------
    values : (..., d, q) array_like
        The values, inputs by outputs, after any leading axes.
    names : sequence of str (d,), optional
        Input names (default ``x1`` ... ``xd``).
    outputs : sequence of str (q,), optional
        Output names (default ``y1`` ... ``yq``).
    lead : sequence of str, optional
        Names of the leading axes, the columns of their positions in :meth:`to_df` (default
        ``axis0``, ``axis1``, ...).

    Raises
    ------
    ValueError
        If ``values`` has fewer than two axes or the names do not match its shape.
    """

    #: the column(s) :meth:`to_df` writes the values under
    columns: tuple[str, ...] = ("value",)

    def __new__(cls, values, *, names: Sequence[str] | None = None,
                outputs: Sequence[str] | None = None, lead: Sequence[str] | None = None):
        a = np.asarray(values, dtype=float)
        if a.ndim < 2:
            raise ValueError(f"values must be (..., d, q), got shape {a.shape}")
        obj = a.view(cls)
        obj.names = labels(names, a.shape[-2], "x", "input")
        obj.outputs = labels(outputs, a.shape[-1], "y", "output")
        nlead = a.ndim - 2
        obj.lead = tuple(f"axis{k}" for k in range(nlead)) if lead is None else tuple(lead)
        if len(obj.lead) != nlead:
            raise ValueError(f"{len(obj.lead)} names for {nlead} leading axes")
        return obj

    def __array_finalize__(self, obj):
        self.names = self.outputs = self.lead = None       # a view of it is not labelled

    def __array_ufunc__(self, ufunc, method, *inputs, out=None, **kwargs):
        if out is not None:
            kwargs["out"] = _plain(out)
        return getattr(ufunc, method)(*_plain(inputs), **kwargs)

    def __array_function__(self, func, types, args, kwargs):
        return _plain(super().__array_function__(func, types, args, kwargs))

    def __getitem__(self, key):
        return self.view(np.ndarray)[key]

    def __reduce__(self):
        return type(self)._restore, (self.view(np.ndarray).copy(), self.names, self.outputs,
                                     self.lead)

    @classmethod
    def _restore(cls, values, names, outputs, lead):
        return cls(values, names=names, outputs=outputs, lead=lead) if names else \
            values.view(cls)

    def copy(self, order="C"):
        """A copy, labelled as this array.

        Parameters
        ----------
        order : {"C", "F", "A", "K"}
            Memory layout, as ``numpy.ndarray.copy``.

        Returns
        -------
        IndexArray
        """
        out = np.ndarray.copy(self, order=order)
        out.names, out.outputs, out.lead = self.names, self.outputs, self.lead
        return out

    def _values(self) -> dict[str, np.ndarray]:
        """``{column: (n_rows,) values}`` for :meth:`to_df` (one column per :attr:`columns`)."""
        v = np.moveaxis(self.view(np.ndarray), -1, -2).ravel()
        return {c: v for c in self.columns}

    def to_df(self) -> pd.DataFrame:
        """The values as a long table: one row per (leading position, output, input).

        Returns
        -------
        pandas.DataFrame
            Columns: one per leading axis (its position), ``output``, ``input``, then the
            values (:attr:`columns`); leading axes outermost, then outputs, then inputs.

        Raises
        ------
        ValueError
            For an unlabelled array (a view of a labelled one).
        """
        if self.names is None:
            raise ValueError("this array is a view of a labelled result and has no labels")
        d, q = self.shape[-2:]
        lead_shape = self.shape[:-2]
        cols = {}
        for k, name in enumerate(self.lead):
            idx = np.indices(lead_shape)[k].ravel() if lead_shape else np.zeros(0, int)
            cols[name] = np.repeat(idx, d * q)
        m = int(np.prod(lead_shape, dtype=int))
        cols["output"] = np.tile(np.repeat(self.outputs, d), m).tolist()
        cols["input"] = list(self.names) * (q * m)
        cols.update(self._values())
        return pd.DataFrame(cols)
