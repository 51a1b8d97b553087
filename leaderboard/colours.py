"""One colour per method in every figure, distinct however many methods a figure draws."""

from __future__ import annotations

from typing import Any

import matplotlib

__all__ = ["method_colours"]


def method_colours(count: int) -> list[Any]:
    """``count`` distinct colours: matplotlib's ten-colour cycle up to 10 methods, ``tab20`` up
    to 20, evenly spaced hues beyond (a cycle would give two methods one colour)."""
    if count <= 10:
        return [f"C{i}" for i in range(count)]
    if count <= 20:
        palette = matplotlib.colormaps["tab20"]
        return [palette(i) for i in range(count)]
    palette = matplotlib.colormaps["hsv"]
    return [palette(i / count) for i in range(count)]
