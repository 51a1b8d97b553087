"""A refused call changes nothing: every face validates its input before any state moves (the
fixed agents' random streams, the engine, the AEC bookkeeping), and the next valid call gives
exactly what it would have given without the refused one. What is refused, and with which
message, is tests/test_bad_input.py."""

from __future__ import annotations

import numpy as np
import pytest
from helpers_envs import env_state, same
from helpers_policies import Wanderer

from empathy_zoo import EmpathyWrapper, FixedAgents, coexistence_v0, sharing_v0
from empathy_zoo.gym_adapter import make_single_agent_env
from empathy_zoo.vector import VectorEnv

ROBOT, CAT = "robot_0", "cat_0"
BAD_ACTIONS = [7, -1, 2.5, "a", None, np.float32(1.0)]


def fixed_coexistence():
    return FixedAgents(coexistence_v0.parallel_env(), {CAT: "random_walk"})


@pytest.mark.parametrize("bad", BAD_ACTIONS, ids=repr)
@pytest.mark.parametrize("wrap", [False, True], ids=["fixed", "empathy(fixed)"])
def test_fixed_agents_reject_a_bad_action_before_the_fixed_agents_act(bad, wrap):
    env = EmpathyWrapper(fixed_coexistence()) if wrap else fixed_coexistence()
    env.reset(seed=3)
    env.step({ROBOT: 1})
    before = env_state(env)
    with pytest.raises(ValueError, match=ROBOT):
        env.step({ROBOT: bad})
    assert same(env_state(env), before)


@pytest.mark.parametrize(
    "actions, message",
    [({}, "no action given"), ({"dog_0": 1, ROBOT: 1}, "unknown agent"), ({ROBOT: 1, CAT: 1}, "fixed agent"), ([1], "dict")],
)
def test_fixed_agents_reject_bad_action_dicts_before_the_fixed_agents_act(actions, message):
    env = fixed_coexistence()
    env.reset(seed=3)
    before = env_state(env)
    with pytest.raises(ValueError, match=message):
        env.step(actions)
    assert same(env_state(env), before)


FACES = {
    "parallel": (lambda: coexistence_v0.parallel_env(), CAT),
    "fixed": (fixed_coexistence, CAT),
    "empathy(fixed) sharing": (lambda: EmpathyWrapper(FixedAgents(sharing_v0.parallel_env(), {"human_0": "patrol"})), "human_0"),
    "gymnasium sharing": (lambda: make_single_agent_env("sharing_v0"), "human_0"),
}


def bad_options(other):
    options = [
        {"positions": {ROBOT: (9, 9)}},
        {"positions": {"dog_0": (0, 0)}},
        {"positions": {ROBOT: (0, 0), other: (0, 0)}},
        {"positions": {ROBOT: (float("inf"), 0)}},
        {"positions": {ROBOT: (float("nan"), 0)}},
        {"positions": []},
        "positions",
    ]
    return options + (
        [{"batteries": []}, {"batteries": [(0, 0), (0, 0)]}, {"batteries": [(0, 0)], "positions": {ROBOT: (0, 0)}}]
        if other == "human_0"
        else []
    )


@pytest.mark.parametrize("face", sorted(FACES))
def test_a_failed_reset_mid_episode_leaves_the_episode_as_it_was(face):
    make, other = FACES[face]
    env = make()
    env.reset(seed=5)
    for options in bad_options(other):
        before = env_state(env)
        with pytest.raises(ValueError):
            env.reset(seed=6, options=options)
        assert same(env_state(env), before), options


def test_a_failed_reset_keeps_fixed_agents_and_their_env_in_step():
    env = fixed_coexistence()
    twin = fixed_coexistence()
    for e in (env, twin):
        e.reset(seed=1)
    with pytest.raises(ValueError):
        env.reset(seed=2, options={"positions": {"dog_0": (0, 0)}})
    assert env.agents == [ROBOT] and env.env.agents == [ROBOT, CAT]
    for action in [0, 1, 2, 3, 4] * 4:
        if not twin.agents:
            break
        assert same(env.step({ROBOT: action}), twin.step({ROBOT: action}))


def test_the_aec_face_rejects_an_invalid_action_at_once_and_goes_on():
    env, twin = coexistence_v0.env(), coexistence_v0.env()
    for e in (env, twin):
        e.reset(seed=4)
    before = env_state(env)
    with pytest.raises(ValueError, match="robot_0"):
        env.step(9)  # the first agent's action: refused now, not when the last agent acts
    assert same(env_state(env), before)
    for action in [1, 3, 0, 2, 4, 1] * 5:
        if not twin.agents:
            break
        if twin.terminations[twin.agent_selection] or twin.truncations[twin.agent_selection]:
            action = None
        env.step(action)
        twin.step(action)
        assert same(env.last(), twin.last())


def test_the_aec_face_refuses_an_action_for_an_agent_that_is_done():
    env = coexistence_v0.env()
    env.reset(seed=0, options={"positions": {ROBOT: (2, 3), CAT: (4, 3)}})
    env.step(1)  # the robot moves down onto the cat's upper neighbour
    env.step(4)
    assert env.terminations[CAT] and env.agent_selection == CAT
    before = env_state(env)
    with pytest.raises(ValueError, match=f"{CAT} is done.*step\\(None\\)"):
        env.step(4)
    assert same(env_state(env), before)
    env.step(None)


