"""Run notebooks with papermill after validating their parameters.

papermill only warns about a parameter the notebook does not declare; this runner refuses it,
and refuses a value of the wrong type or outside the declared constraints, naming the
parameter and the allowed ones, before any kernel starts.

A notebook declares its parameters in the one code cell tagged ``parameters``, one
assignment per line with a comment; the comment may start with constraints in braces::

    n_samples = 500  # {>= 2} Latin hypercube sample size
    method = "lhs"  # {in: lhs|mc} sampling method
    focus = ["dx(z)"]  # {errors: vertical_xyfz} errors to highlight

The type is the default's type (an int parameter refuses 2.5; a float one accepts 2).  The
same checks run inside the notebook (:func:`check_parameters`), so an interactive run in
JupyterLab refuses a bad value too.

Execution goes to ``notebooks/.running/``; only a successful run replaces the notebook in
place (the previous version is kept in ``notebooks/.backup/``).  A failed run is kept in
``notebooks/.failed/`` and the committed notebook is left untouched.

Command line (``make reproduce NB=03 PARAMS="n_samples=1000 seed=2"`` calls this)::

    python -m mtaccuracy.runner all|03|notebooks/03_....ipynb [name=value ...] [--check] [--list]
"""

from __future__ import annotations

import argparse
import ast
import copy
import json
import re
import shutil
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from . import paths


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
        return (f"{self.name} = {self.default!r} ({kind}{'; ' + cons if cons else ''})"
                f"{'  ' + self.help if self.help else ''}")


_CONSTRAINT = re.compile(r"^\s*\{([^}]*)\}\s*(.*)$")
_OPS = (">=", "<=", ">", "<")


