"""The replay memory stores observations as one-byte codes (empathy_zoo/observation_codes.py) and
gives back exactly the float32 observations that were added: integers (both environments'
default values) and Sharing's ``inventory_encoding="authors"`` values alike."""

from __future__ import annotations

import re

import numpy as np
import pytest
import torch

from agents.replay import REPLAY_LAYOUT, StackedReplay
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
    with pytest.raises(ValueError, match=re.escape("float64 0.05")):
        encode(np.array([0.05]))  # the float64 0.05 is not the float32 0.05: no silent rounding


def _transitions(rng: np.random.Generator, k: int, m: int, v: int, others: int = 1) -> tuple[np.ndarray, ...]:
    """``m`` random transitions per run: ``(obs, next_obs, swapped, action, reward, terminated,
    present, live, unseen)``, with ``others`` other agents (present and unseen ones live)."""
    pool = np.concatenate([INTEGERS.astype(np.float32), np.array(AUTHORS[:12], dtype=np.float32)])
    obs, nxt = (pool[rng.integers(len(pool), size=(k, m, v))] for _ in range(2))
    swapped = pool[rng.integers(len(pool), size=(k, m, others, v))]
    action = rng.integers(0, 5, (k, m))
    reward = rng.random((k, m)).astype(np.float32)
    state = rng.integers(0, 4, (k, m, others))  # each other agent gone, left in the step, present, unseen
    present, unseen, live = state == 2, state == 3, state >= 1
    return obs, nxt, swapped, action, reward, rng.random((k, m)) < 0.2, present, live, unseen


