"""The parameter language of the notebooks: declaring, reading and checking their parameters.

A notebook declares its parameters in the one code cell tagged ``parameters``, one
assignment per line with a comment; the comment may start with constraints in braces::

    n_samples = 500  # {>= 2, <= 200000} Latin hypercube sample size
    method = "lhs"  # {in: lhs|mc} sampling method
    focus = ["dx(z)"]  # {errors: vertical_xyfz} errors to highlight
    # {memory: 3e8 + 8 * n_samples * 21 * 4} peak bytes of a run

A comment too long for one line (the notebooks are linted at 100 characters) continues on the
next lines, each an indented comment (``    # ...``): the constraints and the help, or the
memory expression, read as if they were on one line::

    tool_offset_mm = [0.0, 0.0, 0.0]  # {>= -1000, <= 1000} tool tip relative to the
        # carriages' reference point (mm)

The type is the default's type (an int parameter refuses 2.5; a float one accepts 2); a float
must be finite.  The ``memory`` line is an arithmetic expression of the parameters giving the
run's peak memory in bytes: a run that cannot fit in the memory available is refused before it
starts, naming the limit.  ``output_dir`` must be the notebook's own folder under ``figures/``
or a folder outside the repository (:func:`mtaccuracy.compendium.paths.check_output_dir`).

A notebook's next cell calls :func:`check_parameters` (``from mtaccuracy.compendium.parameters
import check_parameters``), so an interactive run in JupyterLab refuses a bad value too; the
runner (:mod:`mtaccuracy.compendium.runner`) calls :func:`validate` before any kernel starts.
Every refusal, here and in a paper's own parameter checks (``rong.check_sweeps``,
``xu2022.check_data``), is a :class:`ParameterError`, a ``ValueError``.

This module holds no execution: the notebooks import it, not the runner.
"""

from __future__ import annotations

import ast
import json
import math
import operator
import os
import re
from dataclasses import dataclass
from pathlib import Path

from . import memory, paths, provenance


class ParameterError(ValueError):
    """A notebook parameter is unknown, of the wrong type or outside its constraints."""


@dataclass
class Parameter:
    name: str
    default: object
    constraints: list[tuple[str, object]]
    help: str

    def describe(self) -> str:
        cons = ", ".join(f"{op} {v:g}" if op not in ("in", "errors") else
                         (f"one of {'|'.join(v)}" if op == "in" else f"error names of {v}")
                         for op, v in self.constraints)
        kind = type(self.default).__name__ if self.default is not None else "any"
        if self.name == "output_dir":
            cons = "its own folder under figures/ or a folder outside the repository"
        return (f"{self.name} = {self.default!r} ({kind}{'; ' + cons if cons else ''})"
                f"{'  ' + self.help if self.help else ''}")


_CONSTRAINT = re.compile(r"^\s*\{([^}]*)\}\s*(.*)$")
_MEMORY = re.compile(r"^\s*#\s*\{\s*memory\s*:([^}]*)\}")
_OPS = (">=", "<=", ">", "<")
_CONTINUED = re.compile(r"^[ \t]+#(.*)$")


def _continued(lines: list[str], start: int) -> list[str]:
    """The text of the indented comment lines from ``lines[start]`` on (a comment's
    continuation), up to the first other line."""
    out = []
    for line in lines[start:]:
        m = _CONTINUED.match(line)
        if not m:
            break
        out.append(m.group(1).strip())
    return out


def _parse_constraints(text: str, where: str) -> list[tuple[str, object]]:
    out = []
    for clause in filter(None, (c.strip() for c in text.split(","))):
        for op in _OPS:
            if clause.startswith(op):
                try:
                    bound = float(clause[len(op):])
                except ValueError:
                    raise ParameterError(f"{where}: bad bound {clause!r}") from None
                if not math.isfinite(bound):
                    raise ParameterError(f"{where}: bound {clause!r} is not finite")
                out.append((op, bound))
                break
        else:
            if clause.startswith("in:"):
                out.append(("in", [s.strip() for s in clause[3:].split("|")]))
            elif clause.startswith("errors:"):
                out.append(("errors", clause[7:].strip()))
            else:
                raise ParameterError(f"{where}: unknown constraint {clause!r} "
                                     f"(use >=, >, <=, <, 'in: a|b', 'errors: machine')")
    return out


def notebook_path(name: str | Path) -> Path:
    """Resolve ``03``, a stem (or its start) or a path to one of the compendium's notebooks.

    The notebooks are ``notebooks/NN_*.ipynb``.  Names are compared as text, never as patterns:
    ``*`` matches nothing."""
    text = str(name).strip()
    known = all_notebooks()
    names = ", ".join(h.stem for h in known)
    if text.endswith(".ipynb") or "/" in text or os.sep in text:
        p = Path(os.path.expanduser(text))
        p = (p if p.is_absolute() else Path.cwd() / p).resolve()
        if p in known:
            return p
        raise ParameterError(f"{text!r} is not one of the compendium's notebooks "
                             f"(notebooks/NN_*.ipynb): {names}")
    hits = [h for h in known if text and h.stem.startswith(text)]
    if len(hits) == 1:
        return hits[0]
    shown = text if len(text) <= 60 else text[:57] + "..."
    if not hits:
        raise ParameterError(f"no notebook matches {shown!r}; notebooks: {names}")
    raise ParameterError(f"{shown!r} matches several notebooks: "
                         f"{', '.join(h.stem for h in hits)}")


