"""The baselines as registered methods: standard DQN (:class:`agents.empathic_dqn.EmpathicDQN` at
β = 1) composed with a reward transform of :mod:`baselines.shaping`."""

from __future__ import annotations

from agents.base import Method
from agents.empathic_dqn import EmpathicDQN
from agents.settings import EmpathicDQNSettings
from baselines.reachability import RelativeReachability
from baselines.shaping import EqualityScaling, HarmPenalty, InequityAversion

BASELINE_METHODS: dict[str, Method] = {
    "dqn_harm_penalty": Method(
        name="dqn_harm_penalty", learner=EmpathicDQN, settings=EmpathicDQNSettings,
        preset={"selfishness": 1.0}, reward=HarmPenalty(),
        label=lambda s: "DQN + harm penalty (−100)",
        description="DQN trained on reward − 100 on every step the robot harms another agent",
    ),
    "dqn_equality": Method(
        name="dqn_equality", learner=EmpathicDQN, settings=EmpathicDQNSettings,
        preset={"selfishness": 1.0}, reward=EqualityScaling(),
        label=lambda s: "DQN × equality",
        description="DQN trained on reward × the episode's current equality of battery rewards",
    ),
    "dqn_inequity_aversion": Method(
        name="dqn_inequity_aversion", learner=EmpathicDQN, settings=EmpathicDQNSettings,
        preset={"selfishness": 1.0}, reward=InequityAversion(),
        label=lambda s: "DQN + inequity aversion",
        description="DQN trained on reward − 5·(other ahead) − 0.05·(self ahead), smoothed rewards (Hughes et al. 2018)",
    ),
    "dqn_relative_reachability": Method(
        name="dqn_relative_reachability", learner=EmpathicDQN, settings=EmpathicDQNSettings,
        preset={"selfishness": 1.0}, reward=RelativeReachability(),
        label=lambda s: "DQN + relative reachability",
        description="DQN trained on reward − 100·relative reachability lost against the stepwise inaction "
                    "baseline, exact on Coexistence (Krakovna et al. 2019)",
    ),
}
"""The baselines, by registry name."""

__all__ = ["BASELINE_METHODS"]
