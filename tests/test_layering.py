"""The science packages never import the compendium's machinery (issue 15): a reader can take
kinematics, machines, sensitivity, spindle, roundness and optimise into their own work without
the runner, the book or the provenance of this repository."""

import ast
from pathlib import Path

import mtaccuracy

LIB = Path(mtaccuracy.__file__).parent
MACHINERY = {"compendium"}   # runner, book, provenance, reproduction, paths, plotting, lab, bench
SCIENCE = ["kinematics.py", "errors.py", "roundness.py", "csvlines.py", "machines",
           "sensitivity", "spindle", "optimise", "thermal"]


def _imports(path: Path) -> set[str]:
    """The top-level mtaccuracy modules a file imports (relative imports resolved)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    package = ["mtaccuracy", *path.relative_to(LIB).parts[:-1]]   # where the file lives
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[:len(package) - (node.level - 1)]
            elif node.module and node.module.split(".")[0] == "mtaccuracy":
                base = []
            else:
                continue
            full = base + (node.module.split(".") if node.module else [])
            out.update([full[1]] if len(full) > 1 else [a.name for a in node.names])
        elif isinstance(node, ast.Import):
            out.update(a.name.split(".")[1] for a in node.names
                       if a.name.startswith("mtaccuracy."))
    return out


def _files():
    for entry in SCIENCE:
        p = LIB / entry
        yield from (sorted(p.rglob("*.py")) if p.is_dir() else [p])


def test_science_modules_import_no_machinery():
    bad = {str(f.relative_to(LIB)): sorted(_imports(f) & MACHINERY) for f in _files()}
    bad = {k: v for k, v in bad.items() if v}
    assert not bad, f"science modules importing the compendium's machinery: {bad}"


def test_the_check_sees_an_import_and_covers_every_science_package():
    # the checker itself sees a relative import: book.py's ``from . import paths`` is
    # ``mtaccuracy.compendium``
    assert "compendium" in _imports(LIB / "compendium" / "book.py")
    # every top-level package or module of the library is science or the compendium
    top = {p.name for p in LIB.iterdir() if p.name != "__pycache__" and not p.name.startswith(".")
           and (p.is_dir() or p.suffix == ".py")}
    assert top == {*SCIENCE, "compendium", "__init__.py"}
