"""The library installs (issue 25, item 6): a wheel built from the sources, installed into a fresh
environment outside the repository, finds its own data and runs the README's library examples
with only its declared dependencies.

The fresh environment is a ``venv --without-pip`` whose ``site-packages`` also sees this
interpreter's (a ``.pth`` line: third-party packages without a download), but not the repository's
``lib`` (the editable install's own ``.pth`` is not processed there).  A guard in the child process
refuses to import any package that is not among the wheel's requirements (or theirs), so a
science module that needs matplotlib, sympy or papermill without declaring it fails here.  The
build runs on a copy of the sources, so that nothing is written into the repository.
"""

import email
import json
import os
import re
import shutil
import subprocess
import sys
import sysconfig
import textwrap
import tomllib
import zipfile
from importlib import metadata
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name
from packaging.version import Version

ROOT = Path(__file__).resolve().parents[2]
#: What the build reads: the package, its metadata and the licence files it ships.
SOURCES = ("lib", "pyproject.toml", "README.md", "LICENSE", "LICENSES.md")
SECTION = "## Using the library in your own work"
PLACEHOLDER = "path/to/your/folder"


#: CONTRIBUTING.md's section of the five typical calls, run like README's examples.
TYPICAL = "## Five typical calls"


def readme_examples(text: str, section: str = SECTION, name: str = "README.md") -> list[str]:
    """The ```python blocks of a section (default: the README's library section), in order."""
    if section not in text:
        raise AssertionError(f"{name} has no section {section!r}")
    part = text.split(section, 1)[1].split("\n## ", 1)[0]
    return re.findall(r"```python\n(.*?)```", part, flags=re.S)


def build_wheel(source: Path, out: Path) -> Path:
    """Build the wheel from a copy of ``source`` (offline, with this environment's setuptools)."""
    tree = out / "src"
    for name in SOURCES:
        p = source / name
        if p.is_dir():
            shutil.copytree(p, tree / name,
                            ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
        else:
            tree.mkdir(parents=True, exist_ok=True)
            shutil.copy(p, tree / name)
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation",
                    "--no-index", "--disable-pip-version-check", "-q", "-w", str(out / "dist"),
                    str(tree)], check=True, capture_output=True, text=True, timeout=120)
    (wheel,) = (out / "dist").glob("mtaccuracy-*.whl")
    return wheel


def core_requirements(wheel: Path) -> list[Requirement]:
    """The wheel's requirements without an extra."""
    with zipfile.ZipFile(wheel) as z:
        (name,) = [n for n in z.namelist() if n.endswith(".dist-info/METADATA")]
        meta = email.message_from_bytes(z.read(name))
    reqs = [Requirement(r) for r in meta.get_all("Requires-Dist") or []]
    return [r for r in reqs if r.marker is None or r.marker.evaluate({"extra": ""})]


def _top_level(dist) -> set[str]:
    text = dist.read_text("top_level.txt")
    if text:
        return set(text.split())
    names = set()
    for f in dist.files or []:
        first = f.parts[0]
        if len(f.parts) > 1 and not first.endswith((".dist-info", ".data")) and first != "..":
            names.add(first)
        elif len(f.parts) == 1 and f.suffix in (".py", ".so", ".pyd"):
            names.add(first.split(".")[0])
    return names - {"__pycache__"}


def undeclared_modules(requirements, site: list[str]) -> set[str]:
    """Top-level modules of the distributions in ``site`` that ``requirements`` do not bring."""
    dists = {canonicalize_name(d.metadata["Name"]): d for d in metadata.distributions(path=site)}
    dists.pop("mtaccuracy", None)                     # the editable install of this checkout
    todo, wanted = list(requirements), set()
    while todo:
        req = todo.pop()
        name = canonicalize_name(req.name)
        if name in wanted or name == "mtaccuracy":    # an extra naming its own package
            continue
        if name not in dists:
            raise AssertionError(f"requirement {req} is not installed in {site}")
        wanted.add(name)
        todo += [r for r in map(Requirement, dists[name].requires or [])
                 if r.marker is None or r.marker.evaluate({"extra": ""})]
    allowed = set().union(*(_top_level(dists[n]) for n in wanted))
    other = set().union(*(_top_level(d) for n, d in dists.items() if n not in wanted))
    return other - allowed - set(sys.stdlib_module_names)


