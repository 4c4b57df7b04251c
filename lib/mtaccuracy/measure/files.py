"""Reading a measurement file (ISO 230-2 positioning, ISO 230-4 circle) into checked columns.

The readers of :mod:`~mtaccuracy.measure.iso230_2` and :mod:`~mtaccuracy.measure.iso230_4`
share this: the file is read once (:func:`mtaccuracy.validate.file_bytes`), decoded as UTF-8
(a byte-order mark allowed), split into records with the lines an editor shows
(:func:`mtaccuracy.csvlines.records`, ``#`` comments and blank lines skipped), and every
problem found is collected with its line and the fix, then raised at once as one
:class:`MeasurementFileError` before any evaluation starts.

Why hand-written: the schemas and their checks are ours; pandas does not report lines.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import csvlines, validate

__all__ = ["MeasurementFileError", "BelowStandardWarning", "Problems", "Rows", "read_rows",
           "MAX_FILE_BYTES", "MAX_ROWS", "SHOWN"]

#: A measurement file larger than this (bytes) is refused before it is read: 200 000 rows of
#: a circle test at about 60 characters a row take 12 MB.
MAX_FILE_BYTES = 20_000_000
#: Data rows beyond this are refused (a laser or ballbar file has thousands).
MAX_ROWS = 200_000
#: A refusal lists at most this many problems (and says how many more there are).
SHOWN = 20


class MeasurementFileError(ValueError):
    """A measurement file that breaks its schema: every problem with its line and the fix.

    Parameters
    ----------
    path : str or os.PathLike
        The file at fault.
    problems : list of (int or None, str)
        ``(line, problem)`` pairs: the physical line (1-based, as an editor shows it; None for
        the whole file) and what is wrong and what to do.
    """

    def __init__(self, path, problems):
        self.path, self.problems = str(path), sorted(
            problems, key=lambda p: (-1 if p[0] is None else p[0]))
        self.line = self.problems[0][0] if self.problems else None
        shown = [f"{self.path}" + ("" if ln is None else f", line {ln}") + f": {text}"
                 for ln, text in self.problems[:SHOWN]]
        more = len(self.problems) - SHOWN
        if more > 0:
            shown.append(f"... and {more} more problem(s)")
        super().__init__("\n".join(shown))


class BelowStandardWarning(UserWarning):
    """A test evaluated although it is smaller than its standard asks (fewer cycles or
    targets): the values follow the standard's definitions, their uncertainty is larger."""


class Problems:
    """The problems found in one file, raised at once by :meth:`raise_if_any`.

    Parameters
    ----------
    path : str or os.PathLike
        The file being read.
    """

    def __init__(self, path):
        self.path, self.items = path, []

    def add(self, line, problem: str) -> None:
        """Record one problem.

        Parameters
        ----------
        line : int or None
            Its physical line (None: the whole file).
        problem : str
            What is wrong and the fix.
        """
        self.items.append((None if line is None else int(line), problem))

    def raise_if_any(self) -> None:
        """Raise a :class:`MeasurementFileError` listing every problem, if there is one."""
        if self.items:
            raise MeasurementFileError(self.path, self.items)


@dataclass(frozen=True)
class Rows:
    """A file's data rows as text, by column, with their lines.

    Attributes
    ----------
    path : str
        The file.
    header_line : int
        The header's physical line.
    lines : (n_rows,) ndarray of int
        Each data row's first physical line.
    text : dict of str to list of str
        The stripped text of each required column's cells, one per data row.
    """

    path: str
    header_line: int
    lines: np.ndarray
    text: dict

    def numbers(self, column: str, problems: Problems, *, unit: str) -> np.ndarray:
        """A column as floats; a cell that is not a finite number is a problem at its line.

        Parameters
        ----------
        column : str
            The column's name.
        problems : Problems
            Where a bad cell is recorded.
        unit : str
            The unit the column is written in, for the message.

        Returns
        -------
        (n_rows,) ndarray of float
            The values (NaN where a cell was refused).
        """
        out = np.full(len(self.lines), np.nan)
        for k, cell in enumerate(self.text[column]):
            try:
                value = float(cell)
            except ValueError:
                comma = "," in cell or ";" in cell
                problems.add(self.lines[k], (
                    f"{column} is {cell!r}, not a number: write a number in {unit}"
                    + (" with a decimal point (1.5)" if comma else "")))
                continue
            if not math.isfinite(value):
                problems.add(self.lines[k], f"{column} is {cell!r}: write a finite number in "
                                            f"{unit}")
                continue
            out[k] = value
        return out


