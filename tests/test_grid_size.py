"""Grid size: the engines' lookup tables grow with the number of cells (not its square) and
:func:`table_bytes` bounds what they measure, sizes up to :data:`MAX_SIZE` work and give the
rules' exact outcomes, larger ones are refused up front with the memory they would need."""

from __future__ import annotations

import tracemalloc
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest

from empathy_zoo import coexistence_v0, sharing_v0
from empathy_zoo.actions import NUM_ACTIONS
from empathy_zoo.engine.base import MAX_SIZE, table_bytes
from empathy_zoo.engine.coexistence import harm_outcome
from empathy_zoo.environments import ENGINES
from empathy_zoo.grid import MOVES, window_indices
from empathy_zoo.vector import VectorEnv

TABLE_BYTES_SLACK = 3
""":func:`table_bytes` is at most this many times the bytes of the arrays of the engine that needs
the most (an upper bound, not a guess from far above)."""


def held_arrays(value: Any, seen: set[int]) -> Iterator[np.ndarray]:
    """Every numpy array ``value`` holds (an engine: its tables and the state of its environments),
    through its attributes, containers, the suite's own objects and arrays' bound methods, each once."""
    if id(value) in seen:
        return
    seen.add(id(value))
    if isinstance(value, np.ndarray):
        yield value
    elif isinstance(value, (tuple, list)):
        for item in value:
            yield from held_arrays(item, seen)
    elif isinstance(value, dict):
        for item in value.values():
            yield from held_arrays(item, seen)
    elif type(value).__module__.startswith("empathy_zoo"):
        yield from held_arrays(vars(value), seen)
    elif isinstance(getattr(value, "__self__", None), np.ndarray):  # (a lookup kept as ``table.take``)
        yield from held_arrays(value.__self__, seen)


def used_engine(engine_class, size: int, view: int):
    """An engine of one environment after a reset and each kind of observation (tables built on
    first use are built)."""
    engine = engine_class(1, size=size, view=view)
    engine.reset(seeds=[0])
    engine.observe(0)
    engine.observe_swapped(0, 1)
    engine.in_view(0, 1)
    return engine


@pytest.mark.parametrize("size, view", [(7, 5), (31, 5), (61, 15), (101, 3)])
def test_table_bytes_is_a_close_upper_bound_of_the_arrays_an_engine_holds(size, view):
    held = {name: sum(array.nbytes for array in held_arrays(used_engine(ENGINES[name], size, view), set())) for name in ENGINES}
    for name, nbytes in held.items():
        assert nbytes <= table_bytes(size, view), (name, nbytes)
    assert table_bytes(size, view) <= TABLE_BYTES_SLACK * max(held.values()), held


def construction_peak(engine_class, size: int, view: int) -> int:
    """Most memory (``tracemalloc``) taken while an engine is built and first observed."""
    tracemalloc.start()
    try:
        used_engine(engine_class, size, view)
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


@pytest.mark.parametrize("name", sorted(ENGINES))
def test_building_an_engine_takes_memory_in_proportion_to_its_cells(name):
    for size, view in ((31, 5), (61, 5), (61, 15)):
        peak = construction_peak(ENGINES[name], size, view)
        assert peak <= table_bytes(size, view), (size, view, peak)


@pytest.mark.parametrize("module", [coexistence_v0, sharing_v0], ids=["coexistence", "sharing"])
def test_a_size_beyond_the_limit_is_refused_with_the_memory_it_would_need(module):
    with pytest.raises(ValueError, match=rf"size must be at most {MAX_SIZE}, got 1001.*MB") as error:
        module.parallel_env(size=1001)
    assert "docs/limits.md" in str(error.value)
    with pytest.raises(ValueError, match=f"at most {MAX_SIZE}"):
        VectorEnv(module.__name__.rsplit(".", 1)[1], 2, size=MAX_SIZE + 1)
    assert f"at most {MAX_SIZE}" in module.__doc__  # the env's documentation states the limit


def brute_force_observation(engine, viewer: int) -> np.ndarray:
    """The window around ``viewer`` painted cell by cell, straight from the rules (Coexistence)."""
    half = engine.view // 2
    row, col = engine.pos[0, viewer]
    picture = np.zeros((engine.view, engine.view), dtype=np.float32)
    for agent in range(engine.num_agents):
        if agent != viewer and engine.present[0, agent]:
            dr, dc = (engine.pos[0, agent] - (row, col) + half) % engine.size
            if dr < engine.view and dc < engine.view:
                picture[dr, dc] = -1.0
    picture[half, half] = 1.0
    return picture.ravel()


@pytest.mark.parametrize("size, view", [(5, 3), (8, 5), (13, 11), (40, 7), (MAX_SIZE, 5)])
def test_observations_and_harms_follow_the_rules_at_every_size(size, view):
    """Agents start two or three cells apart (anywhere, so moves wrap), then act at random."""
    env = coexistence_v0.parallel_env(size=size, view=view, max_cycles=8)
    engine = env.unwrapped.engine
    rng = np.random.default_rng(size)
    harms = 0
    for episode in range(150):
        robot = rng.integers(size, size=2)
        gap = [(2, 0), (0, 2), (-2, 0), (0, -2), (1, 1), (-1, 1), (2, 1), (1, -2)][episode % 8]
        cat = (robot + gap) % size
        observations, _ = env.reset(seed=episode, options={"positions": {"robot_0": tuple(robot), "cat_0": tuple(cat)}})
        while env.agents:
            for agent in env.agents:
                np.testing.assert_array_equal(observations[agent], brute_force_observation(engine, engine.agents.index(agent)))
            before = engine.pos[0].copy()
            actions = {agent: int(rng.integers(NUM_ACTIONS)) for agent in env.agents}
            observations, _, _, _, infos = env.step(actions)
            if len(actions) == 2:
                robot_move, cat_move = MOVES[actions["robot_0"]], MOVES[actions["cat_0"]]
                after = before[1] + cat_move - before[0] - robot_move
                expected = harm_outcome((before[1] - before[0])[None], after[None], size)[0]
                harmed = (infos["robot_0"]["harmed"], infos["cat_0"]["harmed"])
                assert harmed == [([], []), (["cat_0"], []), ([], ["robot_0"])][expected], (before, actions, harmed)
                harms += expected > 0
    assert harms > 20  # the rule was exercised, both ways


@pytest.mark.parametrize("size", [7, 21, MAX_SIZE])
def test_in_view_agrees_with_the_window(size):
    engine = ENGINES["sharing_v0"](64, size=size, view=5)
    engine.reset(seeds=list(range(64)))
    window = window_indices(size, 5)
    expected = [engine.cells[i, 1] in window[engine.cells[i, 0]] for i in range(64)]
    assert engine.in_view(0, 1).tolist() == expected
