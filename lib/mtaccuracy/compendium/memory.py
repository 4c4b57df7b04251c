"""How much memory a new notebook run may still use: the smallest headroom of every limit.

The runner refuses a run whose estimated peak memory (the ``# {memory: ...}`` line of a
notebook, which counts the kernel's own libraries and figures as well as the run's arrays)
does not fit, before any kernel starts.  :func:`available` answers "how much may a Jupyter
kernel started by this process still use" as the minimum over every limit that applies to
that child process:

* the machine: ``psutil.virtual_memory().available`` (``MemAvailable``);
* cgroup v2: the process's own cgroup (the ``0::/path`` line of ``/proc/self/cgroup``) and
  each ancestor up to the root; at each level ``memory.max`` and ``memory.high`` minus what
  the level already holds;
* cgroup v1: the ``memory`` controller's cgroup and each ancestor under
  ``<cgroup_root>/memory``; ``memory.limit_in_bytes`` and ``memory.memsw.limit_in_bytes``
  minus what the level already holds;
* per-process limits, inherited by the kernel: ``ulimit -v`` (``RLIMIT_AS``) and ``ulimit -d``
  (``RLIMIT_DATA``), minus what the kernel itself maps before the run does any work
  (:func:`kernel_baseline`).

Decisions
---------
*What a cgroup level already holds* is its working set, ``memory.current`` (v1:
``memory.usage_in_bytes``) minus the inactive page cache (``inactive_file`` of
``memory.stat``, v1 ``total_inactive_file``): the kernel reclaims that cache before it
reclaims or kills anything else, so it is room a run can have.  This is the working set of
cAdvisor, the kubelet's eviction and ``docker stats``.  Without ``memory.stat`` nothing is
subtracted (the smaller, safe headroom).

*memory.high* counts as a limit.  It is a soft limit only in that crossing it does not kill:
the kernel throttles the cgroup's allocations and reclaims hard, and a run's memory is
anonymous (numpy arrays), which without swap cannot be reclaimed, so a run above
``memory.high`` crawls instead of finishing.  systemd's ``MemoryHigh=`` is set as the
workload's intended ceiling.  The phrase says "soft limit" so that a reader knows which.

*cgroup v1 memory+swap* (``memory.memsw.limit_in_bytes``, present when swap accounting is
on) counts as a second limit beside ``memory.limit_in_bytes``.  It is never below the memory
limit, but its headroom is smaller when the cgroup already has pages in swap, and crossing it
kills.  Swap beyond ``memory.limit_in_bytes`` is not counted as room (a run that swaps is
refused, as it should be).  For v2, ``memory.swap.max`` is not read for the same reason:
``memory.max`` alone bounds memory.

*Where the cgroup is.*  ``/proc/self/cgroup`` gives the path from the hierarchy's root; in a
container without a cgroup namespace the container's own cgroup is mounted at the root, so a
path that does not exist under ``cgroup_root`` is looked up without its leading components
(``/docker/<id>`` -> ``/<id>`` -> ``/``).  cgroup v2 is read from ``cgroup_root`` or, on a
hybrid system (v2 mounted at ``<cgroup_root>/unified``), from there.

*Unreadable values.*  A missing or unreadable file, or a value that is not a whole number
(``max`` aside), means that limit does not apply; a readable limit whose usage cannot be read
still bounds the run by the limit itself.  A v1 limit of 2**60 bytes or more (the kernel writes
9223372036854771712 for none) is no limit.  Nothing here raises for a missing ``/proc``,
``/sys/fs/cgroup``, ``psutil`` or ``resource``.

*Per-process limits* (:attr:`Limit.per_process`) hold for each kernel separately: a caller
that shares the machine's memory among several runs at once divides the shared limits among
them, not these.
"""

from __future__ import annotations

import math
import os
import re
from pathlib import Path
from typing import NamedTuple

try:
    import resource
except ImportError:  # pragma: no cover - not on Windows
    resource = None

