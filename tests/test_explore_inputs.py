"""The explorer's per-error ranges table and the reader's own files (issue 35, item 5).

Truth comes from models written here: the linear model's indices ``p_i = J_i^2 v_i / sum``
change in closed form when one variance changes (scaling ``v_i`` by ``s`` gives
``p_i' = s p_i / (1 + (s - 1) p_i)``, the others ``p_j / (1 + (s - 1) p_i)``); a ranges file
and a probe file written here from known ranges and a known roundness profile, spindle motion
and probe layout.
"""

import numpy as np
import pandas as pd
import pytest

from mtaccuracy.apps import explore_files as EF
from mtaccuracy.apps import explore_model as M
from mtaccuracy.compendium.notebook import ROOT
from mtaccuracy.papers import rong

TOPOLOGY = "w C b X Y Z B t"


@pytest.fixture(scope="module")
def typed():
    return M.topology_setup(TOPOLOGY)


# -- the ranges table --------------------------------------------------------------------------

def test_the_table_starts_from_the_notebooks_declarations():
    """Notebook 02: range_factor x the acceptance half widths of its ranges_file (µm, arcsec)."""
    s = M.machine_setup("horizontal_3axis")
    p = rong.Parameters.defaults()
    table = M.ranges_table(s)
    assert table.error.tolist() == s.names and (table.half_range == table.notebook).all()
    from mtaccuracy.machines.readers import read_ranges
    half = p["range_factor"] * read_ranges(ROOT / p["ranges_file"], s.machine)[1]
    per = np.where(s.translational, 1e-3, M.ARCSEC)
    np.testing.assert_allclose(table.notebook, half / per, rtol=1e-14)
    assert set(table.unit) == {"µm", "arcsec"}
    assert (table.unit == "µm").tolist() == s.translational.tolist()


@pytest.mark.parametrize("scale", [0.0, 0.5, 2.0, 7.0])
def test_one_error_s_range_changes_the_indices_in_closed_form(typed, scale):
    pose = dict(x=40.0, y=-30.0, z=25.0, B=20.0, C=35.0)
    half = typed.half_range.copy()
    base = M.indices_at_pose(typed, pose, half_range=half)
    k = base.names.index("EBX") if "EBX" in base.names else int(np.argmax(base.indices[:, 0]))
    half[k] *= scale                                 # its variance by scale**2
    new = M.indices_at_pose(typed, pose, half_range=half)
    s = scale**2
    p = base.indices                                 # (d, q)
    want = p / (1.0 + (s - 1.0) * p[k])
    want[k] = s * p[k] / (1.0 + (s - 1.0) * p[k])
    first = base.first_order & new.first_order
    np.testing.assert_allclose(new.indices[:, first], want[:, first], rtol=1e-12, atol=1e-15)
    if scale == 0.0:
        assert np.all(new.indices[k] == 0.0)


def test_the_group_sliders_scale_the_table_and_keep_its_ratios(typed):
    half = typed.half_range * np.linspace(0.5, 1.5, typed.half_range.size)
    out = M.scaled_group(typed, half, translational=True, largest=12.0)
    t = typed.translational
    assert out[t].max() == pytest.approx(12.0e-3, rel=1e-14)
    np.testing.assert_allclose(out[t] / half[t], 12.0e-3 / half[t].max(), rtol=1e-13)
    assert np.array_equal(out[~t], half[~t])
    # from the notebook's ranges, the group sliders give what they always gave
    z = M.machine_setup("ac_double_turntable")
    np.testing.assert_allclose(
        M.scaled_group(z, z.half_range, translational=False, largest=4.0),
        M.error_half_ranges(z, angular_arcsec=4.0), rtol=1e-14)


@pytest.mark.parametrize("bad, why", [
    (np.nan, "NaN"), (np.inf, "infinite"), (-1.0, "out of bounds"), (1e5, "out of bounds"),
    ("3", "must be a number"), (None, "is empty")])
def test_a_bad_half_range_is_refused_naming_the_error(typed, bad, why):
    values = list(M.ranges_table(typed).half_range)
    values[3] = bad
    with pytest.raises(ValueError, match=why) as exc:
        M.checked_half_ranges(typed, values, in_table_units=True)
    assert typed.names[3] in str(exc.value)
    with pytest.raises(ValueError, match="has 37 errors, got 36"):
        M.checked_half_ranges(typed, values[:-1], in_table_units=True)


