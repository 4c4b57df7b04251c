"""The memory a new notebook run may use: cgroup v1 and v2 limits at every level, the machine's
available memory, and the per-process limits less what a kernel maps before any work."""

import json
import math
import os
import resource
import subprocess
import sys
from types import SimpleNamespace

import psutil
import pytest

from mtaccuracy.compendium import memory, runner

RAM = 64e9  # the machine's available memory in the fake-tree tests
GB = 1e9


@pytest.fixture
def only_fakes(monkeypatch):
    """The machine has RAM available and no ulimit -v / -d, whatever runs the tests."""
    monkeypatch.setattr(psutil, "virtual_memory", lambda: SimpleNamespace(available=RAM))
    real = resource.getrlimit
    inf = resource.RLIM_INFINITY

    def getrlimit(which):
        return (inf, inf) if which in (resource.RLIMIT_AS, resource.RLIMIT_DATA) else real(which)

    monkeypatch.setattr(resource, "getrlimit", getrlimit)


def tree(tmp_path, cgroup: str, files: dict[str, str]) -> dict:
    """A fake ``/proc`` whose ``self/cgroup`` is ``cgroup`` and a fake ``/sys/fs/cgroup``
    holding ``files`` (relative path -> content)."""
    proc = tmp_path / "proc"
    (proc / "self").mkdir(parents=True)
    (proc / "self" / "cgroup").write_text(cgroup)
    cg = tmp_path / "cgroup"
    cg.mkdir()
    for rel, text in files.items():
        p = cg / rel
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(text)
    return {"proc_root": proc, "cgroup_root": cg}


SESSION = "user.slice/user-1000.slice/session-3.scope"


def v2(**levels) -> dict[str, str]:
    """A cgroup v2 tree down to SESSION: ``levels`` maps "user", "user1000", "session" to
    ``{file: content}`` of that level."""
    where = {"user": "user.slice", "user1000": "user.slice/user-1000.slice", "session": SESSION}
    files = {"cgroup.controllers": "cpuset cpu io memory pids", f"{SESSION}/cgroup.procs": "1"}
    for key, content in levels.items():
        files.update({f"{where[key]}/{f}": v for f, v in content.items()})
    return files


# --- cgroup v2 ------------------------------------------------------------------------------

@pytest.mark.parametrize("user, user1000, expected", [
    # the nested limit is smaller than its parent's: it wins
    ({"memory.max": "8000000000", "memory.current": "1000000000"},
     {"memory.max": "4000000000", "memory.current": "1500000000"},
     (2.5 * GB, "the cgroup limit (memory.max of /user.slice/user-1000.slice)")),
    # an ancestor's headroom is smaller than the nested one's: the ancestor wins
    ({"memory.max": "3000000000", "memory.current": "2000000000"},
     {"memory.max": "4000000000", "memory.current": "1500000000"},
     (1 * GB, "the cgroup limit (memory.max of /user.slice)")),
])
def test_v2_the_smallest_headroom_of_every_level_wins(tmp_path, only_fakes, user, user1000,
                                                      expected):
    files = v2(user=user, user1000=user1000,
               session={"memory.max": "max", "memory.current": "1000000000"})
    roots = tree(tmp_path, f"0::/{SESSION}\n", files)
    assert memory.available(**roots) == expected
    found = memory.limits(**roots)
    assert [lim.what for lim in found] == [
        "available memory", "the cgroup limit (memory.max of /user.slice/user-1000.slice)",
        "the cgroup limit (memory.max of /user.slice)"]
    assert not any(lim.per_process for lim in found)


def test_v2_memory_high_counts_as_a_soft_limit(tmp_path, only_fakes):
    files = v2(session={"memory.max": "4000000000", "memory.high": "2000000000",
                        "memory.current": "1200000000"})
    assert memory.available(**tree(tmp_path, f"0::/{SESSION}\n", files)) == (
        0.8 * GB, f"the cgroup soft limit (memory.high of /{SESSION})")


def test_v2_inactive_page_cache_is_room_for_a_run(tmp_path, only_fakes):
    stat = ("anon 900000000\nfile 2000000000\nactive_file 500000000\n"
            "inactive_file 1500000000\ninactive_anon 3\n")
    files = v2(session={"memory.max": "4000000000", "memory.current": "3000000000",
                        "memory.stat": stat})
    # 4 GB - (3 GB used - 1.5 GB reclaimable cache)
    assert memory.available(**tree(tmp_path, f"0::/{SESSION}\n", files))[0] == 2.5 * GB


