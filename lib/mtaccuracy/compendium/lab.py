"""``make lab``: JupyterLab on the notebooks, bound to 127.0.0.1 and protected by a token.

As root (containers, CI machines) JupyterLab refuses to start without ``--allow-root``; it is
added then.  ``LAB_ARGS`` (from the environment, split like a shell would but never evaluated by
one) is appended, e.g. ``make lab LAB_ARGS="--port 9999 --no-browser"``; an argument that would
expose the server beyond this machine or switch its token off is refused.
"""

from __future__ import annotations

import os
import shlex
import sys
from pathlib import Path

from . import paths

_LOCAL = {"127.0.0.1", "localhost", "::1"}


class LabArgsError(ValueError):
    """LAB_ARGS that cannot be passed on."""


def command(lab_args: str = "", uid: int | None = None) -> list[str]:
    """The JupyterLab command line for ``lab_args`` run by user ``uid`` (default: ours)."""
    uid = os.getuid() if uid is None else uid
    try:
        extra = shlex.split(lab_args)
    except ValueError as exc:
        raise LabArgsError(f"LAB_ARGS={lab_args!r}: {exc}") from None
    for i, a in enumerate(extra):
        key, _, value = a.partition("=")
        if key.lstrip("-") in ("ip", "ServerApp.ip"):
            value = value or (extra[i + 1] if i + 1 < len(extra) else "")
            if value.strip("'\"[]") not in _LOCAL:
                raise LabArgsError(f"LAB_ARGS: {a!r} would serve the notebooks beyond this "
                                   f"machine; the lab stays on 127.0.0.1 (use an SSH tunnel)")
        if key.lstrip("-").endswith(("token", "password")) and value.strip("'\"") == "" \
                and "=" in a:
            raise LabArgsError(f"LAB_ARGS: {a!r} would switch the token off; the lab keeps it")
    jupyter = Path(sys.executable).with_name("jupyter")
    cmd = [str(jupyter), "lab", "--ip=127.0.0.1", f"--notebook-dir={paths.NOTEBOOKS}"]
    if uid == 0:
        cmd.append("--allow-root")
    return cmd + extra


def main() -> int:
    try:
        cmd = command(os.environ.get("LAB_ARGS", ""))
    except LabArgsError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print("==> " + " ".join(shlex.quote(c) for c in cmd), flush=True)
    os.execv(cmd[0], cmd)
    return 0  # pragma: no cover - execv does not return


if __name__ == "__main__":
    raise SystemExit(main())
