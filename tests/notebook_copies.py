"""``python tests/notebook_copies.py DIR``: the committed notebooks, parameterised to write there.

``make check`` runs nbval on these copies: each is the committed notebook (its stored outputs
are what nbval compares) with papermill's injected cell setting ``output_dir`` to
``DIR/figures/<stem>``, so that executing it never writes over ``figures/``; the output folder
reaches the notebook as a parameter, like every run of the workflow.
"""

import sys
from pathlib import Path

import nbformat
from papermill.parameterize import parameterize_notebook

ROOT = Path(__file__).resolve().parents[1]


def main(argv: list[str]) -> int:
    if len(argv) != 1:
        print(__doc__.splitlines()[0], file=sys.stderr)
        return 2
    out = Path(argv[0]).resolve()
    (out / "notebooks").mkdir(parents=True, exist_ok=True)
    for path in sorted((ROOT / "notebooks").glob("[0-9][0-9]_*.ipynb")):
        nb = nbformat.read(path, as_version=4)
        nb = parameterize_notebook(nb, {"output_dir": str(out / "figures" / path.stem)},
                                   kernel_name="python3", language="python")
        nbformat.write(nb, out / "notebooks" / path.name)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
