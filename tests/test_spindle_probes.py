"""A reader's multi-probe spindle file (issue 22): the reader's checks, the separation at any
probe angles, and ISO 230-7 radial error motion values.

The separation is tested on data made by this file's own physical model (:func:`_readings`):
an artefact drawn as a closed curve, moved by the spindle's radial motion and turned by the
spindle, read by probes on rays from the origin (the distance to the surface, found by
iteration), not by the project's generators or by Eq. 7 itself.  Eq. 7 holds for it to second
order in motion / radius; a test checks that directly.
"""

import hashlib
import io
import json
import re
import shutil
import warnings

import numpy as np
import pandas as pd
import pytest

from mtaccuracy import roundness
from mtaccuracy import spindle as S
from mtaccuracy.compendium.provenance import ROOT
from mtaccuracy.spindle import errormotion as E
from mtaccuracy.spindle import example as X
from mtaccuracy.spindle import probedata as D
from mtaccuracy.spindle import probefile as F
from mtaccuracy.spindle import probes as P

RADIUS_UM = 25_000.0          # the artefact's nominal radius: 25 mm
TWO_PI = 2 * np.pi
LAYOUTS = {3: (0.0, 99.5, 211.3), 4: (0.0, 38.5, 97.0, 221.0),
           5: (12.0, 81.7, 150.2, 233.9, 301.4)}


# ------------------------------------------------------------------ the tests' physical model


def _form(coefs):
    """The artefact's radius deviation (um) at its own angle, from ``(k, a, b)`` terms."""
    return lambda u: sum(a * np.cos(k * u) + b * np.sin(k * u) for k, a, b in coefs)


def _readings(form, x, y, phi, theta, radius=RADIUS_UM):
    """What probes on rays from the origin at fixed angles ``phi`` (L,) read: the distance to
    the artefact's surface minus ``radius`` (um), at spindle angles ``theta`` (N,), the
    artefact's centre at ``(x, y)`` (R, N) and the spindle turning it clockwise: its point at
    its own angle psi lies at the fixed angle psi - theta.  Solved exactly by iteration on the
    distance s along the ray: |s e_phi - c| = radius + form(psi)."""
    e = np.stack([np.cos(phi), np.sin(phi)])[:, None, :, None]          # (2, 1, L, 1)
    c = np.stack([x, y])[:, :, None, :]                                  # (2, R, 1, N)
    s = np.full(np.broadcast_shapes(e.shape[1:], c.shape[1:]), radius)
    for _ in range(8):
        p = s * e - c
        psi = np.arctan2(p[1], p[0]) + theta
        rho = radius + form(psi)
        along = (c * e).sum(0)
        across = c[0] * e[1] - c[1] * e[0]
        s = along + np.sqrt(rho ** 2 - across ** 2)
    return s - radius                                                   # (R, L, N)


def _case(n_probes, rng, n=256, n_rev=5, noise=0.005, motion=0.3):
    """A random artefact (harmonics 2..40 and a 5-lobed shape, a centring error), a spindle
    motion (synchronous harmonics, a genuine once-per-revolution motion turning against the
    spindle, random asynchronous motion, an offset), probe zeros and white noise."""
    coefs = [(k, a, b) for k, a, b in zip(range(2, 41), *(0.3 * rng.standard_normal((2, 39))
                                                          / np.arange(2, 41)), strict=True)]
    coefs += [(5, 0.4, -0.2), (1, 0.8, -0.5)]                           # lobes, centring
    theta = TWO_PI * np.arange(n) / n + np.deg2rad(3.0)                 # not starting at 0
    sync = sum(motion * rng.standard_normal() / k * np.exp(1j * (k * theta + rng.uniform(0, 7)))
               for k in (2, 3, -2, 4, 7))
    sync = sync + 0.05 * np.exp(1j * theta)                             # turns against
    asyn = sum(0.03 * (rng.standard_normal((n_rev, 1)) + 1j * rng.standard_normal((n_rev, 1)))
               / k * np.exp(1j * k * theta) for k in range(-20, 21) if k)
    z = sync + asyn + (0.4 - 0.2j)
    phi = np.deg2rad(LAYOUTS[n_probes])
    y = _readings(_form(coefs), z.real, z.imag, phi, theta)
    y = y + rng.uniform(-5, 5, (1, n_probes, 1)) + noise * rng.standard_normal(y.shape)
    return dict(coefs=coefs, theta=theta, z=z, phi=phi, y=y, noise=noise, n=n, n_rev=n_rev)


def _without_01(p):
    """A profile without its mean and first harmonic (the conventions of the separation)."""
    spec = np.fft.fft(p, axis=-1)
    spec[..., [0, 1, -1]] = 0
    return np.fft.ifft(spec, axis=-1).real


def _amplification_ls(phi, ks):
    """q_k of least squares, independently: the (0, 0) element of (A^H A)^-1 (numpy.linalg)."""
    out = []
    for k in ks:
        a = np.column_stack([np.exp(1j * k * phi), np.cos(phi), np.sin(phi)])
        out.append(np.sqrt(np.linalg.inv(a.conj().T @ a)[0, 0].real))
    return np.array(out)


# ------------------------------------------------------------------ the convention, directly


