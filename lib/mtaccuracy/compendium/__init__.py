"""The compendium's machinery: how this repository runs, checks and publishes its notebooks.

None of it is science; the science packages (:mod:`mtaccuracy.kinematics`,
:mod:`mtaccuracy.errors`, :mod:`mtaccuracy.machines`, :mod:`mtaccuracy.sensitivity`,
:mod:`mtaccuracy.spindle`, :mod:`mtaccuracy.roundness`, :mod:`mtaccuracy.thermal`,
:mod:`mtaccuracy.optimise`) never import it, and ``tests/test_layering.py`` enforces that
direction, so they can be taken into other work without this repository's runner.

==========================  ===========================================================
``parameters``              the notebooks' parameter language: declarations, checks,
                            ``check_parameters``, ``ParameterError`` (what notebooks import)
``runner``                  runs a notebook with papermill: staging, the commit, Ctrl-C safety
                            (``python -m mtaccuracy.compendium.runner``, ``make reproduce``)
``paths``                   the repository's folders, output folders, input files checked
``provenance``              which code, notebook, parameters and inputs made each output
``reproduction``            published values (``data/papers/``), tolerances, the scorecard ``Card``,
                            ``figures/REPRODUCTION.md``
``book``                    ``make book``: the published book (Sphinx, MyST-NB), its checks of
                            every output shown against ``provenance.json``
``plotting``                the house style and byte-stable figure files
``bench``                   ``make bench``: the speed targets of the issues, measured
``lab``                     ``make lab``: JupyterLab at the repository root
``explore``                 ``make explore``: the interactive explorer (Panel)
``zheng2024``               notebook 01: the pose search (orbits, fits to the published indices,
                            fixed ratios), the test points of Fig. 4, references and figures
``rong``                    notebook 02: linear Sobol' at the paper's tool and poses, ranking at the
                            tables' precision, the range-set bracket and the tool-length figure
``guo2016``                 notebook 03: the printed Eqs. 8, 11-13 against the matrix product
                            (sympy), the units-slip reading of Eq. 12, exchangeable pairs and
                            what an XY circle sees in the paper's model
``xu2022``                  notebook 04: published tables, the reconstruction's folders, tolerances,
                            scorecard helpers and figures
``xu2022_reconstruction``   notebook 04's seeded reconstruction of the paper's dataset,
                            calibrated to its printed tables (``data/thermal/``)
``yang2021``                notebook 05's parameter checks, Table 1's consistency check, the GA
                            settings study, the simulated experiment's inputs and figures
``your_machine``            notebook 06's chain figure and the numbers of its conclusion
``commit``                  the journalled commit of a finished run; finishes one a kill interrupted
``memory``                  the memory a run may use (available memory, cgroups, ``ulimit -v``)
``ownenv``                  refuses a ``.venv`` that runs another checkout's code
==========================  ===========================================================

Run as a command (``python -m mtaccuracy.compendium.<tool>``, as the Makefile does), a tool
stopped with Ctrl-C says so in one line instead of a traceback, wherever it was (importing
its dependencies included): :func:`_one_line_interrupt` is installed when this package is
imported on the way to ``-m``.
"""

import sys


def _one_line_interrupt(kind, value, tb, _previous=sys.excepthook):
    """``sys.excepthook`` of the compendium's commands: Ctrl-C ends with one line."""
    if issubclass(kind, KeyboardInterrupt):
        tool = next((a for a in sys.argv[:1] if a and a != "-m"), "the command")
        name = tool.rsplit("/", 1)[-1].removesuffix(".py")
        print(f"interrupted (Ctrl-C): {name} stopped before it finished; every file it "
              f"writes is replaced whole, so none is left half-written", file=sys.stderr)
        return
    _previous(kind, value, tb)


if sys.argv[:1] == ["-m"]:  # python -m mtaccuracy.compendium.<tool>: sys.argv[0] is "-m" here
    sys.excepthook = _one_line_interrupt
