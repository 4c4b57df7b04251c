"""Thermal data as a lab exports them (notebook 04's ``data_dir``), and what every thermal file
reader refuses before reading a byte.

The data come from the tests' own model (``tests/thermal_lab.py``, ``write_lab_export``): closed-
form first-order thermal nodes logged every 30 s with timestamps and ``CH1 Motor X [°C]``
headers, runs between logger samples, errors from the temperatures; one experiment written
semicolon-separated with decimal commas, a flaky sensor with 2-sample gaps (one around a run),
another with a 20-sample gap.
"""

import os
import re
import shutil
import warnings

import numpy as np
import pytest
import thermal_lab

from mtaccuracy import thermal

SCHEMA_FILES = ("temperatures.csv", "errors.csv", "experiments.csv")


def _read(folder):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        data = thermal.read_measurements(folder)
    return data, caught


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    folder = tmp_path_factory.mktemp("lab")
    truth = thermal_lab.write_lab_export(folder)
    data, caught = _read(folder)
    return folder, truth, data, caught


# ------------------------------------------------------------------ what the reader gives


def test_the_temperatures_at_each_run_are_the_models_within_the_interpolation_bound(lab):
    """Linear interpolation over h misses T by at most h**2 / 8 max|T''|; the logged values are
    rounded to 0.01 (0.005 each way, kept by a convex combination).  h is 0.5 min between
    samples, 1.5 min across a 2-sample gap: the bound with h = 1.5 holds for every run."""
    _, truth, data, _ = lab
    bound = 1.5**2 / 8 * thermal_lab.lab_curvature_bound() + 0.005
    names = [c for c, _, _ in thermal_lab.CHANNELS]
    assert data.sensors == names[:5]                       # CH6 dropped (its long gap)
    for e in thermal_lab.LAB_STEMS:
        got = data.subset(e).temperatures.to_numpy()
        want = truth["temps"][e][:, :5]
        assert np.abs(got - want).max() <= bound, (e, np.abs(got - want).max(), bound)
    # the run inside experiment 1's gap of CH3 (20 min) is one of them, and the bound is tight
    # enough to matter: a run read off the wrong sample (30 s away) would miss it
    d1 = data.subset(1)
    miss = abs(d1.temperatures["CH3 Nut"][1] - truth["temps"][1][1, 2])
    step = abs(np.diff(thermal_lab.lab_temperature([20.0, 20.5], 1)[:, 0]))[0]
    assert miss <= bound < step


def test_runs_are_numbered_by_time_and_the_errors_are_the_written_ones(lab):
    _, truth, data, _ = lab
    assert data.experiments == [1, 2, 3, 4]                 # 1, exp2, E03, run_4
    np.testing.assert_array_equal(data.positions_mm, thermal_lab.LAB_POSITIONS)
    for e in data.experiments:
        d = data.subset(e)
        np.testing.assert_array_equal(d.index.measurement, np.arange(1, 9))
        np.testing.assert_allclose(d.index.time_min, thermal_lab.RUN_MIN, atol=1e-12)
        np.testing.assert_array_equal(d.errors, truth["errors"][e])   # newest-first columns


def test_short_gaps_are_interpolated_and_named_a_long_one_drops_the_sensor(lab):
    folder, truth, data, caught = lab
    gaps = [str(w.message) for w in caught if w.category is thermal.InterpolatedGapWarning]
    dropped = [str(w.message) for w in caught if w.category is thermal.DroppedSensorWarning]
    assert len(gaps) == 2 and len(dropped) == 1
    for e, stem, first in ((1, "1", 50), (3, "E03", 200)):
        line = truth["lines"][(e, "CH3 Nut", first)]
        assert any(f"{stem}_temperatures.csv: sensor 'CH3 Nut', experiment {e}: 2 missing "
                   f"sample(s) on lines {line}-{line + 1} interpolated" in g for g in gaps), gaps
    line = truth["lines"][(2, "CH6 Column", 100)]
    assert re.search(rf"exp2_temperatures.csv: sensor 'CH6 Column' .*experiment 2: a gap of 20 "
                     rf"missing sample\(s\) on lines {line}-{line + 19} .*10.5 min apart",
                     dropped[0]), dropped
    assert set(data.filled) == {"CH3 Nut"} and set(data.dropped) == {"CH6 Column"}
    assert not any(w.category is thermal.IgnoredColumnWarning for w in caught)


