"""The ``population`` partner (empathy_zoo.partner_policies.Population): one registered member per
episode, drawn with the given weights from a stream keyed by the episode's seed; its shares, its
members' moves, its state, its refusals, and a scenario file naming it (both env paths alike: tests/test_partner_policies.py)."""

from __future__ import annotations

import numpy as np
import pytest

from empathy_zoo.partner_policies import MAX_MEMBERS, Chase, KeepAway, Population
from empathy_zoo.policies import POLICIES, make_policy
from empathy_zoo.scenarios import parse_scenario_set

CONTEXT = {"step": 0, "agent": "cat_0", "size": 7, "positions": {"cat_0": (3, 3), "robot_0": (2, 3)}}
"""The robot one row above the cat: chase steps up, keep-away down."""


def test_registered_and_built_from_an_entry() -> None:
    policy = make_policy({"policy": "population", "members": ["chase", "random_walk"], "weights": [1, 3]})
    assert POLICIES["population"] is Population and isinstance(policy, Population)
    assert policy.members == ["chase", "random_walk"] and policy.weights == [1.0, 3.0] and policy.needs_state


def test_members_are_drawn_per_episode_in_their_shares_and_repeat_with_the_seed() -> None:
    population = Population(["chase", "keep_away", "stay"], weights=[1, 1, 2])
    drawn = []
    for seed in range(4_000):
        population.reset(seed)
        drawn.append(population.member)
    shares = np.bincount(drawn, minlength=3) / 4_000
    assert np.allclose(shares, [0.25, 0.25, 0.5], atol=0.03)
    again = Population(["chase", "keep_away", "stay"], weights=[1, 1, 2])
    assert [again.reset(seed) or again.member for seed in range(50)] == drawn[:50]


def test_the_member_plays_the_whole_episode() -> None:
    population = Population(["chase", "keep_away"])
    moves = {0: Chase().act(np.zeros(25), CONTEXT), 1: KeepAway().act(np.zeros(25), CONTEXT)}
    assert moves[0] != moves[1]
    for seed in range(20):
        population.reset(seed)
        assert {population.act(np.zeros(25), {**CONTEXT, "step": t}) for t in range(10)} == {moves[population.member]}


def test_an_unseeded_reset_continues_the_stream_and_the_state_resumes_it() -> None:
    population = Population(["random_walk", "chase"])
    population.reset(5)
    [population.act(np.zeros(25), CONTEXT) for _ in range(7)]
    copy = Population(["random_walk", "chase"])
    copy.load_state(population.state())
    for _ in range(5):
        population.reset(None)
        copy.reset(None)
        assert copy.member == population.member
        acted = [population.act(np.zeros(25), CONTEXT) for _ in range(20)]
        assert [copy.act(np.zeros(25), CONTEXT) for _ in range(20)] == acted


@pytest.mark.parametrize(
    "arguments, says",
    [
        ({"members": []}, "members must be a list of 1 to"),
        ({"members": "chase"}, "members must be a list of 1 to"),
        ({"members": ["chase"] * 2}, "members must differ"),
        ({"members": ["chase", "population"]}, "other than 'population'"),
        ({"members": ["os:system"]}, "registered policies"),
        ({"members": [f"m{i}" for i in range(MAX_MEMBERS + 1)]}, "members must be a list of 1 to"),
        ({"members": ["chase", "stay"], "weights": [1]}, "one per member"),
        ({"members": ["chase", "stay"], "weights": [1, 0]}, "positive finite"),
        ({"members": ["chase", "stay"], "weights": [1, float("inf")]}, "positive finite"),
        ({"members": ["chase", "stay"], "weights": [1, True]}, "positive finite"),
        ({"members": ["chase", "stay"], "weights": [1, 10**400]}, "positive finite"),
        ({"members": ["chase", "stay"], "weights": [1e308, 1e308]}, "at most 1e\\+09"),
    ],
)
def test_bad_arguments_are_refused(arguments, says) -> None:
    with pytest.raises(ValueError, match=says):
        Population(**arguments)


def test_a_bad_state_is_refused() -> None:
    population = Population(["chase", "stay"])
    population.reset(0)
    with pytest.raises(ValueError, match="'member' must be an index below 2"):
        population.load_state({**population.state(), "member": 2})
    with pytest.raises(ValueError, match="'members' must hold 2 states"):
        population.load_state({**population.state(), "members": [{}]})


def test_a_scenario_file_names_a_population_and_never_code() -> None:
    entry = {"policy": "population", "members": ["chase", "keep_away", "stay"]}
    data = {
        "scenario_set": {"env": "coexistence_v0", "description": "d"},
        "scenarios": {"mixed": {"reason": "r", "fixed": {"cat_0": entry}}},
    }
    assert parse_scenario_set(data, source="test", default_name="p").scenarios
    data["scenarios"]["mixed"]["fixed"]["cat_0"] = {"policy": "population", "members": ["chase", "os:system"]}
    with pytest.raises(ValueError, match="members"):
        parse_scenario_set(data, source="test", default_name="p")


def test_a_checkpoint_of_the_batched_path_resumes_every_environments_member() -> None:
    from empathy_zoo.policies import batched, load_policy_state, policy_state

    def fresh():
        fast = batched(Population(["random_walk", "chase", "stay"]), 3)
        fast.reset(np.arange(3), [4, 5, 6])
        return fast

    first, second = fresh(), fresh()
    steps, active = np.zeros(3, dtype=np.int64), np.ones(3, dtype=bool)
    contexts = [CONTEXT] * 3
    observations = np.zeros((3, 25), np.float32)

    def act(policy):
        if getattr(policy, "needs_context", False):
            return policy.act(observations, steps, active, contexts).tolist()
        return policy.act(observations, steps, active).tolist()

    [act(first) for _ in range(5)]
    load_policy_state(second, policy_state(first))
    assert [act(first) for _ in range(10)] == [act(second) for _ in range(10)]


def _episodes(population: Population, seed: int, episodes: int = 30, steps: int = 12) -> list[list[int]]:
    """The moves of ``episodes`` episodes, seeded once at the first, as training resets them."""
    moves = []
    for episode in range(episodes):
        population.reset(seed if episode == 0 else None)
        moves.append([population.act(np.zeros(25), {**CONTEXT, "step": step}) for step in range(steps)])
    return moves


def test_episodes_after_the_seeded_one_repeat_whichever_member_plays_first_later() -> None:
    members = ["stay", "random_walk", "slow_walk"]  # the first seeded episode's member is stay (seed 3)
    first, second = Population(members), Population(members)
    moves = _episodes(first, 3)
    assert _episodes(second, 3) == moves
    assert len({tuple(m) for m in moves}) > 2  # random members moved: not a trivially equal sequence


def test_every_members_saved_key_is_rederived_from_the_seed() -> None:
    population = Population(["stay", "random_walk", "slow_walk"])
    _episodes(population, 3, episodes=5)
    state = population.state()
    assert population.saved_key_problem(state, 3) is None
    for index in (1, 2):
        members = [dict(m) for m in state["members"]]
        members[index]["key"] = (members[index]["key"] + 1) % 2**64
        assert str(population.saved_key_problem({**state, "members": members}, 3)).startswith(f"members[{index}].key is ")
