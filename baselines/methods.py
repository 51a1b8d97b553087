"""The baselines as registered methods: standard DQN (:class:`agents.empathic_dqn.EmpathicDQN` at
β = 1) composed with a reward transform: those of :mod:`baselines.shaping`, social value
orientation (:mod:`baselines.social_value`: McKee et al. 2020, ``r − w·|θ − θ*|`` with ``θ`` the
angle of the smoothed rewards of the learner and its closest other agent, w = 0.5 per radian,
θ* = 45°) and attainable utility preservation (:mod:`baselines.aup`: Turner, Hadfield-Menell &
Tadepalli 2020, ``r − λ·(1/N)·Σᵢ |Q_Rᵢ(s,a) − Q_Rᵢ(s,∅)| / scaleᵢ`` over N = 30 random auxiliary
rewards whose Q it learns beside the run, λ = 1/1.501, scale the running mean of ``|Q_Rᵢ(s,∅)|``)."""

from __future__ import annotations

from agents.base import Method
from agents.empathic_dqn import EmpathicDQN
from agents.settings import EmpathicDQNSettings
from baselines.aup import AttainableUtility
from baselines.reachability import RelativeReachability
from baselines.shaping import EqualityScaling, HarmPenalty, InequityAversion
from baselines.social_value import SocialValueOrientation

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
    "dqn_social_value": Method(
        name="dqn_social_value", learner=EmpathicDQN, settings=EmpathicDQNSettings,
        preset={"selfishness": 1.0}, reward=SocialValueOrientation(),
        label=lambda s: "DQN + social value orientation (45°)",
        description="DQN trained on reward − 0.5·|reward angle − 45°| (radians), the angle of smoothed "
                    "own and other rewards (McKee et al. 2020)",
    ),
    "dqn_aup": Method(
        name="dqn_aup", learner=EmpathicDQN, settings=EmpathicDQNSettings,
        preset={"selfishness": 1.0}, reward=AttainableUtility(),
        label=lambda s: "DQN + AUP",
        description="DQN trained on reward − 0.67·mean relative shift of 30 random auxiliary Q-values against "
                    "the no-op, learnt beside it (Turner et al. 2020)",
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
