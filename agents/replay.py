"""Per-run replay memories as preallocated tensors, observations stored as int8.

Observations of both environments are small integers (-1 … 10), so each transition costs
3·V bytes of observations (s, s', s_emp' packed in one int8 row), 3 bytes of flags (action,
terminated, other present) and 4 bytes of reward: 82 bytes at V = 25, 41 MB per run at the
paper's 500,000 transitions. Packing keeps a sample to three gathers.
"""

from __future__ import annotations

import numpy as np
import torch

__all__ = ["StackedReplay"]

OBS, NEXT_OBS, SWAPPED_NEXT_OBS = 0, 1, 2
ACTION, TERMINATED, OTHER_PRESENT = 0, 1, 2


class StackedReplay:
    """``K`` ring buffers of ``capacity`` transitions, filled in lockstep (one row per run per add)."""

    def __init__(self, num_runs: int, capacity: int, obs_size: int, device: torch.device) -> None:
        k, c = num_runs, capacity
        self.num_runs, self.capacity, self.obs_size = k, c, obs_size
        self.device = device
        self.observations = torch.zeros((k, c, 3, obs_size), dtype=torch.int8, device=device)
        """(s, s', s_emp') of every transition."""
        self.flags = torch.zeros((k, c, 3), dtype=torch.uint8, device=device)
        """(action, terminated, other present) of every transition."""
        self.reward = torch.zeros((k, c), dtype=torch.float32, device=device)
        self.position = 0
        self.size = 0
        self._runs = torch.arange(k, device=device)[:, None]

    @staticmethod
    def _as_int8(observations: np.ndarray) -> np.ndarray:
        small = observations.astype(np.int8)
        if not np.array_equal(small, observations):
            raise ValueError("replay stores observations as int8; got values that are not small integers")
        return small

    def add(self, obs: np.ndarray, next_obs: np.ndarray, swapped_next_obs: np.ndarray, action: np.ndarray,
            reward: np.ndarray, terminated: np.ndarray, other_present: np.ndarray) -> None:
        """Append ``m`` transitions per run: arrays ``(K, m, V)`` / ``(K, m)``."""
        m = action.shape[1]
        rows = (np.arange(m) + self.position) % self.capacity
        packed = self._as_int8(np.stack([obs, next_obs, swapped_next_obs], axis=2))
        flags = np.stack([action, terminated, other_present], axis=2).astype(np.uint8)
        self.observations[:, rows] = torch.from_numpy(packed).to(self.device)
        self.flags[:, rows] = torch.from_numpy(flags).to(self.device)
        self.reward[:, rows] = torch.from_numpy(np.asarray(reward, dtype=np.float32)).to(self.device)
        self.position = int((self.position + m) % self.capacity)
        self.size = min(self.size + m, self.capacity)

    def sample(self, index: torch.Tensor) -> dict[str, torch.Tensor]:
        """Transitions at ``index`` ``(K, B)`` (one row of indices per run), observations as float32."""
        observations = self.observations[self._runs, index].float()
        flags = self.flags[self._runs, index]
        return {
            "obs": observations[:, :, OBS], "next_obs": observations[:, :, NEXT_OBS],
            "swapped_next_obs": observations[:, :, SWAPPED_NEXT_OBS],
            "action": flags[:, :, ACTION].long(), "terminated": flags[:, :, TERMINATED].bool(),
            "other_present": flags[:, :, OTHER_PRESENT].bool(), "reward": self.reward[self._runs, index],
        }

    def nbytes_per_run(self) -> int:
        """Bytes of memory each run's buffer holds."""
        return sum(t.element_size() * t[0].numel() for t in (self.observations, self.flags, self.reward))

    def state_dict(self) -> dict[str, torch.Tensor | int]:
        """The filled part of every buffer plus the write position (for checkpoints)."""
        return {
            "observations": self.observations[:, : self.size].clone(), "flags": self.flags[:, : self.size].clone(),
            "reward": self.reward[:, : self.size].clone(), "position": self.position, "size": self.size,
        }

    def load_state_dict(self, state: dict) -> None:
        size = int(state["size"])
        for name in ("observations", "flags", "reward"):
            getattr(self, name)[:, :size] = state[name]
        self.position, self.size = int(state["position"]), size
