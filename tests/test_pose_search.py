"""The pose search of notebook 01 (papers.zheng2024): symmetry group of the linear indices,
canonical pose, canonical ranking of optimiser output, least-squares fit of a known pose."""

import numpy as np
import pandas as pd
import pytest

from mtaccuracy import sensitivity as S
from mtaccuracy.machines import build
from mtaccuracy.papers.zheng2024 import (
    POSE_SYMMETRIES,
    canonical_pose,
    fit_pose_average_to_indices,
    fit_pose_to_indices,
    index_invariants,
    pose_orbit,
    rank_poses,
    ratio_interval,
)

M = build("ac_double_turntable")
SD = np.array([5e-3 if e.translational else 1.6e-5 for e in M.catalogue])
RNG = np.random.default_rng(11)
AXES = ("x", "y", "z", "A", "C")


def indices(pose):
    """(P, 6, 41): components x errors, as the paper's Table 2 and zheng2024's rows, cols."""
    return S.linear_indices(M.jacobian(pose), sd=SD).swapaxes(-1, -2)


def random_pose(rng=RNG):
    return dict(x=rng.uniform(-380, 380), y=rng.uniform(-400, 400), z=rng.uniform(-260, 260),
                A=rng.uniform(-2.2, 2.2), C=rng.uniform(0, 2 * np.pi))


def test_every_member_of_the_orbit_has_the_same_indices():
    for _ in range(3):
        pose = random_pose()
        orbit = pose_orbit(pose)
        assert len(POSE_SYMMETRIES) == 32 and orbit["x"].shape == (32,)
        s = indices(orbit)
        assert np.abs(s - s[0]).max() < 1e-13
        # 32 distinct poses (a generic pose is no fixed point)
        key = np.round(np.c_[[orbit[k] for k in AXES]].T, 9)
        assert len({tuple(r) for r in key}) == 32
        # a map outside the group changes them: x -> -x alone, C -> C + 90 deg
        assert np.abs(indices(dict(pose, x=-pose["x"])) - s[0]).max() > 1e-3
        assert np.abs(indices(dict(pose, C=pose["C"] + np.pi / 2)) - s[0]).max() > 1e-3


def test_the_symmetry_needs_the_tool_tip_at_the_z_carriage():
    pose = dict(random_pose(), L=50.0)
    with pytest.raises(ValueError, match="L = 0"):
        pose_orbit(pose)
    # indeed: with a tool length the z reflection changes the indices
    mirrored = dict(pose, z=-pose["z"], A=-pose["A"])
    assert np.abs(indices(mirrored) - indices(pose)).max() > 1e-4
    assert np.abs(pose_orbit(dict(pose, L=0.0))["x"]).max() > 0


def test_fixed_position_orbit_keeps_x_y_z():
    pose = random_pose()
    orbit = pose_orbit(pose, fixed_position=True)
    assert orbit["x"].shape == (4,)
    for k in "xyz":
        assert np.all(orbit[k] == pose[k])
    s = indices(orbit)
    assert np.abs(s - s[0]).max() < 1e-13


def test_canonical_pose_is_the_same_for_every_member_and_lies_in_the_domain():
    for _ in range(5):
        orbit = pose_orbit(random_pose())
        canon = [canonical_pose({k: orbit[k][i] for k in AXES}) for i in range(32)]
        first = canon[0]
        for c in canon[1:]:
            assert all(abs(c[k] - first[k]) < 1e-9 for k in AXES)
        assert min(first["x"], first["y"], first["z"]) >= 0
        assert -np.pi / 2 < first["A"] <= np.pi / 2 and 0 <= first["C"] < np.pi


