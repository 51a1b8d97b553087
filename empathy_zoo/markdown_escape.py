"""Data written into Markdown, escaped so that it reads as itself.

Every Markdown page the suite writes (leaderboards, reports, separation and discrimination pages,
the readers' printed tables) holds data from files that may come from anyone: labels, method and
row names, reasons, commits, paths. :func:`markdown_text` escapes such text for running prose or a
table cell; :func:`code_span` puts it in a code span where it can be one (no backtick, one line),
and escapes it as text otherwise. Neither lets data open HTML, a link, emphasis, code or a cell.
"""

from __future__ import annotations

import re

__all__ = ["code_span", "markdown_cell", "markdown_text"]

_MARKDOWN_SYNTAX = re.compile(r"[\\`*~\[\]<>&|]|(?<!\w)_|_(?!\w)")
"""What text must not carry unescaped into Markdown to read as itself: a backslash, code, emphasis,
strike-through, link and HTML characters, a table's ``|``, and a ``_`` at a word's edge (one
inside a word, ``other_return``, is no emphasis and stays as it is)."""
_BARE_LINK = re.compile(r"(?<=[A-Za-z0-9])(:)(?=//)|(?<![A-Za-z0-9])(www)(\.)", re.IGNORECASE)
"""Where a renderer that links bare addresses (GitHub's) would start a link: the ``:`` of
``scheme://`` and the ``.`` of ``www.``."""
_EMAIL_AT = re.compile(r"(?<=[A-Za-z0-9.+_\-])@(?=[A-Za-z0-9_\-])")
"""The ``@`` of an e-mail address (``name@host``), which a renderer that links bare addresses
(GitHub's) would make a ``mailto:`` link."""
_MARKDOWN_CELL = re.compile(r"[\\<>&|]")
"""What a cell of figures must not carry unescaped: HTML characters and a table's ``|``."""
_LINE_BREAKS = re.compile(r"[\r\n\u2028\u2029]+")


def markdown_text(text: str) -> str:
    """``text`` (a label, a name: data) escaped for Markdown, so it reads as itself: no HTML (a
    label ``<script>`` is shown, not run), no link (a bare ``https://`` or ``www.`` address
    included, and an e-mail address), no emphasis, no code, no table cell of its own, and on one line."""
    escaped = _MARKDOWN_SYNTAX.sub(lambda found: "\\" + found.group(), _LINE_BREAKS.sub(" ", text))
    unlinked = _BARE_LINK.sub(lambda found: "\\:" if found.group(1) else found.group(2) + "\\.", escaped)
    return _EMAIL_AT.sub("\\\\@", unlinked)


def markdown_cell(text: str) -> str:
    """A table cell of figures: HTML characters and ``|`` escaped, on one line."""
    return _MARKDOWN_CELL.sub(lambda found: "\\" + found.group(), _LINE_BREAKS.sub(" ", text))


def code_span(text: str) -> str:
    """``text`` as a code span (shown as typed: a code span opens no HTML, link or emphasis), or,
    where it holds a backtick or a line break (it could close the span), as :func:`markdown_text`."""
    if "`" in text or _LINE_BREAKS.search(text) or "|" in text:
        return markdown_text(text)
    return f"`{text}`"
