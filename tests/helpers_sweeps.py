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
    "--steps",
    "200",
    "--eval-interval",
    "200",
    "--eval-episodes",
    "1",
    "--max-cycles",
    "50",
    "--learning-starts",
    "32",
    "--replay-capacity",
    "200",
    "--hidden-size",
    "8",
    "--no-progress",
]
"""``train`` flags of the same run."""

TWO_ENV_SWEEP = """
[sweep]
seeds = 2
steps = 300
eval_interval = 150
eval_episodes = 2

[settings]
learning_starts = 32
replay_capacity = 300
hidden_size = 16
target_update_interval = 50
epsilon_decay_steps = 200

[envs.coexistence_v0]
max_cycles = 50

[envs.sharing_v0]
max_cycles = 50

[[methods]]
method = "empathic_dqn"
selfishness = 0.5

[[methods]]
method = "dqn"
"""
"""Empathic DQN (β = 0.5) and DQN on both environments, 2 seeds, 300 steps: 8 runs in 4 ensembles."""

TUNE_SWEEP = """
[sweep]
seeds = [0, 1]
steps = 300
eval_interval = 100
eval_episodes = 1

[settings]
learning_starts = 32
replay_capacity = 300
hidden_size = 8
target_update_interval = 50
epsilon_decay_steps = 200

[envs.coexistence_v0]
max_cycles = 40

[[methods]]
method = "dqn_harm_penalty"
"""
"""One 300-step experiment on reporting seeds 0 and 1 (three greedy evaluations per run): what the
`tune` tests tune."""

TUNE_PARAMS = ["--param", "penalty=float:-200:-1", "--param", "learning_rate=log:1e-4:1e-2"]
"""The search space of :data:`TUNE_SWEEP`: penalty (uniform) and learning_rate (log-uniform)."""

TINY_DQN_TRAIN = [
    "train",
    "--method",
    "dqn",
    "--eval-episodes",
    "1",
    "--hidden-size",
    "8",
    "--learning-starts",
    "50",
    "--replay-capacity",
    "100",
    "--batch-size",
    "8",
    "--epsilon-decay-steps",
    "10",
    "--no-progress",
]
"""A DQN run of a few hundred steps, without its steps and evaluation interval (each test adds them)."""
