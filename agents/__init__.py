"""Learning methods: Empathic DQN (and DQN, its β = 1 case), behind one plug-in interface."""

from __future__ import annotations

from agents.base import Learner, Method, StepBatch
from agents.empathic_dqn import EmpathicDQN
from agents.rewards import RewardTransform
from agents.settings import EmpathicDQNSettings

__all__ = ["EmpathicDQN", "EmpathicDQNSettings", "Learner", "Method", "RewardTransform", "StepBatch"]
