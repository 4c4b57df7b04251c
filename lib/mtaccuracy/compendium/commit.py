"""The commit of a finished run: journalled, so that a kill at any step leaves one whole run.

A run writes its outputs into a staging folder inside its output folder
(``<output>/.staging-<pid>/``) and its executed notebook into a temporary file.  When every
cell has succeeded, :func:`commit` switches the output folder and the notebook from the old run
to the new one:

1. under a lock (one commit at a time, in this checkout), it reads what the old run wrote: the
   files listed in the output folder's ``provenance.json`` (the *manifest*, with the SHA-256 of
   each file; the runner lists there every file a run writes);
2. it plans the switch: each staged file moves into the output folder, each file of the old
   manifest that the new run did not write again is removed, the notebook is replaced.  A file
   the compendium did not write (not in the manifest, or changed since: its bytes no longer
   match the recorded hash) is never overwritten or removed: a planned overwrite is refused
   before anything moves (:class:`CommitConflict`; the run is kept in ``notebooks/.failed/``),
   a file merely lying there is left alone and named in the result;
3. it writes the plan to a journal, ``notebooks/.commits/<stem>-<pid>.json`` (written to a
   temporary file, flushed to disk, then renamed into place: it exists whole or not at all);
4. it carries the plan out, every step a rename or a removal that can be repeated;
5. it removes the journal.

A kill before step 3 leaves the old run whole (the staging folder is garbage, removed later);
after it, :func:`recover` (called by every ``make`` target and at the start of every runner
command) finds the journal and carries the remaining steps out, so the next command sees the
new run whole.  Steps are idempotent: a rename whose source is gone was done.

Standard library only, so that ``make clean`` can recover without the virtual environment.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import shutil
import sys
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath

from . import paths
from .provenance import SIDECAR, sha256, write_sidecar

STAGING_PREFIX = paths.STAGING_PREFIX


class CommitConflict(RuntimeError):
    """A commit would overwrite a file the compendium did not write."""


def journal_dir() -> Path:
    """Where pending commits are journalled (``notebooks/.commits/``)."""
    return paths.NOTEBOOKS / ".commits"


def _safe_rel(name) -> str | None:
    """``name`` as a relative POSIX path inside a folder, or None when it could leave it (an
    absolute path, ``..``, an empty part): a manifest is data, never trusted to name a file
    elsewhere."""
    if not isinstance(name, str) or not name or "\\" in name or "\0" in name:
        return None
    p = PurePosixPath(name)
    if p.is_absolute() or any(part in ("", ".", "..") for part in name.split("/")):
        return None
    return p.as_posix()


def manifest(folder: Path, stem: str) -> dict[str, str | None]:
    """The files the compendium wrote in ``folder`` for notebook ``stem``, with their hashes.

    Relative path -> the SHA-256 recorded when it was written (None: not hashed, a measured file or
    the manifest itself).  Empty when ``folder`` has no manifest of ``stem``."""
    try:
        data = json.loads((Path(folder) / SIDECAR).read_text(encoding="utf-8"))
        if data["run"]["notebook"] != stem or not isinstance(data.get("files", {}), dict):
            return {}
    except (OSError, ValueError, KeyError, TypeError):
        return {}
    out: dict[str, str | None] = {}
    for name, entry in data.get("files", {}).items():
        rel = _safe_rel(name)
        if rel is not None and rel != SIDECAR:
            digest = entry.get("sha256") if isinstance(entry, dict) else None
            out[rel] = digest if isinstance(digest, str) else None
    out[SIDECAR] = None
    return out


def _is_ours(path: Path, digest: str | None) -> bool:
    """Whether the file at ``path`` still holds what the compendium wrote (no recorded hash:
    a measured file or the manifest, ours whatever its bytes)."""
    if path.is_symlink() or not path.is_file():
        return False
    return digest is None or sha256(path) == digest


def written_notebook_is_ours(path: Path, name: str) -> bool:
    """Whether ``path`` is an executed notebook the compendium stored.

    It is when its papermill metadata names ``notebooks/<name>``, as
    :func:`mtaccuracy.compendium.runner` normalises it."""
    if path.is_symlink() or not path.is_file():
        return False
    try:
        meta = json.loads(path.read_text(encoding="utf-8"))["metadata"]["papermill"]
    except (OSError, ValueError, KeyError, TypeError):
        return False
    return meta.get("input_path") == f"notebooks/{name}"


def modified_outputs(folder: Path, stem: str) -> list[str]:
    """Files of ``folder``'s manifest whose bytes changed since the compendium wrote them."""
    folder = Path(folder)
    return sorted(rel for rel, digest in manifest(folder, stem).items()
                  if (folder / rel).exists() and not _is_ours(folder / rel, digest))


