"""A leaderboard page as data: an ordered list of sections, each a title and blocks.

The page is written once, as these records, and rendered once per format by
:func:`leaderboard.page_markdown.to_markdown` and :func:`leaderboard.page_html.to_html`, so the
Markdown and HTML pages carry the same sections and blocks in the same order.

Text in a heading, a paragraph, a list item or a definition is Markdown inline text: prose with
`code spans`, and data (a label, an environment's name) escaped with
:func:`leaderboard.page_markdown.markdown_text`. The Markdown page writes it as it is; the HTML page
shows its code spans as ``<code>`` and its backslash escapes as the characters they escape. A
table's cells and a figure's alt text are data, escaped by each renderer.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

__all__ = ["Heading", "Paragraph", "Table", "Figure", "BulletList", "DefinitionList", "Block", "Section", "Page"]


@dataclass(frozen=True)
class Heading:
    """A heading inside a section (a section's own title is level 2)."""

    text: str
    """Markdown inline text."""
    level: int = 3
    """1 to 6: ``###`` and ``<h3>`` for 3."""


@dataclass(frozen=True)
class Paragraph:
    """A paragraph of Markdown inline text."""

    text: str
    """Markdown inline text."""
    note: bool = False
    """Whether it is a legend or a note (``<p class="note">`` in HTML, smaller and grey)."""


@dataclass(frozen=True)
class Table:
    """A table of data: a header and rows of cells, as plain text."""

    header: Sequence[str]
    rows: Sequence[Sequence[str]]
    text_columns: int = 1
    """How many leading cells of each row are text (a label, a name) rather than figures: the
    Markdown escapes them as text (:func:`leaderboard.page_markdown.markdown_text`)."""
    left_columns: int = 1
    """How many leading columns the Markdown aligns left (the others right; the HTML's style sheet
    aligns the first column left)."""


@dataclass(frozen=True)
class Figure:
    """An image: a PNG the HTML page embeds, or a file both pages link."""

    alt: str
    """Its alternative text (plain text)."""
    link: str
    """Its path relative to the page (the Markdown's image link)."""
    png: bytes | None = None
    """The PNG's bytes, embedded in the HTML page (reduced: :func:`leaderboard.html_images.img_tag`);
    ``None``: the HTML page links :attr:`link` (a GIF, too large to embed)."""


@dataclass(frozen=True)
class BulletList:
    """A list of items, each Markdown inline text."""

    items: Sequence[str]


@dataclass(frozen=True)
class DefinitionList:
    """Terms and their definitions, each Markdown inline text."""

    items: Sequence[tuple[str, str]]
    """``(term, definition)`` pairs, in order."""


Block = Heading | Paragraph | Table | Figure | BulletList | DefinitionList
"""Anything a section holds."""


@dataclass(frozen=True)
class Section:
    """A part of the page: a level-2 heading (none where ``title`` is empty) and its blocks."""

    title: str = ""
    """Markdown inline text; ``""``: the blocks follow the previous section's without a heading."""
    blocks: Sequence[Block] = field(default_factory=tuple)


@dataclass(frozen=True)
class Page:
    """A whole page: its title (the HTML's ``<title>`` and the level-1 heading) and its sections in order."""

    title: str
    sections: Sequence[Section]
