"""Per-run replay memories as preallocated tensors, observations stored as one-byte codes.

Every observation value of the suite is a multiple of 1/20 in [-1, 11.75] (small integers, and
Sharing's ``inventory_encoding="authors"`` values ``(n+1)/20``), so an observation value is
stored as a uint8 code and decoded exactly by a 256-entry float32 table
(:mod:`empathy_zoo.observation_codes`, the arithmetic the engine draws them with): a sampled
observation is bit for bit the float32 observation that was added, and integers decode to
themselves. A value the code cannot hold exactly raises ``ValueError`` when added; nothing is
rounded. With several other agents whose values a learner aggregates, one swapped observation
and one presence flag per other agent are kept. Each transition costs 3·V bytes of observations (s, s', s_emp' packed in one uint8
row), 3 bytes of flags (action, terminated, the other's code) and 4 bytes of reward: 82 bytes at
V = 25, 41 MB per run at the paper's 500,000 transitions. Packing keeps a sample to three
gathers and one table look-up.
"""

from __future__ import annotations

import numpy as np
import torch

from empathy_zoo.observation_codes import DECODE_TABLE, MAX_VALUE, MIN_VALUE, encode

__all__ = ["StackedReplay"]

OBS, NEXT_OBS, SWAPPED_NEXT_OBS = 0, 1, 2
ACTION, TERMINATED, OTHER_PRESENT = 0, 1, 2


