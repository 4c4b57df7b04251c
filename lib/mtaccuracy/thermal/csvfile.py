"""Reading one CSV file of the thermal schema, with messages that name the file's lines.

pandas reads the data (fast: numbers come as float columns); everything a message needs is
taken from the text itself.

Line numbers.  pandas numbers the rows it keeps, not the file's lines: it skips blank lines
and a quoted field may hold line breaks.  Every message about a bad row names the line an
editor shows, from :func:`mtaccuracy.csvlines.records` (the schema has no comment lines).  It
runs only when a message is written, so reading a good file costs nothing extra.  A row whose
every field is empty (``,,,`` or ``;;;``, as a spreadsheet writes an empty row) is dropped on
both sides, so that pandas' rows and the scanned records stay in step.

Separator.  A file is comma-separated with decimal points, or semicolon-separated (as
European spreadsheet software writes CSV) with decimal commas or points; the first non-blank
line, the header, tells which (:func:`_separator`); ``csvlines.records(text, sep=sep)``
scans either.

Encoding: UTF-8, a byte-order mark allowed; UTF-16 (Excel's "Unicode Text") is refused with
the way to save the file instead.

Read once.  A file is read through :func:`mtaccuracy.validate.file_bytes` (a directory, a FIFO,
a device or a link to one, or a file over :data:`~mtaccuracy.thermal.schema.MAX_FILE_BYTES`, is
refused before a byte is read), decoded once, and pandas parses the decoded text; the text is
kept on the file's :class:`Source` so that a message scans it without reading the file again.
A physical line longer than :data:`MAX_LINE_CHARS` (the csv module's field limit, 128 KiB) is
refused naming it: no field of the schema comes near it, and the scanner could not place it.
Every function here is private to the thermal readers (:mod:`~mtaccuracy.thermal.io`,
:mod:`~mtaccuracy.thermal.labexport`); written by hand, as the messages are ours.
"""

from __future__ import annotations

import io
import re
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

from .. import csvlines, validate
from .schema import _TEMP_UNIT, MAX_FILE_BYTES, DataFormatError, _problem

__all__: list[str] = []

#: The longest physical line read (characters): the csv module's field limit
#: (``csv.field_size_limit()``, 131072), beyond which its scanner cannot name a line.  A line of
#: the schema at its limits (100 sensors of long names, numbers) holds a few thousand.
MAX_LINE_CHARS = csvlines.FIELD_LIMIT
#: The largest whole number read as an experiment or measurement number (as written; beyond
#: it a number is refused, never wrapped round): 9 digits.
MAX_WHOLE = 999_999_999


class Source(type(Path())):
    """A file's path that carries its decoded text once :func:`_read_csv` has read it.

    Messages about its lines scan ``text`` instead of reading the file again (a file is read
    once, through :func:`mtaccuracy.validate.file_bytes`).
    """

    text: str | None = None


def _source(path) -> Source:
    """``path`` as a :class:`Source` (itself when it is one)."""
    return path if isinstance(path, Source) else Source(path)


def _text(path: Path) -> str:
    """The decoded text of ``path``: the one kept by :func:`_read_csv`, else read once now."""
    text = getattr(path, "text", None)
    if text is None:
        text = _decode(path, _file_bytes(path))
        if isinstance(path, Source):
            path.text = text
    return text


def _file_bytes(path: Path) -> bytes:
    """The bytes of ``path`` through :func:`mtaccuracy.validate.file_bytes`, or the refusal."""
    try:
        return validate.file_bytes(path, max_bytes=MAX_FILE_BYTES)
    except validate.FileRefused as exc:
        fix = (" (the schema needs temperatures.csv and errors.csv, or a lab export; see "
               "data/thermal/README.md)" if exc.reason == "missing" else
               " (the size limits of the schema need far less)" if exc.reason == "too large"
               else "")
        raise _problem(path, f"{exc}{fix}") from None