def all_notebooks() -> list[Path]:
    """The paper notebooks, in order (``notebooks/NN_*.ipynb``)."""
    return sorted(paths.NOTEBOOKS.glob("[0-9][0-9]_*.ipynb"))


def _parameters_cell(nb: dict, where: str) -> dict:
    cells = [c for c in nb.get("cells", []) if c.get("cell_type") == "code"
             and "parameters" in c.get("metadata", {}).get("tags", [])]
    if len(cells) != 1:
        raise ParameterError(f"{where}: expected exactly one code cell tagged 'parameters', "
                             f"found {len(cells)}")
    return cells[0]


def _parameters_source(notebook) -> tuple[Path, str]:
    path = notebook_path(notebook)
    nb = json.loads(path.read_text(encoding="utf-8"))
    return path, "".join(_parameters_cell(nb, path.name)["source"])


def read_parameters(notebook: str | Path) -> dict[str, Parameter]:
    """The declared parameters of a notebook, in order."""
    path, src = _parameters_source(notebook)
    lines = src.splitlines()
    tree = ast.parse(src)
    out: dict[str, Parameter] = {}
    for node in tree.body:
        where = f"{path.name}, parameters cell line {node.lineno}"
        if not (isinstance(node, ast.Assign) and len(node.targets) == 1
                and isinstance(node.targets[0], ast.Name)):
            raise ParameterError(f"{where}: only 'name = literal  # comment' lines are allowed")
        try:
            default = ast.literal_eval(node.value)
        except ValueError:
            raise ParameterError(f"{where}: the default must be a literal") from None
        rest = lines[node.end_lineno - 1].encode()[node.end_col_offset:].decode()
        comment = rest.split("#", 1)[1].strip() if "#" in rest else ""
        comment = " ".join([comment, *_continued(lines, node.end_lineno)]).strip()
        m = _CONSTRAINT.match(comment)
        cons, help_ = (_parse_constraints(m.group(1), where), m.group(2)) if m else ([], comment)
        out[node.targets[0].id] = Parameter(node.targets[0].id, default, cons, help_)
    return out


# --- memory estimate ----------------------------------------------------------------------

_BINOPS = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul,
           ast.Div: operator.truediv, ast.Pow: operator.pow, ast.FloorDiv: operator.floordiv}


def _eval_arithmetic(node, names: dict, where: str) -> float:
    if isinstance(node, ast.Expression):
        return _eval_arithmetic(node.body, names, where)
    if isinstance(node, ast.Constant) and isinstance(node.value, int | float) \
            and not isinstance(node.value, bool):
        return float(node.value)
    if isinstance(node, ast.Name):
        v = names.get(node.id)
        if isinstance(v, bool) or not isinstance(v, int | float | list | tuple):
            raise ParameterError(f"{where}: {node.id!r} is not a numeric parameter")
        return float(len(v)) if isinstance(v, list | tuple) else float(v)
    if isinstance(node, ast.BinOp) and type(node.op) in _BINOPS:
        return _BINOPS[type(node.op)](_eval_arithmetic(node.left, names, where),
                                      _eval_arithmetic(node.right, names, where))
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
        return -_eval_arithmetic(node.operand, names, where)
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) \
            and node.func.id in ("max", "min", "len") and node.args and not node.keywords:
        args = [_eval_arithmetic(a, names, where) for a in node.args]
        return {"max": max, "min": min, "len": lambda x: x}[node.func.id](*args) \
            if node.func.id != "len" else args[0]
    raise ParameterError(f"{where}: the memory expression may use numbers, parameter names, "
                         f"+ - * / ** and max/min/len only")


def memory_estimate(notebook: str | Path, values: dict) -> float | None:
    """Peak bytes of a run with ``values`` (all parameters), from the notebook's declaration.

    The declaration is the ``# {memory: ...}`` line of the parameters cell; None when the notebook
    declares none."""
    path, src = _parameters_source(notebook)
    lines = src.splitlines()
    for i, line in enumerate(lines):
        m = _MEMORY.match(" ".join([line, *_continued(lines, i + 1)]))
        if m:
            where = f"{path.name}, memory line"
            try:
                tree = ast.parse(m.group(1).strip(), mode="eval")
            except SyntaxError:
                raise ParameterError(f"{where}: cannot parse {m.group(1).strip()!r}") from None
            try:
                return _eval_arithmetic(tree, values, where)
            except (OverflowError, ZeroDivisionError):
                return math.inf
    return None


