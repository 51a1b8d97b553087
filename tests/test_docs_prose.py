"""The pages a newcomer reads first (the docs site's first two pages) read in one sitting: their
median sentence is at most 20 words, as the README's is (the splitter is the README test's)."""

from __future__ import annotations

import statistics
from pathlib import Path

import pytest
from test_readme import MAX_MEDIAN_WORDS, sentences, word_count

ROOT = Path(__file__).resolve().parent.parent
FIRST_PAGES = ("docs/index.md", "docs/usage.md")
"""The site's "Getting started" and "Everyday use" pages (mkdocs.yml's first two entries)."""


def test_the_first_pages_are_the_sites_first() -> None:
    nav = [
        line.split(":", 1)[1].strip()
        for line in (ROOT / "mkdocs.yml").read_text(encoding="utf-8").splitlines()
        if line.startswith("  - ") and line.rstrip().endswith(".md")
    ]
    assert tuple(f"docs/{page}" for page in nav[: len(FIRST_PAGES)]) == FIRST_PAGES


@pytest.mark.parametrize("page", FIRST_PAGES)
def test_first_pages_have_short_sentences(page: str) -> None:
    found = sentences((ROOT / page).read_text(encoding="utf-8"))
    assert found, f"{page}: no prose found"
    median = statistics.median(word_count(s) for s in found)
    assert median <= MAX_MEDIAN_WORDS, f"{page}: median sentence is {median} words, over {MAX_MEDIAN_WORDS}"