def test_v2_max_everywhere_leaves_the_machines_available_memory(tmp_path, only_fakes):
    files = v2(user={"memory.max": "max", "memory.high": "max", "memory.current": "5"},
               session={"memory.max": "max", "memory.current": "5"})
    assert memory.available(**tree(tmp_path, f"0::/{SESSION}\n", files)) == (
        RAM, "available memory")


def test_v2_on_a_hybrid_system_is_read_under_unified(tmp_path, only_fakes):
    files = {"unified/cgroup.controllers": "", "unified/job/memory.max": "2000000000",
             "unified/job/memory.current": "500000000", "memory/memory.limit_in_bytes": "x"}
    roots = tree(tmp_path, "4:memory:/\n0::/job\n", files)
    assert memory.available(**roots) == (1.5 * GB, "the cgroup limit (memory.max of /job)")


def test_a_containers_own_cgroup_mounted_at_the_root_is_found(tmp_path, only_fakes):
    # /proc/self/cgroup names the host's path; the container sees its cgroup at the root
    files = {"cgroup.controllers": "memory", "memory.max": "1000000000",
             "memory.current": "200000000"}
    roots = tree(tmp_path, "0::/docker/0123abcd\n", files)
    assert memory.available(**roots) == (0.8 * GB, "the cgroup limit (memory.max of /)")


# --- cgroup v1 ------------------------------------------------------------------------------

V1_NONE = "9223372036854771712"   # what the kernel shows for "no limit"
V1_CG = "9:name=systemd:/\n4:memory:/process_api/abc\n1:cpu:/\n0::/\n"


def v1(**files) -> dict[str, str]:
    base = {"memory/memory.limit_in_bytes": V1_NONE, "memory/memory.usage_in_bytes": "9",
            "memory/process_api/memory.limit_in_bytes": V1_NONE,
            "memory/process_api/memory.usage_in_bytes": "3000000000"}
    base.update({f"memory/process_api/abc/{f}": v for f, v in files.items()})
    return base


def test_v1_a_memory_limit_less_the_working_set(tmp_path, only_fakes):
    files = v1(**{"memory.limit_in_bytes": "3000000000", "memory.usage_in_bytes": "1000000000",
                  "memory.stat": "inactive_file 5\ntotal_inactive_file 200000000\n"})
    roots = tree(tmp_path, V1_CG, files)
    assert memory.available(**roots) == (
        2.2 * GB, "the cgroup limit (memory.limit_in_bytes of /process_api/abc)")
    assert len(memory.limits(**roots)) == 2  # the unlimited ancestors add nothing


def test_v1_memory_and_swap_limit_binds_when_swap_is_in_use(tmp_path, only_fakes):
    files = v1(**{"memory.limit_in_bytes": "3000000000", "memory.usage_in_bytes": "1000000000",
                  "memory.memsw.limit_in_bytes": "4000000000",
                  "memory.memsw.usage_in_bytes": "3500000000"})
    assert memory.available(**tree(tmp_path, V1_CG, files)) == (
        0.5 * GB,
        "the cgroup memory+swap limit (memory.memsw.limit_in_bytes of /process_api/abc)")


def test_v1_a_limit_on_an_ancestor_applies(tmp_path, only_fakes):
    files = v1(**{"memory.limit_in_bytes": V1_NONE, "memory.usage_in_bytes": "100"})
    files["memory/process_api/memory.limit_in_bytes"] = "5000000000"
    assert memory.available(**tree(tmp_path, "4:memory,hugetlb:/process_api/abc\n", files)) == (
        2 * GB, "the cgroup limit (memory.limit_in_bytes of /process_api)")


def test_v1_unlimited_everywhere_leaves_the_machines_available_memory(tmp_path, only_fakes):
    files = v1(**{"memory.limit_in_bytes": V1_NONE, "memory.usage_in_bytes": "8396800",
                  "memory.memsw.limit_in_bytes": V1_NONE})
    assert memory.available(**tree(tmp_path, V1_CG, files)) == (RAM, "available memory")


# --- what cannot be read --------------------------------------------------------------------

@pytest.mark.parametrize("content, expected", [
    ({"memory.max": "lots", "memory.current": "1"}, RAM),          # garbage limit: none
    ({"memory.max": "", "memory.current": "1"}, RAM),
    ({"memory.max": "-5", "memory.current": "1"}, RAM),
    ({"memory.max": "2.5e9", "memory.current": "1"}, RAM),         # not a whole number
    ({"memory.max": "2000000000", "memory.current": "??"}, 2 * GB),  # the limit still bounds
    ({"memory.max": "2000000000"}, 2 * GB),                        # usage missing
    ({"memory.max": "2000000000", "memory.current": "3000000000"}, 0.0),  # used up
    ({"memory.max": "2000000000", "memory.current": "500000000",
      "memory.stat": "inactive_file lots\n"}, 1.5 * GB),           # garbage stat: no cache
])
def test_garbage_or_missing_values(tmp_path, only_fakes, content, expected):
    roots = tree(tmp_path, f"0::/{SESSION}\n", v2(session=content))
    assert memory.available(**roots)[0] == expected


