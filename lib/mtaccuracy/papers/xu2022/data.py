"""Notebook 04's data: the published tables, the committed reconstruction, its regeneration.

The thermal science (:mod:`mtaccuracy.thermal`) takes arrays and tables and never reads
``data/papers/`` or knows the repository's folders; this module does that for notebook 04: it
reads the published tables the reconstruction is built from (the seeded generator is
:mod:`mtaccuracy.papers.xu2022_reconstruction`), says by content whether a folder holds the
committed reconstruction (:func:`reconstruction_seed`) and what a run does with its data
(:func:`data_origin`).

A normal run of the notebook only reads its ``data_dir``.  Rewriting ``data/thermal`` is a
command of its own, :func:`regenerate` (:func:`main`)::

    python -m mtaccuracy.papers.xu2022 regenerate [FOLDER] [--seed S]
"""

from __future__ import annotations

import hashlib
import json
import sys
from pathlib import Path

from ... import thermal, validate
from .. import printed, xu2022_reconstruction
from ..xu2022_reconstruction import DEFAULT_SEED

__all__ = ["DATA", "DATA_FILES", "published_targets", "published_models", "published_inputs",
           "published_metrics", "reconstruct", "noise_replicates", "calibrate",
           "reconstruction_seed", "regenerate", "data_origin", "main"]


#: The committed reconstruction (``data/thermal``), with its ``provenance.json``: the generator,
#: the seed and the hashes of the files it wrote there (:func:`regenerate`).
DATA = printed.FOLDER.parent / "thermal"
#: The files whose content makes a folder the reconstruction (``experiments.csv`` may be absent).
DATA_FILES = ("temperatures.csv", "errors.csv", "experiments.csv")


def published_targets(*, on_read=None) -> xu2022_reconstruction.Targets:
    """Table 5 (k, b) and Table 1 (feeds, ambient ranges) from ``data/papers``.

    Parameters
    ----------
    on_read : callable, optional
        Called with each file read (``run.track``, for the run's provenance).

    Returns
    -------
    xu2022_reconstruction.Targets
        What the generator is built from.
    """
    t5 = printed.published("xu2022_table5_slope_intercept",
                           ["experiment", "measurement", "k_um_per_m", "b_um"], on_read=on_read)
    t1 = printed.published("xu2022_table1_experiments",
                           ["experiment", "feed_mm_per_min", "ambient_min_C", "ambient_max_C"],
                           on_read=on_read)
    return xu2022_reconstruction.targets_from_tables(t5, t1)


def published_models(*, on_read=None):
    """The printed models (Eqs. 8-9) from ``data/papers/xu2022_models.csv``.

    Parameters
    ----------
    on_read : callable, optional
        Called with the file read.

    Returns
    -------
    pandas.DataFrame
        ``model, target, term, coefficient``, as printed (text).
    """
    return printed.published("xu2022_models", ["model", "target", "term", "coefficient"],
                             on_read=on_read)


def published_inputs(*, on_read=None) -> dict[str, list[str]]:
    """The paper's sensitive points, read off the terms of its printed models.

    Parameters
    ----------
    on_read : callable, optional
        Called with the file read (``data/papers/xu2022_models.csv``).

    Returns
    -------
    dict
        ``{"point": Eq. 8's sensors, "k": Eq. 9's for the slope, "b": Eq. 9's for the
        intercept}``, each in the order the paper prints them.
    """
    models = published_models(on_read=on_read)
    terms = models[models.term != "intercept"]

    def of(model, prefix=""):
        rows = terms[(terms.model == model) & terms.target.str.startswith(prefix)]
        return list(dict.fromkeys(t.removeprefix("d") for t in rows.term))
    return {"point": of("point_by_point_mlr"), "k": of("decoupled_mlr", "k"),
            "b": of("decoupled_mlr", "b")}


