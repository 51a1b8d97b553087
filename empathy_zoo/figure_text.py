"""The text of figures, drawn as written: a label, a name or a title read from a file (a result
file's method label, ``train --label``, a sweep's labels, a scenario's name) is drawn by Matplotlib
letter for letter, never as mathtext. Matplotlib reads text between two ``$`` as mathtext: a label
like ``$\\foo$`` would fail the whole figure (a parse error), and ``$x$`` be drawn as an italic x.

Text the code itself writes as mathtext stays as it is; only what comes from outside goes through
:func:`literal_text`.
"""

from __future__ import annotations

__all__ = ["literal_text"]


def literal_text(text: str) -> str:
    """``text`` as Matplotlib draws it letter for letter: each ``$`` escaped, so no part of it is
    mathtext (a label like ``$\\foo$`` would fail to parse, ``$x$`` be drawn as math). Matplotlib
    draws ``\\$`` as ``$`` in text without mathtext, and every other character as it is."""
    return text.replace("$", "\\$")