def test_the_table_is_guarded_on_the_server_and_drives_what_is_shown():
    pytest.importorskip("panel")
    from mtaccuracy.apps import explore

    tab = explore.MachineTab()
    table, before = tab.ranges, tab.half_range.copy()
    col = list(table.value.half_range)
    for bad, why in ((1e9, "out of bounds"), (float("nan"), "NaN"), ("x", "must be a number")):
        data = {"half_range": [*col[:2], bad, *col[3:]]}
        table._process_data(data)
        assert why in tab.refused and tab.setup.names[2] in tab.refused
        assert np.array_equal(tab.half_range, before)
    table._process_data({"half_range": col[:-1]})           # a row less
    assert "got 40 half ranges" in tab.refused
    table._process_data({"error": ["<script>"] * len(col)})  # another column: never taken
    assert "no column 'half_range'" in tab.refused and table.value.error[0] == tab.setup.names[0]
    edited = [*col[:2], 25.0, *col[3:]]                        # a good edit: 25 µm for one
    table._process_data({"half_range": edited, "error": ["x"] * len(col)})
    assert tab.refused == "" and table.value.error.tolist() == tab.setup.names
    assert tab.half_range[2] == pytest.approx(25e-3, rel=1e-14)
    assert tab.position_um == pytest.approx(25.0)               # the slider shows the largest
    res = M.indices_at_pose(tab.setup, tab.pose_values(), half_range=tab.half_range)
    assert np.array_equal(tab.heat_src.data["index"],
                          np.where(res.first_order, res.indices, np.nan).ravel(), equal_nan=True)
    tab.set_half_ranges(tab.setup.half_range)                 # the notebook's again
    assert np.array_equal(tab.ranges.value.half_range, tab.ranges.value.notebook)


# -- the reader's own files --------------------------------------------------------------------

def _ranges_csv(setup, half_um_or_urad) -> bytes:
    rows = ["# my machine's ranges", "symbol,low,high,unit"]
    for name, t, h in zip(setup.names, setup.translational, half_um_or_urad, strict=True):
        rows.append(f"{name},{-float(h)!r},{float(h)!r},{'um' if t else 'urad'}")
    return ("\n".join(rows) + "\n").encode()


def test_a_ranges_file_is_read_by_notebook_06_s_reader(typed):
    h = 1.0 + 0.25 * np.arange(len(typed.names))                # µm or µrad, known
    up = EF.read_upload("mine.csv", _ranges_csv(typed, h),
                        lambda path: M.ranges_from_file(typed, path))
    assert up.message == "" and up.names == ("mine.csv",)
    want = np.where(typed.translational, h * 1e-3, h * 1e-6)
    np.testing.assert_allclose(up.result, want, rtol=1e-14)
    # the reader's own message, naming the file as uploaded and the line of the bad row
    bad = _ranges_csv(typed, h).replace(b"EXC,", b"EXQ,", 1)
    up = EF.read_upload("mine.csv", bad, lambda path: M.ranges_from_file(typed, path))
    assert up.result is None and "mine.csv" in up.message and "line 3" in up.message
    assert "mtaccuracy-upload" not in up.message and "/tmp" not in up.message


def test_the_machine_tab_takes_a_ranges_file():
    pytest.importorskip("panel")
    from mtaccuracy.apps import explore

    tab = explore.MachineTab()
    h = 2.0 + 0.1 * np.arange(len(tab.setup.names))
    tab.load_ranges("zheng.csv", _ranges_csv(tab.setup, h))
    assert tab.file_error == "" and "41 ranges read" in tab.file_read
    np.testing.assert_allclose(tab.half_range, np.where(tab.setup.translational, h * 1e-3,
                                                        h * 1e-6), rtol=1e-14)
    tab.load_ranges("zheng.csv", b"symbol,low\n")
    assert "zheng.csv" in tab.file_error and tab.file_read == ""


@pytest.mark.parametrize("names, contents, why", [
    ("../x.csv", b"a", "not a plain .csv file name"), ("x.txt", b"a", "not a plain"),
    ("/etc/x.csv", b"a", "not a plain"), (None, None, "no file chosen"),
    ("x.csv", "text", "no file content"),
    ("big.csv", b"0" * (EF.MAX_UPLOAD_BYTES + 1), "at most"),
    (["a.csv", "a.csv"], [b"1", b"2"], "chosen twice"),
    ([f"{i}.csv" for i in range(9)], [b""] * 9, "at most 5")])
def test_an_upload_is_refused_before_anything_is_written(names, contents, why, monkeypatch):
    def never(path):
        raise AssertionError("the reader ran")
    monkeypatch.setattr(EF.tempfile, "TemporaryDirectory", never)
    up = EF.read_upload(names, contents, never)
    assert why in up.message and up.result is None


