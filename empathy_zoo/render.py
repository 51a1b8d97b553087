"""Pictures of one environment of an engine: a text grid and an RGB image."""

from __future__ import annotations

import numpy as np

from empathy_zoo.engine.base import GridEngine

__all__ = ["render_text", "render_rgb"]

FLOOR_CHAR, BATTERY_CHAR, CROWD_CHAR = ".", "o", "*"
FLOOR_RGB = (235, 235, 235)
GRID_RGB = (190, 190, 190)
BATTERY_RGB = (60, 170, 70)


def _battery_cells(engine: GridEngine, env_id: int) -> np.ndarray:
    batteries = getattr(engine, "batteries", None)
    if batteries is None:
        return np.zeros(0, dtype=np.int64)
    return np.flatnonzero(batteries[env_id])


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
    inset = px // 4
    for cell in _battery_cells(engine, env_id):
        r, c = divmod(int(cell), size)
        image[r * px + inset : (r + 1) * px - inset, c * px + inset : (c + 1) * px - inset] = BATTERY_RGB
    for agent in range(engine.num_agents):
        if engine.present[env_id, agent]:
            r, c = engine.pos[env_id, agent]
            shift = min(agent, 2) * (px // 6)  # agents on one cell stay visible
            image[r * px + 2 + shift : (r + 1) * px - 2, c * px + 2 + shift : (c + 1) * px - 2] = engine.colors[agent]
    return image
