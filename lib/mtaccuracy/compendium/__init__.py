"""The compendium's workflow: how this repository runs, records and scores its notebooks.

None of it is science or paper code: the science packages and :mod:`mtaccuracy.papers` never
import it (``tests/test_layering.py``); the apps (:mod:`mtaccuracy.apps`: the book, the
explorer, the bench, the lab) read what it records.

==================  =================================================================
``notebook``        a notebook's first call (:func:`notebook.start`: its parameters checked,
                    its output folder, its run) and what it saves through (:class:`notebook.Run`)
``workflow``        ``make reproduce`` and ``make sweep`` on Snakemake (``workflow/Snakefile``):
                    the request checked, each notebook executed with papermill and published
``provenance``      which notebook, library modules, parameters and inputs made each output
``reproduction``    a notebook's scorecard (``Card``), the tolerance policy, byte-stable tables
``scorecard``       every notebook's card gathered (``figures/REPRODUCTION.md``, README)
``plotting``        the house style and byte-stable figure files
==================  =================================================================

Run as a command (``python -m mtaccuracy.compendium.<tool>``), a tool stopped with Ctrl-C says
so in one line instead of a traceback (:func:`_one_line_interrupt`).
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
