"""mtaccuracy: the thin library behind the machine-tool accuracy compendium.

Units inside the library are millimetres and radians; every function that draws random
numbers takes a ``numpy.random.Generator`` or an explicit seed.

Where things are
----------------
Science (usable without this repository; none of it imports :mod:`mtaccuracy.compendium`):

=======================  ================================================================
``kinematics``           homogeneous transforms, rotations, pose differences, the chain's
                         kernels
``errors``               the geometric error catalogue (ISO 230-1 names), ranges, sampling
``machines``             kinematic chains of any machine (``machines.chain``; topologies,
                         ISO catalogues and file readers beside it) and the
                         three papers' machines built on it
``sensitivity``          Sobol' (sampling, PCE, linear closed form), Spearman, screening
``spindle``              multi-probe spindle error separation, probe-layout design
``roundness``            roundness of a profile (least squares, minimum zone, filters)
``thermal``              thermal error modelling: data, clustering, estimators, validation
``optimise``             a genetic algorithm over real or binary encodings
``csvlines``             CSV records with the lines an editor shows (the readers' messages)
``validate``             the argument checks every public function uses (one wording)
=======================  ================================================================

The compendium's machinery (runner, book, provenance, published values, paths, plotting,
bench) is in :mod:`mtaccuracy.compendium`.
"""

__version__ = "0.2.0"