#: Run in the fresh environment: the guard, every science module, the README's examples (each
#: in a namespace of its own, its printed lines checked against their ``# comment``), the Zheng
#: machine against the package's ISO 230-1 map.
CHILD = textwrap.dedent('''
    import contextlib, importlib, io, json, pkgutil, sys
    job = json.loads(sys.argv[1])
    blocked = frozenset(job["blocked"])

    class Undeclared:
        def find_spec(self, name, path=None, target=None):
            if name.partition(".")[0] in blocked:
                raise ModuleNotFoundError(f"{name} is not a declared dependency of mtaccuracy",
                                          name=name)
            return None

    sys.meta_path.insert(0, Undeclared())
    import mtaccuracy
    from mtaccuracy import errors
    modules = []
    def walk(pkg):
        for m in pkgutil.iter_modules(pkg.__path__, pkg.__name__ + "."):
            if m.name not in ("mtaccuracy.papers", "mtaccuracy.compendium", "mtaccuracy.apps"):
                modules.append(m.name)
                mod = importlib.import_module(m.name)
                if m.ispkg:
                    walk(mod)
    walk(mtaccuracy)
    for i, code in enumerate(job["examples"]):
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            exec(compile(code, f"README/CONTRIBUTING example {i + 1}", "exec"),
                 {"__name__": "__main__"})
        printed = out.getvalue().splitlines()
        for line in code.splitlines():
            if line.startswith("print(") and "#" in line:
                want = line.rsplit("#", 1)[1].strip()
                assert want in printed, f"example {i + 1} printed {printed}, its text says {want}"
    from mtaccuracy.machines import build
    zheng = build("ac_double_turntable")
    iso = errors.iso_names()
    assert [e.iso_code for e in zheng.catalogue] == [iso[e.symbol] for e in zheng.catalogue]
    print(json.dumps({"file": mtaccuracy.__file__, "data": str(errors.ISO230_NAMES),
                      "sys_path": sys.path, "modules": modules, "n_zheng": zheng.n_errors,
                      "n_iso": len(iso)}))
''')


def new_environment(where: Path) -> tuple[Path, Path]:
    """A venv without pip whose site-packages also sees this interpreter's (python, site)."""
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(where)], check=True,
                   timeout=60)
    python = where / "bin" / "python"
    site = Path(subprocess.run([str(python), "-I", "-c",
                                "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                               check=True, capture_output=True, text=True).stdout.strip())
    ours = dict.fromkeys([sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]])
    (site / "this_interpreters_packages.pth").write_text("\n".join(ours) + "\n")
    return python, site


def install_and_run(source: Path, tmp: Path) -> dict:
    """Build the wheel of ``source``, install it into a fresh environment under ``tmp`` and run
    :data:`CHILD` there, from a folder outside the repository, without ``PYTHON*`` variables."""
    wheel = build_wheel(source, tmp)
    python, site = new_environment(tmp / "env")
    subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "--no-index",
                    "--disable-pip-version-check", "-q", "--target", str(site), str(wheel)],
                   check=True, capture_output=True, timeout=120)
    shutil.copytree(source / "data" / "thermal", tmp / "your_folder")  # the reader's own data
    blocks = readme_examples((source / "README.md").read_text(encoding="utf-8")) + \
        readme_examples((source / "CONTRIBUTING.md").read_text(encoding="utf-8"), TYPICAL,
                        "CONTRIBUTING.md")
    examples = [b.replace(PLACEHOLDER, str(tmp / "your_folder")) for b in blocks]
    ours = list(dict.fromkeys([sysconfig.get_paths()["purelib"],
                               sysconfig.get_paths()["platlib"]]))
    job = {"examples": examples,
           "blocked": sorted(undeclared_modules(core_requirements(wheel), ours))}
    (tmp / "work").mkdir()
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTHON")}
    run = subprocess.run([str(python), "-I", "-c", CHILD, json.dumps(job)], cwd=tmp / "work",
                         env=env, capture_output=True, text=True, timeout=300)
    return {"wheel": wheel, "site": site, "job": job, "third_party": ours, "run": run}


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """The wheel, its fresh environment and the JSON report of the child run."""
    tmp = tmp_path_factory.mktemp("wheel")
    assert ROOT not in tmp.parents, "the test environment must lie outside the repository"
    out = install_and_run(ROOT, tmp)
    assert out["run"].returncode == 0, out["run"].stderr[-3000:]
    out["report"] = json.loads(out["run"].stdout.strip().splitlines()[-1])
    return out


def test_the_wheel_ships_the_package_data(installed):
    names = zipfile.ZipFile(installed["wheel"]).namelist()
    assert "mtaccuracy/data/iso230_names.csv" in names
    # the installed package reads its data from itself, not from a checkout
    assert Path(installed["report"]["data"]).is_relative_to(installed["site"])
    assert installed["report"]["n_iso"] == 41 and installed["report"]["n_zheng"] == 41


