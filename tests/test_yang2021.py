"""Notebook 05 (Yang et al. 2021) after the second audit: the inputs of the simulated lathe
experiment and the bases they give, the paper's experimental layout as printed, the GA
settings study (its speed-ups against their definition, its determinism), the declaration's
checks of its parameters and the captions' texts."""

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest

from mtaccuracy import spindle as SP
from mtaccuracy.compendium import reproduction
from mtaccuracy.papers import printed, yang2021
from mtaccuracy.papers.parameters import ParameterError, check


def _facts():
    facts = printed.published("yang2021_facts", ["quantity", "value"])
    return facts.set_index("quantity").value


def test_the_experiment_layout_is_table1s_k20_row():
    genes = yang2021.experiment_genes(_facts())
    t1 = printed.published("yang2021_table1", ["k", "phi1_rad", "a3"]).set_index("k")
    row = t1.loc["20"]
    assert genes == pytest.approx([float(row.phi1_rad), float(row.phi2_rad), float(row.phi3_rad),
                                   float(row.a3)])
    # with Eq. 15's weights the printed layout is far from the printed H = 0.257 at k = 20
    assert SP.objective_H(genes, 20) > 4 * float(t1.loc["20", "H"])
    bad = pd.Series({"experiment_angles": "0.5 3.4", "experiment_a3": "1"})
    with pytest.raises(ValueError, match="3 angles"):
        yang2021.experiment_genes(bad)


def test_a_mandrel_at_the_calibration_value_makes_every_row_using_it_constructed():
    card = reproduction.Card()
    mandrel, sim, sync = yang2021.experiment_inputs(card, 3.0, 3.0)
    card.number("Table 2 (simulated)", "600 r/min: shape error", "2.87", 2.871, "um",
                uses=[mandrel, sim])
    card.statement("Other", "not a target", "x", "x", holds=True, uses=[mandrel, sim])
    card.statement("Table 2 (simulated)", "std falls", "yes", "yes", holds=True, uses=[sim])
    card.statement("Fig. 19 (simulated)", "curves coincide", "coincide", "ratio 0.5", holds=True,
                   uses=[sim, sync])
    bases = [(r["verdict"], r["basis"]) for r in card.rows]
    assert bases == [("reproduced", "constructed"), ("reproduced", "constructed"),
                     ("reproduced", "simulated"), ("not reproducible", "unchecked")]
    assert "synchronous motion" in card.rows[-1]["note"]


def test_a_mandrel_of_another_roundness_is_simulated():
    card = reproduction.Card()
    mandrel, sim, _ = yang2021.experiment_inputs(card, 5.0, 3.0)
    card.number("Table 2 (simulated)", "600 r/min: shape error", "2.87", 4.9, "um",
                uses=[mandrel, sim])
    assert (card.rows[0]["verdict"], card.rows[0]["basis"]) == ("differs", "simulated")


def test_single_run_speedups_by_hand():
    got = yang2021.single_run_speedups([10, 20], [20, 0, 40])
    assert got == pytest.approx([50, 75, 0, 50])


@pytest.mark.parametrize("counts", [[20, 30], [30]])
def test_the_settings_study_against_its_definition(counts):
    box = list(SP.PAPER_BOX[:3]) + [(0.1, 3.0)]
    kw = dict(bounds=box, generation_counts=counts, pc_values=[0.5, 0.9], pm_values=[0.01],
              traditional_pc=0.8, traditional_pm=0.05, generations=20, n_runs=6, pop_size=6,
              encoding="binary", seed=3)
    study = yang2021.ga_settings_study(8, **kw)
    assert len(study) == len(counts) + 2
    by_gen = study[study.study == "generation count"]
    assert by_gen.generations.tolist() == counts
    assert (by_gen.improved_median <= by_gen.generations).all()
    assert (by_gen.traditional_median <= by_gen.generations).all()
    rates = study[study.study == "fixed rates"]
    assert rates[["pc", "pm"]].to_numpy().tolist() == [[0.5, 0.01], [0.9, 0.01]]
    assert rates.improved_median.nunique() == 1 and (rates.generations == 20).all()
    if 20 in counts:      # the improved GA at `generations` is the generation-count run, not rerun
        same = by_gen.improved_median[by_gen.generations == 20].iloc[0]
        assert rates.improved_median.iloc[0] == same
    assert np.allclose(study.speedup_percent,
                       100 * (1 - study.improved_median / study.traditional_median))
    pd.testing.assert_frame_equal(study, yang2021.ga_settings_study(8, **kw))


