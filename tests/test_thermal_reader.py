"""The thermal measurement reader on a real lab's files (issue 22): any valid dataset of the
schema, the ways spreadsheets and loggers write CSV (BOM, CRLF, semicolons and decimal commas,
empty rows), and what the reader sets aside (dead sensors, extra columns) or refuses (wrong
units, duplicate names, an experiments.csv that does not match the data).

The data come from the small model below (not ``papers.xu2022_reconstruction``): each sensor
warms from an offset towards a steady rise with its own time constant, and the error line's
slope and intercept follow two of the rises, plus a pitch error; files are written by hand so
that every byte of their format is chosen here.
"""

import re
import warnings
from pathlib import Path

import numpy as np
import pytest

from mtaccuracy import thermal

# ------------------------------------------------------------------ the model and the writer


def model(experiments=(1, 2, 3), n_meas=6, sensors=("T1", "T2", "T3", "T4"),
          positions=tuple(range(0, 501, 100)), seed=0, first_meas=1):
    """A dataset as plain arrays: index rows, temperatures (n, S) at 0.01 degC, errors (n, P)
    at 0.001 um, feeds."""
    rng = np.random.default_rng(seed)
    positions = np.asarray(positions, dtype=float)
    S = len(sensors)
    tau = rng.uniform(20.0, 90.0, S)                 # min
    rise = rng.uniform(0.5, 6.0, S)                  # degC at the steady state
    rows, temps, errors, feeds = [], [], [], {}
    for i, e in enumerate(experiments):
        feeds[e] = 1000 * (i + 2)
        air = 20.0 + rng.uniform(-1.0, 1.0)
        offset = rng.uniform(-0.3, 0.3, S)
        times = np.round(np.arange(n_meas) * rng.uniform(8.0, 25.0)
                         + np.r_[0.0, rng.uniform(-2.0, 2.0, n_meas - 1)], 1)
        for j, tm in enumerate(times):
            t = air + offset + rise * (1 - np.exp(-tm / tau)) + rng.normal(0, 0.01, S)
            temps.append(t)
            rows.append((e, first_meas + j, tm))
        block = np.array(temps[-n_meas:])
        r = block - block[0]
        k = 3.0 * r[:, 0] - 1.5 * r[:, 1 % S]        # um/m
        b = -2.0 * r[:, 2 % S] + 0.4 * np.arange(n_meas)
        x = positions - positions[0]
        err = k[:, None] * x / 1000 + b[:, None] + 0.8 * np.sin(x / 37.0)[None, :]
        errors.append(err + rng.normal(0, 0.02, err.shape))
    return dict(rows=rows, sensors=list(sensors), temps=np.round(np.array(temps), 2),
                errors=np.round(np.vstack(errors), 3), positions=positions, feeds=feeds)


def tables(d, temp_columns=None):
    """The three tables as (header, rows of strings), decimal point."""
    cols = temp_columns or [f"{s}_degC" for s in d["sensors"]]
    t_rows = [[str(e), str(m), f"{tm:g}", *(f"{v:.2f}" for v in t)]
              for (e, m, tm), t in zip(d["rows"], d["temps"], strict=True)]
    e_rows = [[str(e), str(m), f"{p:g}", f"{v:.3f}"]
              for (e, m, _), err in zip(d["rows"], d["errors"], strict=True)
              for p, v in zip(d["positions"], err, strict=True)]
    x_rows = [[str(e), str(f)] for e, f in d["feeds"].items()]
    return {"temperatures.csv": (["experiment", "measurement", "time_min", *cols], t_rows),
            "errors.csv": (["experiment", "measurement", "position_mm", "error_um"], e_rows),
            "experiments.csv": (["experiment", "feed_mm_per_min"], x_rows)}


def text_of(header, rows, sep=",", decimal=".", newline="\n", bom=False, quote_header=False,
            trailing_blank=0):
    """A CSV text as a lab's software might write it."""
    def cell(v):
        return v.replace(".", decimal) if re.fullmatch(r"-?\d+\.\d+", v) else v
    head = [f'"{h}"' if quote_header else h for h in header]
    lines = [sep.join(head)] + [sep.join(cell(v) for v in r) for r in rows]
    return ("\ufeff" if bom else "") + newline.join(lines) + newline + newline * trailing_blank