def test_canonical_pose_does_not_depend_on_rounding_at_a_symmetry_boundary():
    # x zero up to rounding: its sign must not decide (it would flip C to -C)
    base = dict(x=0.0, y=120.0, z=80.0, A=0.9, C=1.1)
    a = canonical_pose(dict(base, x=+1e-9))
    b = canonical_pose(dict(base, x=-1e-9))
    assert abs(a["C"] - b["C"]) < 1e-12 and abs(a["A"] - b["A"]) < 1e-12
    # C = 0 up to rounding (C = 0 and C = 180 deg are both boundaries of the domain)
    a = canonical_pose(dict(base, x=50.0, C=1e-12))
    b = canonical_pose(dict(base, x=50.0, C=2 * np.pi - 1e-12))
    assert abs(np.angle(np.exp(1j * (a["C"] - b["C"])))) < 1e-9 and a["A"] == b["A"]


def candidates(poses_and_misfits, rng, noise=1e-13):
    """Every orbit member of each pose as an optimiser's output, with rounding noise on the
    pose and on the misfit, in a random order."""
    rows = []
    for pose, misfit in poses_and_misfits:
        orbit = pose_orbit(pose)
        for i in range(32):
            if abs(orbit["A"][i]) > np.deg2rad(130):  # outside the travel: never returned
                continue
            r = {k: orbit[k][i] * (1 + noise * rng.standard_normal()) for k in AXES}
            r["misfit"] = misfit * (1 + noise * rng.standard_normal())
            rows.append(r)
    df = pd.DataFrame(rows)
    return df.iloc[rng.permutation(len(df))].reset_index(drop=True)


def test_rank_poses_merges_symmetric_optima_whatever_the_order_and_noise():
    p1 = dict(x=106.1, y=58.6, z=255.3, A=np.deg2rad(60.7), C=np.deg2rad(123.3))
    p2 = dict(x=88.8, y=238.7, z=196.2, A=np.deg2rad(60.7), C=np.deg2rad(123.3))
    results = []
    for seed in range(4):
        ranked = rank_poses(candidates([(p2, 0.0141456), (p1, 0.0141361)],
                                       np.random.default_rng(seed)))
        assert len(ranked) == 2
        results.append(ranked)
    for r in results:
        assert r.x.iloc[0] == pytest.approx(106.1) and r.C.iloc[0] == pytest.approx(p1["C"])
        assert list(r.n_starts) == list(results[0].n_starts)
        assert np.allclose(r[list(AXES)].to_numpy(), results[0][list(AXES)].to_numpy(),
                           atol=1e-9)


def test_rank_poses_breaks_misfit_ties_by_the_canonical_pose_not_by_noise():
    p1 = dict(x=50.0, y=10.0, z=20.0, A=0.3, C=0.4)
    p2 = dict(x=70.0, y=10.0, z=20.0, A=0.3, C=0.4)
    for first_smaller in (True, False):
        m1, m2 = (1.0, 1.0 + 1e-9) if first_smaller else (1.0 + 1e-9, 1.0)
        df = pd.DataFrame([{**p1, "misfit": m1}, {**p2, "misfit": m2}])
        ranked = rank_poses(df, rtol=1e-6)
        assert list(ranked.x) == [70.0, 50.0]  # tie: the larger x first
        ranked = rank_poses(df, rtol=0.0)
        assert ranked.x.iloc[0] == (50.0 if first_smaller else 70.0)
    with pytest.raises(ValueError, match="lack column"):
        rank_poses(pd.DataFrame({"x": [1.0]}))


