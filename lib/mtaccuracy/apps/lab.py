"""``make lab``: JupyterLab as Jupyter itself starts it, at the repository root.

Jupyter's own defaults already serve on the loopback interface behind a token; this adds the
repository root as the server's root (so that ``data/machines/`` can be opened beside the
notebooks), opens on ``notebooks/``, and, run as root (a container), ``--allow-root``, which
Jupyter otherwise refuses.  ``LAB_ARGS`` are JupyterLab's own options, split like a shell would
(never run by one) and passed on after these: an option given there wins, and what it exposes
is the user's choice (``--ip=0.0.0.0`` serves the network).
"""

from __future__ import annotations

import os
import shlex
import sys

from ..compendium.provenance import ROOT


def command(lab_args: str = "", *, uid: int | None = None) -> list[str]:
    """The ``jupyter lab`` command line, with ``lab_args`` last.

    Parameters
    ----------
    lab_args : str
        JupyterLab's options as typed (``--port 9999 --no-browser``).
    uid : int, optional
        The user id (default: this process's); 0 adds ``--allow-root``.

    Returns
    -------
    list of str
        The program and its arguments.
    """
    uid = os.getuid() if uid is None else uid
    return [sys.executable, "-m", "jupyter", "lab", "--ServerApp.ip=127.0.0.1",
            f"--ServerApp.root_dir={ROOT}", "--LabApp.default_url=/lab/tree/notebooks",
            *(["--allow-root"] if uid == 0 else []), *shlex.split(lab_args)]


def main() -> int:
    """Replace this process with JupyterLab."""
    try:
        cmd = command(os.environ.get("LAB_ARGS", ""))
    except ValueError as exc:
        print(f"error: LAB_ARGS: {exc}", file=sys.stderr)
        return 2
    os.execv(cmd[0], cmd)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
