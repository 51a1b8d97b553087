"""The episode GIF's frame size is bounded (F10): a grid whose 24-pixel cells would make a frame
wider than MAX_GIF_FRAME_SIDE is drawn with smaller cells (every k-th pixel of the environment's
frame), so a size-255 world's GIF has frames of 1,307 × 1,045 pixels, not 6,407 × 6,145; the
layout of every size up to 54 (the default 7 × 7 grid among them) is the one the shipped GIFs have."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from empathy_zoo.episode_gif import MARGIN, EpisodeRecorder, FrameLayout, frame_layout, grid_scale
from empathy_zoo.greedy_episode import play_greedy, watch_env
from empathy_zoo.limits import BOUNDS, MAX_GIF_FRAME_SIDE, MAX_SIZE
from empathy_zoo.render import GRID_RGB, legend

ROOT = Path(__file__).resolve().parents[1]


class StayingAgent:
    """An agent that always takes action 0 (a GIF needs an agent, not a trained one)."""

    def reset(self, seed: int) -> None:
        """Nothing to reset."""

    def act(self, observation: np.ndarray) -> int:
        """Action 0, whatever it sees."""
        return 0


def _gif_frames(data: bytes) -> list[np.ndarray]:
    frames = []
    with Image.open(io.BytesIO(data)) as image:
        for k in range(image.n_frames):
            image.seek(k)
            frames.append(np.asarray(image.convert("RGB")))
    return frames


def test_the_bound_is_listed() -> None:
    assert MAX_GIF_FRAME_SIDE == 1_600 and BOUNDS["GIF frame size"] == MAX_GIF_FRAME_SIDE


def test_the_layout_of_the_default_grid_is_todays() -> None:
    assert frame_layout(7) == FrameLayout(cell=24, stride=1, factor=2, width=624, height=362)
    assert frame_layout(5) == FrameLayout(cell=24, stride=1, factor=3, width=649, height=387)
    assert frame_layout(31) == FrameLayout(cell=24, stride=1, factor=1, width=1_031, height=769)
    shipped = sorted(ROOT.glob("docs/results/coexistence_sensitivity/figures/*_episode.gif"))
    for path in shipped[:3]:  # (the shipped 7 × 7 GIFs: their logical screen is today's frame)
        header = path.read_bytes()[:10]
        assert (int.from_bytes(header[6:8], "little"), int.from_bytes(header[8:10], "little")) == (624, 362), path


@pytest.mark.parametrize("legend_entries", [2, 3])
def test_every_size_fits_the_bound_and_small_ones_keep_their_cells(legend_entries) -> None:
    for size in range(1, MAX_SIZE + 1):
        layout = frame_layout(size, legend_entries)
        assert layout.width <= MAX_GIF_FRAME_SIDE and layout.height <= MAX_GIF_FRAME_SIDE, (size, layout)
        assert layout.cell * layout.stride == 24 and layout.factor == grid_scale(size * layout.cell)
        if size <= 54:  # (as they were: 24-pixel cells, enlarged as before)
            assert layout.cell == 24 and layout.stride == 1, size
        else:  # (the largest cell that fits: one size up would not)
            bigger = [c for c in (24, 12, 8, 6, 4, 3, 2, 1) if c > layout.cell]
            assert all(12 * 3 + 250 + size * c + 1 > MAX_GIF_FRAME_SIDE for c in bigger), size
    assert frame_layout(MAX_SIZE) == FrameLayout(cell=4, stride=6, factor=1, width=1_307, height=1_045)


def test_a_gif_of_a_size_255_world_is_within_the_bound() -> None:
    env = watch_env("coexistence_v0", {"size": 255}, render_mode="rgb_array")
    recorder = EpisodeRecorder("staying", "coexistence_v0 · size 255", max_steps=2)
    play_greedy(StayingAgent(), env, 0, max_steps=2, on_step=recorder)
    frames = _gif_frames(recorder.gif())
    layout = frame_layout(255, len(legend(env.unwrapped.engine)))
    assert len(frames) == 3 and all(frame.shape == (layout.height, layout.width, 3) for frame in frames)
    assert layout.width <= MAX_GIF_FRAME_SIDE and layout.height <= MAX_GIF_FRAME_SIDE
    # the grid is the environment's own frame, every 6th pixel of it (4-pixel cells), closed by a line
    again = watch_env("coexistence_v0", {"size": 255}, render_mode="rgb_array")
    again.reset(seed=0)
    picture = again.render()[:: layout.stride, :: layout.stride]
    side = picture.shape[0]
    assert side == 255 * layout.cell
    grid = frames[0][MARGIN : MARGIN + side, MARGIN : MARGIN + side]
    assert np.array_equal(grid, picture)
    assert (frames[0][MARGIN + side, MARGIN : MARGIN + side + 1] == GRID_RGB).all()
    for entry in legend(env.unwrapped.engine):  # every agent still shows, in its own colour
        if not entry.battery:
            assert (grid == entry.color).all(axis=2).any(), entry.label
