"""The README reads in one sitting: short, short sentences, and the CI's own commands.

The sentence splitter is deliberately small: fenced code, tables, headings, HTML comments, image
lines and list items that are only links are not prose and are skipped; inline code counts as one
word and a link as its text; a sentence ends at ``.``, ``!`` or ``?`` followed by a space, or at the
end of a paragraph or list item.
"""

from __future__ import annotations

import re
import statistics
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"
CI = ROOT / ".ci" / "run"

MAX_BYTES = 10_240
MAX_MEDIAN_WORDS = 20
START = "<!-- --8<-- [start:quickstart] -->"
END = "<!-- --8<-- [end:quickstart] -->"
MAIN_JOB = "pip install torch==2.13.0 && pip install -e . && empathy-zoo reproduce --profile quick"

_LINK = re.compile(r"!?\[([^\]]*)\]\([^)]*\)")
_CODE = re.compile(r"`[^`]*`")
_LIST_ITEM = re.compile(r"^\s*(?:[-*+]|\d+\.)\s+")
_SENTENCE_END = re.compile(r"(?<=[.!?])\s+")


def prose_blocks(text: str) -> list[str]:
    """Paragraphs and list items of prose, each as one line."""
    blocks: list[str] = []
    current: list[str] = []
    in_fence = False

    def flush() -> None:
        if current:
            blocks.append(" ".join(current))
            current.clear()

    for raw in text.splitlines():
        line = raw.strip()
        if line.startswith("```"):
            flush()
            in_fence = not in_fence
            continue
        if in_fence:
            continue
        if not line or line.startswith(("#", "|", "<!--", "![")) or line.startswith("--8<--"):
            flush()
            continue
        if _LIST_ITEM.match(line):
            flush()
            item = _LIST_ITEM.sub("", line)
            if not re.search(r"\w", _LINK.sub("", item)):
                continue  # a list item that is only links
            current.append(item)
            continue
        current.append(line)
    flush()
    return blocks


def sentences(text: str) -> list[str]:
    """Every prose sentence of a Markdown text."""
    found: list[str] = []
    for block in prose_blocks(text):
        plain = _CODE.sub("CODE", _LINK.sub(r"\1", block))
        found.extend(part for part in _SENTENCE_END.split(plain) if re.search(r"\w", part))
    return found


def word_count(sentence: str) -> int:
    return sum(1 for token in sentence.split() if re.search(r"\w", token))


def median_words(text: str) -> float:
    return statistics.median(word_count(s) for s in sentences(text))


def test_splitter_on_a_known_text() -> None:
    text = (
        "# Title\n\nOne two three. Four `a b c` five!\n\n```bash\nnot prose here at all\n```\n\n"
        "| a | b |\n|---|---|\n\n- [only a link](x.md)\n- [a link](y.md) with words.\n"
    )
    assert [word_count(s) for s in sentences(text)] == [3, 3, 4]


def test_readme_is_short() -> None:
    size = len(README.read_bytes())
    assert size <= MAX_BYTES, f"README.md is {size} bytes, over {MAX_BYTES}"


def test_readme_sentences_are_short() -> None:
    median = median_words(README.read_text(encoding="utf-8"))
    assert median <= MAX_MEDIAN_WORDS, f"median sentence is {median} words, over {MAX_MEDIAN_WORDS}"


def test_quickstart_has_the_two_commands_of_ci() -> None:
    text = README.read_text(encoding="utf-8")
    assert text.count(START) == 1 and text.count(END) == 1
    snippet = text[text.index(START) : text.index(END)]
    ci_test_command = next(
        line.strip() for line in CI.read_text(encoding="utf-8").splitlines() if line.strip().endswith("python -m pytest -n 2")
    )
    commands = [line.strip() for line in snippet.splitlines() if line.strip().startswith("pip install")]
    assert commands == [MAIN_JOB, ci_test_command]