def _probe_csv(angles_deg, n=64, revolutions=2) -> bytes:
    """Readings of a known roundness profile and spindle motion at ``angles_deg`` (µm)."""
    theta = np.arange(n) * 2 * np.pi / n
    head = "revolution,angle_deg," + ",".join(f"probe_{a:g}_um" for a in angles_deg)
    rows = [head]
    for r in range(1, revolutions + 1):
        x = 0.8 * np.cos(theta + 0.3 * r) + 0.2 * np.sin(7 * theta)       # spindle motion
        y = 0.6 * np.sin(theta + 0.1) + 0.15 * np.cos(4 * theta)
        for j in range(n):
            vals = []
            for a in np.deg2rad(angles_deg):
                t = theta[j] + a
                vals.append(2.0 * np.cos(3 * t) + np.sin(5 * t + 0.4) + x[j] * np.cos(a)
                            + y[j] * np.sin(a))
            angle = float(np.rad2deg(theta[j]))
            rows.append(f"{r},{angle!r}," + ",".join(f"{v:.6f}" for v in vals))
    return ("\n".join(rows) + "\n").encode()


def test_the_spindle_tab_takes_a_probe_file_through_notebook_07_s_reader():
    pytest.importorskip("panel")
    from mtaccuracy.apps.explore_tabs import SpindleTab

    tab = SpindleTab()
    tab.load_probes("probes.csv", _probe_csv([20.0, 60.0, 200.0, 335.0]))
    assert tab.file_error == "", tab.file_error
    assert (tab.probe2, tab.probe3, tab.probe4) == (40.0, 180.0, 315.0)   # from probe 1
    assert tab.layout == "custom" and "probes at 20, 60, 200, 335 deg" in tab.file_read
    t = tab.transfer()                    # the layout's harmonics are a rotation invariant
    from mtaccuracy import spindle as SP
    ks = np.arange(2, tab.max_harmonic + 1)
    np.testing.assert_allclose(t.q_least_squares, SP.noise_amplification(
        np.deg2rad([20.0, 60.0, 200.0, 335.0]), ks), rtol=1e-10)
    # notebook 07's reader's message: the file as uploaded, the header's line
    bad = _probe_csv([0.0, 60.0, 200.0, 335.0]).replace(b"probe_60_um", b"probe_60_mm")
    tab.load_probes("probes.csv", bad)
    assert "probes.csv" in tab.file_error and "line 1" in tab.file_error
    assert "/tmp" not in tab.file_error and tab.probe3 == 180.0
    tab.load_probes("three.csv", _probe_csv([0.0, 100.0, 230.0]))
    assert "3 probes; this tab shows four-probe layouts" in tab.file_error


def test_the_thermal_tab_takes_a_folder_through_notebook_04_s_reader():
    pytest.importorskip("panel")
    from mtaccuracy.apps.explore_tabs import ThermalTab

    src = ROOT / "data" / "thermal"
    names = ["temperatures.csv", "errors.csv", "experiments.csv"]
    # my own measurements: the shipped ones with every error doubled (a known change)
    errors = pd.read_csv(src / "errors.csv")
    errors["error_um"] *= 2.0
    contents = [(src / "temperatures.csv").read_bytes(),
                errors.to_csv(index=False, lineterminator="\n").encode(),
                (src / "experiments.csv").read_bytes()]
    tab = ThermalTab()
    shipped = tab.data
    tab.load_files(names, contents)
    assert tab.file_error == "" and not tab.reconstructed
    np.testing.assert_allclose(np.asarray(tab.data.errors, float),
                               2.0 * np.asarray(shipped.errors, float), rtol=1e-12)
    assert "not the paper's reconstruction" in tab.source
    tab.load_files(["temperatures.csv"], [contents[0]])          # errors.csv missing
    assert "errors.csv" in tab.file_error and "/tmp" not in tab.file_error


# -- the state in the URL ----------------------------------------------------------------------

