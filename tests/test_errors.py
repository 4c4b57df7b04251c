import numpy as np
import pytest

from mtaccuracy import errors


def test_three_axis_catalogue_counts_and_uniqueness():
    cat = errors.three_axis_catalogue()
    kinds = [e.kind for e in cat]
    assert len(cat) == 21
    assert (kinds.count("positioning"), kinds.count("straightness"), kinds.count("angular"),
            kinds.count("squareness")) == (3, 6, 9, 3)
    assert len({e.symbol for e in cat}) == 21 and len({e.iso_code for e in cat}) == 21


def test_iso_codes_agree_with_the_shared_mapping():
    """mtaccuracy/data writes dx(z) as d_xz and ez(x) as e_zx; every code must agree."""
    iso = errors.iso_names()
    for e in errors.three_axis_catalogue():
        key = e.symbol if e.kind == "squareness" else f"{e.symbol[0]}_{e.symbol[1]}{e.axis}"
        assert iso[key] == e.iso_code, e.symbol


def test_uniform_bounds_converts_units():
    cat = errors.three_axis_catalogue()
    b = errors.uniform_bounds(cat, {"positioning": (0, 3), "straightness": (0, 4),
                                    "angular": (0, 3.2e-5), "squareness": (0, 1.9)})
    syms = errors.symbols(cat)
    assert b[1, syms.index("dx(x)")] == pytest.approx(3e-3)
    assert b[1, syms.index("dy(x)")] == pytest.approx(4e-3)
    assert b[1, syms.index("ez(z)")] == pytest.approx(3.2e-5)
    assert b[1, syms.index("S_xy")] == pytest.approx(1.9e-6)
    assert np.all(b[0] == 0)


@pytest.mark.parametrize("ranges, message", [
    ({"positioning": (0, 3), "straightness": (0, 4), "angular": (0, 1)}, "no range"),
    ({"positioning": (0, 3), "straightness": (0, 4), "angular": (0, 1), "squareness": (0, 1),
      "thermal": (0, 1)}, "unknown error kind"),
    ({"positioning": (3, 3), "straightness": (0, 4), "angular": (0, 1), "squareness": (0, 1)},
     "high > low"),
])
def test_uniform_bounds_refuses_bad_ranges(ranges, message):
    with pytest.raises(ValueError, match=message):
        errors.uniform_bounds(errors.three_axis_catalogue(), ranges)


def test_select_names_the_allowed_symbols():
    cat = errors.three_axis_catalogue()
    assert errors.select(cat, ["dx(x)", "S_xz"]) == [0, 20]
    with pytest.raises(ValueError, match="unknown error name.*allowed: dx\\(x\\)"):
        errors.select(cat, ["dq(x)"])


# --- one maker of ISO 230-1 codes (issue 25 item 3) ------------------------------------------

def test_every_code_of_the_package_map_is_what_iso_code_makes_of_its_symbol():
    rot = {"x": "A", "y": "B", "z": "C"}
    square = {"S_xy": ("X", "Y"), "S_yz": ("Y", "Z"), "S_xz": ("X", "Z")}
    names = errors.iso_names()
    checked = 0
    for symbol, code in names.items():
        if symbol in square:
            assert code == errors.squareness_code(*square[symbol]), symbol
        elif symbol[:2] in ("d_", "e_") and len(symbol) == 4:      # motions: d_xz, e_yc
            comp = symbol[2] if symbol[0] == "d" else rot[symbol[2]]
            assert code == errors.iso_code(comp, symbol[3]), symbol
        else:                                                    # location errors: E?0?
            assert code == errors.iso_code(code[1], code[3], zero=True), symbol
            assert len(code) == 4
        checked += 1
    assert checked == len(names) == 41


def test_the_chain_and_the_catalogues_make_the_same_codes():
    from mtaccuracy.machines import iso
    cat, _ = iso.iso_catalogue("w X b Y Z t")
    three = {s.iso_code for s in errors.three_axis_catalogue()}
    assert three == {s.symbol for s in cat}          # 18 motions and 3 squareness errors
    five = {s.iso_code for s in errors.five_axis_ac_catalogue()}
    ac, _ = iso.iso_catalogue("w C A b Y X Z t")
    # the paper's motions and squareness errors are among the chain's codes (its location
    # errors are placed differently: the paper's d_xAM is no ISO 230-7 location error)
    motions = {c for c in five if "0" not in c} | {"EC0Y", "EA0Z", "EB0Z"}
    assert motions <= {s.symbol for s in ac}


@pytest.mark.parametrize("args, kwargs, words", [
    (("Q", "X"), {}, "component and an axis among XYZABC"),
    (("X", "XY"), {}, "component and an axis"),
    (("X", "X"), {"square": True}, None)])
def test_iso_code_refuses_what_is_not_a_code(args, kwargs, words):
    if words is None:
        with pytest.raises(TypeError):
            errors.iso_code(*args, **kwargs)
        return
    with pytest.raises(ValueError, match=words):
        errors.iso_code(*args, **kwargs)
    with pytest.raises(ValueError, match="two different linear axes"):
        errors.squareness_code("X", "A")
