"""The reader's own files in the explorer, read by the notebooks' own readers.

A file the page uploads (Panel's ``FileInput``) is checked (its name, its size: at most
:data:`MAX_UPLOAD_BYTES`, before anything is written), written to a fresh private temporary
folder (mode 0700, never the working tree, removed once read) under its own base name, and read
there by the reader a notebook uses: notebook 06's
:func:`mtaccuracy.machines.readers.read_ranges` for a ranges file, notebook 07's
:func:`mtaccuracy.spindle.probefile.read_probe_file` for a probe file, notebook 04's
:func:`mtaccuracy.thermal.read_measurements` for a folder of thermal measurements (its files
uploaded together).  The reader's message (file and line) is shown as it words it, with the
temporary folder taken out: the file is named as the reader named it on their disk.
"""

from __future__ import annotations

import base64
import binascii
import re
import tempfile
import warnings
from dataclasses import dataclass
from pathlib import Path

#: The largest upload, per file (bytes).  The readers' own caps are larger (a probe file may
#: have 120 MB); the explorer takes what a browser sends in a second or two.
MAX_UPLOAD_BYTES = 8 * 1024 * 1024
#: The most files in one upload (a thermal folder has two or three).
MAX_UPLOAD_FILES = 5
#: A file name the explorer writes: letters, digits, ``. _ -`` and spaces, ending in ``.csv``.
SAFE_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._ -]{0,99}\.csv")


@dataclass(frozen=True)
class Upload:
    """What a reader made of an upload: its result, or its message (``""`` when read)."""

    names: tuple
    result: object
    message: str
    warnings: tuple


def checked_files(names, contents) -> dict[str, bytes]:
    """``{name: bytes}`` of an upload, refused before anything is written (a ValueError why).

    ``names`` and ``contents`` are the ``FileInput``'s ``filename`` and ``value`` (one each, or
    lists of them).  Refused: no file, more than :data:`MAX_UPLOAD_FILES`, a name that is not
    a plain ``.csv`` base name (:data:`SAFE_NAME`: no folder, no ``..``), the same name twice,
    content that is not bytes, or a file over :data:`MAX_UPLOAD_BYTES`.
    """
    if isinstance(names, str) or names is None:
        names, contents = [names], [contents]
    names, contents = list(names), list(contents or [])
    if not names or names == [None] or len(names) != len(contents):
        raise ValueError("no file chosen: choose a .csv file")
    if len(names) > MAX_UPLOAD_FILES:
        raise ValueError(f"{len(names)} files chosen: at most {MAX_UPLOAD_FILES}")
    out = {}
    for name, content in zip(names, contents, strict=True):
        if not isinstance(name, str) or not SAFE_NAME.fullmatch(name) or ".." in name:
            raise ValueError(f"{str(name)[:80]!r} is not a plain .csv file name (letters, "
                             "digits, '. _ -' and spaces): rename the file")
        if name in out:
            raise ValueError(f"{name} chosen twice")
        if not isinstance(content, bytes | bytearray):
            raise ValueError(f"{name}: the page sent no file content")
        if len(content) > MAX_UPLOAD_BYTES:
            raise ValueError(f"{name} has {len(content):,} bytes: the explorer takes at most "
                             f"{MAX_UPLOAD_BYTES:,} (run the notebook on larger files)")
        out[name] = bytes(content)
    return out


def checked_base64(value):
    """An upload's content as the page sends it, checked before Panel decodes it.

    ``value``: base64 text, or a list of them (``multiple``).  Refused (a ValueError): not text,
    more than :data:`MAX_UPLOAD_FILES`, more than :data:`MAX_UPLOAD_BYTES` once decoded (judged
    from its length), or not base64.
    """
    many = isinstance(value, list | tuple)
    items = list(value) if many else [value]
    if len(items) > MAX_UPLOAD_FILES:
        raise ValueError(f"{len(items)} files chosen: at most {MAX_UPLOAD_FILES}")
    for item in items:
        if not isinstance(item, str):
            raise ValueError("the page sent a file that is not base64 text")
        if len(item) * 3 // 4 > MAX_UPLOAD_BYTES + 2:
            raise ValueError(f"a file of about {len(item) * 3 // 4:,} bytes: the explorer "
                             f"takes at most {MAX_UPLOAD_BYTES:,} (run the notebook on larger "
                             "files)")
        try:
            base64.b64decode(item, validate=True)
        except (binascii.Error, ValueError):
            raise ValueError("the page sent a file that is not base64 text") from None
    return value


def read_upload(names, contents, reader, *, folder: bool = False) -> Upload:
    """Run ``reader`` on the uploaded file(s), in a private temporary folder removed after.

    ``reader(path)`` gets the one file's path, or (``folder``) the folder holding every file.
    Its ValueError (the readers' messages: file, line, fix), a refusal of
    :func:`checked_files`, or an OSError become ``message``, with the temporary folder's path
    taken out; its warnings are kept as their messages.
    """
    shown = names if isinstance(names, list | tuple) else [names]
    try:
        files = checked_files(names, contents)
    except ValueError as exc:
        return Upload(tuple(map(str, shown)), None, str(exc), ())
    with tempfile.TemporaryDirectory(prefix="mtaccuracy-upload-") as tmp:   # mode 0700
        root = Path(tmp)
        for name, content in files.items():
            (root / name).write_bytes(content)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                result, message = reader(root if folder else root / next(iter(files))), ""
            except (ValueError, OSError) as exc:
                result, message = None, str(exc)
        for prefix, by in ((f"{root}/", ""), (f"{root.resolve()}/", ""),
                           (str(root.resolve()), "the folder uploaded"),
                           (str(root), "the folder uploaded")):
            message = message.replace(prefix, by)
        told = tuple(str(w.message).replace(f"{root}/", "") for w in caught)
    return Upload(tuple(files), result, message, told)
