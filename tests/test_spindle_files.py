"""Probe files as a data acquisition records them (issue: time-sampled files, comments, gaps,
readers closed to what is not a file).

The tests' own DAQ model (:func:`_daq`): an artefact of known harmonics on a spindle whose speed
drifts linearly in time (1200 rpm, +0.5 %/s), a known synchronous and asynchronous radial
motion, four probes reading Eq. 7 at their mounting angles, sampled by a clock at 10 kHz or
1 kHz, an index pulse lasting three samples that rises on the first sample after the mark passes
(quantised to the sample), or an encoder.  The truth is the readings at the true times where the
spindle is at the resampled angles.
"""

import os
import re

import numpy as np
import pandas as pd
import pytest
from scipy.interpolate import make_interp_spline

from mtaccuracy.spindle import probedata as D
from mtaccuracy.spindle import probefile as F
from mtaccuracy.spindle import probes as P
from mtaccuracy.spindle import timefile as T

TWO_PI = 2 * np.pi
ANGLES = np.array([0.0, 38.5, 97.0, 221.0])
PHI = np.deg2rad(ANGLES)
F0, DRIFT, THETA0 = 20.0, 0.005, 0.37          # 1200 rpm, +0.5 %/s, the angle at t = 0 (rad)
KS = np.arange(2, 16)                          # the profile's harmonics
_RNG = np.random.default_rng(7)
A, B = 0.3 * _RNG.standard_normal((2, KS.size)) / KS
ECC = (1.0, -0.4)                              # centring (um)


def _revs(t):
    """The spindle's revolutions at time t: speed F0 (1 + DRIFT t)."""
    return F0 * (t + DRIFT * t * t / 2) + THETA0 / TWO_PI


def _time_of(revs):
    """The inverse of :func:`_revs`."""
    return (-1 + np.sqrt(1 + 2 * DRIFT * (revs - THETA0 / TWO_PI) / F0)) / DRIFT


def _profile(alpha):
    """The artefact's radius deviation (um) at its own angle(s)."""
    al = np.asarray(alpha)[..., None]
    return ((A * np.cos(KS * al) + B * np.sin(KS * al)).sum(-1)
            + ECC[0] * np.cos(al[..., 0]) + ECC[1] * np.sin(al[..., 0]))


def _readings(t, unsteady=0.0):
    """Eq. 7 at time(s) t (n,) -> (n, 4): profile under each probe, synchronous motion (2 and 3
    per revolution) and asynchronous motion (7.3 Hz, 13.1 Hz)."""
    th = TWO_PI * (_revs(t) + unsteady * np.sin(TWO_PI * 3.1 * t))
    x = 0.1 * np.cos(2 * th + 0.3) + 0.03 * np.cos(TWO_PI * 7.3 * t)
    y = 0.05 * np.sin(3 * th - 1.0) + 0.02 * np.sin(TWO_PI * 13.1 * t + 0.5)
    return (_profile(th[:, None] + PHI) + x[:, None] * np.cos(PHI)
            + y[:, None] * np.sin(PHI))


