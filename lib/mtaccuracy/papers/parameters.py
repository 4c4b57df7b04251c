"""A notebook's parameters, declared once with `param`: type, default, bounds and help.

Each paper module declares its notebook's parameters as a :class:`NotebookParameters` subclass
called ``Parameters`` (``papers.guo2016.Parameters``).  Everything that needs them reads it:

* the notebook's cell tagged ``parameters`` is its rendering (:meth:`NotebookParameters.cell`):
  one ``name: type = default  # help`` line per parameter, plain papermill literals that
  ``papermill.inspect_notebook`` reads whole (``tests/test_parameters.py`` holds every cell to
  its declaration);
* the notebook's own first check (:func:`mtaccuracy.compendium.notebook.start`) and the
  workflow's check before any job (:mod:`mtaccuracy.compendium.workflow`) call :func:`check`;
* the explorer takes its defaults and bounds from it; the book lists it in each chapter.

Beyond what `param` checks (type, bounds, choices), :func:`check` refuses unknown names and
non-finite numbers, and runs the declaration's own :meth:`NotebookParameters.check` (values that
contradict each other); :meth:`NotebookParameters.memory_bytes` bounds a run's peak memory, for
refusing a run the machine cannot hold.  Every refusal is a :class:`ParameterError`: one line
naming the notebook, the parameter and what is allowed.
"""

from __future__ import annotations

import math

import param


class ParameterError(ValueError):
    """A notebook parameter is unknown, of the wrong type, out of its bounds or contradictory."""


class NumberList(param.List):
    """A list of numbers, each within ``item_bounds`` (``bounds`` bounds the list's length)."""

    __slots__ = ["item_bounds", "item_inclusive"]

    def __init__(self, default=None, *, item_bounds=(None, None), item_inclusive=(True, True),
                 **params):
        self.item_bounds = item_bounds
        self.item_inclusive = item_inclusive
        super().__init__(default=default, **params)

    def _validate(self, val):
        super()._validate(val)
        lo, hi = self.item_bounds
        for v in val or []:
            if isinstance(v, bool) or not isinstance(v, int | float):
                raise ValueError(f"parameter '{self.name}': {v!r} is not a number")
            low_ok = lo is None or (v >= lo if self.item_inclusive[0] else v > lo)
            high_ok = hi is None or (v <= hi if self.item_inclusive[1] else v < hi)
            if not (low_ok and high_ok):
                raise ValueError(f"parameter '{self.name}': {v!r} is outside "
                                 f"{self.describe_items()}")

    def describe_items(self) -> str:
        """The items' interval, as text (``[0, 1000]``, ``(0, 1)``)."""
        lo, hi = self.item_bounds
        return (f"{'[' if self.item_inclusive[0] else '('}{'-inf' if lo is None else lo}, "
                f"{'inf' if hi is None else hi}{']' if self.item_inclusive[1] else ')'}")


class _Path(param.String):
    """A path parameter: a string that is valid UTF-8 text and holds no NUL.

    A path that is not UTF-8 (a Latin-1 file name, given on the command line, arrives with
    surrogate escapes) cannot go into the executed notebook's JSON, and a NUL ends a path for the
    operating system: both are refused here, naming the parameter, before any work."""

    def _validate_value(self, val, allow_None):
        super()._validate_value(val, allow_None)
        if isinstance(val, str):
            try:
                val.encode("utf-8")
            except UnicodeEncodeError as exc:
                raise ValueError(f"parameter '{self.name}': the path {val!r} is not valid UTF-8 "
                                 f"text (byte 0x{ord(val[exc.start]) & 0xff:02x} at character "
                                 f"{exc.start}); rename the file or folder with UTF-8 "
                                 f"characters") from None
            if "\0" in val:
                raise ValueError(f"parameter '{self.name}': the path {val!r} holds a NUL "
                                 f"character")


class InputFile(_Path):
    """The path of an input file: relative to the repository root, or absolute."""


class InputFolder(_Path):
    """The path of an input folder: relative to the repository root, or absolute."""


class OutputFolder(_Path):
    """Where a run writes its figures and tables (``figures/<stem>`` or outside the repository)."""


_TYPES = {param.Boolean: "bool", param.Integer: "int", param.Number: "float",
          param.Selector: "str", NumberList: "list", param.String: "str"}


def literal(value) -> str:
    """A default as Python source, strings in double quotes (as the notebooks write them)."""
    if isinstance(value, str) and '"' not in value and "\\" not in value:
        return f'"{value}"'
    return repr(value)


def type_name(p: param.Parameter) -> str:
    """The Python type a parameter's values have, as papermill reads it (``int``, ``list``)."""
    return next(name for kind, name in _TYPES.items() if isinstance(p, kind))