def _one_other(k: int, m: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(present, live, unseen)`` of one other agent present in every transition."""
    return np.ones((k, m, 1), bool), np.ones((k, m, 1), bool), np.zeros((k, m, 1), bool)


@pytest.mark.parametrize("others", [1, 3])
def test_a_sampled_batch_is_exactly_what_was_added(others: int) -> None:
    rng = np.random.default_rng(0)
    k, m, v = 3, 40, 25
    replay = StackedReplay(k, 64, v, torch.device("cpu"), others=others)
    added = _transitions(rng, k, m, v, others)
    obs, nxt, swapped, action, reward, terminated, present, live, unseen = added
    for j in range(m):  # one transition per run per add, as the learner adds them
        replay.add(*(x[:, j : j + 1] for x in added))
    index = torch.from_numpy(rng.integers(0, m, (k, 32)))
    batch = replay.sample(index)
    rows = index.numpy()
    picked = np.arange(k)[:, None], rows
    for name, value in (("obs", obs), ("next_obs", nxt)):
        assert batch[name].dtype == torch.float32 and batch[name].shape == (k, 32, v)
        np.testing.assert_array_equal(bits(batch[name]), bits(value[picked]), err_msg=name)
    assert batch["others_swapped"].shape == (k, 32, others, v)
    np.testing.assert_array_equal(bits(batch["others_swapped"]), bits(swapped[picked]))
    assert torch.equal(batch["action"], torch.from_numpy(action[picked]).long())
    assert torch.equal(batch["reward"], torch.from_numpy(reward[picked]))
    assert torch.equal(batch["terminated"], torch.from_numpy(terminated[picked]))
    for name, value in (("others_present", present), ("others_live", live), ("others_unseen", unseen)):
        assert batch[name].shape == (k, 32, others) and torch.equal(batch[name], torch.from_numpy(value[picked])), name


def test_integer_batches_equal_the_old_int8_decoding() -> None:
    """For integer observations the codes give what int8 storage and ``.float()`` gave before."""
    rng = np.random.default_rng(1)
    k, m, v = 2, 16, 25
    replay = StackedReplay(k, m, v, torch.device("cpu"))
    obs = rng.integers(-1, 11, (3, k, m, v)).astype(np.float32)
    nothing = np.zeros((k, m), int), np.zeros((k, m)), np.zeros((k, m), bool)  # action, reward, terminated
    replay.add(obs[0], obs[1], obs[2][:, :, None], *nothing, *_one_other(k, m))
    index = torch.from_numpy(rng.integers(0, m, (k, 8)))
    batch = replay.sample(index)
    old = torch.from_numpy(obs.astype(np.int8))[:, torch.arange(k)[:, None], index].float()
    for part, name in enumerate(("obs", "next_obs")):
        np.testing.assert_array_equal(bits(batch[name]), bits(old[part]))
    np.testing.assert_array_equal(bits(batch["others_swapped"][:, :, 0]), bits(old[2]))


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
            swapped[None, None, None],
            np.zeros((1, 1), int),
            np.zeros((1, 1)),
            np.zeros((1, 1), bool),
            *_one_other(1, 1),
        )
        if not env.agents:
            break
    assert any(0 < value < 1 for row in added for value in row[0]), "the robot should be drawn at least once"
    batch = replay.sample(torch.arange(len(added))[None])
    for part, name in enumerate(("obs", "next_obs")):
        np.testing.assert_array_equal(bits(batch[name][0]), bits(np.stack([row[part] for row in added])))
    np.testing.assert_array_equal(bits(batch["others_swapped"][0, :, 0]), bits(np.stack([row[2] for row in added])))


def test_rejected_add_leaves_the_replay_untouched() -> None:
    replay = StackedReplay(1, 4, 2, torch.device("cpu"))
    bad = np.array([[[0.5, 0.07]]], dtype=np.float32)
    with pytest.raises(ValueError, match="cannot be stored exactly"):
        replay.add(bad, bad, bad[:, :, None], np.zeros((1, 1)), np.zeros((1, 1)), np.zeros((1, 1), bool), *_one_other(1, 1))
    assert replay.size == 0 and replay.position == 0


def test_state_dict_round_trip_and_old_int8_checkpoints_convert() -> None:
    rng = np.random.default_rng(3)
    k, m, v = 2, 10, 25
    replay = StackedReplay(k, 16, v, torch.device("cpu"))
    replay.add(*_transitions(rng, k, m, v))
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
    assert torch.equal(batch["obs"], expected[:, :, 0]) and torch.equal(batch["others_swapped"][:, :, 0], expected[:, :, 2])

    with pytest.raises(ValueError, match="dtype"):
        converted.load_state_dict({**state, "observations": state["observations"].float()})


def test_a_layout_1_checkpoint_keeping_one_other_agent_means_what_it_meant() -> None:
    """Layout 1 coded the one other agent kept 0 (absent or terminal), 1 (present), 2 (unseen):
    loaded, each transition says the same of it."""
    k, m, v = 1, 3, 2
    zeros = np.zeros((k, m, v), np.float32)
    replay = StackedReplay(k, 4, v, torch.device("cpu"))
    present, unseen = np.array([[[True], [False], [False]]]), np.array([[[False], [False], [True]]])
    nothing = np.zeros((k, m), int), np.zeros((k, m)), np.zeros((k, m), bool)  # action, reward, terminated
    replay.add(zeros, zeros, zeros[:, :, None], *nothing, present, present | unseen, unseen)
    state = replay.state_dict()
    assert state["layout"] == REPLAY_LAYOUT == 2
    legacy = {name: value for name, value in state.items() if name != "layout"}
    legacy["flags"] = state["flags"].clone()
    legacy["flags"][0, :, 2] = torch.tensor([1, 0, 2], dtype=torch.uint8)
    restored = StackedReplay(k, 4, v, torch.device("cpu"))
    restored.load_state_dict(legacy)
    batch = restored.sample(torch.arange(m)[None])
    assert batch["others_present"][0, :, 0].tolist() == [True, False, False]
    assert batch["others_unseen"][0, :, 0].tolist() == [False, False, True]
    with pytest.raises(ValueError, match="keeps 1 other agent"):
        StackedReplay(k, 4, v, torch.device("cpu"), others=2).load_state_dict(state)


def test_training_an_env_the_codes_cannot_hold_is_refused_before_it_starts(tmp_path) -> None:
    from empathy_zoo.experiment.model import RunSpec
    from empathy_zoo.training import RunnerOptions, train_ensemble

    # Sharing on 9×9 holds 16 batteries: an agent can be drawn as 17, beyond the codes' 11.75
    spec = RunSpec.of(
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