def _check_memory(notebook: str, values: dict, share: int = 1) -> None:
    """Refuse a run whose declared peak memory does not fit.  ``share`` runs at once divide
    the machine's memory and the cgroups' limits between them; a per-process limit
    (``ulimit -v``) holds for each run whole."""
    need = memory_estimate(notebook, values)
    if need is None:
        return
    have = memory.tightest(memory.limits(), share=share)
    if need > have.bytes:
        raise ParameterError(
            f"{notebook}: these parameters need about {need / 1e9:.3g} GB of memory, more "
            f"than the {max(have.bytes, 0) / 1e9:.3g} GB left under {have.what}"
            f"{f' (shared by {share} runs at once)' if share > 1 and not have.per_process else ''}"
            f" on this machine; lower the sample sizes")


# --- checking values -------------------------------------------------------------------------

def parse_value(text: str):
    """A command-line value: a Python literal if it parses as one, else the string."""
    try:
        return ast.literal_eval(text)
    except (ValueError, SyntaxError, MemoryError, RecursionError):
        return text


def _type_ok(default, value) -> bool:
    if default is None:
        return True
    if isinstance(default, bool):
        return isinstance(value, bool)
    if isinstance(default, int):
        return isinstance(value, int) and not isinstance(value, bool)
    if isinstance(default, float):
        return isinstance(value, int | float) and not isinstance(value, bool)
    if isinstance(default, list | tuple):
        if not isinstance(value, list | tuple):
            return False
        kinds = {type(d) for d in default}
        if len(kinds) == 1 and default:
            return all(_type_ok(default[0], v) for v in value)
        return True
    return isinstance(value, type(default))


def _finite(value) -> bool:
    if isinstance(value, float):
        return math.isfinite(value)
    if isinstance(value, list | tuple):
        return all(_finite(v) for v in value)
    return True


def _check_one(p: Parameter, value, notebook: str) -> object:
    if not _type_ok(p.default, value):
        raise ParameterError(
            f"{notebook}: parameter {p.name!r} must be {type(p.default).__name__} like its "
            f"default {p.default!r}, got {type(value).__name__} {value!r}")
    if not _finite(value):
        raise ParameterError(f"{notebook}: parameter {p.name!r} = {value!r} is not a finite "
                             f"number (1e400 overflows to inf)")
    if isinstance(p.default, float) and isinstance(value, int):
        value = float(value)
    if p.name == "output_dir":
        try:
            paths.check_output_dir(value, notebook)
        except paths.OutputDirError as exc:
            raise ParameterError(str(exc)) from None
    items = value if isinstance(value, list | tuple) else [value]
    for op, bound in p.constraints:
        for v in items:
            if op == "in":
                ok = v in bound
            elif op == "errors":
                # imported here: machines brings numpy and scipy, which the runner's command
                # line (--list, --check) and most notebooks' checks do not need
                from ..machines import build
                ok = v in build(bound).error_names
                if not ok:
                    raise ParameterError(
                        f"{notebook}: parameter {p.name!r}: unknown error name {v!r}; allowed: "
                        f"{', '.join(build(bound).error_names)}")
            elif isinstance(v, bool) or not isinstance(v, int | float):
                raise ParameterError(f"{notebook}: parameter {p.name!r}: {v!r} is not a number "
                                     f"(it must be {op} {bound:g})")
            else:
                ok = {">=": v >= bound, ">": v > bound, "<=": v <= bound, "<": v < bound}[op]
            if not ok:
                allowed = f"one of {'|'.join(bound)}" if op == "in" else f"{op} {bound:g}"
                raise ParameterError(f"{notebook}: parameter {p.name!r} = {v!r} is not allowed; "
                                     f"it must be {allowed}")
    return value


def validate(notebook: str | Path, overrides: dict, share: int = 1) -> dict:
    """Check ``overrides`` against the notebook's declared parameters; return them cleaned.

    They are checked against the run's memory estimate too.  Raises :class:`ParameterError` naming
    the parameter and the allowed ones."""
    path = notebook_path(notebook)
    declared = read_parameters(path)
    unknown = [k for k in overrides if k not in declared]
    if unknown:
        raise ParameterError(
            f"{path.stem}: unknown parameter(s) {', '.join(unknown)}; allowed:\n  "
            + "\n  ".join(p.describe() for p in declared.values()))
    clean = {k: _check_one(declared[k], v, path.stem) for k, v in overrides.items()}
    if "output_dir" in declared and "output_dir" not in clean:
        _check_one(declared["output_dir"], declared["output_dir"].default, path.stem)
    _check_memory(path.stem, {**{k: p.default for k, p in declared.items()}, **clean}, share)
    return clean


def check_parameters(namespace: dict, notebook: str) -> None:
    """Inside a notebook: check the current values of its declared parameters.

    It also starts the provenance record of this run (:mod:`mtaccuracy.compendium.provenance`)."""
    declared = read_parameters(notebook)
    for name, p in declared.items():
        if name not in namespace:
            raise ParameterError(f"{notebook}: parameter {name!r} is not defined")
        _check_one(p, namespace[name], notebook)
    if not os.environ.get(paths.STAGING_ENV):  # the runner checked the memory for its share
        _check_memory(notebook, {k: namespace[k] for k in declared})
    provenance.start(notebook_path(notebook).stem, {k: namespace[k] for k in declared},
                     source=notebook_path(notebook))
