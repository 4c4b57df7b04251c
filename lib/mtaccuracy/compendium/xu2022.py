"""The compendium's side of notebook 04 (Xu et al. 2022): published values, files, tolerances.

The thermal science (:mod:`mtaccuracy.thermal`) takes arrays and tables and never reads
``data/papers/`` or knows the repository's folders; this module does that for the notebook:
it reads the published tables the reconstruction is built from, decides where the
reconstruction is written (never over a reader's own measurements), reads the measurements
with provenance recorded, and declares how closely regenerated tables must agree.
"""

from __future__ import annotations

from pathlib import Path

from .. import thermal
from ..thermal import synthetic
from . import paths, provenance, reproduction

__all__ = [
    "DEFAULT_DIR", "LSTSQ_TOLERANCE", "SVR_TOLERANCE", "published_targets", "published_models",
    "reconstruct", "noise_replicates", "calibrate", "read", "is_default_dir", "prepare",
]

#: Where the committed reconstruction lives (relative to the repository root).
DEFAULT_DIR = "data/thermal"

#: How closely tables of least-squares results (MLR coefficients, their predictions and
#: metrics) regenerated on another machine must agree: ``LinearRegression`` solves through
#: LAPACK and BLAS, whose kernels round differently; the centred designs of the notebook have
#: condition numbers below 30, so the coefficients move by about cond**2 * eps < 2e-13
#: relative (observed < 2e-10 on the metrics, which subtract predictions from errors).
LSTSQ_TOLERANCE = reproduction.Tolerance(
    rel=1e-8, why="least-squares solve (LAPACK/BLAS) with condition number < 30: "
                  "kernel-dependent rounding moves results by < 1e-9 relative")
#: ... and of tables with SVR results (and mixed tables holding them): libsvm stops at
#: ``thermal.SVR_SOLVER_TOL``, and where that stopping point is reached along another
#: floating-point path the metrics move by up to 3e-5 relative (observed).
SVR_TOLERANCE = reproduction.Tolerance(
    rel=1e-3, why="SVR solved by libsvm to tol 1e-6: rounding-level input changes move "
                  "held-out metrics by up to 3e-5 relative; 1e-3 bounds that with margin")


def published_targets(folder=None) -> synthetic.Targets:
    """Table 5 (k, b) and Table 1 (feeds, ambient ranges) from ``data/papers``."""
    t5 = reproduction.published("xu2022_table5_slope_intercept",
                                ["experiment", "measurement", "k_um_per_m", "b_um"], folder)
    t1 = reproduction.published("xu2022_table1_experiments",
                                ["experiment", "feed_mm_per_min", "ambient_min_C",
                                 "ambient_max_C"], folder)
    return synthetic.targets_from_tables(t5, t1)


def published_models(folder=None):
    """The printed models (Eqs. 8-9) from ``data/papers/xu2022_models.csv``."""
    return reproduction.published("xu2022_models", ["model", "target", "term", "coefficient"],
                                  folder)


def reconstruct(seed: int = synthetic.DEFAULT_SEED, papers_folder=None) -> thermal.ThermalData:
    """:func:`mtaccuracy.thermal.synthetic.reconstruct` on the published targets."""
    return synthetic.reconstruct(published_targets(papers_folder), seed)


def noise_replicates(seed: int = synthetic.DEFAULT_SEED, n: int = 40, papers_folder=None):
    """:func:`mtaccuracy.thermal.synthetic.noise_replicates` on the published targets."""
    return synthetic.noise_replicates(published_targets(papers_folder), seed, n)


def calibrate(papers_folder=None, **kwargs):
    """:func:`mtaccuracy.thermal.synthetic.calibrate` on the published tables (about a minute)."""
    return synthetic.calibrate(published_targets(papers_folder), published_models(papers_folder),
                               **kwargs)


def read(folder) -> thermal.ThermalData:
    """:func:`mtaccuracy.thermal.read_measurements` with every file read recorded in the run's
    provenance."""
    return thermal.read_measurements(folder, on_read=provenance.track)


def is_default_dir(data_dir) -> bool:
    """Whether ``data_dir`` names the committed reconstruction folder ``data/thermal``."""
    p = Path(data_dir)
    p = p if p.is_absolute() else paths.ROOT / p
    return p.resolve() == (paths.ROOT / DEFAULT_DIR).resolve()


def prepare(data_dir: str = DEFAULT_DIR, regenerate: bool = True,
            seed: int = synthetic.DEFAULT_SEED, out=None) -> tuple[Path, list[Path], str]:
    """Decide where to read from and, for the reconstruction only, regenerate it first.

    * ``data_dir`` is the default ``data/thermal``, ``regenerate`` is true and ``seed`` is the
      committed one: the generator writes into it (resolved like an output folder, so under the
      tests it goes to ``.test-output/data/thermal``), a file only when its bytes change.
    * the same with another ``seed``: the reconstruction goes to ``<out>/reconstruction`` (the
      run's own output folder), never over the committed data.
    * any other ``data_dir`` is the reader's own measurements: read, **never written**.

    Returns (folder to read, files that changed, a sentence saying what happened).
    """
    if not is_default_dir(data_dir):
        p = Path(data_dir)
        p = p if p.is_absolute() else paths.ROOT / p
        what = (f"{data_dir}: your measurements, read only"
                + (" (regenerate_data applies to the reconstruction only)" if regenerate else ""))
        return p, [], what
    if not regenerate:
        return paths.ROOT / DEFAULT_DIR, [], f"{DEFAULT_DIR}: committed reconstruction, as stored"
    if seed == synthetic.DEFAULT_SEED:
        folder = paths.resolve_output(DEFAULT_DIR)
    elif out is None:
        raise ValueError(f"a reconstruction with seed {seed} (not the committed "
                         f"{synthetic.DEFAULT_SEED}) is written into the run's output folder: "
                         f"pass out=")
    else:
        folder = Path(out) / "reconstruction"
    folder.mkdir(parents=True, exist_ok=True)
    changed = thermal.write_measurements(reconstruct(seed), folder,
                                         save=reproduction.save_table)
    where = (folder.relative_to(paths.ROOT) if folder.is_relative_to(paths.ROOT)
             else f"<output_dir>/{folder.name}" if out is not None and folder.parent == Path(out)
             else folder)
    what = (f"{where}: reconstruction regenerated with seed {seed}: "
            + (f"{len(changed)} file(s) rewritten ({', '.join(p.name for p in changed)})"
               if changed else "every file byte-identical, nothing rewritten"))
    return folder, changed, what
