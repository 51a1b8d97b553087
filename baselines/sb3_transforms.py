"""Stable-Baselines3 DQN and PPO composed with the suite's reward transforms, as registered methods.

Every baseline of :mod:`baselines.methods` that is DQN with a reward transform (``dqn_<name>``:
harm penalty, equality scaling, inequity aversion, the literal silver rule, social value
orientation, AUP, relative reachability, Be Considerate, the Lagrangian method) is registered
again on each SB3 learner, as ``sb3_ppo_<name>`` and ``sb3_dqn_<name>``: the same transform, with
the same fields (sweep keys, ``reward.<field>``, ``train`` options) and defaults, so a sweep asks
whether a method's effect survives a change of learner by naming the two methods side by side::

    [[methods]]
    method = "sb3_ppo_harm_penalty"
    penalty = -100.0

The trainer applies the transform before the learner sees the step (:class:`agents.rewards.TrainRewards`),
so SB3 stores and trains on the shaped reward, and the suite scores the runs from the
environment's events, as every method's. The transforms that keep learners of their own (AUP's
auxiliary values, Be Considerate's value of the other) or watch the engine (relative
reachability's stepwise inaction baseline) keep them in the transform and the trainer, so they run
beside any learner. One combination is refused: the Lagrangian method prices its costs when a
step is sampled (:class:`agents.rewards.PricedTransform`), which SB3 PPO does for each rollout it
trains on and SB3 DQN cannot (its replay and ``train()`` are SB3's): ``sb3_dqn_lagrangian`` is
no method, and naming it raises a ``ValueError`` saying why (:data:`SB3_REFUSED`).

A plug-in composes its own transform with :func:`with_transform`
(``MY_METHOD = with_transform(SB3_PPO, MyTransform(), name="sb3_ppo_mine", label="SB3 PPO + mine")``,
named ``package.module:MY_METHOD``).
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Mapping
from dataclasses import replace

from agents.base import Method
from agents.rewards import RewardTransform, is_priced
from baselines.methods import BASELINE_METHODS
from baselines.sb3 import PRICED_AT_SAMPLE_ON_DQN, SB3_DQN, SB3_PPO

__all__ = ["SB3_TRANSFORM_METHODS", "SB3_REFUSED", "with_transform", "from_baseline", "sb3_name"]

BASELINE_PREFIX = "dqn_"
"""The prefix of the DQN baselines' names that an SB3 composition replaces with ``sb3_<algorithm>_``."""


def sb3_name(sb3: Method, baseline: str) -> str:
    """The registry name of the SB3 method ``sb3`` with the transform of baseline ``baseline``:
    ``sb3_ppo`` and ``dqn_harm_penalty`` make ``sb3_ppo_harm_penalty``."""
    return f"{sb3.name}_{baseline.removeprefix(BASELINE_PREFIX)}"


def _sb3_label(sb3: Method) -> str:
    """``"SB3 PPO"``: the SB3 method's own label (its settings do not change it)."""
    if sb3.label is None:
        return sb3.name
    return str(sb3.label(sb3.settings(**sb3.preset)))


def with_transform(
    sb3: Method,
    reward: RewardTransform,
    *,
    name: str,
    label: str | Callable[..., str] | None = None,
    description: str = "",
    identical_to: Mapping[str, tuple[str, str]] | None = None,
) -> Method:
    """The SB3 method ``sb3`` (:data:`baselines.sb3.SB3_DQN` or :data:`~baselines.sb3.SB3_PPO`)
    trained on ``reward``'s transform of the environment's reward, registered as ``name``; its
    ``label`` (a text, or a function as :attr:`agents.base.Method.label` takes; default: the SB3
    label and the transform's name). A transform that prices its costs when sampled on SB3 DQN
    raises ``ValueError`` (:data:`baselines.sb3.PRICED_AT_SAMPLE_ON_DQN`)."""
    if sb3.learner is not SB3_DQN.learner or sb3.family != "sb3":
        raise ValueError(f"with_transform composes an SB3 method (sb3_dqn, sb3_ppo), not {sb3.name!r}")
    if sb3.reward is not None:
        raise ValueError(f"{sb3.name!r} already has a reward transform ({sb3.reward.name!r})")
    if is_priced(reward) and sb3.preset.get("algorithm") != "ppo":
        raise ValueError(f"{name}: {PRICED_AT_SAMPLE_ON_DQN}")
    if label is None:
        label = f"{_sb3_label(sb3)} + {reward.name.replace('_', ' ')}"
    if isinstance(label, str):
        text = label
        label = lambda s: text  # noqa: E731
    return replace(
        sb3,
        name=name,
        reward=reward,
        label=label,
        description=description or f"{sb3.description}, trained on the reward transform {reward.name!r}",
        identical_to=dict(identical_to or {}),
    )


