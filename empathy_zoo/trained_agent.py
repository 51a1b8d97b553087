"""A trained agent read back from its agent file: greedy actions, its values, and a fixed policy.

:func:`empathy_zoo.load_agent` returns one of these (its file format: :mod:`empathy_zoo.agent_file`).
Both kinds offer the same surface:

* ``act(observation) -> int``: the greedy action for one PettingZoo observation (``(V,)``);
* ``act_batch(observations) -> (B,) int64`` for ``(B, V)`` observations;
* ``q_values(observation) -> {head: values}``: every value head the method has, by name
  (Empathic DQN: ``q`` and ``q_emp``; ``(A,)`` arrays for one observation, ``(B, A)`` for ``B``);
* ``describe() -> dict``: method, settings, env and its arguments, sizes, heads, acting head, file;
* ``reset(seed)`` and ``act(observation, context)``: a :class:`~empathy_zoo.policies.FixedPolicy`
  (``stateless = True``), so a trained robot goes wherever a fixed agent goes.

:class:`TrainedAgent` holds MLPs (``x → ReLU(x·W₁ + b₁) → … → x·Wₙ + bₙ``) and computes them with the
float32 operations, in the order, of :meth:`agents.stacked_mlp.StackedMLP.forward_exact`, which
Empathic DQN acts with: its values and greedy actions (the first largest value, as ``torch.argmax``)
are bit for bit those of the learner on the CPU, whatever the batch size or thread count (it computes
on the CPU; against a learner trained on a GPU this was not checked). :class:`SB3Agent` wraps a
Stable-Baselines3 model and acts through its own ``policy.predict(..., deterministic=True)``, as the
suite's SB3 learner does greedily.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import torch

__all__ = ["TrainedAgent", "SB3Agent", "mlp_values"]


def mlp_values(layers: Sequence[torch.Tensor], x: torch.Tensor) -> torch.Tensor:
    """``(1, B, A)`` values of one MLP on ``(1, B, V)`` inputs; ``layers`` is ``[W₁, b₁, …]`` with
    ``W: (1, in, out)`` and ``b: (1, 1, out)``, ReLU between layers. The operations of
    ``StackedMLP.forward_exact`` (products summed over each input, then the bias), so a run's values
    equal the learner's bit for bit."""
    last = len(layers) // 2 - 1
    for layer in range(last + 1):
        weight, bias = layers[2 * layer], layers[2 * layer + 1]
        x = (x.unsqueeze(-1) * weight.unsqueeze(1)).sum(dim=2) + bias
        if layer < last:
            x = torch.relu(x)
    return x


def _observations(observations: Any, obs_size: int, batched: bool) -> np.ndarray:
    """``observations`` as float32, ``(B, V)`` (``batched``) or ``(1, V)`` from one ``(V,)``; a wrong
    shape raises ``ValueError`` naming the expected one."""
    array = np.asarray(observations, dtype=np.float32)
    if batched and (array.ndim != 2 or array.shape[1] != obs_size):
        raise ValueError(f"act_batch takes observations of shape (B, {obs_size}), got {array.shape}")
    if not batched:
        if array.shape != (obs_size,):
            raise ValueError(f"act takes one observation of shape ({obs_size},), got {array.shape} (use act_batch for many)")
        array = array[None]
    return array


