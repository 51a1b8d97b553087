"""Baselines: the methods a side-effect researcher compares against, as registered methods — DQN
with a reward transform (the paper's harm penalty and equality scaling, inequity aversion, social
value orientation, attainable utility preservation, relative reachability), the silver rule
(a variant of Empathic DQN's target) and Stable-Baselines3's algorithms.

The reward transforms are in :mod:`baselines.shaping`, :mod:`baselines.social_value`,
:mod:`baselines.aup` and :mod:`baselines.reachability`; the registered methods in
:mod:`baselines.methods`, :mod:`baselines.sb3` and, with Empathic DQN's, :mod:`baselines.registry`.
"""

from __future__ import annotations

from baselines.shaping import HARM_PENALTY, EqualityScaling, HarmPenalty

__all__ = ["HARM_PENALTY", "EqualityScaling", "HarmPenalty"]