def test_the_pipeline_predicts_as_well_as_from_the_same_data_in_the_schema_layout(lab, tmp_path):
    """Notebook 04's split (train 1-3, test 4) on the lab export and on the same runs written in
    the schema's layout: the temperatures differ by at most the interpolation bound eps, so the
    decoupled MLR's predictions move by at most sum|beta| eps (about, with the refit): the
    held-out RMSEs agree within that."""
    _, truth, data, _ = lab
    thermal_lab.write_lab_as_schema(tmp_path, truth,
                                    channels=[c for c, _, _ in thermal_lab.CHANNELS][:5])
    schema, _ = _read(tmp_path)
    assert schema.sensors == data.sensors
    np.testing.assert_array_equal(schema.errors, data.errors)
    inputs = {"point": ["CH2 Bearing", "CH3 Nut", "CH1 Motor X"],
              "k": ["CH2 Bearing", "CH3 Nut", "CH5 Air"], "b": ["CH1 Motor X", "CH4 Bed"]}
    runs = [thermal.evaluate_split(d, train=[1, 2, 3], test=[4], kinds=("mlr",), sensors=inputs)
            for d in (data, schema)]
    eps = 1.5**2 / 8 * thermal_lab.lab_curvature_bound() + 0.01
    coef = thermal.eq9_table(runs[1].models["decoupled_mlr"], inputs)
    slope = coef[coef.term != "intercept"].coefficient.abs()
    span_m = np.ptp(data.positions_mm) / 1000
    bound = 2 * eps * (slope[coef.target.str.startswith("k ")].sum() * span_m
                       + 2 * slope[coef.target.str.startswith("b ")].sum())
    rmse = [r.table.set_index(["method", "target"]).rmse for r in runs]
    key = ("decoupled_mlr", "thermal positioning error")
    assert abs(rmse[0][key] - rmse[1][key]) <= bound, (rmse[0][key], rmse[1][key], bound)
    assert rmse[0][key] < 0.2 * np.abs(data.subset(4).errors).max()   # and it predicts


def test_a_schema_folder_may_give_timestamps_and_bracketed_celsius_headers(tmp_path):
    thermal_lab.write(tmp_path, experiments=(1, 2, 3), n_measurements=4)
    text = (tmp_path / "temperatures.csv").read_text().splitlines()
    head = text[0].replace("time_min", "timestamp").replace("bearing_degC", "bearing [°C]")
    rows = []
    for line in text[1:]:
        e, m, t, rest = line.split(",", 3)
        stamp = np.datetime64(f"2024-05-0{e}T09:00") + np.timedelta64(int(float(t) * 60), "s")
        rows.append(f"{e},{m},{stamp},{rest}")
    (tmp_path / "temperatures.csv").write_text("\n".join([head, *rows[::-1]]) + "\n")
    data, _ = _read(tmp_path)
    ref = thermal_lab.simulate(experiments=(1, 2, 3), n_measurements=4)
    np.testing.assert_allclose(data.index.time_min, [t for _, _, t in ref["index"]], atol=1e-9)
    assert data.sensors[0] == "bearing"


# ------------------------------------------------------------------ refused, with the fix


def _copy(lab, tmp_path):
    folder = tmp_path / "copy"
    shutil.copytree(lab[0], folder)
    return folder


