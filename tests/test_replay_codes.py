"""The replay memory stores observations as one-byte codes (empathy_zoo/observation_codes.py) and
gives back exactly the float32 observations that were added: integers (both environments'
default values) and Sharing's ``inventory_encoding="authors"`` values alike."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from agents.replay import StackedReplay
from empathy_zoo import sharing_v0
from empathy_zoo.engine.sharing import authors_agent_value
from empathy_zoo.observation_codes import CODE_OFFSET, DECODE_TABLE, STEPS_PER_UNIT, encode, step_value

INTEGERS = np.arange(-1, 11)
"""Every value the default encodings draw on the 7×7 grid (battery/cat −1 … 1 + 9 batteries)."""
AUTHORS = [np.float32((n + 1) / 20) for n in range(215)]
"""Every authors value the codes hold (n + 1 = 1 … 215, i.e. up to 10.75), by the SPEC formula."""


def bits(values: np.ndarray | torch.Tensor) -> np.ndarray:
    """float32 values as their bit patterns (so that comparisons are exact, -0.0 and NaN included)."""
    array = values.numpy() if isinstance(values, torch.Tensor) else np.asarray(values, dtype=np.float32)
    return array.astype(np.float32).view(np.uint32)


def test_table_is_the_k_over_20_formula_for_every_code() -> None:
    assert DECODE_TABLE.shape == (256,) and DECODE_TABLE.dtype == np.float32
    assert STEPS_PER_UNIT == 20 and CODE_OFFSET == 20
    for code in range(256):
        assert bits(DECODE_TABLE[code]) == bits(np.float32((code - 20) / 20)), code
    assert not DECODE_TABLE.flags.writeable
    assert encode(DECODE_TABLE).tolist() == list(range(256))  # every code's value encodes back to it


def test_integers_round_trip_exactly() -> None:
    values = INTEGERS.astype(np.float32)
    codes = encode(values)
    assert codes.dtype == np.uint8
    assert codes.tolist() == [20 * v + 20 for v in INTEGERS.tolist()]
    np.testing.assert_array_equal(bits(DECODE_TABLE[codes]), bits(values))
    assert DECODE_TABLE[codes].tolist() == INTEGERS.tolist()  # integers decode to themselves


def test_authors_values_round_trip_exactly_and_match_the_engine() -> None:
    values = np.array(AUTHORS, dtype=np.float32)
    np.testing.assert_array_equal(bits(authors_agent_value(np.arange(215))), bits(values))
    np.testing.assert_array_equal(bits(step_value(np.arange(1, 216))), bits(values))
    np.testing.assert_array_equal(bits(DECODE_TABLE[encode(values)]), bits(values))


@pytest.mark.parametrize("bad", [0.025, 0.51, -1.05, 11.8, 12.0, -2.0, np.nan, np.inf], ids=str)
def test_values_the_codes_cannot_hold_raise(bad: float) -> None:
    with pytest.raises(ValueError, match="cannot be stored exactly"):
        encode(np.array([0.0, bad], dtype=np.float32))


def test_a_float64_value_must_be_its_float32_code_exactly() -> None:
    encode(np.array([1.0, -1.0, 0.5]))  # exactly representable: fine
    with pytest.raises(ValueError, match="float64 0.05"):
        encode(np.array([0.05]))  # the float64 0.05 is not the float32 0.05: no silent rounding


def _transitions(rng: np.random.Generator, k: int, m: int, v: int) -> tuple[np.ndarray, ...]:
    pool = np.concatenate([INTEGERS.astype(np.float32), np.array(AUTHORS[:12], dtype=np.float32)])
    obs, nxt, swapped = (pool[rng.integers(len(pool), size=(k, m, v))] for _ in range(3))
    action = rng.integers(0, 5, (k, m))
    reward = rng.random((k, m)).astype(np.float32)
    return obs, nxt, swapped, action, reward, rng.random((k, m)) < 0.2, rng.random((k, m)) < 0.8


def test_a_sampled_batch_is_exactly_what_was_added() -> None:
    rng = np.random.default_rng(0)
    k, m, v = 3, 40, 25
    replay = StackedReplay(k, 64, v, torch.device("cpu"))
    obs, nxt, swapped, action, reward, terminated, present = _transitions(rng, k, m, v)
    for j in range(m):  # one transition per run per add, as the learner adds them
        replay.add(
            obs[:, j : j + 1],
            nxt[:, j : j + 1],
            swapped[:, j : j + 1],
            action[:, j : j + 1],
            reward[:, j : j + 1],
            terminated[:, j : j + 1],
            present[:, j : j + 1],
        )
    index = torch.from_numpy(rng.integers(0, m, (k, 32)))
    batch = replay.sample(index)
    rows = index.numpy()
    picked = np.arange(k)[:, None], rows
    for name, added in (("obs", obs), ("next_obs", nxt), ("swapped_next_obs", swapped)):
        assert batch[name].dtype == torch.float32 and batch[name].shape == (k, 32, v)
        np.testing.assert_array_equal(bits(batch[name]), bits(added[picked]), err_msg=name)
    assert torch.equal(batch["action"], torch.from_numpy(action[picked]).long())
    assert torch.equal(batch["reward"], torch.from_numpy(reward[picked]))
    assert torch.equal(batch["terminated"], torch.from_numpy(terminated[picked]))
    assert torch.equal(batch["other_present"], torch.from_numpy(present[picked]))


def test_integer_batches_equal_the_old_int8_decoding() -> None:
    """For integer observations the codes give what int8 storage and ``.float()`` gave before."""
    rng = np.random.default_rng(1)
    k, m, v = 2, 16, 25
    replay = StackedReplay(k, m, v, torch.device("cpu"))
    obs = rng.integers(-1, 11, (3, k, m, v)).astype(np.float32)
    replay.add(obs[0], obs[1], obs[2], np.zeros((k, m), int), np.zeros((k, m)), np.zeros((k, m), bool), np.ones((k, m), bool))
    index = torch.from_numpy(rng.integers(0, m, (k, 8)))
    batch = replay.sample(index)
    old = torch.from_numpy(obs.astype(np.int8))[:, torch.arange(k)[:, None], index].float()
    for part, name in enumerate(("obs", "next_obs", "swapped_next_obs")):
        np.testing.assert_array_equal(bits(batch[name]), bits(old[part]))


def test_replay_of_an_authors_env_keeps_its_observations() -> None:
    env = sharing_v0.parallel_env(inventory_encoding="authors", start="centre")
    observations, _ = env.reset(seed=3, options={"positions": {"robot_0": (1, 0)}})
    rng = np.random.default_rng(2)
    added = []
    replay = StackedReplay(1, 200, 25, torch.device("cpu"))
    for _ in range(200):
        before = observations["robot_0"]
        observations, *_ = env.step({"robot_0": int(rng.integers(5)), "human_0": int(rng.integers(5))})
        swapped = env.unwrapped.swapped_observation("robot_0", "human_0")
        added.append((before, observations["robot_0"], swapped))
        replay.add(
            before[None, None],
            observations["robot_0"][None, None],
            swapped[None, None],
            np.zeros((1, 1), int),
            np.zeros((1, 1)),
            np.zeros((1, 1), bool),
            np.ones((1, 1), bool),
        )
        if not env.agents:
            break
    assert any(0 < value < 1 for row in added for value in row[0]), "the robot should be drawn at least once"
    batch = replay.sample(torch.arange(len(added))[None])
    for part, name in enumerate(("obs", "next_obs", "swapped_next_obs")):
        np.testing.assert_array_equal(bits(batch[name][0]), bits(np.stack([row[part] for row in added])))


def test_rejected_add_leaves_the_replay_untouched() -> None:
    replay = StackedReplay(1, 4, 2, torch.device("cpu"))
    bad = np.array([[[0.5, 0.07]]], dtype=np.float32)
    with pytest.raises(ValueError, match="cannot be stored exactly"):
        replay.add(bad, bad, bad, np.zeros((1, 1)), np.zeros((1, 1)), np.zeros((1, 1), bool), np.ones((1, 1), bool))
    assert replay.size == 0 and replay.position == 0


def test_state_dict_round_trip_and_old_int8_checkpoints_convert() -> None:
    rng = np.random.default_rng(3)
    k, m, v = 2, 10, 25
    obs, nxt, swapped, action, reward, terminated, present = _transitions(rng, k, m, v)
    replay = StackedReplay(k, 16, v, torch.device("cpu"))
    replay.add(obs, nxt, swapped, action, reward, terminated, present)
    state = replay.state_dict()
    assert state["observations"].dtype == torch.uint8
    restored = StackedReplay(k, 16, v, torch.device("cpu"))
    restored.load_state_dict(state)
    index = torch.from_numpy(rng.integers(0, m, (k, 12)))
    for name, value in replay.sample(index).items():
        assert torch.equal(restored.sample(index)[name], value), name

    # a checkpoint written before the codes: the integer values themselves, as int8
    integers = rng.integers(-1, 11, (k, m, 3, v))
    legacy = {**state, "observations": torch.from_numpy(integers.astype(np.int8))}
    converted = StackedReplay(k, 16, v, torch.device("cpu"))
    converted.load_state_dict(legacy)
    batch = converted.sample(index)
    expected = torch.from_numpy(integers.astype(np.float32))[torch.arange(k)[:, None], index]
    assert torch.equal(batch["obs"], expected[:, :, 0]) and torch.equal(batch["swapped_next_obs"], expected[:, :, 2])

    with pytest.raises(ValueError, match="dtype"):
        converted.load_state_dict({**state, "observations": state["observations"].float()})


def test_training_an_env_the_codes_cannot_hold_is_refused_before_it_starts(tmp_path) -> None:
    from empathy_zoo.training import RunnerOptions, train_ensemble
    from empathy_zoo.training.spec import RunSpec

    # Sharing on 9×9 holds 16 batteries: an agent can be drawn as 17, beyond the codes' 11.75
    spec = RunSpec(
        env="sharing_v0",
        env_kwargs={"size": 9},
        steps=50,
        eval_interval=50,
        eval_episodes=1,
        settings={"learning_starts": 32, "replay_capacity": 100},
    )
    with pytest.raises(ValueError, match=r"observations range over \[-1, 17\]"):
        train_ensemble([spec], tmp_path, RunnerOptions(progress=False))
    assert not list(tmp_path.rglob("*.json"))
