"""The probe file: a multi-probe spindle / roundness measurement sampled by spindle angle.

**The file** (``data/spindle/README.md``): a CSV with the columns ``revolution``, ``angle_deg``
(the spindle's angle of each sample, equally spaced over a revolution, the same samples every
revolution) and one column per probe named ``probe_<mounting angle in degrees>_um``
(``probe_0_um``, ``probe_38.5_um``): three probes or more, at any angles, readings in
micrometres.  :func:`read_probe_file` reads it and refuses, before any work and with a message
naming the file and the line, everything that breaks the schema
(:class:`~mtaccuracy.spindle.probedata.ProbeFileError`); :func:`write_probe_file` writes it.
The checks that hold for any file format (probe columns, readings, layout) are
:mod:`~mtaccuracy.spindle.probedata`'s; the separation is :mod:`~mtaccuracy.spindle.probes`'.

Why hand-written: the schema and its checks are ours; pandas parses the numbers and
:mod:`mtaccuracy.csvlines` finds the line of a message.
"""

from __future__ import annotations

import io
import re
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

from .. import csvlines, validate
from . import timefile
from .probedata import (
    MAX_SAMPLES,
    ProbeData,
    ProbeFileError,
    _check_layout,
    _check_values,
    _probe_columns,
    probe_column,
)
from .probedata import (
    _show_number as _show,
)
from .probes import MIN_SAMPLES
from .separation import TWO_PI

__all__ = ["read_probe_file", "write_probe_file", "MAX_ROWS", "MAX_FILE_BYTES",
           "ANGLE_TOLERANCE", "MAX_REVOLUTION"]

#: Data rows (revolutions x samples): 500 000 rows (e.g. 122 revolutions of 4096 samples) keep a
#: run of notebook 07 within 0.6 GB of memory and about 20 s (measured with 16 probes); a larger
#: file is refused as soon as the parser reaches row 500 001, and one of more than
#: :data:`MAX_FILE_BYTES` bytes before it is read (500 000 rows of 16 probes at 12 characters a
#: value take about 100 MB).
MAX_ROWS = 500_000
MAX_FILE_BYTES = 120_000_000
#: ``angle_deg`` may deviate from the equally spaced grid of its revolution by this fraction of
#: the step ``360 / N`` (angles written with few decimals); a missing, repeated or shifted sample
#: deviates by a whole step.
ANGLE_TOLERANCE = 0.05

#: Revolution numbers beyond this are refused: a revolution counter does not reach it (1e15
#: revolutions at 60 000 rpm take 30 million years), and float64 and int64 hold every whole
#: number up to it exactly, so a message prints the number as written.
MAX_REVOLUTION = 10**15

_REQUIRED = ("revolution", "angle_deg")
_TIME = "time_s"
_REFERENCES = ("index", "encoder_deg")
_COMMENT = "#"
#: The header and the blank lines before it lie within this many characters of the start.
_HEAD_CHARS = 1_000_000
_DECIMAL_COMMA = re.compile(r"^\s*[+-]?\d+,\d+\s*$")
_COMMA_HINT = ("; decimal commas (1,5)? In a comma-separated file write decimal points (1.5), or "
               "save the file semicolon-separated")


def _text(raw: bytes) -> str:
    """The file's text (UTF-8, a byte-order mark allowed; checked when it was first read)."""
    return raw.decode("utf-8-sig")


def _records(text: str, sep: str):
    """The records of a file's text with their lines (:func:`mtaccuracy.csvlines.records`,
    ``#`` comments dropped), the header first, the fields as the file has them (swapped back in
    a semicolon file), rows whose every field is empty left out (pandas' rows and these stay in
    step)."""
    for rec in csvlines.records(text, sep=sep, comment=_COMMENT):
        if any(f.strip() for f in rec.fields):
            yield rec


def _csv_refusal(path, exc: csvlines.CSVLineError) -> ProbeFileError:
    """A record the csv module cannot read, named at its line."""
    if "field limit" in exc.reason:
        return ProbeFileError(path, exc.line, (
            f"a field of more than {csvlines.FIELD_LIMIT} characters (the csv module's limit): no "
            f"value of a probe file is that long; a line without its line ends, or not a CSV "
            f"file?"))
    return ProbeFileError(path, exc.line, exc.reason)