class NotebookParameters(param.Parameterized):
    """The base of a notebook's declaration: its stem, its memory bound and its own checks."""

    #: The notebook declared (``notebooks/<stem>.ipynb``).
    stem = ""

    def memory_bytes(self) -> float:
        """Peak bytes of a run with these values, libraries and figures included."""
        return 5e8

    def check(self) -> None:
        """Refuse values that contradict each other (raise :class:`ParameterError`)."""

    @classmethod
    def names(cls) -> list[str]:
        """The declared parameters, in declaration order."""
        return [n for n in cls.param if n != "name"]

    @classmethod
    def defaults(cls) -> dict:
        """``{name: default}``, in declaration order."""
        return {n: cls.param[n].default for n in cls.names()}

    @classmethod
    def files(cls) -> list[str]:
        """The parameters that name input files or folders."""
        return [n for n in cls.names() if isinstance(cls.param[n], InputFile | InputFolder)]

    @classmethod
    def cell(cls) -> str:
        """The source of the notebook's cell tagged ``parameters``: papermill literals."""
        return "\n".join(f"{n}: {type_name(cls.param[n])} = {literal(cls.param[n].default)}  "
                         f"# {cls.param[n].doc}" for n in cls.names())

    @classmethod
    def allowed(cls, name: str) -> str:
        """What a parameter allows beyond its type, in words ("" when nothing more)."""
        p = cls.param[name]
        if isinstance(p, param.Selector):
            return f"one of {'|'.join(map(str, p.objects))}"
        if isinstance(p, NumberList):
            return f"each in {p.describe_items()}"
        if isinstance(p, param.Number) and p.bounds is not None:
            (lo, hi), inc = p.bounds, p.inclusive_bounds
            return (f"{'[' if inc[0] else '('}{'-inf' if lo is None else lo}, "
                    f"{'inf' if hi is None else hi}{']' if inc[1] else ')'}")
        if isinstance(p, OutputFolder):
            return "its own folder under figures/ or a folder outside the repository"
        return ""

    @classmethod
    def describe(cls, name: str) -> str:
        """One line on a parameter: name, default, type, what is allowed, help."""
        p, allowed = cls.param[name], cls.allowed(name)
        return (f"{name} = {p.default!r} ({type_name(p)}{'; ' + allowed if allowed else ''})"
                f"  {p.doc}")


def _finite(value) -> bool:
    if isinstance(value, float):
        return math.isfinite(value)
    if isinstance(value, list | tuple):
        return all(_finite(v) for v in value)
    return True


def _as_declared(p: param.Parameter, v):
    """An int given for a float (alone or in a list of floats) as that float; a tuple as a
    list."""
    if isinstance(p, param.Number) and not isinstance(p, param.Integer) \
            and isinstance(v, int) and not isinstance(v, bool):
        return float(v)
    if isinstance(p, NumberList) and isinstance(v, list | tuple):
        if p.item_type is float:
            v = [float(x) if isinstance(x, int) and not isinstance(x, bool) else x for x in v]
        return list(v)
    return v


def check(declared: type[NotebookParameters], values: dict) -> NotebookParameters:
    """Check ``values`` against a notebook's declaration; the others take their defaults.

    Parameters
    ----------
    declared : type
        The notebook's declaration (``papers.guo2016.Parameters``).
    values : dict
        ``{name: value}``, some or all of the parameters.  An int given for a float parameter
        (or in a list of floats) is taken as that float.

    Returns
    -------
    NotebookParameters
        The declaration filled with every value, defaults included.

    Raises
    ------
    ParameterError
        One line: an unknown name (the allowed ones follow, one per line), a wrong type, a
        value out of its bounds or not finite, or values that contradict each other.
    """
    stem = declared.stem
    unknown = [k for k in values if k not in declared.names()]
    if unknown:
        raise ParameterError(f"{stem}: unknown parameter(s) {', '.join(unknown)}; allowed:\n  "
                             + "\n  ".join(declared.describe(n) for n in declared.names()))
    for k, v in values.items():
        if not _finite(v):
            raise ParameterError(f"{stem}: parameter {k!r} = {v!r} is not a finite number "
                                 f"(1e400 overflows to inf)")
    try:
        filled = declared(**{k: _as_declared(declared.param[k], v) for k, v in values.items()})
    except (ValueError, TypeError) as exc:
        text = str(exc).replace(f"'{declared.__name__}.", "'")
        raise ParameterError(f"{stem}: {text}") from None
    filled.check()
    return filled


def values(filled: NotebookParameters) -> dict:
    """``{name: value}`` of a filled declaration, in declaration order."""
    return {n: getattr(filled, n) for n in type(filled).names()}