def test_the_physical_model_reads_eq7_and_not_the_other_signs():
    rng = np.random.default_rng(0)
    c = _case(4, rng, noise=0.0)
    theta, phi, z = c["theta"], c["phi"], c["z"]
    form = _form(c["coefs"])
    y = _readings(form, z.real, z.imag, phi, theta)
    t, f = theta[None, None, :], phi[None, :, None]
    zx, zy = z.real[:, None, :], z.imag[:, None, :]
    eq7 = form(t + f) + zx * np.cos(f) + zy * np.sin(f)
    # second order: the centre's tangential shift turns the artefact by |c| / radius, which
    # moves the form by its slope, and lengthens the ray by |c|^2 / (2 radius)
    u = np.linspace(0, TWO_PI, 4096, endpoint=False)
    slope = np.abs(np.gradient(form(u), u)).max()
    second = np.abs(z).max() * slope / RADIUS_UM + np.abs(z).max() ** 2 / RADIUS_UM
    assert np.abs(y - eq7).max() < second < 5e-4
    for wrong in (form(t - f) + zx * np.cos(f) + zy * np.sin(f),
                  form(t + f) - zx * np.cos(f) - zy * np.sin(f),
                  form(t + f) + zx * np.sin(f) + zy * np.cos(f)):
        assert np.abs(y - wrong).max() > 0.1


def test_the_reader_keeps_the_convention_probe_at_phi_reads_r_of_theta_plus_phi(tmp_path):
    """A file whose probes read a single harmonic of the profile: r(theta + phi) for each probe,
    with angles off the grid, comes back as that harmonic at the file's sample angles."""
    n, angles = 64, np.array([0.0, 38.5, 97.0, 221.0])
    theta_deg = 360 * np.arange(n) / n + 10.0
    r = lambda u: 0.8 * np.cos(3 * u - 0.4) + 0.3 * np.sin(7 * u)      # noqa: E731
    readings = r(np.deg2rad(theta_deg)[None, :] + np.deg2rad(angles)[:, None])
    df = pd.DataFrame({"revolution": 1, "angle_deg": theta_deg})
    for a, col in zip(angles, readings, strict=True):
        df[f"probe_{a:g}_um"] = col
    path = tmp_path / "one.csv"
    df.to_csv(path, index=False)
    data = F.read_probe_file(path)
    assert data.columns == ("probe_0_um", "probe_38.5_um", "probe_97_um", "probe_221_um")
    for method in ("least_squares", "weighted"):
        s = P.separate_probe_data(data, method=method)
        assert np.abs(s.profile - r(data.theta)).max() < 1e-10
        assert np.abs(s.dx).max() < 1e-10 and np.abs(s.dy).max() < 1e-10


# ------------------------------------------------------------------ separation accuracy


