"""Settings of Empathic DQN and its DQN baselines (SPEC §6; paper values are the defaults)."""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields
from typing import Any

from agents.phases import TrainingPhases
from empathy_zoo.schedules import linear_schedule

__all__ = ["EmpathicDQNSettings", "OTHERS_RULES", "PER_RUN_FIELDS", "RECORDED_WHEN_SET", "TIME_LIMIT_ENDS"]

OTHERS_RULES = ("closest", "mean", "min")
"""The values of :attr:`EmpathicDQNSettings.others`."""
TIME_LIMIT_ENDS = ("bootstrap", "terminal")
"""The values of :attr:`EmpathicDQNSettings.time_limit`."""


@dataclass(frozen=True)
class EmpathicDQNSettings:
    """Everything Empathic DQN (and DQN, its β = 1 case) can be told. One line per field.
    (Reward shaping is not a setting: a method composes a reward transform, see
    :class:`agents.rewards.RewardTransform`.)"""

    selfishness: float = 1.0
    """β: weight of the robot's own target in the empathic target; 1.0 is plain DQN."""
    gamma: float = 0.99
    """Discount factor γ."""
    learning_rate: float = 1e-3
    """Adam step size (both networks)."""
    batch_size: int = 32
    """Transitions per gradient step."""
    replay_capacity: int = 500_000
    """Transitions kept in each run's replay memory (oldest overwritten first)."""
    learning_starts: int = 20_000
    """Warm-up: env steps taken at ε = 1 before the first gradient step."""
    target_update_interval: int = 10_000
    """Gradient steps between copies of Q into the target network Q̂."""
    epsilon_start: float = 1.0
    """ε at the end of warm-up."""
    epsilon_end: float = 0.01
    """ε after the decay."""
    epsilon_decay_steps: int = 980_000
    """Env steps (after warm-up) over which ε falls linearly from start to end. The default
    ends the decay at env step 1,000,000 (20,000 warm-up + 980,000): the paper decays ε "over
    the first 1,000,000 steps", and SPEC §6 has it reach 0.01 by the end of that budget."""
    hidden_size: int = 128
    """Width of both hidden layers of every network (obs → hidden → hidden → 5)."""
    others: str = "closest"
    """Whose swapped value the other-term takes when the environment has several other agents
    (``num_cats`` / ``num_humans`` > 1): ``"closest"`` (the paper's rule: the closest other agent),
    ``"mean"`` (the average over every other agent: utilitarian) or ``"min"`` (the worst off:
    suffering-focused), over the others there when the step began: one harmed (or done) in the
    step counts with 0, as the single other agent does, so harming one of several is never free;
    one that had left before does not count, so the robot goes on caring for the rest. With one
    other agent the three are the same."""
    time_limit: str = "bootstrap"
    """A learner's episode cut by the time limit: its target bootstraps there (``"bootstrap"``,
    SPEC §6) or that end counts as terminal, ``y = r`` (``"terminal"``, the authors' code; the
    other-term is unchanged)."""

    def __post_init__(self) -> None:
        checks = {
            "selfishness": 0.0 <= self.selfishness <= 1.0,
            "gamma": 0.0 <= self.gamma <= 1.0,
            "learning_rate": self.learning_rate > 0,
            "batch_size": self.batch_size >= 1,
            "replay_capacity": self.replay_capacity >= self.batch_size,
            "learning_starts": self.learning_starts >= self.batch_size,
            "target_update_interval": self.target_update_interval >= 1,
            "epsilon_start": 0.0 <= self.epsilon_start <= 1.0,
            "epsilon_end": 0.0 <= self.epsilon_end <= min(1.0, self.epsilon_start),
            "epsilon_decay_steps": self.epsilon_decay_steps >= 1,
            "hidden_size": self.hidden_size >= 1,
            "others": self.others in OTHERS_RULES,
            "time_limit": self.time_limit in TIME_LIMIT_ENDS,
        }
        expectations = {
            "selfishness": "in [0, 1]",
            "gamma": "in [0, 1]",
            "learning_rate": "> 0",
            "batch_size": ">= 1",
            "replay_capacity": f">= batch_size ({self.batch_size})",
            "learning_starts": f">= batch_size ({self.batch_size})",
            "target_update_interval": ">= 1",
            "epsilon_start": "in [0, 1]",
            "epsilon_end": f"in [0, epsilon_start = {self.epsilon_start!r}] (ε decays; it never rises)",
            "epsilon_decay_steps": ">= 1",
            "hidden_size": ">= 1",
            "others": f"one of {OTHERS_RULES}",
            "time_limit": f"one of {TIME_LIMIT_ENDS}",
        }
        for name, ok in checks.items():
            if not ok:
                raise ValueError(f"{name} must be {expectations[name]}, got {getattr(self, name)!r}")

    def describe(self) -> dict[str, Any]:
        """What a result file's description records of these settings (:meth:`agents.base.Method.describe`):
        β, γ and the ε schedule as data (:func:`empathy_zoo.schedules.linear_schedule`)."""
        return {"selfishness": self.selfishness, "gamma": self.gamma, "exploration": linear_schedule(self)}

    def training_phases(self) -> TrainingPhases:
        """The warm-up (:attr:`learning_starts`) and the env step at which ε reaches
        :attr:`epsilon_end` (``learning_starts + epsilon_decay_steps``), checked against a run's
        budget before it trains (:mod:`agents.phases`)."""
        return TrainingPhases(
            learning_starts=self.learning_starts,
            learning_starts_setting="learning_starts",
            learning_starts_least=self.batch_size,
            exploration_ends=self.learning_starts + self.epsilon_decay_steps,
            exploration_rule="learning_starts + epsilon_decay_steps",
            exploration_fix=lambda steps: f"epsilon_decay_steps = {steps - self.learning_starts:,}",
        )

    def record(self) -> dict[str, Any]:
        """Every field as a result file's ``config.settings`` holds it: those of
        :data:`RECORDED_WHEN_SET` only where they differ from their default, so that adding one
        changes no earlier run's record or id."""
        record = asdict(self)
        for name, default in RECORDED_WHEN_SET.items():
            if record.get(name) == default:
                del record[name]
        return record

    def shared(self) -> tuple:
        """The settings runs must share to train in one ensemble (all but the per-run ones)."""
        return tuple(getattr(self, f.name) for f in fields(self) if f.name not in PER_RUN_FIELDS)


PER_RUN_FIELDS = frozenset({"selfishness"})
"""Settings that may differ between the runs of one ensemble."""
RECORDED_WHEN_SET: dict[str, Any] = {"time_limit": "bootstrap"}
"""Settings added after runs were shipped, and their defaults: a run records one only where it
differs (:meth:`EmpathicDQNSettings.record`); a record without one had the default."""