class _Lines:
    """The physical lines of data rows, found (one pass of :func:`csvlines.records` over the
    bytes read once) only when a message needs them.  A record the csv module cannot read
    (a field over 128 KiB) is refused at its own line when a message needs a row after it."""

    def __init__(self, path: Path, raw: bytes, sep: str, names=()):
        self.path, self.raw, self.sep, self.names = path, raw, sep, list(names)
        self._cache, self._error = None, None

    def _all(self):
        if self._cache is None:
            first = []
            recs = _records(_text(self.raw), self.sep)
            try:
                next(recs, None)
                for r in recs:
                    first.append(r.first)
            except csvlines.CSVLineError as exc:
                self._error = exc
            self._cache = first
        return self._cache

    def __call__(self, row: int) -> int:
        lines = self._all()
        if 0 <= row < len(lines):
            return lines[row]
        if self._error is not None:
            raise _csv_refusal(self.path, self._error)
        raise ProbeFileError(self.path, None, (
            f"data row {row + 1} could not be matched to a line of the file (not a readable "
            f"CSV file?)"))

    def cell(self, row: int, column: str) -> str:
        """The text of a data row's cell, as written."""
        j = self.names.index(column)
        recs = _records(_text(self.raw), self.sep)
        try:
            next(recs, None)
            for k, rec in enumerate(recs):
                if k == row:
                    return rec.fields[j].strip() if j < len(rec.fields) else ""
        except csvlines.CSVLineError as exc:
            raise _csv_refusal(self.path, exc) from None
        return "?"

    def some(self, rows, limit: int = 10) -> str:
        rows = list(rows)
        shown = ", ".join(str(self(r)) for r in rows[:limit])
        return shown + (f", ... ({len(rows)} lines)" if len(rows) > limit else "")


def _name(column: str, sep: str) -> str:
    """A column's name as the reader uses it: stripped, and in a semicolon file a probe's
    angle written with a decimal comma (``probe_38,5_um``) written with a point."""
    column = column.strip()
    return column.replace(",", ".") if sep == ";" and column.lower().startswith("probe") \
        else column


def _header(path, text):
    """The header record: (line, names, separator); refuses an empty file, a tab-separated one
    and repeated names.  ``text``: the start of the file (the header and any blank lines before
    it lie within :data:`_HEAD_CHARS` characters).  The first non-blank line tells the
    separator: ``;`` when it holds one (a spreadsheet's CSV in a locale with decimal commas),
    else ``,``."""
    first = next((ln for ln in text.splitlines() if ln.split(_COMMENT, 1)[0].strip()), "")
    first = first.split(_COMMENT, 1)[0] if '"' not in first else first
    sep = ";" if ";" in first else ","
    if sep == "," and "\t" in first and "," not in first:
        number = text.splitlines().index(first) + 1
        raise ProbeFileError(path, number, (
            "the header is tab-separated; the schema is comma-separated with decimal points (or "
            "semicolon-separated, as a spreadsheet in a locale with decimal commas writes it): "
            "export the file as CSV"))
    recs = _records(text, sep)
    try:
        head = next(recs, None)
    except csvlines.CSVLineError as exc:
        raise _csv_refusal(path, exc) from None
    if head is None:
        raise ProbeFileError(path, None, "the file is empty; it needs the header revolution,"
                                         "angle_deg,probe_<angle>_um,... (or time_s,index,"
                                         "probe_<angle>_um,...) and data rows")
    names = [_name(f, sep) for f in head.fields]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise ProbeFileError(path, head.first, f"column(s) {twice} appear more than once")
    return head.first, names, sep