def _files(folder: Path) -> list[str]:
    """Every file below ``folder``, as sorted relative POSIX paths."""
    return sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*")
                  if p.is_file() or p.is_symlink())


def complete_manifest(staging: Path, stem: str) -> None:
    """List in ``staging/provenance.json`` every staged file the notebook wrote unregistered.

    Each is listed with its hash, so that the next run knows the compendium wrote it."""
    side = staging / SIDECAR
    try:
        data = json.loads(side.read_text(encoding="utf-8")) if side.exists() else {}
    except ValueError:
        data = {}
    if not isinstance(data, dict) or not isinstance(data.get("run"), dict):
        data = {"run": {"notebook": stem}, "files": {}}
    data.setdefault("files", {})
    listed = set(data["files"])
    extra = [rel for rel in _files(staging) if rel != SIDECAR and rel not in listed]
    if not extra and side.exists():
        return
    for rel in extra:
        data["files"][rel] = {"sha256": sha256(staging / rel)}
    write_sidecar(staging, data)


@dataclass
class Result:
    """What a commit did."""

    written: list[str] = field(default_factory=list)
    removed: list[str] = field(default_factory=list)
    left_alone: list[str] = field(default_factory=list)


@contextlib.contextmanager
def _locked():
    """The checkout's commit lock (released by the kernel when the process dies)."""
    import fcntl  # POSIX only: imported where the lock is taken, so the module imports anywhere

    d = journal_dir()
    d.mkdir(parents=True, exist_ok=True)
    fd = os.open(d / ".lock", os.O_RDWR | os.O_CREAT, 0o644)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)


def _step(name: str) -> None:
    """Called after every step of a commit that changes the disk: the fault-injection point
    of the tests (they replace it with a function that kills the process at step ``name``)."""


def _write_journal(plan: dict, path: Path) -> None:
    tmp = path.with_name(f".{path.name}.tmp")
    with open(tmp, "w", encoding="utf-8") as fh:
        json.dump(plan, fh, indent=1, sort_keys=True)
        fh.write("\n")
        fh.flush()
        os.fsync(fh.fileno())
    _step("journal-temp")
    os.replace(tmp, path)
    with contextlib.suppress(OSError):
        dfd = os.open(path.parent, os.O_RDONLY)
        try:
            os.fsync(dfd)
        finally:
            os.close(dfd)
    _step("journal")


def _carry_out(plan: dict) -> None:
    """Steps 4 and 5; every step may already have been done by a process that was killed."""
    target, staging = Path(plan["target"]), Path(plan["staging"])
    for rel in plan["moves"]:
        src, dst = staging / rel, target / rel
        if src.exists() or src.is_symlink():
            dst.parent.mkdir(parents=True, exist_ok=True)
            os.replace(src, dst)
            _step(f"move {rel}")
    for rel in plan["removes"]:
        p = target / rel
        if p.exists() or p.is_symlink():
            p.unlink()
            _step(f"remove {rel}")
    nb = plan.get("notebook")
    if nb and Path(nb["src"]).exists():
        os.replace(nb["src"], nb["dst"])
        _step("notebook")
    shutil.rmtree(staging, ignore_errors=True)
    _step("staging")


