"""The checks notebooks 04 and 01 make on their data and results (papers.xu2022, zheng2024);
the checks of the parameters alone are the declarations' (tests/test_parameters.py)."""

import pytest

from mtaccuracy.papers import xu2022, zheng2024
from mtaccuracy.papers.parameters import ParameterError


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


def test_zheng_fixed_ratio_floor_spans_every_group_not_the_last():
    """The noise floor is the RMS deviation of the published PCE values from their group means
    over all fixed groups (a loop variable once shadowed the set and left only the last)."""
    import numpy as np
    import pandas as pd


    t2 = pd.DataFrame({"comp": ["Px"] * 5, "symbol": list("abcde"),
                       "pce": [1.0, 1.2, 2.0, 2.0, 3.0], "mcs": [1.0] * 5, "lhs": [1.0] * 5})
    half = pd.DataFrame({m: [0.005] * 5 for m in ("pce", "mcs", "lhs")})
    groups = pd.DataFrame({"entry": [0, 1, 2, 3, 4], "group": [0, 0, 1, 1, 2],
                           "factor": [1.0] * 5})
    cross = pd.DataFrame(columns=["num_k", "den_k", "num_l", "den_l", "value"])
    eq, quot, floor, scatter = zheng2024.fixed_ratio_checks(t2, half=half, groups=groups,
                                                            cross=cross, any_sd=set())
    assert floor == pytest.approx(np.sqrt((0.1 ** 2 * 2) / 5))    # group 0 scatters, 1 and 2 not
    assert list(eq.group) == ["Px a/b", "Px c/d"] and quot.empty
    assert eq.pce_spread_percent.iloc[0] == pytest.approx(20.0)
    assert not eq.pce_holds.iloc[0] and eq.pce_holds.iloc[1]


def test_zheng_converged_at_is_the_first_size_from_which_r_stays_small():
    import pandas as pd


    g = pd.DataFrame({"n": [100, 200, 400, 800, 1600],
                      "R_percent": [float("nan"), 2.0, 5.0, 1.0, 0.5]})
    assert zheng2024.converged_at(g) == 800
    assert pd.isna(zheng2024.converged_at(g.assign(R_percent=[0, 9, 9, 9, 9])))