def read_rows(path, *, columns: tuple, what: str) -> Rows:
    """The data rows of a CSV measurement file, refused with every problem of its layout.

    Refuses (at once, every problem with its line): a path that is not a readable file of at
    most :data:`MAX_FILE_BYTES`, text that is not UTF-8, a record the csv module cannot read,
    an empty file, a header without a required column or with one twice, a data row whose
    number of fields differs from the header's, more than :data:`MAX_ROWS` rows, no data row.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    columns : tuple of str
        The required columns (others are ignored).
    what : str
        The file's kind for the messages ("an ISO 230-2 file").

    Returns
    -------
    Rows
        The text of the required columns, with the data rows' lines.

    Raises
    ------
    MeasurementFileError
        Naming the file, the line and the fix of every problem found.
    """
    header = ",".join(columns)
    try:
        raw = validate.file_bytes(path, max_bytes=MAX_FILE_BYTES)
    except validate.FileRefused as exc:
        raise MeasurementFileError(path, [(None, f"{exc}; {what} is a CSV file with the "
                                                 f"header {header}")]) from None
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise MeasurementFileError(path, [(csvlines.bad_byte_line(raw, exc), (
            "not UTF-8 text: save the file as CSV UTF-8"))]) from None
    problems = Problems(path)
    recs, names, head_line = [], None, None
    try:
        for rec in csvlines.records(text, comment="#"):
            if not any(f.strip() for f in rec.fields):
                continue
            if names is None:
                names, head_line = [f.strip() for f in rec.fields], rec.first
                continue
            recs.append(rec)
            if len(recs) > MAX_ROWS:
                raise MeasurementFileError(path, [(rec.first, (
                    f"more than {MAX_ROWS} data rows; {what} holds one test: split the "
                    f"file"))])
    except csvlines.CSVLineError as exc:
        raise MeasurementFileError(path, [(exc.line, exc.reason)]) from None
    if names is None:
        raise MeasurementFileError(path, [(None, f"the file is empty; {what} needs the header "
                                                 f"{header} and data rows")])
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        problems.add(head_line, f"column(s) {twice} appear more than once: keep one of each")
    missing = [c for c in columns if c not in names]
    if missing:
        low = {n.lower(): n for n in names}
        near = [f"{low[c]!r} -> {c!r}" for c in missing if c in low]
        problems.add(head_line, (
            f"missing column(s) {missing}; {what} needs the header {header}"
            + (f" (rename {', '.join(near)})" if near else "")))
    problems.raise_if_any()
    if not recs:
        raise MeasurementFileError(path, [(head_line, f"a header and no data rows; {what} "
                                                      f"needs one row per reading")])
    index = [names.index(c) for c in columns]
    for rec in recs:
        if len(rec.fields) != len(names):
            problems.add(rec.first, (
                f"{len(rec.fields)} fields, but the header names {len(names)} columns: one "
                f"value per column, decimal points (1.5), no thousands separators"))
    problems.raise_if_any()
    cells = {c: [rec.fields[j].strip() for rec in recs] for c, j in zip(columns, index,
                                                                         strict=True)}
    return Rows(str(path), head_line, np.array([r.first for r in recs]), cells)
