"""Notebook 05 (Yang et al. 2021) after the second audit: the inputs of the simulated lathe
experiment and the bases they give, the paper's experimental layout as printed, and the GA
settings study (its speed-ups against their definition, its determinism)."""

import numpy as np
import pandas as pd
import pytest

from mtaccuracy import spindle as SP
from mtaccuracy.compendium import reproduction, yang2021


def _facts():
    facts = reproduction.published("yang2021_facts", ["quantity", "value"])
    return facts.set_index("quantity").value


def test_the_experiment_layout_is_table1s_k20_row():
    genes = yang2021.experiment_genes(_facts())
    t1 = reproduction.published("yang2021_table1", ["k", "phi1_rad", "a3"]).set_index("k")
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


#: Notebook 05's default parameters that ``check_run`` reads.
RUN = dict(probe_positions=[0, 14, 65, 116], n_samples=128, lowpass_harmonic=50,
           exp_n_samples=128, interleave=2, worst_k=20, harmonic_k=20, k_sweep_max=80,
           pop_size=50, unrelated="ignored")


@pytest.mark.parametrize("change, words", [
    (dict(probe_positions=[1, 14, 65, 116]), r"probe_positions must be 4 distinct .* 0\.\.127"),
    (dict(probe_positions=[0, 14, 14, 116]), "probe_positions must be 4 distinct"),
    (dict(lowpass_harmonic=65), "need lowpass_harmonic <= exp_n_samples / 2"),
    (dict(interleave=3), "need .* and interleave dividing exp_n_samples"),
    (dict(worst_k=64), "worst_k must stay below N/2 = 64"),
    (dict(harmonic_k=81), "need harmonic_k <= k_sweep_max"),
    (dict(pop_size=51), "need .* and an even pop_size"),
])
def test_check_run_names_the_parameters_that_contradict_each_other(change, words):
    yang2021.check_run(RUN, "05_x")                    # the defaults pass
    with pytest.raises(ValueError, match=r"^05_x: " + words):
        yang2021.check_run({**RUN, **change}, "05_x")
