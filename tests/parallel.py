"""Run pytest sessions side by side: ``python tests/parallel.py "ARGS 1" "ARGS 2" ...``.

``make test`` runs the unit tests (``--part=unit``) and nbval's notebook checks
(``--part=notebooks``) as two pytest sessions at once: each is mostly single-threaded, so on two
cores the pair takes about as long as the longer of the two instead of their sum.  Each argument
is one session's pytest arguments, split by :func:`shlex.split` (the Makefile's own literal
text, never a user's).  The first session prints as it goes; the others print when they end,
whole, under a header, so that no two sessions' lines interleave.  The exit status is the first
non-zero one of the sessions (0 when all passed).

Each session is an ordinary pytest run with its own scratch folder (conftest.py: one per
process) and its own guard on ``figures/`` and ``notebooks/``.  Ctrl-C reaches every session
(one process group); this driver then waits for them and prints what they wrote, so that an
interrupted run still says where it stopped.  With SIGINT ignored (as under some CI runners)
the children inherit that, as they would under ``make`` alone.
"""

from __future__ import annotations

import shlex
import subprocess
import sys
import tempfile
import time


def main(argv: list[str]) -> int:
    if not argv:
        print(__doc__.splitlines()[0], file=sys.stderr)
        return 2
    sessions = [shlex.split(a) for a in argv]
    logs = [tempfile.TemporaryFile(mode="w+", encoding="utf-8") for _ in sessions[1:]]
    t0 = time.perf_counter()
    procs = [subprocess.Popen([sys.executable, "-m", "pytest", *args],
                              stdout=log, stderr=subprocess.STDOUT)
             for args, log in zip(sessions[1:], logs, strict=True)]
    procs.insert(0, subprocess.Popen([sys.executable, "-m", "pytest", *sessions[0]]))
    codes = []
    for proc in procs:
        while True:
            try:
                codes.append(proc.wait())
                break
            except KeyboardInterrupt:   # the sessions got it too: wait for them to stop
                continue
    for args, log, code in zip(sessions[1:], logs, codes[1:], strict=True):
        log.seek(0)
        print(f"\n==== pytest {shlex.join(args)} (ran alongside; exit {code}) ====", flush=True)
        sys.stdout.write(log.read())
        log.close()
    print(f"\n==== {len(sessions)} pytest sessions in {time.perf_counter() - t0:.0f} s; exit "
          f"codes {codes} ====", flush=True)
    return next((c for c in codes if c), 0)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