def _long_line(path: Path, text: str) -> None:
    """Refuse a physical line longer than :data:`MAX_LINE_CHARS`, naming it (linear time)."""
    if len(text) <= MAX_LINE_CHARS:
        return
    lengths = [len(line) for line in re.split(r"\r\n|\r|\n", text)]
    long = next((i for i, n in enumerate(lengths) if n > MAX_LINE_CHARS), None)
    if long is not None:
        raise _problem(path, f"line {long + 1} is {lengths[long]} characters long; lines up to "
                             f"{MAX_LINE_CHARS} characters are read (the csv module's field "
                             f"limit; no field of numbers and names comes near it: a stray "
                             f"paste, or not a CSV file?)")


def _decode(path: Path, raw: bytes) -> str:
    """The text of a file's bytes: UTF-8, without the byte-order mark Excel writes first."""
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")) or b"\x00" in raw[:4096]:
        what = ("UTF-16 text" if raw.startswith((b"\xff\xfe", b"\xfe\xff")) else
                "holds NUL bytes, as UTF-16 text does")
        raise _problem(path, f"{what} (what Excel saves as 'Unicode Text'); save the file as "
                             f"'CSV UTF-8' (comma-separated) instead")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        raise _problem(path, f"not UTF-8 text: byte 0x{raw[e.start]:02x} on line "
                             f"{csvlines.bad_byte_line(raw, e)}; save the file as UTF-8") from None
    return text.removeprefix("\ufeff")


def _header_line(text: str) -> tuple[int, int, int]:
    """Start, end and number (1-based) of the first non-blank line; ``(0, 0, 1)`` if blank."""
    first = re.search(r"\S", text)
    if first is None:
        return 0, 0, 1
    start = max(text.rfind("\n", 0, first.start()), text.rfind("\r", 0, first.start())) + 1
    head = text[:start]
    return (start, re.compile(r"[^\r\n]*").match(text, first.start()).end(),
            head.count("\n") + head.count("\r") - head.count("\r\n") + 1)


def _separator(path: Path, text: str) -> str:
    """The header's field separator, ``","`` or ``";"``; refuse tabs and a header with both.

    The header is the first non-blank line; ``";"`` when it holds ``;`` and no ``,``.
    """
    start, end, number = _header_line(text)
    line = text[start:end]
    if ";" in line and "," in line:
        raise _problem(path, f"the header (line {number}) holds both ',' and ';', so the field "
                             f"separator is unclear; save the file comma-separated with decimal "
                             f"points (or semicolon-separated, with no ',' in the header)")
    if ";" in line:
        return ";"
    if "\t" in line and "," not in line:
        raise _problem(path, f"tab-separated (the header, line {number}, holds tabs and no "
                             f"','); save the file comma-separated with decimal points, or "
                             f"semicolon-separated with decimal commas")
    return ","


def _records_of(text: str, sep: str):
    """A file's records (:func:`mtaccuracy.csvlines.records`), header first, fields as written."""
    return csvlines.records(text, sep=sep)


def _records(path: Path):
    """The file's records with their lines, the header first (see :func:`_records_of`)."""
    text = _text(path)
    return _records_of(text, _separator(path, text))


def _blank(fields) -> bool:
    """Whether a record is a row the reader drops (every field empty)."""
    return all(not f.strip() for f in fields)


def _where(path: Path, rows, column: int | None = None) -> list[tuple[int, str]]:
    """The line and, with ``column``, the field text of each data row of ``rows``, in order.

    Lines are 1-based, as an editor shows them; ``rows`` are positions in the table
    :func:`_read_csv` returns, ``column`` a position in the header; the text is '' where the
    row is short.
    """
    wanted = {int(r) for r in rows}
    found: dict[int, tuple[int, str]] = {}
    text = _text(path)
    sep = _separator(path, text)
    records = _records_of(text, sep)
    try:
        next(records, None)                          # the header
        row = -1
        for rec in records:
            if _blank(rec.fields):
                continue
            row += 1
            if row in wanted:
                f = rec.fields[column] if column is not None and column < len(rec.fields) else ""
                found[row] = (rec.first, f.strip())
                if len(found) == len(wanted):
                    break
    except csvlines.CSVLineError as exc:             # pandas read what the csv module cannot
        raise _problem(path, f"line {exc.line}: {exc.reason}") from None
    return [found.get(int(r), (-1, "")) for r in rows]