__all__ = ["Baseline", "Limit", "available", "kernel_baseline", "limits"]

#: A cgroup v1 limit at or above this many bytes means "no limit" (the kernel shows
#: ``PAGE_COUNTER_MAX`` pages: 9223372036854771712 with 4 KiB pages, other sizes elsewhere).
V1_UNLIMITED = 2**60

# --- the kernel's own virtual size (measured; see kernel_baseline) ----------------------------
#: Virtual size of an ipykernel after ``import numpy, scipy, pandas, matplotlib, sklearn``, a
#: BLAS product, a LAPACK solve and one saved figure, less its threads' stacks: measured
#: 1.142e9 bytes, counted with a 10 % margin rounded up.
KERNEL_VIRTUAL = 1.3e9
#: The same for ``VmData`` (what ``RLIMIT_DATA`` counts): measured 0.298e9 bytes.
KERNEL_DATA = 0.35e9
#: Threads of an idle ipykernel besides its main thread (heartbeat, IOPub, control, history,
#: zmq's I/O threads, ...): 13 threads in all, measured.
KERNEL_THREADS = 12
#: Libraries that each keep a pool of BLAS threads: numpy's scipy-openblas64 and scipy's own
#: scipy-openblas32 (``numpy.show_config()`` and ``scipy.show_config()``).
BLAS_LIBRARIES = 2
#: Virtual size and ``VmData`` of each BLAS worker thread besides its stack (its buffers and
#: malloc arena): measured 35.1e6 and 33.6e6 bytes, counted with a 10 % margin.
BLAS_WORKER_VIRTUAL = 40e6
BLAS_WORKER_DATA = 40e6
#: OpenBLAS's compile-time thread cap of both wheels (``MAX_THREADS=64``).
BLAS_MAX_THREADS = 64
#: Thread stack counted when ``ulimit -s`` is unlimited: glibc then gives each thread its
#: built-in default (measured 2 MiB on x86-64); counted at the usual 8 MiB limit, to be safe.
UNLIMITED_STACK = 8 * 2**20


class Limit(NamedTuple):
    """One memory limit that applies to a new kernel, and the headroom it leaves.

    Parameters
    ----------
    bytes : float
        Bytes a new kernel may still use under this limit (0 when it is already used up).
    what : str
        Which limit, for a message: "available memory", "the cgroup limit (memory.max of
        /user.slice)", "the address-space limit (ulimit -v)", ...
    per_process : bool
        True for the per-process limits (``ulimit -v``, ``ulimit -d``), which every kernel
        has whole; False for the machine's memory and the cgroups, shared by all runs.
    """

    bytes: float
    what: str
    per_process: bool = False


class Baseline(NamedTuple):
    """What a freshly started kernel maps before a notebook does any work.

    Parameters
    ----------
    virtual : float
        Its virtual size in bytes (``VmSize``, what ``RLIMIT_AS`` counts).
    data : float
        Its private writable memory in bytes (``VmData``, what ``RLIMIT_DATA`` counts since
        Linux 4.7).
    blas_threads : int
        The number of threads each OpenBLAS pool runs.
    stack : float
        The stack each thread reserves, in bytes.
    """

    virtual: float
    data: float
    blas_threads: int
    stack: float


def _read(path: Path) -> str | None:
    try:
        return path.read_text().strip()
    except (OSError, UnicodeDecodeError, ValueError):
        return None


def _bytes(text: str | None) -> float | None:
    """A limit or usage in bytes: a whole number >= 0, inf for "max" or a v1 'unlimited';
    None for anything else (missing or garbage)."""
    if text is None:
        return None
    if text == "max":
        return math.inf
    try:
        value = int(text)
    except ValueError:
        return None
    if value < 0:
        return None
    return math.inf if value >= V1_UNLIMITED else float(value)


