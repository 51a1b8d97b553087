"""Pictures of one environment of an engine: a text grid, an RGB image, and what a picture's
legend and enlargement need (:func:`legend`, :func:`swatch`, :func:`scaled`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from empathy_zoo.engine.base import GridEngine

__all__ = ["render_text", "render_rgb", "LegendEntry", "legend", "swatch", "scaled"]

FLOOR_CHAR, BATTERY_CHAR, CROWD_CHAR = ".", "o", "*"
FLOOR_RGB = (235, 235, 235)
GRID_RGB = (190, 190, 190)
BATTERY_RGB = (60, 170, 70)
AGENT_INSET = 2
"""Pixels of floor left around an agent's square in its cell."""


def _battery_cells(engine: GridEngine, env_id: int) -> np.ndarray:
    batteries = getattr(engine, "batteries", None)
    if batteries is None:
        return np.zeros(0, dtype=np.int64)
    return np.flatnonzero(batteries[env_id])


def _battery_inset(cell_pixels: int) -> int:
    """Pixels of floor left around a battery's square in its cell."""
    return cell_pixels // 4


def render_text(engine: GridEngine, env_id: int = 0) -> str:
    """The grid as text: ``.`` floor, ``o`` battery, one letter per agent, ``*`` for several on one cell."""
    size = engine.size
    grid = [[FLOOR_CHAR] * size for _ in range(size)]
    for cell in _battery_cells(engine, env_id):
        grid[cell // size][cell % size] = BATTERY_CHAR
    for agent in range(engine.num_agents):
        if engine.present[env_id, agent]:
            row, col = engine.pos[env_id, agent]
            here = grid[row][col]
            grid[row][col] = CROWD_CHAR if here in engine.symbols else engine.symbols[agent]
    return "\n".join(" ".join(row) for row in grid) + "\n"


def render_rgb(engine: GridEngine, env_id: int = 0, cell_pixels: int = 24) -> np.ndarray:
    """The grid as an ``(H, W, 3)`` uint8 image, ``cell_pixels`` per cell."""
    size, px = engine.size, cell_pixels
    image = np.empty((size * px, size * px, 3), dtype=np.uint8)
    image[...] = FLOOR_RGB
    image[::px, :] = GRID_RGB
    image[:, ::px] = GRID_RGB
    inset = _battery_inset(px)
    for cell in _battery_cells(engine, env_id):
        r, c = divmod(int(cell), size)
        image[r * px + inset : (r + 1) * px - inset, c * px + inset : (c + 1) * px - inset] = BATTERY_RGB
    for agent in range(engine.num_agents):
        if engine.present[env_id, agent]:
            r, c = engine.pos[env_id, agent]
            shift = min(agent, 2) * (px // 6)  # agents on one cell stay visible
            top, left = r * px + AGENT_INSET + shift, c * px + AGENT_INSET + shift
            image[top : (r + 1) * px - AGENT_INSET, left : (c + 1) * px - AGENT_INSET] = engine.colors[agent]
    return image


@dataclass(frozen=True)
class LegendEntry:
    """One kind of thing :func:`render_rgb` draws, and how."""

    label: str
    """What it is: the agents' names (``robot_0``; ``cat_0, cat_1``; ``cat_0 … cat_2`` for more alike) or ``battery``."""
    color: tuple[int, int, int]
    """The RGB colour it is drawn in."""
    battery: bool
    """Drawn as a battery (a smaller square) rather than an agent."""


def legend(engine: GridEngine) -> list[LegendEntry]:
    """What the image of ``engine`` shows, in agent order: one entry per agent colour (agents
    drawn alike share one, e.g. ``cat_0 … cat_2``), then ``battery`` for an engine with batteries."""
    groups: dict[tuple[int, int, int], list[str]] = {}
    for name, color in zip(engine.agents, engine.colors, strict=True):
        groups.setdefault(color, []).append(name)
    entries = [
        LegendEntry(", ".join(names) if len(names) <= 2 else f"{names[0]} … {names[-1]}", color, False)
        for color, names in groups.items()
    ]
    if getattr(engine, "batteries", None) is not None:
        entries.append(LegendEntry("battery", BATTERY_RGB, True))
    return entries


def swatch(entry: LegendEntry, cell_pixels: int = 24) -> np.ndarray:
    """One floor cell showing ``entry`` as :func:`render_rgb` draws it, ``(cell_pixels, cell_pixels, 3)`` uint8."""
    px = cell_pixels
    image = np.empty((px, px, 3), dtype=np.uint8)
    image[...] = FLOOR_RGB
    image[0, :] = image[-1, :] = image[:, 0] = image[:, -1] = GRID_RGB
    inset = _battery_inset(px) if entry.battery else AGENT_INSET
    image[inset : px - inset, inset : px - inset] = entry.color
    return image


def scaled(image: np.ndarray, factor: int) -> np.ndarray:
    """``image`` (``(H, W, C)``) enlarged ``factor`` times by repeating each pixel (nearest neighbour)."""
    if isinstance(factor, bool) or not isinstance(factor, int) or factor < 1:
        raise ValueError(f"a scale factor is a positive int, got {factor!r}")
    return image.repeat(factor, axis=0).repeat(factor, axis=1)