def _daq(path, fs, *, seconds=1.6, noise=0.0, ref="index", unsteady=0.0, seed=1):
    """Write what a DAQ at ``fs`` Hz records; returns (t, readings, index)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * fs)) / fs
    y = _readings(t, unsteady) + rng.uniform(-3, 3, 4) + noise * rng.standard_normal((t.size, 4))
    turns = np.floor(_revs(t) + unsteady * np.sin(TWO_PI * 3.1 * t))
    index = (turns > np.r_[turns[:1].repeat(3), turns[:-3]]).astype(int)   # 3 samples high
    df = pd.DataFrame({"time_s": t})
    if ref == "index":
        df["index"] = index
    elif ref == "encoder":                                    # wrapping at 360
        df["encoder_deg"] = np.round(np.mod(360 * _revs(t), 360), 6)
    else:                                                     # counting on
        df["encoder_deg"] = np.round(360 * _revs(t), 6)
    for j, a in enumerate(ANGLES):
        df[D.probe_column(a)] = y[:, j]
    df.to_csv(path, index=False, float_format="%.7f", lineterminator="\n")
    return t, y, index


def _exact(data):
    """The noiseless readings at the true times of the resampled angles (R, 4, N), and those
    times."""
    n, r = data.n_samples, data.n_revolutions
    first = round(_revs(data.resampling.start_s))
    times = _time_of(first + np.arange(r)[:, None] + np.arange(n) / n)
    return _readings(times.ravel()).reshape(r, n, 4).transpose(0, 2, 1), times


def _centred(e):
    return e - e.mean(axis=(0, 2), keepdims=True)           # the probes' zero offsets


def _without_01(p):
    spec = np.fft.fft(p, axis=-1)
    spec[..., [0, 1, -1]] = 0
    return np.fft.ifft(spec, axis=-1).real


# ------------------------------------------------------------------ the interpolation's bound


@pytest.mark.parametrize("nu", [0.1, 0.2, 0.25, 1 / 3])
def test_the_spline_bound_holds_for_a_tone_away_from_the_ends(nu):
    u = np.arange(300.0)
    x = np.linspace(T.EDGE_SAMPLES, 299 - T.EDGE_SAMPLES, 7001)
    spline = make_interp_spline(u, np.cos(TWO_PI * nu * u + 0.4), k=T.SPLINE_DEGREE)
    err = np.abs(spline(x) - np.cos(TWO_PI * nu * x + 0.4)).max()
    bound = T.interpolation_bound(nu)
    assert err <= bound and err >= bound / 3            # tight: the first alias dominates


def test_the_rule_for_n():
    assert [T.samples_per_revolution_rule(s) for s in (12, 49.8, 498, 1e6)] == \
        [8, 32, 256, D.MAX_SAMPLES]
    assert T.samples_per_revolution_rule(11.9) == 4                   # refused by the reader


# ------------------------------------------------------------------ resampling, against truth


@pytest.mark.parametrize("fs, ref", [(10_000, "encoder"), (1000, "encoder"),
                                     (1000, "encoder_counting")])
def test_an_encoder_file_resamples_to_the_exact_readings_within_the_spline_bound(
        tmp_path, fs, ref):
    """Noiseless, the encoder's angle exact to 1e-6 deg: what is left is the spline's error,
    at most the bound summed over the readings' harmonics, plus the readings' rounding (5e-8
    um, written with 7 decimals) times the spline's Lebesgue constant (< 3)."""
    _daq(tmp_path / "enc.csv", fs, ref="encoder" if ref == "encoder" else "counting")
    d = F.read_probe_file(tmp_path / "enc.csv")
    r = d.resampling
    assert r.reference == "encoder" and d.n_samples == (256 if fs == 10_000 else 32)
    exact, times = _exact(d)
    err = np.abs(_centred(d.signals_um - exact)).max()
    s_min = fs / (F0 * (1 + DRIFT * times.max()))
    amp = np.zeros(KS.max() + 1)
    amp[KS] = np.hypot(A, B)
    amp[1] += np.hypot(*ECC)
    amp[2] += 0.1
    amp[3] += 0.05
    bound = float(np.sum(amp * T.interpolation_bound(np.arange(amp.size) / s_min))) + 1.5e-7
    assert err <= bound, (err, bound)
    assert abs(r.speed_rpm / (60 * F0 * (1 + DRIFT * r.start_s)) - 1) < 0.01
    assert abs(r.drift_per_s - DRIFT / (1 + DRIFT * 0.8)) < 2e-4
    assert r.residual_s < 1e-3 / fs