@pytest.mark.parametrize("change, words", [
    (dict(probe_positions=[1, 14, 65, 116]), r"probe_positions must be 4 distinct .* 0\.\.127"),
    (dict(probe_positions=[0, 14, 14, 116]), "probe_positions must be 4 distinct"),
    (dict(lowpass_harmonic=65), "need lowpass_harmonic <= exp_n_samples / 2"),
    (dict(interleave=3), "need .* and interleave dividing exp_n_samples"),
    (dict(worst_k=64), "worst_k must stay below N/2 = 64"),
    (dict(harmonic_k=81), "need harmonic_k <= k_sweep_max"),
    (dict(pop_size=51), "need .* and an even pop_size"),
])
def test_the_declaration_names_the_parameters_that_contradict_each_other(change, words):
    check(yang2021.Parameters, {})                     # the defaults pass
    with pytest.raises(ParameterError, match=r"^05_yang2021_spindle_four_point_ga: " + words):
        check(yang2021.Parameters, change)


def _section13():
    """The printed Section 1.3 simulation: N = 128, probes 0 14 65 116, a3 = 1.953."""
    n = 128
    t = 2 * np.pi * np.arange(n) / n
    prof = (20 + 1.2 * np.cos(t) - 0.8 * np.sin(t) + 0.2 * np.sin(2 * t) + 0.5 * np.cos(6 * t)
            - 0.8 * np.cos(8 * t))
    delta = 1.3 + 0.6 * np.sin(2 * t + np.pi / 12) - 0.4 * np.cos(12 * t + np.pi / 10)
    positions = [0, 14, 65, 116]
    phi = SP.probe_angles(positions, n)
    return t, prof, delta, positions, phi, SP.full_weights(phi, 1.953)


def test_every_mapping_keeps_the_mean_and_the_radial_pair_is_exact():
    _, prof, delta, positions, phi, w = _section13()
    alt = yang2021.mappings_and_conventions(prof, delta, phi=phi, weights=w, positions=positions)
    assert len(alt) == 2 * len(SP.MAPPINGS)
    # a first harmonic has zero mean: every separation keeps the set mean, 20
    assert np.allclose(alt.mean_separated, 20, atol=1e-12)
    assert np.allclose(alt.mean_reconstructed, 20, atol=1e-12)
    exact = alt[(alt.mapping == "radial") & (alt.convention == "radial")].iloc[0]
    assert exact.max_profile_error < 1e-12 and exact.max_error_motion_error < 1e-12
    assert exact.mean_separated_error == pytest.approx(1.3, abs=1e-12)
    # the reversed radial mapping turns the constant 1.3 with the workpiece: all of it looks like
    # a first harmonic of the profile
    rev = alt[alt.mapping == "radial_reversed"]
    assert np.allclose(rev.mean_separated_error, 0, atol=1e-12)
    assert (rev.max_error_motion_error > 1).all()


def test_the_eq17_sign_check_recovers_a_and_b_under_the_right_convention():
    t, _, _, _, phi, w = _section13()
    a, b = 0.5, -0.3
    eq17 = yang2021.eq17_sign_check(t, phi, w, k=6, a=a, b=b).set_index("model")
    eq11, eq13 = eq17.iloc[0], eq17.iloc[1]
    # under Eq. 13's convention the sign-fixed Eq. 17 is the inverse, the printed one gives -A, -B
    assert (eq13.A_eq17_sign_fixed, eq13.B_eq17_sign_fixed) == pytest.approx((a, b))
    assert (eq13.A_eq17_printed, eq13.B_eq17_printed) == pytest.approx((-a, -b))
    # under Eq. 11's the exact inverse has -mu; the printed form recovers neither coefficient
    assert (eq11.A_inverse_of_this_model, eq11.B_inverse_of_this_model) == pytest.approx((a, b))
    assert abs(eq11.A_eq17_printed - a) > 0.1 and abs(eq11.B_eq17_printed - b) > 0.1
    assert (eq17.A_true == a).all() and (eq17.B_true == b).all()


def test_the_noise_figure_draws_eq18_n_times_the_corrected_variance():
    kk = np.arange(2, 6)
    q2 = np.array([1.0, 2.0, 3.0, 4.0])
    fig = yang2021.noise_transfer_figure(kk, q2 / 100, q2, noise_um=0.1, n_samples=64,
                                         colours=("C0", "C1"))
    mc, corrected, printed = (line.get_ydata() for line in fig.axes[0].get_lines())
    assert np.allclose(corrected, 2 * q2 * 0.01 / 64) and np.allclose(printed, 64 * corrected)
    assert "sigma = 0.1 µm" in fig.axes[0].get_title()
    plt.close(fig)


