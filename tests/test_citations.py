"""Citations in the package: every source is a document listed in docs/references.md.

The source documents are cited by short key and place ("Douglas et al. 1996, §4.1, (4.3)");
nothing under ``src/`` may point at material outside the repository (working notes, local
copies of the sources).
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src"
REFERENCES = ROOT / "docs" / "references.md"

#: The five source documents, as the code cites them.
SEED_KEYS = ("Douglas et al. 1996", "Murray 2012", "Hallouzi 2008", "van der Ploeg 2018", "Varrier et al. 2014")

#: Phrases that must not occur in the package (outside material).
FORBIDDEN = ("research note", "note §", "../shared", "/work/shared")

#: "<Name> [et al.][,] [(]<year>": the last author's name before a year is enough to find the entry.
KEY = re.compile(r"\b([A-Z][a-zA-Z\u00C0-\u017F\-]+)(?:'s)?(?: et al\.)?,? \(?((?:19|20)\d\d[a-z]?)\b")

#: Name–year pairs that are not citations.
NOT_CITATIONS = {("Prius", "2010")}  # "Toyota Prius 2010", a vehicle


def _sources():
    return sorted(p for p in SRC.rglob("*.py") if "__pycache__" not in p.parts)


def _reference_lines() -> list[str]:
    return REFERENCES.read_text(encoding="utf-8").splitlines()


@pytest.mark.parametrize("phrase", FORBIDDEN)
def test_no_source_cites_outside_material(phrase):
    hits = [
        f"{p.relative_to(ROOT)}:{i}"
        for p in _sources()
        for i, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1)
        if phrase.lower() in line.lower()
    ]
    assert not hits, f"{phrase!r} found in {hits}"


def test_references_file_exists():
    assert REFERENCES.is_file()


@pytest.mark.parametrize("key", SEED_KEYS)
def test_references_have_each_seed(key):
    entries = [line for line in _reference_lines() if line.startswith("|") and f"**{key}**" in line]
    assert len(entries) == 1, f"docs/references.md needs one table row for {key!r}"
    year = key.rsplit(" ", 1)[1]
    assert year in entries[0].split("|", 2)[2], f"the entry for {key!r} does not give the year"


def test_every_short_key_in_src_has_a_reference():
    lines = _reference_lines()
    missing = {}
    for p in _sources():
        for m in KEY.finditer(p.read_text(encoding="utf-8")):
            name, year = m.group(1), m.group(2)
            if (name, year) in NOT_CITATIONS:
                continue
            if not any(name in line and year in line for line in lines if line.startswith("|")):
                missing.setdefault(f"{name} {year}", str(p.relative_to(ROOT)))
    assert not missing, f"short keys without an entry in docs/references.md: {missing}"


def test_key_pattern_finds_the_usual_forms():
    text = "Douglas et al. 1996, §4.1; Murray (2012); Kanev's (2006) QCQP; Basseville & Nikiforov 1993"
    assert [m.groups() for m in KEY.finditer(text)] == [
        ("Douglas", "1996"), ("Murray", "2012"), ("Kanev", "2006"), ("Nikiforov", "1993")
    ]