def _layout(path, line, names) -> str:
    """The file's layout from its header: ``"angle"`` (``revolution``, ``angle_deg``) or
    ``"time"`` (``time_s`` and one of ``index``, ``encoder_deg``); refuses a header with
    neither, or with both ``index`` and ``encoder_deg``."""
    if _TIME in names and not any(n in names for n in _REQUIRED):
        refs = [n for n in _REFERENCES if n in names]
        if len(refs) == 2:
            raise ProbeFileError(path, line, (
                "both 'index' and 'encoder_deg': a time-sampled file takes its spindle angle "
                "from one of them; drop the other column (or rename it)"))
        if not refs:
            like = [n for n in names if n.lower() in ("idx", "trigger", "once_per_rev",
                                                      "encoder", "angle", "tacho")]
            hint = f" ({like[0]!r} found: rename it 'index' or 'encoder_deg')" if like else ""
            raise ProbeFileError(path, line, (
                f"a time-sampled file (time_s) needs an 'index' column (1 where the "
                f"once-per-revolution mark is seen, else 0) or an 'encoder_deg' column (the "
                f"spindle angle){hint}"))
        return "time"
    if any(n in names for n in _REFERENCES) and not any(n in names for n in _REQUIRED):
        like = [n for n in names if n.lower() in ("time", "t", "time_ms", "timestamp", "t_s")]
        hint = (f" ({like[0]!r} found: rename it 'time_s'; times in seconds)") if like else ""
        raise ProbeFileError(path, line, f"missing column 'time_s'{hint}; a time-sampled file "
                                         f"needs time_s, index or encoder_deg, and "
                                         f"probe_<angle>_um columns")
    return "angle"


def _require_columns(path, line, names) -> None:
    """Refuse a header without ``revolution`` or ``angle_deg``, naming a near miss."""
    for want, alts in (("revolution", ("rev", "revolutions", "turn")),
                       ("angle_deg", ("angle", "angle_rad", "theta", "theta_deg"))):
        if want not in names:
            like = [n for n in names if n.lower() in alts or n.lower() == want]
            hint = (f" ({like[0]!r} found: rename it {want!r}"
                    + ("; angles in degrees" if want == "angle_deg" else "") + ")") if like else ""
            raise ProbeFileError(path, line, (
                f"missing column {want!r}{hint}; the header needs revolution, angle_deg and "
                f"probe_<angle>_um columns (an angle-sampled file), or time_s, index or "
                f"encoder_deg and probe_<angle>_um columns (a time-sampled file)"))


def _parse(path, raw, names, header_line, sep, lines):
    """The data rows as a DataFrame (pandas' C parser; blank rows, and rows whose every field
    is empty, skipped), or a message naming the line of a row with more fields than the
    header."""
    def ragged():
        recs = _records(_text(raw), sep)
        try:
            next(recs, None)
            for rec in recs:
                if len(rec.fields) > len(names):
                    comma = sep == "," and any(_DECIMAL_COMMA.match(f"{a},{b}") for a, b in
                                               zip(rec.fields, rec.fields[1:], strict=False))
                    return ProbeFileError(path, rec.first, (
                        f"{len(rec.fields)} fields, but the header names {len(names)} "
                        f"columns{_COMMA_HINT if comma else ''}"))
        except csvlines.UnclosedQuote as exc:
            return ProbeFileError(path, exc.line, "a quoted field opens here and is never "
                                                  "closed (a '\"' is missing)")
        except csvlines.CSVLineError as exc:
            return _csv_refusal(path, exc)
        return ProbeFileError(path, None, "not a readable CSV file")

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", pd.errors.ParserWarning)
        try:
            df = pd.read_csv(io.BytesIO(raw), encoding="utf-8-sig", sep=sep,
                             decimal="," if sep == ";" else ".", na_filter=False,
                             skipinitialspace=True, index_col=False, nrows=MAX_ROWS + 1,
                             comment=_COMMENT)
        except pd.errors.ParserError:
            raise ragged() from None
        except pd.errors.EmptyDataError:
            raise ProbeFileError(path, None, "the file is empty") from None
    if any(issubclass(w.category, pd.errors.ParserWarning) for w in caught):
        raise ragged()
    df.columns = [_name(c, sep) for c in df.columns]
    text_cols = [c for c in df.columns if not pd.api.types.is_numeric_dtype(df[c])]
    if len(text_cols) == len(df.columns) and len(df):       # rows a spreadsheet left empty
        empty = np.logical_and.reduce([df[c].astype(str).str.strip().eq("").to_numpy()
                                       for c in df.columns])
        df = df[~empty].reset_index(drop=True)
    if df.empty:
        raise ProbeFileError(path, header_line, "the file has a header but no data rows")
    if len(df) > MAX_ROWS:
        raise ProbeFileError(path, lines(MAX_ROWS), (
            f"more than {MAX_ROWS} data rows; at most {MAX_ROWS} (revolutions x samples per "
            f"revolution) are read, to keep a run within about 0.6 GB of memory: keep fewer "
            f"revolutions"))
    return df


