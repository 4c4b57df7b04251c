"""The ISO 230-7 / ISO 12181-2 low-pass filter in undulations per revolution (``max_upr``), the
separated motion per sample and the spectrum of its asynchronous part (notebook 07's
``error_motion.csv`` and ``asynchronous_spectrum.csv``).

The data come from this file's own model: an artefact and a spindle motion given by their
harmonics and fractional frequencies, probes off the sample grid, readings computed exactly
(``r(theta + phi) + x cos(phi) + y sin(phi)``), white probe noise.
"""

import warnings

import numpy as np
import pytest

from mtaccuracy import roundness
from mtaccuracy.spindle import errormotion as E
from mtaccuracy.spindle import probes as P

TWO_PI = 2 * np.pi
PHI = np.deg2rad([0.0, 38.5, 97.0, 221.0])


def _measure(rng, *, n=512, n_rev=8, noise=0.01):
    """Readings (R, 4, N) and the true motion (R, N): an artefact of harmonics 2..12, a
    synchronous motion of harmonics 2 and 3, an asynchronous motion at 1.5 and 6.25 cycles per
    revolution (0.04 um along x, a 0.02 um circular whirl)."""
    theta = TWO_PI * np.arange(n) / n
    t = (np.arange(n_rev)[:, None] * n + np.arange(n)[None, :]) / n          # revolutions
    z = (0.05 * np.exp(2j * theta) + 0.02 * np.exp(-3j * theta))[None, :] \
        + 0.04 * np.cos(TWO_PI * 1.5 * t) + 0.02 * np.exp(1j * (TWO_PI * 6.25 * t + 0.5))
    ks = np.arange(2, 13)
    a, b = 0.4 * rng.standard_normal((2, ks.size)) / ks
    u = theta[None, None, :] + PHI[None, :, None]
    form = (a[:, None, None, None] * np.cos(ks[:, None, None, None] * u)
            + b[:, None, None, None] * np.sin(ks[:, None, None, None] * u)).sum(0)
    y = form + z.real[:, None, :] * np.cos(PHI)[:, None] + z.imag[:, None, :] * np.sin(PHI)[
        :, None]
    return y + noise * rng.standard_normal(y.shape), z, theta


def test_the_gaussian_filter_passes_half_at_the_cutoff_and_all_at_zero():
    assert roundness.gaussian_transmission(50.0, cutoff=50.0) == pytest.approx(0.5, rel=1e-12)
    assert roundness.gaussian_transmission(0.0, cutoff=50.0) == 1.0
    assert roundness.gaussian_transmission(150.0, cutoff=50.0) == pytest.approx(0.5 ** 9)
    n = 256
    t = TWO_PI * np.arange(n) / n
    profile = np.cos(15 * t) + 0.5 * np.sin(2 * t)
    out = roundness.upr_filter(profile, max_upr=15)
    np.testing.assert_allclose(out, 0.5 * np.cos(15 * t) + 0.5 * 0.5 ** (4 / 225) * np.sin(2 * t),
                               atol=1e-12)
    np.testing.assert_array_equal(roundness.upr_filter(profile, max_upr=0), profile)
    # a record over 4 revolutions: 2.5 cycles per revolution pass by a(2.5)
    rec = np.cos(TWO_PI * 2.5 * np.arange(4 * n) / n).reshape(4, n)
    np.testing.assert_allclose(roundness.upr_filter(rec, max_upr=5.0, continuous=True),
                               0.5 ** 0.25 * rec, atol=1e-12)
    with pytest.raises(ValueError, match="max_upr must be 0"):
        roundness.upr_filter(profile, max_upr=-1)


def test_the_filter_stops_the_probes_noise_inflating_the_asynchronous_value():
    rng = np.random.default_rng(1)
    y, z, theta = _measure(rng)
    with warnings.catch_warnings():
        warnings.simplefilter("error")                   # a well-sampled file: no warning
        s = P.separate_probes(y, PHI)
    z_true = z - z.mean()
    kw = dict(fixed_directions=[0.0], rotating_direction=0.0)

    def asyn(dx, dy, upr):
        return E.error_motion_table(dx, dy, theta, max_upr=upr, **kw)[0].asynchronous_um.to_numpy()

    truth, raw = asyn(z_true.real, z_true.imag, 0), asyn(s.dx, s.dy, 0)
    truth50, filt = asyn(z_true.real, z_true.imag, 50), asyn(s.dx, s.dy, 50)
    # unfiltered, the noise (0.01 um, white to 256 UPR) widens the band well beyond the truth
    assert np.all(raw - truth > 0.02)
    # at 50 UPR the motion (below 7 UPR) passes whole and the noise above 50 UPR is cut: what
    # stays is the noise below it, sqrt(50 / 256) of it
    np.testing.assert_allclose(truth50, truth, rtol=0.02)
    assert np.all(np.abs(filt - truth50) < 0.4 * (raw - truth))
    assert np.all(np.abs(filt - truth50) < 0.015)


def test_the_motion_table_and_the_asynchronous_spectrum_against_the_truth():
    rng = np.random.default_rng(2)
    y, z, theta = _measure(rng, noise=0.002)
    s = P.separate_probes(y, PHI)
    r, n = s.dx.shape
    table = E.error_motion_samples(s.dx, s.dy, revolutions=np.arange(1, r + 1),
                                   angle_deg=np.rad2deg(theta))
    assert list(table.columns) == ["revolution", "angle_deg", "x_um", "y_um"]
    assert len(table) == r * n and table.revolution.iloc[n] == 2
    assert table.angle_deg.iloc[n + 3] == pytest.approx(360 * 3 / n)
    np.testing.assert_allclose(table.x_um.to_numpy().reshape(r, n), s.dx)
    spec = E.asynchronous_spectrum(s.dx, s.dy)
    assert list(spec.columns) == ["frequency_cpr", "amplitude_um"]
    assert len(spec) == r * n // 2 + 1
    np.testing.assert_allclose(np.diff(spec.frequency_cpr), 1 / r)
    f, a = spec.frequency_cpr.to_numpy(), spec.amplitude_um.to_numpy()
    assert np.all(a[::r] == 0.0)                                 # integer: synchronous only
    top = set(np.round(f[np.argsort(a)[-2:]], 6))
    assert top == {1.5, 6.25}
    # 0.04 um along x reads 0.04; a circular whirl of 0.02 um reads sqrt(2) 0.02
    assert a[f == 1.5][0] == pytest.approx(0.04, abs=0.002)
    assert a[f == 6.25][0] == pytest.approx(np.sqrt(2) * 0.02, abs=0.002)
    # the truth's spectrum: the same peaks, and nothing else
    tz = z - z.mean(axis=0)
    truth = E.asynchronous_spectrum(tz.real, tz.imag).amplitude_um.to_numpy()
    assert np.abs(np.delete(truth, np.searchsorted(f, [1.5, 6.25]))).max() < 1e-12
    with pytest.raises(ValueError, match="R >= 2"):
        E.asynchronous_spectrum(s.dx[:1], s.dy[:1])
