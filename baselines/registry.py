"""Every learning method by name, in one table: the runner, the command line, sweep files and the
result-file checks look them up here. It sits above every method (Empathic DQN and DQN from
:mod:`agents`, the baselines of this package), so :mod:`agents` never imports :mod:`baselines`.

Adding a method = one file with a :class:`~agents.base.Learner` (or a preset of an existing one)
plus one entry below; or name it ``"package.module:NAME"`` where ``NAME`` is a ``Method``.
"""

from __future__ import annotations

from agents.base import Method
from agents.empathic_dqn import EmpathicDQN
from agents.settings import EmpathicDQNSettings
from baselines.methods import BASELINE_METHODS
from baselines.sb3 import SB3_METHODS
from baselines.sb3_transforms import SB3_REFUSED, SB3_TRANSFORM_METHODS
from baselines.silver_rule import SilverRuleDQN
from empathy_zoo.import_names import resolve_name

__all__ = ["METHODS", "get_method"]

METHODS: dict[str, Method] = {
    "empathic_dqn": Method(
        name="empathic_dqn",
        learner=EmpathicDQN,
        settings=EmpathicDQNSettings,
        family="empathic_dqn",
        target="golden",
        dqn_reference=True,
        label=lambda s: f"Empathic DQN (β={s.selfishness:g})",
        description="Empathic DQN: acts on Q_emp, trained on β·own target + (1−β)·the other's swapped value",
    ),
    "dqn": Method(
        name="dqn",
        learner=EmpathicDQN,
        settings=EmpathicDQNSettings,
        preset={"selfishness": 1.0},
        family="dqn",
        target="golden",
        dqn_reference=True,
        label=lambda s: "DQN",
        description="Double DQN (Empathic DQN at β = 1)",
    ),
    "empathic_dqn_in_view": Method(
        name="empathic_dqn_in_view",
        learner=EmpathicDQN,
        settings=EmpathicDQNSettings,
        in_view_only=True,
        family="empathic_dqn",
        target="golden",
        label=lambda s: f"Empathic DQN in view (β={s.selfishness:g})",
        description="Empathic DQN that swaps only with an agent inside its window (no omniscience; "
        "the paper's future work); an unseen other fares as the robot does: y_emp = y − (1−β)·r",
    ),
    "empathic_dqn_silver": Method(
        name="empathic_dqn_silver",
        learner=SilverRuleDQN,
        settings=EmpathicDQNSettings,
        family="empathic_dqn",
        target="silver",
        label=lambda s: f"Empathic DQN, silver rule (β={s.selfishness:g})",
        description="Empathic DQN that counts the other's future only where it falls below the robot's own "
        "continuation (the paper's silver rule: empathy with bad outcomes only)",
    ),
    **BASELINE_METHODS,
    **SB3_METHODS,
    **SB3_TRANSFORM_METHODS,
}
"""Registered methods."""


def get_method(name: str) -> Method:
    """The method registered as ``name``, or a ``package.module:NAME`` ``Method`` object; a
    composition that cannot run (``sb3_dqn_lagrangian``) raises ``ValueError`` saying why."""
    if name in SB3_REFUSED:
        raise ValueError(SB3_REFUSED[name])
    method = resolve_name(name, METHODS, "method")
    if not isinstance(method, Method):
        raise ValueError(f"{name!r} is not an agents.base.Method")
    return method
