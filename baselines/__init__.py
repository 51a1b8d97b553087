"""Reward-shaped DQN baselines: a harm penalty (Coexistence) and equality scaling (Sharing).

The shaping functions are in :mod:`baselines.shaping`, the registered methods in
:mod:`baselines.methods`.
"""

from __future__ import annotations

from baselines.shaping import HARM_PENALTY, shaped_reward

__all__ = ["HARM_PENALTY", "shaped_reward"]
