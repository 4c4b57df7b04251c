"""The tool length in Zheng et al.'s machine: what Section 3.2's position claims rest on.

The tip sits a tool length L along the tool axis from the gauge point, so the position error's
Jacobian changes by L times the attitude error's (the tool-axis direction, which L does not
move): translational errors keep their position index, angular ones gain a lever arm L.
"""

import numpy as np

from mtaccuracy.machines import build
from mtaccuracy.papers import zheng2024

POSES = dict(x=np.array([120.0, -300.0, 0.0]), y=np.array([-80.0, 400.0, 10.0]),
             z=np.array([150.0, -200.0, 0.0]), A=np.deg2rad([40.0, -110.0, 0.0]),
             C=np.deg2rad([75.0, 300.0, 0.0]))


def test_position_jacobian_moves_by_the_tool_length_times_the_attitude_one():
    m = build("ac_double_turntable")
    j0 = m.jacobian({**POSES, "L": 0.0})
    for L in (50.0, 200.0):
        jl = m.jacobian({**POSES, "L": L})
        # the attitude (tool-axis direction) does not depend on L
        np.testing.assert_allclose(jl[:, 3:], j0[:, 3:], atol=1e-12)
        # tip = gauge point -/+ L * tool axis: the position Jacobian moves by L times the attitude
        d = jl[:, :3] - j0[:, :3]
        sign = np.sign(np.sum(d * j0[:, 3:]))
        np.testing.assert_allclose(d, sign * L * j0[:, 3:], atol=1e-9 * L)
        trans = np.array([e.translational for e in m.catalogue])
        np.testing.assert_allclose(d[..., trans], 0.0, atol=1e-12)


def test_translational_errors_never_reach_the_attitude_at_any_tool_length():
    """Section 3.2's "only angular errors matter" in the attitude: true of the model class."""
    m = build("ac_double_turntable")
    sd = np.array([e.to_library * (15.0 if e.translational else 10.0) / 3
                   for e in m.catalogue])
    comps = ["Px", "Py", "Pz", "Vx", "Vy", "Vz"]
    for L in (0.0, 200.0):
        s = zheng2024.table_indices(m.jacobian({**POSES, "L": L}), sd=sd).mean(axis=0)
        sh = zheng2024.group_shares(s, m.catalogue, comps)
        np.testing.assert_allclose(sh.translational.to_numpy()[3:], 0.0, atol=1e-12)
        np.testing.assert_allclose(sh.angular.to_numpy()[3:5], 1.0, atol=1e-12)
