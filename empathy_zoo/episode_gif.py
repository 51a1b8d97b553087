"""An animated GIF of a trained agent's greedy episode: the environment's ``rgb_array`` frames,
enlarged, beside a panel with the legend, the step and the episode's metrics so far.

:func:`episode_gif` plays one short episode (at most :data:`GIF_STEPS` steps) of a trained agent
in its own environment (:mod:`empathy_zoo.greedy_episode`) and writes its GIF atomically; an
:class:`EpisodeRecorder` passed as ``on_step`` to :func:`~empathy_zoo.greedy_episode.play_greedy`
does the same inside a longer loop (``empathy-zoo watch --gif``). A frame is the face's
``render()`` in ``render_mode="rgb_array"`` (:func:`empathy_zoo.render.render_rgb`) scaled by
repeating pixels, and a panel drawn with Pillow (a dependency of matplotlib) in matplotlib's own
DejaVu Sans: the title, the step, the robot's last action, a legend of what the grid shows
(:func:`empathy_zoo.render.legend`: the engine's declared colours and the battery's) and the
metrics (:data:`~empathy_zoo.metrics.METRIC_NAMES`). Each frame lasts one tick of the
environment's ``render_fps``; the last one is held :data:`HOLD_MS`.

A frame is at most :data:`~empathy_zoo.limits.MAX_GIF_FRAME_SIDE` (1,600) pixels wide, grid and panel
together (:func:`frame_layout`): a grid whose 24-pixel cells would make it wider is drawn with
smaller cells, the largest of 12, 8, 6, 4, 3, 2 or 1 pixels that fits, by keeping every 2nd, 3rd, …
pixel of the 24-pixel picture (its grid lines fall on kept pixels), when each step is recorded. Sizes
up to 54 keep their 24-pixel cells (the default 7 × 7 grid, enlarged twice, is drawn as it always
was); a 255 × 255 grid is drawn at 4 pixels a cell, a frame of 1,307 × 1,045 pixels (its 24-pixel
cells made frames of 6,407 × 6,145, and ``watch --gif`` was killed at 16.7 GB). The frame's height is the
grid's or the panel's, whichever is taller, and the margins: the panel takes a few hundred pixels.
"""

from __future__ import annotations

import io
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from empathy_zoo.actions import Action
from empathy_zoo.atomic import write_bytes_atomic
from empathy_zoo.greedy_episode import EpisodeOutcome, EpisodeStep, agent_env, play_greedy, watch_env
from empathy_zoo.limits import MAX_GIF_FRAME_SIDE
from empathy_zoo.metrics import METRIC_NAMES
from empathy_zoo.policies import PolicyEntry
from empathy_zoo.render import FLOOR_RGB, GRID_RGB, LegendEntry, legend, scaled, swatch

__all__ = ["GIF_STEPS", "HOLD_MS", "FrameLayout", "GifEpisode", "EpisodeRecorder", "episode_gif", "frame_layout", "grid_scale"]

GIF_STEPS = 60
"""Steps a GIF shows at most by default (a short episode: a few hundred KB)."""
HOLD_MS = 2000
"""How long the last frame is shown, in milliseconds."""
GRID_PIXELS = 336
"""The width the grid is enlarged to, as nearly as a whole factor gets (:func:`grid_scale`)."""
PANEL_WIDTH = 250
"""Width of the text panel beside the grid, in pixels."""
MARGIN = 12
FONT_SIZE = 14
LINE = 19
"""Pixels per line of text."""
SWATCH = 24
"""Cell pixels of a legend swatch."""
CELL_PIXELS = 24
"""Pixels a cell of the environment's ``rgb_array`` frame takes (:func:`empathy_zoo.render.render_rgb`'s default)."""
PANEL_RGB = (255, 255, 255)
TEXT_RGB = (0, 0, 0)


@dataclass(frozen=True)
class GifEpisode:
    """What :func:`episode_gif` played and wrote."""

    outcome: EpisodeOutcome
    """The episode: its steps and metrics."""
    path: Path
    """The GIF written."""
    frames: int
    """Frames in the GIF (steps + 1: the reset, then every step)."""
    size: tuple[int, int]
    """``(width, height)`` of a frame, in pixels."""
    bytes: int
    """Size of the file."""


def grid_scale(grid_width: int) -> int:
    """The whole factor (at least 1) that brings a grid image ``grid_width`` pixels wide nearest to
    :data:`GRID_PIXELS` (2 for the paper's 7 × 7 grid of 24-pixel cells)."""
    return max(1, round(GRID_PIXELS / max(1, grid_width)))