@pytest.mark.parametrize("change, message", [
    (lambda f: (f / "temperatures.csv").write_text("experiment\n"),
     r"holds both the schema's file\(s\) \['temperatures.csv'\] and a lab export's .*keep one "
     r"layout per folder"),
    (lambda f: ((f / "exp01_temperatures.csv").write_bytes((f / "1_temperatures.csv").read_bytes()),
                (f / "exp01_laser.csv").write_bytes((f / "1_laser.csv").read_bytes())),
     r"'1' and 'exp01' both name experiment 1; give every experiment its own number"),
    (lambda f: ((f / "run_4_temperatures.csv").rename(f / "warmup_temperatures.csv"),
                (f / "run_4_laser.csv").rename(f / "warmup_laser.csv")),
     r"warmup_temperatures.csv: 'warmup': cannot tell its experiment number; name each pair "
     r"<experiment>_temperatures.csv and <experiment>_laser.csv"),
    (lambda f: (f / "E03_laser.csv").unlink(),
     r"\['E03_temperatures.csv'\] without its partner"),
    (lambda f: ((f / "12345678901234567890123456_temperatures.csv").write_text("x"),
                (f / "12345678901234567890123456_laser.csv").write_text("x")),
     r"'12345678901234567890123456': experiment number 12345678901234567890123456 is too large"),
])
def test_a_lab_export_that_cannot_be_told_apart_is_refused(lab, tmp_path, change, message):
    folder = _copy(lab, tmp_path)
    change(folder)
    with pytest.raises(thermal.DataFormatError, match=message):
        thermal.read_measurements(folder)


def test_a_folder_with_neither_layout_is_refused(tmp_path):
    (tmp_path / "notes.txt").write_text("")
    with pytest.raises(thermal.DataFormatError, match=r"holds neither the schema's "
                       r"temperatures.csv and errors.csv nor a lab export .*found \['notes.txt'\]"):
        thermal.read_measurements(tmp_path)


def _edit(path, old, new):
    text = path.read_text(encoding="utf-8")
    assert old in text
    path.write_text(text.replace(old, new, 1), encoding="utf-8")


def test_a_run_outside_the_logged_span_is_refused_naming_it(lab, tmp_path):
    folder = _copy(lab, tmp_path)
    _edit(folder / "run_4_laser.csv", "2024-03-14T10:20:13", "2024-03-14T11:20:13")
    with pytest.raises(thermal.DataFormatError, match=r"run_4_laser.csv: run "
                       r"'2024-03-14T11:20:13' lies outside the logged span of "
                       r"run_4_temperatures.csv"):
        thermal.read_measurements(folder)


def test_a_header_that_is_no_timestamp_and_text_in_a_logger_cell_are_refused(lab, tmp_path):
    folder = _copy(lab, tmp_path)
    _edit(folder / "1_laser.csv", "2024-03-11T08:20:13", "run 2")
    with pytest.raises(thermal.DataFormatError, match=r"1_laser.csv: 'run 2' \(the header of "
                       r"column 8; head every run's column with its ISO 8601 timestamp\) is not "
                       r"an ISO 8601 timestamp"):
        thermal.read_measurements(folder)
    folder = _copy(lab, tmp_path / "b")
    path = folder / "E03_temperatures.csv"
    lines = path.read_text(encoding="utf-8").splitlines()
    lines[9] = re.sub(r",[\d.]+$", ",OL", lines[9])
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    with pytest.raises(thermal.DataFormatError, match=r"column 'CH6 Column \[°C\]' holds 'OL', "
                       r"not a number, on line\(s\) \[10\]"):
        thermal.read_measurements(folder)


def test_timestamps_with_and_without_a_zone_are_refused(lab, tmp_path):
    folder = _copy(lab, tmp_path)
    _edit(folder / "1_laser.csv", "2024-03-11T08:20:13", "2024-03-11T08:20:13+01:00")
    with pytest.raises(thermal.DataFormatError, match=r"carries a time zone, the first "
                       r"\('2024-03-11T10:20:13'\) does not"):
        thermal.read_measurements(folder)


# ----------------------------------------- every thermal file: refused before a byte is read


def _schema(tmp_path):
    folder = tmp_path / "schema"
    thermal_lab.write(folder, experiments=(1, 2), n_measurements=3)
    return folder


def _replace(path, kind, tmp_path):
    path.unlink()
    if kind == "directory":
        path.mkdir()
    elif kind == "fifo":
        os.mkfifo(path)
    elif kind == "device":
        path.symlink_to("/dev/zero")
    return {"directory": "is a directory", "fifo": r"is a FIFO \(named pipe\)",
            "device": "is a character device"}[kind]