def published_metrics(*, on_read=None):
    """The printed prediction metrics (Tables 4, 7, 8) from ``data/papers/xu2022_metrics.csv``.

    Parameters
    ----------
    on_read : callable, optional
        Called with the file read.

    Returns
    -------
    pandas.DataFrame
        ``table, method, target, rmse, max_residual, mae, unit``, as printed (text).
    """
    return printed.published("xu2022_metrics", ["table", "method", "target", "rmse",
                                                "max_residual", "mae", "unit"], on_read=on_read)


def reconstruct(seed: int = DEFAULT_SEED, *, on_read=None) -> thermal.ThermalData:
    """:func:`.xu2022_reconstruction.reconstruct` on the published targets, in memory.

    Parameters
    ----------
    seed : int
        Seed of the reconstruction's noise (:data:`DEFAULT_SEED` gives ``data/thermal``).
    on_read : callable, optional
        Called with each published table read.

    Returns
    -------
    ThermalData
        The reconstruction, as :func:`mtaccuracy.thermal.read_measurements` would read it
        written.
    """
    return xu2022_reconstruction.reconstruct(published_targets(on_read=on_read), seed)


def noise_replicates(seed: int = DEFAULT_SEED, n: int = 40, *, on_read=None):
    """:func:`.xu2022_reconstruction.noise_replicates` on the published targets.

    Parameters
    ----------
    seed : int
        Seed of the reconstruction (replicate 0).
    n : int
        Replicates, replicate 0 included.
    on_read : callable, optional
        Called with each published table read.

    Returns
    -------
    xu2022_reconstruction.Replicates
        ``n`` realisations of the reconstruction's noise.
    """
    return xu2022_reconstruction.noise_replicates(published_targets(on_read=on_read), seed, n)


def calibrate(**kwargs):
    """:func:`.xu2022_reconstruction.calibrate` on the published tables (about a minute).

    Parameters
    ----------
    **kwargs
        Passed on to :func:`.xu2022_reconstruction.calibrate`.

    Returns
    -------
    object
        What :func:`.xu2022_reconstruction.calibrate` returns.
    """
    return xu2022_reconstruction.calibrate(published_targets(), published_models(),
                                           published_metrics(), **kwargs)


def _sha256(path: Path) -> str:
    # through validate.file_bytes: a FIFO, a device or an over-size file is refused unread
    return hashlib.sha256(validate.file_bytes(path, max_bytes=thermal.MAX_FILE_BYTES)
                          ).hexdigest()


def _recorded() -> tuple[int | None, dict]:
    """The seed and ``{file: sha256}`` that ``data/thermal/provenance.json`` records."""
    try:
        side = json.loads((DATA / "provenance.json").read_text(encoding="utf-8"))
        files = {n: e["sha256"] for n, e in side["files"].items() if "sha256" in e}
        return int(side["run"]["seed"]), files
    except (OSError, ValueError, KeyError, TypeError):
        return None, {}


def reconstruction_seed(folder) -> int | None:
    """The seed of the committed reconstruction when ``folder`` holds it, else None.

    Decided by content: its ``temperatures.csv`` and ``errors.csv`` (and ``experiments.csv``,
    if it has one) are byte-identical to the files whose SHA-256 ``data/thermal/provenance.json``
    records.  A copy anywhere is the reconstruction; an edited file in ``data/thermal`` is not.
    The seed is the one that file records (:data:`DEFAULT_SEED`, 2022, as committed).

    Parameters
    ----------
    folder : path
        The folder the measurements were read from.

    Returns
    -------
    int or None
        The seed of the reconstruction, or None for a reader's own data.
    """
    folder = Path(folder)
    seed, recorded = _recorded()
    names = [n for n in DATA_FILES if n != "experiments.csv" or (folder / n).is_file()]
    if recorded and all((folder / n).is_file() and recorded.get(n) == _sha256(folder / n)
                        for n in names):
        return seed
    return None