def _stat(level: Path, key: str) -> float:
    """One entry of ``memory.stat``; 0 when it cannot be read."""
    text = _read(level / "memory.stat") or ""
    m = re.search(rf"^{re.escape(key)}\s+(\d+)\s*$", text, re.M)
    return float(m.group(1)) if m else 0.0


def _cgroup_lines(proc_root: Path) -> list[tuple[str, list[str], str]]:
    """``(hierarchy id, controllers, path)`` of each line of ``/proc/self/cgroup``."""
    text = _read(proc_root / "self" / "cgroup") or ""
    out = []
    for line in text.splitlines():
        parts = line.split(":", 2)
        if len(parts) == 3:
            out.append((parts[0], [c for c in parts[1].split(",") if c], parts[2]))
    return out


def _levels(base: Path, path: str) -> list[Path]:
    """The cgroup directory of ``path`` under ``base`` and each of its ancestors up to
    ``base``, innermost first; leading components that do not exist under ``base`` are
    dropped (a container's own cgroup mounted at the root)."""
    parts = [p for p in path.split("/") if p and p not in (".", "..")]
    for i in range(len(parts) + 1):
        here = base.joinpath(*parts[i:])
        if here.is_dir():
            levels = [here]
            while here != base:
                here = here.parent
                levels.append(here)
            return levels
    return []


def _name(base: Path, level: Path) -> str:
    rel = level.relative_to(base).as_posix()
    return "/" if rel == "." else "/" + rel


def _headroom(level: Path, limit_file: str, usage_file: str, inactive_key: str) -> float | None:
    """``limit - (usage - inactive page cache)`` at one level, at least 0; None when the
    level sets no readable limit."""
    limit = _bytes(_read(level / limit_file))
    if limit is None or math.isinf(limit):
        return None
    usage = _bytes(_read(level / usage_file))
    if usage is None or math.isinf(usage):
        return limit  # the limit still bounds the run
    working = max(usage - _stat(level, inactive_key), 0.0)
    return max(limit - working, 0.0)


def _cgroup_v2(proc_root: Path, cgroup_root: Path) -> list[Limit]:
    path = next((p for hid, ctl, p in _cgroup_lines(proc_root) if hid == "0" and not ctl), None)
    if path is None:
        return []
    base = cgroup_root
    if not (base / "cgroup.controllers").is_file() \
            and (base / "unified" / "cgroup.controllers").is_file():
        base = base / "unified"  # hybrid: v1 controllers, v2 at unified/
    out = []
    for level in _levels(base, path):
        for limit_file, kind in (("memory.max", "the cgroup limit"),
                                 ("memory.high", "the cgroup soft limit")):
            room = _headroom(level, limit_file, "memory.current", "inactive_file")
            if room is not None:
                out.append(Limit(room, f"{kind} ({limit_file} of {_name(base, level)})"))
    return out


def _cgroup_v1(proc_root: Path, cgroup_root: Path) -> list[Limit]:
    path = next((p for _, ctl, p in _cgroup_lines(proc_root) if "memory" in ctl), None)
    if path is None:
        return []
    base = cgroup_root / "memory"
    out = []
    for level in _levels(base, path):
        for limit_file, usage_file, kind in (
                ("memory.limit_in_bytes", "memory.usage_in_bytes", "the cgroup limit"),
                ("memory.memsw.limit_in_bytes", "memory.memsw.usage_in_bytes",
                 "the cgroup memory+swap limit")):
            room = _headroom(level, limit_file, usage_file, "total_inactive_file")
            if room is not None:
                out.append(Limit(room, f"{kind} ({limit_file} of {_name(base, level)})"))
    return out


def _soft_rlimit(which: int) -> float | None:
    """The soft limit in bytes; None when unlimited or unknown."""
    try:
        soft, _ = resource.getrlimit(which)
    except (OSError, ValueError, TypeError, AttributeError):
        return None
    if soft == resource.RLIM_INFINITY or soft < 0:
        return None
    return float(soft)