def _table1_row(**kw):
    row = dict(H_weights_only_bound=0.31234, H_possible_for_the_weights=True, H_consistent=True,
               a1_consistent=True, abs_a1_consistent=True, a2_consistent=True,
               H_min_within_rounding=0.2561, H_max_within_rounding=0.2583, H_as_printed=0.8329,
               eq15_a1_min=-0.97, eq15_a1_max=-0.946, eq15_a2_min=1.296, eq15_a2_max=1.308)
    return pd.Series({**row, **kw})


PRINTED = pd.Series(dict(H="0.257", phi1_rad="0.522", phi2_rad="3.45", phi3_rad="5.47",
                         a1="1.2", a2="2.1", a3="1.39"))


def test_table1_texts_say_why_a_printed_row_fails_or_holds():
    ours, conclusion, ok, note = yang2021.table1_consistency_texts(
        _table1_row(H_possible_for_the_weights=False), PRINTED)
    assert ours == 0.8329 and not ok
    assert note.startswith("Eq. 20 with the printed phi = (0.522, 3.45, 5.47), a = (1, 1.2, 2.1, "
                           "1.39); impossible: the printed weights force H >= 0.312; weights-only")
    _, conclusion, ok, note = yang2021.table1_consistency_texts(_table1_row(a1_consistent=False),
                                                                PRINTED)
    assert ok and conclusion.endswith("which are the printed ones once the sign of a1 is restored")
    assert "give H 0.256..0.258 within the rounding, a1 -0.970..-0.946" in note
    _, conclusion, ok, _ = yang2021.table1_consistency_texts(
        _table1_row(a1_consistent=False, abs_a1_consistent=False), PRINTED)
    assert not ok and "sign of a1" not in conclusion


def test_a_row_that_holds_only_after_a_correction_is_close_at_best():
    # a made-up printed row whose H follows from Eq. 15's weights but whose a1 lost its sign
    card = reproduction.Card()
    ours, conclusion, ok, note = yang2021.table1_consistency_texts(
        _table1_row(a1_consistent=False), PRINTED)
    card.number("Table 1", "H at the printed parameters", "0.257", ours, conclusion=conclusion,
                holds=ok, note=note)
    assert card.rows[-1]["verdict"] == "close"


def test_least_squares_is_never_noisier_than_the_weights():
    rng = np.random.default_rng(5)
    lo, hi = np.array(list(SP.PAPER_BOX[:3]) + [(0.1, 3.0)]).T
    layouts = {f"r{i}": lo + rng.random(4) * (hi - lo) for i in range(6)}
    band = np.arange(2, 21)
    tab = yang2021.least_squares_vs_weighted(layouts, band)
    assert tab.layout.tolist() == list(layouts)          # Gauss-Markov, row by row
    assert (tab.worst_q2_least_squares <= tab.worst_q2_weighted * (1 + 1e-9)).all()
    assert (tab.mean_q2_least_squares <= tab.mean_q2_weighted * (1 + 1e-9)).all()
    x = layouts["r0"]
    q2 = SP.transfer(x[:3], SP.full_weights(x[:3], x[3]), band)
    assert tab.worst_q2_weighted[0] == q2.max() and tab.mean_q2_weighted[0] == q2.mean()


def test_the_speed_figure_closes_and_offsets_the_first_measurement_of_each_speed():
    theta = np.linspace(0, 2 * np.pi, 8, endpoint=False)
    curves = np.arange(2 * 3 * 8, dtype=float).reshape(2, 3, 8)
    fig = yang2021.speed_curves_figure(theta, curves, np.zeros(8), offset=3.0, speeds=[600, 900],
                                       title="Fig. 19", colours=plt.get_cmap("tab10"))
    true, *by_speed = fig.axes[0].get_lines()
    assert true.get_label() == "true" and np.allclose(true.get_ydata(), 3.0)
    assert [ln.get_label() for ln in by_speed] == ["600 r/min", "900 r/min"]
    assert np.allclose(by_speed[1].get_ydata(), np.r_[curves[1, 0], curves[1, 0, 0]] + 3)
    assert len(by_speed[0].get_xdata()) == 9
    plt.close(fig)


