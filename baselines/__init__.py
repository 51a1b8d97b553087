"""Baselines: reward-shaped DQNs (a harm penalty for Coexistence, equality scaling for Sharing)
and Stable-Baselines3's algorithms, as registered methods.

The reward transforms are in :mod:`baselines.shaping`, the registered methods in
:mod:`baselines.methods` and :mod:`baselines.sb3`.
"""

from __future__ import annotations

from baselines.shaping import HARM_PENALTY, EqualityScaling, HarmPenalty

__all__ = ["HARM_PENALTY", "EqualityScaling", "HarmPenalty"]
