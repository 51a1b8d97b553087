"""The silver rule: Empathic DQN that empathizes only with the other's bad outcomes (the paper's
Discussion: "Do not do unto others as you would not have them do unto you ... approximated by
considering only negative rewards as objects of empathy").

Neither environment has a negative reward (a harmed cat gets 0 and leaves; the robot's own
rewards are ≥ 0), so "only negative rewards" taken literally would leave nothing to empathize
with and make the method plain DQN. The suite reads "negative" relative to the robot's own
standard instead: the other's imagined outcome counts only where it is *worse* than the robot's
own, and never pulls the robot towards states that are good for the other:

    y        = r + γ·(1 − done)·Q̂(s', argmax_a Q(s', a))                (the robot's own target)
    o        = γ·other_present·max_a Q̂(s_emp', a)                      (the golden rule's other-term)
    y_silver = β·y + (1 − β)·min(y, o)  =  y − (1 − β)·max(y − o, 0)

With β = 1 it is DQN; where the other fares at least as well as the robot (``o ≥ y``) the target
is the robot's own (Empathic DQN would raise it towards ``o``); where the other fares worse — in
Coexistence, above all when the cat is harmed and ``o`` drops to 0 — the target falls by
``(1 − β)`` times the shortfall, exactly as Empathic DQN's would. Acting is ε-greedy on ``Q_emp``
as in Empathic DQN (every run of this method trains ``Q_emp``, also at β = 1).
"""

from __future__ import annotations

import torch

from agents.empathic_dqn import EmpathicDQN, double_dqn_target, other_term

__all__ = ["SilverRuleDQN", "silver_targets"]


def silver_targets(y: torch.Tensor, other: torch.Tensor, selfishness: torch.Tensor) -> torch.Tensor:
    """``y_silver = β·y + (1 − β)·min(y, o)``, ``(K, B)``, from the robot's target ``y``, the
    other-term ``o`` (:func:`agents.empathic_dqn.other_term`) and β per run ``(K, 1)``."""
    return selfishness * y + (1.0 - selfishness) * torch.minimum(y, other)


class SilverRuleDQN(EmpathicDQN):
    """Empathic DQN whose other-term counts only where the other fares worse than the robot
    (see the module page)."""

    def targets(
        self, batch: dict[str, torch.Tensor], q_next: torch.Tensor, target_next: torch.Tensor, target_swapped: torch.Tensor
    ) -> tuple[torch.Tensor, torch.Tensor]:
        y = double_dqn_target(batch["reward"], batch["terminated"], q_next, target_next, self.config.gamma)
        other = other_term(target_swapped, batch["other_present"], self.config.gamma, self._others_rule(),
                           batch.get("others_live"))
        return y, silver_targets(y, other, self.selfishness)
