"""Render a :class:`leaderboard.page.Page` as Markdown, and escape data for Markdown.

Blocks are separated by one blank line; headings, paragraphs, list items and definitions are
written as they are (they are Markdown); table cells and a figure's alt text are data, escaped here
so that each reads as itself (:func:`markdown_text`, :func:`markdown_table`).
"""

from __future__ import annotations

import re
from collections.abc import Sequence

from empathy_zoo.markdown_escape import markdown_cell, markdown_text
from leaderboard.page import Block, BulletList, DefinitionList, Figure, Heading, Page, Paragraph, Section, Table

__all__ = ["markdown_text", "markdown_table", "markdown_block", "section_markdown", "to_markdown"]

_LINE_BREAKS = re.compile(r"[\r\n\u2028\u2029]+")
_ALT_SYNTAX = re.compile(r"[\\\[\]]")
"""What an image's alt text must not carry unescaped: a backslash and the brackets around it."""


def markdown_table(header: Sequence[str], rows: Sequence[Sequence[str]], text_columns: int = 1, left_columns: int = 1) -> str:
    """A Markdown table; the first ``left_columns`` columns are left-aligned, the others
    right-aligned. The first ``text_columns`` cells of each row (a method's label, and the DQN row
    it is compared with) are :func:`markdown_text`; in every cell, HTML characters and ``|`` are escaped."""
    align = [":---" if i < left_columns else "---:" for i in range(len(header))]
    lines = ["| " + " | ".join(markdown_cell(cell) for cell in header) + " |", "|" + "|".join(align) + "|"]
    lines += [
        "| " + " | ".join(markdown_text(cell) if i < text_columns else markdown_cell(cell) for i, cell in enumerate(row)) + " |"
        for row in rows
    ]
    return "\n".join(lines)


def markdown_block(block: Block) -> str:
    """One block as Markdown (no blank line around it)."""
    match block:
        case Heading(text, level):
            return f"{'#' * level} {text}"
        case Paragraph(text):
            return text
        case Table(header, rows, text_columns, left_columns):
            return markdown_table(header, rows, text_columns, left_columns)
        case Figure(alt, link):
            return f"![{_ALT_SYNTAX.sub(lambda found: chr(92) + found.group(), _LINE_BREAKS.sub(' ', alt))}]({link})"
        case BulletList(items):
            return "\n".join(f"- {item}" for item in items)
        case DefinitionList(items):
            return "\n".join(f"- **{term}**: {definition}" for term, definition in items)
    raise TypeError(f"not a block of a page: {block!r}")


def section_markdown(section: Section) -> str:
    """A section as Markdown: its title as a level-2 heading (where it has one), then its blocks,
    one blank line between each; ``""`` for a section with neither."""
    heading = [Heading(section.title, 2)] if section.title else []
    return "\n\n".join(markdown_block(block) for block in [*heading, *section.blocks])


def to_markdown(page: Page) -> str:
    """The whole page as Markdown: its title as the level-1 heading, then every section, one blank
    line between each block; ends with a newline."""
    parts = [f"# {page.title}", *(section_markdown(section) for section in page.sections)]
    return "\n\n".join(part for part in parts if part) + "\n"
