"""The baselines as registered methods: standard DQN (:class:`agents.empathic_dqn.EmpathicDQN` at
β = 1) composed with a reward transform: those of :mod:`baselines.shaping`, social value
orientation (:mod:`baselines.social_value`: McKee et al. 2020, ``r − w·|θ − θ*|`` with ``θ`` the
angle of the smoothed rewards of the learner and its closest other agent, w = 0.5 per radian,
θ* = 45°) and attainable utility preservation (:mod:`baselines.aup`: Turner, Hadfield-Menell &
Tadepalli 2020, ``r − λ·Σᵢ |Q_Rᵢ(s,a) − Q_Rᵢ(s,∅)| / Σᵢ |Q_Rᵢ(s,∅)|`` over N = 30 random
auxiliary rewards whose Q it learns beside the run, λ = 100/1.501: the paper's 1/1.501 in units of
Coexistence's task value), relative reachability with a stepwise inaction baseline without
rollouts (:mod:`baselines.reachability`: Krakovna et al. 2019's ``step_noroll``).
Be Considerate (:mod:`baselines.considerate`: Alizadeh Alamdari et al. 2022, ``r + γ·α·F(V_j(s_T))``
when the learner's episode reaches the time limit, the other's value learnt from its own rewards,
α = 1; DQN itself on Sharing) and the
Lagrangian constrained DQN (:mod:`baselines.lagrangian`: ``r − λ·harms``, ``λ ← max(0, λ + η·(Ĵ_C −
d))`` per episode, d = 0.1 harms per episode, η = 1) close the table."""

from __future__ import annotations

from collections.abc import Callable

from agents.base import Method
from agents.empathic_dqn import EmpathicDQN
from agents.settings import EmpathicDQNSettings
from baselines.aup import AttainableUtility
from baselines.considerate import SHARING_IS_DQN, Considerate
from baselines.lagrangian import Lagrangian
from baselines.reachability import RelativeReachability
from baselines.shaping import EqualityScaling, HarmPenalty, InequityAversion, NegativeRewardEmpathy
from baselines.social_value import SocialValueOrientation
from empathy_zoo.environments import ENVIRONMENT_TABLE, Environment

NO_NEGATIVE_REWARDS = "no agent's reward is ever negative here: the other's negative rewards add 0"
"""Why the literal silver rule trains as DQN on the suite's environments."""


def dqn_where(fact: Callable[[Environment], bool], why: Callable[[str], str]) -> dict[str, tuple[str, str]]:
    """``identical_to`` marks: DQN, with ``why(title)``, on every environment of the table for which
    ``fact`` of its entry holds (the environment's facts, not its name, make a method DQN there)."""
    return {name: ("dqn", why(entry.title)) for name, entry in ENVIRONMENT_TABLE.items() if fact(entry)}