def write(folder: Path, d, files=None, **fmt) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    for name, (header, rows) in (files or tables(d)).items():
        (folder / name).write_bytes(text_of(header, rows, **fmt).encode("utf-8"))
    return folder


def read_quietly(folder):
    """Read, failing on any warning (a valid dataset sets nothing aside)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return thermal.read_measurements(folder)


def assert_matches(data, d):
    """The data read hold the model's numbers, sorted by experiment and measurement."""
    order = sorted(range(len(d["rows"])), key=lambda i: d["rows"][i][:2])
    rows = [d["rows"][i] for i in order]
    assert data.index.experiment.tolist() == [r[0] for r in rows]
    assert data.index.measurement.tolist() == [r[1] for r in rows]
    assert np.array_equal(data.index.time_min.to_numpy(), [r[2] for r in rows])
    assert data.sensors == d["sensors"]
    assert np.array_equal(data.temperatures.to_numpy(), d["temps"][order])
    assert np.array_equal(data.positions_mm, np.sort(d["positions"]))
    col = np.argsort(d["positions"], kind="stable")
    assert np.array_equal(data.errors, d["errors"][order][:, col])
    assert data.feeds == d["feeds"]


# ------------------------------------------------------------------ any valid dataset reads

LAB = dict(experiments=(11, 12, 13, 14, 15), n_meas=19,
           sensors=("Spindle_front_degC".removesuffix("_degC"), "S1", "motor housing",
                    "Bed-left", "nut.2", "Air", "X", "T_12b"),
           positions=np.linspace(-480.0, 480.0, 25), seed=3)


@pytest.mark.parametrize("kw", [
    LAB,
    dict(LAB, positions=np.linspace(0.0, 960.0, 25)),
    dict(LAB, positions=np.linspace(185.0, 1145.0, 25)),
    dict(experiments=(7,), n_meas=2, sensors=("a", "b", "c"), positions=(-3.5, 12.25), seed=1),
    dict(experiments=(0, 2, 5, 100), n_meas=4, first_meas=0, seed=2,
         positions=(960.0, 720.0, 480.0, 240.0, 0.0)),            # targets written downwards
], ids=["11-15x19x8x25 from -480", "0..960", "185..1145", "smallest", "odd numbers, descending"])
def test_any_valid_dataset_reads_the_models_numbers(tmp_path, kw):
    d = model(**kw)
    assert_matches(read_quietly(write(tmp_path, d)), d)


def test_rows_in_any_order_and_measurement_numbers_with_gaps(tmp_path):
    d = model(experiments=(3, 1, 2), n_meas=5, seed=4)
    d["rows"] = [(e, 10 * m, tm) for e, m, tm in d["rows"]]       # 10, 20, ... 50
    t = tables(d)
    rng = np.random.default_rng(0)
    for name in ("temperatures.csv", "errors.csv"):
        header, rows = t[name]
        t[name] = (header, [rows[i] for i in rng.permutation(len(rows))])
    assert_matches(read_quietly(write(tmp_path, d, files=t)), d)


FORMATS = {
    "bom": dict(bom=True),
    "crlf": dict(newline="\r\n"),
    "trailing empty lines": dict(trailing_blank=3),
    "quoted header": dict(quote_header=True),
    "bom, quoted header, crlf": dict(bom=True, quote_header=True, newline="\r\n"),
    "semicolon, decimal comma": dict(sep=";", decimal=","),
    "semicolon, decimal point": dict(sep=";"),
    "semicolon, decimal comma, bom, crlf, quoted": dict(sep=";", decimal=",", bom=True,
                                                        newline="\r\n", quote_header=True),
}


@pytest.mark.parametrize("fmt", FORMATS.values(), ids=FORMATS.keys())
def test_spreadsheet_formats_read_the_same_numbers(tmp_path, fmt):
    d = model(seed=5)
    assert_matches(read_quietly(write(tmp_path, d, **fmt)), d)


def test_a_semicolon_file_with_decimal_commas_and_points_mixed_reads(tmp_path):
    d = model(seed=6)
    write(tmp_path, d, sep=";", decimal=",")
    p = tmp_path / "errors.csv"
    lines = p.read_text().split("\n")
    lines[5] = lines[5].replace(",", ".")                          # one row with a point
    p.write_text("\n".join(lines))
    assert_matches(read_quietly(tmp_path), d)


