"""ISO 230-4 circular test evaluation: recovery from an exact geometric model of our own.

The model (written here, not the library's signatures): the commanded circle of radius R about
the origin, each axis at its command a time tau earlier (a pure delay), minus half its backlash
in the direction it moves, scaled by (1 + s); the +b axis moving along (-sin alpha, cos alpha)
(the included angle 90 deg + alpha); the instrument's pivot at -c so that the path's centre
sits at +c relative to it; the reading is |P - pivot| - R exactly.
"""

import numpy as np
import pandas as pd
import pytest

from mtaccuracy.measure import iso230_4
from mtaccuracy.measure.files import MeasurementFileError

R, FEED = 100.0, 1200.0                     # mm, mm/min
N = 180                                      # readings per direction


def angles(n=N, shift=0.5):
    """Equally spaced angles (deg), shifted half a step off the axis reversals."""
    return (np.arange(n) + shift) * 360.0 / n


def exact(theta_deg, ccw, *, scale=(0.0, 0.0), alpha=0.0, tau=(0.0, 0.0), backlash=(0.0, 0.0),
          centre=(0.0, 0.0), radius=R, feed=FEED):
    """The ballbar reading (um) and the tool's position error (mm), exactly.

    scale (um/m), alpha (urad), tau (ms), backlash (um), centre (um)."""
    th = np.deg2rad(theta_deg)
    s = np.where(ccw, 1.0, -1.0)
    omega = feed / 60.0 / radius                             # rad/s
    q = []
    for k, (phase, deriv) in enumerate(((np.cos, lambda t: -np.sin(t)),
                                        (np.sin, np.cos))):
        lagged = th - s * omega * tau[k] * 1e-3
        vel_sign = np.sign(s * deriv(th))
        pos = radius * phase(lagged) - backlash[k] * 1e-3 / 2 * vel_sign
        q.append(pos * (1 + scale[k] * 1e-6))
    a = alpha * 1e-6
    p = np.stack([q[0] - np.sin(a) * q[1], np.cos(a) * q[1]], axis=-1)
    pivot = -np.asarray(centre) * 1e-3
    d = (np.linalg.norm(p - pivot, axis=-1) - radius) * 1e3
    e = p - pivot - radius * np.stack([np.cos(th), np.sin(th)], axis=-1)
    return d, e


def frame(theta, ccw, d, *, plane="XY", radius=R, feed=FEED):
    return pd.DataFrame({"plane": plane, "radius_mm": radius, "feed_mm_per_min": feed,
                         "direction": np.where(ccw, "ccw", "cw"), "angle_deg": theta,
                         "deviation_um": d})


def both(n=N, shift=0.5):
    th = angles(n, shift)
    return np.concatenate([th, th[::-1]]), np.repeat([True, False], n)


NAMES = ("centre_X", "centre_Y", "scale_mismatch", "squareness", "servo_mismatch",
         "backlash_X", "backlash_Y")


def truth_vector(scale=(0.0, 0.0), alpha=0.0, tau=(0.0, 0.0), backlash=(0.0, 0.0),
                 centre=(0.0, 0.0)):
    """The first-order model's parameters (PARAMETERS' order) of the exact model's errors."""
    return np.array([R * (scale[0] + scale[1]) / 2 * 1e-3, *centre, scale[0] - scale[1],
                     alpha, tau[0] - tau[1], *backlash])


TRUTH = dict(scale=(12.0, -8.0), alpha=35.0, tau=(1.3, 0.9), backlash=(4.0, -2.5),
             centre=(7.0, -5.0))
EXPECT = {"scale_mismatch": 20.0, "squareness": 35.0, "servo_mismatch": 0.4, "backlash_X": 4.0,
          "backlash_Y": -2.5, "centre_X": 7.0, "centre_Y": -5.0}


def test_noise_free_recovery_within_the_first_order_remainder():
    th, ccw = both()
    d, e = exact(th, ccw, **TRUTH)
    x = iso230_4.signatures(th, ccw, radius_mm=R, feed_mm_per_min=FEED)
    truth = np.array([(R * (TRUTH["scale"][0] + TRUTH["scale"][1]) / 2) * 1e-3,
                      *TRUTH["centre"], 20.0, 35.0, 0.4, *TRUTH["backlash"]])
    delta = d - x @ truth
    # |R u + e| - R - e.u lies in [0, |e|^2 / (2R)]; the delay's, squareness's and scale's own
    # second-order terms are of the same order: |delta| <= |e|^2 / R (e in mm, delta in um)
    e2 = (np.linalg.norm(e, axis=-1) ** 2).max() / R * 1e3
    assert np.abs(delta).max() <= e2
    bound = np.abs(np.linalg.pinv(x)).sum(axis=1) * np.abs(delta).max()
    res = iso230_4.evaluate_iso230_4(frame(th, ccw, d))
    got = np.array([res.value(q) for q in EXPECT])
    want = np.array(list(EXPECT.values()))
    order = [3, 4, 5, 6, 7, 1, 2]
    assert np.all(np.abs(got - want) <= bound[order] + 1e-9)
    assert np.all(np.abs(got - want) < 5e-3 * np.abs(want))    # measured: 2.2e-3 at most


