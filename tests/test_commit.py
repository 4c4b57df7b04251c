"""The journalled commit of a finished run: a kill at any step leaves one whole run.

The fault-injection tests run the commit in a child process that kills itself with SIGKILL
right after the k-th step that changes the disk, for every k, then run the recovery every
``make`` target starts with, and check that the output folder and the notebook hold either the
old run or the new one, whole, and that the user's own file was never touched.
"""

import json
import os
import signal
import subprocess
import sys

import pytest

from mtaccuracy.compendium import commit, paths

STEM = "01_tiny"
OLD = {"a.csv": "old a\n", "b.png": "old b\n", "gone.csv": "old gone\n"}
NEW = {"a.csv": "new a\n", "b.png": "new b\n", "new.csv": "new\n"}
NB_OLD, NB_NEW = '{"old": 1}\n', '{"new": 1}\n'

# The child: the new run staged as the runner stages it, then the commit (or the recovery).
CHILD = r"""
import json, os, signal, sys
from pathlib import Path
from mtaccuracy.compendium import commit, paths
root, mode, kill_at = Path(sys.argv[1]), sys.argv[2], int(sys.argv[3])
paths.ROOT, paths.NOTEBOOKS, paths.FIGURES = root, root / "notebooks", root / "figures"
steps = []
def step(name):
    steps.append(name)
    if len(steps) == kill_at:
        os.kill(os.getpid(), signal.SIGKILL)
commit._step = step
if mode == "commit":
    new = json.loads(sys.argv[4])
    target = paths.FIGURES / "01_tiny"
    staging = target / f".staging-{os.getpid()}"
    staging.mkdir()
    for name, text in new.items():
        (staging / name).write_text(text)
    side = {"run": {"notebook": "01_tiny"}, "files": {n: {"sha256": commit.sha256(staging / n)}
                                                      for n in new if n != "new.csv"}}
    (staging / "provenance.json").write_text(json.dumps(side))  # new.csv: written unregistered
    tmp = paths.NOTEBOOKS / f".01_tiny.ipynb.commit-{os.getpid()}.tmp"
    tmp.write_text(sys.argv[5])
    commit.commit(staging, target, stem="01_tiny",
                  notebook=(tmp, paths.NOTEBOOKS / "01_tiny.ipynb"))
else:
    commit.recover(quiet=True)
print(json.dumps(steps))
"""


def _old_run(root):
    target = root / "figures" / STEM
    target.mkdir(parents=True)
    (root / "notebooks").mkdir()
    for name, text in OLD.items():
        (target / name).write_text(text)
    side = {"run": {"notebook": STEM},
            "files": {n: {"sha256": commit.sha256(target / n)} for n in OLD}}
    (target / "provenance.json").write_text(json.dumps(side))
    (target / "notes.txt").write_text("the user's notes\n")
    (root / "notebooks" / f"{STEM}.ipynb").write_text(NB_OLD)
    return target


def _child(root, mode, kill_at):
    return subprocess.run([sys.executable, "-c", CHILD, str(root), mode, str(kill_at),
                           json.dumps(NEW), NB_NEW], capture_output=True, text=True, timeout=60)


def _state(root):
    """Which run the folder and the notebook hold: 'old', 'new', or a description of a mix."""
    target = root / "figures" / STEM
    files = {p.name: p.read_text() for p in target.iterdir() if p.is_file()
             and p.name not in ("provenance.json", "notes.txt")}
    nb = (root / "notebooks" / f"{STEM}.ipynb").read_text()
    side = json.loads((target / "provenance.json").read_text())
    listed = set(side["files"])
    if files == OLD and nb == NB_OLD and listed == set(OLD):
        return "old"
    if files == NEW and nb == NB_NEW and listed == set(NEW):
        return "new"
    return f"mixed: files {files}, notebook {nb!r}, manifest {sorted(listed)}"


def _leftovers(root):
    return sorted(str(p.relative_to(root)) for p in root.rglob("*")
                  if p.name.startswith((".staging-", ".01_tiny.ipynb"))
                  or (p.suffix == ".json" and p.parent.name == ".commits"))


def test_a_commit_without_faults_switches_to_the_new_run(tmp_path):
    _old_run(tmp_path)
    res = _child(tmp_path, "commit", 0)
    assert res.returncode == 0, res.stderr
    steps = json.loads(res.stdout)
    assert steps[:2] == ["journal-temp", "journal"] and steps[-1] == "done"
    assert _state(tmp_path) == "new"
    assert (tmp_path / "figures" / STEM / "notes.txt").read_text() == "the user's notes\n"
    assert _leftovers(tmp_path) == []


