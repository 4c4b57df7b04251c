"""The public API of the science packages has numpydoc docstrings (issue 15 item 5).

For every public function of a science module (its ``__all__``, else the names without a
leading underscore, defined in that module) and every public method of a public class: a
docstring; a ``Parameters`` section that documents exactly the signature's parameters
(``self``/``cls`` aside; ``a, b : ...`` documents two; ``*args`` and ``**kwargs`` with or
without their stars); a ``Returns`` (or ``Yields``) section when the function returns a value
(a return annotation other than None or, without one, a ``return <value>``).  For every public
class whose constructor takes arguments: a ``Parameters`` section documenting exactly them, or
(dataclasses, estimators) an ``Attributes`` section naming each of them.  Every public property
has a docstring.  Every science module renders with ``pydoc``, and the docstrings' examples run.

The parser below is small on purpose (numpydoc is not a dependency): a section is a heading
line followed by a line of dashes; a documented name is an unindented ``name : type`` line.
"""

import ast
import importlib
import inspect
import pkgutil
import pydoc
import re
import textwrap
from pathlib import Path

import pytest

import mtaccuracy

#: Modules whose docstrings must carry runnable examples (kinematics, chain building, the pose
#: error); ``test_the_examples_in_docstrings_run`` runs the examples of every science module.
WITH_EXAMPLES = ("mtaccuracy.kinematics", "mtaccuracy.errors", "mtaccuracy.machines",
                 "mtaccuracy.machines.chain", "mtaccuracy.machines.topology",
                 "mtaccuracy.machines.iso", "mtaccuracy.sensitivity.pce")

_SECTION = re.compile(r"^(Parameters|Returns|Yields|Raises|Attributes|Notes|References|"
                      r"Examples|See Also|Other Parameters|Warns)\n-{3,}$", re.M)


#: The rooms above the science: paper code, the workflow, the apps (one-line summaries only).
ABOVE = ("mtaccuracy.papers", "mtaccuracy.compendium", "mtaccuracy.apps")


def science_modules() -> list[str]:
    return sorted(m.name for m in pkgutil.walk_packages(mtaccuracy.__path__, "mtaccuracy.")
                  if not m.name.startswith(ABOVE))


def sections(doc: str | None) -> dict[str, str]:
    """numpydoc sections of a docstring: {heading: body}."""
    doc = inspect.cleandoc(doc or "")
    heads = list(_SECTION.finditer(doc))
    return {m.group(1): doc[m.end():heads[i + 1].start() if i + 1 < len(heads) else len(doc)]
            for i, m in enumerate(heads)}


def documented(body: str) -> list[str]:
    """The names a Parameters section documents (its unindented ``name : type`` lines)."""
    out = []
    for line in textwrap.dedent(body).splitlines():
        if line.strip() and not line.startswith((" ", "\t")):
            out += [n.strip().lstrip("*") for n in line.split(" : ")[0].split(",") if n.strip()]
    return out


def bare_entries(body: str) -> list[str]:
    """The entries of a Parameters section that give a name and type but no description line
    (issue 25 item 9: ``machine : Horizontal3Axis`` and nothing else says nothing)."""
    lines = textwrap.dedent(body).strip("\n").splitlines()
    out = []
    for i, line in enumerate(lines):
        if line.strip() and not line.startswith((" ", "\t")):
            rest = []
            for nxt in lines[i + 1:]:
                if nxt.strip() and not nxt.startswith((" ", "\t")):
                    break
                rest.append(nxt.strip())
            if not "".join(rest):
                out.append(line.split(" : ")[0].strip())
    return out


def _returns_value(func) -> bool:
    ann = inspect.signature(func).return_annotation
    if ann is not inspect.Signature.empty:
        return ann not in (None, "None")
    try:
        tree = ast.parse(textwrap.dedent(inspect.getsource(func)))
    except (OSError, TypeError):
        return False
    body = tree.body[0]
    nested = {id(n) for d in ast.walk(body) if d is not body and isinstance(
        d, ast.FunctionDef | ast.Lambda) for n in ast.walk(d)}
    return any(isinstance(n, ast.Return) and n.value is not None and id(n) not in nested
               for n in ast.walk(body))