@pytest.mark.parametrize("kw, quantity, want", [
    (dict(alpha=40.0), "squareness", 40.0), (dict(alpha=-40.0), "squareness", -40.0),
    (dict(scale=(25.0, 0.0)), "scale_mismatch", 25.0),
    (dict(scale=(0.0, 25.0)), "scale_mismatch", -25.0),
    (dict(tau=(1.0, 0.0)), "servo_mismatch", 1.0), (dict(tau=(0.0, 1.0)), "servo_mismatch", -1.0),
    (dict(backlash=(6.0, 0.0)), "backlash_X", 6.0), (dict(backlash=(0.0, 6.0)), "backlash_Y", 6.0),
    (dict(centre=(9.0, 0.0)), "centre_X", 9.0), (dict(centre=(0.0, -9.0)), "centre_Y", -9.0)])
def test_one_error_signs_and_no_leak(kw, quantity, want):
    th, ccw = both()
    d, _ = exact(th, ccw, **kw)
    res = iso230_4.evaluate_iso230_4(frame(th, ccw, d))
    assert res.value(quantity) == pytest.approx(want, rel=2e-3)
    # every diagnostic (the others at zero) within the first-order remainder's image
    x = iso230_4.signatures(th, ccw, radius_mm=R, feed_mm_per_min=FEED)
    p = truth_vector(**kw)
    bound = np.abs(np.linalg.pinv(x)).sum(axis=1) * np.abs(d - x @ p).max()
    got = np.array([res.value(q) for q in NAMES])
    assert np.all(np.abs(got - p[1:]) <= bound[1:] + 1e-12)


def test_squareness_sign_is_the_included_angle_over_90_degrees():
    alpha = 40e-6
    axis_b = np.array([-np.sin(alpha), np.cos(alpha)])      # the model's +b axis
    assert np.degrees(np.arccos(axis_b @ [1.0, 0.0])) > 90
    th, ccw = both()
    d, _ = exact(th, ccw, alpha=40.0)
    assert iso230_4.evaluate_iso230_4(frame(th, ccw, d)).value("squareness") > 0


def test_servo_mismatch_flips_with_direction_squareness_does_not():
    th = angles()
    x_ccw = iso230_4.signatures(th, np.ones(N, bool), radius_mm=R, feed_mm_per_min=FEED)
    x_cw = iso230_4.signatures(th, np.zeros(N, bool), radius_mm=R, feed_mm_per_min=FEED)
    np.testing.assert_array_equal(x_ccw[:, :5], x_cw[:, :5])
    np.testing.assert_array_equal(x_ccw[:, 5:], -x_cw[:, 5:])


def test_G_of_a_known_ellipse_and_H_F():
    a, b = R + 0.004, R - 0.004                              # mm: G = a - b = 8 um
    th = np.arange(N) * 360.0 / N                            # through 0 and 90 deg
    t = np.deg2rad(th)
    r = a * b / np.sqrt((b * np.cos(t)) ** 2 + (a * np.sin(t)) ** 2)
    d_ccw = (r - R) * 1e3
    d_cw = d_ccw + 3.0 * np.sin(t) ** 2                      # H = 3 um at 90 and 270 deg
    thb, ccw = np.concatenate([th, th]), np.repeat([True, False], N)
    res = iso230_4.evaluate_iso230_4(frame(thb, ccw, np.concatenate([d_ccw, d_cw])))
    assert res.value("G_ccw") == pytest.approx(8.0, abs=1e-9)
    assert res.value("G_cw") == pytest.approx(5.0, abs=1e-3)   # 1.5 + (4 - 1.5) cos 2theta
    assert res.value("H") == pytest.approx(3.0, abs=1e-9)
    assert res.value("F_max") == pytest.approx(d_cw.max(), abs=1e-12)
    assert res.value("F_min") == pytest.approx(-4.0, abs=1e-9)
    # both paths in one zone about their common centre (the instrument's: both are symmetric):
    # the ellipse's +4 um at 0 deg to its -4 um at 90 deg; the cw path (-1 um there) lies inside
    assert res.value("G_b") == pytest.approx(8.0, abs=1e-9)
    lifted = iso230_4.evaluate_iso230_4(frame(thb, ccw, np.concatenate([d_ccw, d_cw + 5.0])))
    assert lifted.value("G_b") == pytest.approx(4.0 + 5.0 + 4.0, abs=1e-9)   # cw 5 um out
    one = iso230_4.evaluate_iso230_4(frame(thb, ccw, np.concatenate([d_ccw, d_ccw])))
    assert one.value("G_b") == pytest.approx(one.value("G_ccw"), abs=1e-12)  # one path twice


