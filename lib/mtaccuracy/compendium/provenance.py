"""Provenance of every output: which notebook, library code, parameters and inputs made it.

A run's record (:func:`record`) holds content hashes only: of the notebook's source cells, of
the library modules the notebook imports (:func:`library_modules`: the closure of its
``mtaccuracy`` imports, read from the source, so that a change to the explorer does not touch
notebook 03), of every input file the run read (absolute paths included), plus the parameters
(without ``output_dir``, which only says where files go) and the versions of the main packages.
No timestamp, no git commit: unchanged code, notebook, inputs and parameters give identical
records, and so identical figure bytes.

Each output folder's ``provenance.json`` is that record plus the list of the files the run
wrote, each with its SHA-256 and, for a table, how closely a regeneration on another machine
must match it (``tolerance``, or ``measured`` for wall-clock times); a figure's entry carries
its label and caption, which the book shows.  The workflow reads the list to know which files
are the run's (a file it does not list is the user's, never replaced), the book to check what
it shows (:func:`output_problem`).
"""

from __future__ import annotations

import ast
import functools
import hashlib
import json
import os
import platform
import xml.etree.ElementTree as ET
from importlib import metadata
from pathlib import Path

#: The repository root (``lib/mtaccuracy/compendium/provenance.py`` -> three levels up).
ROOT = Path(__file__).resolve().parents[3]
LIBRARY = ROOT / "lib"
PACKAGES = ("numpy", "scipy", "pandas", "matplotlib", "SALib", "chaospy", "scikit-learn",
            "sympy", "papermill")
SIDECAR = "provenance.json"


def sha256(path) -> str:
    """The SHA-256 of a file's bytes, as hex."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def shown(path) -> str:
    """``path`` relative to the repository root when it lies inside, else absolute."""
    p = Path(path).resolve()
    return p.relative_to(ROOT).as_posix() if p.is_relative_to(ROOT) else p.as_posix()


def _code_cells(notebook: Path) -> list[str]:
    nb = json.loads(Path(notebook).read_text(encoding="utf-8"))
    return ["".join(c["source"]) if isinstance(c["source"], list) else c["source"]
            for c in nb.get("cells", []) if c.get("cell_type") == "code"
            and "injected-parameters" not in c.get("metadata", {}).get("tags", [])]


def notebook_source_hash(notebook) -> str:
    """SHA-256 over a notebook's cell types and sources: what its author wrote.

    Without outputs, execution counts, metadata or the cell papermill injects."""
    nb = json.loads(Path(notebook).read_text(encoding="utf-8"))
    h = hashlib.sha256()
    for c in nb.get("cells", []):
        if "injected-parameters" in c.get("metadata", {}).get("tags", []):
            continue
        src = c.get("source", "")
        h.update(c.get("cell_type", "").encode() + b"\0")
        h.update(("".join(src) if isinstance(src, list) else src).encode("utf-8") + b"\0")
    return h.hexdigest()


def _module_file(name: str) -> Path | None:
    """The source file of module ``mtaccuracy.x.y`` under ``lib/``, or None."""
    base = LIBRARY.joinpath(*name.split("."))
    for p in (base.with_suffix(".py"), base / "__init__.py"):
        if p.is_file():
            return p
    return None


def _imported(tree: ast.AST, package: str) -> set[str]:
    """The ``mtaccuracy`` modules a syntax tree imports (function-local imports included):
    ``from a import b`` counts ``a.b`` when that is a module, else ``a``."""
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                parts = package.split(".")
                base = ".".join(parts[:len(parts) - node.level + 1])
                mod = f"{base}.{node.module}" if node.module else base
            else:
                mod = node.module or ""
            found.add(mod)
            found.update(f"{mod}.{a.name}" for a in node.names
                         if _module_file(f"{mod}.{a.name}") is not None)
    return {m for m in found if m == "mtaccuracy" or m.startswith("mtaccuracy.")}


@functools.cache
def _closure(roots: frozenset[str]) -> tuple[Path, ...]:
    seen: set[str] = set()
    todo = list(roots)
    while todo:
        name = todo.pop()
        parts = name.split(".")
        for i in range(1, len(parts) + 1):  # importing a.b.c runs a and a.b first
            parent = ".".join(parts[:i])
            if parent in seen or _module_file(parent) is None:
                continue
            seen.add(parent)
            path = _module_file(parent)
            package = parent if path.name == "__init__.py" else parent.rpartition(".")[0]
            todo.extend(_imported(ast.parse(path.read_text(encoding="utf-8")), package))
    data = sorted((LIBRARY / "mtaccuracy" / "data").glob("*"))
    return tuple(sorted(_module_file(m) for m in seen)) + tuple(p for p in data if p.is_file())


def library_modules(notebook) -> list[Path]:
    """The library files a notebook's code depends on: the closure of its imports.

    Read from the source (every ``import`` in its code cells, then in each ``mtaccuracy``
    module reached, function-local ones included, and each parent package), plus the library's
    package data (``mtaccuracy/data``).

    Parameters
    ----------
    notebook : path
        The ``.ipynb`` file.

    Returns
    -------
    list of Path
        The files, sorted.
    """
    roots: set[str] = set()
    for src in _code_cells(Path(notebook)):
        python = "\n".join("" if line.lstrip().startswith(("%", "!")) else line
                           for line in src.splitlines())  # IPython's magics and shell lines
        try:
            roots |= _imported(ast.parse(python), "")
        except SyntaxError:  # not Python: it imports nothing of ours
            continue
    return list(_closure(frozenset(roots)))


def library_hash(files) -> str:
    """SHA-256 over library files (their paths under ``lib/`` and their bytes), in order."""
    h = hashlib.sha256()
    for p in files:
        h.update(Path(p).relative_to(LIBRARY).as_posix().encode() + b"\0")
        h.update(Path(p).read_bytes())
    return h.hexdigest()


@functools.cache
def versions() -> dict:
    """The versions of the main packages and of Python."""
    out = {}
    for pkg in PACKAGES:
        try:
            out[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            out[pkg] = "not installed"
    out["python"] = platform.python_version()
    return out


def record(stem: str, notebook, parameters: dict) -> dict:
    """The start of a run's record: notebook, library code, parameters, packages.

    Parameters
    ----------
    stem : str
        The notebook's stem.
    notebook : path
        Its ``.ipynb`` file (its source cells and imports are hashed).
    parameters : dict
        The run's parameters (``output_dir`` is left out).

    Returns
    -------
    dict
        JSON-serialisable; ``inputs`` starts empty and the run adds each file it reads.
    """
    files = library_modules(notebook)
    return {"notebook": stem, "notebook_sha256": notebook_source_hash(notebook),
            "library_sha256": library_hash(files),
            "library_modules": [p.relative_to(LIBRARY).as_posix() for p in files],
            "parameters": {k: v for k, v in sorted(parameters.items()) if k != "output_dir"},
            "inputs": {}, "packages": versions()}


def as_text(rec: dict) -> str:
    """A record as one line of JSON (what figures carry in their metadata)."""
    return json.dumps(rec, sort_keys=True, separators=(",", ":"), default=str)


def write_atomic(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` only when its bytes change, replaced whole (rename)."""
    path = Path(path)
    if path.exists() and path.read_bytes() == data:
        return
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_bytes(data)
    os.replace(tmp, path)


