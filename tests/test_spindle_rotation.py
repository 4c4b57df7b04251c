"""The sense of rotation (``rotation="cw"``/``"ccw"``): the separation under both, the warning
when the sense is stated wrongly, the rotating sensitive direction, and the aliasing warning.

The data come from this file's own model (:func:`_readings`): an artefact given by its
harmonics (an eccentricity among them), a spindle motion given by complex exponentials
(synchronous, a forward elliptic once-per-revolution whirl, asynchronous at fractional
frequencies), probes at arbitrary angles off the sample grid; every reading is computed exactly
from the harmonics at the probe's own angle, in the sense stated: ``r(theta + phi)`` for cw,
``r(phi - theta)`` for ccw, plus ``x cos(phi) + y sin(phi)``.
"""

import warnings

import numpy as np
import pytest

from mtaccuracy import spindle as S
from mtaccuracy.spindle import checks as C
from mtaccuracy.spindle import errormotion as E
from mtaccuracy.spindle import probes as P

TWO_PI = 2 * np.pi
LAYOUTS = {3: np.deg2rad([0.0, 101.3, 227.9]), 4: np.deg2rad([0.0, 38.5, 97.0, 221.0])}


def _profile(coefs):
    """The artefact's radius deviation at its own angle from ``(k, a, b)``: a cos k + b sin k."""
    return lambda u: sum(a * np.cos(k * u) + b * np.sin(k * u) for k, a, b in coefs)


def _readings(coefs, z, phi, theta, rotation):
    """Exact readings (R, L, N) of probes at ``phi`` (L,), spindle angles ``theta`` (N,), motion
    ``z = x + i y`` (R, N), in the sense given."""
    t, f = theta[None, None, :], phi[None, :, None]
    u = t + f if rotation == "cw" else f - t
    return _profile(coefs)(u) + z.real[:, None, :] * np.cos(f) + z.imag[:, None, :] * np.sin(f)


def _case(rng, *, n_probes=4, n=128, n_rev=4, noise=0.004, ecc=(2.0, -1.1), k_max=30,
          whirl=(0.08, 0.03), rotation="cw", theta0=7.0):
    """Artefact harmonics 2..k_max (~0.3/k um) and a lobed form, an eccentricity (um), a spindle
    motion: synchronous harmonics, a forward elliptic once-per-revolution whirl (semi-axes in
    um, turning with the spindle), asynchronous motion at 2.25 and 5.5 cycles per revolution;
    probe zeros and white noise."""
    theta = TWO_PI * np.arange(n) / n + np.deg2rad(theta0)
    ks = np.arange(2, k_max + 1)
    coefs = [(k, a, b) for k, a, b in zip(ks, *(0.3 * rng.standard_normal((2, ks.size)) / ks),
                                          strict=True)]
    coefs += [(3, 0.3, 0.1), (1, *ecc)]
    s = -1 if rotation == "cw" else 1                    # the spindle turns the artefact by s theta
    a, b = whirl
    sync = 0.5 * (a + b) * np.exp(1j * (s * theta + 0.4)) + 0.5 * (a - b) * np.exp(
        -1j * (s * theta + 0.4))
    sync = sync + 0.06 * np.exp(2j * theta + 1.0) + 0.03 * np.exp(-3j * theta)
    t_rec = (np.arange(n_rev)[:, None] * n + np.arange(n)[None, :]) / n          # revolutions
    asyn = 0.05 * np.cos(TWO_PI * 2.25 * t_rec) + 0.03j * np.sin(TWO_PI * 5.5 * t_rec + 0.3)
    z = sync[None, :] + asyn
    phi = LAYOUTS[n_probes]
    y = _readings(coefs, z, phi, theta, rotation)
    y = y + rng.uniform(-3, 3, (1, n_probes, 1)) + noise * rng.standard_normal(y.shape)
    return dict(coefs=coefs, theta=theta, z=z, phi=phi, y=y, noise=noise, rotation=rotation,
                s=s)