def test_G_is_blind_to_the_centre_offset_H_to_nothing_common():
    th, ccw = both(shift=0.0)
    base, _ = exact(th, ccw, scale=(10.0, -10.0))
    moved, _ = exact(th, ccw, scale=(10.0, -10.0), centre=(15.0, -10.0))
    r0 = iso230_4.evaluate_iso230_4(frame(th, ccw, base))
    r1 = iso230_4.evaluate_iso230_4(frame(th, ccw, moved))
    # the limacon's remainder: c^2 / (2R) = (18 um)^2 / 200 mm = 1.6e-3 um
    assert r1.value("G_ccw") == pytest.approx(r0.value("G_ccw"), abs=3.3e-3)
    assert r0.value("G_ccw") == pytest.approx(2.0, abs=1e-3)   # R ds = 100 mm * 20 um/m


def test_uncertainty_covers_the_truth_over_noisy_replicates():
    th, ccw = both(n=120)
    kw = dict(scale=(12.0, -8.0), alpha=35.0, tau=(0.3, 0.1), backlash=(4.0, -2.5),
              centre=(7.0, -5.0))
    d, _ = exact(th, ccw, **kw)
    x = iso230_4.signatures(th, ccw, radius_mm=R, feed_mm_per_min=FEED)
    rng = np.random.default_rng(20261129)
    sigma = 0.4
    y = d + sigma * rng.standard_normal((500, d.size))      # (500, n)
    coef = y @ np.linalg.pinv(x).T                           # the library's fit, batched
    res = y - coef @ x.T
    s2 = (res ** 2).sum(axis=1) / (d.size - x.shape[1])
    u = np.sqrt(s2[:, None] * np.diag(np.linalg.inv(x.T @ x)))
    one = iso230_4.evaluate_iso230_4(frame(th, ccw, y[0])).to_df().set_index("quantity")
    assert one.loc["squareness", "value"] == pytest.approx(coef[0, 4], abs=1e-9)
    assert one.loc["squareness", "standard_uncertainty"] == pytest.approx(u[0, 4], rel=1e-9)
    truth = np.array([R * 2e-3, 7.0, -5.0, 20.0, 35.0, 0.2, 4.0, -2.5])
    err = coef - truth
    se = err.std(axis=0, ddof=1) / np.sqrt(500)
    assert np.all(np.abs(err.mean(axis=0)) < 3 * se)
    ratio = err.var(axis=0, ddof=1) / (u ** 2).mean(axis=0)
    assert np.all((ratio > 0.8) & (ratio < 1.25)), ratio
    cover = (np.abs(err) <= 1.96 * u).mean(axis=0)
    assert 0.93 <= cover.mean() <= 0.97, cover
    assert np.all((cover > 0.91) & (cover < 0.99)), cover


def test_axes_named_from_the_plane():
    th, ccw = both()
    d, _ = exact(th, ccw, backlash=(3.0, 0.0))
    res = iso230_4.evaluate_iso230_4(frame(th, ccw, d, plane="ZX"))
    q = res.to_df()["quantity"].tolist()
    assert q == ["G_cw", "G_ccw", "G_b", "H", "F_max", "F_min", "squareness", "scale_mismatch",
                 "servo_mismatch", "backlash_Z", "backlash_X", "centre_Z", "centre_X"]
    assert res.value("backlash_Z") == pytest.approx(3.0, rel=2e-3)
    assert list(res.to_df().columns) == ["quantity", "value", "unit", "standard_uncertainty"]
    said = res.describe().set_index("quantity")["convention"]
    assert said.notna().all()
    assert "+Z and +X exceeds 90 deg" in said["squareness"]
    assert "least-squares centre" in said["G_cw"] and "instrument's centre" in said["F_max"]


def _write(tmp_path, text):
    p = tmp_path / "circle.csv"
    p.write_text(text)
    return p