def _numbers(path, df, column, lines, sep) -> np.ndarray:
    """A column as finite floats: pandas parsed it as numbers, or it holds text (a semicolon
    file's decimal points or commas, both read; anything else refused at its first bad
    cell)."""
    col = df[column]
    if pd.api.types.is_numeric_dtype(col) and not pd.api.types.is_bool_dtype(col):
        values = col.to_numpy(dtype=float)
        text = pd.Series([repr(v) for v in values]) if not np.all(np.isfinite(values)) else None
    else:
        text = col.astype(str).str.strip()
        number = text.str.replace(",", ".", regex=False) if sep == ";" else text
        values = pd.to_numeric(number, errors="coerce").to_numpy(dtype=float)
    bad = ~np.isfinite(values)
    if bad.any():
        rows = np.flatnonzero(bad)
        shown = ", ".join(repr(t if len(t) <= 40 else t[:37] + "...") for t in
                          text.iloc[rows[:3]])
        comma = sep == "," and any(_DECIMAL_COMMA.match(t) for t in text.iloc[rows[:3]])
        hint = _COMMA_HINT if comma else "; every cell needs a finite number"
        raise ProbeFileError(path, lines(rows[0]), (
            f"column {column!r} has a missing, NaN, infinite or non-numeric value ({shown}); "
            f"line(s) {lines.some(rows)}{hint}"))
    return values