def test_empty_spreadsheet_rows_are_skipped_and_lines_stay_right(tmp_path):
    """Rows of separators only (``;;;;``, a spreadsheet's empty rows) are skipped; a bad value
    after them is still named on its own line."""
    d = model(seed=7)
    write(tmp_path, d, sep=";", decimal=",")
    p = tmp_path / "temperatures.csv"
    lines = p.read_text().split("\n")
    lines[3:3] = [";;;;;;", "", ";  ;;;;;"]
    p.write_text("\n".join(lines) + ";;;;;;\n;;;;;;\n")
    assert_matches(read_quietly(tmp_path), d)
    lines = p.read_text().split("\n")
    assert lines[9].startswith("1;6;")
    lines[9] = lines[9].rsplit(";", 1)[0] + ";30,4x"
    p.write_text("\n".join(lines))
    with pytest.raises(thermal.DataFormatError,
                       match=r"temperatures.csv: column 'T4_degC' has a missing, NaN or "
                             r"non-numeric value \('30,4x'\) on line\(s\) \[10\]"):
        thermal.read_measurements(tmp_path)


def test_semicolon_file_messages_name_real_lines_and_the_files_own_text(tmp_path):
    d = model(seed=8)
    write(tmp_path, d, sep=";", decimal=",", newline="\r\n")
    p = tmp_path / "temperatures.csv"
    lines = p.read_text().splitlines()
    lines.insert(2, "")
    fields = lines[6].split(";")
    fields[4] = "250,5"                                            # T2, out of range
    lines[6] = ";".join(fields)
    p.write_text("\r\n".join(lines) + "\r\n")
    with pytest.raises(thermal.DataFormatError,
                       match=r"temperatures.csv: column 'T2_degC' has value\(s\) 250.5 degC on "
                             r"line\(s\) \[7\], outside the plausible range"):
        thermal.read_measurements(tmp_path)
    fields[4] = "1.234,5"                                          # thousands separator
    lines[6] = ";".join(fields)
    p.write_text("\r\n".join(lines) + "\r\n")
    with pytest.raises(thermal.DataFormatError,
                       match=r"column 'T2_degC' has a missing, NaN or non-numeric value "
                             r"\('1.234,5'\) on line\(s\) \[7\]$"):
        thermal.read_measurements(tmp_path)


@pytest.mark.parametrize("header, message", [
    ("experiment;measurement;time_min,T1_degC", r"the header \(line 2\) holds both ',' and ';'"),
    ("experiment\tmeasurement\ttime_min\tT1_degC",
     r"tab-separated \(the header, line 2, holds tabs and no ','\); save the file "
     r"comma-separated"),
])
def test_an_unclear_separator_is_refused_saying_so(tmp_path, header, message):
    d = model(seed=9)
    write(tmp_path, d)
    (tmp_path / "temperatures.csv").write_text(f"\n{header}\n1;1;0;20\n")
    with pytest.raises(thermal.DataFormatError, match="temperatures.csv: " + message):
        thermal.read_measurements(tmp_path)


def test_utf16_is_refused_saying_what_to_save(tmp_path):
    d = model(seed=9)
    write(tmp_path, d)
    p = tmp_path / "errors.csv"
    p.write_bytes(p.read_text().encode("utf-16"))
    with pytest.raises(thermal.DataFormatError,
                       match=r"errors.csv: UTF-16 text \(what Excel saves as 'Unicode Text'\); "
                             r"save the file as 'CSV UTF-8'"):
        thermal.read_measurements(tmp_path)


def test_decimal_commas_in_a_comma_file_are_named_as_the_likely_cause(tmp_path):
    d = model(seed=10)
    write(tmp_path, d)
    p = tmp_path / "temperatures.csv"
    header, *rows = p.read_text().splitlines()
    p.write_text("\n".join([header] + [r.replace(".", ",") for r in rows]) + "\n")
    with pytest.raises(thermal.DataFormatError,
                       match=r"temperatures.csv: line 2 has 11 fields, the header \(line 1\) has "
                             r"7; the first rows all have more fields than the header: decimal "
                             r"commas \(30,41\) in a comma-separated file\?"):
        thermal.read_measurements(tmp_path)
    rows[2] = re.sub(r",([^,]*)$", lambda m: f',"{m.group(1).replace(".", ",")}"', rows[2])
    p.write_text("\n".join([header] + rows) + "\n")
    with pytest.raises(thermal.DataFormatError,
                       match=r"column 'T4_degC' has a missing, NaN or non-numeric value "
                             r"\('\d+,\d+'\) on line\(s\) \[4\]; a decimal comma\? Write decimal "
                             r"points"):
        thermal.read_measurements(tmp_path)