def _without_01(p):
    spec = np.fft.fft(p, axis=-1)
    spec[..., [0, 1, -1]] = 0
    return np.fft.ifft(spec, axis=-1).real


def _separate(c, rotation, **kw):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        s = P.separate_probes(c["y"], c["phi"], rotation=rotation, theta0=c["theta"][0], **kw)
    return s, [w for w in caught if issubclass(w.category, (C.RotationSenseWarning,
                                                             C.AliasingWarning))]


@pytest.mark.parametrize("n_probes", [3, 4])
@pytest.mark.parametrize("rotation", ["cw", "ccw"])
def test_the_right_sense_recovers_profile_and_motion_to_the_noise_bound(rotation, n_probes):
    rng = np.random.default_rng(3 + n_probes)
    c = _case(rng, n_probes=n_probes, rotation=rotation)
    s, warned = _separate(c, rotation)
    assert warned == []
    n, r = c["y"].shape[-1], c["y"].shape[0]
    # the profile at the sample angles, in the probes' frame at theta = 0: r(theta_n)
    truth = _profile(c["coefs"])(c["theta"])
    err = _without_01(s.profile) - _without_01(truth)
    predicted = P.profile_noise_rms(s.amplification, n_samples=n, n_revolutions=r,
                                    noise_sd=c["noise"])
    assert np.sqrt((err ** 2).mean()) < 1.5 * predicted
    # the first harmonic: the eccentricity plus the spindle's co-rotating once-per-rev motion
    grid = TWO_PI * np.arange(n) / n
    z = c["z"] - c["z"].mean()
    co = (z * np.exp(-1j * c["s"] * grid)).mean()
    z = z - co * np.exp(1j * c["s"] * grid)
    ez = (s.dx + 1j * s.dy) - z
    g = np.column_stack([np.cos(c["phi"]), np.sin(c["phi"])])
    per_sample = c["noise"] * np.sqrt(np.trace(np.linalg.inv(g.T @ g)))
    assert np.sqrt((np.abs(ez) ** 2).mean()) < 1.3 * per_sample + 3 * predicted
    # the counter-rotating part of the elliptic whirl stays in the motion: 0.025 um
    counter = (s.dx + 1j * s.dy).mean(axis=0) * np.exp(1j * c["s"] * grid)
    assert abs(counter.mean()) == pytest.approx(0.025, abs=0.003)
    assert s.rotation == rotation and not s.checks.wrong_sense


@pytest.mark.parametrize("rotation", ["cw", "ccw"])
def test_the_wrong_sense_warns_and_names_the_right_one(rotation):
    rng = np.random.default_rng(11)
    c = _case(rng, rotation=rotation)
    other = "ccw" if rotation == "cw" else "cw"
    s, warned = _separate(c, other)
    sense = [w for w in warned if issubclass(w.category, S.RotationSenseWarning)]
    assert len(sense) == 1 and f"the data look like rotation={rotation!r}" in str(sense[0].message)
    # under the wrong sense the centring is a motion turning against the spindle
    assert float(s.checks.counter_rotating) == pytest.approx(np.hypot(2.0, 1.1), rel=0.05)
    # and the wrong sense is not blamed on aliasing
    assert not any(issubclass(w.category, S.AliasingWarning) for w in warned)
    # the misfit of the profile's harmonics read in the wrong sense: far above the noise
    assert P.probe_noise_estimate(s, 4) > 10 * c["noise"]


def test_a_centred_artefact_cannot_tell_the_sense_and_says_nothing():
    rng = np.random.default_rng(5)
    c = _case(rng, ecc=(0.0, 0.0), whirl=(0.0, 0.0))
    for rotation in ("cw", "ccw"):
        s, warned = _separate(c, rotation)
        assert not any(issubclass(w.category, S.RotationSenseWarning) for w in warned)
        assert float(s.checks.counter_rotating) < C.SENSE_SIGNIFICANCE * float(
            s.checks.counter_standard_error)


