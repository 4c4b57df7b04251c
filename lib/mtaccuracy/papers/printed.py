"""The papers' printed numbers: read from ``data/papers/``, and the precision they were printed at.

Published numbers live only in ``data/papers/<name>.csv`` (transcribed from the papers, as
text: ``"0.0776"`` keeps its printed digits).  They are read here and shown as "published";
never used as a computed result.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

#: ``data/papers/`` of the repository this library was imported from.
FOLDER = Path(__file__).resolve().parents[3] / "data" / "papers"


def published(name: str, required: list[str] | None = None, *, folder=None,
              on_read=None) -> pd.DataFrame:
    """Read ``data/papers/<name>.csv``, every cell as the text printed.

    Parameters
    ----------
    name : str
        The file's stem (``zheng2024_facts``).
    required : list of str, optional
        Columns that must be present and non-empty in every row.
    folder : path, optional
        Another folder of published tables (the tests' own).
    on_read : callable, optional
        Called with the file's path once it is read (a run's ``track``, for its provenance).

    Returns
    -------
    pandas.DataFrame
        The table, strings only; ``.attrs["path"]`` is the file read.

    Raises
    ------
    FileNotFoundError
        No such table (the message lists the ones there are).
    ValueError
        A required column is missing or empty (the message names the file and its rows).
    """
    path = Path(folder or FOLDER) / f"{name}.csv"
    if not path.exists():
        have = sorted(p.stem for p in path.parent.glob("*.csv"))
        raise FileNotFoundError(f"no published table {path}; available: {', '.join(have)}")
    df = pd.read_csv(path, dtype=str, keep_default_na=False)
    missing = [c for c in (required or []) if c not in df.columns]
    if missing:
        raise ValueError(f"{path}: missing column(s) {missing}; has {list(df.columns)}")
    for c in required or []:
        empty = df.index[df[c].str.strip() == ""].tolist()
        if empty:
            raise ValueError(f"{path}: column {c!r} is empty in row(s) {[i + 2 for i in empty]}")
    df.attrs["path"] = path
    if on_read is not None:
        on_read(path)
    return df


def last_digit_place(text: pd.Series) -> np.ndarray:
    """The place value of the last digit written in each numeric string.

    Parameters
    ----------
    text : pandas.Series
        Numbers as printed (``"0.0776"``, ``"1.2e-05"``, ``"120"``).

    Returns
    -------
    numpy.ndarray
        ``(n,)``: ``1e-4``, ``1e-6``, ``1`` for the examples.
    """
    out = np.zeros(len(text))
    for i, s in enumerate(text.astype(str)):
        s = s.strip().lower()
        mant, _, exp = s.partition("e")
        decimals = len(mant.split(".", 1)[1]) if "." in mant else 0
        out[i] = 10.0 ** (-decimals + (int(exp) if exp else 0))
    return out


def half_unit(published) -> float:
    """Half a unit of the last digit printed in ``published``: its printed precision.

    Parameters
    ----------
    published : str or number
        A number as printed.

    Returns
    -------
    float
        ``"0.0776"`` -> 5e-5, ``"12"`` -> 0.5, ``"1.2e-05"`` -> 5e-7.
    """
    return 0.5 * float(last_digit_place(pd.Series([str(published)]))[0])
