"""Notebook 07 (your spindle): the shipped example recognised by its content and its truth
recorded, and the numbers its captions state, with and without a truth."""

import shutil

import numpy as np
import pandas as pd
import pytest

from mtaccuracy.papers import your_spindle
from mtaccuracy.spindle import example


def _example(tmp_path):
    """A copy of the shipped example's folder (probes, truth and record)."""
    folder = tmp_path / "spindle"
    folder.mkdir()
    for name in example.EXAMPLE_FILES.values():
        shutil.copy(your_spindle.EXAMPLE_FOLDER / name, folder / name)
    return folder


def test_the_shipped_example_is_recognised_by_content_and_its_truth_is_recorded(tmp_path):
    folder = _example(tmp_path)
    moved = tmp_path / "renamed.csv"                    # any name, any place
    shutil.copy(folder / example.EXAMPLE_FILES["probes"], moved)
    read = []
    truth = your_spindle.shipped_example(moved, folder=folder, on_read=read.append)
    assert list(truth.columns) == ["revolution", "angle_deg", "profile_um", "x_um", "y_um"]
    assert read == [folder / example.EXAMPLE_FILES["truth"]]
    # the repository's own example, with the default folder
    assert your_spindle.shipped_example(
        your_spindle.EXAMPLE_FOLDER / example.EXAMPLE_FILES["probes"]) is not None


def test_another_file_has_no_truth_and_reads_none(tmp_path):
    folder = _example(tmp_path)
    other = tmp_path / "mine.csv"
    text = (folder / example.EXAMPLE_FILES["probes"]).read_text()
    other.write_text(text + "\n")                      # one byte more: not the example
    read = []
    assert your_spindle.shipped_example(other, folder=folder, on_read=read.append) is None
    assert read == []


def test_a_truth_that_is_not_the_recorded_one_is_refused(tmp_path):
    folder = _example(tmp_path)
    truth = folder / example.EXAMPLE_FILES["truth"]
    truth.write_text(truth.read_text() + "\n")
    with pytest.raises(ValueError, match="not the truth recorded"):
        your_spindle.shipped_example(folder / example.EXAMPLE_FILES["probes"], folder=folder)


def _tables(with_truth: bool):
    methods = pd.DataFrame({"least_squares_um": [0.0, 1.0, -1.0, 0.0],
                            "weighted_um": [0.0, 1.02, -1.0, -0.01],
                            "difference_um": [0.0, 0.02, 0.0, -0.01]})
    rows = [dict(profile="least squares", lsc_um=2.0004, mz_um=1.9),
            dict(profile="weighted", lsc_um=2.02, mz_um=1.91)]
    if with_truth:
        methods["true_um"] = [0.0, 1.0, -1.03, 0.0]
        rows.append(dict(profile="true (simulated)", lsc_um=2.03, mz_um=1.95))
    noise = pd.DataFrame({"estimator": ["least_squares", "weighted"],
                          "profile_noise_um": [0.012, 0.02]})
    return methods, pd.DataFrame(rows), noise


def test_the_profile_caption_states_the_truth_only_where_there_is_one():
    fields = your_spindle.profile_caption_fields(*_tables(False))
    assert fields == dict(largest=0.02, lsc=2.0004, mz=1.9, truth_left="", truth_right="",
                          rms="", true_roundness="")
    fields = your_spindle.profile_caption_fields(*_tables(True))
    assert fields["largest"] == pytest.approx(0.03)          # weighted - true at the third angle
    rms_ls, rms_w = np.sqrt(0.03 ** 2 / 4), np.sqrt((0.02 ** 2 + 0.03 ** 2 + 0.01 ** 2) / 4)
    assert fields["rms"] == (f"; rms errors {rms_ls:.4f} and {rms_w:.4f} µm, where the noise "
                             "predicts 0.0120 and 0.0200 µm")
    assert fields["true_roundness"] == " against the true 2.030 and 1.950 µm"
    text = your_spindle.FIGURES["separated_profile"].format(
        source=your_spindle.SOURCES[True], **fields).text
    assert "least-squares circle (µm, to scale on an arbitrary base circle), with the true" in text
    assert "LSC 2.000 µm and MZ 1.900 µm against the true 2.030" in text
    assert text.endswith("Simulated data: the shipped example file, not a measurement.")


def test_every_centre_is_named_and_every_caption_says_where_its_data_come_from():
    assert set(your_spindle.CENTRES) == set(your_spindle.Parameters.param["centre"].objects)
    assert list(your_spindle.FIGURES) == ["probe_readings", "layout_harmonics",
                                          "separated_profile", "radial_error_motion_polar",
                                          "error_motion", "asynchronous_spectrum"]
    assert all(c.text.endswith("{source}") for c in your_spindle.FIGURES.values())