def summary_problems(name: str, doc: str) -> list[str]:
    """A summary (the docstring's first paragraph) that runs past one line (issue 25 item 9)."""
    first = doc.strip().split("\n\n", 1)[0]
    return [f"{name}: the summary runs over {first.count(chr(10)) + 1} lines"] \
        if "\n" in first else []


def function_problems(name: str, func) -> list[str]:
    """What a function's docstring lacks of the numpydoc rules."""
    doc = inspect.getdoc(func)
    if not doc:
        return [f"{name}: no docstring"]
    out, sec = summary_problems(name, doc), sections(doc)
    params = [p for p in inspect.signature(func).parameters if p not in ("self", "cls")]
    if params:
        if "Parameters" not in sec:
            out.append(f"{name}: no Parameters section")
        else:
            doc_names = documented(sec["Parameters"])
            missing = [p for p in params if p not in doc_names]
            extra = [p for p in doc_names if p not in params]
            if missing or extra:
                out.append(f"{name}: Parameters undocumented {missing}, not in signature {extra}")
            out += [f"{name}: parameter {p} has a type and nothing else"
                    for p in bare_entries(sec["Parameters"])]
    if _returns_value(func) and not ({"Returns", "Yields"} & set(sec)):
        out.append(f"{name}: no Returns section")
    return out


def class_problems(name: str, cls) -> list[str]:
    """What a class's docstring (constructor) and its public methods and properties lack."""
    if not inspect.getdoc(cls):
        return [f"{name}: no docstring"]
    out = summary_problems(name, inspect.getdoc(cls))
    try:
        params = [p for p in inspect.signature(cls).parameters if p not in ("self", "cls")]
    except (TypeError, ValueError):
        params = []
    sec = sections(inspect.getdoc(cls))
    if params:
        if "Parameters" in sec:
            doc_names = documented(sec["Parameters"])
            missing = [p for p in params if p not in doc_names]
            extra = [p for p in doc_names if p not in params]
            if missing or extra:
                out.append(f"{name}: Parameters undocumented {missing}, not in signature {extra}")
        elif "Attributes" in sec:
            missing = [p for p in params if p not in documented(sec["Attributes"])]
            if missing:
                out.append(f"{name}: constructor arguments {missing} not in Attributes")
        else:
            out.append(f"{name}: no Parameters or Attributes section")
    for attr, member in vars(cls).items():
        if attr.startswith("_"):
            continue
        if isinstance(member, property):
            if not inspect.getdoc(member):
                out.append(f"{name}.{attr}: property without docstring")
            continue
        func = getattr(member, "__func__", member)       # staticmethod, classmethod
        if inspect.isfunction(func):
            out += function_problems(f"{name}.{attr}", func)
    return out


def module_problems(module_name: str) -> list[str]:
    mod = importlib.import_module(module_name)
    public = getattr(mod, "__all__", None)
    out = summary_problems(module_name, inspect.getdoc(mod) or "")
    for name, obj in vars(mod).items():
        if (public is not None and name not in public) or (public is None and name[0] == "_"):
            continue
        if getattr(obj, "__module__", None) != module_name:
            continue
        if inspect.isfunction(obj):
            out += function_problems(name, obj)
        elif inspect.isclass(obj) and not issubclass(obj, Exception):
            out += class_problems(name, obj)
    return out


@pytest.mark.parametrize("module_name", science_modules())
def test_public_api_has_numpydoc_docstrings(module_name):
    problems = module_problems(module_name)
    assert not problems, "\n".join(problems)


@pytest.mark.parametrize("module_name", science_modules())
def test_every_science_module_renders_with_pydoc(module_name):
    text = pydoc.render_doc(importlib.import_module(module_name), renderer=pydoc.plaintext)
    assert module_name in text