# ------------------------------------------------------------------ dead sensors


def _with_sensor(d, name, values):
    """The model with one more sensor reading ``values`` (strings, one per row)."""
    t = tables(d)
    header, rows = t["temperatures.csv"]
    t["temperatures.csv"] = (header[:5] + [f"{name}_degC"] + header[5:],
                             [r[:5] + [v] + r[5:] for r, v in zip(rows, values, strict=True)])
    return t


def _dead(tmp_path, d, name, values, sep=","):
    write(tmp_path, d, files=_with_sensor(d, name, values), sep=sep,
          decimal="," if sep == ";" else ".")
    with pytest.warns(thermal.DroppedSensorWarning) as caught:
        data = thermal.read_measurements(tmp_path)
    assert_matches(data, d)                                        # the others, untouched
    assert list(data.dropped) == [name]
    return [str(w.message) for w in caught if w.category is thermal.DroppedSensorWarning], data


@pytest.mark.parametrize("values, why", [
    (lambda n, e: ["21.30"] * n, r"reads 21.3 degC in every measurement"),
    (lambda n, e: ["-999"] * n, r"reads -999 degC in every measurement"),   # a logger's code
    (lambda n, e: [f"{20 + 0.1 * (x % 7):.1f}" for x in e],
     r"reads one value through each experiment \(20.1 in experiment 1, 20.2 in experiment 2, "
     r"20.3 in experiment 3 degC\): it never changes within an experiment"),
    (lambda n, e: [""] * n, r"holds no reading \(every cell is empty\)"),
    (lambda n, e: ["NaN"] * n, r"holds no number \(every cell reads 'NaN'\)"),
])
def test_a_dead_sensor_is_dropped_with_a_warning_naming_file_sensor_and_value(tmp_path, values,
                                                                               why):
    d = model(seed=11)
    exps = [r[0] for r in d["rows"]]
    messages, data = _dead(tmp_path, d, "Dead", values(len(exps), exps))
    assert len(messages) == 1
    assert re.fullmatch(rf"{re.escape(str(tmp_path / 'temperatures.csv'))}: sensor 'Dead' "
                        rf"\(column 'Dead_degC'\) {why}: a dead or disconnected sensor carries "
                        rf"no information; dropped \(delete the column to silence this "
                        rf"warning\)", messages[0]), messages[0]
    assert re.fullmatch(rf"temperatures.csv, column 'Dead_degC': {why}", data.dropped["Dead"])
    assert "Dead" not in data.sensors and data.ignored_columns == {}


def test_a_dead_sensor_in_a_semicolon_file_names_its_value(tmp_path):
    d = model(seed=12)
    messages, _ = _dead(tmp_path, d, "Amb", ["19,80"] * len(d["rows"]), sep=";")
    assert "sensor 'Amb' (column 'Amb_degC') reads 19.8 degC in every measurement" in messages[0]


def test_a_coarse_sensor_steady_through_one_experiment_is_kept(tmp_path):
    """At 0.1 degC a steady sensor may read one value through a whole experiment; it is dead
    only if it never changes within any experiment."""
    d = model(seed=13)
    exps = [r[0] for r in d["rows"]]
    values = [("20.1" if e != 2 else f"{20.1 + 0.1 * (i % 2):.1f}") for i, e in enumerate(exps)]
    write(tmp_path, d, files=_with_sensor(d, "Coarse", values))
    data = read_quietly(tmp_path)
    assert data.sensors == ["T1", "T2", "Coarse", "T3", "T4"] and data.dropped == {}
    assert np.array_equal(data.temperatures.Coarse.to_numpy(), np.array(values, dtype=float))