def _check_structure(path, rev, ang, lines):
    """Revolutions in order and of equal length, angles increasing and equally spaced, the same
    every revolution; returns (revolution numbers, N, the first revolution's angles)."""
    big = np.abs(rev) > MAX_REVOLUTION
    if big.any():
        row = int(np.flatnonzero(big)[0])
        raise ProbeFileError(path, lines(row), (
            f"revolution {lines.cell(row, 'revolution')} is beyond {MAX_REVOLUTION:.0e}, more "
            f"than a revolution counter reaches: number the file's revolutions from 1"))
    if np.any(rev != np.round(rev)):
        row = int(np.flatnonzero(rev != np.round(rev))[0])
        raise ProbeFileError(path, lines(row), (
            f"revolution {lines.cell(row, 'revolution')} is not a whole number"))
    rn = rev.astype(np.int64)                      # exact: whole and within MAX_REVOLUTION
    back = np.flatnonzero(np.diff(rn) < 0)
    if back.size:
        i = int(back[0])
        raise ProbeFileError(path, lines(i + 1), (
            f"revolution {rn[i + 1]} comes after revolution {rn[i]} (line {lines(i)}): "
            f"the rows of a revolution must stand together and the revolutions in the order "
            f"measured"))
    gap = np.flatnonzero(np.diff(rn) > 1)
    if gap.size:
        i = int(gap[0])
        missing = (f"revolution {rn[i] + 1} is" if rn[i + 1] - rn[i] == 2 else
                   f"revolutions {rn[i] + 1}..{rn[i + 1] - 1} are")
        raise ProbeFileError(path, lines(i + 1), (
            f"revolution {rn[i + 1]} follows revolution {rn[i]} (line {lines(i)}): {missing} "
            f"missing; the asynchronous motion and its spectrum need consecutive revolutions: "
            f"keep only a run of consecutive revolutions (renumbering them would join "
            f"revolutions that were not measured one after the other)"))
    starts = np.r_[0, np.flatnonzero(np.diff(rn) > 0) + 1]
    sizes = np.diff(np.r_[starts, len(rn)])
    if np.any(sizes != sizes[0]):
        j = int(np.flatnonzero(sizes != sizes[0])[0])
        a, b = starts[j], starts[j] + sizes[j] - 1
        raise ProbeFileError(path, lines(a), (
            f"unequal samples per revolution: revolution {rn[a]} (lines {lines(a)}-"
            f"{lines(b)}) has {sizes[j]} samples, revolution {rn[0]} (lines {lines(0)}-"
            f"{lines(sizes[0] - 1)}) has {sizes[0]}; every revolution needs the same samples"
            f" (a file sampled in time? Write time_s and index or encoder_deg instead of "
            f"revolution and angle_deg, and the reader resamples it)"))
    n, n_rev = int(sizes[0]), len(starts)
    if not MIN_SAMPLES <= n <= MAX_SAMPLES:
        raise ProbeFileError(path, lines(0), (
            f"{n} samples per revolution; {MIN_SAMPLES}..{MAX_SAMPLES} are supported"))
    a = ang.reshape(n_rev, n)
    if np.any(np.abs(a[0]) > 720):
        row = int(np.flatnonzero(np.abs(a[0]) > 720)[0])
        raise ProbeFileError(path, lines(row), (
            f"angle_deg = {_show(ang[row])}: the spindle angle within a revolution, in degrees, "
            f"lies within -360..720"))
    step = np.diff(a, axis=1)
    if np.any(step <= 0):
        r, i = (int(v) for v in np.argwhere(step <= 0)[0])
        row = r * n + i + 1
        if np.all(step < 0):
            hint = ("; the angles decrease throughout: angle_deg is the angle the spindle has "
                    "turned, increasing with time. If your angle counts the other way, write it "
                    "negated (modulo 360), keep the probes' angles as mounted, and state the "
                    "sense with rotation: 'cw' when the spindle turns against the sense the "
                    "probe angles are counted in, 'ccw' when it turns with it (README: "
                    "Geometry)")
        else:
            hint = ""
        raise ProbeFileError(path, lines(row), (
            f"angle_deg must increase within a revolution: {_show(a[r, i + 1])} deg does not "
            f"come after {_show(a[r, i])} deg (line {lines(row - 1)}) in revolution "
            f"{rn[r * n]}{hint}"))
    pitch = 360.0 / n
    expected = a[0, :1] + pitch * np.arange(n)
    off = np.abs(a[0] - expected) > ANGLE_TOLERANCE * pitch
    if off.any():
        i = int(np.flatnonzero(off)[0])
        span = a[0, -1] - a[0, 0]
        if abs(span - 360.0) < ANGLE_TOLERANCE * 360.0 / (n - 1):
            raise ProbeFileError(path, lines(n - 1), (
                f"the last sample of revolution {rn[0]} ({_show(a[0, -1])} deg) repeats its "
                f"first ({_show(a[0, 0])} deg, line {lines(0)}), 360 deg later: the N samples of a "
                f"revolution are 360 / N apart and end one step before 360 deg; drop the "
                f"repeated sample from every revolution"))
        hint = ""
        if abs(span - TWO_PI * (n - 1) / n) < ANGLE_TOLERANCE * TWO_PI / n:
            hint = (f"; they span {span:.4g}, 2 pi (N - 1) / N: radians? (deg = rad x 180 / "
                    f"pi)")
        raise ProbeFileError(path, lines(i), (
            f"angle_deg is not equally spaced over the revolution: {_show(a[0, i])} deg where "
            f"{n} samples from {_show(a[0, 0])} deg (line {lines(0)}), 360 / {n} = {pitch:.6g} deg "
            f"apart, put sample {i + 1} at {expected[i]:.6g} deg (tolerance "
            f"{ANGLE_TOLERANCE:g} of a step){hint}"))
    moved = np.abs(a - a[:1]) > ANGLE_TOLERANCE * pitch
    if moved.any():
        r, i = (int(v) for v in np.argwhere(moved)[0])
        raise ProbeFileError(path, lines(r * n + i), (
            f"revolution {rn[r * n]} has sample {i + 1} at {_show(a[r, i])} deg where "
            f"revolution {rn[0]} has it at {_show(a[0, i])} deg (line {lines(i)}); every "
            f"revolution needs "
            f"the same angles: angle_deg is the angle within the revolution (if it counts on "
            f"across revolutions, write it modulo 360)"))
    return rn[starts], n, a[0]


