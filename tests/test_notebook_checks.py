"""The parameter checks notebooks 02 and 04 call (compendium.rong, compendium.xu2022)."""

import pytest

from mtaccuracy.compendium import rong, xu2022
from mtaccuracy.compendium.runner import ParameterError

GOOD = dict(workspace_mm=[800, 700, 600], tool_offset_mm=[0, 0, 100],
            sweep_thresholds=[0.5, 0.99, 0.01], tool_lengths_mm=[0, 300, 10], n_plot=100,
            n_base=1000)


def test_check_sweeps_counts_the_thresholds():
    assert rong.check_sweeps(**GOOD) == 50


@pytest.mark.parametrize("change, message", [
    (dict(workspace_mm=[800, 700]), "workspace_mm and tool_offset_mm need three values"),
    (dict(sweep_thresholds=[0.9, 0.5, 0.01]), r"0 < first <= last < 1, step > 0"),
    (dict(tool_lengths_mm=[0, 300, 1]), "more than 200 tool lengths"),
    (dict(tool_lengths_mm=[300, 0, 10]), "first <= last and step > 0"),
    (dict(n_plot=2000), "n_plot = 2000 must be at most n_base = 1000"),
    (dict(sweep_thresholds=[0.01, 0.99, 0.001]), "gives 981 thresholds; at most 200"),
])
def test_check_sweeps_refuses_with_a_clear_message(change, message):
    with pytest.raises(ValueError, match=message):
        rong.check_sweeps(**{**GOOD, **change})


def test_xu2022_checks_refuse_a_split_the_data_cannot_serve():
    with pytest.raises(ParameterError, match="test_experiment 3 is also a training experiment"):
        xu2022.check_experiments("04", [1, 2, 3], 3)
    with pytest.raises(ParameterError, match="needs at least 2 experiments"):
        xu2022.check_experiments("04", [1], 4)
    data = xu2022.reconstruct()
    paper = {"point": ["T1"], "k": ["T99"], "b": ["T2"]}
    with pytest.raises(ParameterError, match=r"experiment\(s\) \[9\] are not in"):
        xu2022.check_data("04", data, "f", [1, 2], 9, 3, "selected", paper)
    with pytest.raises(ParameterError, match="n_clusters = 50 exceeds the 12 sensors"):
        xu2022.check_data("04", data, "f", [1, 2], 4, 50, "selected", paper)
    with pytest.raises(ParameterError, match=r"lacks \['T99'\]; use inputs = 'selected'"):
        xu2022.check_data("04", data, "f", [1, 2], 4, 3, "published", paper)
    assert xu2022.check_data("04", data, "f", [1, 2], 4, 3, "selected", paper) == ["T99"]
