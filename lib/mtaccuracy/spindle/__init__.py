"""Spindle radial error separation with four (or more) probes (Yang et al. 2021).

Modules:

``separation``
    the probe model (Eq. 7), the weights (Eqs. 5, 15), the eigenvalues and the transfer
    function (Eqs. 14, 19), the matrix method (Eqs. 3-10), and the least-squares multi-probe
    estimator beside it;
``design``
    the layout objective ``H = q_k^2`` (Eqs. 19-20), its bounds, the best ``a_3``, canonical
    layouts;
``optimise``
    the genetic algorithms (fixed rates, and the adaptive rates of Eqs. 22-23) and differential
    evolution, batched over runs;
``simulate``
    simulated measurements (Section 3);
``probes``
    a reader's own multi-probe measurement: the probe file (``revolution``, ``angle_deg``,
    ``probe_<angle>_um``), its checks, and the separation at any probe angles (the weighted
    method with weights for the given angles, and least squares), with the shipped simulated
    example;
``errormotion``
    radial error motion in ISO 230-7 terms: fixed and rotating sensitive directions,
    synchronous, asynchronous and total error motion values about the LSC or MRS centre.

Roundness (least-squares circle, minimum zone) is :mod:`mtaccuracy.roundness`.  Every public name
is importable from here: ``from mtaccuracy import spindle as S; S.separate(...)``.

Why hand-written: the four-point separation, its weights and transfer function, and the adaptive
genetic algorithm are what the paper contributes, so they are written out here to be checked line
by line against its equations; the numerical building blocks come from numpy (FFT) and scipy
(``linalg.lstsq``/``pinv``, ``linalg.circulant``, ``optimize.linprog``, ``optimize.minimize``).
The baseline differential evolution follows the scheme of ``scipy.optimize.differential_evolution``
but is written out batched over runs (:func:`_differential_evolution`): scipy runs one
optimisation at a time, looping over the population in Python, and hundreds of runs are needed.
"""

from .. import roundness  # noqa: F401
from ..roundness import *  # noqa: F403
from . import design, errormotion, optimise, probes, separation, simulate  # noqa: F401
from .design import *  # noqa: F403
from .errormotion import *  # noqa: F403
from .optimise import *  # noqa: F403
from .probes import *  # noqa: F403
from .separation import *  # noqa: F403
from .simulate import *  # noqa: F403
