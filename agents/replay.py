"""Per-run replay memories as preallocated tensors, observations stored as one-byte codes.

Every observation value of the suite is a multiple of 1/20 in [-1, 11.75] (small integers, and
Sharing's ``inventory_encoding="authors"`` values ``(n+1)/20``), so an observation value is
stored as a uint8 code and decoded exactly by a 256-entry float32 table
(:mod:`empathy_zoo.observation_codes`, the arithmetic the engine draws them with): a sampled
observation is bit for bit the float32 observation that was added, and integers decode to
themselves. A value the code cannot hold exactly raises ``ValueError`` when added; nothing is
rounded. Each transition keeps ``others`` swapped observations and a one-byte code per other
agent of what is known of it (:attr:`StackedReplay.flags`): one, the closest other agent's, for
a learner that cares about the closest; one per other agent for a learner that aggregates them.
With one, each transition costs 3·V bytes of observations (s, s', s_emp' packed in one uint8
row), 3 bytes of flags (action, terminated, the other's code) and 4 bytes of reward: 82 bytes at
V = 25, 41 MB per run at the paper's 500,000 transitions. Packing keeps a sample to three
gathers and one table look-up.

A memory built with ``costs=True`` (a learner that prices costs when they are sampled:
:meth:`agents.empathic_dqn.EmpathicDQN.price_costs`) also keeps each transition's cost, 4 bytes of
float32 beside the reward, sampled as ``cost``; every other memory, and its checkpoint, is as
before.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import torch

from empathy_zoo.actions import NUM_ACTIONS
from empathy_zoo.document_checks import shown
from empathy_zoo.observation_codes import DECODE_TABLE, MAX_VALUE, MIN_VALUE, encode

__all__ = ["StackedReplay", "REPLAY_LAYOUT", "MAX_ABS_REWARD", "STATE_KEYS", "check_keys"]

OBS, NEXT_OBS, SWAPPED = 0, 1, 2
ACTION, TERMINATED, OTHERS = 0, 1, 2
GONE, LEFT_IN_STEP, PRESENT, UNSEEN = 0, 1, 2, 3
"""The codes of an other agent (see :attr:`StackedReplay.flags`)."""
MAX_ABS_REWARD = 1e6
"""The largest reward or cost a transition may hold, in magnitude (the suite's rewards and
penalties are a few hundred at most; beyond this a network's squared errors leave float32)."""
STATE_KEYS = frozenset({"observations", "flags", "reward", "position", "size", "layout", "cost"})
"""The keys of :meth:`StackedReplay.state_dict`."""

REPLAY_LAYOUT = 2
"""Layout of :meth:`StackedReplay.state_dict` (1, unmarked: with one other agent stored, its code
was 0 absent or terminal, 1 present, 2 unseen; 2: the codes of :attr:`StackedReplay.flags` for any
number, which a layout-1 checkpoint is converted to)."""


class StackedReplay:
    """``K`` ring buffers of ``capacity`` transitions, filled in lockstep (one row per run per add);
    each keeps the swapped observation and the code of ``others`` other agents per transition."""

    def __init__(
        self, num_runs: int, capacity: int, obs_size: int, device: torch.device, others: int = 1, costs: bool = False
    ) -> None:
        k, c = num_runs, capacity
        if others < 1:
            raise ValueError(f"others must be >= 1, got {others}")
        self.num_runs, self.capacity, self.obs_size, self.others = k, c, obs_size, others
        self.device = device
        self.observations = torch.zeros((k, c, 2 + others, obs_size), dtype=torch.uint8, device=device)
        """(s, s', s_emp'₁ … s_emp'ₒ) of every transition, as codes (see :attr:`decode_table`)."""
        self.decode_table = torch.from_numpy(DECODE_TABLE.copy()).to(device)
        """(256,) float32: the observation value of every code."""
        self.flags = torch.zeros((k, c, 2 + others), dtype=torch.uint8, device=device)
        """(action, terminated, code₁ … codeₒ) of every transition. An other agent's code: 0 it had
        left before the step, 1 it was there when the step began but is not at its end (harmed, or
        done: its term is 0), 2 it is there at the end (its term bootstraps), 3 it is there but
        unseen (out of view with in-view-only swaps: it is taken to fare as the robot does, SPEC §4)."""
        self.reward = torch.zeros((k, c), dtype=torch.float32, device=device)
        self.cost: torch.Tensor | None = torch.zeros((k, c), dtype=torch.float32, device=device) if costs else None
        """(K, C) float32: each transition's cost, priced when it is sampled (``None``: not kept)."""
        self.position = 0
        self.size = 0
        self._codes = (0, 255)
        """The smallest and largest observation code the environment can give (:meth:`check_range`)."""
        self._first_row = torch.arange(k, device=device)[:, None] * c
        self._arrays = (
            (self.observations.numpy(), self.flags.numpy(), self.reward.numpy()) if torch.device(device).type == "cpu" else None
        )
        """On a CPU: numpy views of :attr:`observations`, :attr:`flags` and :attr:`reward` (the same
        memory), through which :meth:`add` writes without a tensor round trip per step."""
        """(K, 1): where each run's buffer starts in the flattened ``(K·capacity, …)`` tensors."""

    def check_range(self, low: float, high: float) -> None:
        """Refuse, before any training, observations in ``[low, high]`` that the codes cannot hold."""
        if low < MIN_VALUE or high > MAX_VALUE:
            raise ValueError(
                f"observations range over [{low:g}, {high:g}], but the replay memory stores values in "
                f"[{MIN_VALUE:g}, {MAX_VALUE:g}] only (one-byte codes); use a smaller env (fewer batteries)"
            )
        self._codes = (int(encode(np.array([low], dtype=np.float32))[0]), int(encode(np.array([high], dtype=np.float32))[0]))

    def add(
        self,
        obs: np.ndarray,
        next_obs: np.ndarray,
        swapped: np.ndarray,
        action: np.ndarray,
        reward: np.ndarray,
        terminated: np.ndarray,
        present: np.ndarray,
        live: np.ndarray,
        unseen: np.ndarray,
        cost: np.ndarray | None = None,
    ) -> None:
        """Append ``m`` transitions per run: ``obs``, ``next_obs`` ``(K, m, V)``; ``action``,
        ``reward``, ``terminated`` ``(K, m)``; and of the ``others`` other agents kept,
        ``swapped`` ``(K, m, others, V)`` and ``present``, ``live``, ``unseen`` ``(K, m, others)``
        bool (as :class:`agents.step_batch.StepBatch` names them; coded as :attr:`flags` says);
        ``cost`` ``(K, m)`` exactly where the memory keeps costs."""
        m = action.shape[1]
        if (cost is None) != (self.cost is None):
            raise ValueError(
                "this replay memory keeps costs: give each transition's cost"
                if cost is None
                else "this replay memory keeps no costs (built without costs=True)"
            )
        expected = (*action.shape, self.others)
        shapes = [np.shape(x) for x in (present, live, unseen)]
        if swapped.shape[:3] != expected or any(shape != expected for shape in shapes):
            raise ValueError(
                f"expected swapped observations {(*expected, self.obs_size)} and present/live/unseen {expected} "
                f"for {self.others} other agent(s), got {swapped.shape} and {shapes}"
            )
        _check_bounded("reward", np.asarray(reward, dtype=np.float64))
        if cost is not None:
            _check_bounded("cost", np.asarray(cost, dtype=np.float64), low=0.0)
        rows = (np.arange(m) + self.position) % self.capacity
        packed = encode(np.concatenate([obs[:, :, None], next_obs[:, :, None], swapped], axis=2))  # raises unless exact
        codes = np.where(present, PRESENT, np.where(unseen, UNSEEN, np.where(live, LEFT_IN_STEP, GONE)))
        flags = np.concatenate([action[..., None], terminated[..., None], codes], axis=2).astype(np.uint8)
        if self._arrays is not None:
            observations, flag_array, rewards = self._arrays
            observations[:, rows] = packed
            flag_array[:, rows] = flags
            rewards[:, rows] = np.asarray(reward, dtype=np.float32)
            if cost is not None and self.cost is not None:
                self.cost.numpy()[:, rows] = np.asarray(cost, dtype=np.float32)
        else:
            self.observations[:, rows] = torch.from_numpy(packed).to(self.device)
            self.flags[:, rows] = torch.from_numpy(flags).to(self.device)
            self.reward[:, rows] = torch.from_numpy(np.asarray(reward, dtype=np.float32)).to(self.device)
            if self.cost is not None:
                self.cost[:, rows] = torch.from_numpy(np.asarray(cost, dtype=np.float32)).to(self.device)
        self.position = int((self.position + m) % self.capacity)
        self.size = min(self.size + m, self.capacity)

    def sample(self, index: torch.Tensor) -> dict[str, torch.Tensor]:
        """Transitions at ``index`` ``(K, B)`` (one row of indices per run), observations as float32
        (decoded by a look-up in :attr:`decode_table`: exactly the values that were added):
        ``obs``, ``next_obs`` ``(K, B, V)``, ``action``, ``terminated``, ``reward`` ``(K, B)``,
        ``others_swapped`` ``(K, B, others, V)`` and ``others_present``, ``others_live``,
        ``others_unseen`` ``(K, B, others)``, as they were added; and ``cost`` ``(K, B)`` where the
        memory keeps costs."""
        rows = index + self._first_row  # (index_select on flat rows: the cheapest gathers)
        k, b = rows.shape
        rows = rows.reshape(-1)
        codes = self.observations.view(k * self.capacity, -1).index_select(0, rows)
        width = 2 + self.others
        observations = self.decode_table.index_select(0, codes.view(-1).int()).view(k, b, width, self.obs_size)
        flags = self.flags.view(k * self.capacity, width).index_select(0, rows).view(k, b, width)
        others = flags[:, :, OTHERS:]  # (see flags)
        batch = {
            "obs": observations[:, :, OBS],
            "next_obs": observations[:, :, NEXT_OBS],
            "others_swapped": observations[:, :, SWAPPED:],
            "action": flags[:, :, ACTION].long(),
            "terminated": flags[:, :, TERMINATED].bool(),
            "reward": self.reward.view(-1).index_select(0, rows).view(k, b),
            "others_present": others == PRESENT,
            "others_live": others >= LEFT_IN_STEP,
            "others_unseen": others == UNSEEN,
        }
        if self.cost is not None:
            batch["cost"] = self.cost.view(-1).index_select(0, rows).view(k, b)
        return batch

    def nbytes_per_run(self) -> int:
        """Bytes of memory each run's buffer holds."""
        kept = (self.observations, self.flags, self.reward, *(() if self.cost is None else (self.cost,)))
        return sum(t.element_size() * t[0].numel() for t in kept)

    def state_dict(self) -> dict[str, torch.Tensor | int]:
        """The filled part of every buffer plus the write position (for checkpoints, written at once).

        Full buffers are the live tensors, not copies (as a torch module's ``state_dict``): a copy
        would double the replay's memory while a checkpoint is written. The filled part of buffers
        not yet full is copied (``torch.save`` of a slice would write the whole buffer)."""

        def filled(buffer: torch.Tensor) -> torch.Tensor:
            return buffer if self.size == self.capacity else buffer[:, : self.size].clone()

        state: dict[str, torch.Tensor | int] = {
            "observations": filled(self.observations),
            "flags": filled(self.flags),
            "reward": filled(self.reward),
            "position": self.position,
            "size": self.size,
            "layout": REPLAY_LAYOUT,
        }
        if self.cost is not None:
            state["cost"] = filled(self.cost)
        return state

    def load_state_dict(self, state: dict) -> None:
        """Continue from :meth:`state_dict`. A checkpoint written before the codes (int8 integer
        observations) is converted: integer ``v`` becomes code ``20·v + 20``, the same value; so
        is one of layout 1 keeping one other agent (its codes 0, 1, 2 become 0, 2, 3: the same
        facts, see :data:`REPLAY_LAYOUT`)."""
        check_keys(state, STATE_KEYS, "replay checkpoint", "a replay memory")
        size = int(state["size"])
        if self.cost is not None and "cost" not in state:
            raise ValueError(
                "replay checkpoint keeps no costs, and this memory prices each transition's cost when it is "
                "sampled: it was made by another method, or by a version that priced costs when they were "
                "stored; move it away to restart"
            )
        if self.cost is None and "cost" in state:
            raise ValueError("replay checkpoint keeps each transition's cost, and this memory keeps none (another method)")
        layout = int(state.get("layout", 1))
        if layout not in (1, REPLAY_LAYOUT):
            raise ValueError(f"replay checkpoint of layout {layout}; this version reads layouts 1 and {REPLAY_LAYOUT}")
        flags = state["flags"]
        if flags.shape[2:] != self.flags.shape[2:]:
            raise ValueError(
                f"replay checkpoint keeps {flags.shape[2] - 2} other agent(s) per transition, this memory {self.others}"
            )
        if layout == 1 and self.others == 1:
            flags = flags.clone()
            flags[:, :, OTHERS] = torch.tensor([GONE, PRESENT, UNSEEN], dtype=flags.dtype)[flags[:, :, OTHERS].long()]
        observations = state["observations"]
        if observations.dtype == torch.int8:  # the old format: the values themselves
            observations = torch.from_numpy(encode(observations.cpu().numpy()))
        elif observations.dtype != torch.uint8:
            raise ValueError(
                f"replay checkpoint holds observations of dtype {observations.dtype}; expected uint8 codes (or int8 values)"
            )
        self._check_stored(observations, flags, state["reward"], state.get("cost"))
        self.observations[:, :size] = observations
        self.flags[:, :size] = flags
        self.reward[:, :size] = state["reward"]
        if self.cost is not None:
            self.cost[:, :size] = state["cost"]
        self.position, self.size = int(state["position"]), size

    def _check_stored(self, observations: torch.Tensor, flags: torch.Tensor, reward: Any, cost: Any) -> None:
        """``ValueError`` naming the first stored value out of its range: an observation code the
        environment cannot give (:meth:`check_range`), an action, a terminated flag or an other
        agent's code that is none, a reward or cost that is no finite float32 within
        :data:`MAX_ABS_REWARD` (a cost also ≥ 0)."""
        low, high = self._codes
        wrong = (observations < low) | (observations > high)
        if bool(wrong.any()):
            code = int(observations[wrong][0])
            raise ValueError(
                f"replay checkpoint holds observation code {code} (value {float(DECODE_TABLE[code]):g}), outside this "
                f"environment's observations [{float(DECODE_TABLE[low]):g}, {float(DECODE_TABLE[high]):g}]"
            )
        if flags.dtype != torch.uint8:
            raise ValueError(f"replay checkpoint holds flags of dtype {flags.dtype}, not torch.uint8")
        for column, name, limit in ((ACTION, "action", NUM_ACTIONS - 1), (TERMINATED, "terminated flag", 1)):
            if bool((flags[:, :, column] > limit).any()):
                raise ValueError(f"replay checkpoint holds {name} {int(flags[:, :, column].max())}, not in [0, {limit}]")
        if bool((flags[:, :, OTHERS:] > UNSEEN).any()):
            code = int(flags[:, :, OTHERS:].max())
            raise ValueError(f"replay checkpoint holds other agent's code {code}, not one of {GONE}–{UNSEEN}")
        for name, values, floor in (("reward", reward, None), ("cost", cost, 0.0)):
            if values is None:
                continue
            if not isinstance(values, torch.Tensor) or values.dtype != torch.float32:
                kind = values.dtype if isinstance(values, torch.Tensor) else type(values).__name__
                raise ValueError(f"replay checkpoint holds a {name} of dtype {kind}, not torch.float32")
            _check_bounded(f"replay checkpoint's {name}", values.double().numpy(force=True), low=floor)


def check_keys(state: Mapping[Any, Any], known: frozenset[str], what: str, keeper: str) -> None:
    """``ValueError`` naming (at most four of) the keys of ``state`` not in ``known``."""
    unknown = [key for key in state if key not in known]
    if unknown:
        names = ", ".join(shown(key) for key in unknown[:4])
        raise ValueError(f"{what} holds key(s) {names} that {keeper} does not keep")


def _check_bounded(name: str, values: np.ndarray, low: float | None = None) -> None:
    """``ValueError`` unless every value is finite, within :data:`MAX_ABS_REWARD` in magnitude and
    (where ``low`` is given) at least ``low``."""
    bad = ~np.isfinite(values) | (np.abs(values) > MAX_ABS_REWARD)
    if low is not None:
        bad |= values < low
    if bad.any():
        value = float(values[bad].flat[0])
        floor = "" if low is None else f" and >= {low:g}"
        raise ValueError(f"a {name} of {value:g}: each must be finite, within ±{MAX_ABS_REWARD:g}{floor}")
