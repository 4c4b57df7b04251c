"""``make bench``: timings of the library's hot paths (median of repeated runs).

Speed targets named in the issues are shown here, never asserted in timed tests.  Each row:
what is timed, its size, the median time, and the throughput.
"""

from __future__ import annotations

import statistics
import time

import numpy as np

from . import errors, sensitivity
from .machines import build


def _median(fn, repeat: int = 5) -> float:
    fn()  # warm-up
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def rows():
    m = build("vertical_xyfz")
    b = errors.uniform_bounds(m.catalogue, {"positioning": (0, 3), "straightness": (0, 4),
                                            "angular": (0, 3.2e-5), "squareness": (0, 1.9)})
    x = sensitivity.latin_hypercube(1_000_000, b, 0)
    pose = dict(x=100.0, y=100.0, z=100.0)
    t = _median(lambda: m.pose_error(x, pose), 3)
    yield "vertical_xyfz pose_error", "1e6 samples", t, f"{1e6 / t / 1e6:.2f} M samples/s"
    t = _median(lambda: sensitivity.latin_hypercube(500, b, 1))
    yield "Latin hypercube (scipy.qmc)", "n=500, d=21", t, ""
    d = sensitivity.repeated_latin_hypercube(500, b, 200, 2)
    y = sensitivity.position_outputs(m.pose_error(d.reshape(-1, 21), pose)).reshape(200, 500, 4)
    t = _median(lambda: sensitivity.spearman(d, y))
    yield "Spearman, batched", "200 repeats x 500 x 21 x 4", t, ""
    rng = np.random.default_rng(3)
    poses = {"x": np.zeros(441), "y": rng.uniform(0, 500, 441), "z": rng.uniform(0, 500, 441)}
    t = _median(lambda: sensitivity.spearman_over_poses(m, x[:500], poses), 3)
    yield "Spearman over a pose grid", "441 poses x 500 samples", t, ""


def main() -> int:
    print(f"{'what':<32} {'size':<28} {'median':>10}  throughput")
    for what, size, t, extra in rows():
        print(f"{what:<32} {size:<28} {t * 1e3:>8.1f} ms  {extra}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