BASELINE_METHODS: dict[str, Method] = {
    "dqn_harm_penalty": Method(
        name="dqn_harm_penalty",
        learner=EmpathicDQN,
        settings=EmpathicDQNSettings,
        preset={"selfishness": 1.0},
        family="dqn",
        target="golden",
        reward=HarmPenalty(),
        label=lambda s, reward: f"DQN + harm penalty ({reward.penalty:g})".replace("-", "−"),
        description="DQN trained on reward − 100 on every step the robot harms another agent",
        identical_to=dqn_where(
            lambda env: not env.can_harm, lambda title: f"nobody is harmed in {title}: the penalty is always 0"
        ),
    ),
    "dqn_equality": Method(
        name="dqn_equality",
        learner=EmpathicDQN,
        settings=EmpathicDQNSettings,
        preset={"selfishness": 1.0},
        family="dqn",
        target="golden",
        reward=EqualityScaling(),
        label=lambda s: "DQN × equality",
        description="DQN trained on reward × the episode's current equality of battery rewards",
        identical_to=dqn_where(lambda env: not env.batteries, lambda title: f"{title} has no batteries: equality is always 1"),
    ),
    "dqn_inequity_aversion": Method(
        name="dqn_inequity_aversion",
        learner=EmpathicDQN,
        settings=EmpathicDQNSettings,
        preset={"selfishness": 1.0},
        family="dqn",
        target="golden",
        reward=InequityAversion(),
        label=lambda s: "DQN + inequity aversion",
        description="DQN trained on reward − 5·(other ahead) − 0.05·(self ahead), smoothed rewards (Hughes et al. 2018)",
    ),
    "dqn_silver_literal": Method(
        name="dqn_silver_literal",
        learner=EmpathicDQN,
        settings=EmpathicDQNSettings,
        preset={"selfishness": 1.0},
        family="dqn",
        target="golden",
        reward=NegativeRewardEmpathy(),
        label=lambda s, reward: f"DQN + the other's negative rewards ({reward.care:g})",
        description="the paper's silver rule read literally: DQN trained on reward + 0.5·min(the other's reward, 0)",
        identical_to=dqn_where(lambda env: not env.negative_rewards, lambda title: NO_NEGATIVE_REWARDS),
    ),
    "dqn_social_value": Method(
        name="dqn_social_value",
        learner=EmpathicDQN,
        settings=EmpathicDQNSettings,
        preset={"selfishness": 1.0},
        family="dqn",
        target="golden",
        reward=SocialValueOrientation(),
        label=lambda s: "DQN + social value orientation (45°)",
        description="DQN trained on reward − 0.5·|reward angle − 45°| (radians), the angle of smoothed "
        "own and other rewards (McKee et al. 2020)",
    ),
    "dqn_aup": Method(
        name="dqn_aup",
        learner=EmpathicDQN,
        settings=EmpathicDQNSettings,
        preset={"selfishness": 1.0},
        family="dqn",
        target="golden",
        reward=AttainableUtility(),
        label=lambda s: "DQN + AUP",
        description="DQN trained on reward − 66.6·relative shift (Σ|ΔQ| / Σ|Q(s,∅)|) of 30 random auxiliary "
        "Q-values against the no-op, learnt beside it, from the 2,000th transition (Turner et al. 2020)",
    ),
    "dqn_relative_reachability": Method(
        name="dqn_relative_reachability",
        learner=EmpathicDQN,
        settings=EmpathicDQNSettings,
        preset={"selfishness": 1.0},
        family="dqn",
        target="golden",
        reward=RelativeReachability(),
        label=lambda s: "DQN + relative reachability (stepwise, no rollouts)",
        description="DQN trained on reward − 100·relative reachability lost against the stepwise inaction "
        "baseline without rollouts (step_noroll in Krakovna et al.'s code), none on the step the "
        "robot is harmed, exact on Coexistence, Charger, Helping and the vase task (Krakovna et al. 2019)",
    ),
    "dqn_considerate": Method(
        name="dqn_considerate",
        learner=EmpathicDQN,
        settings=EmpathicDQNSettings,
        preset={"selfishness": 1.0},
        family="dqn",
        target="golden",
        reward=Considerate(),
        label=lambda s: "DQN + Be Considerate",
        description="DQN paid 0.99·1·V_other(s_T) when its episode reaches the time limit, the other agent's future "
        "return learnt beside it from that agent's rewards (Alizadeh Alamdari et al. 2022)",
        identical_to={"sharing_v0": ("dqn", SHARING_IS_DQN)},  # (an argument about Sharing's own dynamics)
    ),
    "dqn_lagrangian": Method(
        name="dqn_lagrangian",
        learner=EmpathicDQN,
        settings=EmpathicDQNSettings,
        preset={"selfishness": 1.0},
        family="dqn",
        target="golden",
        reward=Lagrangian(),
        label=lambda s: "DQN-Lagrangian",
        description="DQN trained on reward − λ·harms, each sampled step priced at the current λ, "
        "λ ← max(0, λ + 1·(episode harms − 0.1)) at each episode's end (constrained RL: harms per episode ≤ 0.1, "
        "as OmniSafe's PPO-Lag)",
        identical_to=dqn_where(
            lambda env: not env.can_harm, lambda title: f"nobody is harmed in {title}: every cost is 0 and λ stays 0"
        ),
    ),
}
"""The baselines, by registry name."""

__all__ = ["BASELINE_METHODS"]