def write_sidecar(folder, data: dict) -> None:
    """Write ``folder/provenance.json`` (files sorted, fixed format), replaced whole."""
    data = {**data, "files": dict(sorted(data.get("files", {}).items()))}
    text = json.dumps(data, sort_keys=True, indent=1, default=str) + "\n"
    write_atomic(Path(folder) / SIDECAR, text.encode("utf-8"))


def read(folder) -> dict:
    """The ``provenance.json`` of an output folder ({} when there is none or it is unreadable)."""
    try:
        data = json.loads((Path(folder) / SIDECAR).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def written_by(folder) -> str | None:
    """The notebook whose run wrote ``folder`` (its ``provenance.json``), or None."""
    run = read(folder).get("run")
    return run.get("notebook") if isinstance(run, dict) else None


def from_png(path) -> dict:
    """The provenance record stamped into a PNG ({} when there is none)."""
    from PIL import Image  # Pillow: only where a PNG is read

    with Image.open(path) as im:
        text = im.info.get("mtaccuracy:provenance")
    return json.loads(text) if text else {}


# ---------------------------------------------------------- checks before an output is shown

def output_kind(path) -> str:
    """What an output file is, for messages: "figure", "table" or "file"."""
    return {".png": "figure", ".svg": "figure", ".csv": "table"}.get(Path(path).suffix, "file")


def output_problem(path, side: dict) -> str | None:
    """Why an output file cannot be shown or linked, or None when it is sound.

    Parameters
    ----------
    path : Path
        The file, in its output folder.
    side : dict
        That folder's ``provenance.json`` (:func:`read`).

    Returns
    -------
    str or None
        The problem, to follow the file's name: missing though listed, a figure that cannot be
        decoded, not listed, no hash though not ``measured``, or bytes that are not the ones
        the run recorded.  A ``measured`` entry need only exist (and, for a figure, decode).
    """
    path = Path(path)
    entry = side.get("files", {}).get(path.name)
    if not path.is_file():
        return (f"is missing (listed in {SIDECAR}, not on disk)" if entry is not None
                else "is missing")
    from PIL import Image  # Pillow: only where a PNG is read

    try:
        if path.suffix == ".png":
            with Image.open(path) as im:
                im.load()  # decodes every byte: a truncated file fails here
        elif path.suffix == ".svg":
            ET.parse(path)
    except Exception as exc:  # PIL and expat raise many kinds
        return f"cannot be read ({type(exc).__name__}: {str(exc)[:80]})"
    if entry is None:
        return f"is not listed in {SIDECAR} (not written by this folder's run)"
    if entry.get("measured"):
        return None
    if "sha256" not in entry:
        return f"has no hash in {SIDECAR} and is not declared measured"
    if entry["sha256"] != sha256(path):
        return f"does not match the hash in {SIDECAR} (changed after its run)"
    return None


def folder_problems(folder, side: dict | None = None) -> list[tuple[Path, str]]:
    """Every problem (:func:`output_problem`) of the files an output folder's record lists.

    Parameters
    ----------
    folder : Path
        A notebook's output folder.
    side : dict, optional
        Its ``provenance.json`` (read when not given).

    Returns
    -------
    list of (Path, str)
        ``(path, why)`` for each listed file with a problem, sorted by name.
    """
    folder = Path(folder)
    side = read(folder) if side is None else side
    found = ((folder / n, output_problem(folder / n, side)) for n in sorted(side.get("files", {})))
    return [(p, why) for p, why in found if why]


def not_outputs(folder, side: dict | None = None) -> list[str]:
    """The files of an output folder that its ``provenance.json`` does not list: the user's.

    Parameters
    ----------
    folder : Path
        A notebook's output folder.
    side : dict, optional
        Its ``provenance.json`` (read when not given).

    Returns
    -------
    list of str
        Their names, sorted (hidden files left out).
    """
    folder = Path(folder)
    side = read(folder) if side is None else side
    listed = set(side.get("files", {})) | {SIDECAR}
    return sorted(p.name for p in folder.iterdir() if p.is_file()
                  and not p.name.startswith(".") and p.name not in listed) \
        if folder.is_dir() else []