def commit(staging: Path, target: Path, *, stem: str,
           notebook: tuple[Path, Path] | None = None) -> Result:
    """Switch ``target`` (and the notebook) from the old run to the staged one, journalled.

    Parameters
    ----------
    staging : Path
        The new run's outputs (a folder inside ``target``).
    target : Path
        The output folder.
    stem : str
        The notebook's stem (whose manifest ``target`` holds).
    notebook : (Path, Path), optional
        ``(temporary file, destination)`` of the executed notebook when it is stored outside
        ``target`` (in ``notebooks/`` for a run in place).

    Returns
    -------
    Result
        The files written, removed and left alone (relative to ``target``).

    Raises
    ------
    CommitConflict
        When a staged file would overwrite a file the compendium did not write; nothing has
        moved then.
    """
    staging, target = Path(staging), Path(target)
    complete_manifest(staging, stem)
    with _locked():
        old = manifest(target, stem)
        new = _files(staging)
        conflicts = []
        for rel in new:
            dst = target / rel
            if dst.exists() or dst.is_symlink():
                if rel not in old and not (rel == f"{stem}.ipynb"
                                           and written_notebook_is_ours(dst, rel)):
                    conflicts.append(f"{rel} (not written by the compendium)")
                elif not _is_ours(dst, old[rel]):
                    conflicts.append(f"{rel} (changed since the compendium wrote it)")
        if notebook is not None:
            src, dst = notebook
            if (dst.exists() or dst.is_symlink()) and dst != paths.NOTEBOOKS / dst.name \
                    and not written_notebook_is_ours(dst, dst.name):
                conflicts.append(f"{dst} (not a notebook the compendium stored)")
        if conflicts:
            raise CommitConflict(f"{target}: the run would overwrite {', '.join(conflicts)}; "
                                 f"nothing was changed: move that away and run again")
        result = Result(written=new)
        removes = []
        for rel in sorted(set(old) - set(new)):
            p = target / rel
            if p.exists() or p.is_symlink():
                (removes if _is_ours(p, old[rel]) else result.left_alone).append(rel)
        result.removed = removes
        mine = set(new) | set(old)
        result.left_alone += [rel for rel in _files(target)
                              if rel not in mine and not rel.startswith(STAGING_PREFIX)]
        result.left_alone.sort()
        plan = {"version": 1, "stem": stem, "target": str(target), "staging": str(staging),
                "moves": new, "removes": removes,
                "notebook": {"src": str(notebook[0]), "dst": str(notebook[1])}
                if notebook is not None else None}
        journal = journal_dir() / f"{stem}-{os.getpid()}.json"
        _write_journal(plan, journal)
        _carry_out(plan)
        journal.unlink()
        _step("done")
    return result


def pending() -> list[Path]:
    """The journals of commits that were started and not finished."""
    d = journal_dir()
    return sorted(d.glob("*.json")) if d.is_dir() else []


def recover(*, quiet: bool = False) -> list[str]:
    """Finish every commit a killed process left half done, and clean up after dead runs.

    What runs that died before committing left (staging folders, temporary notebooks) in
    ``figures/`` and ``notebooks/`` is removed.  Returns one line per commit finished."""
    done = []
    d = journal_dir()
    if pending() or (d.is_dir() and any(d.glob(".*.json.tmp"))):
        with _locked():
            for j in pending():
                try:
                    plan = json.loads(j.read_text(encoding="utf-8"))
                    _carry_out(plan)
                except (OSError, ValueError, KeyError, TypeError) as exc:
                    print(f"warning: cannot finish the interrupted commit {j}: {exc}",
                          file=sys.stderr)
                    continue
                j.unlink()
                done.append(f"finished the interrupted commit of {plan['stem']} into "
                            f"{plan['target']}")
            for tmp in d.glob(".*.json.tmp"):  # a journal never renamed: the commit not begun
                tmp.unlink(missing_ok=True)
    for folder in [paths.NOTEBOOKS, *paths.FIGURES.glob("*/")]:
        remove_stale(folder)
    if not quiet:
        for line in done:
            print(line, file=sys.stderr)
    return done


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError):
        return True
    return True


_LEFTOVER = re.compile(r"^\.(?:staging-(\d+)|.+\.commit-(\d+)\.tmp)$")


def remove_stale(folder: Path) -> list[Path]:
    """Remove from ``folder`` the staging folders and temporary notebooks of dead runs.

    Staging folders are ``.staging-<pid>``, temporary notebooks ``.<name>.commit-<pid>.tmp``; a run
    is dead when its process is gone and no pending journal names it.  Returns what was removed."""
    gone = []
    try:
        entries = list(Path(folder).iterdir())
    except OSError:
        return gone
    named = set()
    for j in pending():
        with contextlib.suppress(OSError, ValueError, KeyError, TypeError):
            plan = json.loads(j.read_text(encoding="utf-8"))
            named |= {plan["staging"], (plan.get("notebook") or {}).get("src")}
    for p in entries:
        m = _LEFTOVER.match(p.name)
        if not m or _alive(int(m.group(1) or m.group(2))) or str(p) in named:
            continue
        try:
            shutil.rmtree(p) if p.is_dir() and not p.is_symlink() else p.unlink()
        except OSError:
            continue
        gone.append(p)
    return gone


def main(argv=None) -> int:
    """``python -m mtaccuracy.compendium.commit [--recover]``: finish interrupted commits."""
    try:
        recover()
    except KeyboardInterrupt:
        print("interrupted while finishing an interrupted commit; run it again",
              file=sys.stderr)
        return 130
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