def regenerate(folder=DATA, *, seed: int = DEFAULT_SEED) -> list[Path]:
    """Write the reconstruction with ``seed`` into ``folder`` (``data/thermal``): its own command.

    A normal run of notebook 04 only reads its data; this rewrites them (``python -m
    mtaccuracy.papers.xu2022 regenerate``) and the folder's ``provenance.json`` (generator,
    seed, each file's SHA-256).  A file is written only when its bytes change, and a file whose
    bytes are not those ``data/thermal/provenance.json`` records (edited by someone; in any
    other folder, every existing file that would change) is never overwritten: nothing is
    written and the error names it.

    Parameters
    ----------
    folder : path
        Where to write (created if missing).
    seed : int
        Seed of the reconstruction's noise; the committed files are :data:`DEFAULT_SEED`'s.

    Returns
    -------
    list of Path
        The data files that changed.

    Raises
    ------
    RuntimeError
        A file would be overwritten that the generator did not write last.
    """
    folder = Path(folder)
    recorded = _recorded()[1] if folder.resolve() == DATA.resolve() else {}

    def refuse(files):
        edited = [p for p in files if recorded.get(p.name) != _sha256(p)]
        if edited:
            raise RuntimeError(f"{', '.join(str(p) for p in edited)}: edited since the "
                               f"generator wrote it (not the SHA-256 {folder}/provenance.json "
                               f"records); nothing was written: restore it (git checkout) or "
                               f"move it away first")
    folder.mkdir(parents=True, exist_ok=True)
    changed = thermal.write_measurements(reconstruct(seed), folder, before_overwrite=refuse)
    files = {n: {"sha256": _sha256(folder / n)} for n in DATA_FILES if (folder / n).is_file()}
    side = {"run": {"generator": "mtaccuracy.papers.xu2022_reconstruction", "seed": seed},
            "files": files}
    text = json.dumps(side, sort_keys=True, indent=1) + "\n"
    if not (folder / "provenance.json").is_file() or \
            (folder / "provenance.json").read_text(encoding="utf-8") != text:
        (folder / "provenance.json").write_text(text, encoding="utf-8")
    return changed


def data_origin(data_dir, recon_seed: int | None, seed: int) -> str:
    """What notebook 04 does with its data, in one line (its output says so).

    Parameters
    ----------
    data_dir : str
        The ``data_dir`` parameter, as given.
    recon_seed : int or None
        :func:`reconstruction_seed` of the folder read.
    seed : int
        The ``seed`` parameter.

    Returns
    -------
    str
        The reconstruction read as it is, the reconstruction with another seed built in memory
        (nothing written), or a reader's own data ("not the paper's reconstruction").
    """
    if recon_seed is None:
        return (f"{data_dir}: your measurements, read only; not the paper's reconstruction: the "
                f"method on these data, no comparison with the paper (seed does not apply)")
    if seed == recon_seed:
        return (f"{data_dir}: the paper's reconstruction (seed {seed}; its files' SHA-256 are "
                f"those data/thermal/provenance.json records), read only: compared with the "
                f"paper below")
    return (f"{data_dir}: the paper's reconstruction with seed {recon_seed}; seed = {seed}: the "
            f"reconstruction with seed {seed}, built in memory (nothing written; `python -m "
            f"mtaccuracy.papers.xu2022 regenerate FOLDER --seed {seed}` writes it): compared "
            f"with the paper below")


def main(argv=None) -> int:
    """``python -m mtaccuracy.papers.xu2022 regenerate [FOLDER] [--seed S]``: :func:`regenerate`.

    Parameters
    ----------
    argv : list of str, optional
        The command line's arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        0, or 2 when a file was edited (nothing is written).
    """
    import argparse  # the command line: only when run as a command

    ap = argparse.ArgumentParser(prog="python -m mtaccuracy.papers.xu2022")
    ap.add_argument("command", choices=["regenerate"])
    ap.add_argument("folder", nargs="?", default=str(DATA))
    ap.add_argument("--seed", type=int, default=DEFAULT_SEED)
    args = ap.parse_args(argv)
    try:
        changed = regenerate(args.folder, seed=args.seed)
    except RuntimeError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(f"{args.folder}: reconstruction with seed {args.seed}: "
          + (f"{len(changed)} file(s) rewritten" if changed else "every file byte-identical"))
    return 0
