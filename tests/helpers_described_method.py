"""A plug-in method the leaderboard has never heard of (named ``helpers_described_method:KIND_DQN``):
it declares itself a DQN-like family that learns Empathic DQN's target with a β of its own naming,
and builds result files of it from the synthetic numbers of :mod:`helpers_results`."""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

from helpers_results import SETTINGS, derive_run_id, synthetic_schema_1

from agents.base import Method
from empathy_zoo.experiment.records import RunResult
from empathy_zoo.experiment.result_reader import check_result

NAME = "helpers_described_method:KIND_DQN"
"""How a result file names the method."""


class KindLearner:
    """Stands in for a learner: nothing here trains."""


@dataclass(frozen=True)
class KindSettings:
    """This method's settings: its own names for β, γ and the ε schedule."""

    care: float = 0.0
    """How much the robot cares for the other agent: 1 − β."""
    discount: float = 0.99
    """γ."""
    explore_for: int = SETTINGS["learning_starts"]
    """Env steps at ε = 1 before ε decays."""
    decay: int = SETTINGS["epsilon_decay_steps"]
    """Env steps over which ε decays linearly from 1 to 0.01."""

    def describe(self) -> dict[str, Any]:
        """β, γ and the ε schedule, as the result file's description records them."""
        schedule = {"kind": "linear", "start": 1.0, "end": 0.01, "warmup": self.explore_for, "decay_steps": self.decay}
        return {"selfishness": 1.0 - self.care, "gamma": self.discount, "exploration": schedule}


KIND_DQN = Method(
    name="kind_dqn",
    learner=KindLearner,
    settings=KindSettings,
    family="kind_dqn",
    target="golden",
    dqn_reference=True,
    label=lambda s: f"Kind DQN (care={s.care:g})",
    description="a plug-in that learns Empathic DQN's target, its β named as care = 1 − β",
)
"""The plug-in: DQN at care 0 (β = 1), Empathic DQN's target otherwise."""


def kind_result(env: str, beta: float, seed: int, fixed: dict | None = None, **means: float) -> RunResult:
    """The record of :func:`kind_document`."""
    return RunResult.from_checked(kind_document(env, beta, seed, fixed, **means))


def kind_document(env: str, beta: float, seed: int, fixed: dict | None = None, **means: float) -> dict:
    """A schema-3 result of :data:`KIND_DQN` at β (care = 1 − β), under the run id its config gives, with the numbers
    ``helpers_results.synthetic_result`` gives Empathic DQN at that β."""
    run = synthetic_schema_1(env, "empathic_dqn", beta, seed, fixed, **means)
    settings = KindSettings(care=1.0 - beta)
    run |= {"schema": 3, "method": NAME, "method_label": KIND_DQN.display_name(settings)}
    run["config"] = {**run["config"], "settings": asdict(settings), "description": KIND_DQN.describe(settings, None)}
    return check_result(derive_run_id(run), "kind.json")