def test_sigkill_at_every_step_of_the_commit_leaves_one_whole_run(tmp_path):
    """The done criterion of issue 21: SIGKILL at each step, then the next command's
    recovery; the committed state is the old run or the new one, whole."""
    _old_run(tmp_path / "probe")
    steps = json.loads(_child(tmp_path / "probe", "commit", 0).stdout)
    assert len(steps) >= 9  # journal, 4 moves, a removal, the notebook, staging, done
    seen = set()
    for k in range(1, len(steps) + 1):
        root = tmp_path / f"kill{k}"
        _old_run(root)
        res = _child(root, "commit", k)
        assert res.returncode == -signal.SIGKILL, (k, res.stderr)
        rec = _child(root, "recover", 0)
        assert rec.returncode == 0, rec.stderr
        state = _state(root)
        assert state in ("old", "new"), f"killed after step {k} ({steps[k - 1]}): {state}"
        assert (root / "figures" / STEM / "notes.txt").read_text() == "the user's notes\n"
        assert _leftovers(root) == [], k
        seen.add(state)
        # before the journal is in place the old run stands; from then on, the new one
        assert state == ("old" if k < steps.index("journal") + 1 else "new"), k
    assert seen == {"old", "new"}


def test_a_recovery_killed_in_turn_is_finished_by_the_next_one(tmp_path):
    probe = tmp_path / "probe"
    _old_run(probe)
    assert _child(probe, "commit", 4).returncode == -signal.SIGKILL  # after the first moves
    assert _child(probe, "recover", 2).returncode == -signal.SIGKILL  # recovery killed too
    assert _child(probe, "recover", 0).returncode == 0
    assert _state(probe) == "new" and _leftovers(probe) == []


def test_a_staged_file_over_a_file_the_compendium_did_not_write_is_refused(tmp_path, monkeypatch):
    monkeypatch.setattr(paths, "NOTEBOOKS", tmp_path / "notebooks")
    target = _old_run(tmp_path)
    staging = target / ".staging-1"
    staging.mkdir()
    (staging / "notes.txt").write_text("a table called notes.txt\n")
    (staging / "a.csv").write_text("new a\n")
    with pytest.raises(commit.CommitConflict, match=r"notes.txt \(not written by the compendium"):
        commit.commit(staging, target, stem=STEM)
    assert (target / "notes.txt").read_text() == "the user's notes\n"
    assert (target / "a.csv").read_text() == "old a\n"  # nothing moved
    (target / "a.csv").write_text("edited by hand\n")
    (staging / "notes.txt").unlink()
    assert commit.modified_outputs(target, STEM) == ["a.csv"]
    with pytest.raises(commit.CommitConflict, match=r"a.csv \(changed since the compendium"):
        commit.commit(staging, target, stem=STEM)


def test_an_old_output_edited_by_hand_is_left_alone_not_removed(tmp_path, monkeypatch):
    monkeypatch.setattr(paths, "NOTEBOOKS", tmp_path / "notebooks")
    target = _old_run(tmp_path)
    (target / "gone.csv").write_text("the user's edit\n")
    staging = target / ".staging-1"
    staging.mkdir()
    (staging / "a.csv").write_text("new a\n")
    done = commit.commit(staging, target, stem=STEM)
    assert done.left_alone == ["gone.csv", "notes.txt"] and done.removed == ["b.png"]
    assert (target / "gone.csv").read_text() == "the user's edit\n"


@pytest.mark.parametrize("name", ["../outside.txt", "/etc/passwd", "a/../../b", "", "./x"])
def test_a_manifest_never_names_a_file_outside_its_folder(tmp_path, name):
    (tmp_path / "provenance.json").write_text(json.dumps(
        {"run": {"notebook": STEM}, "files": {name: {"sha256": "0"}, "ok.csv": {}}}))
    assert set(commit.manifest(tmp_path, STEM)) == {"ok.csv", "provenance.json"}
    assert commit.manifest(tmp_path, "02_other") == {}


def test_stale_leftovers_of_dead_runs_are_removed_live_ones_kept(tmp_path):
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True).stdout.strip()
    (tmp_path / f".staging-{dead}").mkdir()
    (tmp_path / f".staging-{os.getpid()}").mkdir()
    (tmp_path / f".01_tiny.ipynb.commit-{dead}.tmp").write_text("x")
    (tmp_path / "notes.staging-1").write_text("the user's")
    gone = commit.remove_stale(tmp_path)
    assert sorted(p.name for p in gone) == sorted([f".staging-{dead}",
                                                   f".01_tiny.ipynb.commit-{dead}.tmp"])
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        [f".staging-{os.getpid()}", "notes.staging-1"])
