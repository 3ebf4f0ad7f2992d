"""Write the API reference pages of the documentation site (docs/api/*.md), one page per package.

Each page lists the package's modules as mkdocstrings ``:::`` blocks; the members shown are each module's ``__all__``.
Run ``python tools/api_pages.py`` after adding or removing a module; ``tests/test_docs_site.py`` fails when a page is
missing or stale.
"""

from __future__ import annotations

import ast
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
SRC = ROOT / "src" / "fdikit"
API = ROOT / "docs" / "api"

#: Package pages in site order: (page file stem, package dotted name, title).
PAGES = [
    ("core", "fdikit", "Core: models, faults, simulation, traces, residuals, diagnoses"),
    ("linalg", "fdikit.linalg", "Linear algebra: subspaces and detection geometry"),
    ("validate", "fdikit.validate", "Argument validation"),
    ("residuals", "fdikit.residuals", "Residual generation"),
    ("plants", "fdikit.plants", "Plants"),
    ("design", "fdikit.design", "Design: residual names and the faults they isolate"),
    ("design-observers", "fdikit.design.observers", "Design: observer-type filters"),
    ("design-game", "fdikit.design.game", "Design: game-theoretic filters"),
    ("design-parity", "fdikit.design.parity", "Design: parity space"),
    ("design-nullspace", "fdikit.design.nullspace", "Design: nullspace synthesis (FDITOOLS)"),
    ("descriptor", "fdikit.descriptor", "Descriptor models: reductions and Kronecker structure"),
    ("decision", "fdikit.decision", "Decision: residual evaluators"),
    ("decision-learned", "fdikit.decision.learned", "Decision: learned classifiers"),
    ("multimodel", "fdikit.multimodel", "Multiple-model estimation"),
    ("estimate", "fdikit.estimate", "Fault estimation"),
    ("analysis", "fdikit.analysis", "Analysis"),
    ("nonlinear", "fdikit.nonlinear", "Nonlinear plants: trim, linearisation, reduction"),
    ("identify", "fdikit.identify", "Identification: models from data"),
    ("vehicle", "fdikit.vehicle", "The nonlinear PATH vehicle"),
    ("aircraft", "fdikit.aircraft", "Nonlinear aircraft through JSBSim"),
    ("spc", "fdikit.spc", "Subspace predictive control"),
    ("ftc", "fdikit.ftc", "Fault-tolerant control"),
    ("campaign", "fdikit.campaign", "Campaigns: Monte Carlo over plants, faults, designs and evaluators"),
    ("runtime", "fdikit.runtime", "Runtime: compiled online steps, batch kernels, C export"),
    ("studies-path1996", "fdikit.studies.path1996", "Study: Douglas et al. 1996 (PATH)"),
    ("studies-hallouzi2008", "fdikit.studies.hallouzi2008", "Study: Hallouzi 2008"),
    ("studies-vanderploeg2018", "fdikit.studies.vanderploeg2018", "Study: van der Ploeg 2018"),
    ("studies-varga2017", "fdikit.studies.varga2017", "Study: Varga 2017, Chapter 8"),
    ("studies-varrier2014", "fdikit.studies.varrier2014", "Study: Varrier et al. 2014"),
]

#: Modules without an API page: the command line (documented by ``fdikit --help``).
SKIP = {"fdikit.cli", "fdikit.cli_campaign"}


def modules(package: str) -> list[str]:
    """Dotted names of the modules directly in ``package`` (not its subpackages), in file order."""
    folder = SRC.joinpath(*package.split(".")[1:])
    out = []
    for path in sorted(folder.glob("*.py")):
        name = f"{package}.{path.stem}"
        if path.stem == "__init__" or name in SKIP:
            continue
        out.append(name)
    return out


def summary(module: str) -> str:
    """First line of a module's docstring."""
    path = SRC.joinpath(*module.split(".")[1:]).with_suffix(".py")
    doc = ast.get_docstring(ast.parse(path.read_text(encoding="utf-8"))) or ""
    return doc.split("\n")[0]


def page(package: str, title: str) -> str:
    """Markdown of one API page."""
    lines = [f"# {title}", "", f"Package `{package}`.", ""]
    for mod in modules(package):
        lines += [f"## `{mod}`", "", f"::: {mod}", "    options:", "      show_root_heading: false", ""]
    return "\n".join(lines)


def expected() -> dict[str, str]:
    """Page file name → content."""
    return {f"{stem}.md": page(pkg, title) for stem, pkg, title in PAGES}


def main() -> int:
    API.mkdir(parents=True, exist_ok=True)
    for name, text in expected().items():
        (API / name).write_text(text, encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