def test_the_speed_fitted_to_all_pulses_beats_resampling_revolution_by_revolution(tmp_path):
    """1 kHz, noiseless: the pulse times err uniformly within +-dt/2 (sd dt / sqrt 12).  The
    quadratic fitted to P pulses errs by sd dt sqrt(3 / (12 P)) on average over the record (the
    mean leverage is 3 / P); a revolution resampled between its own two pulses by
    dt sqrt(2 / 3 / 12) (a weighted mean of two errors): sqrt(2 P / 9) = 2.7 times more for
    P = 32.  The readings err by their rate of change times that (the spline's error is far
    smaller at 1 kHz: the test above)."""
    fs = 1000
    t, y, index = _daq(tmp_path / "idx.csv", fs)
    d = F.read_probe_file(tmp_path / "idx.csv")
    r = d.resampling
    exact, times = _exact(d)
    rate = (_readings(times.ravel() + 1e-6) - _readings(times.ravel() - 1e-6)) / 2e-6
    rate_rms = np.sqrt(np.mean(rate ** 2))
    ours = np.sqrt(np.mean(_centred(d.signals_um - exact) ** 2))
    predicted = rate_rms * np.sqrt(3 / (12 * r.marks)) / fs
    assert ours <= 1.5 * predicted, (ours, predicted)
    # revolution by revolution, the same pulses and spline
    rises = np.flatnonzero((index[1:] == 1) & (index[:-1] == 0)) + 1 - 0.5
    first = np.searchsorted(rises, r.start_s * fs - 0.5)
    marks = rises[first:first + d.n_revolutions + 1]
    n = d.n_samples
    u = marks[:-1, None] + np.diff(marks)[:, None] * np.arange(n) / n
    spline = make_interp_spline(np.arange(t.size), y, k=T.SPLINE_DEGREE, axis=0)
    per_rev = spline(u.ravel()).reshape(d.n_revolutions, n, 4).transpose(0, 2, 1)
    theirs = np.sqrt(np.mean(_centred(per_rev - exact) ** 2))
    assert theirs >= 2 * predicted > ours, (theirs, predicted, ours)


def test_a_10khz_index_file_separates_the_true_profile_within_1_percent(tmp_path):
    """With 0.005 um of probe noise, the separated profile (harmonics 2..127) against the true
    one: within 1 % of its peak-to-valley (the noise alone leaves about 0.2 %)."""
    _daq(tmp_path / "daq.csv", 10_000, noise=0.005)
    d = F.read_probe_file(tmp_path / "daq.csv")
    r = d.resampling
    assert (r.reference, r.n_samples, r.marks, r.revolutions) == ("index", 256, 32, 31)
    assert r.fit_degree == 2 and r.residual_s <= 0.5e-4 + 1e-9      # within dt / 2
    assert abs(r.sample_rate_hz - 10_000) < 1e-6 and abs(r.samples_per_revolution - 498) < 1
    assert "10000 Hz" in r.describe() and "N = 256" in r.describe()
    np.testing.assert_allclose(d.sample_deg, 360 * np.arange(256) / 256)
    assert list(d.revolutions) == list(range(1, 32)) and d.max_harmonic == 127
    s = P.separate_probe_data(d)
    truth = _without_01(_profile(d.theta))
    err = np.abs(_without_01(s.profile) - truth).max() / np.ptp(truth)
    assert err < 0.01, err


def test_an_unsteady_speed_is_warned_about(tmp_path):
    path = tmp_path / "wobble.csv"
    _daq(path, 1000, unsteady=0.02)                       # +-7 deg at 3.1 Hz
    with pytest.warns(T.UnsteadySpeedWarning, match=r"wobble.csv: .*not steady") as caught:
        d = F.read_probe_file(path)
    assert caught[0].filename == __file__
    assert d.resampling.residual_s > d.resampling.residual_limit_s


# ------------------------------------------------------------------ comments, gaps


def _angle_text(n=16, n_rev=3, revolutions=None):
    rng = np.random.default_rng(3)
    th = TWO_PI * np.arange(n) / n
    y = _profile(th[:, None] + PHI) + 0.01 * rng.standard_normal((n_rev, n, 4))
    revs = np.arange(1, n_rev + 1) if revolutions is None else np.asarray(revolutions)
    df = pd.DataFrame({"revolution": np.repeat(revs, n),
                       "angle_deg": np.tile(360 * np.arange(n) / n, n_rev)})
    for j, a in enumerate(ANGLES):
        df[D.probe_column(a)] = np.round(y[:, :, j].ravel(), 5)
    return df.to_csv(index=False, lineterminator="\n")


def _write(tmp_path, text, name="p.csv"):
    path = tmp_path / name
    path.write_bytes(text.encode() if isinstance(text, str) else text)
    return path


