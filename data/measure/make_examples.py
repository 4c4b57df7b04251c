"""Write the SIMULATED example measurements of this folder from a known machine (seeded).

    PYTHONPATH=lib .venv/bin/python data/measure/make_examples.py          # (re)write both
    PYTHONPATH=lib .venv/bin/python data/measure/make_examples.py --check  # compare, write nothing

``positioning_X.csv``: an ISO 230-2 test of a linear axis X (-400 to 400 mm), the model below;
``circle_XY.csv``: an ISO 230-4 circular test in XY, both directions, from an exact geometric
model of the axes.  The truth is in ``README.md``; ``tests/test_iso230_2.py`` and
``tests/test_iso230_4.py`` check that this script gives the committed bytes and that the
evaluation recovers the truth.  Plain numpy, independent of ``mtaccuracy.measure``.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
SEED = 20261129

# --- ISO 230-2: axis X -------------------------------------------------------------------------
#: Targets (mm): 11 over the 800 mm travel of notebook 06's machine (X from -400 to 400 mm),
#: spaced unevenly (ISO 230-2 5.3.2: no common period with a screw's pitch).
TARGETS_MM = np.array([-400.0, -321.3, -239.6, -160.8, -79.5, 0.4, 80.9, 159.7, 241.2, 319.8,
                       400.0])
CYCLES = 5
POSITIONING = dict(
    scale_um_per_m=15.0,       # pitch error: x = 15 um/m * P (the circle's X scale)
    periodic_um=1.5,           # the screw's cyclic error: 1.5 um * sin(2 pi P / 10 mm)
    lead_mm=10.0,
    backlash_um=4.0,           # lost motion: -2 um approached in +, +2 um approached in -
    drift_um_per_cycle=0.3,    # thermal growth: 0.3 um * (P / 1000 mm) more each cycle
    noise_um=0.4,              # repeatability: independent N(0, 0.4 um) per reading
)


def positioning_truth(target_mm, up, cycle):
    """The noise-free deviation (um) of a reading."""
    p = POSITIONING
    return (p["scale_um_per_m"] * target_mm * 1e-3
            + p["periodic_um"] * np.sin(2 * np.pi * target_mm / p["lead_mm"])
            + np.where(up, -1.0, 1.0) * p["backlash_um"] / 2
            + p["drift_um_per_cycle"] * (cycle - 1) * target_mm / 1000.0)


def positioning_text(rng) -> str:
    """The file: cycle by cycle, up the targets then down (the linear cycle of ISO 230-2)."""
    rows = []
    for j in range(1, CYCLES + 1):
        for up, order in ((True, TARGETS_MM), (False, TARGETS_MM[::-1])):
            x = positioning_truth(order, up, j) + POSITIONING["noise_um"] * rng.standard_normal(
                order.size)
            rows += [f"X,{t:g},{j},{'+' if up else '-'},{v:.3f}"
                     for t, v in zip(order, x, strict=True)]
    return "axis,target_mm,cycle,direction,deviation_um\n" + "\n".join(rows) + "\n"


# --- ISO 230-4: circle in XY --------------------------------------------------------------------
RADIUS_MM, FEED = 150.0, 1000.0
POINTS = 360                   # per direction, at 0.5, 1.5, ... deg
CIRCLE = dict(
    scale_um_per_m=(15.0, -5.0),   # X, Y: scale mismatch X - Y = 20 um/m
    squareness_urad=30.0,          # +Y moves along (-sin a, cos a): the XY angle is 90 deg + a
    lag_ms=(1.2, 0.9),             # X, Y delays: servo mismatch X - Y = 0.3 ms
    backlash_um=(3.0, 1.5),        # lost motion, X and Y
    centre_um=(4.0, -2.5),         # the path's centre relative to the ballbar's pivot
    noise_um=0.3,                  # independent N(0, 0.3 um) per reading
)


def circle_truth(theta_deg, ccw):
    """The exact ballbar reading (um): |P - pivot| - R, P the axes' actual position."""
    c = CIRCLE
    th = np.deg2rad(theta_deg)
    s = np.where(ccw, 1.0, -1.0)
    omega = FEED / 60.0 / RADIUS_MM
    lag = [th - s * omega * t * 1e-3 for t in c["lag_ms"]]
    vel = [np.sign(-s * np.sin(th)), np.sign(s * np.cos(th))]
    qa = (RADIUS_MM * np.cos(lag[0]) - c["backlash_um"][0] * 5e-4 * vel[0]) \
        * (1 + c["scale_um_per_m"][0] * 1e-6)
    qb = (RADIUS_MM * np.sin(lag[1]) - c["backlash_um"][1] * 5e-4 * vel[1]) \
        * (1 + c["scale_um_per_m"][1] * 1e-6)
    a = c["squareness_urad"] * 1e-6
    px = qa - np.sin(a) * qb + c["centre_um"][0] * 1e-3
    py = np.cos(a) * qb + c["centre_um"][1] * 1e-3
    return (np.hypot(px, py) - RADIUS_MM) * 1e3


def circle_text(rng) -> str:
    """The file: the ccw run (angles increasing), then the cw run (decreasing)."""
    th = (np.arange(POINTS) + 0.5) * 360.0 / POINTS
    rows = []
    for ccw, order in ((True, th), (False, th[::-1])):
        d = circle_truth(order, ccw) + CIRCLE["noise_um"] * rng.standard_normal(order.size)
        rows += [f"XY,{RADIUS_MM:g},{FEED:g},{'ccw' if ccw else 'cw'},{t:g},{v:.3f}"
                 for t, v in zip(order, d, strict=True)]
    return ("plane,radius_mm,feed_mm_per_min,direction,angle_deg,deviation_um\n"
            + "\n".join(rows) + "\n")


def texts() -> dict:
    """Both files' texts, from one seeded generator."""
    rng = np.random.default_rng(SEED)
    return {"positioning_X.csv": positioning_text(rng), "circle_XY.csv": circle_text(rng)}


if __name__ == "__main__":
    check = "--check" in sys.argv[1:]
    bad = []
    for name, text in texts().items():
        if check:
            if (HERE / name).read_text() != text:
                bad.append(name)
        else:
            (HERE / name).write_text(text)
    if bad:
        sys.exit(f"differ from the generator: {bad}")