def from_baseline(sb3: Method, baseline: Method) -> Method:
    """The DQN baseline ``baseline`` (``dqn_<name>``, a reward transform on DQN) with SB3's learner
    ``sb3`` in DQN's place: its transform and defaults, its label and description with ``DQN``
    replaced by the SB3 method's label, and its marks of identity (``identical_to``: on Sharing,
    nobody is harmed, so ``sb3_ppo_harm_penalty`` trains as ``sb3_ppo``)."""
    if baseline.reward is None:
        raise ValueError(f"{baseline.name!r} has no reward transform to compose with {sb3.name!r}")
    own = _sb3_label(sb3)
    description = baseline.description.replace("DQN", own, 1)
    if is_priced(baseline.reward):
        description += f"; {own} charges each rollout's costs at the run's price when it trains on it"
    return with_transform(
        sb3,
        baseline.reward,
        name=sb3_name(sb3, baseline.name),
        label=_relabelled(baseline.label, own) if baseline.label is not None else None,
        description=description,
        identical_to={
            env: (sb3.name if other == "dqn" else other, why.replace("DQN", own))
            for env, (other, why) in baseline.identical_to.items()
        },
    )


def _relabelled(label: Callable[..., str], own: str) -> Callable[..., str]:
    """``label`` with its leading ``DQN`` replaced by ``own``, taking the same arguments (a label
    of two arguments is given the run's reward transform too: :attr:`agents.base.Method.label`)."""

    def renamed(text: str) -> str:
        return own + text[len("DQN") :] if text.startswith("DQN") else f"{own}: {text}"

    positional = [
        p for p in inspect.signature(label).parameters.values() if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)
    ]
    if len(positional) >= 2:
        return lambda s, reward: renamed(label(s, reward))
    return lambda s: renamed(label(s))


def _compositions() -> tuple[dict[str, Method], dict[str, str]]:
    """Every DQN baseline with a reward transform on SB3 PPO and SB3 DQN, and the refused ones."""
    methods: dict[str, Method] = {}
    refused: dict[str, str] = {}
    for sb3 in (SB3_PPO, SB3_DQN):
        for baseline in BASELINE_METHODS.values():
            if baseline.reward is None or not baseline.name.startswith(BASELINE_PREFIX):
                continue
            name = sb3_name(sb3, baseline.name)
            if is_priced(baseline.reward) and sb3.preset.get("algorithm") != "ppo":
                refused[name] = f"{name} is not a method: {PRICED_AT_SAMPLE_ON_DQN}"
                continue
            methods[name] = from_baseline(sb3, baseline)
    return methods, refused


SB3_TRANSFORM_METHODS: dict[str, Method]
"""``sb3_ppo_<name>`` and ``sb3_dqn_<name>`` for every DQN baseline ``dqn_<name>`` with a reward
transform, by registry name (for ``baselines.registry.METHODS``)."""
SB3_REFUSED: dict[str, str]
"""``{name: why}`` of the compositions that cannot run (``sb3_dqn_lagrangian``): naming one raises
``ValueError(why)`` (``baselines.registry.get_method``)."""
SB3_TRANSFORM_METHODS, SB3_REFUSED = _compositions()