def _good_lines(n=20):
    out = ["plane,radius_mm,feed_mm_per_min,direction,angle_deg,deviation_um"]
    for direction in ("ccw", "cw"):
        out += [f"XY,100,1000,{direction},{k * 360 / n:g},{np.sin(k):.3f}" for k in range(n)]
    return out


def test_reader_reads_a_good_file(tmp_path):
    data = iso230_4.read_iso230_4(_write(tmp_path, "\n".join(_good_lines()) + "\n"))
    assert data.plane == "XY" and data.radius_mm == 100 and data.ccw.sum() == 20


@pytest.mark.parametrize("edit, line, words", [
    (lambda ls: [ls[0].replace("angle_deg", "angle")] + ls[1:], 1, "missing column"),
    (lambda ls: ls[:3] + [ls[3].replace("ccw", "clockwise")] + ls[4:], 4, "'ccw'"),
    (lambda ls: ls[:3] + [ls[3].replace("XY", "XZ")] + ls[4:], 4, "'ZX'"),
    (lambda ls: ls[:5] + [ls[5].replace(",100,", ",150,")] + ls[6:], 6, "one circular test"),
    (lambda ls: ls[:2] + [ls[2].replace(",1000,", ",0,")] + ls[3:], 3, "> 0"),
    (lambda ls: ls[:4] + [ls[4].rsplit(",", 1)[0] + ",abc"] + ls[5:], 5, "not a number"),
    (lambda ls: ls[:21], None, "0 reading(s) in direction cw"),
    (lambda ls: ls[:3] + [ls[2]] + ls[3:], 4, "keep one reading per angle"),
    (lambda ls: [ln for k, ln in enumerate(ls) if not 3 <= k <= 6], 3, "whole circle")])
def test_reader_refuses_with_line_and_fix(tmp_path, edit, line, words):
    with pytest.raises(MeasurementFileError) as info:
        iso230_4.read_iso230_4(_write(tmp_path, "\n".join(edit(_good_lines())) + "\n"))
    assert info.value.line == line
    assert words in str(info.value) and "circle.csv" in str(info.value)


def test_reader_lists_every_problem_at_once(tmp_path):
    ls = _good_lines()
    ls[2] = ls[2].replace("ccw", "up")
    ls[30] = ls[30].rsplit(",", 1)[0] + ",x"
    with pytest.raises(MeasurementFileError) as info:
        iso230_4.read_iso230_4(_write(tmp_path, "\n".join(ls) + "\n"))
    assert [p[0] for p in info.value.problems] == [3, 31]


def test_the_committed_example_is_the_generators_and_recovers_its_truth():
    import importlib.util
    from pathlib import Path
    path = Path(__file__).resolve().parents[1] / "data" / "measure" / "make_examples.py"
    spec = importlib.util.spec_from_file_location("make_examples", path)
    gen = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(gen)
    assert (path.parent / "circle_XY.csv").read_text() == gen.texts()["circle_XY.csv"]
    table = iso230_4.evaluate_iso230_4(path.parent / "circle_XY.csv").to_df()
    table = table.set_index("quantity")
    c = gen.CIRCLE
    truth = {"scale_mismatch": c["scale_um_per_m"][0] - c["scale_um_per_m"][1],
             "squareness": c["squareness_urad"], "servo_mismatch": c["lag_ms"][0] - c["lag_ms"][1],
             "backlash_X": c["backlash_um"][0], "backlash_Y": c["backlash_um"][1],
             "centre_X": c["centre_um"][0], "centre_Y": c["centre_um"][1]}
    for q, want in truth.items():
        assert abs(table.loc[q, "value"] - want) < 3 * table.loc[q, "standard_uncertainty"], q


def test_H_between_paths_sampled_at_different_angles():
    def path(th, extra):
        t = np.deg2rad(th)
        return 4.0 * np.cos(2 * t) + extra * 3.0 * np.sin(t) ** 2   # um
    th_ccw, th_cw = angles(shift=0.5), angles(shift=0.0)
    thb = np.concatenate([th_ccw, th_cw])
    d = np.concatenate([path(th_ccw, 0), path(th_cw, 1)])
    res = iso230_4.evaluate_iso230_4(frame(thb, np.repeat([True, False], N), d))
    # linear interpolation over h = 2 deg errs by at most h^2 / 8 * max|f''| (f'' <= 22 um/rad^2
    # = 3.4e-3 um) and the ccw grid misses 90 deg by 1 deg: 3 (1 - cos^2 1 deg) = 9.1e-4 um
    assert res.value("H") == pytest.approx(3.0, abs=3.4e-3 + 9.2e-4)