class TrainedAgent:
    """A trained agent whose value heads are MLPs with ReLU between layers (see the module page).

    Built by :func:`empathy_zoo.load_agent`; ``heads`` maps each head's name to its layers
    ``[W₁, b₁, …]`` (``W: (in, out)``, ``b: (out,)``, float32), ``acting`` names the head whose
    largest value is the greedy action, and ``description`` is what :meth:`describe` returns."""

    stateless = True
    """A fixed policy that keeps nothing between steps (checkpoints need no state of it)."""

    def __init__(self, heads: Mapping[str, Sequence[torch.Tensor]], acting: str, description: Mapping[str, Any]) -> None:
        if acting not in heads:
            raise ValueError(f"acting head {acting!r} is not one of the heads {sorted(heads)}")
        self._heads = {
            name: [t.reshape(1, *t.shape) if i % 2 == 0 else t.reshape(1, 1, -1) for i, t in enumerate(layers)]
            for name, layers in heads.items()
        }
        self.acting = acting
        """Name of the head the agent acts on."""
        first = self._heads[acting]
        self.obs_size = int(first[0].shape[1])
        """Length ``V`` of one observation."""
        self.num_actions = int(first[-1].shape[-1])
        """Number of actions ``A``."""
        self._description = copy.deepcopy(dict(description))

    # ------------------------------------------------------------------ acting
    def act(self, observation: Any, context: Mapping[str, Any] | None = None) -> int:
        """The greedy action for one observation ``(V,)``; ``context`` (a fixed policy's) is not used."""
        return int(self._greedy(_observations(observation, self.obs_size, batched=False))[0])

    def act_batch(self, observations: Any) -> np.ndarray:
        """``(B,)`` int64 greedy actions for ``(B, V)`` observations."""
        return self._greedy(_observations(observations, self.obs_size, batched=True))

    def q_values(self, observation: Any) -> dict[str, np.ndarray]:
        """Every head's values, by name: ``(A,)`` float32 for one observation ``(V,)``, ``(B, A)``
        for ``(B, V)`` observations."""
        one = np.ndim(observation) == 1
        x = _observations(observation, self.obs_size, batched=not one)
        values = {name: self._values(name, x) for name in self._heads}
        return {name: v[0] if one else v for name, v in values.items()}

    def reset(self, seed: int | None = None) -> None:
        """Start an episode (a trained agent keeps nothing between steps)."""

    def describe(self) -> dict[str, Any]:
        """Method, settings, env and its arguments, sizes, heads, acting head and source file."""
        return copy.deepcopy(self._description)

    def _values(self, head: str, x: np.ndarray) -> np.ndarray:
        with torch.no_grad():
            return mlp_values(self._heads[head], torch.as_tensor(x, dtype=torch.float32)[None])[0].numpy()

    def _greedy(self, x: np.ndarray) -> np.ndarray:
        with torch.no_grad():
            values = mlp_values(self._heads[self.acting], torch.as_tensor(x, dtype=torch.float32)[None])
            if not bool(torch.isfinite(values).all()):  # (weights whose products overflow float32: no greedy action)
                where = self._description.get("file", "(not from a file)")
                raise ValueError(
                    f"agent file {where}: its head {self.acting!r} gives values that are no finite numbers "
                    "(its weights overflow float32): it has no greedy action"
                )
            return values.argmax(dim=2)[0].numpy()

    def __repr__(self) -> str:
        d = self._description
        return f"TrainedAgent({d.get('method')!r} on {d.get('env')!r}, heads {sorted(self._heads)}, acting on {self.acting!r})"


class SB3Agent:
    """A trained Stable-Baselines3 model (read back with SB3's own ``load``) with the surface of
    :class:`TrainedAgent`. ``q_values`` gives DQN's ``q`` (its ``q_net``); PPO learns no Q-values
    (a policy and a state value), so its ``q_values`` raises ``ValueError`` and its heads are ``[]``."""

    stateless = True
    """A fixed policy that keeps nothing between steps."""

    def __init__(self, model: Any, heads: Sequence[str], acting: str, description: Mapping[str, Any]) -> None:
        self.model = model
        """The SB3 model."""
        self.heads = list(heads)
        """Names of its value heads (``["q"]`` for DQN, ``[]`` for PPO)."""
        self.acting = acting
        """What it acts on (``"q"`` for DQN, ``"policy"``: the most likely action, for PPO)."""
        self.obs_size = int(model.observation_space.shape[0])
        """Length ``V`` of one observation."""
        self.num_actions = int(model.action_space.n)
        """Number of actions ``A``."""
        self._description = copy.deepcopy(dict(description))

    def act(self, observation: Any, context: Mapping[str, Any] | None = None) -> int:
        """The greedy action for one observation ``(V,)``; ``context`` is not used."""
        return int(self._predict(_observations(observation, self.obs_size, batched=False))[0])

    def act_batch(self, observations: Any) -> np.ndarray:
        """``(B,)`` int64 greedy actions for ``(B, V)`` observations."""
        return self._predict(_observations(observations, self.obs_size, batched=True))

    def q_values(self, observation: Any) -> dict[str, np.ndarray]:
        """DQN's ``{"q": values}`` (``(A,)`` for one observation, ``(B, A)`` for ``B``); a model without
        Q-values (PPO) raises ``ValueError``."""
        q_net = getattr(self.model.policy, "q_net", None)
        if q_net is None:
            raise ValueError(f"SB3 {type(self.model).__name__} learns no Q-values (heads: none); act and act_batch work")
        one = np.ndim(observation) == 1
        x = _observations(observation, self.obs_size, batched=not one)
        with torch.no_grad():
            values = q_net(self.model.policy.obs_to_tensor(x)[0]).cpu().numpy()
        return {"q": values[0] if one else values}

    def reset(self, seed: int | None = None) -> None:
        """Start an episode (the agent keeps nothing between steps)."""

    def describe(self) -> dict[str, Any]:
        """Method, settings, env and its arguments, sizes, heads, acting head and source file."""
        return copy.deepcopy(self._description)

    def _predict(self, x: np.ndarray) -> np.ndarray:
        return np.asarray(self.model.policy.predict(x, deterministic=True)[0], dtype=np.int64).reshape(len(x))

    def __repr__(self) -> str:
        d = self._description
        return f"SB3Agent({d.get('method')!r} on {d.get('env')!r}, {type(self.model).__name__})"