def test_too_few_working_sensors_are_refused_naming_the_dead_ones(tmp_path):
    d = model(sensors=("A", "B", "C"), seed=14)
    t = tables(d)
    header, rows = t["temperatures.csv"]
    t["temperatures.csv"] = (header, [r[:4] + ["25.00"] + r[5:] for r in rows])
    write(tmp_path, d, files=t)
    with pytest.raises(thermal.DataFormatError,
                       match=r"temperatures.csv: 2 working sensor\(s\) \['A', 'C'\] once the dead "
                             r"ones are dropped \(B: reads 25 degC in every measurement\); at "
                             r"least 3 are needed"):
        thermal.read_measurements(tmp_path)


def test_a_sensor_with_some_cells_missing_is_still_refused(tmp_path):
    d = model(seed=15)
    values = ["21.00", "21.50"] * (len(d["rows"]) // 2)
    values[4] = ""
    write(tmp_path, d, files=_with_sensor(d, "Flaky", values))
    with pytest.raises(thermal.DataFormatError,
                       match=r"column 'Flaky_degC' has a missing, NaN or non-numeric value "
                             r"\(''\) on line\(s\) \[6\]"):
        thermal.read_measurements(tmp_path)


# ------------------------------------------------------------------ extra columns


def _add_columns(t, name, columns):
    """``columns``: {column: function(row index) -> text}, appended to file ``name``."""
    header, rows = t[name]
    t[name] = (header + list(columns),
               [r + [f(i) for f in columns.values()] for i, r in enumerate(rows)])
    return t


def _drop_column(t, name, k):
    """Column ``k`` (0-based) removed from file ``name``."""
    header, rows = t[name]
    t[name] = (header[:k] + header[k + 1:], [r[:k] + r[k + 1:] for r in rows])
    return t


def test_extra_columns_are_ignored_with_a_note(tmp_path):
    d = model(seed=16)
    t = tables(d)
    _add_columns(t, "temperatures.csv", {
        "spindle_speed_rpm": lambda i: str(1000 * (i % 4)), "feed_mm_per_min": lambda i: "2000",
        "note": lambda i: "warm-up" if i else "", "time_s": lambda i: str(60 * i),
        "table_angle_deg": lambda i: "90", "load [%]": lambda i: str(i % 50)})
    _add_columns(t, "errors.csv", {"direction": lambda i: "+", "note": lambda i: "ok"})
    _add_columns(t, "experiments.csv", {"operator": lambda i: "HB"})
    write(tmp_path, d, files=t)
    with pytest.warns(thermal.IgnoredColumnWarning) as caught:
        data = thermal.read_measurements(tmp_path)
    assert_matches(data, d)
    messages = sorted(str(w.message) for w in caught)
    assert len(messages) == 3
    assert messages[0] == (f"{tmp_path / 'errors.csv'}: column(s) ['direction', 'note'] "
                           f"ignored: not part of the schema, which reads experiment, "
                           f"measurement, position_mm, error_um (data/thermal/README.md)")
    assert messages[2].startswith(
        f"{tmp_path / 'temperatures.csv'}: column(s) ['spindle_speed_rpm', 'feed_mm_per_min', "
        f"'note', 'time_s', 'table_angle_deg', 'load [%]'] ignored: not part of the schema, "
        f"which reads experiment, measurement, time_min and the temperatures <sensor>_degC")
    assert "experiments.csv: column(s) ['operator'] ignored" in messages[1]
    def other(unit):
        return f"temperatures.csv: another quantity (its name ends in {unit!r}, not a " \
               f"temperature unit)"
    assert data.ignored_columns == {
        "spindle_speed_rpm": other("rpm"), "feed_mm_per_min": other("min"),
        "note": "temperatures.csv: no unit, text; errors.csv: not part of the schema",
        "time_s": other("s"), "table_angle_deg": other("deg"), "load [%]": other("%"),
        "direction": "errors.csv: not part of the schema",
        "operator": "experiments.csv: not part of the schema"}
    sub = data.subset([2])
    assert sub.ignored_columns == data.ignored_columns and sub.dropped == {}


def test_a_bidirectional_errors_file_is_refused_naming_the_ignored_column(tmp_path):
    d = model(seed=17)
    t = tables(d)
    header, rows = t["errors.csv"]
    t["errors.csv"] = (header + ["direction"],
                       [r + [s] for r in rows for s in ("forward", "backward")])
    write(tmp_path, d, files=t)
    with pytest.raises(thermal.DataFormatError,
                       match=r"errors.csv: experiment 1 measurement 1 lists position 0 mm twice "
                             r"\(lines \[2, 3\]\); the reader ignores column\(s\) \['direction'\]: "
                             r"it reads one error per target and measurement \(a bidirectional "
                             r"measurement: keep one direction, or the mean of both, per "
                             r"target\)"):
        thermal.read_measurements(tmp_path)


@pytest.mark.parametrize("column, message", [
    ("T5_K", r"temperatures must be in degrees Celsius, named <sensor>_degC \(found 'K'\); "
             r"convert the values to degrees Celsius .* and rename it 'T5_degC'; a column that "
             r"is not a temperature is ignored when its name ends in its own unit"),
    ("T5_degF", r"\(found 'degF'\); convert the values"),
    ("T5_F", r"\(found 'F'\); convert the values"),
    ("T5_kelvin", r"\(found 'kelvin'\); convert the values"),
    ("T5_C", r"\(found 'C'\); rename it 'T5_degC'"),
    ("T5_degc", r"\(found 'degc'\); rename it 'T5_degC'"),
    ("T5_deg_C", r"\(found 'C'\); rename it 'T5_degC'"),
    ("T5 [K]", r"\(found 'K'\); convert the values to degrees Celsius"),
    ("T5 (K)", r"\(found 'K'\); convert the values"),
    ("T5", r"temperatures must be in degrees Celsius, named <sensor>_degC \(found 'no unit'\); "
           r"a column of numbers needs its unit in its name"),
    ("T_5", r"\(found 'no unit'\)"),
])
def test_a_temperature_in_another_unit_or_without_one_is_refused(tmp_path, column, message):
    """The rule: a name ending in a temperature unit other than ``_degC`` (however spelled) is
    refused, as is a column of numbers whose name has no unit; any other unit is ignored."""
    d = model(seed=18)
    t = _add_columns(tables(d), "temperatures.csv", {column: lambda i: f"{25 + 0.1 * i:.2f}"})
    write(tmp_path, d, files=t)
    with pytest.raises(thermal.DataFormatError,
                       match=rf"temperatures.csv: column '{re.escape(column)}': .*{message}"):
        thermal.read_measurements(tmp_path)


def test_a_unit_column_beside_the_schemas_own_is_ignored_and_alone_is_refused(tmp_path):
    d = model(seed=19)
    t = _add_columns(tables(d), "errors.csv", {"error_mm": lambda i: "0.001"})
    write(tmp_path, d, files=t)
    with pytest.warns(thermal.IgnoredColumnWarning, match=r"column\(s\) \['error_mm'\] ignored"):
        assert_matches(thermal.read_measurements(tmp_path), d)
    _drop_column(t, "errors.csv", 3)
    write(tmp_path, d, files=t)
    with pytest.raises(thermal.DataFormatError,
                       match=r"errors.csv: column 'error_mm' gives error in 'mm'; the schema "
                             r"needs 'error_um'"):
        thermal.read_measurements(tmp_path)


def test_unnamed_columns(tmp_path):
    """A spreadsheet's trailing separators make an unnamed empty column: ignored; an unnamed
    column of numbers is refused."""
    d = model(seed=20)
    t = tables(d)
    for name, (header, rows) in t.items():
        t[name] = (header + [""], [r + [""] for r in rows])
    write(tmp_path, d, files=t, sep=";", decimal=",")
    with pytest.warns(thermal.IgnoredColumnWarning) as caught:
        data = thermal.read_measurements(tmp_path)
    assert_matches(data, d)
    assert [re.search(r"(\w+).csv: column\(s\) (.*) ignored", str(w.message)).groups()
            for w in caught] == [("temperatures", "['<unnamed column 8>']"),
                                 ("errors", "['<unnamed column 5>']"),
                                 ("experiments", "['<unnamed column 3>']")]
    assert data.ignored_columns["<unnamed column 8>"] == "temperatures.csv: no name, empty"
    _add_columns(t, "temperatures.csv", {"": lambda i: "3"})
    write(tmp_path, d, files=t)
    with pytest.raises(thermal.DataFormatError,
                       match=r"temperatures.csv: column 9 has no name in the header but holds "
                             r"numbers"):
        thermal.read_measurements(tmp_path)
    _drop_column(t, "temperatures.csv", 7)
    write(tmp_path, d, files=t)
    with pytest.raises(thermal.DataFormatError,
                       match=r"temperatures.csv: column 8 has no name in the header but holds "
                             r"numbers; name it"):
        thermal.read_measurements(tmp_path)


def test_a_column_name_in_the_wrong_case_is_named(tmp_path):
    d = model(seed=21)
    t = tables(d)
    header, rows = t["temperatures.csv"]
    t["temperatures.csv"] = (["experiment", "measurement", "Time_min", *header[3:]], rows)
    write(tmp_path, d, files=t)
    with pytest.raises(thermal.DataFormatError,
                       match=r"missing column\(s\) \['time_min'\]; .* \(names are "
                             r"case-sensitive: 'Time_min'\)"):
        thermal.read_measurements(tmp_path)


# ------------------------------------------------------------------ duplicate names


@pytest.mark.parametrize("rename, message", [
    ({6: "T1_degC"}, r"duplicate sensor name 'T1': column 'T1_degC' appears 2 times in the "
                     r"header \(line 1\), as columns 4, 7; every column needs its own name"),
    ({6: " T1_degC "}, r"duplicate sensor name 'T1': column 'T1_degC' appears 2 times"),
    ({6: "T1 _degC"}, r"duplicate sensor name 'T1': columns 'T1_degC' and 'T1 _degC'"),
    ({1: "experiment"}, r"duplicate column name 'experiment' appears 2 times in the header "
                        r"\(line 1\), as columns 1, 2"),
])
def test_duplicate_names_are_refused_as_such(tmp_path, rename, message):
    d = model(seed=22)
    t = tables(d)
    header, rows = t["temperatures.csv"]
    t["temperatures.csv"] = ([rename.get(i, h) for i, h in enumerate(header)], rows)
    write(tmp_path, d, files=t)
    with pytest.raises(thermal.DataFormatError, match="temperatures.csv: " + message):
        thermal.read_measurements(tmp_path)


def test_a_duplicate_sensor_in_a_quoted_semicolon_header_after_blank_lines(tmp_path):
    d = model(seed=22)
    t = tables(d)
    header, rows = t["temperatures.csv"]
    t["temperatures.csv"] = (header[:6] + ["T2_degC"], rows)
    write(tmp_path, d, files=t, sep=";", decimal=",", quote_header=True, bom=True)
    p = tmp_path / "temperatures.csv"
    p.write_text("\ufeff\n \n" + p.read_text(encoding="utf-8-sig"))
    with pytest.raises(thermal.DataFormatError,
                       match=r"duplicate sensor name 'T2': column 'T2_degC' appears 2 times in "
                             r"the header \(line 3\), as columns 5, 7"):
        thermal.read_measurements(tmp_path)


# ------------------------------------------------------------------ experiments.csv


@pytest.mark.parametrize("feeds, message", [
    ({1: 2000, 2: 3000, 3: 4000, 9: 5000},
     r"experiments.csv: lists experiment\(s\) \[9\] \(line\(s\) \[5\]\) that have no measurements "
     r"in temperatures.csv and errors.csv; list every experiment of the data once \(with its "
     r"feed\) and no other, or delete experiments.csv"),
    ({1: 2000, 3: 4000},
     r"experiments.csv: misses experiment\(s\) \[2\], which have measurements in "
     r"temperatures.csv and errors.csv; list every"),
    ({8: 1, 1: 2000, 7: 1},
     r"lists experiment\(s\) \[7, 8\] \(line\(s\) \[2, 4\]\) that have no measurements .* and "
     r"misses experiment\(s\) \[2, 3\]"),
])
def test_experiments_csv_must_list_exactly_the_experiments_of_the_data(tmp_path, feeds, message):
    d = model(seed=23)
    d["feeds"] = feeds
    write(tmp_path, d)
    with pytest.raises(thermal.DataFormatError, match=message):
        thermal.read_measurements(tmp_path)


# ------------------------------------------------------------------ compatibility


def test_on_read_sees_every_file_and_thermaldata_keeps_its_constructor(tmp_path):
    d = model(seed=24)
    write(tmp_path, d)
    seen = []
    data = thermal.read_measurements(tmp_path, seen.append)
    assert [p.name for p in seen] == ["temperatures.csv", "errors.csv", "experiments.csv"]
    old = thermal.ThermalData(data.index, data.temperatures, data.errors, data.positions_mm,
                              data.feeds, "somewhere")
    assert old.dropped == {} and old.ignored_columns == {}
