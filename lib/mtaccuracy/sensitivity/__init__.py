"""Sensitivity analysis: samplers, Spearman ranking, Sobol indices, sparse PCE, key-error rules.

One submodule per method; everything is re-exported here, so notebooks write
``from mtaccuracy import sensitivity`` and call ``sensitivity.spearman(...)``.

| submodule | what |
| --- | --- |
| ``inputs`` | :class:`Inputs`: names and marginal laws of independent inputs, their samples (MC,
  Latin hypercube, Sobol': the package's one sampler, which every design is drawn by), moments
  and standard variables; what every estimator takes |
| ``spearman`` | Spearman ranking (Guo et al. 2016); ``latin_hypercube``, a design given by
  bounds drawn through ``Inputs.sample`` |
| ``sobol`` | Sobol first-order and total indices (Saltelli/Jansen), designs drawn and run in
  blocks of base rows (memory flat in N), with streamed bootstrap intervals (``n_boot=``) |
| ``bootstrap`` | bootstrap intervals of the indices: held (resamples of the stored runs,
  SALib's) and streamed (Poisson weights accumulated block by block) |
| ``linear`` | closed-form Sobol indices of the first-order model J(pose) e: at poses, pose uniform
  in a box (Gauss-Legendre), and the size of the nonlinear remainder it misses |
| ``checks`` | the closed form over a workspace (atlas, dominant errors) and checked against
  sampled indices of the exact model (family-wise bootstrap intervals plus the remainder) |
| ``pce`` | sparse polynomial chaos (OMP/LARS, bases by input law, validated basis adaptivity) and
  Sobol indices from its coefficients (Zheng et al.); a package: ``basis``, ``solvers``,
  ``fit``, ``sparse`` |
| ``results`` | the one result shape: :class:`IndexArray`, a labelled ``(..., d, q)`` array |
| ``benchmarks`` | Ishigami, G function, interaction polynomial: exact indices for tests and bench |
| ``screening`` | key-error selection rules (the 90 % rule, its bootstrap frequencies and
  margin) and reduced models (Rong et al.); imports ``sobol``, never the reverse |
| ``tie_rule`` | the one tie rule (``ties``, ``merge_ties``, ``rank_with_ties``) |
| ``posefit`` | which pose explains a published table: candidate screening and least-squares or
  Powell refinement for any statistic (notebooks 01 and 03) |

Conventions.  The inputs are one :class:`Inputs` (or, where a function still takes bare
arrays, ``sd=`` or ``var=`` by keyword: never one for the other).  Randomness is one argument,
``seed``: None, an int or a ``numpy.random.Generator`` (``mtaccuracy.validate.rng``).  Index
arrays put inputs before outputs, ``(..., d, q)``, with any leading axis (poses, bootstrap
resamples) first: ``sobol_indices``, ``sobol_estimate``, ``linear_indices``,
``indices_at_poses``, ``pose_box_indices`` and the key-set rules of ``screening`` (a Jacobian
is ``(..., q, d)``, outputs by inputs, as a derivative is written); :func:`pce_sobol` is one
output's ``(d,)``.

One result shape (:mod:`~mtaccuracy.sensitivity.results`): every analyser returns what its
callers have always indexed or unpacked, labelled by input and output names, with ``.to_df()``
(a long table, outputs outermost): :class:`SobolIndices` (``sobol_indices``, ``pce_sobol``;
``s1, st = ...``), :class:`SpearmanCoefficients` (``spearman``, ``spearman_over_poses``: the
array, its ``to_df()`` the ranking), :class:`LinearIndices` (``linear_indices``,
``indices_at_poses``: the array), :class:`PoseBoxIndices` (``pose_box_indices``:
``s1, st, var = ...``), :class:`KeySets` (``key_errors_by_output``: the dict),
:class:`KeySetFrequencies` (``key_set_bootstrap``: ``freq, counts = ...``) and
:class:`SparsePCE`.
"""

from . import benchmarks  # noqa: F401
from .bootstrap import *  # noqa: F403
from .checks import *  # noqa: F403
from .inputs import *  # noqa: F403
from .linear import *  # noqa: F403
from .pce import *  # noqa: F403
from .posefit import *  # noqa: F403
from .results import *  # noqa: F403
from .screening import *  # noqa: F403
from .sobol import *  # noqa: F403
from .spearman import *  # noqa: F403
from .tie_rule import *  # noqa: F403
