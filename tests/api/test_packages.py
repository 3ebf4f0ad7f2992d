"""Every package's ``__all__``: star import works, each listed name exists and has a docstring; imports are light."""

from __future__ import annotations

import importlib
import pathlib
import subprocess
import sys

import pytest

SRC = pathlib.Path(__file__).resolve().parents[2] / "src" / "fdikit"
PACKAGES = sorted(
    "fdikit" + ("." + ".".join(p.parent.relative_to(SRC).parts) if p.parent != SRC else "")
    for p in SRC.rglob("__init__.py")
)
MODULES = sorted(
    "fdikit." + ".".join(p.with_suffix("").relative_to(SRC).parts)
    for p in SRC.rglob("*.py") if p.name != "__init__.py"
)


def test_every_package_is_listed():
    assert {"fdikit", "fdikit.design", "fdikit.design.observers", "fdikit.design.game", "fdikit.design.parity",
            "fdikit.decision", "fdikit.decision.learned", "fdikit.studies"} <= set(PACKAGES)


@pytest.mark.parametrize("package", PACKAGES)
def test_star_import_gives_every_name_with_a_docstring(package):
    mod = importlib.import_module(package)
    names = list(mod.__all__)
    assert names, f"{package}.__all__ is empty"
    assert len(set(names)) == len(names), f"{package}.__all__ lists a name twice"
    ns: dict = {}
    exec(f"from {package} import *", ns)  # noqa: S102 - the star import is what is tested
    missing = [n for n in names if n not in ns]
    assert not missing, f"from {package} import * does not give {missing}"
    for n in names:
        obj = getattr(mod, n)
        doc = getattr(obj, "__doc__", None)
        assert doc and doc.strip(), f"{package}.{n} has no docstring"


@pytest.mark.parametrize("module", MODULES)
def test_every_module_lists_its_public_names(module):
    if module == "fdikit.cli":
        pytest.skip("the CLI module is the typer application, documented by `fdikit --help`")
    mod = importlib.import_module(module)
    assert hasattr(mod, "__all__"), f"{module} has no __all__"
    for n in mod.__all__:
        assert hasattr(mod, n), f"{module}.__all__ lists {n!r}, which {module} does not define"


@pytest.mark.parametrize("module", MODULES)
def test_no_module_is_over_600_lines(module):
    path = SRC.joinpath(*module.split(".")[1:]).with_suffix(".py")
    lines = len(path.read_text(encoding="utf-8").splitlines())
    assert lines <= 600, f"{path.relative_to(SRC.parent)} has {lines} lines; split it by concept (limit 600)"


#: Modules a light package import must not load (each costs 0.1–1 s; the packages that need them load them lazily).
HEAVY = ("scipy.signal", "scipy.stats", "scipy.optimize", "scipy.integrate", "control", "cvxpy", "matplotlib",
         "pandas", "pyarrow", "rich", "typer", "jsbsim")


@pytest.mark.parametrize("package", ["fdikit", "fdikit.design", "fdikit.decision", "fdikit.multimodel",
                                     "fdikit.plants", "fdikit.studies", "fdikit.analysis", "fdikit.estimate",
                                     "fdikit.vehicle", "fdikit.aircraft", "fdikit.identify",
                                     "fdikit.spc", "fdikit.ftc"])
def test_package_import_is_light(package):
    # A fresh interpreter: which modules does importing the package (not using it) load?  The wall time of the same
    # imports is measured in benchmarks/bench_import.py (docs/PERFORMANCE.md), not here.
    code = f"import sys, {package}; print(','.join(m for m in {HEAVY!r} if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == "", f"import {package} loads {out}; import them inside the functions that need them"


def test_no_module_imports_another_modules_private_names():
    import ast

    found = []
    for path in sorted(SRC.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("fdikit"):
                private = [a.name for a in node.names if a.name.startswith("_") and a.name != "__version__"]
                if private:
                    found.append(f"{path.relative_to(SRC.parent)}: from {node.module} import {', '.join(private)}")
    assert not found, "private names imported across modules (make them public or move them):\n" + "\n".join(found)


def test_no_module_re_exports_another_modules_names_in_its_all():
    # A name belongs to the module that defines it; only package __init__ files collect names of their modules.
    found = []
    for module in MODULES:
        if module == "fdikit.cli":
            continue
        mod = importlib.import_module(module)
        for n in mod.__all__:
            home = getattr(getattr(mod, n), "__module__", module)
            if callable(getattr(mod, n)) and home != module and home.startswith("fdikit"):
                found.append(f"{module}.{n} is defined in {home}")
    assert not found, "\n".join(found)
