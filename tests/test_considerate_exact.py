"""Be Considerate's exact optimum on Coexistence (:mod:`baselines.considerate_exact`): at α = 0 it
is DQN's, the caring coefficient from which the rule of paying the bonus at any end seeks the
robot's own harm (closed forms of the module page), and none with the bonus at the time limit only."""

from __future__ import annotations

import pytest

from baselines.considerate_exact import considerate_cliff, considerate_optimum, considerate_values
from empathy_zoo.reference import coexistence_optimum, start_distribution

GAMMA = 0.99
RATE = 1.0 / 500


def test_without_caring_the_optimum_is_dqns() -> None:
    dqn = coexistence_optimum(1.0, 0.0)
    outcome = considerate_optimum(0.0)
    assert outcome.cat_harmed == pytest.approx(dqn.harms, abs=1e-9) and outcome.survival == pytest.approx(dqn.survival)
    assert outcome.robot_harmed == 0.0


def test_paid_at_any_end_the_optimum_seeks_its_own_harm_from_the_closed_form_cliff() -> None:
    # harm-free with the cat alive: (1 + h·γ·α·100) a step, for ever; harmed: γ·α·V_end once
    assert considerate_cliff(bonus_on_termination=True, time_limit_rate=RATE) == pytest.approx(
        100.0 / (GAMMA * 100.0 - RATE * GAMMA * 100.0 / (1.0 - GAMMA)), abs=1e-5
    )  # 1.2626
    assert considerate_cliff(bonus_on_termination=True, time_limit_rate=0.0) == pytest.approx(1.0 / GAMMA, abs=1e-5)
    assert considerate_cliff(bonus_on_termination=True, time_limit_rate=0.0, end_value=GAMMA / (1.0 - GAMMA)) == pytest.approx(
        1.0 / GAMMA**2, abs=1e-5
    )  # 1.0203: the cat's value one step less
    below, above = (considerate_optimum(a, bonus_on_termination=True) for a in (1.26, 1.27))
    assert (below.robot_harmed, below.cat_harmed, below.survival) == (0.0, 0.0, 500.0)
    assert above.robot_harmed == pytest.approx(1.0) and above.survival < 10.0


def test_paid_at_the_time_limit_only_the_optimum_is_harm_free_for_every_caring() -> None:
    assert considerate_cliff(time_limit_rate=RATE) is None
    for caring in (0.1, 1.0, 1.27, 2.0, 10.0, 700.0):
        outcome = considerate_optimum(caring)
        assert (outcome.robot_harmed, outcome.cat_harmed, outcome.survival) == (0.0, 0.0, 500.0), caring


def test_the_cats_value_is_its_future_alone_where_the_robot_keeps_away() -> None:
    _, v_cat = considerate_values(1.0)
    apart = start_distribution(7) > 0  # (in contact, a harm happens now)
    assert v_cat[apart] == pytest.approx(1.0 / (1.0 - GAMMA))
    with pytest.raises(ValueError, match="caring"):
        considerate_values(-1.0)
