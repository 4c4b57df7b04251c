"""From sensitivity to measurement: the standard tests as linear models of a machine's errors.

A test reads ``y_k = g_k' J_t(q_k) eps + n_k' nu + e_k``: the pose error's Jacobian
(:meth:`mtaccuracy.machines.chain.ChainMachine.jacobian`) at the test's poses ``q_k``, seen along
its sensing directions ``g_k``, plus set-up nuisances ``nu`` (a centre, a bar length, a
reference line) and noise ``e_k``.  :class:`.design.Design` holds one test's matrices; the test
models, the identifiability analysis, the identification and the ISO 230-2 / 230-4 evaluations
build on it.
"""