def test_fit_recovers_the_canonical_image_of_a_known_pose():
    truth = dict(x=-150.0, y=90.0, z=-200.0, A=np.deg2rad(-55.0), C=np.deg2rad(250.0))
    target_all = indices(truth)[0]
    rows, cols = np.nonzero(target_all > 0.02)
    target = target_all[rows, cols]
    expected = canonical_pose(truth)
    start = np.array([[expected[k] for k in AXES]]) + [[20.0, -15.0, 10.0, 0.05, -0.05]]
    fits = fit_pose_to_indices(M, SD, target, rows=rows, cols=cols, starts=start)
    best = rank_poses(fits).iloc[0]
    assert best.misfit < 1e-9
    for k in AXES:
        assert best[k] == pytest.approx(expected[k], abs=1e-5)
    # A and C alone, x, y, z fixed at the truth (not canonical: only the half-turns apply)
    fits = fit_pose_to_indices(M, SD, target, rows=rows, cols=cols, starts=[[-0.8, 4.0]],
                               free=("A", "C"), fixed={k: truth[k] for k in "xyz"})
    best = rank_poses(fits, fixed_position=True).iloc[0]
    half = canonical_pose(truth, fixed_position=True)
    assert best.misfit < 1e-9 and best.A == pytest.approx(half["A"], abs=1e-7)
    assert best.C == pytest.approx(half["C"], abs=1e-7)
    with pytest.raises(ValueError, match="must split the axes"):
        fit_pose_to_indices(M, SD, target, rows=rows, cols=cols, starts=[[0.0, 0.0]],
                            free=("A", "C"))
    with pytest.raises(ValueError, match="starts must have 5 columns"):
        fit_pose_to_indices(M, SD, target, rows=rows, cols=cols, starts=[[0.0, 0.0]])


# --- necessary conditions: ratios the model fixes at every pose ------------------------------

COMP = ["Px", "Py", "Pz", "Vx", "Vy", "Vz"]
NAMES = M.error_names
VX, VY = COMP.index("Vx"), COMP.index("Vy")
Y_ROT = ["e_yx", "e_yy", "e_yz", "S_xz"]        # rotations about y of the tool chain
Z_ROT = ["e_za", "e_zc", "g_AM"]                # rotations about z of the A and C frames


def random_poses(rng, n, tool=False):
    p = dict(x=rng.uniform(-400, 400, n), y=rng.uniform(-425, 425, n),
             z=rng.uniform(-275, 275, n), A=rng.uniform(-2.27, 2.27, n),
             C=rng.uniform(0, 2 * np.pi, n))
    if tool:
        p["L"] = rng.uniform(0, 300, n)
    return p


def entries(pairs):
    return (np.array([COMP.index(c) for c, _ in pairs]),
            np.array([NAMES.index(s) for _, s in pairs]))


def test_vx_vy_ratio_is_the_same_at_every_pose_tool_length_and_variance():
    # S(e_yx)/S(e_za) in Vx equals that in Vy (both are 1/sin^2 A times the variance
    # ratio): whatever the pose, the tool length and the variances of the errors
    rng = np.random.default_rng(3)
    for tool in (False, True):
        sd = SD * rng.uniform(0.2, 5.0, SD.size)
        s = S.linear_indices(M.jacobian(random_poses(rng, 400, tool)), sd=sd).swapaxes(1, 2)
        j, k = NAMES.index("e_yx"), NAMES.index("e_za")
        q = (s[:, VX, j] / s[:, VX, k]) / (s[:, VY, j] / s[:, VY, k])
        assert np.abs(q - 1).max() < 1e-9
        # while each ratio alone moves with the pose by orders of magnitude
        assert (s[:, VX, j] / s[:, VX, k]).max() > 100 * (s[:, VX, j] / s[:, VX, k]).min()
    # the mean over two poses with different A breaks it: the test can tell
    two = dict(x=np.array([100.0, 300.0]), y=np.array([200.0, 350.0]),
               z=np.array([20.0, 50.0]), A=np.deg2rad([40.0, 80.0]), C=np.deg2rad([60.0, 120.0]))
    s = indices(two).mean(axis=0)
    q = (s[VX, j] / s[VX, k]) / (s[VY, j] / s[VY, k])
    assert abs(q - 1) > 0.02


