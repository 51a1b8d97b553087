"""Attainable utility preservation (AUP; Turner, Hadfield-Menell & Tadepalli 2020, "Conservative
agency via attainable utility preservation"; its deep form: Turner, Ratzlaff & Tadepalli 2020,
"Avoiding side effects in complex environments"): the learner pays for every change its action
makes, compared with doing nothing, in how well it could pursue other goals:

    r' = r − λ · Σᵢ |Q_Rᵢ(s, a) − Q_Rᵢ(s, ∅)| / Σᵢ |Q_Rᵢ(s, ∅)|

with ``∅`` the no-op (``Action.STAY``, 4), ``Rᵢ`` ``N`` auxiliary reward functions and ``Q_Rᵢ``
their optimal action values, which the transform learns on the side.

* **Auxiliary rewards.** ``Rᵢ(s') = wᵢ · o(s') / V``: a fixed random linear map of the
  ``V``-value observation reached, as the deep variant's random projection of the observation,
  each weight uniform in ``[−1, 1)`` (:func:`auxiliary_reward_map`); ``N = 30`` of them, as the
  tabular paper's authors' code draws. They know nothing of the task, nor of the other agent:
  AUP keeps the learner's ability to reach arbitrary goals, and a side effect (a harmed cat
  leaves the grid, a battery taken is gone) is whatever shifts it. The weights take both signs
  because the tabular paper's rewards are random *per state*: whether a state with the cat is
  worth more than the same state without it is a coin toss per goal. The observation draws the
  cat (and a battery) as −1, so weights in ``[0, 1)`` (this transform's draw before 2026-12-01)
  made *every* goal prefer the cat gone: with them (exact values, seeds 0–2, the scale below), a
  move that may harm the cat shifted the attainable utilities under twice as much as a harmless
  move, and one harm a quarter of their sum, against 3.5 to 4.2 times and 0.66 to 0.88 of it
  with signed weights, whatever λ.
* **Scale.** The summed shift is divided by the summed attainable utility of the no-op at the same
  state, ``Σᵢ |Q_Rᵢ(s, ∅)|``, as the tabular paper's authors' code does with its ``use_scale``
  option, so the penalty is the *relative* shift of what the goals could attain from ``s``,
  whatever the rewards' magnitudes. Their code's other option divides each head by its own ``Q_Rᵢ(s, ∅)`` (and
  the deep variant its one head by ``Q_aux(s, ∅)``), which needs values away from 0: true of
  their rewards in ``[0, 1]``, not of signed ones, whose values cross 0 (exactly, per-head
  division charges seed 0's dearest state and action 41 times its mean penalty, the summed scale
  10 to 12 times for every seed); the sum of 30 absolute values stays away from 0. A state whose
  every ``Q_Rᵢ(s, ∅)`` is 0 is charged nothing. (Before 2026-12-01 the scale was a per-head
  running mean over the training batches, so a penalty depended on how many states of the replay
  had the cat gone.)
* **λ = 100 / 1.501** (≈ 66.6, :data:`TASK_VALUE` / 1.501). The tabular paper's λ = 1/1.501 prices
  a relative shift against tasks whose whole attainable utility is a goal reward of 1 (its
  gridworlds pay 1 at the goal, 0 a move): a shift of about 1.5 outweighs the task. Kept in that
  unit, λ is 1/1.501 of the task's own attainable utility, which on Coexistence is
  ``1/(1 − γ) = 100`` (+1 for every step survived, γ = 0.99, SPEC §6). With the 30 auxiliary
  values exact, a harm then costs about 44–59 (tens of steps' reward, where the former
  calibration charged 0.16–0.49), while a move that can neither harm nor get the robot harmed
  costs under a step's reward where standing still is safe (0.47–0.56 at the placed state below).
  λ was fixed from this reasoning and the exact table, before any training result of the method.
  The deep variant's λ (0.015 in its DQN code, a schedule 0.001 → 0.1 with PPO) weighs an
  unscaled shift while its agent first learns the task; here the penalty holds from the
  learner's first gradient step, and the replay keeps every transition's reward as it was given,
  so a schedule would price one step differently depending on when it was stored: none. On
  Sharing the same rule gives at most λ ≈ 3.6 (its task's attainable utility is the robot's
  batteries, at most 5.4: all nine); the default is Coexistence's, the environment the penalty
  is calibrated on (``penalty_weight`` is a reward field a run may set).
* **Warm-up.** No penalty until the run has made 2,000 transitions (``penalty_starts``): the
  learner's warm-up (``learning_starts``) in the methods profile, the one AUP is run in (the
  quick profile's too), so every transition its replay holds past its own warm-up is penalised
  (20,000 before 2026-12-01, which left 40 % of a 50,000-step run's replay unpenalised). The
  transform is told neither a run's budget nor its learner's settings (the trainer builds it from
  the method and the run's reward fields alone), so this is a number, not a fraction: for a
  learner of another warm-up, set it to that ``learning_starts``. The auxiliary learner has then
  made 250 updates: its values are rough (below).
* **Auxiliary learner.** One small Q-network per run, ``V → 64 → 64 → N·5`` (ReLU), one head of
  five action values per reward, trained online by TD(0) (``y = Rᵢ(s') + γ·(1 − done)·max_b
  Q̂_Rᵢ(s', b)``, a target copy ``Q̂`` every 1,000 updates, Adam 1e-3, γ = 0.99 as the suite's
  own discount) on batches of 32 from its own replay of the last 10,000 transitions the run made,
  one update every 4 transitions from the 1,000th on. A run's time-limit truncation bootstraps; its
  termination does not. It reads the learner's window, not the state: a cat out of view looks
  like no cat.

**What a harm costs** (Coexistence, ``size = 7``, the 30 auxiliary values exact on the
full-observability state for the methods profile's seeds 0, 1, 2; reward units, +1 a step; over
the 44 states with the cat present; computed and tested in ``tests/test_aup_calibration.py``,
printed by ``.venv/bin/python -m tests.test_aup_calibration`` from the repository root):

| | per step (random action) | harmless move | harming move | per harm | self-risking move |
|---|---|---|---|---|---|
| before (λ = 1/1.501, w ∈ [0, 1), per-head running-mean scale) | 0.021–0.107 | 0.015–0.127 | 0.036–0.117 | 0.16–0.49 | 0.13–0.24 |
| after (λ = 66.6, w ∈ [−1, 1), summed no-op scale) | 3.7–4.3 | 3.0–3.4 | 10.5–14.2 | 44–59 | 14.0–14.5 |

("per harm": a harming move's penalty over its chance of harming the cat; "harmless": neither
harms nor risks the robot, its mean raised by moves out of a spot where standing still is
risky.) At the robot (3, 3) and the cat (6, 3), seed 0, only moving down may harm (chance 0.2):
it costs 12.8; up, left, right 0.47–0.56; the no-op 0.

**Limits the table shows** (of AUP with a stepwise no-op baseline, not of this code): the shift
is absolute, so where standing still may itself harm the cat (cat at (5, 3): chance 0.2),
moving away costs as much as moving in (about 12 each); the robot's own harm ends every
auxiliary value, so risking it costs as much as risking the cat's (14 against 10.5–14.2); harms
done by standing still are free; and once the cat is gone every action has the same auxiliary
values, so no penalty follows. Even with exact values, the optimum of the penalised reward
harms the cat in 98 % of episodes (surviving 491 of 500 steps), as the unpenalised optimum
(whose ties leave it to chance) does in all. The learnt values are rougher than the exact ones:
trained on a uniformly random robot's transitions (seed 0), their penalties correlate 0.25–0.45
with the exact ones over the in-view states from 2,000 to 100,000 transitions; target copies
every 100 or 250 updates did no better (0.13–0.54).

The transform's state is its learner, as numpy arrays (rewards map, networks, target copies,
Adam's moments, replay), so checkpoints keep it and a resumed run equals an uninterrupted one;
the transform updates those arrays in place (copying them every step would cost more than the
update). The state is built at the first step, when the observation size is known.

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
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
import torch

from agents.stacked_adam import StackedAdam
from agents.stacked_mlp import StackedMLP, init_stacked_mlp
from agents.step_batch import StepBatch
from agents.transform_state import StateBounds, check_same, check_side_learner, check_within
from baselines.side_network import train_side_network
from empathy_zoo.actions import NUM_ACTIONS, Action
from empathy_zoo.randomness import STREAMS, check_seed, counter_integers, derive_key

__all__ = [
    "NO_OP",
    "TASK_VALUE",
    "AttainableUtility",
    "attainable_utility_penalty",
    "auxiliary_reward_map",
    "auxiliary_rewards",
]

NO_OP = int(Action.STAY)
"""∅: the action AUP compares every action with."""
TASK_VALUE = 1.0 / (1.0 - 0.99)
"""The attainable utility of Coexistence's own task: +1 for every step survived, for ever, at the
suite's discount γ = 0.99 (SPEC §6): 100. λ's default prices a relative shift of the auxiliary
utilities in this unit (see the module page)."""
STREAM = STREAMS["attainable_utility"]
_INIT, _REWARDS, _SAMPLE = 0, 1, 2  # the sub-streams of STREAM
_LAYERS = 3  # obs → hidden → hidden → N·actions: three weight matrices and three biases


def auxiliary_reward_map(seed: int, obs_size: int, num_rewards: int) -> np.ndarray:
    """``(V, N)`` float32 weights ``wᵢ`` of the auxiliary rewards of the run of seed ``seed``: each
    uniform in ``[−1, 1)``, drawn from the run's own stream (``STREAMS["attainable_utility"]``)."""
    draw = np.random.default_rng(derive_key(_run_seed(seed), STREAM, _REWARDS)).random((obs_size, num_rewards))
    return (2.0 * draw - 1.0).astype(np.float32)


