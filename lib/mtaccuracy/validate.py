"""The library's argument checks, written once (issue 25 item 5).

Every public function checks its integer and probability arguments through these helpers, so
that the same kind of argument is refused with the same words everywhere, and a bound (``folds``
at most n/2, say) is stated once, at the call, not re-derived in a hand-copied ``if``.  The
messages name the argument, the range it must lie in and the value given.

The helpers are written by hand rather than taken from scikit-learn's ``validate_params``:
that decorator is private API (``sklearn.utils._param_validation``) and would make the science
layer's lowest module depend on scikit-learn.
"""

from __future__ import annotations

import numbers
import os
import stat

import numpy as np

__all__ = ["integer", "probability", "rng", "file_bytes", "FileRefused"]


def _range(low, high) -> str:
    if low is not None and high is not None:
        return f"an integer in [{low}, {high}]"
    if low is not None:
        return f"an integer >= {low}"
    if high is not None:
        return f"an integer <= {high}"
    return "an integer"


def integer(value, name: str, *, low: int | None = None, high: int | None = None) -> int:
    """``value`` as a Python int, or a ValueError naming ``name``, its range and the value.

    Parameters
    ----------
    value
        An integer (Python or numpy) or a float with an integral value (``1e5``, as a notebook
        parameter may be written).  Booleans, non-finite and fractional numbers are refused.
    name
        The argument's name as the caller's signature spells it (it is what the message says).
    low, high
        Inclusive bounds; None for none.

    Returns
    -------
    int
        The value as a Python int (a numpy integer or integral float converted).

    Raises
    ------
    ValueError
        When the value is not an integer or lies outside [low, high].

    Examples
    --------
    >>> integer(1e3, "n", low=2)
    1000
    >>> integer(3, "folds", low=2, high=2)
    Traceback (most recent call last):
    ...
    ValueError: folds must be an integer in [2, 2], got 3
    """
    ok = not isinstance(value, bool | np.bool_)
    if ok and isinstance(value, numbers.Integral):
        out = int(value)
    elif ok and isinstance(value, numbers.Real) and np.isfinite(value) \
            and float(value) == int(value):
        out = int(value)
    else:
        raise ValueError(f"{name} must be {_range(low, high)}, got {value!r}")
    if (low is not None and out < low) or (high is not None and out > high):
        raise ValueError(f"{name} must be {_range(low, high)}, got {value!r}")
    return out


def probability(value, name: str) -> float:
    """``value`` as a float in [0, 1], or a ValueError naming ``name`` and the value.

    Parameters
    ----------
    value
        A real number (a crossover or mutation rate, a quantile level).
    name
        The argument's name as the caller's signature spells it.

    Returns
    -------
    float
    """
    ok = not isinstance(value, bool | np.bool_) and isinstance(value, numbers.Real)
    if not ok or not 0.0 <= float(value) <= 1.0:
        raise ValueError(f"{name} must be a probability in [0, 1], got {value!r}")
    return float(value)


def rng(seed) -> np.random.Generator:
    """The generator behind the library's one randomness argument, ``seed``.

    Parameters
    ----------
    seed
        None (fresh entropy), an int >= 0, a ``numpy.random.SeedSequence``, or a
        ``numpy.random.Generator``, which is used as it is so that the caller's stream continues.

    Returns
    -------
    numpy.random.Generator
    """
    if isinstance(seed, bool | np.bool_):
        raise ValueError(f"seed must be None, an integer or a numpy Generator, got {seed!r}")
    try:
        return np.random.default_rng(seed)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"seed must be None, an integer >= 0 or a numpy Generator, "
                         f"got {seed!r}") from exc


class FileRefused(ValueError):
    """A path that is not a readable regular file within its reader's size (:func:`file_bytes`).

    ``str()`` is the problem alone, for the reader to put after its file's name; ``reason``
    says which (``"missing"``, ``"not a file"``, ``"too large"``, ``"unreadable"``) and
    ``size`` the file's size in bytes when it is known to be too large, so that a reader adds
    its own hint by the reason, never by the wording."""

    def __init__(self, problem: str, *, reason: str, size: int | None = None):
        super().__init__(problem)
        self.reason, self.size = reason, size


_KINDS = ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
          (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
          (stat.S_ISSOCK, "a socket"))


def _kind(mode: int) -> str | None:
    """What a file that is not regular is, from its ``st_mode``; None for a regular file."""
    if stat.S_ISREG(mode):
        return None
    return next((name for test, name in _KINDS if test(mode)), "not a regular file")


def file_bytes(path, *, max_bytes: int) -> bytes:
    """The bytes of a regular file of at most ``max_bytes``, refused before a byte is read.

    Every reader of a user's file (probe file, thermal folder, axis table, ranges) reads
    through this, so that a directory, a FIFO, a device, a socket, or a link to any of them is
    refused at once instead of hanging (a FIFO) or filling memory (a link to ``/dev/zero``).
    The file is opened non-blocking and checked again on its descriptor (it cannot be swapped
    between the check and the read), and at most ``max_bytes + 1`` bytes are read (a file that
    grows while being read is refused too).  Written by hand: ``open()`` and ``pathlib`` block
    on a FIFO and read devices.

    Parameters
    ----------
    path : str or os.PathLike
        The file; a symbolic link is followed to what it points at.
    max_bytes : int
        The reader's documented largest file.

    Returns
    -------
    bytes

    Raises
    ------
    FileRefused
        Naming the problem: not found, not a regular file (which kind), larger than
        ``max_bytes``, or unreadable (the operating system's reason).
    """
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise FileRefused("file not found", reason="missing") from None
    except (OSError, ValueError) as exc:          # a dangling link loop, a NUL in the path
        raise FileRefused(f"cannot be read ({exc.strerror if isinstance(exc, OSError) else exc})",
                          reason="unreadable") from None
    kind = _kind(st.st_mode)
    if kind is not None:
        raise FileRefused(f"is {kind}, not a regular file", reason="not a file")
    if st.st_size > max_bytes:
        raise FileRefused(f"{st.st_size} bytes; files up to {max_bytes} bytes are read",
                          reason="too large", size=st.st_size)
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except OSError as exc:
        raise FileRefused(f"cannot be read ({exc.strerror})", reason="unreadable") from None
    with os.fdopen(fd, "rb") as handle:
        kind = _kind(os.fstat(fd).st_mode)
        if kind is not None:
            raise FileRefused(f"is {kind}, not a regular file", reason="not a file")
        raw = handle.read(max_bytes + 1)
    if len(raw) > max_bytes:
        raise FileRefused(f"more than {max_bytes} bytes; files up to {max_bytes} bytes are read",
                          reason="too large")
    return raw
