"""Typed stubs (.pyi) of the zwidth package, made from the signatures the package itself
gives inspect (zwidth/_signatures.py), so that they cannot drift from the module:

    python3 -m zwidth._stubgen OUT.pyi     (the build writes zwidth/__init__.pyi this way)
"""
import inspect
import re
import sys

_TYPES = [
    (re.compile(r"numpy\.ndarray\[([\w.]+)\]"), r"NDArray[\1]"),
    (re.compile(r"\bnumpy\.ndarray\b(?!\[)"), "NDArray[Any]"),
    (re.compile(r"\bobject\b"), "Any"),
    (re.compile(r"\bcapsule\b"), "Any"),
]


def _type(ann):
    if ann is inspect.Parameter.empty or ann is inspect.Signature.empty or ann is None:
        return "Any"
    text = ann if isinstance(ann, str) else getattr(ann, "__name__", repr(ann))
    for pattern, repl in _TYPES:
        text = pattern.sub(repl, text)
    return text


def _params(sig, method):
    out, star = [], False
    for p in sig.parameters.values():
        if p.kind is p.KEYWORD_ONLY and not star:
            out.append("*")
            star = True
        if p.kind is p.VAR_POSITIONAL:
            out.append(f"*{p.name}: Any")
            star = True
        elif p.kind is p.VAR_KEYWORD:
            out.append(f"**{p.name}: Any")
        elif method and not out and p.name == "self":
            out.append("self")
        else:
            out.append(f"{p.name}: {_type(p.annotation)}" + ("" if p.default is p.empty else " = ..."))
    return ", ".join(out)


def _function(name, f, indent="", method=False):
    try:
        sig = inspect.signature(f)
    except (TypeError, ValueError):
        return [f"{indent}def {name}(*args: Any, **kwargs: Any) -> Any: ..."]
    params = _params(sig, method)
    if method and not params.startswith("self"):
        params = "self" + (", " + params if params else "")
    return [f"{indent}def {name}({params}) -> {_type(sig.return_annotation)}: ..."]


def _property_type(prop):
    doc = (prop.fget.__doc__ or "") if prop.fget else ""
    m = re.match(r"^\((?:self|arg0): [^)]*\) -> (.+)$", doc.split("\n")[0])
    return _type(re.sub(r"\bzwidth\._zwidth\.", "", m.group(1))) if m else "Any"


def _class(cls):
    lines = [f"class {cls.__name__}:"]
    for name, member in sorted(vars(cls).items()):
        if isinstance(member, property):
            lines += ["    @property", f"    def {name}(self) -> {_property_type(member)}:",
                      f"        {(member.__doc__ or '').strip()!r}"]
        elif isinstance(member, staticmethod):
            lines += ["    @staticmethod"] + _function(name, getattr(cls, name), "    ")
        elif name == "__init__" or (not name.startswith("__") and callable(member)):
            lines += _function(name, member, "    ", method=True)
        elif name.startswith("__") and name != "__init__":
            continue
    lines += ["    def __eq__(self, other: object) -> bool: ..."]
    return lines


def stub_text():
    import zwidth
    out = ["# Typed stubs of the zwidth package, generated at build time by zwidth/_stubgen.py",
           "# from the module's own signatures (tests/python checks they match it).",
           "import os", "from typing import Any, Dict, List, Optional, Tuple, Union",
           "import numpy", "from numpy.typing import ArrayLike, NDArray", "",
           "__version__: str", "",
           "class InputError(ValueError): ...", "class ComputationError(RuntimeError): ...",
           "class FitQualityWarning(UserWarning):", "    reasons: List[Dict[str, str]]",
           "    result: FitResult", ""]
    for name in zwidth.__all__:
        obj = getattr(zwidth, name)
        if name in ("__version__", "InputError", "ComputationError", "FitQualityWarning"):
            continue
        out += _class(obj) + [""] if isinstance(obj, type) else _function(name, obj)
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    text = stub_text()
    with open(sys.argv[1], "w", encoding="utf-8") as f:
        f.write(text)