def test_a_limit_file_that_is_a_directory_is_no_limit(tmp_path, only_fakes):
    roots = tree(tmp_path, f"0::/{SESSION}\n", v2(session={"memory.max/x": "1"}))
    assert memory.available(**roots) == (RAM, "available memory")


@pytest.mark.parametrize("cgroup", ["", "garbage\n", "0::\n", "0::/nowhere/at/all\n"])
def test_an_unreadable_proc_self_cgroup_means_no_cgroup_limit(tmp_path, only_fakes, cgroup):
    roots = tree(tmp_path, cgroup, {"user.slice/memory.max": "1000"})
    assert memory.available(**roots) == (RAM, "available memory")


def test_without_proc_cgroups_or_psutil_nothing_is_known_and_nothing_raises(tmp_path,
                                                                           only_fakes,
                                                                           monkeypatch):
    gone = {"proc_root": tmp_path / "no-proc", "cgroup_root": tmp_path / "no-cgroup"}
    assert memory.available(**gone) == (RAM, "available memory")

    def broken():
        raise OSError("no /proc/meminfo")

    monkeypatch.setattr(psutil, "virtual_memory", broken)
    assert memory.available(**gone) == (math.inf, "no known limit")
    assert memory.limits(**gone) == []


# --- the kernel's own mappings --------------------------------------------------------------

@pytest.mark.parametrize("env, threads", [
    ({}, 8),                                               # all the CPUs
    ({"OPENBLAS_NUM_THREADS": "1"}, 1),
    ({"OPENBLAS_NUM_THREADS": "32"}, 8),                   # never more than the CPUs
    ({"OPENBLAS_NUM_THREADS": "x", "GOTO_NUM_THREADS": "3", "OMP_NUM_THREADS": "2"}, 3),
    ({"OMP_NUM_THREADS": "2,1"}, 2),
    ({"OPENBLAS_NUM_THREADS": "0", "OMP_NUM_THREADS": "4"}, 4),
])
def test_the_baseline_counts_the_blas_threads_openblas_will_start(monkeypatch, env, threads):
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: set(range(8)), raising=False)
    base = memory.kernel_baseline(env)
    assert base.blas_threads == threads
    one = memory.kernel_baseline({"OPENBLAS_NUM_THREADS": "1"})
    workers = memory.BLAS_LIBRARIES * (threads - 1)
    assert base.virtual - one.virtual == pytest.approx(
        workers * (base.stack + memory.BLAS_WORKER_VIRTUAL))
    assert base.data - one.data == pytest.approx(workers * (base.stack + memory.BLAS_WORKER_DATA))


@pytest.mark.parametrize("stack, counted", [(16 * 2**20, 16 * 2**20),
                                            (resource.RLIM_INFINITY, memory.UNLIMITED_STACK)])
def test_the_baseline_counts_every_threads_stack(monkeypatch, stack, counted):
    real = resource.getrlimit
    monkeypatch.setattr(resource, "getrlimit", lambda which: (
        (stack, resource.RLIM_INFINITY) if which == resource.RLIMIT_STACK else real(which)))
    base = memory.kernel_baseline({"OPENBLAS_NUM_THREADS": "1"})
    assert base.stack == counted
    assert base.virtual == memory.KERNEL_VIRTUAL + memory.KERNEL_THREADS * counted
    assert base.data == memory.KERNEL_DATA + memory.KERNEL_THREADS * counted


KERNEL_CODE = """
import json
import matplotlib
matplotlib.use("agg")
import matplotlib.pyplot as plt, numpy as np, pandas, scipy.linalg, sklearn.linear_model
a = np.random.default_rng(0).random((300, 300))
scipy.linalg.solve(a @ a + 300 * np.eye(300), a[:, 0])
fig, ax = plt.subplots()
ax.plot([0, 1])
fig.savefig(__import__("io").BytesIO(), format="png")
status = dict(line.split(":", 1) for line in open("/proc/self/status"))
print(json.dumps({k: int(status[k].split()[0]) * 1024 for k in ("VmSize", "VmData")}))
"""