@pytest.mark.filterwarnings("ignore::UserWarning")   # the lab export read before experiments.csv
@pytest.mark.skipif(not hasattr(os, "mkfifo") or not os.path.exists("/dev/zero"),
                    reason="needs FIFOs and /dev/zero")
@pytest.mark.parametrize("kind", ["directory", "fifo", "device"])
@pytest.mark.parametrize("name", [*SCHEMA_FILES, "1_temperatures.csv", "exp2_laser.csv",
                                  "lab:experiments.csv"])
def test_every_thermal_file_that_is_not_a_regular_file_is_refused(lab, tmp_path, name, kind):
    """A FIFO would hang the reader, a link to /dev/zero fill its memory: refused at once."""
    if name in SCHEMA_FILES:
        folder = _schema(tmp_path)
    else:
        folder = _copy(lab, tmp_path)
        name = name.removeprefix("lab:")
        if name == "experiments.csv":
            (folder / name).write_text("experiment,feed_mm_per_min\n1,2000\n")
    what = _replace(folder / name, kind, tmp_path)
    with pytest.raises(thermal.DataFormatError,
                       match=rf"{re.escape(name)}: {what}, not a regular file"):
        thermal.read_measurements(folder)


@pytest.mark.parametrize("name", ["temperatures.csv", "errors.csv", "E03_laser.csv",
                                  "run_4_temperatures.csv"])
def test_every_thermal_file_over_its_size_is_refused(lab, tmp_path, monkeypatch, name):
    folder = _schema(tmp_path) if "_" not in name else _copy(lab, tmp_path)
    with open(folder / name, "a") as f:
        f.write("\n" * 100_000)                     # blank lines: the largest file, still valid
    size = (folder / name).stat().st_size
    monkeypatch.setattr(thermal.csvfile, "MAX_FILE_BYTES", size - 1)
    with pytest.raises(thermal.DataFormatError,
                       match=rf"{name}: {size} bytes; files up to {size - 1} bytes are read"):
        thermal.read_measurements(folder)


def test_a_26_digit_experiment_number_is_reported_as_written(tmp_path):
    folder = _schema(tmp_path)
    path = folder / "temperatures.csv"
    lines = path.read_text().splitlines()
    lines[3] = "12345678901234567890123456" + lines[3][1:]
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(thermal.DataFormatError, match=r"temperatures.csv: column 'experiment' "
                       r"holds 12345678901234567890123456 on line 4: too large; experiment "
                       r"numbers have at most 9 digits") as info:
        thermal.read_measurements(folder)
    assert "-9223372036854775808" not in str(info.value)


@pytest.mark.parametrize("name, line", [("errors.csv", 5), ("temperatures.csv", 3),
                                        ("exp2_laser.csv", 4)])
def test_a_field_over_the_csv_modules_limit_is_placed_on_its_line(lab, tmp_path, name, line):
    folder = _schema(tmp_path) if "_" not in name else _copy(lab, tmp_path)
    path = folder / name
    lines = path.read_text(encoding="utf-8").splitlines()
    lines[line - 1] += "x" * 140_000
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    with pytest.raises(thermal.DataFormatError, match=rf"{name}: line {line} is \d+ characters "
                       r"long; lines up to 131072 characters are read") as info:
        thermal.read_measurements(folder)
    assert "[-1]" not in str(info.value)


def test_a_quoted_field_over_the_limit_across_lines_names_a_line_not_minus_one(tmp_path):
    """Lines each under the limit, one quoted field over it: the scanner's own error is named
    with its line (pandas reads it; the message about the bad value cannot place it)."""
    folder = _schema(tmp_path)
    path = folder / "errors.csv"
    lines = path.read_text().splitlines()
    lines[2] = lines[2].rsplit(",", 1)[0] + ',"' + "\n".join(["y" * 60_000] * 3) + '"'
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(thermal.DataFormatError, match=r"errors.csv: line \d+: not a readable "
                       r"CSV: field larger than field limit") as info:
        thermal.read_measurements(folder)
    assert "[-1]" not in str(info.value)