def _line_numbers(path: Path, rows) -> list[int]:
    """The file's line numbers (1-based, as an editor shows them) of data rows ``rows``.

    ``rows`` are positions in the table :func:`_read_csv` returns; the order is kept.
    """
    return [line for line, _ in _where(path, rows)]


def _lines(path: Path, mask) -> str:
    """The file's line numbers of the data rows where ``mask`` holds, at most ten shown."""
    rows = np.flatnonzero(np.asarray(mask))
    return f"{_line_numbers(path, rows[:10])}{' ...' if len(rows) > 10 else ''}"


def _unreadable(path: Path, exc: Exception) -> DataFormatError:
    """The message for a file pandas cannot tokenise, naming the line at fault.

    The line pandas names counts records, not lines, so the file is scanned again.
    """
    if isinstance(exc, pd.errors.EmptyDataError):
        return _problem(path, "is empty (no header line)")
    if isinstance(exc, pd.errors.ParserError):
        problem = _ragged(path)
        if problem is not None:
            return problem
    return _problem(path, f"not a readable CSV file ({exc})")


def _ragged(path: Path) -> DataFormatError | None:
    """The error for the first row wider than the header or a quote never closed, else None.

    When the first data rows all have more fields than the header, a comma file with decimal
    commas is the likely cause, and the message says so.
    """
    text = _text(path)
    sep = _separator(path, text)
    records = _records_of(text, sep)
    try:
        header = next(records, None)
        if header is None:
            return None
        width, wider, bad = len(header.fields), [], None
        for rec in records:
            if _blank(rec.fields):
                continue
            if len(wider) < 3:
                wider.append(len(rec.fields) > width)
            if bad is None and len(rec.fields) > width:
                bad = rec
            if bad is not None and len(wider) >= 3:
                break
    except csvlines.UnclosedQuote as exc:
        return _problem(path, f"a quoted field of the row starting on line {exc.line} is never "
                              f"closed (a '\"' is missing)")
    except csvlines.CSVLineError:
        return None
    if bad is None:
        return None
    hint = ("; the first rows all have more fields than the header: decimal commas (30,41) in "
            "a comma-separated file? Write decimal points, or separate the fields with ';'"
            if sep == "," and all(wider) else "")
    return _problem(path, f"line {bad.first} has {len(bad.fields)} fields, the header (line "
                          f"{header.first}) has {width}{hint}")


#: How a column without a name in the header is called in messages (1-based position).
_UNNAMED = "<unnamed column {}>"


def _header(path: Path, text: str, sep: str) -> list[str] | None:
    """The header's column names, stripped; refuse a name given twice.

    An empty name becomes :data:`_UNNAMED` (pandas would rename a second ``T1_degC``
    ``T1_degC.1`` silently).  None when the scanner cannot read the header (pandas' error then
    names the problem).
    """
    try:
        # the header line alone when it is a whole record (no quoted line break in it)
        rec = next(_records_of(text[:_header_line(text)[1]], sep), None)
    except csvlines.CSVLineError:
        try:
            rec = next(_records_of(text, sep), None)
        except csvlines.CSVLineError:
            return None
    if rec is None:
        return None
    names = [f.strip() for f in rec.fields]
    names = [n or _UNNAMED.format(i + 1) for i, n in enumerate(names)]
    seen: dict[str, list[int]] = {}
    for i, n in enumerate(names):
        seen.setdefault(n, []).append(i + 1)
    for n, at in seen.items():
        if len(at) > 1:
            what = (f"duplicate sensor name {n[:-len(_TEMP_UNIT)]!r}: column {n!r}"
                    if n.endswith(_TEMP_UNIT) else f"duplicate column name {n!r}")
            raise _problem(path, f"{what} appears {len(at)} times in the header (line "
                                 f"{rec.first}), as columns {', '.join(map(str, at))}; every "
                                 f"column needs its own name (two sensors, two names)")
    return names


