"""Render a :class:`leaderboard.page.Page` as one self-contained HTML file (inline CSS, PNG figures embedded).

Every text is escaped for an HTML text node (:func:`html_text`: ``<``, ``>`` and ``&``; quotes stay
readable), every attribute value for an attribute (quotes too). Markdown inline text (headings,
paragraphs, list items, definitions) shows its `code spans` as ``<code>`` and its backslash
escapes as the characters they escape (:func:`html_inline`); table cells are shown as they are.
"""

from __future__ import annotations

import html
import re
from collections.abc import Sequence

from leaderboard.html_images import img_tag
from leaderboard.page import Block, BulletList, DefinitionList, Figure, Heading, Page, Paragraph, Section, Table

__all__ = ["CSS", "html_text", "html_inline", "html_table", "html_block", "to_html"]

CSS = """
body { font-family: system-ui, sans-serif; margin: 2em auto; max-width: 76em; color: #222; }
table { border-collapse: collapse; margin: 0.5em 0 1.5em; font-size: 0.9em; }
th, td { border: 1px solid #ccc; padding: 0.3em 0.6em; text-align: right; white-space: nowrap; }
th:first-child, td:first-child { text-align: left; }
thead th { background: #f0f0f0; }
img { max-width: 100%; margin: 0.5em 0; }
code { background: #f4f4f4; padding: 0.1em 0.3em; }
.note { color: #555; font-size: 0.9em; }
"""
"""The page's style sheet, inline in its ``<head>``."""
_CODE_SPAN = re.compile(r"(?<!\\)((?:\\\\)*)`")
"""A backtick that opens or closes a code span: one not escaped by a backslash."""
_ESCAPED = re.compile(r"\\([!-/:-@\[-`{-~])")
"""A Markdown backslash escape: a backslash before an ASCII punctuation character."""


def html_text(text: str) -> str:
    """Escape ``text`` for an HTML text node (quotes stay readable)."""
    return html.escape(text, quote=False)


def html_inline(markdown: str) -> str:
    """Markdown inline text as HTML: its `code spans` as ``<code>`` (their text as typed), the
    rest with its backslash escapes resolved (``\\<`` shows ``<``), all escaped."""
    pieces: list[str] = []
    start = 0
    for found in _CODE_SPAN.finditer(markdown):
        pieces.append(markdown[start : found.end(1)])
        start = found.end()
    pieces.append(markdown[start:])
    return "".join(
        f"<code>{html_text(piece)}</code>" if i % 2 else html_text(_ESCAPED.sub(r"\1", piece)) for i, piece in enumerate(pieces)
    )


def html_table(header: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    """A table of plain-text cells (header in ``<thead>``)."""
    head = "".join(f"<th>{html_text(cell)}</th>" for cell in header)
    body = "\n".join("<tr>" + "".join(f"<td>{html_text(cell)}</td>" for cell in row) + "</tr>" for row in rows)
    return f"<table>\n<thead><tr>{head}</tr></thead>\n<tbody>\n{body}\n</tbody>\n</table>"


def html_block(block: Block) -> str:
    """One block as HTML (its elements on lines of their own, no trailing newline)."""
    match block:
        case Heading(text, level):
            return f"<h{level}>{html_inline(text)}</h{level}>"
        case Paragraph(text, note):
            style = ' class="note"' if note else ""
            return f"<p{style}>{html_inline(text)}</p>"
        case Table(header, rows):
            return html_table(header, rows)
        case Figure(alt, link, png):
            if png is not None:
                return img_tag(png, alt)
            return f'<img alt="{html.escape(alt)}" src="{html.escape(link)}">'  # (linked: a GIF is large)
        case BulletList(items):
            return "\n".join(["<ul>", *(f"<li>{html_inline(item)}</li>" for item in items), "</ul>"])
        case DefinitionList(items):
            lines = [f"<dt>{html_inline(term)}</dt><dd>{html_inline(definition)}</dd>" for term, definition in items]
            return "\n".join(["<dl>", *lines, "</dl>"])
    raise TypeError(f"not a block of a page: {block!r}")


def _section_lines(section: Section) -> list[str]:
    heading = [Heading(section.title, 2)] if section.title else []
    return [html_block(block) for block in [*heading, *section.blocks]]


def to_html(page: Page) -> str:
    """The whole page as one HTML file: ``<head>`` with its title and style sheet, its title as
    ``<h1>``, then every section's blocks, each on lines of its own; ends with a newline."""
    lines = [
        "<!DOCTYPE html>",
        '<html lang="en">',
        "<head>",
        '<meta charset="utf-8">',
        f"<title>{html_text(page.title)}</title>",
        f"<style>{CSS}</style>",
        "</head>",
        "<body>",
        f"<h1>{html_text(page.title)}</h1>",
    ]
    for section in page.sections:
        lines += _section_lines(section)
    lines += ["</body>", "</html>"]
    return "\n".join(lines) + "\n"
