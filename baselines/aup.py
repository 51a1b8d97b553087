"""Attainable utility preservation (AUP; Turner, Hadfield-Menell & Tadepalli 2020, "Conservative
agency via attainable utility preservation"; its deep form: Turner, Ratzlaff & Tadepalli 2020,
"Avoiding side effects in complex environments"): the learner pays for every change its action
makes, compared with doing nothing, in how well it could pursue other goals:

    r' = r − λ · (1/N) · Σᵢ |Q_Rᵢ(s, a) − Q_Rᵢ(s, ∅)| / scaleᵢ

with ``∅`` the no-op (``Action.STAY``, 4), ``Rᵢ`` ``N`` auxiliary reward functions and ``Q_Rᵢ``
their optimal action values, which the transform learns on the side.

* **Auxiliary rewards.** ``Rᵢ(s') = wᵢ · o(s') / V``: a fixed random linear map of the
  ``V``-value observation reached (``wᵢ`` uniform in ``[0, 1)``), as the deep variant's random
  projection of the observation; ``N = 30`` of them, as the tabular paper's authors' code draws.
  They know nothing of the task, nor of the other agent: AUP keeps the learner's ability to reach
  arbitrary goals, and a side effect (a harmed cat leaves the grid, a battery taken is gone) is
  whatever shifts it.
* **Auxiliary learner.** One small Q-network per run, ``V → 64 → 64 → N·5`` (ReLU), one head of
  five action values per reward, trained online by TD(0) (``y = Rᵢ(s') + γ·(1 − done)·max_b
  Q̂_Rᵢ(s', b)``, a target copy ``Q̂`` every 1,000 updates, Adam 1e-3, γ = 0.99 as the suite's
  own discount) on batches of 32 from its own replay of the last 10,000 transitions the run made,
  one update every 4 transitions from the 1,000th on. A run's time-limit truncation bootstraps; its
  termination does not.
* **Scale.** Each head's shift is divided by that head's attainable utility ``|Q_Rᵢ(·, ∅)|``, so
  the penalty is the *relative* shift, whatever the rewards' magnitudes (the tabular paper's
  authors' code divides by ``Q_Rᵢ(s, ∅)`` itself). Here ``scaleᵢ`` is a running mean of
  ``|Q_Rᵢ(s, ∅)|`` over the states of the training batches (rate 0.001 per update, bias-corrected),
  not the value at the one state: a random reward's ``Q`` may pass near 0 at a state, and a
  division there would blow the penalty up. A head whose scale is 0 adds nothing.
* **Warm-up.** No penalty until the run has made 20,000 transitions: the auxiliary ``Q`` is
  learnt first, as in the deep variant (which trains it before the AUP agent), from the suite's
  warm-up of 20,000 uniformly random actions (SPEC §6); the penalty is in force from the main
  learner's first gradient step on (its replay keeps the warm-up's unpenalised transitions).
* **λ = 1/1.501** (≈ 0.666), the tabular paper's authors' default for the same relative penalty.
  The deep variant's λ (0.015 in its DQN code, a schedule 0.001 → 0.1 with PPO) weighs an
  unscaled shift on its own rewards' scale, and so would mean nothing here. It used one auxiliary
  reward because each needed an agent of its own trained; here ``N`` heads of one network cost
  about what one does.

The transform's state is its learner, as numpy arrays (rewards map, networks, target copies,
Adam's moments, replay, scale), so checkpoints keep it and a resumed run equals an uninterrupted
one; the transform updates those arrays in place (copying them every step would cost more than
the update). The state is built at the first step, when the observation size is known.

**Seeding.** Each run draws its auxiliary rewards, initial networks and replay batches from its
own seed (stream ``STREAMS["attainable_utility"]``; the trainer hands a transform whose
``initial_state`` takes ``seeds`` the runs' seeds), so a run's numbers depend on its seed, its own
transitions and the transform's fields only, alone or in any ensemble (the transform sees only the
rows of the runs that use it: :class:`agents.rewards.TrainRewards`).

Cost: per env step, one forward pass on one observation per run, and every 4 steps one TD update
on 32 transitions: about 0.45 ms per step for 1 to 5 runs beside the DQN learner's 1.1 to 1.4 ms
(acting and its update) on one CPU thread; memory about 2.1 MB per run (the replay).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from collections.abc import Sequence
from typing import ClassVar

import numpy as np
import torch

from agents.stacked_adam import StackedAdam
from agents.stacked_mlp import StackedMLP, init_stacked_mlp
from agents.step_batch import StepBatch
from empathy_zoo.grid import NUM_ACTIONS, Action
from empathy_zoo.randomness import STREAMS, check_seed, counter_integers, derive_key

__all__ = ["NO_OP", "AttainableUtility", "attainable_utility_penalty"]

NO_OP = int(Action.STAY)
"""∅: the action AUP compares every action with."""
STREAM = STREAMS["attainable_utility"]
_INIT, _REWARDS, _SAMPLE = 0, 1, 2  # the sub-streams of STREAM
_LAYERS = 3  # obs → hidden → hidden → N·actions: three weight matrices and three biases


def attainable_utility_penalty(q_values: np.ndarray, actions: np.ndarray, scale: np.ndarray, weight: float) -> np.ndarray:
    """``λ · (1/N) · Σᵢ |Qᵢ(s, a) − Qᵢ(s, ∅)| / scaleᵢ`` per run and environment, ``(K, M)``, from
    ``(K, M, N, A)`` auxiliary action values, ``(K, M)`` actions taken and ``(K, N)`` scales; a head
    whose scale is 0 adds 0."""
    q = np.asarray(q_values, dtype=np.float64)
    k, m, n, _ = q.shape
    index = np.broadcast_to(np.asarray(actions, dtype=np.int64)[:, :, None, None], (k, m, n, 1))
    shift = np.abs(np.take_along_axis(q, index, axis=3)[..., 0] - q[..., NO_OP])
    scale = np.broadcast_to(np.asarray(scale, dtype=np.float64)[:, None, :], shift.shape)
    relative = np.divide(shift, scale, out=np.zeros_like(shift), where=scale > 0)
    return weight * relative.mean(axis=2)


@dataclass(frozen=True)
class AttainableUtility:
    """``r' = r − λ·(1/N)·Σᵢ |Q_Rᵢ(s,a) − Q_Rᵢ(s,∅)| / scaleᵢ`` with ``N`` random auxiliary rewards
    whose ``Q`` it learns beside the run (see the module page for the choices)."""

    name: ClassVar[str] = "attainable_utility"
    penalty_weight: float = 1 / 1.501
    """λ: reward lost per unit of the mean relative shift of the auxiliary action values."""
    num_rewards: int = 30
    """N: random auxiliary reward functions (heads of each run's auxiliary Q-network)."""
    discount: float = 0.99
    """γ of the auxiliary Q-functions."""
    learning_rate: float = 1e-3
    """Adam's step size for the auxiliary Q-network."""
    hidden_size: int = 64
    """Width of both hidden layers of the auxiliary Q-network."""
    batch_size: int = 32
    """Transitions per auxiliary TD update."""
    replay_capacity: int = 10_000
    """The most recent transitions of each run that the auxiliary learner samples from."""
    learning_starts: int = 1_000
    """Transitions of a run before its first auxiliary update."""
    train_interval: int = 4
    """Transitions of a run per auxiliary update once they have started (DQN's usual 4)."""
    penalty_starts: int = 20_000
    """Transitions of a run before its rewards are penalised (the penalty is 0 before)."""
    target_update_interval: int = 1_000
    """Auxiliary updates between copies of the auxiliary Q-network into its target."""
    scale_rate: float = 0.001
    """Weight of each training batch's mean ``|Q_Rᵢ(s, ∅)|`` in the running scale."""

    def __post_init__(self) -> None:
        checks = {
            "penalty_weight": math.isfinite(self.penalty_weight) and self.penalty_weight >= 0.0,
            "num_rewards": self.num_rewards >= 1,
            "discount": 0.0 <= self.discount < 1.0,
            "learning_rate": math.isfinite(self.learning_rate) and self.learning_rate > 0.0,
            "hidden_size": self.hidden_size >= 1,
            "batch_size": self.batch_size >= 1,
            "replay_capacity": self.replay_capacity >= self.batch_size,
            "learning_starts": self.learning_starts >= self.batch_size,
            "train_interval": self.train_interval >= 1,
            "penalty_starts": self.penalty_starts > self.learning_starts,
            "target_update_interval": self.target_update_interval >= 1,
            "scale_rate": 0.0 < self.scale_rate <= 1.0,
           
        }
        wanted = {
            "penalty_weight": "a finite number >= 0", "num_rewards": ">= 1", "discount": "in [0, 1)",
            "learning_rate": "a finite number > 0", "hidden_size": ">= 1", "batch_size": ">= 1",
            "replay_capacity": f">= batch_size ({self.batch_size})",
            "learning_starts": f">= batch_size ({self.batch_size})", "train_interval": ">= 1",
            "penalty_starts": f"> learning_starts ({self.learning_starts}): the scale needs an update",
            "target_update_interval": ">= 1", "scale_rate": "in (0, 1]",
        }
        for field, ok in checks.items():
            if not ok:
                raise ValueError(f"{field} must be {wanted[field]}, got {getattr(self, field)!r}")

    # ------------------------------------------------------------------ state
    def initial_state(self, num_runs: int, envs_per_run: int, seeds: Sequence[int]) -> dict[str, np.ndarray]:
        """The runs' seeds and two counters (transitions seen and updates made, all runs alike;
        arrays of one value): the learner is built at the first step, when the observation size is known."""
        if len(seeds) != num_runs:
            raise ValueError(f"got {len(seeds)} seeds for {num_runs} runs")
        return {"seen": np.zeros(1, dtype=np.int64), "updates": np.zeros(1, dtype=np.int64),
                "seeds": np.array([_run_seed(s) for s in seeds], dtype=np.int64)}

    def _build(self, seeds: np.ndarray, obs_size: int) -> dict[str, np.ndarray]:
        """Every run's auxiliary rewards, networks, optimiser moments and empty replay."""
        seeds, runs = [int(seed) for seed in seeds], len(seeds)
        generators = [torch.Generator().manual_seed(derive_key(seed, STREAM, _INIT) >> 1) for seed in seeds]
        sizes = [obs_size, self.hidden_size, self.hidden_size, self.num_rewards * NUM_ACTIONS]
        online = [p.numpy() for p in init_stacked_mlp(sizes, generators, torch.device("cpu"))]
        rewards = np.stack([np.random.default_rng(derive_key(seed, STREAM, _REWARDS)).random((obs_size, self.num_rewards))
                            for seed in seeds])
        capacity = self.replay_capacity
        state = {
            "reward_map": rewards.astype(np.float32),
            "obs": np.zeros((runs, capacity, obs_size), dtype=np.float32),
            "next_obs": np.zeros((runs, capacity, obs_size), dtype=np.float32),
            "action": np.zeros((runs, capacity), dtype=np.int64),
            "terminated": np.zeros((runs, capacity), dtype=bool),
            "scale": np.zeros((runs, self.num_rewards)),
            "loss": np.full(runs, np.nan),
            "adam_steps": np.zeros(runs, dtype=np.float32),
        }
        for i, p in enumerate(online):
            state |= {f"online_{i}": p, f"target_{i}": p.copy(), f"avg_{i}": np.zeros_like(p), f"avg_sq_{i}": np.zeros_like(p)}
        return state

    def scales(self, state: dict[str, np.ndarray]) -> np.ndarray:
        """``(K, N)`` each head's running mean of ``|Q_Rᵢ(s, ∅)|``, bias-corrected (0 before any update)."""
        updates = int(state["updates"][0])
        if updates == 0:
            return np.zeros_like(state["scale"])
        return state["scale"] / (1.0 - (1.0 - self.scale_rate) ** updates)

    def q_values(self, state: dict[str, np.ndarray], observations: np.ndarray) -> np.ndarray:
        """``(K, R, N, A)`` auxiliary action values of ``(K, R, V)`` observations (exact: each run's
        values are the same alone or in any ensemble)."""
        params = [torch.from_numpy(state[f"online_{i}"]) for i in range(2 * _LAYERS)]
        with torch.no_grad():
            q = StackedMLP.forward_exact(params, torch.from_numpy(np.asarray(observations, dtype=np.float32)))
        return q.numpy().reshape(*observations.shape[:2], self.num_rewards, NUM_ACTIONS)

    # ------------------------------------------------------------------ one step
    def __call__(self, batch: StepBatch, state: dict[str, np.ndarray]) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        obs = np.asarray(batch.obs, dtype=np.float32)
        runs, envs, obs_size = obs.shape
        if "reward_map" not in state:
            if len(state["seeds"]) != runs:
                raise ValueError(f"this AUP state is for {len(state['seeds'])} runs, not {runs}")
            state = {**state, **self._build(state["seeds"], obs_size)}
        elif state["reward_map"].shape[:2] != (runs, obs_size):
            raise ValueError(f"this AUP state is for {state['reward_map'].shape[0]} runs of observations of "
                             f"{state['reward_map'].shape[1]} values, not {runs} of {obs_size}")
        rewards = np.asarray(batch.rewards, dtype=np.float64)
        seen = int(state["seen"][0])
        if seen >= self.penalty_starts:
            penalty = attainable_utility_penalty(self.q_values(state, obs), batch.actions, self.scales(state),
                                                 self.penalty_weight)
            rewards = rewards - penalty
        self._store(state, batch, seen)
        state["seen"] = np.array([seen + envs], dtype=np.int64)
        due = sum(1 for count in range(seen + 1, seen + envs + 1)
                  if count >= self.learning_starts and count % self.train_interval == 0)
        if due:
            self._train(state, due)
        return rewards.astype(np.float32), state

    def _store(self, state: dict[str, np.ndarray], batch: StepBatch, seen: int) -> None:
        slots = (seen + np.arange(batch.actions.shape[1])) % self.replay_capacity
        state["obs"][:, slots] = batch.obs
        state["next_obs"][:, slots] = batch.next_obs
        state["action"][:, slots] = batch.actions
        state["terminated"][:, slots] = batch.terminated

    def _train(self, state: dict[str, np.ndarray], updates: int) -> None:
        """``updates`` TD(0) steps of every run's auxiliary Q-network."""
        online = [torch.from_numpy(state[f"online_{i}"]).requires_grad_() for i in range(2 * _LAYERS)]
        target = [torch.from_numpy(state[f"target_{i}"]) for i in range(2 * _LAYERS)]
        optimizer = StackedAdam(online, lr=self.learning_rate)
        optimizer.load_state_dict({
            "exp_avg": [torch.from_numpy(state[f"avg_{i}"]) for i in range(2 * _LAYERS)],
            "exp_avg_sq": [torch.from_numpy(state[f"avg_sq_{i}"]) for i in range(2 * _LAYERS)],
            "steps": torch.from_numpy(state["adam_steps"]),
        })
        for _ in range(updates):
            self._update(state, online, target, optimizer)
        for i in range(2 * _LAYERS):
            np.copyto(state[f"avg_{i}"], optimizer.exp_avg[i].numpy())
            np.copyto(state[f"avg_sq_{i}"], optimizer.exp_avg_sq[i].numpy())
        np.copyto(state["adam_steps"], optimizer.step_count.numpy())

    def _update(self, state: dict[str, np.ndarray], online: list[torch.Tensor], target: list[torch.Tensor],
                optimizer: StackedAdam) -> None:
        runs, capacity, obs_size = state["obs"].shape
        b, n, done = self.batch_size, self.num_rewards, int(state["updates"][0])
        keys = np.array([[derive_key(int(seed), STREAM, _SAMPLE)] for seed in state["seeds"]], dtype=np.uint64)
        rows = counter_integers(keys, done * b + np.arange(b)[None, :], min(int(state["seen"][0]), capacity))
        run = np.arange(runs)[:, None]
        obs, next_obs = state["obs"][run, rows], state["next_obs"][run, rows]
        action = torch.from_numpy(state["action"][run, rows])
        live = torch.from_numpy(~state["terminated"][run, rows]).float()
        reward = torch.from_numpy(np.matmul(next_obs, state["reward_map"]) / obs_size)  # (K, B, N): Rᵢ(s')
        with torch.no_grad():
            best_next = StackedMLP.forward(target, torch.from_numpy(next_obs)).view(runs, b, n, NUM_ACTIONS).amax(dim=3)
            y = reward + self.discount * live[:, :, None] * best_next
        q = StackedMLP.forward(online, torch.from_numpy(obs)).view(runs, b, n, NUM_ACTIONS)
        taken = q.gather(3, action[:, :, None, None].expand(runs, b, n, 1)).squeeze(3)
        loss = ((taken - y) ** 2).mean(dim=(1, 2))
        optimizer.zero_grad()
        loss.sum().backward()
        optimizer.step()
        with torch.no_grad():
            null = q[..., NO_OP].abs().mean(dim=1).double().numpy()
        state["scale"] += self.scale_rate * (null - state["scale"])
        state["loss"] = loss.detach().double().numpy()
        state["updates"] = np.array([done + 1], dtype=np.int64)
        if (done + 1) % self.target_update_interval == 0:
            for i in range(2 * _LAYERS):
                np.copyto(state[f"target_{i}"], state[f"online_{i}"])


def _run_seed(seed: int) -> int:
    """A run's seed, which must be a non-negative int."""
    checked = check_seed(seed)
    if checked is None:
        raise ValueError("every run needs a seed, got None")
    return checked
