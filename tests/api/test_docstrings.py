"""Numpydoc sections on every public function and class (the API reference renders them; docs/ARCHITECTURE.md).

For each name in a module's ``__all__`` that the module defines:

* a function has ``Parameters`` (when it takes any), ``Returns`` or ``Yields`` (unless annotated ``-> None``),
  ``Raises`` (when its body raises an exception itself) and ``Examples`` with a doctest (``>>>``);
* a class has ``Parameters`` or ``Attributes`` (when it has fields or constructor arguments) and ``Examples``;
* in the method packages (design, decision, multimodel, estimate, plants, studies) both also have ``References``
  (the source document, section and equation; full references in docs/references.md).
"""

from __future__ import annotations

import ast
import dataclasses
import importlib
import inspect
import pathlib
import re
import textwrap

import pytest

SRC = pathlib.Path(__file__).resolve().parents[2] / "src" / "fdikit"
MODULES = sorted(
    "fdikit." + ".".join(p.with_suffix("").relative_to(SRC).parts)
    for p in SRC.rglob("*.py") if p.name != "__init__.py" and p.name != "cli.py"
)
METHOD_PACKAGES = ("fdikit.design.", "fdikit.decision.", "fdikit.multimodel.", "fdikit.estimate.", "fdikit.plants.",
                   "fdikit.studies.", "fdikit.nonlinear.", "fdikit.identify.", "fdikit.spc.",
                   "fdikit.ftc.")


def sections(doc: str) -> set[str]:
    """Numpydoc section titles of a docstring (a title line underlined with dashes)."""
    lines = textwrap.dedent(doc).splitlines()
    return {lines[i].strip() for i in range(len(lines) - 1)
            if lines[i].strip() and re.fullmatch(r"\s*-{3,}\s*", lines[i + 1])}


def raises_itself(func) -> bool:
    """Whether the function body (not nested functions) contains a ``raise`` of an exception."""
    try:
        tree = ast.parse(textwrap.dedent(inspect.getsource(func)))
    except (OSError, TypeError, SyntaxError):
        return False
    body = tree.body[0]

    def walk(node):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda | ast.ClassDef):
                continue
            if isinstance(child, ast.Raise) and child.exc is not None:
                return True
            if walk(child):
                return True
        return False

    return walk(body)


def takes_arguments(func) -> bool:
    try:
        params = list(inspect.signature(func).parameters.values())
    except (TypeError, ValueError):
        return False
    return any(p.name not in ("self", "cls") for p in params)


def returns_something(func) -> bool:
    ann = inspect.signature(func).return_annotation
    return ann not in (None, "None")


def problems(module: str) -> list[str]:
    mod = importlib.import_module(module)
    out = []
    for name in getattr(mod, "__all__", []):
        obj = getattr(mod, name)
        if not (inspect.isfunction(obj) or inspect.isclass(obj)) or getattr(obj, "__module__", None) != module:
            continue
        doc = inspect.getdoc(obj) or ""
        have = sections(doc)
        missing = []
        if inspect.isfunction(obj):
            if takes_arguments(obj) and "Parameters" not in have:
                missing.append("Parameters")
            if returns_something(obj) and not {"Returns", "Yields"} & have:
                missing.append("Returns")
            if raises_itself(obj) and "Raises" not in have:
                missing.append("Raises")
        else:
            fields = dataclasses.is_dataclass(obj) and dataclasses.fields(obj)
            init_args = "__init__" in obj.__dict__ and takes_arguments(obj.__init__)
            if (fields or init_args) and not {"Parameters", "Attributes"} & have:
                missing.append("Parameters or Attributes")
        if "Examples" not in have:
            missing.append("Examples")
        elif ">>>" not in doc:
            missing.append("a doctest (>>>) in Examples")
        if module.startswith(METHOD_PACKAGES) and "References" not in have:
            missing.append("References")
        if missing:
            out.append(f"{module}.{name}: missing {', '.join(missing)}")
    return out


@pytest.mark.parametrize("module", MODULES)
def test_public_names_have_numpydoc_sections(module):
    found = problems(module)
    assert not found, "\n".join(found)