def read_probe_file(path, *, max_harmonic: int | None = None, allow_cancelled: bool = False,
                    on_read=None) -> ProbeData:
    """Read and check a multi-probe spindle / roundness measurement (``data/spindle/README.md``).

    Refused, with a :class:`~mtaccuracy.spindle.probedata.ProbeFileError` naming the file and the
    line (the header's for a problem of the columns, the row's as an editor numbers it otherwise),
    before any separation: a missing file, more than :data:`MAX_FILE_BYTES` bytes or
    :data:`MAX_ROWS` rows, text that is not UTF-8, a tab-separated file, decimal commas in a
    comma-separated file, a missing ``revolution`` or ``angle_deg`` column, a probe column not named
    ``probe_<angle in degrees>_um`` or in other units (``probe_0_mm``: "in mm"), fewer than
    :data:`~mtaccuracy.spindle.probes.MIN_PROBES` or more than
    :data:`~mtaccuracy.spindle.probes.MAX_PROBES` probes, two probes at one angle (modulo 360),
    angles that look like radians, a row with more fields than the header, an empty, NaN, infinite
    or non-numeric cell, revolution numbers that are not whole or not in order, unequal samples per
    revolution (or fewer than :data:`~mtaccuracy.spindle.probes.MIN_SAMPLES`, more than
    :data:`~mtaccuracy.spindle.probedata.MAX_SAMPLES`), angles that do not increase within a
    revolution, are not equally spaced over it (within :data:`ANGLE_TOLERANCE` of a step) or differ
    between revolutions, readings beyond +-:data:`~mtaccuracy.spindle.probedata.MAX_ABS_UM` (nm?) or
    a probe spanning less than :data:`~mtaccuracy.spindle.probedata.MIN_SPAN_UM` (mm?), and a probe
    layout that cannot separate harmonics within 2..max_harmonic
    (:func:`~mtaccuracy.spindle.probes.layout_cancelled`) unless ``allow_cancelled``: then those
    harmonics are set aside with a :class:`~mtaccuracy.spindle.separation.CancelledHarmonicsWarning`
    naming them, as the library's separation does.  Columns that neither are ``revolution``,
    ``angle_deg`` nor start with ``probe`` are ignored (listed in ``ignored_columns``).

    Read, as :mod:`mtaccuracy.thermal.csvfile` reads them: a semicolon-separated file (what a
    spreadsheet writes in a locale with decimal commas; the header tells, by holding a ``;``)
    with decimal commas or points, a probe's angle in its name included (``probe_38,5_um``);
    a byte-order mark; blank lines and rows whose every field is empty (a spreadsheet's
    trailing rows), which are skipped.

    Parameters
    ----------
    path : str or Path
        The CSV file.
    max_harmonic : int, optional
        The highest profile harmonic to separate, 2..(N - 1) // 2; default all
        (:func:`~mtaccuracy.spindle.probes.resolvable_harmonic`).
    allow_cancelled : bool
        Set cancelled harmonics aside with a warning instead of refusing the file.
    on_read : callable, optional
        Called as ``on_read(path)`` once the file is read (the compendium passes
        ``provenance.track`` to hash its input).

    Returns
    -------
    ProbeData
        The readings (um) as ``(R, L, N)``, the angles and the harmonics to separate.

    Raises
    ------
    ProbeFileError
        Naming the file, the line and the problem.
    """
    path = Path(path)
    try:
        raw = validate.file_bytes(path, max_bytes=MAX_FILE_BYTES)
    except validate.FileRefused as exc:
        hint = (" (the probe file: revolution, angle_deg, probe_<angle>_um columns, or time_s, "
                "index or encoder_deg, probe_<angle>_um; see data/spindle/README.md)"
                if exc.reason == "missing" else
                f" ({MAX_ROWS} rows of 16 probes take less)" if exc.reason == "too large" else "")
        raise ProbeFileError(path, None, f"{exc}{hint}") from None
    try:
        head = raw.decode("utf-8-sig")[:_HEAD_CHARS]
    except UnicodeDecodeError as exc:
        raise ProbeFileError(path, csvlines.bad_byte_line(raw, exc), (
            f"not UTF-8 text (byte 0x{raw[exc.start]:02x}); save the file as UTF-8")) from None
    if on_read is not None:
        on_read(path)
    header_line, names, sep = _header(path, head)
    layout = _layout(path, header_line, names)
    if layout == "angle":
        _require_columns(path, header_line, names)
        own = _REQUIRED
    else:
        own = (_TIME, *_REFERENCES)
    probes, angles, ignored = _probe_columns(path, header_line, names, own)
    lines = _Lines(path, raw, sep, names)
    df = _parse(path, raw, names, header_line, sep, lines)
    values = [_numbers(path, df, c, lines, sep) for c in probes]
    resampling = None
    if layout == "angle":
        rev = _numbers(path, df, "revolution", lines, sep)
        ang = _numbers(path, df, "angle_deg", lines, sep)
        del df
        revolutions, n, sample_deg = _check_structure(path, rev, ang, lines)
        _check_values(path, probes, values, lines, header_line)
        signals = np.stack(values).reshape(len(probes), len(revolutions), n).transpose(1, 0, 2)
    else:
        ref = next(c for c in _REFERENCES if c in names)
        time_s = _numbers(path, df, _TIME, lines, sep)
        mark = _numbers(path, df, ref, lines, sep)
        del df
        _check_values(path, probes, values, lines, header_line)
        signals, resampling = timefile.resample_time_series(
            time_s, np.stack(values, axis=1), path=str(path), lines=lines,
            header_line=header_line, stacklevel=2, **{ref: mark})
        n = resampling.n_samples
        revolutions = np.arange(1, signals.shape[0] + 1)
        sample_deg = 360.0 * np.arange(n) / n
    k_top, cancelled = _check_layout(path, header_line, angles, n, max_harmonic,
                                     allow_cancelled)
    return ProbeData(path=str(path), columns=tuple(probes), angles_deg=angles,
                     sample_deg=sample_deg, revolutions=revolutions,
                     signals_um=np.ascontiguousarray(signals), max_harmonic=k_top,
                     cancelled=tuple(cancelled), ignored_columns=tuple(ignored),
                     header_line=header_line, resampling=resampling)


