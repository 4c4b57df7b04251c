"""Spindle radial error separation with four (or more) probes (Yang et al. 2021).

Modules:

``separation``
    the probe model (Eq. 7), the weights (Eqs. 5, 15), the eigenvalues and the transfer
    function (Eqs. 14, 19), the matrix method (Eqs. 3-10);
``least_squares``
    the least-squares multi-probe estimator beside it, on the sampling grid;
``design``
    the layout objective ``H = q_k^2`` (Eqs. 19-20), its bounds, the best ``a_3``, canonical
    layouts;
``optimise``
    the genetic algorithms (fixed rates, and the adaptive rates of Eqs. 22-23) and differential
    evolution, batched over runs;
``simulate``
    simulated measurements (Section 3);
``probes``
    the separation at any probe angles (the weighted method with weights for the given
    angles, and least squares): what a layout separates, its noise amplification;
``probedata``
    a reader's own multi-probe measurement as any reader returns it (:class:`ProbeData`) and
    the checks that hold whatever its file format;
``probefile``
    the probe file (``revolution``, ``angle_deg``, ``probe_<angle>_um``): its reader and
    writer;
``timefile``
    a DAQ's time-sampled readings (``time_s`` with ``index`` or ``encoder_deg``) resampled onto
    equal angles, the speed and its drift fitted to all marks together;
``example``
    the shipped simulated example and its truth;
``checks``
    what a separation tells about its data: the sense of rotation
    (:class:`~mtaccuracy.spindle.checks.RotationSenseWarning`) and aliasing
    (:class:`~mtaccuracy.spindle.checks.AliasingWarning`);
``errormotion``
    radial error motion in ISO 230-7 terms: fixed and rotating sensitive directions,
    synchronous, asynchronous and total error motion values about the LSC or MRS centre, the
    profile about its least-squares circle; the separated motion per sample, the spectrum of its
    asynchronous part, the ISO 230-7 low-pass filter in undulations per revolution.

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
from . import (  # noqa: F401
    checks,
    design,
    errormotion,
    example,
    least_squares,
    optimise,
    probedata,
    probefile,
    probes,
    separation,
    simulate,
    timefile,
)
from .checks import *  # noqa: F403
from .design import *  # noqa: F403
from .errormotion import *  # noqa: F403
from .example import *  # noqa: F403
from .least_squares import *  # noqa: F403
from .optimise import *  # noqa: F403
from .probedata import *  # noqa: F403
from .probefile import *  # noqa: F403
from .probes import *  # noqa: F403
from .separation import *  # noqa: F403
from .simulate import *  # noqa: F403
from .timefile import *  # noqa: F403
