"""Python signatures of the compiled functions, read from the signature line pybind11 writes
at the head of each docstring ("fit(frf: FrequencyResponse, modes: object = 2, ...) -> FitResult").

`inspect.signature` cannot read a pybind11 function; `wrap` gives a thin Python function
with the same behaviour, `__signature__` and the docstring without that line, and
`stub_lines` the typed .pyi lines of the same (zwidth/_stubgen.py).
"""
import ast
import functools
import inspect
import math
import os
import re

_PREFIX = re.compile(r"\bzwidth\._zwidth\.")


class _Default:
    """A default pybind11 shows but Python cannot evaluate (an object's repr): shown as is."""

    def __init__(self, text):
        self.text = text

    def __repr__(self):
        return self.text


def _split_top(text, sep=","):
    """text split at `sep` outside brackets and quotes."""
    parts, depth, quote, cur = [], 0, None, []
    for c in text:
        if quote:
            cur.append(c)
            if c == quote:
                quote = None
            continue
        if c in "'\"":
            quote = c
        elif c in "([{":
            depth += 1
        elif c in ")]}":
            depth -= 1
        elif c == sep and depth == 0:
            parts.append("".join(cur).strip())
            cur = []
            continue
        cur.append(c)
    if "".join(cur).strip():
        parts.append("".join(cur).strip())
    return parts


def _default(text):
    special = {"inf": math.inf, "-inf": -math.inf, "nan": math.nan}
    if text in special:
        return special[text]
    try:
        return ast.literal_eval(text)
    except (ValueError, SyntaxError):
        return _Default(text)


def parse_line(line):
    """(name, [(param, annotation, default text or None)], return annotation) of one
    pybind11 signature line, or None when the line is not one."""
    line = _PREFIX.sub("", line.strip())
    m = re.match(r"^(\w+)\((.*)\)(?: -> (.+))?$", line)
    if not m:
        return None
    params = []
    for p in _split_top(m.group(2)):
        name, _, rest = p.partition(":")
        ann, _, default = (x.strip() for x in rest.partition("="))
        params.append((name.strip(), ann or None, default or None))
    return m.group(1), params, m.group(3)


def overloads(f):
    """Every signature of f (one, or one per overload) and the docstring text after them."""
    doc = f.__doc__ or ""
    lines = doc.split("\n")
    first = parse_line(lines[0]) if lines else None
    if first and len(lines) > 1 and lines[1].strip() == "Overloaded function.":
        sigs, text = [], []
        for block in "\n".join(lines[2:]).split("\n\n"):
            m = re.match(r"^\d+\. (.*)", block.strip())
            parsed = parse_line(m.group(1).split("\n")[0]) if m else None
            if parsed:
                sigs.append(parsed)
                rest = m.group(1).split("\n", 1)
                if len(rest) > 1:
                    text.append(rest[1].strip())
            elif block.strip():
                text.append(block.strip())
        return sigs, "\n\n".join(t for t in text if t)
    if first:
        return [first], "\n".join(lines[1:]).strip()
    return [], doc


# What the bindings that take any object (and check it themselves) accept, by parameter name.
_OBJECT_TYPES = {
    "modes": "Union[int, str, List[Tuple[float, float, float, float]]]", "delay_samples": "Union[int, str]",
    "u": "ArrayLike", "y": "ArrayLike", "f_hz": "ArrayLike", "H": "ArrayLike", "coherence": "Optional[ArrayLike]",
    "H_std": "Optional[ArrayLike]", "K": "ArrayLike", "B": "ArrayLike", "m": "float", "b": "float",
    "sample_rate_hz": "float", "num_averages": "int", "monte_carlo": "int", "n": "Optional[int]",
    "scene": "Union[str, os.PathLike, List[Any]]",
    "paths": "Union[str, os.PathLike, List[Union[str, os.PathLike]]]",
}


