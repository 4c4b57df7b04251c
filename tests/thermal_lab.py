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


# ---------------------------------------------------------------- a lab export (issue: 04)
#
# The same machine seen as a lab exports it: a temperature logger sampling every 30 s with
# timestamps and headers ``CH1 Motor X [°C]``, and the laser software's file with one column per
# measurement run headed by the run's timestamp.  The temperatures are closed-form first-order
# nodes, so that their value at any instant (a run's timestamp) is known exactly, and so is the
# bound of their second derivative that limits linear interpolation.

#: Logger channels: name, time constant (min), steady rise at 6000 mm/min (degC).
CHANNELS = [("CH1 Motor X", 15.0, 8.0), ("CH2 Bearing", 40.0, 4.0), ("CH3 Nut", 25.0, 5.0),
            ("CH4 Bed", 120.0, 1.5), ("CH5 Air", None, 0.0), ("CH6 Column", 80.0, 2.0)]
AIR_AMPLITUDE_C, AIR_PERIOD_MIN = 0.8, 300.0
LOGGER_STEP_MIN = 0.5                  # one sample per 30 s
RUN_MIN = np.arange(8) * 20.0          # runs every 20 min, from the first
RUN_OFFSET_S = 13                      # runs fall between logger samples
LAB_STEMS = {1: "1", 2: "exp2", 3: "E03", 4: "run_4"}
LAB_FEEDS = {1: 2000.0, 2: 4000.0, 3: 6000.0, 4: 5000.0}
LAB_POSITIONS = np.arange(0.0, 521.0, 40.0)
#: Blank or NaN cells: (experiment, channel, first sample, samples).  Short: 2 samples (the
#: readings around them 1.5 min apart; in experiment 1 around the run at 20 min, which lies
#: between samples 50 and 51); long: 20 samples (10.5 min): the channel is dropped.
LAB_GAPS = [(1, "CH3 Nut", 50, 2), (3, "CH3 Nut", 200, 2), (2, "CH6 Column", 100, 20)]


def lab_temperature(t_min, experiment):
    """Every channel's temperature at ``t_min`` (min after the first run), closed form (n, 6)."""
    t = np.atleast_1d(np.asarray(t_min, float))[:, None]
    f = LAB_FEEDS[experiment] / 6000.0
    air = 20.0 + 0.3 * experiment + AIR_AMPLITUDE_C * np.sin(2 * np.pi * t / AIR_PERIOD_MIN
                                                              + experiment)
    cols = [air + rise * f * (1 - np.exp(-(t + 5.0) / tau)) if tau else air
            for _, tau, rise in CHANNELS]
    return np.concatenate(cols, axis=1)


def lab_curvature_bound() -> float:
    """max |d2T/dt2| over every channel and time (degC/min2): rise / tau**2 plus the air's."""
    air = AIR_AMPLITUDE_C * (2 * np.pi / AIR_PERIOD_MIN) ** 2
    return max(rise / tau**2 for _, tau, rise in CHANNELS if tau) + air


def lab_errors(temps, experiment, rng):
    """Errors (um) of the runs at ``LAB_POSITIONS`` from the temperatures (runs, 6): a slope
    from the bearing and nut, an intercept from the motor's rise, a pitch shape, noise; zeroed
    at the first target of the first run."""
    x = LAB_POSITIONS - LAB_POSITIONS[0]
    rise = temps - temps[0]
    k = 3.0 * rise[:, 1] + 1.5 * (temps[:, 2] - temps[:, 4])          # um/m
    b = 0.6 * rise[:, 0] - 0.4 * rise[:, 3]                           # um
    pitch = 0.4 * np.sin(2 * np.pi * x / 130.0)
    err = k[:, None] * x / 1000.0 + b[:, None] + pitch + rng.normal(0.0, 0.05, (len(temps),
                                                                                 len(x)))
    return err - err[0, 0]


