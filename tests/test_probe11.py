"""A checkpoint's replay memory and learner table are data: every stored transition is checked
against its range (observation codes within the environment's bounds, actions, flags, finite
bounded rewards and costs) and a key the learner does not keep is refused, before anything
trains or is written."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
import torch
from test_checkpoint_forgeries import _first, _set, assert_refused, checkpointed, forged  # noqa: F401

from agents.replay import MAX_ABS_REWARD, StackedReplay


def _cell(value: Any, index: tuple[int, ...]) -> Any:
    def change(tensor: torch.Tensor) -> torch.Tensor:
        tensor = tensor.clone()
        tensor[index] = value
        return tensor

    return change


@pytest.mark.parametrize(
    ("path", "value", "field"),
    [
        ("learner.replay.observations", _first(200), "observation code 200"),
        ("learner.replay.flags", _cell(7, (0, 0, 0)), "action 7"),
        ("learner.replay.flags", _cell(2, (0, 0, 1)), "terminated flag 2"),
        ("learner.replay.flags", _cell(9, (1, 3, 2)), "other agent's code 9"),
        ("learner.replay.reward", _first(1e30), "reward"),
        ("learner.replay.reward", _first(float("nan")), "reward"),
        ("learner.replay.reward", lambda t: t.to(torch.float64), "reward of dtype torch.float64"),
        ("learner.replay.flags", lambda t: t.to(torch.int64), "flags of dtype torch.int64"),
    ],
)
def test_a_replay_transition_out_of_its_range_is_refused(checkpointed, tmp_path, capsys, path, value, field):  # noqa: F811
    out, checkpoint = forged(checkpointed, tmp_path, _set(path, value))
    assert_refused(out, checkpoint, field, capsys)


@pytest.mark.parametrize(
    ("path", "key"),
    [("learner", "run_anything"), ("learner.replay", "extra_buffer")],
)
def test_a_key_the_learner_does_not_keep_is_refused(checkpointed, tmp_path, capsys, path, key):  # noqa: F811
    def add(payload: dict[str, Any]) -> None:
        table = payload
        for part in path.split("."):
            table = table[part]
        table[key] = 1

    out, checkpoint = forged(checkpointed, tmp_path, add)
    assert_refused(out, checkpoint, key, capsys)


def test_a_replay_memory_takes_back_what_it_gave() -> None:
    replay = StackedReplay(2, 8, 3, torch.device("cpu"))
    replay.check_range(-1.0, 1.0)
    rng = np.random.default_rng(0)
    obs = rng.integers(-1, 2, size=(2, 5, 3)).astype(np.float32)
    flags = np.zeros((2, 5, 1), dtype=bool)
    replay.add(
        obs, obs, obs[:, :, None], np.full((2, 5), 4), np.full((2, 5), -100.0), np.zeros((2, 5), dtype=bool), flags, flags, flags
    )
    again = StackedReplay(2, 8, 3, torch.device("cpu"))
    again.check_range(-1.0, 1.0)
    again.load_state_dict(replay.state_dict())
    assert torch.equal(again.observations, replay.observations) and torch.equal(again.reward, replay.reward)


def test_a_reward_beyond_the_bound_is_refused_when_added() -> None:
    replay = StackedReplay(1, 4, 2, torch.device("cpu"))
    obs = np.zeros((1, 1, 2), dtype=np.float32)
    flags = np.zeros((1, 1, 1), dtype=bool)
    with pytest.raises(ValueError, match="reward"):
        replay.add(
            obs,
            obs,
            obs[:, :, None],
            np.zeros((1, 1)),
            np.full((1, 1), 2 * MAX_ABS_REWARD),
            np.zeros((1, 1)),
            flags,
            flags,
            flags,
        )


def _fill(path: str, value: Any) -> Any:
    """A forgery: every number of the saved array at the dotted ``path`` set to ``value``."""

    def change(payload: dict[str, Any]) -> None:
        table = payload
        for part in path.split("."):
            table = table[part]
        table["__ndarray__"][:] = value

    return change


@pytest.mark.parametrize(
    ("path", "value", "field"),
    [
        ("vector.engine.episode_return", 12345.0, "vector.engine.episode_return"),
        ("vector.engine.episode_return", 1e300, "vector.engine.episode_return"),
        ("vector.engine.episode_battery_return", 5000.0, "vector.engine.episode_battery_return"),
        ("vector.engine.running", False, "vector.engine.running"),
    ],
)
def test_an_engine_total_beyond_its_clock_or_an_ended_episode_is_refused(checkpointed, tmp_path, capsys, path, value, field):  # noqa: F811
    out, checkpoint = forged(checkpointed, tmp_path, _fill(path, value))
    assert_refused(out, checkpoint, field, capsys)


def test_verdict_changes_shows_each_name_cut_so_its_output_stays_small() -> None:
    from leaderboard.verdict_changes import MAX_SHOWN, changes_markdown

    heading = "## " + "v" * 1_000_000
    metrics = [f"m{i}" for i in range(100)]

    def page(mark: str) -> str:
        rows = [
            f"| method | {' | '.join(metrics)} |",
            "|---" * (len(metrics) + 1) + "|",
            f"| dqn_x | {' | '.join([mark] * 100)} |",
        ]
        return "\n".join([heading, "### P(improves on DQN): greedy", *rows]) + "\n"

    shown = changes_markdown(page("▲ 0.99"), page("▼ 0.01"))
    lines = [line for line in shown.splitlines() if line.startswith("| vv")]
    assert len(lines) >= 99  # (every metric column that changed sign)
    assert all(len(line) < MAX_SHOWN + 200 for line in lines)
    assert "v" * (MAX_SHOWN - 1) + "…" in lines[0]
