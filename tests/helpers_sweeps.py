"""A tiny sweep file and training flags the command-line tests share (a few hundred steps)."""

from __future__ import annotations

TINY_SWEEP = """
[sweep]
seeds = 1
steps = 200
eval_interval = 200
eval_episodes = 1

[settings]
learning_starts = 32
replay_capacity = 200
hidden_size = 8

[envs.coexistence_v0]
max_cycles = 50

[[methods]]
method = "dqn"
"""
"""One run of DQN on Coexistence, 200 steps."""

TINY_TRAIN = [
    "--steps", "200", "--eval-interval", "200", "--eval-episodes", "1", "--max-cycles", "50",
    "--learning-starts", "32", "--replay-capacity", "200", "--hidden-size", "8", "--no-progress",
]
"""``train`` flags of the same run."""
