"""A ``.venv`` shared with another checkout is refused, never re-pointed (issue 21, item 13).

The fake environments here are ``python -m venv --without-pip`` folders whose ``.pth`` file
puts a checkout's ``lib`` on the path, as the editable install does.
"""

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from mtaccuracy.compendium import ownenv, paths

SCRIPT = paths.ROOT / "lib" / "mtaccuracy" / "compendium" / "ownenv.py"


def _venv(where: Path, lib: Path) -> Path:
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(where)], check=True,
                   timeout=120)
    site = next(where.glob("lib/python3*/site-packages"))
    (site / "__editable__.mtaccuracy-0.1.0.pth").write_text(f"{lib}\n")
    return where / "bin" / "python"


def _other_checkout(root: Path) -> Path:
    pkg = root / "lib" / "mtaccuracy"
    pkg.mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    return root / "lib"


def test_problem_names_both_checkouts():
    assert ownenv.problem(None) is None and ownenv.problem(ownenv.MINE) is None
    msg = ownenv.problem("/elsewhere/clone/lib/mtaccuracy", mine="/here/lib/mtaccuracy")
    assert "belongs to another checkout" in msg and "/elsewhere/clone's code" in msg
    assert "Give /here an environment of its own" in msg


def test_an_environment_of_another_checkout_is_refused(tmp_path):
    other = _other_checkout(tmp_path / "other")
    py = _venv(tmp_path / "venv", other)
    res = subprocess.run([str(py), "-I", str(SCRIPT)], capture_output=True, text=True,
                         timeout=60)
    assert res.returncode == 2 and str(other / "mtaccuracy") in res.stderr
    (next((tmp_path / "venv").glob("lib/python3*/site-packages"))
     / "__editable__.mtaccuracy-0.1.0.pth").write_text(f"{paths.ROOT / 'lib'}\n")
    res = subprocess.run([str(py), "-I", str(SCRIPT)], capture_output=True, text=True,
                         timeout=60)
    assert res.returncode == 0, res.stderr


@pytest.mark.skipif(shutil.which("make") is None, reason="needs make")
def test_make_refuses_a_shared_venv_before_it_would_re_point_it(tmp_path):
    """A fresh clone whose ``.venv`` links to another checkout's environment: ``make`` neither
    installs this checkout into it (the install step checks first) nor runs with it."""
    clone = tmp_path / "clone"
    clone.mkdir()
    for name in ("Makefile", "environment.txt", "pyproject.toml"):
        shutil.copy(paths.ROOT / name, clone / name)
    shutil.copytree(paths.ROOT / "lib", clone / "lib",
                    ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
    other = _other_checkout(tmp_path / "other")
    _venv(tmp_path / "shared", other)
    (clone / ".venv").symlink_to(tmp_path / "shared")
    pth = next((tmp_path / "shared").glob("lib/python3*/site-packages/__editable__*.pth"))
    res = subprocess.run(["make", "--no-print-directory", "lint"], cwd=clone,
                         capture_output=True, text=True, timeout=300)
    assert res.returncode != 0 and "belongs to another checkout" in res.stderr
    assert pth.read_text() == f"{other}\n"  # not re-pointed at the clone
    stamp = subprocess.run("cat environment.txt pyproject.toml | cksum", shell=True, cwd=clone,
                           capture_output=True, text=True).stdout.split()[0]
    (tmp_path / "shared" / f".installed-{stamp}").touch()  # installed: make runs targets
    res = subprocess.run(["make", "--no-print-directory", "lint"], cwd=clone,
                         capture_output=True, text=True, timeout=300)
    assert res.returncode != 0 and "belongs to another checkout" in res.stderr
    assert "ruff" not in res.stdout + res.stderr.split("belongs")[0]
