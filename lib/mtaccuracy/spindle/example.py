"""The shipped simulated four-probe measurement (``data/spindle``) and its truth.

:func:`example_measurement` makes it (a known profile and a known motion, read by four probes at
off-grid angles), :func:`write_example` writes it with its record (the setup and each file's
SHA-256), and :func:`match_example` recognises it by content, so that a notebook compares with
the truth only when the file *is* the example.  Everything here is SIMULATED, not measured.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pandas as pd

from .probedata import probe_column
from .probefile import _csv_bytes
from .separation import TWO_PI

__all__ = ["example_measurement", "write_example", "match_example", "EXAMPLE_SETUP",
           "EXAMPLE_FILES"]

#: The shipped simulated example (:func:`write_example`) and its record.
EXAMPLE_FILES = {"probes": "example_probes.csv", "truth": "example_truth.csv",
                 "record": "provenance.json"}


#: How the example is made (recorded in its provenance.json).
EXAMPLE_SETUP = dict(seed=2107, n_samples=256, n_revolutions=8,
                     angles_deg=(0.0, 38.5, 97.0, 221.0), lobes=3, lobe_um=0.35,
                     form_harmonics=(2, 40), form_um=0.25, centring_um=1.8,
                     sync_um=((2, 0.12, 0.08), (3, 0.05, 0.04), (5, 0.03, 0.02),
                              (7, 0.015, 0.02)),
                     async_harmonics=(1, 30), async_um=0.02, noise_um=0.005,
                     offsets_um=(4.2, -1.7, 6.3, -3.1), decimals=4)


def example_measurement(setup: dict | None = None):
    """A simulated four-probe measurement at off-grid angles and the truth it was built from.

    The artefact: a three-lobed form, random harmonics 2..40 (amplitudes ~ 1/k, random phases)
    and a centring eccentricity (a first harmonic).  The spindle: a synchronous radial motion
    of harmonics 2, 3, 5, 7 (an ellipse and lobes, in x and y), plus an asynchronous motion new
    every revolution (random harmonics 1..30 of each axis, rms ``async_um``).  Each probe reads
    Eq. 7 at its off-grid angle, computed from the harmonics (no interpolation), plus its zero
    offset and white noise (``noise_um``), rounded to ``decimals``.  Every draw comes from
    ``numpy.random.default_rng(seed)``.

    Parameters
    ----------
    setup : dict, optional
        Overrides of :data:`EXAMPLE_SETUP`.

    Returns
    -------
    probes : DataFrame
        The probe file's table (columns ``revolution``, ``angle_deg``, ``probe_<angle>_um``).
    truth : DataFrame
        ``revolution``, ``angle_deg``, ``profile_um`` (the artefact at the sample angle, zero
        mean), ``x_um``, ``y_um`` (the spindle's motion at that sample).
    """
    s = {**EXAMPLE_SETUP, **(setup or {})}
    rng = np.random.default_rng(s["seed"])
    n, r = s["n_samples"], s["n_revolutions"]
    phi = np.deg2rad(np.asarray(s["angles_deg"]))
    theta = TWO_PI * np.arange(n) / n

    k0, k1 = s["form_harmonics"]
    ks = np.arange(k0, k1 + 1)
    amp = s["form_um"] * rng.standard_normal(len(ks)) / ks
    ph = rng.uniform(0, TWO_PI, len(ks))
    lobe_phase, ecc_phase = rng.uniform(0, TWO_PI, 2)

    def form(u):                                   # the artefact at its own angles u (..., )
        u = np.asarray(u)[..., None]
        return ((amp * np.cos(ks * u + ph)).sum(-1) + s["lobe_um"]
                * np.cos(s["lobes"] * u[..., 0] + lobe_phase)
                + s["centring_um"] * np.cos(u[..., 0] - ecc_phase))

    sx = sum(a * np.cos(k * theta + 0.7 * k) for k, a, _ in s["sync_um"])
    sy = sum(b * np.sin(k * theta + 0.3 * k) for k, _, b in s["sync_um"])
    a0, a1 = s["async_harmonics"]
    ka = np.arange(a0, a1 + 1)
    coef = rng.standard_normal((r, 2, 2, len(ka))) * s["async_um"] / np.sqrt(len(ka))
    basis = np.stack([np.cos(ka[:, None] * theta), np.sin(ka[:, None] * theta)])  # (2, K, N)
    asyn = np.einsum("racK,cKn->ran", coef, basis)                    # (R, 2, N)
    x, y = sx + asyn[:, 0], sy + asyn[:, 1]                           # (R, N)

    reading = (form(theta[None, :] + phi[:, None])[None]                # (1, L, N)
               + x[:, None, :] * np.cos(phi)[:, None] + y[:, None, :] * np.sin(phi)[:, None]
               + np.asarray(s["offsets_um"])[None, :, None]
               + s["noise_um"] * rng.standard_normal((r, len(phi), n)))
    deg = np.rad2deg(theta)
    table = pd.DataFrame({"revolution": np.repeat(np.arange(1, r + 1), n),
                          "angle_deg": np.tile(deg, r)})
    for j, a in enumerate(s["angles_deg"]):
        table[probe_column(a)] = np.round(reading[:, j].ravel(), s["decimals"]) + 0.0
    prof = form(theta)
    truth = pd.DataFrame({"revolution": table.revolution, "angle_deg": table.angle_deg,
                          "profile_um": np.tile(prof - prof.mean(), r),
                          "x_um": x.ravel(), "y_um": y.ravel()})
    return table, truth


def write_example(folder) -> dict:
    """Write the shipped example and its record into ``folder``.

    The files ``example_probes.csv``, ``example_truth.csv`` and ``provenance.json`` (the setup,
    the generator and each file's SHA-256).

    Parameters
    ----------
    folder : str or Path
        Where (``data/spindle`` in the repository); created if missing.

    Returns
    -------
    dict
        The record written.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    probes, truth = example_measurement()
    data = {"probes": _csv_bytes(probes, EXAMPLE_SETUP["decimals"]),
            "truth": _csv_bytes(truth, 6)}
    for key, blob in data.items():
        (folder / EXAMPLE_FILES[key]).write_bytes(blob)
    record = {"what": "SIMULATED four-probe spindle measurement (not measured data)",
              "generator": "mtaccuracy.spindle.example.write_example (example_measurement with "
                           "EXAMPLE_SETUP)",
              "setup": {k: list(v) if isinstance(v, tuple) else v
                        for k, v in EXAMPLE_SETUP.items()},
              "sha256": {EXAMPLE_FILES[k]: hashlib.sha256(b).hexdigest()
                         for k, b in data.items()}}
    text = json.dumps(record, indent=1, sort_keys=True) + "\n"
    (folder / EXAMPLE_FILES["record"]).write_text(text, encoding="utf-8")
    return record


def match_example(path, folder):
    """The shipped example's truth when the file at ``path`` has its content (SHA-256), else None.

    Whatever the file's name or place.

    Parameters
    ----------
    path : str or Path
        A probe file.
    folder : str or Path
        The folder of the example and its ``provenance.json`` (``data/spindle``).

    Returns
    -------
    DataFrame or None
        The truth table of :func:`example_measurement` (read from ``example_truth.csv``, which
        must match its recorded hash too), or None.
    """
    folder = Path(folder)
    record_path = folder / EXAMPLE_FILES["record"]
    if not record_path.is_file():
        return None
    record = json.loads(record_path.read_text(encoding="utf-8"))
    want = record.get("sha256", {})
    if hashlib.sha256(Path(path).read_bytes()).hexdigest() != want.get(EXAMPLE_FILES["probes"]):
        return None
    truth = folder / EXAMPLE_FILES["truth"]
    if not truth.is_file() or hashlib.sha256(truth.read_bytes()).hexdigest() \
            != want.get(EXAMPLE_FILES["truth"]):
        raise ValueError(f"{truth}: missing or not the truth recorded in {record_path} (its "
                         f"SHA-256 differs); regenerate both with example.write_example")
    return pd.read_csv(truth)
