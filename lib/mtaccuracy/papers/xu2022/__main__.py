"""``python -m mtaccuracy.papers.xu2022 regenerate [FOLDER] [--seed S]``: rewrite ``data/thermal``.

The command is :func:`mtaccuracy.papers.xu2022.data.main` (:func:`.data.regenerate`).
"""

from .data import main

if __name__ == "__main__":
    raise SystemExit(main())
