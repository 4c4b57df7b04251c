"""Notebook 06's paper module: the chain's drawing and its caption, the numbers of its
conclusion, the declared parameters' check and the figures' captions."""

from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import pytest  # noqa: E402

from mtaccuracy.machines.iso import iso_machine  # noqa: E402
from mtaccuracy.machines.readers import read_axis_table  # noqa: E402
from mtaccuracy.papers import parameters, your_machine  # noqa: E402

TOPOLOGY = "w C b X Y Z B t"
ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def swivel_head():
    travels, pivots = read_axis_table(ROOT / "data" / "machines" / "swivel_head_axes.csv",
                                      TOPOLOGY)
    machine = iso_machine(TOPOLOGY, pivots=pivots, travels=travels,
                          tool_offsets=("tool_x", "tool_y", "tool_z"), name="m")
    return machine, travels, pivots


def test_the_chain_figure_draws_every_body_and_the_tool_over_the_head_axis(swivel_head):
    machine, travels, pivots = swivel_head
    tool = dict(tool_x=0.0, tool_y=0.0, tool_z=-120.0)
    fig = your_machine.chain_figure(machine, TOPOLOGY, travels=travels, pivots=pivots,
                                    tool=tool, tool_length_mm=120.0)
    ax0, ax1 = fig.axes
    bodies = [t.get_text().split("\n")[0] for t in ax0.texts if t.get_fontsize() == 8]
    # from the workpiece: the table side reversed (C), the bed, then the head side out to the tool
    assert bodies == ["workpiece", "C", "bed", "X", "Y", "Z", "B", "tool"]
    assert any("pivot" in t.get_text() for t in ax0.texts if t.get_fontsize() == 7)
    assert "B pivot" in [t.get_text() for t in ax1.get_legend().get_texts()]
    # nine tools over the B travel, each 120 mm from tip to spindle nose
    tools = [ln for ln in ax1.lines if ln.get_linestyle() == "-" and len(ln.get_xdata()) == 2]
    assert len(tools) == 9
    lengths = [np.hypot(*np.diff(ln.get_xdata()), *np.diff(ln.get_ydata())) for ln in tools]
    np.testing.assert_allclose(lengths, 120.0, atol=1e-9)
    plt.close(fig)


def test_without_a_rotary_head_axis_the_tool_panel_is_blank():
    topo = "w X b Y Z t"
    machine = iso_machine(topo, tool_offsets=("tool_x", "tool_y", "tool_z"), name="m3")
    travels = {a: (-100.0, 100.0) for a in "XYZ"}
    fig = your_machine.chain_figure(machine, topo, travels=travels, pivots={},
                                    tool=dict(tool_x=0.0, tool_y=0.0, tool_z=-50.0),
                                    tool_length_mm=50.0)
    assert not fig.axes[1].axison and not fig.axes[1].lines
    plt.close(fig)


def test_the_conclusion_numbers_count_and_rank_what_the_tables_hold():
    catalogue = pd.DataFrame({"kind": ["positioning", "angular", "error motion", "squareness",
                                       "location", "location"]})
    removed = pd.DataFrame({"symbol": ["EX0C"], "why removed": ["zero of X"]})
    shares = pd.DataFrame({"Px": [0.9, 0.2, 0.0, 0.1, 0.1, 0.1, 0.3],
                           "Vz": [0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0]},
                          index=["EXX", "EBB", "ECB", "EAX", "EBX", "ECX", "EYY"])
    lines = your_machine.conclusion_numbers(catalogue, removed, shares, centred_ratio=3e-5,
                                            check_ratio=0.87)
    assert lines[0] == ("catalogue: 6 errors (3 error motions, 1 squareness, 2 location); 1 of 3 "
                        "location errors removed as redundant (EX0C)")
    assert "at most 3e-05" in lines[1] and "about 6e-05" in lines[1]
    # ties keep the catalogue's order (a stable sort)
    assert lines[2] == ("Px: key over >= 50% of the workspace: EXX 90%; next: EYY 30%, EBB 20%, "
                        "EAX 10%, EBX 10% and 1 more")
    assert lines[3] == "Vz: key over >= 50% of the workspace: EBB 50%; next: none"
    assert lines[4] == "never key: ECB"
    assert lines[5] == "sampled check: the largest difference uses 0.87 of the allowance"


def test_the_chain_caption_states_the_topology_the_tool_and_the_swept_travel(swivel_head):
    _, travels, _ = swivel_head
    assert your_machine.swept_axis(TOPOLOGY) == "B"
    cap = your_machine.chain_caption(TOPOLOGY, travels, tool_length_mm=120.0,
                                     axis_table="data/machines/swivel_head_axes.csv")
    assert cap.name == "chain" and cap.label == "Figure 1"
    assert ("topology `w C b X Y Z B t` (workpiece <- C <- bed -> X -> Y -> Z -> B -> tool)"
            in cap.text)
    assert "The ideal 120 mm tool (tip dots) at nine B angles from -110° to 110°" in cap.text
    assert "{" not in cap.text


def test_without_a_rotary_head_axis_the_chain_caption_says_the_panel_is_blank():
    topo = "w C b X Y Z t"
    travels = {"x": (-1.0, 1.0), "y": (-1.0, 1.0), "z": (-1.0, 1.0), "C": (0.0, 6.28)}
    assert your_machine.swept_axis(topo) is None
    cap = your_machine.chain_caption(topo, travels, tool_length_mm=50.0, axis_table="a.csv")
    assert "right panel is blank" in cap.text and "tool (tip dots)" not in cap.text


def test_the_declared_parameters_refuse_a_bad_topology_before_any_work():
    assert parameters.check(your_machine.Parameters, {}).topology == TOPOLOGY
    with pytest.raises(parameters.ParameterError,
                       match=r"^06_your_machine: axis \['X'\] appears more than once"):
        parameters.check(your_machine.Parameters, {"topology": "w b X X t"})


def test_the_captions_name_every_figure_in_the_notebooks_order():
    names = list(your_machine.FIGURES)
    assert names == ["chain", "atlas_dominant_error_map", "atlas_key_errors", "sobol_check"]
    assert [c.label for c in your_machine.FIGURES.values()] == [f"Figure {k}" for k in (1, 2, 3, 4)]
    assert {p.stem for p in (ROOT / "figures" / your_machine.Parameters.stem).glob("*.png")} == \
        set(names)
    text = your_machine.FIGURES["atlas_key_errors"].format(
        n_atlas=10000, key_share=0.05, n_shown=36, n_errors=37, never="ECB",
        everywhere="EZZ for Pz", ranges_file="r.csv").text
    assert "10,000 random poses" in text and "(36 of 37; never key: ECB)" in text