def signature(parsed, drop_self=False):
    """An inspect.Signature from parse_line's tuple."""
    _, params, ret = parsed
    out = []
    for name, ann, default in params:
        if ann == "object" and name in _OBJECT_TYPES:
            ann = _OBJECT_TYPES[name]
        if drop_self and name == "self":
            continue
        kind = inspect.Parameter.POSITIONAL_OR_KEYWORD
        if name.startswith("**"):
            name, kind = name[2:], inspect.Parameter.VAR_KEYWORD
        elif name.startswith("*"):
            name, kind = name[1:], inspect.Parameter.VAR_POSITIONAL
        out.append(inspect.Parameter(
            name, kind, default=inspect.Parameter.empty if default is None else _default(default),
            annotation=inspect.Parameter.empty if ann is None else ann))
    return inspect.Signature(out, return_annotation=inspect.Signature.empty if ret is None else ret)


_NUMBER_TYPES = {"float", "int", "Optional[float]", "Optional[int]"}


def number_names(f):
    """(names by position of the only overload, or None; every name) of f's float and int
    parameters, from pybind11's signature lines."""
    sigs, _ = overloads(f)
    names = [[n for n, ann, _ in s[1] if ann in _NUMBER_TYPES or _OBJECT_TYPES.get(n) in ("float", "int")]
             for s in sigs]
    positional = [n for n, _, _ in sigs[0][1]] if len(sigs) == 1 else None
    return positional, {n for ns in names for n in ns}


def check_numbers(numbers, args, kwargs):
    """A bool where a float or an int is taken is a TypeError naming the keyword, as the
    module's own numbers (Number, Integer) refuse it; pybind11 would take True as 1."""
    positional, names = numbers
    given = list(kwargs.items())
    if positional is not None:
        given += [(n, a) for n, a in zip(positional, args)]
    for name, v in given:
        if name in names and (isinstance(v, bool) or type(v).__name__ == "bool_"):
            raise TypeError(f"{name} must be a number, not bool")


def wrap(f, module="zwidth", qualname=None):
    """f as a Python function with its signature (the first overload's when there are
    several) and its docstring without pybind11's signature lines."""
    sigs, text = overloads(f)

    numbers = number_names(f) if sigs else (None, set())

    @functools.wraps(f)
    def wrapper(*args, **kwargs):
        check_numbers(numbers, args, kwargs)
        # Paths may be os.PathLike (pathlib.Path), as open() takes them.
        if any(isinstance(a, os.PathLike) for a in args):
            args = [os.fspath(a) if isinstance(a, os.PathLike) else a for a in args]
        if any(isinstance(a, os.PathLike) for a in kwargs.values()):
            kwargs = {k: os.fspath(a) if isinstance(a, os.PathLike) else a for k, a in kwargs.items()}
        return f(*args, **kwargs)

    if sigs:
        wrapper.__signature__ = signature(sigs[0])
    wrapper.__doc__ = text
    wrapper.__module__ = module
    if qualname:
        wrapper.__qualname__ = qualname
    del wrapper.__wrapped__  # inspect would follow it to the builtin
    wrapper._builtin, wrapper._numbers = f, numbers  # for a caller that must not leave a Python frame
    return wrapper


def wrap_class(cls):
    """Every method of a pybind11 class (and __init__) replaced by its wrap()."""
    for name, member in list(vars(cls).items()):
        if name.startswith("__") and name != "__init__":
            continue
        if isinstance(member, staticmethod):
            cls_member = getattr(cls, name)
            if _is_builtin(cls_member):
                setattr(cls, name, staticmethod(wrap(cls_member, qualname=f"{cls.__name__}.{name}")))
        elif _is_builtin(member):
            setattr(cls, name, wrap(member, qualname=f"{cls.__name__}.{name}"))
    cls.__module__ = "zwidth"


def _is_builtin(f):
    return callable(f) and not inspect.isfunction(f) and not isinstance(f, (type, property)) and \
        (f.__doc__ or "").split("(")[0].isidentifier()