@dataclass(frozen=True)
class FrameLayout:
    """How a GIF draws a grid of ``size`` × ``size`` cells (:func:`frame_layout`)."""

    cell: int
    """Pixels a cell takes before the grid is enlarged (:data:`CELL_PIXELS`, or fewer for a large grid)."""
    stride: int
    """Every ``stride``-th pixel of the environment's frame is kept (``source cell // cell``; 1 keeps all)."""
    factor: int
    """The whole factor the kept grid is enlarged by (:func:`grid_scale`)."""
    width: int
    """Pixels of a frame's width: margins, the enlarged grid, its closing line and the panel."""
    height: int
    """Pixels of a frame's height: the enlarged grid with its closing line, or the panel, whichever
    is taller, and the margins."""


def _panel_height(legend_entries: int) -> int:
    """Pixels the panel's text takes with ``legend_entries`` legend lines (as :meth:`EpisodeRecorder._frame` lays it out)."""
    lines = 2 + 1 + 2 + len(METRIC_NAMES) + 1  # title, env; a gap; step, action; the metrics; the last frame's note
    return lines * LINE + 3 * (LINE // 2) + legend_entries * (SWATCH + 6)


def frame_layout(size: int, legend_entries: int = 2, source_cell: int = CELL_PIXELS) -> FrameLayout:
    """The layout of a GIF frame of a ``size`` × ``size`` grid rendered at ``source_cell`` pixels a
    cell, beside a panel of ``legend_entries`` legend lines: the largest cell of whole pixels that
    divides ``source_cell`` (24, 12, 8, 6, 4, 3, 2, 1) whose frame is at most
    :data:`~empathy_zoo.limits.MAX_GIF_FRAME_SIDE` pixels wide. Computes sizes only, draws nothing.
    A grid too large for that even at 1 pixel a cell (over 1,300 cells a side, beyond the bound of
    ``size``) is a ``ValueError``."""
    if isinstance(size, bool) or not isinstance(size, int) or size < 1:
        raise ValueError(f"a grid's size is a positive int, got {size!r}")
    for cell in (c for c in range(source_cell, 0, -1) if source_cell % c == 0):
        grid = size * cell
        factor = grid_scale(grid)
        width = MARGIN + grid * factor + factor + MARGIN + PANEL_WIDTH + MARGIN
        if width <= MAX_GIF_FRAME_SIDE:
            height = max(grid * factor + factor, _panel_height(legend_entries)) + 2 * MARGIN
            return FrameLayout(cell, source_cell // cell, factor, width, height)
    raise ValueError(
        f"a GIF frame is at most {MAX_GIF_FRAME_SIDE:,} pixels wide: a grid of {size:,} cells a side does not fit "
        "even at 1 pixel a cell (docs/limits.md)"
    )


def _fonts() -> tuple[Any, Any]:
    import matplotlib
    from PIL import ImageFont

    folder = Path(matplotlib.get_data_path(), "fonts", "ttf")
    return ImageFont.truetype(str(folder / "DejaVuSans.ttf"), FONT_SIZE), ImageFont.truetype(
        str(folder / "DejaVuSans-Bold.ttf"), FONT_SIZE
    )


def _fit(draw: Any, text: str, font: Any, width: int) -> str:
    """``text`` shortened with ``…`` until it fits ``width`` pixels."""
    if draw.textlength(text, font=font) <= width:
        return text
    while text and draw.textlength(text + "…", font=font) > width:
        text = text[:-1]
    return text + "…"


def _value(name: str, value: float) -> str:
    return f"{value:.2f}" if name == "equality" else f"{value:g}"


class EpisodeRecorder:
    """Frames of one episode for a GIF: pass it as ``on_step`` to
    :func:`~empathy_zoo.greedy_episode.play_greedy` (on an environment made with
    ``render_mode="rgb_array"``); it keeps the reset and the first ``max_steps`` steps, then
    :meth:`gif` draws them. ``title`` heads the panel (e.g. the method), ``subtitle`` the line below it."""

    def __init__(self, title: str, subtitle: str = "", max_steps: int = GIF_STEPS) -> None:
        if isinstance(max_steps, bool) or not isinstance(max_steps, int) or max_steps < 1:
            raise ValueError(f"a GIF shows a positive number of steps, got {max_steps!r}")
        self.title = title
        """The panel's first line."""
        self.subtitle = subtitle
        """The panel's second line."""
        self.max_steps = max_steps
        """Steps kept at most (after the reset)."""
        self._steps: list[tuple[np.ndarray, EpisodeStep]] = []
        self._legend: list[LegendEntry] = []
        self._max_cycles = 0
        self._fps = 5
        self._stride = 1

    def __call__(self, step: EpisodeStep) -> None:
        """Keep ``step``'s ``rgb_array`` frame (up to ``max_steps``): for a grid too large for
        :data:`~empathy_zoo.limits.MAX_GIF_FRAME_SIDE`, only every ``stride``-th pixel of it
        (:func:`frame_layout`, decided at the reset), so the full-size frame is not kept."""
        if step.step > self.max_steps:
            return
        image = step.env.render()
        if not isinstance(image, np.ndarray):
            raise ValueError("an EpisodeRecorder needs an environment made with render_mode='rgb_array'")
        if not self._steps:
            engine = step.env.unwrapped.engine
            self._legend = legend(engine)
            self._max_cycles = int(engine.max_cycles)
            self._fps = int(step.env.unwrapped.metadata.get("render_fps", 5))
            size = int(engine.size)
            self._stride = frame_layout(size, len(self._legend), max(1, image.shape[1] // size)).stride
        if self._stride > 1:  # (a large grid: keep its smaller cells only, not the full frame of every step)
            image = np.ascontiguousarray(image[:: self._stride, :: self._stride])
        self._steps.append((image, step))

    @property
    def frames(self) -> int:
        """Frames kept so far."""
        return len(self._steps)

    @property
    def whole_episode(self) -> bool:
        """The frames kept reach the episode's end."""
        return bool(self._steps) and self._steps[-1][1].over

    def gif(self, comment: str = "") -> bytes:
        """The GIF of the frames kept (looping; each frame one tick of the env's ``render_fps``,
        the last held :data:`HOLD_MS`); a ``comment`` is written as its comment extension (the
        mark of the tool that wrote it, e.g. :data:`~empathy_zoo.names.WATCH_GIF_MARK`)."""
        if not self._steps:
            raise ValueError("no frame was recorded: pass the recorder as on_step to play_greedy")
        fonts = _fonts()
        palette = _palette(self._legend)
        last = len(self._steps) - 1
        # (each frame is drawn and indexed in turn: one RGB canvas at a time, not all of them)
        frames = [_indexed(self._frame(image, step, fonts, k == last), palette) for k, (image, step) in enumerate(self._steps)]
        tick = max(20, round(1000 / self._fps))
        buffer = io.BytesIO()
        frames[0].save(
            buffer,
            format="GIF",
            save_all=True,
            append_images=frames[1:],
            duration=[tick] * (len(frames) - 1) + [HOLD_MS],
            loop=0,
            **({"comment": comment.encode("latin-1")} if comment else {}),
        )
        return buffer.getvalue()

    def _panel_height(self) -> int:
        """Pixels the panel's text takes (as :meth:`_frame` lays it out)."""
        return _panel_height(len(self._legend))

    def _frame(self, grid: np.ndarray, step: EpisodeStep, fonts: tuple[Any, Any], last: bool) -> np.ndarray:
        from PIL import Image, ImageDraw

        regular, bold = fonts
        factor = grid_scale(grid.shape[1])
        grid = scaled(grid, factor)
        rows, cols = grid.shape[:2]
        height = max(rows + factor, self._panel_height()) + 2 * MARGIN
        width = MARGIN + cols + factor + MARGIN + PANEL_WIDTH + MARGIN
        canvas = np.empty((height, width, 3), dtype=np.uint8)
        canvas[...] = PANEL_RGB
        canvas[MARGIN : MARGIN + rows, MARGIN : MARGIN + cols] = grid
        # (render_rgb draws each cell's top and left line: close the grid on its bottom and right)
        canvas[MARGIN + rows : MARGIN + rows + factor, MARGIN : MARGIN + cols + factor] = GRID_RGB
        canvas[MARGIN : MARGIN + rows + factor, MARGIN + cols : MARGIN + cols + factor] = GRID_RGB
        left = MARGIN + cols + factor + MARGIN
        y = MARGIN
        image = Image.fromarray(canvas)
        draw = ImageDraw.Draw(image)

        def text(line: str, font: Any = regular, x: int = left) -> None:
            nonlocal y
            draw.text((x, y), _fit(draw, line, font, left + PANEL_WIDTH - x), font=font, fill=TEXT_RGB)
            y += LINE

        text(self.title, bold)
        text(self.subtitle)
        y += LINE
        text(f"step {step.step} / {self._max_cycles}")
        text("robot: " + ("(start)" if step.action is None else Action(step.action).name.lower()))
        y += LINE // 2
        swatch_rows = []  # (the swatches are pasted as pixels once the text is drawn)
        for entry in self._legend:
            swatch_rows.append(y)
            draw.text((left + SWATCH + 8, y + (SWATCH - FONT_SIZE) // 2 - 1), entry.label, font=regular, fill=TEXT_RGB)
            y += SWATCH + 6
        y += LINE // 2
        for name in METRIC_NAMES:
            text(f"{name.replace('_', ' ')}: {_value(name, step.metrics[name])}")
        y += LINE // 2
        if last:
            text("episode over" if step.over else f"first {step.step} steps shown")
        canvas = np.asarray(image).copy()
        for entry, row in zip(self._legend, swatch_rows, strict=True):
            canvas[row : row + SWATCH, left : left + SWATCH] = swatch(entry, SWATCH)
        return canvas


def _palette(entries: Sequence[LegendEntry]) -> np.ndarray:
    """``(K, 3)`` every colour a frame holds: the grid's, the legend's, and greys for text (black
    on white, smoothed)."""
    colors = [PANEL_RGB, TEXT_RGB, FLOOR_RGB, GRID_RGB, *(entry.color for entry in entries)]
    colors += [(v, v, v) for v in range(8, 256, 8) if (v, v, v) not in colors]
    return np.array(list(dict.fromkeys(colors)), dtype=np.int64)


def _indexed(image: np.ndarray, palette: np.ndarray) -> Any:
    """``image`` as a Pillow palette image of ``palette``: each pixel the nearest colour, so a
    colour of the palette stays exactly that colour (Pillow's own conversion approximates)."""
    from PIL import Image

    codes = (image[..., 0].astype(np.int64) << 16) | (image[..., 1].astype(np.int64) << 8) | image[..., 2]
    unique, inverse = np.unique(codes.ravel(), return_inverse=True)
    colors = np.stack([unique >> 16, (unique >> 8) & 255, unique & 255], axis=1)
    nearest = ((colors[:, None, :] - palette[None, :, :]) ** 2).sum(axis=2).argmin(axis=1)
    height, width = codes.shape
    indexed = Image.frombytes("P", (width, height), nearest[inverse].astype(np.uint8).tobytes())
    indexed.putpalette([int(v) for v in palette.ravel()])
    return indexed


def episode_gif(
    agent: Any,
    path: str | Path,
    *,
    env: str | None = None,
    env_kwargs: Mapping[str, Any] | None = None,
    fixed: Mapping[str, PolicyEntry] | None = None,
    seed: int = 0,
    max_steps: int = GIF_STEPS,
    title: str | None = None,
) -> GifEpisode:
    """Play one greedy episode of the trained ``agent`` (from :func:`empathy_zoo.load_agent`),
    reset with ``seed``, for at most ``max_steps`` steps, and write its GIF atomically at ``path``.

    ``env`` (with ``env_kwargs``) replaces the agent's own environment (its ``describe()``'s, with
    the fixed agents it recorded); ``fixed`` replaces some of the other agents' policies either way.
    ``title`` heads the panel (default: the run's label, as its tables show it, else its method)."""
    description = agent.describe()
    if env is None:
        if env_kwargs is not None:
            raise ValueError("env_kwargs go with env; without env the agent's own environment and arguments are used")
        environment = agent_env(agent, fixed, render_mode="rgb_array")
        name = description["env"]
    else:
        environment = watch_env(env, env_kwargs, fixed, render_mode="rgb_array")
        name = env
    default = description.get("label") or description.get("method") or "trained agent"
    recorder = EpisodeRecorder(title or str(default), f"{name} · seed {seed}", max_steps)
    outcome = play_greedy(agent, environment, seed, max_steps=max_steps, on_step=recorder)
    data = recorder.gif()
    written = write_bytes_atomic(path, data)
    return GifEpisode(outcome, written, recorder.frames, _gif_size(data), len(data))


def _gif_size(data: bytes) -> tuple[int, int]:
    """``(width, height)`` of a GIF (its logical screen)."""
    return int.from_bytes(data[6:8], "little"), int.from_bytes(data[8:10], "little")