def _blas_threads(environ) -> int:
    """The threads each OpenBLAS pool of a kernel started with ``environ`` runs, as OpenBLAS
    decides it: ``OPENBLAS_NUM_THREADS``, else ``GOTO_NUM_THREADS``, else
    ``OMP_NUM_THREADS``, else the CPUs this process may run on; never more than those CPUs
    nor ``BLAS_MAX_THREADS``."""
    try:
        cpus = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        cpus = os.cpu_count() or 1
    wanted = cpus
    for var in ("OPENBLAS_NUM_THREADS", "GOTO_NUM_THREADS", "OMP_NUM_THREADS"):
        m = re.match(r"\s*(\d+)", environ.get(var, ""))
        if m and int(m.group(1)) > 0:
            wanted = int(m.group(1))
            break
    return max(1, min(wanted, cpus, BLAS_MAX_THREADS))


def kernel_baseline(environ=None) -> Baseline:
    """Virtual size and data size of a new kernel before the notebook does any work.

    An address-space limit counts mappings, not memory used, and a Python kernel maps far
    more than it holds: on the 2-core reference machine an ipykernel that has imported
    numpy, scipy, pandas, matplotlib and scikit-learn, multiplied two matrices, solved a
    system and saved a figure has a ``VmSize`` of 1.33e9 bytes (1.24e9 with
    ``OPENBLAS_NUM_THREADS=1``) for a resident size of 0.22e9 bytes.  The difference is its
    threads' stacks (8 MiB each under ``ulimit -s 8192``), their malloc arenas (up to 64 MiB
    of address space each), OpenBLAS's buffers and mapped libraries.  The same imports in a plain
    ``python -c`` measure only 0.46e9 bytes (0.37e9 single-threaded): the kernel's
    machinery (IPython, zmq, its 12 extra threads) is most of it, so a measurement has to
    start a real kernel.

    This is a model with constants measured once on the locked environment, not a
    measurement at run time: starting a kernel and importing the libraries took 4 to 16 s
    on the 2-core machine, longer than the whole parameter check, and would be paid by every
    ``--check``; a cached measurement would need invalidating on every input the model
    reads.  What varies from machine to machine is read at run time: the thread stack size
    (``ulimit -s``) and the BLAS threads (``OPENBLAS_NUM_THREADS``, ``GOTO_NUM_THREADS``,
    ``OMP_NUM_THREADS``, the CPUs), which on a 64-core machine add some 5 GB of mappings.  The
    model, with a margin of about 10 %::

        virtual = KERNEL_VIRTUAL + stack * threads + BLAS_WORKER_VIRTUAL * workers
        data    = KERNEL_DATA    + stack * threads + BLAS_WORKER_DATA    * workers
        workers = BLAS_LIBRARIES * (blas_threads - 1)
        threads = KERNEL_THREADS + workers

    It was fitted to ``ulimit -s`` 8192, 16384 and unlimited, each with and without
    ``OPENBLAS_NUM_THREADS=1`` (to within 0.1 MB), and ``tests/test_memory.py`` starts a real
    kernel and checks that the model covers it by at most 30 %, so a change of the locked
    libraries that moves it fails a test instead of letting a run die half-way.  The
    notebooks' further imports (sympy, SALib, chaospy, the library) add about as much virtual
    as resident size (45 MB), which their memory estimates already count.

    Parameters
    ----------
    environ : Mapping[str, str] or None
        The environment the kernel will be started with; None for ``os.environ`` (a kernel
        inherits its parent's environment).

    Returns
    -------
    Baseline
        ``virtual`` and ``data`` in bytes, with the ``blas_threads`` and thread ``stack``
        (bytes) they were computed for.
    """
    environ = os.environ if environ is None else environ
    stack = _soft_rlimit(resource.RLIMIT_STACK) if resource is not None else None
    stack = UNLIMITED_STACK if stack is None else stack
    blas = _blas_threads(environ)
    workers = BLAS_LIBRARIES * (blas - 1)
    stacks = stack * (KERNEL_THREADS + workers)
    return Baseline(virtual=KERNEL_VIRTUAL + stacks + BLAS_WORKER_VIRTUAL * workers,
                    data=KERNEL_DATA + stacks + BLAS_WORKER_DATA * workers,
                    blas_threads=blas, stack=stack)


