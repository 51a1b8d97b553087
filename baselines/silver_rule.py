"""The silver rule as a value comparison: Empathic DQN that empathizes only with the other's bad
outcomes, judged against the robot's own (the paper's Discussion: "Do not do unto others as you
would not have them do unto you ... approximated by considering only negative rewards as objects of
empathy"). The literal reading, the other's negative rewards alone, is
:class:`baselines.shaping.NegativeRewardEmpathy` (method ``dqn_silver_literal``).

Neither environment has a negative reward (a harmed cat gets 0 and leaves; the robot's own
rewards are ≥ 0), so "only negative rewards" taken literally would leave nothing to empathize
with and make the method plain DQN. The suite reads "negative" relative to the robot's own
standard instead: the other's imagined future counts only where it is *worse* than the robot's
own, and never pulls the robot towards states that are good for the other. Like is compared
with like — the other's bootstrapped value against the robot's own *continuation* (its target
without the immediate reward), both values of being in a situation at t+1:

    c        = γ·(1 − done)·Q̂(s', argmax_a Q(s', a))        (the robot's continuation; y = r + c)
    o        = γ·other_present·max_a Q̂(s_emp', a)           (Empathic DQN's other-term)
    y_silver = y − (1 − β)·max(c − o, 0)  =  β·y + (1 − β)·(r + min(c, o))

(the same as comparing the robot's whole target ``y`` with ``r + o``). With β = 1 it is DQN. Where
the other's future is at least as good as the robot's (``o ≥ c``) the target is the robot's own
``y`` (Empathic DQN would pull it towards ``o``); where it is worse — in Coexistence, when the cat
is harmed and ``o`` drops to 0 — the target falls by ``(1 − β)`` times the shortfall, as Empathic
DQN's does. And where the *robot* is harmed (``c = 0``) the other's good future does not console
it: the target stays the robot's own 0, while Empathic DQN's is ``(1 − β)·o``.

An earlier version (0.3.0) used ``β·y + (1 − β)·min(y, o)``, comparing the robot's target *with*
its immediate reward against the other's value *without* one: on every harmless step of
Coexistence ``y − o = 1``, so ``min(y, o) = o`` and the method was Empathic DQN but for the
robot's own harm. At the exact optimum of Coexistence (``empathy_zoo.reference``,
``rule="silver"``) the greedy policy equals Empathic DQN's at every β in (0, 1] — both forbid
the same harms, the robot can always avoid both, and there the two targets differ by a constant
``(1 − β)`` per harmless step — and differs at β = 0, where Empathic DQN gives up its own
survival (54 steps of 500) and the silver robot does not (500): the rules differ exactly where
the golden rule lets the other's good future pay for the robot's own harm. In learning the
targets differ wherever the learned ``o`` exceeds ``c``.

With in-view-only swaps an unseen other is taken to fare as the robot does, as in Empathic DQN
(SPEC §4): ``o = c``, so the target is the robot's own ``y``.
Acting is ε-greedy on ``Q_emp`` as in Empathic DQN (every run of this method trains ``Q_emp``,
also at β = 1).
"""

from __future__ import annotations

import torch

from agents.empathic_dqn import EmpathicDQN, continuation_value, other_term, own_continuation_where_unseen

__all__ = ["SilverRuleDQN", "silver_targets"]


def silver_targets(
    reward: torch.Tensor, continuation: torch.Tensor, other: torch.Tensor, selfishness: torch.Tensor
) -> torch.Tensor:
    """``y_silver = y − (1 − β)·max(c − o, 0)``, ``(K, B)``, from the robot's reward ``r`` and
    continuation ``c`` (``y = r + c``), the other-term ``o`` (:func:`agents.empathic_dqn.other_term`)
    and β per run ``(K, 1)``."""
    return reward + continuation - (1.0 - selfishness) * torch.clamp(continuation - other, min=0.0)


class SilverRuleDQN(EmpathicDQN):
    """Empathic DQN whose other-term counts only where the other's future is worse than the
    robot's own (see the module page)."""

    def targets(
        self, batch: dict[str, torch.Tensor], q_next: torch.Tensor, target_next: torch.Tensor, target_swapped: torch.Tensor
    ) -> tuple[torch.Tensor, torch.Tensor]:
        rule, (present, live, unseen) = self._others_rule(), self.other_inputs(batch)
        continuation = continuation_value(batch["terminated"], q_next, target_next, self.config.gamma)
        y = batch["reward"] + continuation
        other = other_term(target_swapped, present, self.config.gamma, rule, live, unseen)
        other = own_continuation_where_unseen(other, continuation, unseen, rule, live)
        return y, silver_targets(batch["reward"], continuation, other, self.selfishness)
