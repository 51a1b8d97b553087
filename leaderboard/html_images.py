"""Figures embedded in a leaderboard's HTML page, made small.

The page is one self-contained file: every figure is inside it as a ``data:`` URI. Each PNG is
embedded as a copy reduced to a palette of at most 256 colours, without dithering (the figures
are lines, markers and text on white), which makes it about a third of its size. The PNG files
beside the page stay as drawn.
"""

from __future__ import annotations

import base64
import html
import io
from pathlib import Path

__all__ = ["embedded_png", "img_tag"]

PALETTE_COLOURS = 256
"""The most colours an embedded copy keeps."""


def embedded_png(png: bytes) -> bytes:
    """``png`` reduced to a palette of :data:`PALETTE_COLOURS` colours (median cut, no dithering),
    saved optimised; the original where that is no smaller or where the bytes are no image PIL
    reads. Deterministic for the same bytes."""
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(io.BytesIO(png)) as image:
            reduced = image.convert("RGB").quantize(
                colors=PALETTE_COLOURS, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE
            )
    except (UnidentifiedImageError, OSError):  # (bytes no image reader takes: embedded as they are)
        return png
    out = io.BytesIO()
    reduced.save(out, "PNG", optimize=True)
    small = out.getvalue()
    return small if len(small) < len(png) else png


def img_tag(figure: Path | bytes, alt: str) -> str:
    """An ``<img>`` element holding ``figure`` (a PNG file or its bytes) as a reduced ``data:`` URI."""
    png = figure if isinstance(figure, bytes) else figure.read_bytes()
    data = base64.b64encode(embedded_png(png)).decode("ascii")
    return f'<img alt="{html.escape(alt)}" src="data:image/png;base64,{data}">'