def test_comments_are_allowed_and_lines_stay_the_editors(tmp_path):
    text = _angle_text()
    plain = F.read_probe_file(_write(tmp_path, text, "plain.csv"))
    lines = text.split("\n")
    lines[0] += "  # header; with a semicolon in the comment"
    lines[3] += " # a trailing comment, 1,2,3"
    commented = "# DAQ export, 2024-05-01; probes in um\n#\n" + "\n".join(lines)
    d = F.read_probe_file(_write(tmp_path, commented, "commented.csv"))
    np.testing.assert_array_equal(d.signals_um, plain.signals_um)
    assert d.header_line == 3
    bad = commented.split("\n")
    bad[9] = ",".join("NaN" if i == 3 else f for i, f in enumerate(bad[9].split(",")))
    with pytest.raises(D.ProbeFileError, match=r"bad.csv, line 10: column 'probe_38.5_um'"):
        F.read_probe_file(_write(tmp_path, "\n".join(bad), "bad.csv"))


def test_a_gap_in_the_revolutions_is_refused_naming_the_line(tmp_path):
    path = _write(tmp_path, _angle_text(n_rev=4, revolutions=[1, 2, 3, 5]))
    with pytest.raises(D.ProbeFileError) as info:
        F.read_probe_file(path)
    assert info.value.line == 2 + 3 * 16
    assert re.search(r"revolution 5 follows revolution 3 \(line 49\): revolution 4 is missing; "
                     r"the asynchronous motion .* consecutive", str(info.value))


def test_a_26_digit_revolution_number_is_reported_as_written(tmp_path):
    text = _angle_text().replace("\n2,", "\n12345678901234567890123456,", 1)
    with pytest.raises(D.ProbeFileError, match=r"line 18: revolution "
                                                r"12345678901234567890123456 is beyond 1e\+15"):
        F.read_probe_file(_write(tmp_path, text))


def test_a_field_over_128_kib_is_refused_at_its_own_line(tmp_path):
    lines = _angle_text().split("\n")
    lines[6] = lines[6].replace(",", "," + "7" * 140_000 + "x", 1)
    with pytest.raises(D.ProbeFileError) as info:
        F.read_probe_file(_write(tmp_path, "\n".join(lines)))
    assert info.value.line == 7 and "line -1" not in str(info.value)
    assert "131072 characters" in str(info.value) and len(str(info.value)) < 400
    lines[3] = lines[3].replace(",", ",oops,", 1).replace(",oops,", ",", 1)
    lines[3] = ",".join("oops" if i == 2 else f for i, f in enumerate(lines[3].split(",")))
    with pytest.raises(D.ProbeFileError, match=r"line 4: column 'probe_0_um' .*'oops'"):
        F.read_probe_file(_write(tmp_path, "\n".join(lines), "q.csv"))


# ------------------------------------------------------------------ what is not a file


def test_what_is_not_a_regular_file_is_refused_before_a_byte_is_read(tmp_path, monkeypatch):
    with pytest.raises(D.ProbeFileError, match=r"is a directory, not a regular file"):
        F.read_probe_file(tmp_path)
    fifo = tmp_path / "fifo.csv"
    os.mkfifo(fifo)
    with pytest.raises(D.ProbeFileError, match=r"fifo.csv: is a FIFO"):
        F.read_probe_file(fifo)
    link = tmp_path / "zero.csv"
    link.symlink_to("/dev/zero")
    with pytest.raises(D.ProbeFileError, match=r"zero.csv: is a character device"):
        F.read_probe_file(link)
    path = _write(tmp_path, _angle_text())
    monkeypatch.setattr(F, "MAX_FILE_BYTES", 500)
    with pytest.raises(D.ProbeFileError, match=r"p.csv: \d+ bytes; files up to 500 bytes"):
        F.read_probe_file(path)


# ------------------------------------------------------------------ time-sampled refusals


def _time_text(fs=1000, ref="index"):
    t = np.arange(int(1.0 * fs)) / fs
    turns = np.floor(_revs(t))
    df = pd.DataFrame({"time_s": np.round(t, 6)})
    if ref == "index":
        df["index"] = (turns > np.r_[turns[:1], turns[:-1]]).astype(int)
    else:
        df["encoder_deg"] = np.round(np.mod(360 * _revs(t), 360), 4)
    y = _readings(t)
    for j, a in enumerate(ANGLES):
        df[D.probe_column(a)] = np.round(y[:, j], 5)
    return df.to_csv(index=False, lineterminator="\n")


def _set(text, line, column, value):
    lines = text.split("\n")
    lines[line - 1] = ",".join(value if i == column else f
                               for i, f in enumerate(lines[line - 1].split(",")))
    return "\n".join(lines)


