"""The rooms of the library and the direction of its imports: science < papers < compendium
(the workflow) < apps.  A reader can take kinematics, machines, sensitivity, spindle, roundness
and optimise into their own work without the papers, the workflow or the book."""

import ast
from pathlib import Path

import mtaccuracy

LIB = Path(mtaccuracy.__file__).parent
MACHINERY = {"papers", "compendium", "apps"}   # paper code, the workflow, the apps
SCIENCE = ["validate.py", "kinematics.py", "errors.py", "roundness.py", "csvlines.py",
           "machines",
           "sensitivity", "spindle", "optimise", "thermal", "measure"]


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
    # the checker itself sees a relative import: workflow.py's ``from . import provenance`` is
    # ``mtaccuracy.compendium``, its ``from ..papers import ...`` ``mtaccuracy.papers``
    assert {"compendium", "papers"} <= _imports(LIB / "compendium" / "workflow.py")
    # every top-level package or module of the library is science or the compendium
    # (package data, such as a folder of CSV files, holds no module)
    top = {p.name for p in LIB.iterdir() if p.name != "__pycache__" and not p.name.startswith(".")
           and (p.is_dir() and any(p.rglob("*.py")) or p.suffix == ".py")}
    assert top == {*SCIENCE, *MACHINERY, "__init__.py"}


# --- no import cycles; layers in one direction (issue 25 item 4) -----------------------------
#
# The import graph of every mtaccuracy module, from the source (ast): module-level imports and
# function-local ones alike (a function-local import is still a dependency, only a later one).
# ``from pkg import name`` is an edge to ``pkg.name`` when that is a module, else to ``pkg``.

def _module_name(path: Path) -> str:
    parts = ["mtaccuracy", *path.relative_to(LIB).with_suffix("").parts]
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {_module_name(p): p for p in sorted(LIB.rglob("*.py"))}


def _known(name: str) -> str:
    """The module ``name`` lies in (``mtaccuracy.sensitivity.linear.linear_indices`` is
    ``mtaccuracy.sensitivity.linear``)."""
    while name not in MODULES:
        name = name.rpartition(".")[0]
    return name


def _edges(name: str, source: str) -> list[str]:
    """The mtaccuracy modules one module imports, one entry per imported name (repeats kept)."""
    is_package = MODULES.get(name, Path()).name == "__init__.py"
    package = name.split(".") if is_package else name.split(".")[:-1]
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom):
            base = package[:len(package) - node.level + 1] if node.level else []
            full = ".".join(base + (node.module.split(".") if node.module else []))
            if full.split(".")[0] != "mtaccuracy":
                continue
            out += [_known(f"{full}.{a.name}") for a in node.names]
        elif isinstance(node, ast.Import):
            out += [_known(a.name) for a in node.names if a.name.split(".")[0] == "mtaccuracy"]
    return [t for t in out if t != name]


def import_graph(modules=None) -> dict[str, list[str]]:
    """``{module: [imported modules]}`` (``modules``: ``{name: source}``, else the library)."""
    if modules is None:
        modules = {m: p.read_text(encoding="utf-8") for m, p in MODULES.items()}
    return {m: _edges(m, src) for m, src in modules.items()}