def test_noise_and_a_strong_elliptic_whirl_do_not_fire_the_sense_check():
    """Correct data: pure noise, and a whirl of 0.5 x 0.05 um (counter part 0.225) on an
    artefact centred to 0.3 um."""
    rng = np.random.default_rng(2)
    for seed in range(20):
        noise = np.random.default_rng(seed).standard_normal((3, 4, 64))
        _, warned = _separate(dict(y=noise, phi=LAYOUTS[4], theta=[0.0]), "cw")
        assert warned == []
    c = _case(rng, ecc=(0.3, 0.0), whirl=(0.5, 0.05), noise=0.01)
    _, warned = _separate(c, "cw")
    assert warned == []


def test_the_ccw_separation_is_the_cw_one_of_the_mirrored_angles():
    """The hint of the brief, checked: ccw readings separated with negated angles under cw give
    r'(u) = r(-u) and y' = -y."""
    rng = np.random.default_rng(8)
    c = _case(rng, rotation="ccw", theta0=0.0, noise=0.0)
    s, _ = _separate(c, "ccw")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = P.separate_probes(c["y"], -c["phi"])
    n = c["y"].shape[-1]
    np.testing.assert_allclose(s.profile, m.profile[-np.arange(n) % n], atol=1e-12)
    np.testing.assert_allclose(s.dy, -m.dy, atol=1e-12)
    np.testing.assert_allclose(s.dx, m.dx, atol=1e-12)


def test_a_bad_rotation_is_refused():
    with pytest.raises(ValueError, match="rotation must be 'cw'"):
        P.separate_probes(np.zeros((1, 3, 16)), LAYOUTS[3], rotation="clockwise")
    with pytest.raises(ValueError, match="rotation must be 'cw' or 'ccw'"):
        E.sensitive_component(np.zeros((1, 8)), np.zeros((1, 8)), np.zeros(8), direction=0.0,
                              rotating=True, rotation="left")


@pytest.mark.parametrize("rotation,s", [("cw", -1), ("ccw", 1)])
def test_a_direction_fixed_to_the_spindle_turns_with_it_in_its_sense(rotation, s):
    theta = TWO_PI * np.arange(64) / 64
    alpha = 0.7
    # a motion of 0.2 um along the spindle-fixed direction alpha + s theta, plus 0.1 across it
    d = np.exp(1j * (alpha + s * theta)) * (0.2 + 0.1j)
    u = E.sensitive_component(d.real[None], d.imag[None], theta, direction=alpha, rotating=True,
                              rotation=rotation)
    np.testing.assert_allclose(u, 0.2, atol=1e-12)
    table, _ = E.error_motion_table(d.real[None], d.imag[None], theta, fixed_directions=[0.0],
                                    rotating_direction=alpha, rotation=rotation)
    assert table.synchronous_um.iloc[-1] < 1e-12


def test_aliasing_warns_and_a_well_sampled_file_does_not():
    rng = np.random.default_rng(4)
    # well sampled: content to harmonic 30, 128 samples a turn
    _, warned = _separate(_case(rng, n=128, k_max=30), "cw")
    assert warned == []
    # 50 samples a turn, content to harmonic 50 (the case), probes off the grid
    c = _case(rng, n=50, k_max=50, noise=0.008)
    s, warned = _separate(c, "cw")
    assert [w.category for w in warned] == [S.AliasingWarning]
    assert "aliasing" in str(warned[0].message) and s.checks.aliased.any()
    assert s.checks.misfit_ratio > C.MISFIT_RATIO
    # on the sample grid and one revolution: only the spectrum can tell, and does
    c = _case(rng, n=48, k_max=48, n_rev=1)
    c["phi"] = TWO_PI * np.array([0, 5, 13, 29]) / 48
    c["y"] = _readings(c["coefs"], c["z"][:1], c["phi"], c["theta"], "cw")
    s, warned = _separate(c, "cw")
    assert [w.category for w in warned] == [S.AliasingWarning]
    assert "has not decayed" in str(warned[0].message)