def _drop_lines(text, first, last):
    lines = text.split("\n")
    return "\n".join(lines[:first - 1] + lines[last:])


def _pulse_lines(text):
    return [i + 1 for i, s in enumerate(text.split("\n")) if s.split(",")[1:2] == ["1"]]


def _missed_pulse(t):
    return _set(t, _pulse_lines(t)[3], 1, "0")


def _bounce(t):
    return _set(t, _pulse_lines(t)[3] + 2, 1, "1")


TIME_FILES = [
    ("time not increasing", lambda t: _set(t, 30, 0, "0.026"), 30,
     r"time_s must increase: 0.026 s does not come after 0.027 s \(line 29\)"),
    ("samples dropped", lambda t: _drop_lines(t, 40, 42), 40,
     r"time_s steps 0.004 s from line 39 .* 4 sample periods.*dropped"),
    ("index a voltage", lambda t: _set(t, 12, 1, "5"), 12, r"index is 5; .*a voltage"),
    ("index 0.9999999", lambda t: _set(t, 12, 1, "0.9999999"), 12, r"index is 0.9999999;"),
    ("no pulse", lambda t: t.replace(",1,", ",0,"), 1, r"the index column has no pulse"),
    ("too few pulses", lambda t: "\n".join(t.split("\n")[:_pulse_lines(t)[1] + 20]), None,
     r"2 index pulse\(s\) \(line\(s\) \d+, \d+\); at least 3"),
    ("missed pulse", _missed_pulse, None, r"comes 99 samples after the one at line \d+, "
                                          r"where the pulses are .*: a pulse missed"),
    ("bouncing pulse", _bounce, None, r"comes 2 samples after .*bounced"),
    ("index and encoder", lambda t: t.replace("time_s,index,", "time_s,index,encoder_deg,", 1)
     .replace(",0,", ",0,0,").replace(",1,", ",1,1,"), 1, r"both 'index' and 'encoder_deg'"),
    ("no index", lambda t: t.replace("time_s,index", "time_s,trigger", 1), 1,
     r"needs an 'index' column .*\('trigger' found"),
    ("time named t", lambda t: t.replace("time_s,index", "t,index", 1), 1,
     r"missing column 'time_s' \('t' found"),
]


@pytest.mark.parametrize("edit, line, message", [c[1:] for c in TIME_FILES],
                         ids=[c[0] for c in TIME_FILES])
def test_a_bad_time_file_is_refused_naming_the_line(tmp_path, edit, line, message):
    text = edit(_time_text())
    path = _write(tmp_path, text, "daq.csv")
    with pytest.raises(D.ProbeFileError) as info:
        F.read_probe_file(path)
    msg = str(info.value)
    assert re.search(message, msg), msg
    assert info.value.line is not None and info.value.line >= 1 and "line -1" not in msg
    if line is not None:
        assert info.value.line == line, msg


def test_a_slow_daq_and_a_backwards_encoder_are_refused(tmp_path):
    text = _time_text(fs=200)                     # 10 samples per revolution
    with pytest.raises(D.ProbeFileError, match=r"daq.csv, line 1: 9.9\d* samples per "
                                                r"revolution .*at least 12"):
        F.read_probe_file(_write(tmp_path, text, "daq.csv"))
    df = pd.read_csv(pd.io.common.StringIO(_time_text(ref="encoder")))
    df["encoder_deg"] = np.mod(-df["encoder_deg"], 360)
    with pytest.raises(D.ProbeFileError, match=r"line 3: encoder_deg must increase.*turning "
                                                r"the other way"):
        F.read_probe_file(_write(tmp_path, df.to_csv(index=False), "back.csv"))


def test_a_time_file_reads_with_comments_and_an_angle_file_keeps_its_time_column(tmp_path):
    text = "# DAQ 1 kHz\n" + _time_text().replace("\n", " # sample\n", 5)
    d = F.read_probe_file(_write(tmp_path, text, "daq.csv"))
    assert d.resampling.n_samples == 32 and d.resampling.first_line > 2
    angle = F.read_probe_file(_write(tmp_path, _angle_text(), "angle.csv"))
    assert angle.resampling is None
