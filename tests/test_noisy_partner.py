"""The ``noisy`` partner (empathy_zoo.partner_policies.Noisy): a deterministic partner that acts at
random on a share of its steps, one counter-based draw per step; its rate, its partner's moves on
the other steps, its state, and its refusals (both env paths alike: tests/test_partner_policies.py)."""

from __future__ import annotations

import numpy as np
import pytest

from empathy_zoo.actions import Action
from empathy_zoo.builtin_policies import CounterStream
from empathy_zoo.partner_policies import Chase, Noisy
from empathy_zoo.policies import POLICIES, make_policy
from empathy_zoo.randomness import counter_uniform
from empathy_zoo.scenarios import parse_scenario_set

SIZE = 7
CONTEXT = {"step": 0, "agent": "cat_0", "size": SIZE, "positions": {"cat_0": (0, 0), "robot_0": (2, 0)}}
"""The robot two rows below the cat: chase steps down."""


def test_registered_and_built_from_an_entry() -> None:
    policy = make_policy({"policy": "noisy", "partner": "keep_away", "noise": 0.3})
    assert POLICIES["noisy"] is Noisy and isinstance(policy, Noisy)
    assert policy.partner == "keep_away" and policy.noise == 0.3 and policy.needs_state


def test_each_step_is_the_partners_move_or_the_draws_random_action() -> None:
    noisy = Noisy("chase", noise=0.25)
    noisy.reset(seed=4)
    key = CounterStream()
    key.reset(seed=4)
    actions = [noisy.act(np.zeros(25), CONTEXT) for _ in range(4_000)]
    draws = [float(counter_uniform(*key._take())[0]) for _ in range(4_000)]
    expected = [min(int(u / 0.25 * 5), 4) if u < 0.25 else int(Action.DOWN) for u in draws]
    assert actions == expected
    random_steps = np.array(draws) < 0.25
    assert 0.23 < random_steps.mean() < 0.27
    assert set(np.array(actions)[random_steps].tolist()) == set(range(5))  # every action, the partner's too


def test_noise_one_is_uniform_over_the_five_actions() -> None:
    noisy = Noisy("stay", noise=1.0)
    noisy.reset(seed=0)
    counts = np.bincount([noisy.act(np.zeros(25), CONTEXT) for _ in range(10_000)], minlength=5)
    assert (np.abs(counts / 10_000 - 0.2) < 0.02).all()


def test_a_seed_repeats_the_episode_and_the_state_resumes_it() -> None:
    first, second = Noisy("chase", 0.5), Noisy("chase", 0.5)
    first.reset(seed=9)
    second.reset(seed=9)
    assert [first.act(np.zeros(25), CONTEXT) for _ in range(30)] == [second.act(np.zeros(25), CONTEXT) for _ in range(30)]
    copy = Noisy("chase", 0.5)
    copy.load_state(first.state())
    assert [first.act(np.zeros(25), CONTEXT) for _ in range(30)] == [copy.act(np.zeros(25), CONTEXT) for _ in range(30)]
    assert Chase().act(np.zeros(25), CONTEXT) == Action.DOWN


@pytest.mark.parametrize(
    "arguments, says",
    [
        ({"noise": 0.0}, "noise must be a number in"),
        ({"noise": 1.5}, "noise must be a number in"),
        ({"noise": True}, "noise must be a number in"),
        ({"noise": 10**400}, "noise must be a number in"),
        ({"partner": "random_walk"}, "must keep nothing between steps"),
        ({"partner": "noisy"}, "other than 'noisy'"),
        ({"partner": "os:system"}, "registered policy"),
        ({"partner": 3}, "registered policy"),
    ],
)
def test_bad_arguments_are_refused(arguments, says) -> None:
    with pytest.raises(ValueError, match=says):
        Noisy(**arguments)


def test_a_scenario_file_names_it_and_never_code() -> None:
    good = {
        "scenario_set": {"env": "coexistence_v0", "description": "noisy"},
        "scenarios": {"noisy_chase": {"reason": "r", "fixed": {"cat_0": {"policy": "noisy", "partner": "chase", "noise": 0.2}}}},
    }
    assert parse_scenario_set(good, source="test", default_name="noisy").scenarios
    bad = {**good, "scenarios": {"x": {"reason": "r", "fixed": {"cat_0": {"policy": "noisy", "partner": "os:system"}}}}}
    with pytest.raises(ValueError, match="partner"):
        parse_scenario_set(bad, source="test", default_name="noisy")