def _process_limits() -> list[Limit]:
    if resource is None:
        return []
    out, base = [], None
    for which, attr, what in (("RLIMIT_AS", "virtual", "the address-space limit (ulimit -v)"),
                              ("RLIMIT_DATA", "data", "the data-segment limit (ulimit -d)")):
        limit = _soft_rlimit(getattr(resource, which, None))
        if limit is None:
            continue
        base = base or kernel_baseline()
        out.append(Limit(max(limit - getattr(base, attr), 0.0), what, per_process=True))
    return out


def limits(*, proc_root="/proc", cgroup_root="/sys/fs/cgroup") -> list[Limit]:
    """Every memory limit that applies to a kernel this process starts, with its headroom.

    Parameters
    ----------
    proc_root : str or Path
        Where ``/proc`` is (``<proc_root>/self/cgroup`` names this process's cgroups).
    cgroup_root : str or Path
        Where the cgroup hierarchies are mounted (v2 there or at ``unified/``, v1 memory at
        ``memory/``).

    Returns
    -------
    list of Limit
        The machine's available memory (when psutil can tell), each cgroup level's limits
        (innermost first, v2 then v1) and the per-process limits, in that order; empty when
        none is known.
    """
    out = []
    try:
        import psutil  # optional here: without it the other limits still apply

        out.append(Limit(float(psutil.virtual_memory().available), "available memory"))
    except Exception:  # no psutil, or a platform it cannot read: that limit is unknown
        pass
    proc_root, cgroup_root = Path(proc_root), Path(cgroup_root)
    out += _cgroup_v2(proc_root, cgroup_root)
    out += _cgroup_v1(proc_root, cgroup_root)
    out += _process_limits()
    return out


def available(*, proc_root="/proc", cgroup_root="/sys/fs/cgroup") -> tuple[float, str]:
    """Bytes a new notebook run may still use, and which limit says so.

    The run is a Jupyter kernel started by this process; the answer is the smallest
    headroom of :func:`limits` (the machine's available memory, every cgroup v1 and v2 level
    from this process's cgroup up to the root, ``ulimit -v`` and ``ulimit -d`` less the
    kernel's own mappings, :func:`kernel_baseline`).  It is compared with a notebook's
    memory estimate, which counts the kernel's libraries and figures as well as its arrays.

    Parameters
    ----------
    proc_root : str or Path
        Where ``/proc`` is (tests pass a fake tree).
    cgroup_root : str or Path
        Where the cgroup hierarchies are mounted.

    Returns
    -------
    tuple of (float, str)
        The bytes (``inf`` when no limit is known) and a short phrase naming the limit, such
        as "available memory", "the cgroup limit (memory.max of /user.slice)" or "the
        address-space limit (ulimit -v)"; ties go to the first in :func:`limits`' order.
    """
    best = tightest(limits(proc_root=proc_root, cgroup_root=cgroup_root))
    return best.bytes, best.what


def tightest(found: list[Limit], *, share: int = 1) -> Limit:
    """The limit that leaves a run the fewest bytes when ``share`` runs start at once.

    They divide the machine's memory and the cgroups' headroom, while each has a per-process limit
    (``ulimit -v``) whole.

    Parameters
    ----------
    found : list of Limit
        From :func:`limits`.
    share : int
        Runs at once.

    Returns
    -------
    Limit
        Its bytes for one run (``inf`` and "no known limit" when ``found`` is empty); ties go
        to the first in ``found``.
    """
    each = [lim if lim.per_process else lim._replace(bytes=lim.bytes / share) for lim in found]
    return min(each, key=lambda lim: lim.bytes, default=Limit(math.inf, "no known limit"))