def test_the_examples_ran_on_the_installed_wheel_outside_the_repository(installed):
    report = installed["report"]
    assert Path(report["file"]).is_relative_to(installed["site"])
    # nothing of the checkout on the path but the third-party packages of its .venv
    assert not [p for p in report["sys_path"] if p and Path(p).is_relative_to(ROOT)
                and p not in installed["third_party"]]
    assert str(ROOT / "lib") not in report["sys_path"]
    assert len(installed["job"]["examples"]) >= 3
    assert not [b for b in installed["job"]["examples"] if PLACEHOLDER in b]
    # every science package was imported under the guard
    assert {"mtaccuracy.errors", "mtaccuracy.machines.chain", "mtaccuracy.sensitivity.pce",
            "mtaccuracy.thermal.models", "mtaccuracy.spindle.probes"} <= set(report["modules"])


def test_the_core_dependencies_leave_out_the_compendium(installed):
    core = {canonicalize_name(r.name) for r in core_requirements(installed["wheel"])}
    assert {"numpy", "scipy", "pandas", "scikit-learn"} <= core
    assert not core & {"matplotlib", "papermill", "nbformat", "sympy", "salib", "panel"}
    # so the guard does refuse them in the child process
    assert {"matplotlib", "papermill", "nbformat", "panel"} <= set(installed["job"]["blocked"])
    assert not {"numpy", "scipy", "pandas", "sklearn"} & set(installed["job"]["blocked"])
    # every extra is in the lock this environment was made from (environment.txt)
    with zipfile.ZipFile(installed["wheel"]) as z:
        (name,) = [n for n in z.namelist() if n.endswith(".dist-info/METADATA")]
        every = email.message_from_bytes(z.read(name)).get_all("Requires-Dist")
    missing = []
    for r in map(Requirement, every):
        try:
            metadata.version(r.name)
        except metadata.PackageNotFoundError:
            missing.append(r.name)
    assert not missing, f"declared but not in the locked environment: {missing}"


def test_readme_examples_are_found_and_a_missing_section_is_named():
    assert len(readme_examples((ROOT / "README.md").read_text(encoding="utf-8"))) >= 3
    typical = readme_examples((ROOT / "CONTRIBUTING.md").read_text(encoding="utf-8"), TYPICAL,
                              "CONTRIBUTING.md")
    # a pose error, Sobol indices, a sparse PCE, a spindle separation, a thermal model
    assert len(typical) == 5
    for block, call in zip(typical, ("pose_error", "sobol_indices", "fit_sparse_pce",
                                     "spindle.separate", "thermal.DecoupledRegressor"),
                           strict=True):
        assert call in block and "print(" in block
    with pytest.raises(AssertionError, match="no section"):
        readme_examples("# a README without the library section\n")


def test_the_build_requirement_reads_the_licence_expression():
    """``license = "MIT"`` (an SPDX expression, PEP 639) needs setuptools >= 77; the lock's
    setuptools, which the Makefile's editable install uses (no build isolation), satisfies it."""
    cfg = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    (setuptools,) = [Requirement(r) for r in cfg["build-system"]["requires"]
                     if canonicalize_name(Requirement(r).name) == "setuptools"]
    if isinstance(cfg["project"]["license"], str):
        assert not setuptools.specifier.contains(Version("76.9")), setuptools
    locked = re.search(r"^setuptools==(\S+)$", (ROOT / "environment.txt").read_text(), re.M)
    assert locked and setuptools.specifier.contains(Version(locked[1])), setuptools


def test_make_lock_installs_what_pyproject_declares_and_the_lock_has_each():
    """``make lock`` installs the output of .ci/direct-requirements, which is every direct
    requirement of pyproject.toml (dependencies and extras) but the project itself; each is
    pinned in environment.txt."""
    out = subprocess.run([sys.executable, str(ROOT / ".ci" / "direct-requirements")],
                         capture_output=True, text=True, check=True).stdout.split()
    names = {canonicalize_name(Requirement(r).name) for r in out}
    cfg = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    declared = {canonicalize_name(Requirement(r).name) for r in
                [*cfg["dependencies"], *sum(cfg["optional-dependencies"].values(), [])]}
    assert names == declared - {"mtaccuracy"} and len(out) == len(names)
    pinned = {canonicalize_name(m[1]) for m in
              re.finditer(r"^([A-Za-z0-9_.-]+)==", (ROOT / "environment.txt").read_text(), re.M)}
    assert names <= pinned, f"declared but not pinned: {sorted(names - pinned)}"
    assert "direct-requirements" in (ROOT / "Makefile").read_text()
