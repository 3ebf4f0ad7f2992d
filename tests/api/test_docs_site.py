"""The documentation site's sources: the API pages cover every module and are current; the nav lists every page."""

from __future__ import annotations

import importlib.util
import pathlib
import re

ROOT = pathlib.Path(__file__).resolve().parents[2]


def _api_pages():
    spec = importlib.util.spec_from_file_location("api_pages", ROOT / "tools" / "api_pages.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_api_pages_are_current():
    pages = _api_pages()
    for name, text in pages.expected().items():
        path = ROOT / "docs" / "api" / name
        assert path.exists() and path.read_text(encoding="utf-8") == text, (
            f"docs/api/{name} is missing or stale; run `python tools/api_pages.py`")


def test_every_module_has_an_api_page():
    pages = _api_pages()
    listed = {m for _, pkg, _ in pages.PAGES for m in pages.modules(pkg)}
    src = ROOT / "src" / "fdikit"
    every = {"fdikit." + ".".join(p.with_suffix("").relative_to(src).parts)
             for p in src.rglob("*.py") if p.name != "__init__.py"}
    assert every - listed == pages.SKIP


def test_nav_lists_every_page():
    nav = (ROOT / "mkdocs.yml").read_text(encoding="utf-8")
    listed = set(re.findall(r":\s*([\w/.-]+\.md)\s*$|^\s*-\s*([\w/.-]+\.md)\s*$", nav, re.M))
    listed = {a or b for a, b in listed}
    pages = {str(p.relative_to(ROOT / "docs")) for p in (ROOT / "docs").rglob("*.md")}
    assert pages - listed == set(), f"pages not in the mkdocs.yml nav: {sorted(pages - listed)}"
    assert listed - pages == set(), f"nav entries without a page: {sorted(listed - pages)}"


def test_test_files_named_in_the_docs_exist():
    texts = [p for p in (ROOT / "docs").rglob("*.md")] + [ROOT / "README.md"]
    named = {(p.name, m) for p in texts for m in re.findall(r"tests/[\w/]+\.py", p.read_text(encoding="utf-8"))}
    missing = sorted(f"{page}: {path}" for page, path in named if not (ROOT / path).exists())
    assert not missing, "the docs name test files that do not exist:\n" + "\n".join(missing)


def test_module_paths_named_in_the_architecture_exist():
    # The layout block and the where-is table name modules by path under src/fdikit/ (`design/observers/uio.py`).
    text = (ROOT / "docs" / "ARCHITECTURE.md").read_text(encoding="utf-8")
    src = ROOT / "src" / "fdikit"
    named = set(re.findall(r"`((?:[a-z0-9_]+/)*[a-z0-9_]+\.py)`", text))
    missing = sorted(p for p in named if not any(base.joinpath(p).exists() for base in (src, ROOT / "tests", ROOT)))
    assert not missing, "docs/ARCHITECTURE.md names modules that do not exist: " + ", ".join(missing)
