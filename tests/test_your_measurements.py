"""Notebook 08's path from a reader's files to the machine's model (measure.from_files) and its
paper code, on files written here from a model of our own (plain geometry, not the chain)."""

import numpy as np
import pandas as pd
import pytest

from mtaccuracy.machines.iso import iso_machine
from mtaccuracy.measure import design, from_files, identify, iso230_2, iso230_4
from mtaccuracy.measure.motions import motion_model
from mtaccuracy.papers import your_measurements as YM

TRAVELS = {"x": (-300.0, 300.0), "y": (-200.0, 200.0), "z": (-250.0, 250.0)}


@pytest.fixture(scope="module")
def model():
    return motion_model(iso_machine("w b X Y Z t", travels=TRAVELS), degree=2)


def _positioning(path, *, scale_um_per_m, lost_motion_um, noise_um, seed, targets=None):
    """An ISO 230-2 file of X: a scale error, lost motion (reversal), independent noise."""
    rng = np.random.default_rng(seed)
    t = np.linspace(-300.0, 300.0, 9) + [0, 3.1, -2.2, 1.7, 0, -1.3, 2.9, -0.8, 0] \
        if targets is None else np.asarray(targets)
    rows = []
    for j in range(1, 6):
        for sign, order in (("+", t), ("-", t[::-1])):
            x = scale_um_per_m * 1e-3 * order + (-0.5 if sign == "+" else 0.5) * lost_motion_um
            x = x + noise_um * rng.standard_normal(order.size)
            rows += [("X", v, j, sign, d) for v, d in zip(order, x, strict=True)]
    pd.DataFrame(rows, columns=["axis", "target_mm", "cycle", "direction",
                                "deviation_um"]).to_csv(path, index=False)
    return path


def _circle(path, *, radius=100.0, lag_ms=(1.0, 0.6), backlash_um=(2.0, 1.0), n=180,
            angles_cw=None):
    """An ISO 230-4 file in XY from axes that lag and have lost motion (no geometric error):
    the exact radial deviation of the actual point, each direction."""
    th = (np.arange(n) + 0.5) * 360.0 / n
    omega = 1000.0 / 60.0 / radius
    rows = []
    for ccw, order in ((True, th), (False, th[::-1] if angles_cw is None else angles_cw)):
        s = 1.0 if ccw else -1.0
        a = np.deg2rad(order)
        x = radius * np.cos(a - s * omega * lag_ms[0] * 1e-3) \
            - backlash_um[0] * 5e-4 * np.sign(-s * np.sin(a))
        y = radius * np.sin(a - s * omega * lag_ms[1] * 1e-3) \
            - backlash_um[1] * 5e-4 * np.sign(s * np.cos(a))
        d = (np.hypot(x, y) - radius) * 1e3
        rows += [("XY", radius, 1000.0, "ccw" if ccw else "cw", v, e)
                 for v, e in zip(order, d, strict=True)]
    pd.DataFrame(rows, columns=["plane", "radius_mm", "feed_mm_per_min", "direction",
                                "angle_deg", "deviation_um"]).to_csv(path, index=False)
    return path


def test_the_reversal_cancels_and_the_scale_is_recovered(model, tmp_path):
    f = _positioning(tmp_path / "p.csv", scale_um_per_m=20.0, lost_motion_um=4.0, noise_um=0.3,
                     seed=3)
    meas, y = from_files.positioning_readings(model, iso230_2.read_iso230_2(f), tool=0.0)
    assert meas.n_obs == y.size == 9
    # the mean bidirectional deviation carries no lost motion: the scale line through zero
    t = iso230_2.evaluate_iso230_2(f).targets_mm
    assert np.abs(y - 20e-3 * t).max() < 4 * 0.3 / np.sqrt(5)
    got = identify.identify(y, meas.design(), prior_sd=np.full(model.n_params, 5e-3))
    k = model.names.index("EXX[1]")
    # EXX[1] is the Legendre coefficient of u = x / 300 mm: 20 um/m * 300 mm = 6 um
    assert got.status[k] == "seen"
    assert abs(got.estimate[k] - 6e-3) < 3 * got.standard_uncertainty[k]


def test_servo_mismatch_and_backlash_cancel_in_the_two_directions_mean(model, tmp_path):
    f = _circle(tmp_path / "c.csv")
    circle = iso230_4.read_iso230_4(f)
    meas, y = from_files.circle_readings(model, circle, tool=0.0)
    raw = np.abs(circle.deviation_um).max()
    # the odd (direction-flipping) signatures cancel; what stays is second order (R (w tau)^2)
    assert raw > 0.5 and np.abs(y - y.mean()).max() < 0.01 * raw
    plan = design.combine([meas.design()])
    got = identify.identify(y, plan, prior_sd=np.full(model.n_params, 5e-3))
    assert np.all(np.abs(got.estimate) <= 3 * got.standard_uncertainty + 1e-12)


def test_a_file_of_another_machine_or_with_unmatched_angles_is_refused(model, tmp_path):
    far = _positioning(tmp_path / "far.csv", scale_um_per_m=1.0, lost_motion_um=0.0,
                       noise_um=0.1, seed=1, targets=np.linspace(0.0, 1000.0, 6))
    with pytest.raises(ValueError, match=r"far\.csv: targets of X from 0 to 1000 mm, outside "
                                         r"the machine's travel -300 to 300 mm"):
        from_files.positioning_readings(model, far)
    th = (np.arange(180) + 0.25) * 2.0
    odd = _circle(tmp_path / "odd.csv", angles_cw=th[::-1])
    with pytest.raises(ValueError, match=r"odd\.csv: the ccw and cw readings are not at the "
                                         r"same angles"):
        from_files.circle_readings(model, odd)


def test_priors_follow_the_ranges_and_the_units_read_um_and_urad(model):
    bounds = np.zeros((2, model.machine.n_errors))
    bounds[0], bounds[1] = -np.arange(1, model.machine.n_errors + 1), 0.0
    sd = model.prior_sd(bounds)
    j = model.names.index("EXX[2]")
    assert sd[j] == pytest.approx((model.column[j] + 1) / np.sqrt(12.0))
    units = YM.reader_units(model)
    assert units["EXX[1]"] == "um" and units["EC0Y"] == "urad"


def test_the_shipped_example_is_recognised_by_content_wherever_it_lies(tmp_path):
    moved = tmp_path / "renamed.csv"
    moved.write_bytes((YM.EXAMPLE_FOLDER / "circle_XY.csv").read_bytes())
    assert YM.is_shipped_example(moved, "circle_XY.csv")
    moved.write_bytes(moved.read_bytes() + b"\n")
    assert not YM.is_shipped_example(moved, "circle_XY.csv")
    assert not YM.is_shipped_example(tmp_path / "missing.csv", "circle_XY.csv")