def test_the_rules_catch_a_missing_section_a_drifted_name_and_a_missing_returns():
    def good(x, y, *args, **kwargs):
        """Sum.

        Parameters
        ----------
        x, y : float
            Terms.
        *args, **kwargs
            Ignored.

        Returns
        -------
        float
        """
        return x + y

    def drifted(x, z):
        """Sum.

        Parameters
        ----------
        x, y : float
            Terms.
        """

    def no_returns(x: float) -> float:
        """Twice.

        Parameters
        ----------
        x : float
            A number.
        """
        return 2 * x

    def inner_return_only(x):
        """A closure maker.

        Parameters
        ----------
        x : float
            The closed-over value.
        """
        def f():
            return x
        print(f)

    assert function_problems("good", good) == []
    assert function_problems("drifted", drifted) == [
        "drifted: Parameters undocumented ['z'], not in signature ['y']"]
    assert function_problems("no_returns", no_returns) == ["no_returns: no Returns section"]
    assert function_problems("inner_return_only", inner_return_only) == []
    assert function_problems("bare", lambda a: a) == ["bare: no docstring"]


def test_the_examples_in_docstrings_run():
    import doctest

    ran = 0
    for name in science_modules():
        mod = importlib.import_module(name)
        result = doctest.testmod(mod, optionflags=doctest.NORMALIZE_WHITESPACE)
        assert result.failed == 0, f"{name}: {result.failed} example(s) fail"
        assert result.attempted > 0 or name not in WITH_EXAMPLES, f"{name} has no example"
        ran += result.attempted
    assert ran > 0


def test_the_rules_catch_bad_classes_methods_and_properties():
    class Good:
        """A good class.

        Parameters
        ----------
        a : float
            Length, mm.
        """

        def __init__(self, a):
            self.a = a

        @property
        def twice(self):
            """float: twice ``a``, mm."""
            return 2 * self.a

        def scaled(self, k):
            """``a`` times ``k``.

            Parameters
            ----------
            k : float
                Factor.

            Returns
            -------
            float
            """
            return k * self.a

    class Bad:
        """A bad class.

        Parameters
        ----------
        b : float
            Not the constructor's argument.
        """

        def __init__(self, a):
            self.a = a

        @property
        def twice(self):
            return 2 * self.a

        @classmethod
        def make(cls, a):
            """A terse prose docstring."""
            return cls(a)

    class Fields:
        """Documented by its attributes only.

        Attributes
        ----------
        a : float
        """

        def __init__(self, a, b):
            self.a, self.b = a, b

    assert class_problems("Good", Good) == []
    assert class_problems("Bad", Bad) == [
        "Bad: Parameters undocumented ['a'], not in signature ['b']",
        "Bad.twice: property without docstring",
        "Bad.make: no Parameters section", "Bad.make: no Returns section"]
    assert class_problems("Fields", Fields) == [
        "Fields: constructor arguments ['b'] not in Attributes"]


def test_a_summary_over_two_lines_is_named():
    def two(x):
        """First line of a summary
        that goes on.

        Parameters
        ----------
        x : int
            Anything.
        """
    def one(x):
        """One line.

        Parameters
        ----------
        x : int
            Anything.
        """
    assert function_problems("two", two) == ["two: the summary runs over 2 lines"]

    def bare(machine):
        """One line.

        Parameters
        ----------
        machine : Horizontal3Axis
        """
    assert function_problems("bare", bare) == ["bare: parameter machine has a type and nothing "
                                               "else"]
    assert function_problems("one", one) == []


def _summaries(node, where: str, public: bool = True):
    """``(name, docstring)`` of the public functions, classes and methods under ``node``."""
    for ch in ast.iter_child_nodes(node):
        if isinstance(ch, ast.FunctionDef | ast.ClassDef):
            pub = public and not ch.name.startswith("_")
            if pub:
                yield f"{where}.{ch.name}", ast.get_docstring(ch) or ""
            if isinstance(ch, ast.ClassDef):
                yield from _summaries(ch, f"{where}.{ch.name}", pub)


def compendium_summary_problems() -> list[str]:
    """Summaries over one line in the compendium's modules (module, public functions, classes
    and their public methods): the machinery reads like the science layer (issue 25 item 9)."""
    out = []
    lib = Path(mtaccuracy.__file__).parent
    for path in sorted(p for room in ("papers", "compendium", "apps")
                       for p in (lib / room).rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        out += summary_problems(path.name, ast.get_docstring(tree) or "")
        for name, doc in _summaries(tree, path.stem):
            out += summary_problems(name, doc)
    return out


def test_compendium_summaries_are_one_line():
    problems = compendium_summary_problems()
    assert not problems, "\n".join(problems)
