"""Battery figures and equality scaling on the exact model of an environment whose layers hold what
each agent has collected (Sharing: :meth:`empathy_zoo.engine.sharing.SharingEngine.tabular_figures`).

* :func:`layer_figures`: SPEC §5's battery metrics of an episode that ends in each layer
  (``batteries``, ``other_batteries``, ``equality``), read off the engine; ``None`` for an engine
  that tabulates none.
* :func:`equality_reward`: the reward :class:`baselines.shaping.EqualityScaling` trains on,
  ``r · equality(own battery return, other's battery return)`` of the episode so far, this step
  included: the equality of the layer the step ends in. Its ``Q*`` is equality scaling's exact
  optimum (the layer holds both battery returns, so the shaped reward is a function of the step).
* :func:`battery_figures`: a row's expected battery metrics at the episode's end, from the
  distribution over the layers it ends in (:attr:`empathy_zoo.exact_solver.PolicyOutcome.end_layers`).
"""

from __future__ import annotations

import numpy as np

from empathy_zoo.environments import ENGINES
from empathy_zoo.exact_solver import PolicyOutcome, TabularModel

__all__ = ["layer_figures", "equality_reward", "battery_figures"]


def layer_figures(model: TabularModel) -> dict[str, np.ndarray] | None:
    """``{metric: (layers,)}``: the battery metrics of an episode that ends in each layer, or
    ``None`` where the engine tabulates none (see the module page)."""
    engine = ENGINES[model.env](1, **model.env_kwargs)
    figures = getattr(engine, "tabular_figures", None)
    if figures is None:
        return None
    return {name: np.asarray(value, dtype=np.float64) for name, value in figures(np.arange(model.layers)).items()}


def equality_reward(model: TabularModel) -> np.ndarray:
    """The model's shape: the robot's reward times the equality of the two battery returns of the
    layer each step ends in (``ValueError`` where the layers hold no battery returns)."""
    figures = layer_figures(model)
    if figures is None or "equality" not in figures:
        raise ValueError(f"{model.env}'s exact model holds no battery returns: equality scaling has no exact reward there")
    return model.reward * figures["equality"][model.after // (model.cells * model.cells)]


def battery_figures(result: PolicyOutcome, figures: dict[str, np.ndarray] | None) -> dict[str, float]:
    """``{metric: expected value at the episode's end}`` of one outcome (empty where ``figures`` is
    ``None``, or where the outcome holds no distribution over layers)."""
    if figures is None or result.end_layers is None:
        return {}
    ends = np.asarray(result.end_layers)
    return {name: float(ends @ value) for name, value in figures.items()}