@pytest.mark.parametrize("noise", [0.0, 0.005, 0.05])
@pytest.mark.parametrize("n_probes", [3, 4, 5])
@pytest.mark.parametrize("method", ["least_squares", "weighted"])
def test_separation_recovers_the_profile_and_motion_of_the_physical_model(method, n_probes,
                                                                          noise):
    rng = np.random.default_rng(10 * n_probes + int(noise * 1000))
    c = _case(n_probes, rng, noise=noise)
    s = P.separate_probes(c["y"], c["phi"], method=method)
    assert s.cancelled == []
    n, ks = c["n"], np.arange(2, (c["n"] - 1) // 2 + 1)
    # the bound: white noise sigma through q_k (derived here, independently), averaged over
    # the revolutions; plus the model's second-order terms (< 2e-4 um)
    if method == "least_squares":
        q = _amplification_ls(c["phi"], ks)
    else:
        lam = np.exp(1j * ks[:, None] * c["phi"]) @ s.weights
        q = np.sqrt((s.weights ** 2).sum() / np.abs(lam) ** 2)
        assert abs(s.weights @ np.exp(1j * c["phi"])) < 1e-9       # cancels the motion
    np.testing.assert_allclose(s.amplification, q, rtol=5e-8)          # to 8 digits
    assert all(float(f"{v:.8g}") == v for v in s.amplification)
    predicted = noise * np.sqrt(2 * (q ** 2).sum() / (n * c["n_rev"]))
    truth = _form(c["coefs"])(c["theta"])
    err = _without_01(s.profile) - _without_01(truth)
    rms = np.sqrt((err ** 2).mean())
    assert rms <= 1.3 * predicted + 2e-4, (rms, predicted)
    assert np.abs(err).max() <= 5 * predicted + 5e-4
    if noise:
        assert rms >= 0.6 * predicted                              # the bound is not loose
    # the motion, without its mean and its mean once-per-revolution part turning with the
    # artefact (given to the profile)
    z = c["z"] - c["z"].mean()
    z = z - (z * np.exp(1j * c["theta"])).mean() * np.exp(-1j * c["theta"])
    ez = (s.dx + 1j * s.dy) - z
    g = np.column_stack([np.cos(c["phi"]), np.sin(c["phi"])])
    per_sample = noise * np.sqrt(np.trace(np.linalg.inv(g.T @ g)))
    spread = np.linalg.norm(np.linalg.pinv(g), 2) * np.sqrt(len(c["phi"])) * predicted
    assert np.sqrt((np.abs(ez) ** 2).mean()) <= 1.3 * (per_sample + spread) + 5e-4


def test_the_noise_estimate_from_the_misfit_and_the_helpers():
    rng = np.random.default_rng(8)
    for n_probes in (3, 4, 5):
        c = _case(n_probes, rng, noise=0.01, n_rev=8)
        s = P.separate_probes(c["y"], c["phi"])
        assert P.probe_noise_estimate(s, n_probes) == pytest.approx(0.01, rel=0.1)
    t = TWO_PI * np.arange(64) / 64
    p = 3.0 + 0.5 * np.cos(t - 1) + 0.2 * np.cos(4 * t)
    np.testing.assert_allclose(E.about_lsc(p), 0.2 * np.cos(4 * t), atol=1e-12)


def test_the_noise_prediction_matches_monte_carlo():
    rng = np.random.default_rng(5)
    n, n_rev, sigma = 128, 2, 0.01
    for n_probes, angles in LAYOUTS.items():
        phi = np.deg2rad(angles)
        noise = sigma * rng.standard_normal((400, n_rev, n_probes, n))
        for method in ("least_squares", "weighted"):
            s = P.separate_probes(noise, phi, method=method)
            mc = np.sqrt((_without_01(s.profile) ** 2).mean())
            pred = P.profile_noise_rms(s.amplification, n_samples=n, noise_sd=sigma,
                                        n_revolutions=n_rev)
            assert abs(mc / pred - 1) < 0.08, (n_probes, method, mc, pred)


def test_least_squares_never_amplifies_noise_more_than_the_weighted_method():
    rng = np.random.default_rng(3)
    ks = np.arange(2, 64)
    for _ in range(8):
        phi = np.sort(rng.uniform(0, TWO_PI, rng.integers(3, 6)))
        if P.layout_cancelled(phi, 63):
            continue
        w = P.layout_weights(phi, ks)
        assert np.all(P.noise_amplification(phi, ks)
                      <= P.noise_amplification(phi, ks, weights=w) * (1 + 1e-9))


# ------------------------------------------------------------------ against the library


def test_on_the_sampling_grid_both_estimators_equal_the_librarys():
    rng = np.random.default_rng(7)
    n, pos = 128, [0, 14, 65, 116]
    phi = S.probe_angles(pos, n)
    w = S.full_weights(phi, 1.953)
    r = roundness.lowpass(rng.standard_normal(n), 63)
    t = TWO_PI * np.arange(n) / n
    dx, dy = 0.3 * np.cos(2 * t + 1), 0.2 * np.sin(3 * t)
    y = S.probe_signals(r, dx, dy, pos)
    y = y - y.mean(axis=-1, keepdims=True)
    # a noise-free profile with content to the top harmonic: rightly taken for aliasing
    with pytest.warns(S.AliasingWarning, match="top harmonics 58..64"):
        mine = P.separate_probes(y[None], phi, method="weighted", weights=w)
    lib = S.separate_details(y, phi, w)
    assert np.abs(mine.profile - (lib.profile - lib.profile.mean())).max() < 1e-10
    assert np.abs(mine.dx[0] - lib.dx).max() < 1e-10 and np.abs(mine.dy[0] - lib.dy).max() < 1e-10
    with pytest.warns(S.AliasingWarning):
        mine = P.separate_probes(y[None], phi)
    lib = S.separate_least_squares(y, phi)
    assert np.abs(mine.profile - (lib.profile - lib.profile.mean())).max() < 1e-10
    ks = np.arange(2, 64)
    np.testing.assert_allclose(P.noise_amplification(phi, ks, weights=w) ** 2,
                               S.transfer(phi, w, ks), rtol=1e-10)
    np.testing.assert_allclose(P.noise_amplification(phi, ks) ** 2,
                               S.least_squares_transfer(phi, ks), rtol=1e-10)


def test_layout_weights_cancel_the_motion_and_beat_every_a3_for_four_probes():
    phi = np.deg2rad(LAYOUTS[4])
    ks = np.arange(2, 128)
    w = P.layout_weights(phi, ks)
    assert w[0] == 1.0 and abs(w @ np.exp(1j * phi)) < 1e-12
    # the library's Eq. 15 weights with this a3 are these weights
    np.testing.assert_allclose(S.full_weights(phi, w[3]), w, atol=1e-12)
    worst = P.noise_amplification(phi, ks, weights=w).max()
    for a3 in np.linspace(-5, 5, 401):
        other = S.full_weights(phi, a3)
        assert worst <= P.noise_amplification(phi, ks, weights=other).max() * (1 + 1e-6)
    # three probes: the unique three-point weights
    w3 = P.layout_weights(np.deg2rad(LAYOUTS[3]), ks)
    assert w3[0] == 1.0 and abs(w3 @ np.exp(1j * np.deg2rad(LAYOUTS[3]))) < 1e-12
    # five probes: no worse than the best four of them
    phi5 = np.deg2rad(LAYOUTS[5])
    w5 = P.layout_weights(phi5, ks)
    best4 = min(P.noise_amplification(np.delete(phi5, j), ks,
                                      weights=P.layout_weights(np.delete(phi5, j), ks)).max()
                for j in range(5))
    assert P.noise_amplification(phi5, ks, weights=w5).max() <= best4 * (1 + 1e-6)


def test_three_probes_120_degrees_apart_cancel_all_but_the_multiples_of_three():
    phi = np.deg2rad([0.0, 120.0, 240.0])
    assert P.layout_cancelled(phi, 40) == [k for k in range(2, 41) if k % 3]
    y = np.zeros((1, 3, 96))
    with pytest.raises(ValueError, match=r"cannot separate harmonic\(s\) 2, 4, 5, 7"):
        P.separate_probes(y, phi)
    t = TWO_PI * np.arange(96) / 96
    r = lambda u: np.cos(6 * u) + 0.5 * np.sin(4 * u)                  # noqa: E731
    y = np.stack([r(t + f) for f in phi])[None]
    with pytest.warns(S.CancelledHarmonicsWarning, match="allow_cancelled=True"):
        s = P.separate_probes(y, phi, allow_cancelled=True)
    assert np.abs(s.profile - np.cos(6 * t)).max() < 1e-10           # the 4th is lost
    assert np.isinf(s.amplification[s.harmonics == 4]).all()
    with pytest.raises(ValueError, match="that is every harmonic: nothing to separate"):
        P.separate_probes(y, phi, max_harmonic=2, allow_cancelled=True)
    # weights given that cancel a harmonic the layout sees: refused, or set aside
    phi4 = np.deg2rad([0.0, 90.0, 180.0, 250.0])
    w = np.array([1.0, 0.0, 1.0, 0.0])                 # cancels the motion and every odd k
    y4 = np.stack([r(t + f) for f in phi4])[None]
    with pytest.raises(ValueError, match=r"the weights \[1.0, 0.0, 1.0, 0.0\] cancel harmonic"):
        P.separate_probes(y4, phi4, method="weighted", weights=w)
    with pytest.warns(S.CancelledHarmonicsWarning, match="the weights"):
        s = P.separate_probes(y4, phi4, method="weighted", weights=w, allow_cancelled=True)
    assert 3 in s.cancelled and np.abs(s.profile - r(t)).max() < 1e-10   # 4 and 6 are even


# ------------------------------------------------------------------ ISO 230-7 values


def _grid(n=360):
    return TWO_PI * np.arange(n) / n


def test_a_two_per_revolution_ellipse_has_the_values_computed_by_hand():
    t = _grid()
    a, b = 0.4, 0.1
    dx, dy = np.tile(a * np.cos(2 * t), (3, 1)), np.tile(b * np.sin(2 * t), (3, 1))
    table, motions = E.error_motion_table(dx, dy, t, fixed_directions=np.deg2rad([0, 90, 45]),
                                          rotating_direction=0.0)
    # fixed along x: a cos 2t, ptp 2a; along y: b sin 2t, 2b; at 45 deg:
    # (a cos 2t + b sin 2t) / sqrt 2, 2 sqrt((a^2 + b^2) / 2)
    expected = [2 * a, 2 * b, 2 * np.sqrt((a ** 2 + b ** 2) / 2)]
    np.testing.assert_allclose(table.synchronous_um[:3], expected, rtol=1e-6)
    np.testing.assert_allclose(table.asynchronous_um, 0, atol=1e-12)
    np.testing.assert_allclose(table.total_um, table.synchronous_um, atol=1e-12)
    # rotating, pointing at -t: u = a cos 2t cos t - b sin 2t sin t
    #                             = (a - b)/2 cos t + (a + b)/2 cos 3t; LSC removes the cos t
    assert table.synchronous_um[3] == pytest.approx(a + b, rel=1e-9)
    mrs = E.radial_error_motion(motions[0].total_plot, centre="MRS")
    assert float(mrs.synchronous_value) == pytest.approx(2 * a, rel=1e-6)


def test_the_asynchronous_value_is_the_largest_spread_between_revolutions():
    t = _grid()
    d = np.array([0.1, 0.3, 0.25])[:, None]
    u = d * np.cos(5 * t) + 0.2 * np.cos(2 * t) + np.array([0.0, 0.02, -0.01])[:, None]
    for centre in E.CENTRES:
        m = E.radial_error_motion(u, centre=centre)
        # at t = 0 the revolutions read 0.3, 0.52, 0.44: spread 0.22; at t = pi/5 (cos 2t
        # = cos(2 pi / 5)) they read -0.1, -0.28, -0.26 + the same: spread 0.18 + 0.02
        spread = np.ptp(u, axis=0).max()
        assert float(m.asynchronous_value) == pytest.approx(spread, rel=1e-12)
        assert spread == pytest.approx(0.22, rel=1e-12)
        # synchronous: mean d = 0.65/3 times cos 5t plus 0.2 cos 2t plus a constant
        sync = (0.65 / 3) * np.cos(5 * t) + 0.2 * np.cos(2 * t)
        assert float(m.synchronous_value) <= np.ptp(sync) + 1e-9
    assert float(E.radial_error_motion(u).synchronous_value) == pytest.approx(np.ptp(sync),
                                                                              rel=1e-9)
    assert np.isnan(E.radial_error_motion(u[:1]).asynchronous_value)


def test_the_centring_does_not_change_any_value_and_mrs_is_never_above_lsc():
    rng = np.random.default_rng(4)
    t = _grid(256)
    u = rng.standard_normal((4, 256)) * 0.05 + 0.1 * np.cos(3 * t)
    shifted = u + 0.7 * np.cos(t - 0.4) + 2.0                    # eccentricity and offset
    for centre in E.CENTRES:
        a, b = E.radial_error_motion(u, centre=centre), E.radial_error_motion(shifted,
                                                                               centre=centre)
        for f in ("synchronous_value", "asynchronous_value", "total_value"):
            assert float(getattr(a, f)) == pytest.approx(float(getattr(b, f)), rel=1e-7)
    lsc, mrs = E.radial_error_motion(u), E.radial_error_motion(u, centre="MRS")
    assert mrs.synchronous_value <= lsc.synchronous_value + 1e-12
    assert mrs.total_value <= lsc.total_value + 1e-12
    assert lsc.total_value >= lsc.synchronous_value
    # the band's minimum radial separation is the minimum zone when the band is one curve
    assert E._band_zone(u[0], u[0]) == pytest.approx(roundness.mz_roundness(u[0])[0], rel=1e-9)


def test_the_rotating_direction_is_what_a_tool_on_the_spindle_sees():
    """A point fixed to the spindle at its own angle psi0 and radius rho lies at fixed angle
    psi0 - theta (the probe file's geometry); its radial displacement is the rotating
    component; a fixed tool at alpha sees the fixed one."""
    rng = np.random.default_rng(6)
    t = _grid(128)
    z = 0.3 * np.exp(2j * t + 0.5) + 0.1 * np.exp(-3j * t) + 0.05 * rng.standard_normal(128)
    rho, psi0 = 40_000.0, np.deg2rad(30.0)
    p = z + rho * np.exp(1j * (psi0 - t))
    radial = np.abs(p) - rho
    u = E.sensitive_component(z.real, z.imag, t, direction=psi0, rotating=True)
    assert np.abs(u - radial).max() < 1e-5
    # a perfectly round artefact read by a fixed probe at alpha: the fixed component
    alpha = np.deg2rad([15.0, 200.0])
    read = _readings(lambda v: 0.0 * v, z.real[None], z.imag[None], alpha, t)[0]
    fixed = E.sensitive_component(z.real, z.imag, t, direction=alpha)
    assert fixed.shape == (2, 128) and np.abs(read - fixed).max() < 1e-5
    # a centring error (a once-per-revolution motion turning with the artefact, e^{-i theta})
    # is a constant along the rotating direction, and would be twice per revolution along
    # the direction theta + alpha
    ecc = 0.8 * np.exp(1j * (0.3 - t))
    u_rot = E.sensitive_component(ecc.real, ecc.imag, t, direction=0.4, rotating=True)
    assert np.ptp(u_rot) < 1e-12
    against = ecc.real * np.cos(t + 0.4) + ecc.imag * np.sin(t + 0.4)
    assert np.ptp(against) > 1.5


# ------------------------------------------------------------------ the whole path


@pytest.mark.parametrize("n_probes", [3, 5])
def test_a_file_of_the_physical_model_gives_the_true_roundness_and_error_motion(tmp_path,
                                                                              n_probes):
    """What notebook 07 does, on a file written from the physical model (probes off the grid,
    sample angles from 3 deg): the roundness and the ISO 230-7 values of the truth, within what
    the noise allows."""
    rng = np.random.default_rng(20 + n_probes)
    c = _case(n_probes, rng, n=360, n_rev=6, noise=0.004)
    df = pd.DataFrame({"revolution": np.repeat(np.arange(1, 7), 360),
                       "angle_deg": np.tile(np.rad2deg(c["theta"]), 6)})
    for j, a in enumerate(LAYOUTS[n_probes]):
        df[f"probe_{a:g}_um"] = np.round(c["y"][:, j].ravel(), 5)
    path = tmp_path / "mine.csv"
    df.to_csv(path, index=False)
    data = F.read_probe_file(path)
    np.testing.assert_allclose(data.theta, c["theta"], atol=1e-9)
    s = P.separate_probe_data(data)
    truth = _form(c["coefs"])(c["theta"])
    pred = P.profile_noise_rms(s.amplification, n_samples=360, noise_sd=c["noise"],
                                n_revolutions=6)
    for f in (roundness.lsc_roundness, roundness.mz_roundness):
        assert abs(f(s.profile)[0] - f(truth)[0]) <= 10 * pred + 1e-3
    fixed = E.fixed_directions(data, [])
    np.testing.assert_allclose(fixed, c["phi"])
    got, _ = E.error_motion_table(s.dx, s.dy, data.theta, fixed_directions=fixed,
                                  rotating_direction=0.5)
    want, _ = E.error_motion_table(c["z"].real, c["z"].imag, c["theta"], fixed_directions=fixed,
                                   rotating_direction=0.5)
    g = np.column_stack([np.cos(c["phi"]), np.sin(c["phi"])])
    per_sample = c["noise"] * np.sqrt(np.linalg.inv(g.T @ g).diagonal().max())
    sync_bound = 6 * (per_sample / np.sqrt(6) + pred) + 1e-3
    assert np.all(np.abs(got.synchronous_um - want.synchronous_um) <= sync_bound)
    # the noise widens the band of the revolutions, by at most a few of its own sizes
    assert np.all(got.asynchronous_um >= want.asynchronous_um - sync_bound)
    assert np.all(got.asynchronous_um <= want.asynchronous_um + 8 * per_sample + sync_bound)
    with pytest.raises(ValueError, match=r"no probe of .*mine.csv is mounted at 45 deg"):
        E.fixed_directions(data, [45.0])


# ------------------------------------------------------------------ the probe file


N_FILE = 64


def _good_text(angles=(0.0, 38.5, 97.0, 221.0), n=N_FILE, n_rev=3, scale=1.0, offsets=None):
    """A correct probe file (text) made with the physical model."""
    rng = np.random.default_rng(1)
    t = TWO_PI * np.arange(n) / n
    coefs = [(3, 0.4, 0.1), (5, -0.2, 0.3), (1, 1.0, 0.0)]
    z = 0.1 * np.exp(2j * t)[None] + 0.02 * rng.standard_normal((n_rev, n))
    y = _readings(_form(coefs), z.real, z.imag, np.deg2rad(angles), t)
    y = y + (np.asarray(offsets)[None, :, None] if offsets is not None else 0)
    df = pd.DataFrame({"revolution": np.repeat(np.arange(1, n_rev + 1), n),
                       "angle_deg": np.tile(360 * np.arange(n) / n, n_rev)})
    for j, a in enumerate(angles):
        df[D.probe_column(a)] = np.round(y[:, j].ravel() * scale, 6)
    return df.to_csv(index=False, lineterminator="\n")


def _write(tmp_path, text, name="probes.csv"):
    path = tmp_path / name
    path.write_bytes(text.encode("utf-8") if isinstance(text, str) else text)
    return path


def _edit_line(text, line, new):
    lines = text.split("\n")
    lines[line - 1] = new(lines[line - 1])
    return "\n".join(lines)


def _set_field(text, line, column, value):
    return _edit_line(text, line, lambda s: ",".join(
        value if i == column else f for i, f in enumerate(s.split(","))))


def test_a_good_file_is_read_with_its_geometry(tmp_path):
    d = F.read_probe_file(_write(tmp_path, _good_text()))
    assert d.signals_um.shape == (3, 4, N_FILE) and d.n_probes == 4
    np.testing.assert_allclose(d.angles_deg, [0, 38.5, 97, 221])
    np.testing.assert_allclose(d.sample_deg, 360 * np.arange(N_FILE) / N_FILE)
    assert list(d.revolutions) == [1, 2, 3] and d.max_harmonic == (N_FILE - 1) // 2
    assert d.cancelled == () and d.ignored_columns == () and d.header_line == 1


def test_extra_columns_blank_lines_and_a_bom_are_fine(tmp_path):
    text = _good_text().replace("angle_deg,", "angle_deg,time_s,", 1)
    text = "\n".join(s if i == 0 else s.replace(",", ",0.5,", 2).replace(",0.5,", ",", 1)
                     if s else s for i, s in enumerate(text.split("\n")))
    text = "\n" + text.replace("\n2,", "\n\n2,", 1)
    d = F.read_probe_file(_write(tmp_path, "\ufeff" + text))
    assert d.ignored_columns == ("time_s",) and d.signals_um.shape == (3, 4, N_FILE)


def _drop_columns(text, names):
    df = pd.read_csv(io.StringIO(text))
    return df.drop(columns=names).to_csv(index=False, lineterminator="\n")


def _header(text, new):
    return _edit_line(text, 1, lambda s: new)


def _two_probes(t):
    return _drop_columns(t, ["probe_97_um", "probe_221_um"])


def _in_mm_named(t):
    return t.replace("probe_38.5_um", "probe_38.5_mm", 1)


def _misnamed(t):
    return t.replace("probe_97_um", "probe97_um", 1)


def _values_in_mm(t):
    df = pd.read_csv(io.StringIO(t))
    for c in df.columns[2:]:
        df[c] = (df[c] - df[c].mean()) / 1000
    return df.to_csv(index=False, lineterminator="\n")


def _values_in_nm(t):
    df = pd.read_csv(io.StringIO(t))
    for c in df.columns[2:]:
        df[c] = (df[c] + 40.0) * 1000
    return df.to_csv(index=False, lineterminator="\n")


def _drop_row(line):
    return lambda t: "\n".join(s for i, s in enumerate(t.split("\n")) if i != line - 1)


def _swap_angles(t):
    lines = t.split("\n")
    a, b = lines[9].split(","), lines[10].split(",")
    a[1], b[1] = b[1], a[1]
    lines[9], lines[10] = ",".join(a), ",".join(b)
    return "\n".join(lines)


def _decreasing(t):
    df = pd.read_csv(io.StringIO(t))
    df["angle_deg"] = -df["angle_deg"]
    return df.to_csv(index=False, lineterminator="\n")


def _cumulative(t):
    df = pd.read_csv(io.StringIO(t))
    df["angle_deg"] = df["angle_deg"] + 360.0 * (df["revolution"] - 1)
    return df.to_csv(index=False, lineterminator="\n")


def _radians(t):
    df = pd.read_csv(io.StringIO(t))
    df["angle_deg"] = np.deg2rad(df["angle_deg"])
    return df.to_csv(index=False, lineterminator="\n")


def _with_360(t):
    df = pd.read_csv(io.StringIO(t))
    df["angle_deg"] = df["angle_deg"] * N_FILE / (N_FILE - 1)
    return df.to_csv(index=False, lineterminator="\n")


def _semicolon(t):
    return t.replace(",", ";")


def _decimal_commas(t):
    return _semicolon(t).replace(".", ",")


def _out_of_order(t):
    lines = t.split("\n")
    lines[1 + N_FILE:1 + 2 * N_FILE], lines[1 + 2 * N_FILE:1 + 3 * N_FILE] = \
        lines[1 + 2 * N_FILE:1 + 3 * N_FILE], lines[1 + N_FILE:1 + 2 * N_FILE]
    return "\n".join(lines)


HEAD = 1                          # the header's line
R2 = 2 + N_FILE                   # the first line of revolution 2

BAD_FILES = [
    ("missing probe column", _two_probes, HEAD, r"2 probe column\(s\) \['probe_0_um', "
                                                r"'probe_38.5_um'\]; at least 3"),
    ("probe column in mm", _in_mm_named, HEAD, r"'probe_38.5_mm'.* is in mm: multiply the "
                                               r"values by 1000 and rename it 'probe_38.5_um'"),
    ("misnamed probe column", _misnamed, HEAD, r"'probe97_um' is not named "
                                               r"probe_<mounting angle in degrees>_um"),
    ("missing revolution", lambda t: t.replace("revolution", "rev", 1), HEAD,
     r"missing column 'revolution' \('rev' found"),
    ("angle in radians named", lambda t: t.replace("angle_deg", "angle_rad", 1), HEAD,
     r"missing column 'angle_deg' \('angle_rad' found.*angles in degrees"),
    ("duplicate angle", lambda t: t.replace("probe_221_um", "probe_360_um", 1), HEAD,
     r"'probe_0_um' and 'probe_360_um' name the same mounting angle"),
    ("probe angles in radians", lambda t: _header(t, "revolution,angle_deg,probe_0_um,"
                                                  "probe_0.67_um,probe_1.69_um,probe_3.86_um"),
     HEAD, r"all lie within 0..2 pi: radians"),
    ("layout cancels harmonics", lambda t: _header(t, "revolution,angle_deg,probe_0_um,"
                                                   "probe_90_um,probe_180_um,probe_270_um"),
     HEAD, r"probes at 0, 90, 180, 270 deg cannot separate harmonic\(s\) 3, 5, 7, .*move a "
           r"probe.*allow_cancelled=True"),
    ("tabs", lambda t: t.replace(",", "\t"), HEAD, r"the header is tab-separated"),
    ("unquoted decimal comma", lambda t: _set_field(t, 5, 3, "1,5"), 5,
     r"7 fields, but the header names 6 columns; decimal commas \(1,5\)\? In a "
     r"comma-separated file write decimal points \(1.5\), or save the file semicolon-separated"),
    ("NaN in a semicolon file", lambda t: _edit_line(_decimal_commas(t), 9, lambda s: ";".join(
        "NaN" if i == 4 else f for i, f in enumerate(s.split(";")))), 9,
     r"'probe_97_um' has a missing, NaN"),
    ("quoted decimal comma", lambda t: _set_field(t, 7, 3, '"1,5"'), 7,
     r"'probe_38.5_um' has a missing, NaN, infinite or non-numeric value \('1,5'\).*decimal "
     r"commas"),
    ("NaN", lambda t: _set_field(t, 9, 4, "NaN"), 9, r"'probe_97_um' has a missing, NaN"),
    ("empty cell", lambda t: _set_field(t, 11, 2, ""), 11, r"'probe_0_um' has a missing"),
    ("text", lambda t: _set_field(t, 12, 1, "twelve"), 12, r"'angle_deg' .*\('twelve'\)"),
    ("inf", lambda t: _set_field(t, 13, 4, "inf"), 13, r"'probe_97_um' has a missing, NaN, "
                                                       r"infinite"),
    ("values in mm", _values_in_mm, HEAD, r"'probe_0_um' spans only .* less than the 0.01 um.*"
                                          r"in mm\? \(um = mm x 1000\)"),
    ("values in nm", _values_in_nm, 2, r"'probe_0_um' reads .* beyond \+-10000 um.*in nm\?"),
    ("unequal samples per revolution", _drop_row(R2 + 5), R2,
     rf"unequal samples per revolution: revolution 2 \(lines {R2}-{R2 + N_FILE - 2}\) has "
     rf"{N_FILE - 1} samples, revolution 1 \(lines 2-{N_FILE + 1}\) has {N_FILE}"),
    ("non-monotonic angles", _swap_angles, 11, r"angle_deg must increase within a revolution: "
                                               r".* \(line 10\) in revolution 1$"),
    ("decreasing angles", _decreasing, 3,
     r"write it negated \(modulo 360\), keep the probes' angles as mounted"),
    ("not equally spaced", lambda t: _set_field(t, 20, 1, "104"), 20,
     r"not equally spaced .* 104 deg where 64 samples from 0 deg \(line 2\), .* put sample 19 "
     r"at 101.25 deg"),
    ("the 360 deg sample repeated", _with_360, N_FILE + 1, r"the last sample of revolution 1 "
                                                           r"\(360 deg\) repeats its first "
                                                           r"\(0 deg, line 2\).*drop the"),
    ("angles in radians", _radians, 3, r"radians\? \(deg = rad x 180 / pi\)"),
    ("angles counting on", _cumulative, R2, r"revolution 2 has sample 1 at 360 deg where "
                                            r"revolution 1 has it at 0 deg .*modulo 360"),
    ("revolutions out of order", _out_of_order, R2 + N_FILE, r"revolution 2 comes after "
                                                             r"revolution 3"),
    ("too many fields", lambda t: _edit_line(t, 30, lambda s: s + ",7"), 30,
     r"7 fields, but the header names 6 columns$"),
    ("not utf-8", lambda t: t.encode("utf-8").replace(b"probe_0_um", b"probe_0_\xb5m", 1), 1,
     r"not UTF-8 text \(byte 0xb5\)"),
    ("fractional revolution", lambda t: _set_field(t, 4, 0, "1.5"), 4,
     r"revolution 1.5 is not a whole number"),
    ("no data rows", lambda t: t.split("\n")[0] + "\n", HEAD, r"a header but no data rows"),
]


@pytest.mark.parametrize("edit, line, message", [b[1:] for b in BAD_FILES],
                         ids=[b[0] for b in BAD_FILES])
def test_a_bad_file_is_refused_naming_the_file_and_the_line(tmp_path, edit, line, message):
    path = _write(tmp_path, edit(_good_text()), name="my probes.csv")
    with pytest.raises(D.ProbeFileError) as info:
        F.read_probe_file(path)
    text = str(info.value)
    assert text.startswith(f"{path}, line {line}: "), text
    assert info.value.line == line and info.value.path == str(path)
    assert re.search(message, text), text


def test_a_semicolon_file_with_decimal_commas_reads_as_the_comma_file(tmp_path):
    good = F.read_probe_file(_write(tmp_path, _good_text(), name="comma.csv"))
    text = _decimal_commas(_good_text()) + ";;;;;\n;;;;;\n"        # a spreadsheet's empty rows
    assert "probe_38,5_um" in text and "1,40625" not in text and ";5,625;" in text
    for name, body in (("semicolon.csv", text), ("points.csv", _semicolon(_good_text()))):
        d = F.read_probe_file(_write(tmp_path, body, name=name))
        assert d.columns == good.columns
        np.testing.assert_array_equal(d.signals_um, good.signals_um)
        np.testing.assert_array_equal(d.sample_deg, good.sample_deg)
    bad = _edit_line(text, 40, lambda s: s.replace(";", ";x", 1))
    with pytest.raises(D.ProbeFileError, match=r", line 40: column 'angle_deg' .*'x"):
        F.read_probe_file(_write(tmp_path, bad, name="bad.csv"))


def test_line_numbers_count_blank_lines_and_windows_line_ends(tmp_path):
    text = _set_field(_good_text(), 9, 4, "NaN")
    text = text.replace("\n", "\n\n", 3).replace("\n", "\r\n")           # 3 blank lines early
    with pytest.raises(D.ProbeFileError, match=r", line 12: column 'probe_97_um'"):
        F.read_probe_file(_write(tmp_path, text))


def test_size_limits_and_a_missing_file(tmp_path, monkeypatch):
    path = _write(tmp_path, _good_text())
    monkeypatch.setattr(F, "MAX_ROWS", 100)
    with pytest.raises(D.ProbeFileError, match=r", line 102: more than 100 data rows"):
        F.read_probe_file(path)
    monkeypatch.setattr(F, "MAX_FILE_BYTES", 1000)
    with pytest.raises(D.ProbeFileError, match=r"probes.csv: \d+ bytes; files up to 1000"):
        F.read_probe_file(path)
    with pytest.raises(D.ProbeFileError, match="nothing.csv: file not found"):
        F.read_probe_file(tmp_path / "nothing.csv")
    short = _write(tmp_path, _good_text(n=6), name="short.csv")
    with pytest.raises(D.ProbeFileError, match=r"line 2: 6 samples per revolution; 8..16384"):
        F.read_probe_file(short)


def test_max_harmonic_and_a_cancelling_layout_allowed(tmp_path):
    path = _write(tmp_path, _good_text())
    with pytest.raises(D.ProbeFileError, match=r"max_harmonic must be an integer in "
                                                r"\[2, 31\], got 32 \(the top is \(N - 1\) // 2"):
        F.read_probe_file(path, max_harmonic=32)
    assert F.read_probe_file(path, max_harmonic=10).max_harmonic == 10
    square = _write(tmp_path, _good_text(angles=(0.0, 90.0, 180.0, 270.0)), name="sq.csv")
    with pytest.warns(S.CancelledHarmonicsWarning, match=r"sq.csv, line 1: .*cannot separate") \
            as caught:
        d = F.read_probe_file(square, allow_cancelled=True)
    assert caught[0].filename == __file__          # the warning points at the reader's caller
    assert d.cancelled == tuple(range(3, 32, 2))
    # no second CancelledHarmonicsWarning; the motion is white to the top harmonic (aliasing)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        s = P.separate_probe_data(d)
    assert [w.category for w in caught] == [S.AliasingWarning]
    assert s.cancelled == list(range(3, 32, 2))
    # every even harmonic is there: the 2-per-rev motion and the 5-lobe form are not, the
    # odd ones: the third and fifth harmonics of the form are lost
    assert np.abs(np.fft.rfft(s.profile)[[3, 5]]).max() < 1e-9
    # max_harmonic below the first cancelled one: nothing to refuse
    assert F.read_probe_file(square, max_harmonic=2).cancelled == ()


# ------------------------------------------------------------------ the shipped example


EXAMPLE = ROOT / "data" / "spindle"


def test_the_shipped_example_is_what_its_generator_makes_and_is_labelled_simulated(tmp_path):
    record = X.write_example(tmp_path)
    committed = json.loads((EXAMPLE / "provenance.json").read_text())
    assert committed["what"].startswith("SIMULATED") and committed["setup"] == json.loads(
        json.dumps(record["setup"]))
    for key in ("probes", "truth"):
        name = X.EXAMPLE_FILES[key]
        assert hashlib.sha256((EXAMPLE / name).read_bytes()).hexdigest() \
            == committed["sha256"][name]
        ours = pd.read_csv(tmp_path / name)
        theirs = pd.read_csv(EXAMPLE / name)
        assert list(ours.columns) == list(theirs.columns)
        # the same numbers, to one unit of the last written decimal (another libm may round a
        # last digit the other way)
        np.testing.assert_allclose(ours.to_numpy(), theirs.to_numpy(), rtol=0, atol=1.01e-4)
    assert "SIMULATED" in (EXAMPLE / "README.md").read_text()
    assert (EXAMPLE / X.EXAMPLE_FILES["probes"]).stat().st_size < 300_000


def test_the_example_separates_to_its_truth_and_is_recognised_by_content(tmp_path):
    probes = EXAMPLE / X.EXAMPLE_FILES["probes"]
    d = F.read_probe_file(probes)
    truth = X.match_example(probes, EXAMPLE)
    assert truth is not None
    copy = shutil.copy(probes, tmp_path / "renamed.csv")
    assert X.match_example(copy, EXAMPLE) is not None                  # by content, not name
    (tmp_path / "renamed.csv").write_text(probes.read_text().replace("1,0,", "1,0.0,", 1))
    assert X.match_example(tmp_path / "renamed.csv", EXAMPLE) is None
    n = d.n_samples
    true_profile = truth.profile_um.to_numpy()[:n]
    noise = X.EXAMPLE_SETUP["noise_um"]
    for method in ("least_squares", "weighted"):
        s = P.separate_probe_data(d, method=method)
        err = _without_01(s.profile) - _without_01(true_profile)
        pred = P.profile_noise_rms(s.amplification, n_samples=n, noise_sd=noise,
                                    n_revolutions=d.n_revolutions)
        assert np.sqrt((err ** 2).mean()) < 1.3 * pred + 3e-5          # + the 1e-4 rounding
        mz_true = roundness.mz_roundness(_without_01(true_profile))[0]
        assert abs(roundness.mz_roundness(_without_01(s.profile))[0] - mz_true) < 0.02


def test_the_amplification_is_the_same_after_a_rounding_level_change():
    """Another CPU's BLAS kernel moves the noise amplification by about 1e-14 relative (the
    singular values, the weights' search); reported to AMPLIFICATION_DIGITS it does not move."""
    c = _case(4, np.random.default_rng(3))
    phi = c["phi"]
    nudged = phi * (1 + 1e-15 * np.array([1, -1, 1, -1]))
    ks = np.arange(2, (c["n"] - 1) // 2 + 1)
    for method in ("least_squares", "weighted"):
        s, t = (P.separate_probes(c["y"], f, method=method) for f in (phi, nudged))
        assert np.array_equal(s.amplification, t.amplification)
        exact = P.noise_amplification(phi, ks, weights=s.weights)
        assert np.abs(s.amplification / exact - 1).max() < 5e-8


def test_the_docstring_geometry_is_the_readme_geometry():
    text = (EXAMPLE / "README.md").read_text()
    assert "r(theta + phi) + x(theta) cos(phi) + y(theta) sin(phi)" in text
    assert "r(theta + phi) + x(theta) cos(phi) + y(theta) sin(phi)" in P.__doc__
