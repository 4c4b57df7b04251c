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
