"""The order of a leaderboard's rows: labels compared with their numbers as numbers.

A sweep's labels carry the values swept (``"DQN + inequity aversion (disadvantageous=0.3)"``,
``"Empathic DQN (β=0.25)"``): compared as plain strings, α = 1 would come before α = 0.3 (``"1"`` <
``"0.3"`` is false, but ``"10"`` < ``"9"`` is true) and −100 before −20. :func:`label_order` splits a
label into text and numbers and compares the numbers by value, so the rows of one method follow
its parameter's values.
"""

from __future__ import annotations

import re

__all__ = ["label_order"]

_NUMBER = re.compile(r"(?<![\w.])([-−]?(?:\d{1,3}(?:,\d{3})+|\d+)(?:\.\d+)?(?:[eE][-+]?\d+)?)(?![\w.])")
"""A number standing on its own: optionally signed (``-`` or the minus sign ``−``), its thousands
optionally grouped by commas (``30,000``: a budget in a row's label), with a fraction and an
exponent; not the digits of a word (``coexistence_v0``, ``x2``) or a version (``1.2.3``)."""


def label_order(label: str) -> tuple[tuple[str | float, ...], str]:
    """A sort key of ``label``: its pieces of text and its numbers by value, in turn (then the
    label itself, so that ``"1"`` and ``"1.0"`` still have an order)."""
    pieces = _NUMBER.split(label)  # text, number, text, number, …, text: the same kinds at the same places
    return tuple(float(piece.replace("−", "-").replace(",", "")) if i % 2 else piece for i, piece in enumerate(pieces)), label
