"""References once: the bibliography (skyscatter/data/references.json, docs/references.md) and its keys."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from skyscatter import references

SRC = Path(references.__file__).parent
DOCS = Path(__file__).parents[1] / "docs"
MODULES = sorted(SRC.rglob("*.py"))


def test_docs_page_is_the_bibliography():
    assert (DOCS / "references.md").read_text(encoding="utf-8") == references.markdown()


def test_every_key_cited_in_the_source_is_in_the_bibliography():
    keys = set(references.entries())
    cited = {k for path in MODULES for k in re.findall(r"\[([A-Z][A-Za-z]+[0-9]{4})\]", path.read_text())}
    assert cited, "the docstrings cite by key"
    assert sorted(cited - keys) == []


@pytest.mark.parametrize("pattern,what", [(r"\b10\.\d{4,}/", "a DOI"), (r"doi\.org", "a DOI link"),
                                           (r"\bissues? \d+", "an issue number")])
def test_no_full_reference_or_issue_number_in_the_source(pattern, what):
    """A full reference is written once (the bibliography); issue numbers mean nothing to a reader of the code."""
    hits = [f"{p.relative_to(SRC)}:{i + 1}" for p in MODULES if p.name != "references.py"
            for i, line in enumerate(p.read_text().splitlines()) if re.search(pattern, line, re.IGNORECASE)]
    assert hits == [], f"{what} in {hits}"


def test_cite_formats_a_reference_and_refuses_unknown_keys():
    text = references.cite("Preetham1999")
    assert text.startswith("A. J. Preetham, P. Shirley, B. Smits (1999), A Practical Analytic Model for Daylight")
    assert text.endswith("doi:10.1145/311535.311545")
    assert references.cite("CIE2003", note="see").startswith("see CIE (2003)")
    with pytest.raises(KeyError, match="no reference 'Nobody2000'"):
        references.cite("Nobody2000")
