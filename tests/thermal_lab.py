"""A thermal-error dataset from the tests' own physical model (not the paper's reconstruction).

A ball screw heated by its moving nut: one-dimensional conduction along the screw (explicit
finite differences, 1 mm/s-stable steps), a bearing and a motor as first-order nodes, a bed that
follows the bearing slowly, and workshop air that drifts as a sine. The positioning error is the
integrated thermal expansion of the screw from its fixed bearing to each target (so it is not a
straight line in the position), plus a scale error that follows the bed, plus interferometer
noise; the laser is zeroed once per experiment at the first target of the first measurement.
Sensors read the bearing, three points of the screw, the motor (twice, different gains), the
bed, the air and a mix of bed and bearing: nothing like the reconstruction's sensor groups.

``write`` saves the three CSV files of the schema of ``data/thermal/README.md`` and returns the
noise-free error of every measurement (the truth a prediction is judged against).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

ALPHA_STEEL = 11.5e-6      # 1/K
#: The dataset conftest.py runs notebook 04 on.
NOTEBOOK_RUN = dict(experiments=(11, 12, 13, 14, 15), n_measurements=19,
                    positions_mm=[40.0 * i for i in range(25)], seed=11)
SCREW_MM = 1200.0


def simulate(*, experiments=(1, 2, 3, 4, 5), n_measurements=10, positions_mm=None,
             duration_min=200.0, seed=7, noise_um=0.1, sensor_noise_c=0.01):
    """Temperatures (n, 9), noise-free errors (n, P), noisy errors, times, feeds, index."""
    rng = np.random.default_rng(seed)
    positions = (np.arange(0.0, 601.0, 50.0) if positions_mm is None
                 else np.asarray(positions_mm, float))
    x = np.linspace(0.0, SCREW_MM, 121)
    dx = x[1] - x[0]
    lo, span = positions.min(), np.ptp(positions)
    times = np.round(np.linspace(0.0, duration_min, n_measurements), 1)
    feeds = {e: int(2000 + 1000 * (i % 5)) for i, e in enumerate(experiments)}
    temps, truth, index = [], [], []
    for i, e in enumerate(experiments):
        feed = feeds[e]
        screw = np.zeros_like(x)
        motor = bearing = bed = 0.0
        amb0 = 20.0 + rng.uniform(-1.0, 1.0)
        t_prev, zero = 0.0, None
        for m, tm in enumerate(times, 1):
            steps = int(np.ceil((tm - t_prev) / 0.25))
            for k in range(steps):
                h = (tm - t_prev) / steps
                t = t_prev + (k + 1) * h
                nut = lo + span * 0.5 * (1 + np.sin(2 * np.pi * t / 3.0))     # sweeping the travel
                q = (feed / 6000.0) ** 1.3 * 0.08 * np.exp(-((x - nut) / 60.0) ** 2)
                lap = np.empty_like(screw)
                lap[1:-1] = (screw[2:] - 2 * screw[1:-1] + screw[:-2]) / dx**2
                lap[0] = 2 * (screw[1] - screw[0]) / dx**2
                lap[-1] = 2 * (screw[-2] - screw[-1]) / dx**2
                screw = screw + h * (30.0 * lap + q - 0.012 * screw)
                motor += h * ((feed / 6000.0) * 0.25 - motor / 25.0)
                bearing += h * (0.01 * motor + 0.05 * screw[0] - bearing / 60.0)
                bed += h * (0.3 * bearing - bed) / 120.0
            t_prev = tm
            amb = amb0 + 1.2 * np.sin(2 * np.pi * tm / 300.0 + i)
            read = np.array([amb + bearing, amb + np.interp(100, x, screw),
                             amb + np.interp(400, x, screw), amb + np.interp(700, x, screw),
                             amb + 8 * motor, amb + 11 * motor, amb + bed, amb,
                             amb + 0.5 * bed + 0.2 * bearing])
            temps.append(read + rng.normal(0.0, sensor_noise_c, read.size))
            grid = np.linspace(0.0, 1.0, 64)
            growth = np.array([ALPHA_STEEL * 1e3 * np.trapezoid(
                np.interp(p * grid, x, screw), p * grid) for p in positions - lo + 50.0])
            err = growth + 4e-3 * bed * (positions - lo) / 100.0
            if zero is None:
                zero = err[0]
            truth.append(err - zero)
            index.append((e, m, tm))
    truth = np.array(truth)
    noisy = truth + rng.normal(0.0, noise_um, truth.shape)
    first = np.array([m == 1 for _, m, _ in index])
    noisy[first, 0] = 0.0                       # the laser zeroed there: reads exactly 0
    return dict(temperatures=np.array(temps), truth=truth, errors=noisy, index=index,
                feeds=feeds, positions=positions)


SENSORS = ["bearing", "screw_100", "screw_400", "screw_700", "motor_housing", "motor_winding",
           "bed", "air", "column"]


def write(folder, *, sensors=SENSORS, crlf=False, **kwargs) -> dict:
    """Simulate and write ``temperatures.csv``, ``errors.csv`` and ``experiments.csv``."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    sim = simulate(**kwargs)
    nl = "\r\n" if crlf else "\n"
    head = "experiment,measurement,time_min," + ",".join(f"{s}_degC" for s in sensors)
    rows = [head] + [f"{e},{m},{t:g}," + ",".join(f"{v:.2f}" for v in temps[:len(sensors)])
                     for (e, m, t), temps in zip(sim["index"], sim["temperatures"], strict=True)]
    (folder / "temperatures.csv").write_bytes((nl.join(rows) + nl).encode())
    rows = ["experiment,measurement,position_mm,error_um"] + [
        f"{e},{m},{p:g},{v:.3f}"
        for (e, m, _), errs in zip(sim["index"], sim["errors"], strict=True)
        for p, v in zip(sim["positions"], errs, strict=True)]
    (folder / "errors.csv").write_bytes((nl.join(rows) + nl).encode())
    (folder / "experiments.csv").write_text("experiment,feed_mm_per_min\n" + "".join(
        f"{e},{f}\n" for e, f in sim["feeds"].items()))
    return sim
