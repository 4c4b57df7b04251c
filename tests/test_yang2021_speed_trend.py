"""What sets the simulated experiment's trends with speed (issue 34): a model of our own.

A three-lobed mandrel, A cos 3θ, has a minimum-zone roundness of exactly 2A; the four-point
weights cancel every rigid motion of the spindle, synchronous or not, at every instant.  So
without probe noise every campaign reads 2A with no scatter, the asynchronous motion changes
nothing, and with noise the scatter falls as one over the root of the revolutions averaged.
"""

import numpy as np
import pytest

from mtaccuracy import spindle as SP
from mtaccuracy.papers import yang2021

N = 48                                         # every extremum of cos 3θ on a sample
THETA = 2 * np.pi * np.arange(N) / N
A_MM = 2e-3                                    # lobe amplitude: roundness 2A = 4 um
LAYOUT = SP.grid_layout(np.array([0.5, 2.5, 5.0, 1.2]), N)
SETTINGS = dict(duration_s=1.0, interleave=2, async_sd_600=3e-4, async_exponent=1.0,
                noise_sd=1e-4, n_measurements=40, lowpass_harmonic=10, first_harmonic="radial")


def _campaigns(variants, speeds=(600, 2400)):
    profile = A_MM * np.cos(3 * THETA)
    dx, dy = 1e-3 * np.cos(2 * THETA), 5e-4 * np.sin(2 * THETA)   # synchronous motion (mm)
    return yang2021.speed_trend_sources(profile, dx, dy, LAYOUT, speeds=list(speeds),
                                        variants=variants, seed=3, **SETTINGS)


def test_without_noise_every_speed_reads_the_true_roundness_whatever_the_motion():
    t = _campaigns({"quiet": dict(noise_sd=0.0, n_measurements=3),
                    "quiet, wild motion": dict(noise_sd=0.0, async_sd_600=5e-3,
                                               async_exponent=3.0, n_measurements=3)})
    assert t.mz_mean_um.to_numpy() == pytest.approx(2 * A_MM * 1e3, abs=1e-9)
    assert t.mz_std_um.max() < 1e-9
    assert t.revolutions.tolist() == [10, 40, 10, 40]


def test_the_asynchronous_motion_changes_nothing_and_fixed_revolutions_flatten_the_trend():
    t = _campaigns({"as set": {}, "no motion": dict(async_sd_600=0.0),
                    "10 revolutions": dict(duration_s=lambda n: 10.5 * 60 / n, n_measurements=5)})
    by = t.set_index(["variant", "speed_rpm"])
    # common random numbers: the motion is cancelled, so the two read the same to round-off
    assert by.loc["as set"].mz_std_um.to_numpy() == pytest.approx(
        by.loc["no motion"].mz_std_um.to_numpy(), rel=1e-9)
    fixed = by.loc["10 revolutions"].mz_std_um.to_numpy()
    assert fixed[1] == pytest.approx(fixed[0], rel=1e-9)      # the speed enters nowhere else
    assert by.loc["10 revolutions"].revolutions.tolist() == [10, 10]
    # 4 times the revolutions: the scatter halves (the noise enters linearly); the sample
    # standard deviation of 40 campaigns has a relative standard error ~ 1 / sqrt(78) = 11 %,
    # 16 % for the ratio of two, so it lies in 0.5 (1 +- 0.4) at 2.5 of them
    ratio = by.loc[("as set", 2400), "mz_std_um"] / by.loc[("as set", 600), "mz_std_um"]
    assert 0.3 < ratio < 0.7
