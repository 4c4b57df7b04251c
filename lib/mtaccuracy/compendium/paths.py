"""Where things live in the compendium, and which output folders a notebook may write.

The paths do not depend on the current working directory.

A notebook's ``output_dir`` may be (:func:`check_output_dir`):

* ``figures/<its own stem>`` (relative paths are taken from the repository root, or from
  ``$MTACCURACY_OUTPUT_BASE`` when that is set, as the tests do), or
* a folder outside the repository that does not exist yet, is empty, or was written by an
  earlier run of the same notebook (its ``provenance.json`` names the notebook).

Never the repository root, never another notebook's folder, never a folder inside the
repository other than its own, never a non-empty folder the compendium did not write.

When the runner executes a notebook it sets ``$MTACCURACY_STAGING``: :func:`output_dir` then
returns that staging folder, and the runner commits its content into the real output folder only
when the whole run succeeded (see :mod:`mtaccuracy.compendium.commit`).
"""

from __future__ import annotations

import json
import os
from pathlib import Path

#: The repository root (``lib/mtaccuracy/compendium/paths.py`` -> three levels up).
ROOT = Path(__file__).resolve().parents[3]
DATA = ROOT / "data"
PAPERS = DATA / "papers"
NOTEBOOKS = ROOT / "notebooks"
FIGURES = ROOT / "figures"

#: Environment variable that redirects relative output folders (used by the tests, so that
#: executing a notebook under test never rewrites the committed figures).
OUTPUT_BASE_ENV = "MTACCURACY_OUTPUT_BASE"
#: Set by the runner for the kernel: the folder a run writes into before it is moved in place.
STAGING_ENV = "MTACCURACY_STAGING"
#: A run's staging folder inside its output folder is ``<output>/.staging-<pid>/``: the
#: runner's own, not a file that makes the folder "not empty".
STAGING_PREFIX = ".staging-"


class OutputDirError(ValueError):
    """An ``output_dir`` that a notebook must not write into."""


def _base() -> Path:
    base = os.environ.get(OUTPUT_BASE_ENV)
    return Path(base).resolve() if base else ROOT


def resolve_output(path: str | os.PathLike) -> Path:
    """The absolute, normalised folder an ``output_dir`` value names.

    ``..`` and symbolic links are resolved."""
    p = Path(os.path.expanduser(os.fspath(path)))
    if not p.is_absolute():
        p = _base() / p
    return p.resolve()


def _written_by(folder: Path) -> str | None:
    """The notebook named by ``folder/provenance.json``, or None."""
    side = folder / "provenance.json"
    try:
        return json.loads(side.read_text(encoding="utf-8"))["run"]["notebook"]
    except (OSError, ValueError, KeyError, TypeError):
        return None


def check_output_dir(path: str | os.PathLike, notebook: str) -> Path:
    """Check that notebook ``notebook`` (its stem) may write into ``path``; return it resolved.

    Raises :class:`OutputDirError` saying what is allowed."""
    allowed = (f"use figures/{notebook} (the default) or a new or empty folder outside the "
               f"repository ({ROOT})")
    if not str(path).strip():
        raise OutputDirError(f"{notebook}: output_dir is empty, which would be the repository "
                             f"root; {allowed}")
    p = resolve_output(path)
    base = _base()
    own = base / "figures" / notebook
    if p == own:
        return p
    inside = [r for r in {ROOT, base} if p == r or p.is_relative_to(r) or r.is_relative_to(p)]
    if inside:
        other = p.parent == base / "figures" and (
            _written_by(p) not in (None, notebook)
            or any(n.stem == p.name for n in NOTEBOOKS.glob("[0-9][0-9]_*.ipynb")))
        what = ("the repository root" if p in (ROOT, base) else
                "a folder that contains the repository" if ROOT.is_relative_to(p) else
                f"another notebook's folder ({p.name})" if other else
                "a folder inside the repository that is not this notebook's")
        raise OutputDirError(f"{notebook}: output_dir {str(path)!r} is {p}, {what}; {allowed}")
    if p.exists() and not p.is_dir():
        raise OutputDirError(f"{notebook}: output_dir {str(path)!r} is a file ({p}); {allowed}")
    if p.is_dir() and any(not c.name.startswith(STAGING_PREFIX) for c in p.iterdir()):
        owner = _written_by(p)
        if owner != notebook:
            why = (f"it holds the outputs of {owner}" if owner else
                   "it is not empty and was not written by the compendium")
            raise OutputDirError(f"{notebook}: output_dir {str(path)!r} ({p}): {why}; nothing "
                                 f"there is overwritten; {allowed}")
    return p


def check_copy_dir(path: str | os.PathLike) -> Path:
    """The folder of ``--copy-to``, resolved: it must lie outside the repository.

    It receives the executed notebook and, by default, its outputs under ``figures/<stem>/`` there;
    outside the repository, a copy never touches the committed notebooks, figures or anything else
    of the checkout.  Raises :class:`OutputDirError`."""
    text = os.fspath(path)
    if not str(text).strip():
        raise OutputDirError("--copy-to needs a folder outside the repository")
    p = Path(os.path.expanduser(text))
    p = (p if p.is_absolute() else Path.cwd() / p).resolve()
    if p == ROOT or p.is_relative_to(ROOT) or ROOT.is_relative_to(p):
        what = ("the repository" if p == ROOT else "a folder inside the repository"
                if p.is_relative_to(ROOT) else "a folder that contains the repository")
        raise OutputDirError(f"--copy-to {text!r} is {p}, {what}; give a folder outside the "
                             f"repository ({ROOT})")
    if p.exists() and not p.is_dir():
        raise OutputDirError(f"--copy-to {text!r} is a file ({p})")
    return p


def output_dir(path: str | os.PathLike) -> Path:
    """Resolve a notebook's ``output_dir`` parameter and create the folder.

    Under the runner (``$MTACCURACY_STAGING`` set) the run writes into the staging folder,
    which the runner moves into place only when the run succeeds.  A relative path is taken
    from the repository root, or from ``$MTACCURACY_OUTPUT_BASE`` when that is set; an
    absolute path is used as given (the rules are checked by :func:`check_output_dir`, which
    ``check_parameters`` calls first).
    """
    staging = os.environ.get(STAGING_ENV)
    p = Path(staging) if staging else resolve_output(path)
    p.mkdir(parents=True, exist_ok=True)
    return p


def relative(path) -> str:
    """``path`` as a reader of this repository's messages wants it, ``/``-separated.

    Relative to the repository root when it lies inside (symbolic links resolved), else absolute."""
    p = Path(path).resolve()
    try:
        return p.relative_to(ROOT).as_posix()
    except ValueError:
        return p.as_posix()


def input_file(name, what: str) -> Path:
    """An input file a notebook parameter names.

    Relative paths are taken from the repository root; a missing file is a ``FileNotFoundError``
    naming the parameter."""
    path = Path(name) if Path(name).is_absolute() else ROOT / name
    if not path.exists():
        raise FileNotFoundError(f"{what} {name!r} not found")
    return path