class StackedReplay:
    """``K`` ring buffers of ``capacity`` transitions, filled in lockstep (one row per run per add)."""

    def __init__(self, num_runs: int, capacity: int, obs_size: int, device: torch.device, others: int = 1) -> None:
        k, c = num_runs, capacity
        if others < 1:
            raise ValueError(f"others must be >= 1, got {others}")
        self.num_runs, self.capacity, self.obs_size, self.others = k, c, obs_size, others
        self.device = device
        self.observations = torch.zeros((k, c, 2 + others, obs_size), dtype=torch.uint8, device=device)
        """(s, s', s_emp') of every transition, as codes (see :attr:`decode_table`); with
        ``others`` > 1, one swapped observation per other agent (``s_emp'₁ … s_emp'ₙ``)."""
        self.decode_table = torch.from_numpy(DECODE_TABLE.copy()).to(device)
        """(256,) float32: the observation value of every code."""
        self.flags = torch.zeros((k, c, 2 + others), dtype=torch.uint8, device=device)
        """(action, terminated, other) of every transition. "other" is a code: 0 the other agent is
        absent or terminal at the end of the step (its term is 0), 1 it is present (its term
        bootstraps), 2 it is present but unseen (out of view with in-view-only swaps: no other-term
        at all, SPEC §4). With several others, one code per other agent: 0 it had left before the
        step, 1 it was there when the step began but is not at its end (harmed, or done), 2 it is
        there at the end, 3 it is there but unseen."""
        self.reward = torch.zeros((k, c), dtype=torch.float32, device=device)
        self.position = 0
        self.size = 0
        self._first_row = torch.arange(k, device=device)[:, None] * c
        """(K, 1): where each run's buffer starts in the flattened ``(K·capacity, …)`` tensors."""

    def check_range(self, low: float, high: float) -> None:
        """Refuse, before any training, observations in ``[low, high]`` that the codes cannot hold."""
        if low < MIN_VALUE or high > MAX_VALUE:
            raise ValueError(
                f"observations range over [{low:g}, {high:g}], but the replay memory stores values in "
                f"[{MIN_VALUE:g}, {MAX_VALUE:g}] only (one-byte codes); use a smaller env (fewer batteries)"
            )

    def add(
        self,
        obs: np.ndarray,
        next_obs: np.ndarray,
        swapped_next_obs: np.ndarray,
        action: np.ndarray,
        reward: np.ndarray,
        terminated: np.ndarray,
        other_present: np.ndarray,
    ) -> None:
        """Append ``m`` transitions per run: arrays ``(K, m, V)`` / ``(K, m)``; with several
        others, ``swapped_next_obs`` is ``(K, m, others, V)`` and ``other_present`` ``(K, m, others)``
        codes (see :attr:`flags`)."""
        m = action.shape[1]
        rows = (np.arange(m) + self.position) % self.capacity
        if self.others == 1:
            packed = encode(np.stack([obs, next_obs, swapped_next_obs], axis=2))  # raises unless exact
            flags = np.stack([action, terminated, other_present], axis=2).astype(np.uint8)
        else:
            expected = (*action.shape, self.others)
            if swapped_next_obs.shape[:3] != expected or other_present.shape != expected:
                raise ValueError(
                    f"expected swapped observations {(*expected, self.obs_size)} and presence {expected} "
                    f"for {self.others} other agents, got {swapped_next_obs.shape} and {other_present.shape}"
                )
            packed = encode(np.concatenate([obs[:, :, None], next_obs[:, :, None], swapped_next_obs], axis=2))
            flags = np.concatenate([action[..., None], terminated[..., None], other_present], axis=2).astype(np.uint8)
        self.observations[:, rows] = torch.from_numpy(packed).to(self.device)
        self.flags[:, rows] = torch.from_numpy(flags).to(self.device)
        self.reward[:, rows] = torch.from_numpy(np.asarray(reward, dtype=np.float32)).to(self.device)
        self.position = int((self.position + m) % self.capacity)
        self.size = min(self.size + m, self.capacity)

    def sample(self, index: torch.Tensor) -> dict[str, torch.Tensor]:
        """Transitions at ``index`` ``(K, B)`` (one row of indices per run), observations as float32
        (decoded by a look-up in :attr:`decode_table`: exactly the values that were added)."""
        rows = index + self._first_row  # (index_select on flat rows: the cheapest gathers)
        k, b = rows.shape
        rows = rows.reshape(-1)
        codes = self.observations.view(k * self.capacity, -1).index_select(0, rows)
        width = 2 + self.others
        observations = self.decode_table.index_select(0, codes.view(-1).int()).view(k, b, width, self.obs_size)
        flags = self.flags.view(k * self.capacity, width).index_select(0, rows).view(k, b, width)
        swapped = SWAPPED_NEXT_OBS if self.others == 1 else slice(SWAPPED_NEXT_OBS, None)
        present = OTHER_PRESENT if self.others == 1 else slice(OTHER_PRESENT, None)
        sample = {  # (with several others: swapped_next_obs (K, B, others, V), other_present (K, B, others))
            "obs": observations[:, :, OBS],
            "next_obs": observations[:, :, NEXT_OBS],
            "swapped_next_obs": observations[:, :, swapped],
            "action": flags[:, :, ACTION].long(),
            "terminated": flags[:, :, TERMINATED].bool(),
            "reward": self.reward.view(-1).index_select(0, rows).view(k, b),
        }
        codes = flags[:, :, present]  # (see flags)
        if self.others == 1:
            sample["other_present"], sample["other_unseen"] = codes == 1, codes == 2
        else:
            sample["other_present"], sample["others_live"], sample["other_unseen"] = codes == 2, codes >= 1, codes == 3
        return sample

    def nbytes_per_run(self) -> int:
        """Bytes of memory each run's buffer holds."""
        return sum(t.element_size() * t[0].numel() for t in (self.observations, self.flags, self.reward))

    def state_dict(self) -> dict[str, torch.Tensor | int]:
        """The filled part of every buffer plus the write position (for checkpoints, written at once).

        Full buffers are the live tensors, not copies (as a torch module's ``state_dict``): a copy
        would double the replay's memory while a checkpoint is written. The filled part of buffers
        not yet full is copied (``torch.save`` of a slice would write the whole buffer)."""

        def filled(buffer: torch.Tensor) -> torch.Tensor:
            return buffer if self.size == self.capacity else buffer[:, : self.size].clone()

        return {
            "observations": filled(self.observations),
            "flags": filled(self.flags),
            "reward": filled(self.reward),
            "position": self.position,
            "size": self.size,
        }

    def load_state_dict(self, state: dict) -> None:
        """Continue from :meth:`state_dict`. A checkpoint written before the codes (int8 integer
        observations) is converted: integer ``v`` becomes code ``20·v + 20``, the same value."""
        size = int(state["size"])
        observations = state["observations"]
        if observations.dtype == torch.int8:  # the old format: the values themselves
            observations = torch.from_numpy(encode(observations.cpu().numpy()))
        elif observations.dtype != torch.uint8:
            raise ValueError(
                f"replay checkpoint holds observations of dtype {observations.dtype}; expected uint8 codes (or int8 values)"
            )
        self.observations[:, :size] = observations
        for name in ("flags", "reward"):
            getattr(self, name)[:, :size] = state[name]
        self.position, self.size = int(state["position"]), size