def _number(v, sep):
    text = f"{v:.2f}"
    return text.replace(".", ",") if sep == ";" else text


def write_lab_export(folder, *, semicolon=(2,), gaps=LAB_GAPS, seed=5) -> dict:
    """Write a lab export of four experiments; return the truth.

    Experiment files are named by ``LAB_STEMS``; the experiments in ``semicolon`` are written
    semicolon-separated with decimal commas.  Returns ``{"start": {e: datetime64 of the first
    run}, "runs": {e: run minutes}, "temps": {e: (8, 6) exact temperatures at the runs},
    "errors": {e: (8, P) errors as written}, "lines": {(e, channel, first sample): line}}``.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    out = {"start": {}, "runs": {}, "temps": {}, "errors": {}, "lines": {}}
    for e, stem in LAB_STEMS.items():
        sep = ";" if e in semicolon else ","
        start = np.datetime64(f"2024-03-{10 + e:02d}T08:00:00") + np.timedelta64(RUN_OFFSET_S,
                                                                                 "s")
        t_log = np.arange(-5.0, RUN_MIN[-1] + 5.0 + 1e-9, LOGGER_STEP_MIN) - RUN_OFFSET_S / 60
        stamps = start + (t_log * 60).round().astype("timedelta64[s]")
        temps = lab_temperature(t_log, e)
        cells = [[_number(v, sep) for v in row] for row in temps]
        for g_e, channel, first, n in gaps:
            if g_e == e:
                j = [c for c, _, _ in CHANNELS].index(channel)
                for i in range(first, first + n):
                    cells[i][j] = "NaN" if (i - first) % 2 else ""
                out["lines"][(e, channel, first)] = first + 2       # the header is line 1
        head = sep.join(["timestamp", *(f"{c} [°C]" for c, _, _ in CHANNELS)])
        rows = [head] + [sep.join([str(s), *row]) for s, row in zip(stamps, cells, strict=True)]
        (folder / f"{stem}_temperatures.csv").write_text("\n".join(rows) + "\n",
                                                         encoding="utf-8")
        at = lab_temperature(RUN_MIN, e)
        errors = np.round(lab_errors(at, e, rng), 3) + 0.0
        runs = [str(start + np.timedelta64(int(m * 60), "s")) for m in RUN_MIN]
        # the laser software lists the runs newest first: the reader orders them by time
        order = np.arange(len(runs))[::-1]
        rows = [sep.join(["target_mm", *(runs[i] for i in order)])] + [
            sep.join([f"{p:g}", *(f"{errors[i, j]:.3f}".replace(".", "," if sep == ";" else ".")
                                  for i in order)]) for j, p in enumerate(LAB_POSITIONS)]
        (folder / f"{stem}_laser.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
        out["start"][e], out["runs"][e], out["temps"][e], out["errors"][e] = \
            start, RUN_MIN.copy(), at, errors
    return out


def write_lab_as_schema(folder, truth, *, channels=None) -> None:
    """The same runs in the schema's layout (temperatures at the runs to 0.01 degC)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    names = [c for c, _, _ in CHANNELS]
    keep = [names.index(c) for c in (channels or names)]
    rows = ["experiment,measurement,time_min," + ",".join(f"{names[j]}_degC" for j in keep)]
    erows = ["experiment,measurement,position_mm,error_um"]
    for e in LAB_STEMS:
        for m, (t, temps, errs) in enumerate(zip(truth["runs"][e], truth["temps"][e],
                                                 truth["errors"][e], strict=True), 1):
            rows.append(f"{e},{m},{t:g}," + ",".join(f"{temps[j]:.2f}" for j in keep))
            erows += [f"{e},{m},{p:g},{v:.3f}" for p, v in zip(LAB_POSITIONS, errs, strict=True)]
    (folder / "temperatures.csv").write_text("\n".join(rows) + "\n")
    (folder / "errors.csv").write_text("\n".join(erows) + "\n")