def _read_csv(path: Path, on_read=None) -> pd.DataFrame:
    """Read one file of the schema (comma- or semicolon-separated, see :func:`_separator`).

    Its data rows are numbered by position (the file's line numbers of any of them:
    :func:`_where`), rows whose every field is empty are dropped, the columns carry the
    header's names (stripped).  A column whose every value reads as a number comes as numbers
    (an empty field is NaN), any other as text (:func:`_numeric` converts it and names the
    values that are not numbers).  ``df.attrs["separator"]`` is the separator.
    """
    if not isinstance(path, Source) or path.text is None:
        text = _decode(path, _file_bytes(path))      # refused before a byte is read
        if isinstance(path, Source):
            path.text = text
    else:
        text = path.text
    _long_line(path, text)
    sep = _separator(path, text)
    names = _header(path, text, sep)
    try:
        with warnings.catch_warnings():
            # a column mixing numbers and text, read in chunks: :func:`_numeric` handles it
            warnings.simplefilter("ignore", pd.errors.DtypeWarning)
            df = pd.read_csv(io.StringIO(text), sep=sep, decimal="," if sep == ";" else ".",
                             keep_default_na=False, na_values=[""], skipinitialspace=True)
        if on_read is not None:
            on_read(Path(path))
    except (pd.errors.ParserError, pd.errors.EmptyDataError) as exc:
        raise _unreadable(path, exc) from None
    if not isinstance(df.index, pd.RangeIndex):
        # pandas takes a first data row with more fields than the header as the sign of an
        # index column and shifts every column; the schema has none
        raise _ragged(path) or _problem(path, "has more fields in its rows than in its header")
    if names is not None and len(names) == len(df.columns):
        df.columns = names
    else:
        df.columns = [str(c).strip() for c in df.columns]
    empty = df.isna().all(axis=1).to_numpy()
    if empty.any():
        df = df.loc[~empty].reset_index(drop=True)
    if df.empty:
        raise _problem(path, "has a header but no data rows")
    df.attrs["separator"] = sep
    return df


def _parse(s: pd.Series, sep: str) -> np.ndarray:
    """The numbers of a text column, NaN where a value is not one.

    In a semicolon file a decimal comma reads as a decimal point.
    """
    text = s.astype(str).str.strip()
    if sep == ";":
        text = text.str.replace(",", ".", regex=False)
    return pd.to_numeric(text, errors="coerce").to_numpy(dtype=float)


def _is_number_column(s: pd.Series) -> bool:
    return pd.api.types.is_numeric_dtype(s.dtype) and not pd.api.types.is_bool_dtype(s.dtype)


def _numeric(path, df, column, integer=False) -> np.ndarray:
    s = df[column]
    values = (s.to_numpy(dtype=float) if _is_number_column(s)
              else _parse(s, df.attrs.get("separator", ",")))
    bad = ~np.isfinite(values)
    if bad.any():
        rows = np.flatnonzero(bad)
        where = _where(path, rows[:10], list(df.columns).index(column))
        shown = [v for _, v in where[:3]]
        hint = ("; a decimal comma? Write decimal points (30.41), or save the file "
                "semicolon-separated" if df.attrs.get("separator", ",") == "," and
                any(re.fullmatch(r"[+-]?\d*,\d+", v) for v in shown) else "")
        raise _problem(path, f"column {column!r} has a missing, NaN or non-numeric value "
                             f"({', '.join(map(repr, shown))}) on line(s) "
                             f"{[line for line, _ in where]}{' ...' if len(rows) > 10 else ''}"
                             f"{hint}")
    if integer:
        if not np.all(values == np.round(values)):
            raise _problem(path, f"column {column!r} must hold whole numbers (line(s) "
                                 f"{_lines(path, values != np.round(values))})")
        large = np.abs(values) > MAX_WHOLE
        if large.any():                              # named as written, never wrapped round
            rows = np.flatnonzero(large)
            where = _where(path, rows[:10], list(df.columns).index(column))
            raise _problem(path, f"column {column!r} holds {where[0][1]} on line {where[0][0]}"
                                 f"{f' (and {len(rows) - 1} more)' if len(rows) > 1 else ''}: "
                                 f"too large; {column} numbers have at most "
                                 f"{len(str(MAX_WHOLE))} digits (at most {MAX_WHOLE})")
        return values.astype(np.int64)
    return values