@pytest.mark.skipif(not os.path.exists("/proc/self/status"), reason="needs Linux's /proc")
def test_the_baseline_covers_a_real_kernel_by_at_most_30_percent():
    """The model's constants hold for the locked libraries: a kernel started as papermill
    starts it, after the imports, a LAPACK solve and a figure, maps no more than the model
    says, and not much less (a model far above it would refuse runs that fit)."""
    from jupyter_client.manager import start_new_kernel

    km, kc = start_new_kernel(kernel_name="python3")
    try:
        out = []
        reply = kc.execute_interactive(
            KERNEL_CODE, timeout=120,
            output_hook=lambda m: out.append(m["content"].get("text", "")))
        assert reply["content"]["status"] == "ok", reply["content"]
    finally:
        kc.stop_channels()
        km.shutdown_kernel(now=True)
    measured = json.loads("".join(out))
    base = memory.kernel_baseline()
    assert measured["VmSize"] <= base.virtual <= 1.3 * measured["VmSize"], (measured, base)
    assert measured["VmData"] <= base.data <= 1.3 * measured["VmData"], (measured, base)


# --- per-process limits, in a process that has them ---------------------------------------

def _under(which: str, limit: int, argv: list[str]) -> subprocess.CompletedProcess:
    """``python *argv`` under a soft and hard ``which`` of ``limit`` bytes."""
    res = getattr(resource, which)
    hard = resource.getrlimit(res)[1]
    if hard != resource.RLIM_INFINITY and hard < limit:
        pytest.skip(f"this process's hard {which} is below {limit}")
    return subprocess.run([sys.executable, *argv], capture_output=True, text=True, timeout=60,
                          preexec_fn=lambda: resource.setrlimit(res, (limit, limit)))


ASK = ["-c", "import json; from mtaccuracy.compendium import memory; "
       "print(json.dumps([memory.available(), memory.kernel_baseline()]))"]


@pytest.mark.parametrize("which, limit, attr, what", [
    ("RLIMIT_AS", 5 * 10**9, "virtual", "the address-space limit (ulimit -v)"),
    ("RLIMIT_DATA", 3 * 10**9, "data", "the data-segment limit (ulimit -d)"),
])
def test_a_per_process_limit_less_the_kernels_own_mappings(which, limit, attr, what):
    res = _under(which, limit, ASK)
    assert res.returncode == 0, res.stderr
    (have, said), base = json.loads(res.stdout)
    assert said == what
    own = memory.kernel_baseline()._asdict()[attr]  # the child has this process's environment
    assert base[memory.Baseline._fields.index(attr)] == own
    assert have == pytest.approx(limit - own) and have <= limit - 0.3 * GB


def test_a_limit_below_the_kernels_own_mappings_leaves_nothing():
    res = _under("RLIMIT_AS", 10**9, ASK)
    assert res.returncode == 0, res.stderr
    assert json.loads(res.stdout)[0] == [0.0, "the address-space limit (ulimit -v)"]


def test_a_per_process_limit_is_marked_as_such():
    res = _under("RLIMIT_AS", 5 * 10**9, ["-c", (
        "import json; from mtaccuracy.compendium import memory; "
        "print(json.dumps({l.what: l.per_process for l in memory.limits()}))")])
    assert res.returncode == 0, res.stderr
    marked = json.loads(res.stdout)
    assert marked.pop("the address-space limit (ulimit -v)") is True
    assert marked and not any(marked.values())  # available memory, cgroups: shared


# --- the runner refuses what the limit cannot hold ------------------------------------------

def test_the_runner_refuses_a_run_an_address_space_limit_cannot_hold(monkeypatch):
    values = {k: p.default for k, p in runner.read_parameters("03").items()}
    need = runner.memory_estimate("03", {**values, "n_samples": 2000})
    base = memory.kernel_baseline().virtual  # the runner's environment is this one
    tight, roomy = int(need + base / 2), int(need + base + 0.3 * GB)
    if memory.available()[0] < roomy:
        pytest.skip("this machine has less memory than the test's roomy limit")
    cmd = ["-m", runner.__name__, "03", "n_samples=2000", "--check"]
    # the limit alone would hold the estimate; the kernel's own mappings make it too small
    refused = _under("RLIMIT_AS", tight, cmd)
    assert refused.returncode == 2, (refused.stdout, refused.stderr)
    assert "memory" in refused.stderr and "ulimit -v" in refused.stderr, refused.stderr
    accepted = _under("RLIMIT_AS", roomy, cmd)
    assert accepted.returncode == 0 and "parameters ok" in accepted.stdout, accepted.stderr
