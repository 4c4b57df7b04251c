"""CSV records with the lines an editor shows, so that a message about a bad row names its line.

The one place the readers of measurement and machine files (:mod:`mtaccuracy.thermal.io`,
:mod:`mtaccuracy.machines.readers`) learn where a record stands.

pandas and the csv module number records, not lines: blank lines are skipped, comment lines
dropped, and a quoted field may span several lines.  :func:`records` reads the text with the
csv module (``skipinitialspace``; a field is quoted when ``"`` opens it after the delimiter and
spaces, ``""`` inside it is a quote, the rules pandas' tokenizer follows too) and gives each
record with its first and last physical line.  Written by hand because neither library reports
lines; linear in the size of the text (the comment and quote scan is one regular-expression
match per line, with possessive quantifiers).
"""

from __future__ import annotations

import csv
import functools
import io
import re
from collections.abc import Iterator
from typing import NamedTuple

#: The longest field the csv module reads (characters, ``csv.field_size_limit()``: 131072):
#: past it :func:`records` raises a :class:`CSVLineError` at the field's line.  The readers
#: quote this one value in their messages.
FIELD_LIMIT = csv.field_size_limit()


class Record(NamedTuple):
    """One CSV record and where it stands.

    Parameters
    ----------
    first, last : int
        Its first and last physical line (1-based, as an editor numbers them; they differ when
        a quoted field spans lines).
    fields : list of str
        Its fields as the csv module reads them.
    """

    first: int
    last: int
    fields: list


class CSVLineError(ValueError):
    """A CSV text that cannot be read, and the line at fault.

    Parameters
    ----------
    line : int
        The physical line (1-based).
    reason : str
        What is wrong there.
    """

    def __init__(self, line: int, reason: str):
        super().__init__(f"line {line}: {reason}")
        self.line, self.reason = line, reason


class UnclosedQuote(CSVLineError):
    """A quoted field that opens on ``line`` and is never closed."""

    def __init__(self, line: int):
        super().__init__(line, "a quoted field opens here and is never closed")


@functools.cache
def _scanner(comment: str | None):
    """The regular expressions that find, in one line, the end of its data (where a comment
    starts, outside quotes) and whether a quoted field is still open at its end."""
    stop = "," + (re.escape(comment) if comment else "")
    quoted = r'"(?:[^"]|"")*+"'
    field = rf'[ ]*+(?:{quoted}[^{stop}]*+|(?!")[^{stop}]*+)'
    opened = r'[ ]*+"(?:[^"]|"")*+\Z'              # a quoted field the line does not close
    return (re.compile(rf'(?:{field},)*+(?:(?P<open>{opened})|{field})'),
            re.compile(rf'(?:[^"]|"")*+(?P<close>"[^{stop}]*+)?'))


def _strip(line: str, quoted: bool, comment: str | None) -> tuple[str, bool]:
    """``line`` without its comment (``comment`` outside a quoted field, to the end of the
    line) and whether a quoted field is open at its end (``quoted``: open at its start)."""
    whole, inside = _scanner(comment)
    pos = 0
    if quoted:
        m = inside.match(line)
        if m.group("close") is None:
            return line, True
        pos = m.end()
        if pos == len(line):
            return line, False
        if line[pos] == comment:
            return line[:pos] + "\n", False
        pos += 1                                     # the delimiter
    elif '"' not in line:
        cut = line.find(comment) if comment else -1
        return (line if cut < 0 else line[:cut] + "\n"), False
    m = whole.match(line, pos)
    if m.group("open") is not None:
        return line, True
    return (line if m.end() == len(line) else line[:m.end()] + "\n"), False


#: A semicolon file is scanned with ';' and ',' swapped (a one-to-one swap of single characters,
#: so lines and quoting stay where they were) and its fields swapped back.
_SWAP = str.maketrans(";,", ",;")


def records(text: str, *, comment: str | None = None, sep: str = ",") -> Iterator[Record]:
    """The records of a CSV text with their physical lines, the header first.

    Lines end with ``\\n``, ``\\r\\n`` or ``\\r``.  A line that is blank (or, with ``comment``,
    holds only a comment) outside a quoted field is skipped, as pandas skips it
    (``skip_blank_lines``, ``comment=``).

    Parameters
    ----------
    text : str
        The file's text (decoded).
    comment : str, optional
        A character that starts a comment outside quoted fields (``"#"``); None: no comments.
    sep : {",", ";"}
        The field separator: ``";"`` reads a semicolon-separated file (as spreadsheet software
        writes CSV in a locale with decimal commas), its fields as the file has them.

    Returns
    -------
    iterator of Record
        ``(first line, last line, fields)`` per record.

    Raises
    ------
    UnclosedQuote
        After the last complete record, when a quoted field is never closed.
    CSVLineError
        When the csv module cannot read a record.
    """
    if sep == ";":
        for rec in _records(text.translate(_SWAP), comment):
            yield Record(rec.first, rec.last, [f.translate(_SWAP) for f in rec.fields])
    elif sep == ",":
        yield from _records(text, comment)
    else:
        raise ValueError(f"sep must be ',' or ';', got {sep!r}")


def _records(text: str, comment: str | None) -> Iterator[Record]:
    """:func:`records` of a comma-separated text."""
    text = text.replace("\r\n", "\n").replace("\r", "\n")
    fed: list[int] = []            # the physical line of every line handed to the csv reader
    opened = [0]                   # where the quoted field open at the end of a line opened

    def lines():
        quoted = False
        for number, line in enumerate(io.StringIO(text, newline="\n"), 1):
            was = quoted
            kept, quoted = _strip(line, quoted, comment)
            if quoted and not was:
                opened[0] = number
            if not was and not kept.strip():
                continue
            fed.append(number)
            yield kept
        if quoted:
            raise UnclosedQuote(opened[0])

    reader = csv.reader(lines(), skipinitialspace=True)
    while True:
        k = len(fed)
        try:
            fields = next(reader)
        except StopIteration:
            return
        except csv.Error as exc:
            raise CSVLineError(fed[-1] if fed else 1, f"not a readable CSV: {exc}") from None
        yield Record(fed[k], fed[-1], fields)


def bad_byte_line(raw: bytes, exc: UnicodeDecodeError) -> int:
    """The physical line (1-based) of the byte a UTF-8 decoding of ``raw`` stopped at.

    Parameters
    ----------
    raw : bytes
        The file's bytes.
    exc : UnicodeDecodeError
        The error of ``raw.decode(...)``.

    Returns
    -------
    int
        Its line, counting ``\\n``, ``\\r\\n`` and ``\\r`` line ends.
    """
    head = raw[:exc.start]
    return head.count(b"\n") + head.count(b"\r") - head.count(b"\r\n") + 1