@pytest.mark.parametrize("bad", [np.full((3, 1), 7), np.full((3, 1), 2.0), np.full((3, 1), -1)], ids=["7", "2.0", "-1"])
def test_the_vector_env_rejects_bad_actions_before_the_fixed_agents_act(bad):
    vector = VectorEnv("coexistence_v0", 3, fixed={CAT: "random_walk"})
    vector.reset(seed=0)
    vector.step(np.ones((3, 1), dtype=np.int64))
    before = env_state(vector)
    with pytest.raises(ValueError):
        vector.step(bad)
    assert same(env_state(vector), before)


# ------------------------------------------------------------------ several fixed agents, one invalid action
class RefusesWhileBroken:
    """Stays, or chooses 9 (no action) while the class attribute ``broken`` is set (a class
    attribute, so the vector env's per-environment copies see it too)."""

    broken = False
    stateless = True

    def reset(self, seed: int | None = None) -> None:
        pass

    def act(self, observation: np.ndarray, info: dict) -> int:
        return 9 if type(self).broken else 4


class KeepsItsGenerator(Wanderer):
    """:class:`helpers_policies.Wanderer` whose ``state()`` holds the generator object itself (no
    plain data: a checkpoint refuses it, a run without checkpoints takes it)."""

    def state(self) -> dict:
        return {"rng": self.rng, "memory": list(self.memory)}

    def load_state(self, state: dict) -> None:
        self.rng, self.memory = state["rng"], list(state["memory"])


FIRST_POLICIES = {
    "random_walk": "random_walk",  # a batched counter stream
    "wanderer": "helpers_policies:Wanderer",  # a generator, saved by state()
    "wanderer_without_state": "helpers_policies:WandererWithoutState",  # no state(): copied
    "keeps_its_generator": "test_refused_calls_change_nothing:KeepsItsGenerator",  # a state that is no plain data
}
"""The policies of the fixed agents that act before the one whose action is refused."""


def several_fixed(first: str, cats: int) -> dict:
    return {**{f"cat_{i}": FIRST_POLICIES[first] for i in range(cats - 1)}, f"cat_{cats - 1}": RefusesWhileBroken()}


@pytest.mark.parametrize("cats", [2, 3])
@pytest.mark.parametrize("first", sorted(FIRST_POLICIES))
def test_fixed_agents_refusing_one_fixed_policys_action_leave_the_others_streams_as_they_were(first, cats, monkeypatch):
    def make():
        return FixedAgents(coexistence_v0.parallel_env(num_cats=cats), several_fixed(first, cats))

    env, twin = make(), make()
    for e in (env, twin):
        e.reset(seed=3)
        e.step({ROBOT: 1})
    before = env_state(env)
    with monkeypatch.context() as patch:
        patch.setattr(RefusesWhileBroken, "broken", True)
        with pytest.raises(ValueError, match=f"cat_{cats - 1} chose an invalid action"):
            env.step({ROBOT: 2})
    assert same(env_state(env), before)
    for action in [2, 0, 3, 1, 4] * 6:
        if not twin.agents:
            break
        assert same(env.step({ROBOT: action}), twin.step({ROBOT: action}))


@pytest.mark.parametrize("cats", [2, 3])
@pytest.mark.parametrize("first", sorted(FIRST_POLICIES))
def test_the_vector_env_refusing_one_fixed_policys_action_leaves_the_others_streams_as_they_were(first, cats, monkeypatch):
    def make():
        vector = VectorEnv("coexistence_v0", 3, fixed=several_fixed(first, cats), num_cats=cats)
        vector.reset(seed=5)
        vector.step(np.ones((3, 1), dtype=np.int64))
        return vector

    vector, twin = make(), make()
    with monkeypatch.context() as patch:
        patch.setattr(RefusesWhileBroken, "broken", True)
        with pytest.raises(ValueError, match=f"cat_{cats - 1} .*invalid action|invalid action 9 for cat_{cats - 1}"):
            vector.step(np.full((3, 1), 2, dtype=np.int64))
    rng = np.random.default_rng(0)
    for _ in range(40):
        actions = rng.integers(5, size=(3, 1))
        assert same(vector.step(actions).observations, twin.step(actions).observations)


class BatchedFloats:
    """A batched policy whose actions are floats (2.0): refused, never truncated to 2."""

    needs_observation = False
    stateless = True

    def reset(self, env_ids: np.ndarray, seeds: list) -> None:
        pass

    def act(self, observations: np.ndarray | None, steps: np.ndarray, active: np.ndarray) -> np.ndarray:
        return np.full(len(active), 2.0)


class FloatsWhenBatched(RefusesWhileBroken):
    def batched(self, num_envs: int) -> BatchedFloats:
        return BatchedFloats()


def test_the_vector_env_refuses_a_batched_policys_float_actions_and_changes_nothing():
    vector = VectorEnv("coexistence_v0", 3, fixed={"cat_0": "random_walk", "cat_1": FloatsWhenBatched()}, num_cats=2)
    vector.reset(seed=0)
    before = env_state(vector)
    with pytest.raises(ValueError, match=r"cat_1 chose an invalid action.*integers"):
        vector.step(np.ones((3, 1), dtype=np.int64))
    assert same(env_state(vector), before)