def _parse_constraints(text: str, where: str) -> list[tuple[str, object]]:
    out = []
    for clause in filter(None, (c.strip() for c in text.split(","))):
        for op in _OPS:
            if clause.startswith(op):
                try:
                    out.append((op, float(clause[len(op):])))
                except ValueError:
                    raise ParameterError(f"{where}: bad bound {clause!r}") from None
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
    """Resolve ``03``, a stem or a path to a notebook file."""
    p = Path(name)
    if p.suffix == ".ipynb" and p.exists():
        return p.resolve()
    hits = sorted(paths.NOTEBOOKS.glob(f"{name}*.ipynb"))
    if len(hits) == 1:
        return hits[0]
    known = ", ".join(h.stem for h in sorted(paths.NOTEBOOKS.glob("[0-9]*.ipynb")))
    if not hits:
        raise ParameterError(f"no notebook matches {str(name)!r}; notebooks: {known}")
    raise ParameterError(f"{str(name)!r} matches several notebooks: "
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


def read_parameters(notebook: str | Path) -> dict[str, Parameter]:
    """The declared parameters of a notebook, in order."""
    path = notebook_path(notebook)
    nb = json.loads(path.read_text(encoding="utf-8"))
    src = "".join(_parameters_cell(nb, path.name)["source"])
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
        m = _CONSTRAINT.match(comment)
        cons, help_ = (_parse_constraints(m.group(1), where), m.group(2)) if m else ([], comment)
        out[node.targets[0].id] = Parameter(node.targets[0].id, default, cons, help_)
    return out


def parse_value(text: str):
    """A command-line value: a Python literal if it parses as one, else the string."""
    try:
        return ast.literal_eval(text)
    except (ValueError, SyntaxError):
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


def _check_one(p: Parameter, value, notebook: str) -> object:
    if not _type_ok(p.default, value):
        raise ParameterError(
            f"{notebook}: parameter {p.name!r} must be {type(p.default).__name__} like its "
            f"default {p.default!r}, got {type(value).__name__} {value!r}")
    if isinstance(p.default, float) and isinstance(value, int):
        value = float(value)
    items = value if isinstance(value, list | tuple) else [value]
    for op, bound in p.constraints:
        for v in items:
            if op == "in":
                ok = v in bound
            elif op == "errors":
                from .machines import build
                ok = v in build(bound).error_names
                if not ok:
                    raise ParameterError(
                        f"{notebook}: parameter {p.name!r}: unknown error name {v!r}; allowed: "
                        f"{', '.join(build(bound).error_names)}")
            else:
                ok = {">=": v >= bound, ">": v > bound, "<=": v <= bound, "<": v < bound}[op]
            if not ok:
                allowed = f"one of {'|'.join(bound)}" if op == "in" else f"{op} {bound:g}"
                raise ParameterError(f"{notebook}: parameter {p.name!r} = {v!r} is not allowed; "
                                     f"it must be {allowed}")
    return value


def validate(notebook: str | Path, overrides: dict) -> dict:
    """Check ``overrides`` against the notebook's declared parameters; return them cleaned.

    Raises :class:`ParameterError` naming the parameter and the allowed ones.
    """
    path = notebook_path(notebook)
    declared = read_parameters(path)
    unknown = [k for k in overrides if k not in declared]
    if unknown:
        raise ParameterError(
            f"{path.stem}: unknown parameter(s) {', '.join(unknown)}; allowed:\n  "
            + "\n  ".join(p.describe() for p in declared.values()))
    return {k: _check_one(declared[k], v, path.stem) for k, v in overrides.items()}


def check_parameters(namespace: dict, notebook: str) -> None:
    """Inside a notebook: check the current values of its declared parameters, and start the
    provenance record of this run (:mod:`mtaccuracy.provenance`)."""
    from . import provenance

    declared = read_parameters(notebook)
    for name, p in declared.items():
        if name not in namespace:
            raise ParameterError(f"{notebook}: parameter {name!r} is not defined")
        _check_one(p, namespace[name], notebook)
    provenance.start(notebook_path(notebook).stem, {k: namespace[k] for k in declared})


def _strip_injected(nb: dict) -> dict:
    nb = copy.deepcopy(nb)
    nb["cells"] = [c for c in nb["cells"]
                   if "injected-parameters" not in c.get("metadata", {}).get("tags", [])]
    return nb


def _strip_timing(nb: dict, rel: str) -> dict:
    """Remove what makes two identical runs differ (timestamps, durations, temp paths)."""
    meta = nb.get("metadata", {}).get("papermill", {})
    for k in ("start_time", "end_time", "duration", "environment_variables", "exception"):
        meta.pop(k, None)
    if meta:
        meta["input_path"] = meta["output_path"] = rel
    for c in nb.get("cells", []):
        md = c.get("metadata", {})
        md.pop("papermill", None)
        md.pop("execution", None)
    return nb


def run(notebook: str | Path, overrides: dict | None = None, progress: bool = True) -> float:
    """Validate, execute with papermill and replace the notebook in place; returns seconds."""
    import papermill as pm

    path = notebook_path(notebook)
    params = validate(path, overrides or {})
    running = paths.NOTEBOOKS / ".running"
    failed = paths.NOTEBOOKS / ".failed"
    backup = paths.NOTEBOOKS / ".backup"
    for d in (running, failed, backup):
        d.mkdir(exist_ok=True)
    src = running / f"{path.stem}.input.ipynb"
    out = running / path.name
    src.write_text(json.dumps(_strip_injected(json.loads(path.read_text(encoding="utf-8"))),
                              indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
    t0 = time.perf_counter()
    try:
        pm.execute_notebook(str(src), str(out), parameters=params, cwd=str(paths.NOTEBOOKS),
                            kernel_name="python3", progress_bar=progress, log_output=False)
    except Exception as exc:  # papermill raises PapermillExecutionError with the cell's error
        shutil.move(str(out), failed / path.name) if out.exists() else None
        msg = getattr(exc, "evalue", None) or str(exc).strip().splitlines()[-1]
        cell = getattr(exc, "exec_count", None)
        raise RuntimeError(
            f"{path.stem} failed{f' in cell [{cell}]' if cell else ''}: "
            f"{getattr(exc, 'ename', type(exc).__name__)}: {msg}\n"
            f"  executed copy: {(failed / path.name).relative_to(paths.ROOT)}; "
            f"{path.relative_to(paths.ROOT)} is unchanged") from None
    finally:
        src.unlink(missing_ok=True)
    seconds = time.perf_counter() - t0
    nb = _strip_timing(json.loads(out.read_text(encoding="utf-8")),
                       str(path.relative_to(paths.ROOT)))
    shutil.copy2(path, backup / path.name)
    path.write_text(json.dumps(nb, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
    out.unlink()
    _record_runtime(path.stem, seconds)
    return seconds


def _record_runtime(stem: str, seconds: float) -> None:
    """Keep the last run time of each notebook for the report (``figures/.runtimes.json``,
    not committed: it is a measurement of this machine)."""
    rt = paths.FIGURES / ".runtimes.json"
    data = json.loads(rt.read_text(encoding="utf-8")) if rt.exists() else {}
    data[stem] = round(seconds, 1)
    rt.parent.mkdir(parents=True, exist_ok=True)
    rt.write_text(json.dumps(dict(sorted(data.items())), indent=1) + "\n", encoding="utf-8")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m mtaccuracy.runner",
                                 description="Validate parameters and run notebooks in place.")
    ap.add_argument("notebook", help="'all', a number such as 03, a stem or a path")
    ap.add_argument("params", nargs="*", help="name=value overrides (Python literals)")
    ap.add_argument("--check", action="store_true", help="validate only, do not run")
    ap.add_argument("--list", action="store_true", help="list the notebook's parameters")
    args = ap.parse_args(argv)
    try:
        targets = all_notebooks() if args.notebook == "all" else [notebook_path(args.notebook)]
        overrides = {}
        for item in args.params:
            if "=" not in item:
                raise ParameterError(f"parameter {item!r} must be written name=value")
            k, v = item.split("=", 1)
            overrides[k.strip()] = parse_value(v.strip())
        if args.list:
            for t in targets:
                print(f"{t.stem}:")
                for p in read_parameters(t).values():
                    print("  " + p.describe())
            return 0
        for t in targets:  # validate everything before running anything
            validate(t, overrides)
        if args.check:
            print("parameters ok")
            return 0
        total = 0.0
        for i, t in enumerate(targets, 1):
            shown = " ".join(f"{k}={v!r}" for k, v in overrides.items()) or "defaults"
            print(f"[{i}/{len(targets)}] {t.relative_to(paths.ROOT)} ({shown})", flush=True)
            s = run(t, overrides, progress=True)
            total += s
            print(f"[{i}/{len(targets)}] {t.stem} done in {s:.1f} s", flush=True)
        print(f"{len(targets)} notebook(s) in {total:.1f} s")
    except (ParameterError, RuntimeError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