def test_a_link_restores_the_tab_the_pose_the_ranges_and_the_probes():
    pytest.importorskip("panel")
    from mtaccuracy.apps import explore
    from mtaccuracy.apps.explore_state import UrlState

    a = explore.create_app()
    m, s = a.tabs["machine"], a.tabs["spindle"]
    m.topology = TOPOLOGY                                   # a typed machine
    m.pose.param.update(x=-212.5, B=33.25)
    m.param.update(across="x", up="B", output="Py")
    half = m.half_range.copy()
    half[4] = 17.5e-3 if m.setup.translational[4] else 17.5 * M.ARCSEC
    m.set_half_ranges(half)
    s.param.update(probe2=41.5, probe3=170.0, probe4=300.125)
    a.views.active = 1
    link = {p: getattr(a.url_state, p) for p in a.url_state.param if p != "name"}
    assert link["tab"] == "spindle" and link["machine"] == M.TOPOLOGY and link["ranges"]
    b = explore.create_app()                                 # a reload with that link
    state = UrlState(**link)
    active = []
    assert state.apply(b.tabs, active=active.append) == [] and active == [1]
    mb, sb = b.tabs["machine"], b.tabs["spindle"]
    assert mb.setup.key == M.TOPOLOGY and mb.topology == TOPOLOGY
    assert mb.pose_values() == m.pose_values() and (mb.across, mb.up, mb.output) == (
        "x", "B", "Py")
    np.testing.assert_allclose(mb.half_range, m.half_range, rtol=1e-15)
    assert (sb.probe2, sb.probe3, sb.probe4) == (41.5, 170.0, 300.125)
    assert np.array_equal(mb.heat_src.data["index"], m.heat_src.data["index"], equal_nan=True)
    # the notebook's ranges are not written in the link
    mb.set_half_ranges(mb.setup.half_range)
    b.url_state.read(b.tabs)
    assert b.url_state.ranges == ""


def test_a_bad_link_is_named_part_by_part_and_the_rest_applied():
    pytest.importorskip("panel")
    from mtaccuracy.apps import explore
    from mtaccuracy.apps.explore_state import UrlState

    app = explore.create_app()
    m, s = app.tabs["machine"], app.tabs["spindle"]
    before = m.pose_values()
    state = UrlState(machine="vertical_xyfz", pose="x:1e9", view="x,Q,Px",
                     ranges="1,2", probes="10,nan,20", tab="<script>")
    problems = state.apply(app.tabs)
    assert m.setup.key == "vertical_xyfz" and m.pose_values() != before    # applied
    text = "; ".join(problems)
    for why in ("pose: axis x = 1e+09 is out of bounds", "view: 'x,Q,Px' is not two axes",
                "ranges: the link's ranges has 2 values, 21 expected", "probes: probe 3 angle "
                "is not a number (NaN)", "tab: '<script>' is not one of"):
        assert why in text, text
    assert (s.probe2, s.probe3) == M.YANG_DEG[1:3]
    assert UrlState(machine="x" * 3000).apply(app.tabs)[0].startswith("machine: the link's")
    assert UrlState(machine=M.TOPOLOGY, topology="w Q t").apply(app.tabs)[0].startswith(
        "machine: unknown axis letter")


def test_each_tab_links_its_chapter(tmp_path):
    from mtaccuracy.apps import explore_state as EU

    cff = tmp_path / "CITATION.cff"
    cff.write_text('cff-version: 1.2.0\nurl: "https://example.org/book"\n')
    assert EU.chapter_url("vertical_xyfz", cff) == \
        "https://example.org/book/chapters/03_guo2016_spearman_21_errors.html"
    assert EU.chapter_url("thermal", tmp_path / "none.cff") == ""
    notebooks = {p.stem for p in (ROOT / "notebooks").glob("*.ipynb")}
    assert set(EU.CHAPTERS.values()) <= notebooks               # each link is a chapter
    assert set(EU.CHAPTERS.values()) >= notebooks - {"08_your_measurements"}  # no tab: 08


def test_a_crafted_upload_is_refused_before_panel_decodes_it(caplog):
    """What the page sends for a FileInput goes through Panel's _process_events."""
    pytest.importorskip("panel")
    import base64

    import panel as pn

    from mtaccuracy.apps.explore_tabs import SpindleTab

    tab = SpindleTab()
    box = [w for w in tab.view().select(pn.widgets.FileInput)][0]
    with caplog.at_level("ERROR"):
        for value, why in (("@@not base64@@", "not base64"), (12, "not base64"),
                           ("A" * (EF.MAX_UPLOAD_BYTES * 2), "at most"),
                           (["QQ=="] * 9, "at most 5")):
            box._process_events({"value": value, "filename": "x.csv"})
            assert why in tab.refused and tab.file_read == "" and tab.file_error == ""
        good = base64.b64encode(_probe_csv([20.0, 60.0, 200.0, 335.0])).decode()
        box._process_events({"filename": "p.csv", "value": good})
        assert tab.refused == "" and "p.csv: probes at 20, 60, 200, 335 deg" in tab.file_read
        box._process_events({"filename": "../p.csv", "value": good})
        assert "not a plain .csv file name" in tab.file_error
    assert not [r for r in caplog.records if r.levelname == "ERROR"], caplog.text