def auxiliary_rewards(observations: np.ndarray, reward_map: np.ndarray) -> np.ndarray:
    """``Rᵢ(s') = wᵢ · o(s') / V`` of every head, ``(..., N)``, for observations ``(..., V)`` reached
    and a ``(V, N)`` reward map (:func:`auxiliary_reward_map`)."""
    observations = np.asarray(observations, dtype=np.float32)
    return np.matmul(observations, reward_map) / observations.shape[-1]


def attainable_utility_penalty(q_values: np.ndarray, actions: np.ndarray, weight: float) -> np.ndarray:
    """``λ · Σᵢ |Qᵢ(s, a) − Qᵢ(s, ∅)| / Σᵢ |Qᵢ(s, ∅)|`` per run and environment, ``(K, M)``, from
    ``(K, M, N, A)`` auxiliary action values and ``(K, M)`` actions taken; 0 where every
    ``Qᵢ(s, ∅)`` is 0 (no attainable utility to shift)."""
    q = np.asarray(q_values, dtype=np.float64)
    k, m, n, _ = q.shape
    index = np.broadcast_to(np.asarray(actions, dtype=np.int64)[:, :, None, None], (k, m, n, 1))
    shift = np.abs(np.take_along_axis(q, index, axis=3)[..., 0] - q[..., NO_OP]).sum(axis=2)
    scale = np.abs(q[..., NO_OP]).sum(axis=2)
    return weight * np.divide(shift, scale, out=np.zeros_like(shift), where=scale > 0)


