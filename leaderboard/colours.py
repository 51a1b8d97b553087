"""Colours of a leaderboard's figures: one per method row, the same for the same label in every
figure and every leaderboard.

:func:`label_colours` gives a DQN reference row black (a second and third one dark and mid grey)
and any other row a colour of :data:`PALETTE` chosen by a hash of its label (SHA-256, so the same
in every process and on every machine), so a method keeps its colour from one leaderboard to the
next whatever other methods sit beside it. Where two rows of one figure hash to one colour, the
label first in the leaderboard's order (:func:`leaderboard.ordering.label_order`) keeps it and the
other takes the next colour of the palette not taken; past the palette's 10 colours (a figure of
more rows), evenly spaced hues. :func:`distinct_colours` gives colours that tell things apart
within one figure only (the held-out figure's scenarios).
"""

from __future__ import annotations

import hashlib
from collections.abc import Collection, Iterable
from typing import Any

import matplotlib
from matplotlib.colors import to_hex

from leaderboard.ordering import label_order

__all__ = ["DQN_COLOURS", "PALETTE", "label_colours", "distinct_colours"]

DQN_COLOURS: tuple[str, ...] = ("#000000", "#555555", "#999999")
"""The colours of a figure's DQN reference rows, in the leaderboard's order of their labels (a
fourth one and more take palette colours)."""
PALETTE: tuple[str, ...] = (
    # Okabe & Ito (2008), without its black and its yellow (too light for a line on white)
    "#e69f00",
    "#56b4e9",
    "#009e73",
    "#0072b2",
    "#d55e00",
    "#cc79a7",
    # Paul Tol's "muted" scheme, without its cyan, teal and sand (too near Okabe–Ito's sky blue,
    # bluish green and yellow to tell apart in one figure) and its rose and purple (with Okabe–Ito's
    # reddish purple and Tol's wine, four pinks: rows of one method family looked alike)
    "#332288",
    "#117733",
    "#999933",
    "#882255",
)
"""The colours a method row may take, from two colour-blind-safe palettes: Okabe–Ito's and Paul Tol's muted."""


def _slot(label: str) -> int:
    """The palette index ``label`` hashes to."""
    return int.from_bytes(hashlib.sha256(label.encode("utf-8")).digest()[:8], "big") % len(PALETTE)


def label_colours(labels: Iterable[str], dqn_labels: Collection[str] = ()) -> dict[str, str]:
    """``{label: hex colour}`` for the rows ``labels`` of one figure (see the module page):
    ``dqn_labels`` are its DQN reference rows."""
    unique = sorted(dict.fromkeys(labels), key=label_order)
    references = [label for label in unique if label in dqn_labels]
    # (unequal on purpose: the first three references take DQN_COLOURS, a fourth and more take palette colours)
    colours = dict(zip(references, DQN_COLOURS, strict=False))
    rest = [label for label in unique if label not in colours]
    spare = [c for c in distinct_colours(len(rest) + len(PALETTE)) if c not in PALETTE and c not in DQN_COLOURS]
    taken: set[str] = set()
    for label in rest:
        start = _slot(label)
        free = [PALETTE[(start + k) % len(PALETTE)] for k in range(len(PALETTE))]
        colour = next((c for c in free if c not in taken), None) or next(c for c in spare if c not in taken)
        colours[label] = colour
        taken.add(colour)
    return colours


def distinct_colours(count: int) -> list[Any]:
    """``count`` distinct colours (hex) of one figure: matplotlib's ten-colour cycle up to 10,
    ``tab20`` up to 20, evenly spaced hues beyond (a cycle would give two things one colour)."""
    if count <= 10:
        palette = matplotlib.colormaps["tab10"]
        return [to_hex(palette(i)) for i in range(count)]
    if count <= 20:
        palette = matplotlib.colormaps["tab20"]
        return [to_hex(palette(i)) for i in range(count)]
    palette = matplotlib.colormaps["hsv"]
    return [to_hex(palette(i / count)) for i in range(count)]
