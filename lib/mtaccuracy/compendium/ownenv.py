"""Refuse a ``.venv`` that runs another checkout's code.

The Makefile installs this checkout into ``.venv`` as an editable package, so that
``.venv/bin/python -m mtaccuracy...`` runs the code of the checkout it belongs to.  A ``.venv``
shared by two checkouts (a symbolic link to one environment, or a copied folder) runs the code of
whichever checkout installed itself last: the other one would silently run foreign code and write
into the foreign checkout's ``figures/`` and ``notebooks/``.  Every ``make`` target runs this
check first (``python -I lib/mtaccuracy/compendium/ownenv.py``: by path and isolated, so that it
imports nothing of the package whose origin it checks), and the install step runs it before it
would re-point the environment at this checkout.

Exit status 0 when ``.venv`` has no ``mtaccuracy`` yet or its ``mtaccuracy`` is this checkout's
``lib/mtaccuracy``; 2, with one paragraph saying what to do, otherwise.
"""

from __future__ import annotations

import importlib.util
import os
import sys

#: This checkout's package folder (``lib/mtaccuracy``), from where this file lies.
MINE = os.path.realpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), os.pardir))


def owner() -> str | None:
    """The ``mtaccuracy`` package folder the running interpreter imports, resolved.

    None when it has none."""
    spec = importlib.util.find_spec("mtaccuracy")
    if spec is None or not spec.origin:
        return None
    return os.path.realpath(os.path.dirname(spec.origin))


def problem(found: str | None, mine: str = MINE, prefix: str = sys.prefix) -> str | None:
    """What is wrong when the environment at ``prefix`` imports ``found`` instead of ``mine``.

    None when nothing is."""
    if found is None or found == mine:
        return None
    other = os.path.dirname(os.path.dirname(found))  # <checkout>/lib/mtaccuracy -> <checkout>
    here = os.path.dirname(os.path.dirname(mine))
    return (f"error: .venv ({os.path.realpath(prefix)}) belongs to another checkout: its "
            f"mtaccuracy is {found}, not this checkout's {mine}. Using it would run {other}'s "
            f"code and write into its figures/ and notebooks/. Give {here} an environment of its "
            f"own: remove the .venv here (if it is a link: rm .venv; the environment it points "
            f"to is kept) and run make again, which creates one from environment.txt.")


def main() -> int:
    msg = problem(owner())
    if msg:
        print(msg, file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