def test_index_invariants_finds_the_structural_groups_and_cross_ratios():
    pairs = [("Vx", s) for s in Y_ROT + Z_ROT] + [("Vy", s) for s in Y_ROT + Z_ROT] \
        + [("Pz", "d_yx"), ("Pz", "d_za"), ("Px", "d_xc")]
    rows, cols = entries(pairs)
    groups, cross = index_invariants(M, SD, rows=rows, cols=cols,
                                     poses=random_poses(np.random.default_rng(4), 50))
    g = groups.group.to_numpy()
    assert len(set(g[:4])) == 1 and len(set(g[4:7])) == 1 and g[0] != g[4]   # Vx groups
    assert len(set(g[7:11])) == 1 and len(set(g[11:14])) == 1                # Vy groups
    assert len(set(g[14:])) == 3                                             # alone
    assert np.allclose(groups.factor, 1.0)  # equal variances within each kind
    # the cross ratio: (y-rotations / z-rotations) in Vx over the same in Vy, fixed at 1;
    # Pz (d_yx / d_za = sin^2 A) pairs with Vx and Vy too (equal variances within kinds)
    found = {(int(r.num_k), int(r.den_k), int(r.num_l), int(r.den_l)): r.value
             for r in cross.itertuples()}
    assert found[(g[0], g[4], g[7], g[11])] == pytest.approx(1.0, abs=1e-9)
    assert found[(g[0], g[4], g[15], g[14])] == pytest.approx(1.0, abs=1e-9)
    assert len(found) == 3
    # with unequal variances the Vx/Vy quotient stays 1, the Pz one moves
    sd = SD.copy()
    sd[NAMES.index("d_yx")] *= 2.0
    _, cross2 = index_invariants(M, sd, rows=rows, cols=cols,
                                 poses=random_poses(np.random.default_rng(4), 50))
    found2 = {(int(r.num_k), int(r.den_k), int(r.num_l), int(r.den_l)): r.value
              for r in cross2.itertuples()}
    assert found2[(g[0], g[4], g[7], g[11])] == pytest.approx(1.0, abs=1e-9)
    assert found2[(g[0], g[4], g[15], g[14])] == pytest.approx(4.0, rel=1e-9)
    with pytest.raises(ValueError, match="at least 3 poses"):
        index_invariants(M, SD, rows=rows, cols=cols,
                         poses=random_poses(np.random.default_rng(4), 2))


def test_ratio_interval_propagates_the_printed_precision():
    lo, hi = ratio_interval((0.08755, 0.08765), (0.07205, 0.07215))
    assert lo == pytest.approx(0.08755 / 0.07215) and hi == pytest.approx(0.08765 / 0.07205)
    with pytest.raises(ValueError, match="positive"):
        ratio_interval((0.1, 0.2), (0.0, 0.1))


def test_fit_pose_average_recovers_the_mean_of_two_known_poses():
    truth = dict(x=np.array([120.0, 300.0]), y=np.array([200.0, 50.0]),
                 z=np.array([30.0, 150.0]), A=np.deg2rad([35.0, 75.0]),
                 C=np.deg2rad([50.0, 110.0]))
    mean = indices(truth).mean(axis=0)
    rows, cols = np.nonzero(mean > 0.02)
    start = np.stack([np.c_[truth["x"], truth["y"], truth["z"], truth["A"], truth["C"]]])
    start = start + [[10.0, -10.0, 5.0, 0.03, -0.03]]
    fits = fit_pose_average_to_indices(M, SD, mean[rows, cols], rows=rows, cols=cols,
                                       starts=start)
    assert len(fits) == 2 and fits.misfit.max() < 1e-8
    assert list(fits.pose) == [0, 1] and fits.A.iloc[0] >= fits.A.iloc[1]
    # the poses up to the symmetries: sin^2 A and sin^2 C of each
    assert np.sort(np.sin(fits.A) ** 2) == pytest.approx(np.sort(np.sin(truth["A"]) ** 2), abs=1e-6)
    with pytest.raises(ValueError, match="starts must be"):
        fit_pose_average_to_indices(M, SD, mean[rows, cols], rows=rows, cols=cols,
                                    starts=np.zeros((2, 5)))