def write_probe_file(path, signals_um, angles_deg, sample_deg, *, revolutions=None,
                     decimals: int = 4) -> None:
    """Write readings in the schema of :func:`read_probe_file` (Unix line ends, fixed decimals).

    Parameters
    ----------
    path : str or Path
        The file (its folder must exist).
    signals_um : array (R, L, N)
        Probe readings (um).
    angles_deg : array (L,)
        Mounting angles (deg).
    sample_deg : array (N,)
        Spindle angle of each sample (deg).
    revolutions : array of int (R,), optional
        Revolution numbers; default 1..R.
    decimals : int
        Decimals of the readings (um); the angles are written with up to 10.
    """
    y = np.asarray(signals_um, dtype=float)
    r, n_probes, n = y.shape
    revolutions = np.arange(1, r + 1) if revolutions is None else np.asarray(revolutions)
    table = pd.DataFrame({"revolution": np.repeat(revolutions, n),
                          "angle_deg": np.tile(np.round(np.asarray(sample_deg, float), 10), r)})
    for j, a in enumerate(np.asarray(angles_deg, dtype=float)):
        table[probe_column(a)] = np.round(y[:, j, :].ravel(), decimals) + 0.0
    Path(path).write_bytes(_csv_bytes(table, decimals))


def _csv_bytes(table: pd.DataFrame, decimals: int) -> bytes:
    buf = io.StringIO()
    cols = {c: (lambda v: f"{v:.{decimals}f}") for c in table.columns if c.startswith(
        ("probe_", "profile_", "x_", "y_"))}
    out = table.copy()
    for c, fmt in cols.items():
        out[c] = [fmt(v) for v in out[c]]
    out["angle_deg"] = [np.format_float_positional(v, trim="-") for v in out["angle_deg"]]
    out.to_csv(buf, index=False, lineterminator="\n")
    return buf.getvalue().encode("utf-8")