def cycles(graph: dict[str, list[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    out = []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in sorted(set(graph.get(v, ()))):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while comp[-1:] != [v]:
                comp.append(stack.pop())
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(out)


#: Cycles that exist today and are being removed; the list may only shrink (the test fails
#: when one of them is gone, so that it is taken off here).
ALLOWED_CYCLES: list[list[str]] = []


def test_no_import_cycles():
    found = cycles(import_graph())
    assert found == ALLOWED_CYCLES, (
        f"import cycles among mtaccuracy modules (function-local imports count): "
        f"{[c for c in found if c not in ALLOWED_CYCLES]}; allowed ones gone (remove them "
        f"from ALLOWED_CYCLES): {[c for c in ALLOWED_CYCLES if c not in found]}")


#: The science layer, bottom first: a module imports only from a lower layer or its own
#: package.  validate (the argument checks) imports nothing of mtaccuracy; csvlines,
#: roundness and optimise import nothing but validate (leaf tools:
#: spindle builds on roundness and optimise, machines, spindle and thermal on csvlines);
#: sensitivity, thermal and spindle do not import one another; measure (the tests as models)
#: builds on machines and them.  Then the paper code, the
#: workflow (compendium) and the apps, each of which may import anything below it.
LAYERS = [{"validate"}, {"csvlines", "roundness", "optimise"}, {"kinematics"}, {"errors"},
          {"machines"},
          {"sensitivity", "thermal", "spindle"}, {"measure"}, {"papers"}, {"compendium"}, {"apps"}]
LAYER = {pkg: k for k, layer in enumerate(LAYERS) for pkg in layer}

#: Imports against the direction that exist today, ``(importer, imported): statements``.
#: The list may only shrink: the test fails on a new one and on one that is gone.
ALLOWED_UPWARD: dict[tuple[str, str], tuple[int, str]] = {}


def _top(module: str) -> str:
    return module.split(".")[1] if "." in module else ""


def upward_imports(graph: dict[str, list[str]]) -> dict[tuple[str, str], int]:
    """``{(importer, imported): count}`` of the imports from a layer into a higher one or a
    sibling package of its own layer (the package ``mtaccuracy`` itself is no layer)."""
    out: dict[tuple[str, str], int] = {}
    for m, targets in graph.items():
        for t in targets:
            a, b = _top(m), _top(t)
            if a and b and a != b and LAYER[b] >= LAYER[a]:
                out[(m, t)] = out.get((m, t), 0) + 1
    return out


def test_science_layers_import_downwards_only():
    found = upward_imports(import_graph())
    allowed = {k: n for k, (n, _why) in ALLOWED_UPWARD.items()}
    new = {k: n for k, n in found.items() if allowed.get(k) != n}
    gone = {k: n for k, n in allowed.items() if found.get(k) != n}
    assert not new and not gone, (
        f"imports against the layers {' -> '.join('/'.join(sorted(la)) for la in LAYERS)}: "
        f"new or changed {new}; allowed ones gone or changed (shrink ALLOWED_UPWARD): {gone}")


def test_every_top_level_module_has_a_layer():
    assert {_top(m) for m in MODULES} - {""} == set(LAYER)


#: Inside ``machines``, bottom first: the topology grammar and the unit checks; the chain;
#: what is built on the chain (the ISO catalogue, the file readers); the papers' machines, which
#: may share descriptions among themselves (horizontal_3axis takes vertical_xyfz's placements).
#: The package itself (the registry) may import any of them.
MACHINES_LAYERS = [{"topology", "units"}, {"chain"}, {"iso", "readers"},
                   {"ac_double_turntable", "horizontal_3axis", "vertical_xyfz"}]
MACHINES_LAYER = {m: k for k, layer in enumerate(MACHINES_LAYERS) for m in layer}


def test_the_machines_modules_import_downwards_only():
    prefix = "mtaccuracy.machines."
    inside = {m[len(prefix):] for m in MODULES if m.startswith(prefix)}
    assert inside == set(MACHINES_LAYER), "every module of machines has a place"
    top = len(MACHINES_LAYERS) - 1
    bad = [(m, t) for m, targets in import_graph().items() if m.startswith(prefix)
           for t in set(targets) if t.startswith(prefix)
           if not (MACHINES_LAYER[t[len(prefix):]] < MACHINES_LAYER[m[len(prefix):]]
                   or MACHINES_LAYER[t[len(prefix):]] == MACHINES_LAYER[m[len(prefix):]] == top)]
    assert not bad, f"imports against {MACHINES_LAYERS} inside machines: {sorted(bad)}"


def test_the_graph_sees_local_imports_cycles_and_upward_imports():
    mods = {"mtaccuracy.kinematics": "def f():\n    from .machines import chain\n",
            "mtaccuracy.machines": "",
            "mtaccuracy.machines.chain": "from .. import kinematics\n",
            "mtaccuracy.errors": "import mtaccuracy.kinematics\n"}
    saved = dict(MODULES)
    MODULES.update({m: Path(f"{m}.py") for m in mods})
    MODULES["mtaccuracy.machines"] = Path("machines/__init__.py")
    try:
        graph = import_graph(mods)
    finally:
        MODULES.clear()
        MODULES.update(saved)
    assert graph["mtaccuracy.kinematics"] == ["mtaccuracy.machines.chain"]   # function-local
    assert graph["mtaccuracy.machines.chain"] == ["mtaccuracy.kinematics"]   # relative
    assert cycles(graph) == [["mtaccuracy.kinematics", "mtaccuracy.machines.chain"]]
    assert upward_imports(graph) == {("mtaccuracy.kinematics", "mtaccuracy.machines.chain"): 1}


# --- function-local imports say why (issue 25 item 1) ----------------------------------------

def _own_statements(fn):
    """The statements of a function at any depth (in ``if``, ``try``, ``with``...), but not
    those of a function or class defined inside it (the outer walk visits those itself)."""
    todo = list(fn.body)
    while todo:
        node = todo.pop()
        yield node
        if not isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            todo += [c for c in ast.iter_child_nodes(node) if isinstance(c, ast.stmt)]


def unexplained_local_imports(source: str) -> list[int]:
    """The lines of function-local imports with no stated reason: no comment on the import
    lines or in the comment lines right above them, and no ``Local imports:`` paragraph in the
    module docstring (a module whose functions import on purpose, say why once)."""
    tree = ast.parse(source)
    if "Local imports:" in (ast.get_docstring(tree) or ""):
        return []
    lines = source.splitlines()
    out = []
    for fn in ast.walk(tree):
        if not isinstance(fn, ast.FunctionDef | ast.AsyncFunctionDef):
            continue
        for node in _own_statements(fn):
            if not isinstance(node, ast.Import | ast.ImportFrom):
                continue
            own = lines[node.lineno - 1:node.end_lineno]
            above, k = [], node.lineno - 2
            while k >= 0 and lines[k].strip().startswith(("#", "import ", "from ")):
                above.append(lines[k])
                k -= 1
            if not any("#" in line for line in own + above):
                out.append(node.lineno)
    return out


def test_every_function_local_import_says_why():
    bad = {str(p.relative_to(LIB)): unexplained_local_imports(p.read_text(encoding="utf-8"))
           for p in MODULES.values()}
    bad = {k: v for k, v in bad.items() if v}
    assert not bad, f"function-local imports without a reason (a comment, or a 'Local " \
                    f"imports:' paragraph in the module docstring): {bad}"


def test_the_local_import_check_sees_a_bare_one():
    bare = "def f():\n    import json\n    return json\n"
    assert unexplained_local_imports(bare) == [2]
    assert unexplained_local_imports("def f():\n    import json  # lazy: rare path\n") == []
    assert unexplained_local_imports("def f():\n    # heavy\n    import a\n    import b\n") == []
    assert unexplained_local_imports('"""M.\n\nLocal imports: heavy."""\n' + bare) == []
    assert unexplained_local_imports("def f():\n    try:\n        import a\n    except "
                                     "ImportError:\n        pass\n") == [3]
