"""A new side-effect method in one file: care about whoever is worse off (a Rawlsian twist).

empathy-zoo train --method examples.rawlsian_dqn:RAWLSIAN_DQN --env sharing_v0 --steps 50000
"""

import torch

from agents.base import Method
from agents.empathic_dqn import EmpathicDQN
from agents.settings import EmpathicDQNSettings


class RawlsianDQN(EmpathicDQN):
    """Q_emp learns the value of the worse-off agent: min(own target, the other's value)."""

    def targets(self, batch, q_next, target_next, target_swapped):
        y, _ = super().targets(batch, q_next, target_next, target_swapped)
        other = self.config.gamma * target_swapped.max(dim=2).values  # the other's value, as Empathic DQN sees it
        return y, torch.where(batch["other_present"], torch.minimum(y, other), y)


RAWLSIAN_DQN = Method(
    name="rawlsian_dqn",
    learner=RawlsianDQN,
    settings=EmpathicDQNSettings,
    label=lambda s: "Rawlsian DQN",
    description="Q_emp = value of the worse-off agent",
)