@dataclass(frozen=True)
class AttainableUtility:
    """``r' = r − λ·Σᵢ |Q_Rᵢ(s,a) − Q_Rᵢ(s,∅)| / Σᵢ |Q_Rᵢ(s,∅)|`` with ``N`` random auxiliary
    rewards whose ``Q`` it learns beside the run (see the module page for the choices)."""

    name: ClassVar[str] = "attainable_utility"
    penalty_weight: float = TASK_VALUE / 1.501
    """λ: reward lost per unit of relative shift ``Σᵢ |Q_Rᵢ(s,a) − Q_Rᵢ(s,∅)| / Σᵢ |Q_Rᵢ(s,∅)|``
    (≈ 66.6: the tabular paper's 1/1.501 per unit of its task's attainable utility, a goal reward
    of 1, times Coexistence's, :data:`TASK_VALUE`; see the module page)."""
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
    penalty_starts: int = 2_000
    """Transitions of a run before its rewards are penalised (0 before): the warm-up
    (``learning_starts``) of the learner in the methods profile, which AUP is run in, so the
    learner's replay holds no unpenalised transition past its own warm-up there. The transform
    cannot read a run's budget or its learner's settings; for a learner of another warm-up, set it
    to that ``learning_starts`` (a reward field a run may set)."""
    target_update_interval: int = 1_000
    """Auxiliary updates between copies of the auxiliary Q-network into its target."""

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
        }
        wanted = {
            "penalty_weight": "a finite number >= 0",
            "num_rewards": ">= 1",
            "discount": "in [0, 1)",
            "learning_rate": "a finite number > 0",
            "hidden_size": ">= 1",
            "batch_size": ">= 1",
            "replay_capacity": f">= batch_size ({self.batch_size})",
            "learning_starts": f">= batch_size ({self.batch_size})",
            "train_interval": ">= 1",
            "penalty_starts": f"> learning_starts ({self.learning_starts}): the auxiliary values need updates "
            "before they price anything",
            "target_update_interval": ">= 1",
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
        return {
            "seen": np.zeros(1, dtype=np.int64),
            "updates": np.zeros(1, dtype=np.int64),
            "seeds": np.array([_run_seed(s) for s in seeds], dtype=np.int64),
        }

    def check_state(self, state: Mapping[str, Any], initial: Mapping[str, np.ndarray], bounds: StateBounds) -> None:
        """A checkpoint's AUP state (:func:`agents.transform_state.check_side_learner`); once built,
        its auxiliary rewards those its seeds draw and its actions actions."""
        built = {}

        def build() -> dict[str, np.ndarray]:
            built.update(self._build(initial["seeds"], bounds.obs_size))
            return built

        if check_side_learner(state, initial, build, bounds, ("obs", "next_obs")):
            check_same(state, built, "reward_map", "the auxiliary rewards its seeds draw")
            check_within(state, "action", 0, NUM_ACTIONS - 1, "an action")

    def _build(self, seeds: np.ndarray, obs_size: int) -> dict[str, np.ndarray]:
        """Every run's auxiliary rewards, networks, optimiser moments and empty replay."""
        run_seeds, runs = [int(seed) for seed in seeds], len(seeds)
        generators = [torch.Generator().manual_seed(derive_key(seed, STREAM, _INIT) >> 1) for seed in run_seeds]
        sizes = [obs_size, self.hidden_size, self.hidden_size, self.num_rewards * NUM_ACTIONS]
        online = [p.numpy() for p in init_stacked_mlp(sizes, generators, torch.device("cpu"))]
        rewards = np.stack([auxiliary_reward_map(seed, obs_size, self.num_rewards) for seed in run_seeds])
        capacity = self.replay_capacity
        state = {
            "reward_map": rewards,
            "obs": np.zeros((runs, capacity, obs_size), dtype=np.float32),
            "next_obs": np.zeros((runs, capacity, obs_size), dtype=np.float32),
            "action": np.zeros((runs, capacity), dtype=np.int64),
            "terminated": np.zeros((runs, capacity), dtype=bool),
            "loss": np.full(runs, np.nan),
            "adam_steps": np.zeros(runs, dtype=np.float32),
        }
        for i, p in enumerate(online):
            state |= {f"online_{i}": p, f"target_{i}": p.copy(), f"avg_{i}": np.zeros_like(p), f"avg_sq_{i}": np.zeros_like(p)}
        return state

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
            raise ValueError(
                f"this AUP state is for {state['reward_map'].shape[0]} runs of observations of "
                f"{state['reward_map'].shape[1]} values, not {runs} of {obs_size}"
            )
        rewards = np.asarray(batch.rewards, dtype=np.float64)
        seen = int(state["seen"][0])
        if seen >= self.penalty_starts:
            penalty = attainable_utility_penalty(self.q_values(state, obs), batch.actions, self.penalty_weight)
            rewards = rewards - penalty
        self._store(state, batch, seen)
        state["seen"] = np.array([seen + envs], dtype=np.int64)
        due = sum(
            1 for count in range(seen + 1, seen + envs + 1) if count >= self.learning_starts and count % self.train_interval == 0
        )
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
        train_side_network(
            state,
            2 * _LAYERS,
            self.learning_rate,
            updates,
            lambda online, target, optimizer: self._update(state, online, target, optimizer),
        )

    def _update(
        self, state: dict[str, np.ndarray], online: list[torch.Tensor], target: list[torch.Tensor], optimizer: StackedAdam
    ) -> None:
        runs, capacity, _ = state["obs"].shape
        b, n, done = self.batch_size, self.num_rewards, int(state["updates"][0])
        keys = np.array([[derive_key(int(seed), STREAM, _SAMPLE)] for seed in state["seeds"]], dtype=np.uint64)
        rows = counter_integers(keys, done * b + np.arange(b)[None, :], min(int(state["seen"][0]), capacity))
        run = np.arange(runs)[:, None]
        obs, next_obs = state["obs"][run, rows], state["next_obs"][run, rows]
        action = torch.from_numpy(state["action"][run, rows])
        live = torch.from_numpy(~state["terminated"][run, rows]).float()
        reward = torch.from_numpy(auxiliary_rewards(next_obs, state["reward_map"]))  # (K, B, N): Rᵢ(s')
        with torch.no_grad():
            best_next = StackedMLP.forward(target, torch.from_numpy(next_obs)).view(runs, b, n, NUM_ACTIONS).amax(dim=3)
            y = reward + self.discount * live[:, :, None] * best_next
        q = StackedMLP.forward(online, torch.from_numpy(obs)).view(runs, b, n, NUM_ACTIONS)
        taken = q.gather(3, action[:, :, None, None].expand(runs, b, n, 1)).squeeze(3)
        loss = ((taken - y) ** 2).mean(dim=(1, 2))
        optimizer.zero_grad()
        loss.sum().backward()
        optimizer.step()
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
