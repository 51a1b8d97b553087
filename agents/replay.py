"""Per-run replay memories as preallocated tensors, observations stored as int8.

Observations of both environments are small integers (-1 … 10), so each transition costs
3·V bytes of observations plus 7 bytes of the rest: 82 bytes at V = 25, 41 MB per run at the
paper's 500,000 transitions.
"""

from __future__ import annotations

import torch

__all__ = ["StackedReplay"]


class StackedReplay:
    """``K`` ring buffers of ``capacity`` transitions, filled in lockstep (one row per run per add)."""

    FIELDS = ("obs", "next_obs", "swapped_next_obs", "action", "reward", "terminated", "other_present")

    def __init__(self, num_runs: int, capacity: int, obs_size: int, device: torch.device) -> None:
        k, c = num_runs, capacity
        self.num_runs, self.capacity, self.obs_size = k, c, obs_size
        self.obs = torch.zeros((k, c, obs_size), dtype=torch.int8, device=device)
        self.next_obs = torch.zeros((k, c, obs_size), dtype=torch.int8, device=device)
        self.swapped_next_obs = torch.zeros((k, c, obs_size), dtype=torch.int8, device=device)
        self.action = torch.zeros((k, c), dtype=torch.uint8, device=device)
        self.reward = torch.zeros((k, c), dtype=torch.float32, device=device)
        self.terminated = torch.zeros((k, c), dtype=torch.bool, device=device)
        self.other_present = torch.zeros((k, c), dtype=torch.bool, device=device)
        self.position = 0
        self.size = 0
        self._runs = torch.arange(k, device=device)[:, None]

    @staticmethod
    def _as_int8(obs: torch.Tensor) -> torch.Tensor:
        small = obs.to(torch.int8)
        if not torch.equal(small.to(obs.dtype), obs):
            raise ValueError("replay stores observations as int8; got values that are not small integers")
        return small

    def add(self, obs, next_obs, swapped_next_obs, action, reward, terminated, other_present) -> None:
        """Append ``m`` transitions per run: tensors ``(K, m, V)`` / ``(K, m)``."""
        m = action.shape[1]
        idx = (torch.arange(m) + self.position) % self.capacity
        self.obs[:, idx] = self._as_int8(obs)
        self.next_obs[:, idx] = self._as_int8(next_obs)
        self.swapped_next_obs[:, idx] = self._as_int8(swapped_next_obs)
        self.action[:, idx] = action.to(torch.uint8)
        self.reward[:, idx] = reward
        self.terminated[:, idx] = terminated
        self.other_present[:, idx] = other_present
        self.position = int((self.position + m) % self.capacity)
        self.size = min(self.size + m, self.capacity)

    def sample(self, index: torch.Tensor) -> dict[str, torch.Tensor]:
        """Transitions at ``index`` ``(K, B)`` (one row of indices per run), observations as float32."""
        out = {name: getattr(self, name)[self._runs, index] for name in self.FIELDS}
        for name in ("obs", "next_obs", "swapped_next_obs"):
            out[name] = out[name].float()
        out["action"] = out["action"].long()
        return out

    def nbytes_per_run(self) -> int:
        """Bytes of memory each run's buffer holds."""
        return sum(getattr(self, n).element_size() * getattr(self, n)[0].numel() for n in self.FIELDS)

    def state_dict(self) -> dict[str, torch.Tensor | int]:
        """The filled part of every buffer plus the write position (for checkpoints)."""
        state: dict[str, torch.Tensor | int] = {n: getattr(self, n)[:, : self.size].clone() for n in self.FIELDS}
        state["position"], state["size"] = self.position, self.size
        return state

    def load_state_dict(self, state: dict) -> None:
        size = int(state["size"])
        for name in self.FIELDS:
            getattr(self, name)[:, :size] = state[name]
        self.position, self.size = int(state["position"]), size