def test_the_ranges_statement_tests_every_order_from_the_lowest():
    sweep = pd.DataFrame({"k": np.arange(2, 13),
                          "H_best_known": [0.3, 0.29, 0.26, 0.25, 0.26, 0.28, 0.26, 0.25, 0.27,
                                           0.26, 0.25]})
    ours, ok, note = yang2021.ranges_statement(sweep, np.array([20, 30]), np.array([0.26, 0.2745]),
                                               band_text="0.273", full_circle={2: 0.25})
    # above 0.273 + 0.0005: k = 2, 3, 7 and 30; 0.27 at k = 10 is inside
    assert not ok
    assert ours == ("best known H in the ranges within Fig. 10's band (<= 0.273) at 9 of 13 "
                    "orders k = 2..12 and 20 30; above it at k = 2 3 7 30")
    assert note.startswith("above the band: k = 2: 0.300 (full circle 0.250); k = 3: 0.290; "
                           "k = 7: 0.280; k = 30: 0.275; elsewhere within 8.0 % of 1/4; orders "
                           "13..19 not computed")
    ours, ok, _ = yang2021.ranges_statement(sweep[~sweep.k.isin([2, 3, 7])], np.array([20]),
                                            np.array([0.26]), band_text="0.273")
    assert ok and "above it" not in ours


def test_fig10_readings_start_at_every_order_up_to_table1s_smallest():
    sweep = pd.DataFrame({"k": np.arange(2, 9),
                          "H_best_known": [0.33, 0.29, 0.27, 0.2501, 0.26, 0.2504, 0.2502]})
    r = yang2021.fig10_readings(sweep, np.array([40]), np.array([0.2503]), k_tab=4)
    assert r.k_from.tolist() == [2, 3, 4]
    assert r.high.tolist() == [0.33, 0.29, 0.27] and r.k_high.tolist() == [2, 3, 4]
    assert r.low.tolist() == [0.2501] * 3 and r.k_low.tolist() == [5] * 3


def test_a_difference_is_stated_as_round_off_or_by_its_size():
    assert yang2021.difference_text(0.0, 20.0, roundoff=1e-12) == "zero"
    assert yang2021.difference_text(-2.3e-14, 20.0, roundoff=1e-12) == (
        "of order 1e-14 µm: round-off")
    assert yang2021.difference_text(1e-11, 5.0, roundoff=1e-12) == "up to 1e-11 µm"
    assert yang2021.difference_text(0.01234, 20.0, roundoff=1e-12) == "up to 0.0123 µm"


def test_a_layout_is_stated_with_its_genes_and_sample_positions():
    text = yang2021.layout_text("the paper's layout", [0.522, 3.45, 5.47, 1.39], [0, 11, 70, 111],
                                n_samples=128)
    assert text == ("the paper's layout (φ = 0.522, 3.45, 5.47 rad, a3 = 1.39, a1 and a2 from "
                    "Eq. 15, rounded to samples 0, 11, 70, 111 of 128)")


def test_the_captions_follow_the_paper_and_name_every_mapping():
    assert set(yang2021.MAPPING_TEXT) == set(SP.MAPPINGS)
    names = list(yang2021.FIGURES)
    assert names[:3] == ["fig03_set_profile", "fig04_set_rotation_error", "fig05_sensor_signals"]
    assert names.index("fig21_random_vs_optimised_angles_simulated") \
        < names.index("eq06_matrix_eigenvalues")
    assert yang2021.FIGURES["fig08_improved_ga_convergence"] is yang2021.FIG08
    assert yang2021.FIGURES["fig08_09_settings_dependence"].rows == (
        "Fig. 8", "Fig. 9", "Abstract, Figs. 8-9")
    # a caption states no number of its own: the run's numbers fill it
    caption = yang2021.FIGURES["fig03_set_profile"].format(n_samples=64)
    assert "N = 64 points" in caption.text and caption.rows == ("Section 1.3*",)
    settings = yang2021.FIGURES["fig08_09_settings_dependence"].format(
        harmonic_k=20, encoding="binary", pop_size=50, n_runs=32, pc=0.8, pm=0.05,
        generation_counts="120, 200", improved_medians="73, 106", published_improved=55.0,
        published_traditional=118.0, generations=200, pcs="0.6, 0.8", pms="0.01",
        low=-46.2, high=34.4, published_speedup="50")
    assert "Pc ∈ {0.6, 0.8} and Pm ∈ {0.01}: from -46 % to 34 %" in settings.text
