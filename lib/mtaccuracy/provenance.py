"""Provenance of every output: which code, notebook, parameters and input data made it.

A notebook's first call, :func:`mtaccuracy.runner.check_parameters`, starts a record
(:func:`start`); every input file read through the library is hashed into it (:func:`track`,
called by ``reproduction.published`` and the data readers); every figure and table saved
through ``plotting.save`` and ``reproduction.save_table`` carries it: PNG text chunk
``mtaccuracy:provenance``, SVG ``Description``, and for CSVs the sidecar ``provenance.json`` of
their folder, which lists every output file with its SHA-256.

The record holds the git commit, a hash of the library sources (so uncommitted code changes
show), the notebook, its parameters (except ``output_dir``, which only says where files go),
the SHA-256 of each input file and the versions of the main packages.  It has no timestamp:
two runs of the same commit with the same parameters give identical records.
"""

from __future__ import annotations

import hashlib
import json
import platform
import subprocess
from importlib import metadata
from pathlib import Path

from . import paths

PACKAGES = ("numpy", "scipy", "pandas", "matplotlib", "SALib", "chaospy", "scikit-learn",
            "sympy", "papermill")
SIDECAR = "provenance.json"
_IGNORED_PARAMETERS = {"output_dir"}
_state: dict = {"notebook": None, "parameters": {}, "inputs": {}}


def sha256(path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def _rel(path) -> str:
    p = Path(path).resolve()
    try:
        return p.relative_to(paths.ROOT).as_posix()
    except ValueError:
        return p.as_posix()


def git_commit() -> str:
    try:
        out = subprocess.run(["git", "rev-parse", "HEAD"], cwd=paths.ROOT, capture_output=True,
                             text=True, timeout=10)
        return out.stdout.strip() or "unknown"
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def library_hash() -> str:
    """SHA-256 over the library's Python sources, in path order."""
    h = hashlib.sha256()
    lib = Path(__file__).resolve().parent
    for p in sorted(lib.rglob("*.py")):
        h.update(p.relative_to(lib).as_posix().encode())
        h.update(p.read_bytes())
    return h.hexdigest()


def start(notebook: str, parameters: dict) -> None:
    """Begin the record of a notebook run (called by ``check_parameters``)."""
    _state["notebook"] = notebook
    _state["parameters"] = {k: v for k, v in sorted(parameters.items())
                            if k not in _IGNORED_PARAMETERS}
    _state["inputs"] = {}
    for value in _state["parameters"].values():  # a parameter naming a data file or folder
        if isinstance(value, str) and value and not value.startswith("/"):
            p = paths.ROOT / value
            for f in ([p] if p.is_file() else sorted(p.rglob("*")) if p.is_dir() else []):
                track(f)


def track(path) -> None:
    """Add an input file's hash to the current record."""
    p = Path(path)
    if p.is_file():
        _state["inputs"][_rel(p)] = sha256(p)


def record() -> dict:
    """The current provenance record (JSON-serialisable, deterministic)."""
    versions = {}
    for pkg in PACKAGES:
        try:
            versions[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            versions[pkg] = "not installed"
    versions["python"] = platform.python_version()
    return {"commit": git_commit(), "library_sha256": library_hash(),
            "notebook": _state["notebook"], "parameters": dict(_state["parameters"]),
            "inputs": dict(sorted(_state["inputs"].items())), "packages": versions}


def as_text(rec: dict | None = None) -> str:
    return json.dumps(rec or record(), sort_keys=True, separators=(",", ":"), default=str)


def register_output(path) -> None:
    """Record an output file (with its hash) in its folder's ``provenance.json``."""
    p = Path(path)
    side = p.parent / SIDECAR
    data = json.loads(side.read_text(encoding="utf-8")) if side.exists() else {}
    rec = record()
    files = data.get("files", {}) if data.get("run", {}).get("notebook") == rec["notebook"] \
        else {}
    files[p.name] = {"sha256": sha256(p)}
    data = {"run": rec, "files": dict(sorted(files.items()))}
    text = json.dumps(data, sort_keys=True, indent=1, default=str) + "\n"
    if not side.exists() or side.read_text(encoding="utf-8") != text:
        side.write_text(text, encoding="utf-8")


def read(folder) -> dict:
    """The sidecar of an output folder ({} when there is none)."""
    side = Path(folder) / SIDECAR
    return json.loads(side.read_text(encoding="utf-8")) if side.exists() else {}


def from_png(path) -> dict:
    """The provenance record stamped into a PNG (or {})."""
    from PIL import Image

    with Image.open(path) as im:
        text = im.info.get("mtaccuracy:provenance")
    return json.loads(text) if text else {}
