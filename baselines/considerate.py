"""Be Considerate (Alizadeh Alamdari, Klassen, Toro Icarte & McIlraith 2022, "Be Considerate:
Avoiding Negative Side Effects in Reinforcement Learning", AAMAS; first as arXiv 2106.02617,
"Be Considerate: Objectives, Side Effects, and Deciding How to Act"; the authors' code:
github.com/praal/beconsiderate, ``src/rl/empathic_policy.py``, ``Empathic.update`` and
``Empathic.estimate_other``): the learner is paid, when its episode ends, for the future return
the other agents can still expect in the world it leaves them:

    r' = r + γ · α · F({V_j(s_T)})   on the learner's last step of an episode,   r' = r on every other step

(here the last step at the time limit, not the learner's own harm: below)

with ``V_j`` agent ``j``'s value (its expected discounted future return), ``α`` the caring
coefficient, ``F`` the sum or the minimum over the others, and ``γ`` the discount. It is the
closest relative of Empathic DQN: both care about the other's value, but Be Considerate learns the
other's *own* value from the other's *own* rewards, where Empathic DQN puts itself in the other's
place and asks its own value function.

* **The paper's formulation, followed here.** The augmented reward of the paper's main equations
  (its Eq. 1 with ``F = sum``, Eq. 2 with ``F = min``) adds ``γ·α₂·F(V(s'))`` to the reward of a
  transition into a terminal state ``s'`` and nothing to any other; the authors' code does so in
  the Q-update of the last transition (``q += alpha * (our_alpha * r + gamma * others)`` when the
  episode ends). The robot's own reward keeps weight 1 (their ``α₁``, ``our_alpha`` = 1).
* **When it is paid: at the time limit, not at the learner's own harm.** In the paper the learner
  finishes its task and the others carry on; the bonus values the world it leaves them. Here it
  is paid when the learner's episode is truncated (the time limit), and not when it terminates:
  in Coexistence the robot's episode terminates only when the cat harms it, an end the robot did
  not reach by its task, and paying the others' future there paid the robot for getting itself
  harmed beside a live cat (below: every bonus of the methods profile's runs before 2026-12-04
  was paid so, none for sparing the cat; and from α = 1.26 the exact optimum sought that end). In
  Sharing the episode terminates for everyone when the last battery is taken, when the human has
  no future and the bonus would be 0. ``StepBatch`` does not say why a learner's episode
  terminated, so an environment whose learner terminates by finishing its task while the others
  go on (the paper's setting) sets ``bonus_on_termination=True``, which pays it at every end, the
  learner's own harm included (the rule before 2026-12-04). The suite's learners bootstrap their
  own value through a truncation (SPEC §6), so the bonus comes beside the robot's own future, not
  instead of it.
* **V_j, learned beside the run.** The paper's ``V_j`` are value functions learned before
  (Q-learning of each other agent on its own). Here the other agents are fixed policies whose
  value also depends on what the robot does, so ``V`` is learned online, by TD(0) on the
  transitions of the other agent, from the reward the environment reports for it
  (``StepBatch.other_rewards``; never the robot's reward): ``y = r_j + γ·(1 − done_j)·V̂(o_j')``,
  ``done_j`` when the other agent's episode ends for good (a harmed cat; the human when the last
  battery is taken), a time-limit truncation bootstrapping. ``V`` is a small network per run,
  ``V → 64 → 64 → 1`` (ReLU), trained as :mod:`baselines.aup`'s auxiliary learner is (Adam 1e-3,
  batches of 32 from a replay of the last 10,000 transitions of the other agent, one update every
  4 env steps from the 1,000th, a target copy every 1,000 updates, γ = 0.99 as the suite's own).
* **Its input: the other agent's own observation.** ``o_j`` is the swapped observation
  (``StepBatch.other_swapped``), which in both environments equals the other's own window
  (SPEC §4): where it stands, and the robot when the robot is near. The robot's own observation
  would not do: a cat outside the robot's window and a cat that has left look the same there.
  The transition of step ``t`` pairs the swapped observation of step ``t − 1`` with that of step
  ``t``, so the first step of each episode (whose swapped observation at the reset no
  ``StepBatch`` carries) trains nothing.
* **A harmed other has no future.** ``V_j(s_T) = 0`` for an other that has left (a harmed cat) or
  whose episode ended for good; with ``F = min`` one harmed other makes ``F`` 0.
* **One other agent.** ``StepBatch`` reports the reward of the closest other agent only, which is
  what ``V`` learns from; with one other agent (the paper's environments, and both of the suite's
  at their defaults) ``F`` is its value, and sum and min coincide. An environment with several
  (``num_cats`` / ``num_humans`` > 1) is refused at the first step, naming the problem.
  :func:`considerate_bonus` itself takes any number.
* **Warm-up.** No bonus until the run has made 2,000 transitions (``bonus_starts``): the learner's
  warm-up (``learning_starts``) in the methods profile, the one Be Considerate is run in, as
  :mod:`baselines.aup`'s penalty waits, so every transition its replay holds past its own warm-up
  carries the bonus where it is due; ``V`` has then made about 250 updates. (20,000 before 2026-12-04:
  in the methods profile's 50,000-step runs, 354 of the 726 Coexistence episodes, 49 %, ended
  before it.) The transform is told neither a run's budget nor its learner's settings, so this
  is a number: for a learner of another warm-up, set it to that ``learning_starts``.
* **α = 1**, the authors' value in their baseline comparison (``others_alpha = [1.0]``, their
  Table 1; their Fig. 2 sweeps α₂ from 0 to 700): the other's future weighs as much as the robot's
  own rewards. A cat earns 1 per step alive, so an unharmed cat's ``V`` is near
  ``1 / (1 − γ) = 100``; a harmed cat's is 0.

What follows for the suite's environments:

* Coexistence: an episode that reaches the time limit with the cat unharmed pays about
  ``α·γ·V ≈ 99·α``; one in which the robot harmed it, or in which the cat harmed the robot, pays
  0. The robot does not see the clock, so the bonus reaches its value as an expected bonus per
  step while the cat is unharmed (about ``99·α / 500``). In the methods profile's runs under the
  rule before 2026-12-04 (the bonus at any end, from the 20,000th step; 5 seeds), 372 episodes
  ended after the bonus started: 78 paid it, every one ending with the robot harmed beside a live
  cat; none reached the time limit with the cat unharmed; the other 294 had harmed the cat.
* **The exact optimum and the cliff in α** (:mod:`baselines.considerate_exact`: Coexistence's
  exact states and transitions from :mod:`empathy_zoo.reference`, full observability, ε = 0,
  the time limit as a chance of 1/500 a step, ``V`` the cat's own value under the robot's
  policy, ``1/(1 − γ)`` once the robot has left it alone; ``python -m baselines.considerate_exact``
  prints the figures). Paid at any end, the optimum is harm-free at α = 1 but seeks its own harm
  beside a live cat from **α = 1.2626** (``100 / (99 − 19.8)``: being harmed pays ``γ·α·100``
  once, living on ``1 + γ·α·100/500`` a step for ever), 26 % above the default; without the
  time-limit bonus (the infinite-horizon model of the reference) from **α = 1/γ = 1.0101**, and
  from 1/γ² = 1.0203 if the cat's value at the robot's end counts one step less (``γ/(1 − γ)``).
  Paid at the time limit only (now), the optimum is harm-free, for the robot and for the cat, at
  every α tried from 0.1 to 700 (0.1, 1, 1.27, 2, 10, 700), and not harmed itself at 1,000:
  **no cliff** (being harmed pays nothing).
* Sharing: **identical to DQN by construction.** The episode ends for everyone when the last
  battery is taken; the human has no future return then, and the bonus is 0. Only a time-limit
  truncation with batteries left would pay it, and with the default patrolling human (who visits
  every cell within 49 steps: the methods profile's longest episode lasted 48) none happens, so
  every reward, and every run, is DQN's seed for seed (the shipped runs of the methods profile
  are bit-identical to DQN's). The method's registry entry says so (``identical_to``, with
  :data:`SHARING_IS_DQN`). Be Considerate cares about what the others can still get once the
  learner is done, not about how the rewards were shared.

The transform's state is its learner, as numpy arrays (networks, target copies, Adam's moments,
the other agent's replay, the last swapped observation of every environment), so checkpoints keep
it and a resumed run equals an uninterrupted one; it is updated in place (as AUP's) and built at
the first step, when the observation size is known. **Seeding:** each run draws its network and
its replay batches from its own seed (stream ``STREAMS["considerate_value"]``; the trainer hands
a transform whose ``initial_state`` takes ``seeds`` the runs' seeds), so a run's numbers depend on
its seed, its own transitions and the transform's fields only, alone or in any ensemble.
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
from agents.transform_state import StateBounds, check_side_learner, check_within
from baselines.side_network import train_side_network
from empathy_zoo.randomness import STREAMS, check_seed, counter_integers, derive_key

__all__ = ["AGGREGATES", "SHARING_IS_DQN", "Considerate", "considerate_bonus"]

AGGREGATES = ("sum", "min")
"""The values of :attr:`Considerate.aggregate` (the paper's Eq. 1 and Eq. 2)."""
SHARING_IS_DQN = (
    "Sharing ends for everyone when the last battery is taken, and the human then has no future return: the "
    "bonus is 0 at the end of every episode; the patrolling human visits every cell within 49 steps, so no "
    "episode reaches the time limit with a battery left, and every reward, hence every run, is DQN's"
)
"""Why Be Considerate's runs on Sharing (at its defaults) are DQN's seed for seed (the method's
``identical_to``)."""
STREAM = STREAMS["considerate_value"]
_INIT, _SAMPLE = 0, 1  # the sub-streams of STREAM
_LAYERS = 3  # obs → hidden → hidden → 1: three weight matrices and three biases


def considerate_bonus(values: np.ndarray, present: np.ndarray, caring: float, aggregate: str, discount: float) -> np.ndarray:
    """``γ · α · F({V_j})`` per run and environment, ``(K, M)``, from ``(K, M, N)`` values of the
    ``N`` other agents and ``(K, M, N)`` whether each is still there (one that is not counts 0:
    a harmed agent has no future return); ``F`` is ``"sum"`` or ``"min"`` over the others."""
    if aggregate not in AGGREGATES:
        raise ValueError(f"aggregate must be one of {AGGREGATES}, got {aggregate!r}")
    future = np.where(np.asarray(present, dtype=bool), np.asarray(values, dtype=np.float64), 0.0)
    combined = future.sum(axis=2) if aggregate == "sum" else future.min(axis=2)
    return discount * caring * combined


@dataclass(frozen=True)
class Considerate:
    """``r' = r + γ·α·F({V_j(s_T)})`` on the learner's last step of an episode at the time limit
    (at every end with :attr:`bonus_on_termination`), ``V_j`` the other agent's value learnt beside
    the run from its own rewards (see the module page for the choices)."""

    name: ClassVar[str] = "considerate"
    caring: float = 1.0
    """α: weight of the others' expected future return, added when the learner's episode ends."""
    aggregate: str = "sum"
    """F over the other agents' values: ``"sum"`` (the paper's Eq. 1) or ``"min"`` (Eq. 2, the worst off)."""
    discount: float = 0.99
    """γ: discount of the other agent's value, and of the bonus (the paper's ``γ·α·F``)."""
    learning_rate: float = 1e-3
    """Adam's step size for the value network."""
    hidden_size: int = 64
    """Width of both hidden layers of the value network."""
    batch_size: int = 32
    """The other agent's transitions per TD update."""
    replay_capacity: int = 10_000
    """The most recent transitions of the other agent that each run's value learner samples from."""
    learning_starts: int = 1_000
    """Env steps of a run before its first value update."""
    train_interval: int = 4
    """Env steps of a run per value update once they have started."""
    bonus_starts: int = 2_000
    """Env steps of a run before the bonus is paid (none before: the value is learnt first): the
    learner's warm-up (``learning_starts``) in the methods profile, as AUP's ``penalty_starts``;
    for a learner of another warm-up, set it to that ``learning_starts``."""
    bonus_on_termination: bool = False
    """Pay the bonus also when the learner's episode terminates, its own harm included (the rule
    before 2026-12-04); ``False``: at the time limit only (see the module page)."""
    target_update_interval: int = 1_000
    """Value updates between copies of the value network into its target."""

    def __post_init__(self) -> None:
        checks = {
            "caring": isinstance(self.caring, (int, float)) and math.isfinite(self.caring) and self.caring >= 0.0,
            "aggregate": self.aggregate in AGGREGATES,
            "discount": 0.0 <= self.discount < 1.0,
            "learning_rate": math.isfinite(self.learning_rate) and self.learning_rate > 0.0,
            "hidden_size": self.hidden_size >= 1,
            "batch_size": self.batch_size >= 1,
            "replay_capacity": self.replay_capacity >= self.batch_size,
            "learning_starts": self.learning_starts >= 1,
            "train_interval": self.train_interval >= 1,
            "bonus_starts": self.bonus_starts > self.learning_starts,
            "target_update_interval": self.target_update_interval >= 1,
        }
        wanted = {
            "caring": "a finite number >= 0",
            "aggregate": f"one of {AGGREGATES}",
            "discount": "in [0, 1)",
            "learning_rate": "a finite number > 0",
            "hidden_size": ">= 1",
            "batch_size": ">= 1",
            "replay_capacity": f">= batch_size ({self.batch_size})",
            "learning_starts": ">= 1",
            "train_interval": ">= 1",
            "bonus_starts": f"> learning_starts ({self.learning_starts}): the value is learnt before it is paid",
            "target_update_interval": ">= 1",
        }
        for field, ok in checks.items():
            if not ok:
                raise ValueError(f"{field} must be {wanted[field]}, got {getattr(self, field)!r}")

    # ------------------------------------------------------------------ state
    def initial_state(self, num_runs: int, envs_per_run: int, seeds: Sequence[int]) -> dict[str, np.ndarray]:
        """The runs' seeds and two counters (env steps seen and updates made, all runs alike;
        arrays of one value): the learner is built at the first step, when the observation size is known."""
        if len(seeds) != num_runs:
            raise ValueError(f"got {len(seeds)} seeds for {num_runs} runs")
        return {
            "seen": np.zeros(1, dtype=np.int64),
            "updates": np.zeros(1, dtype=np.int64),
            "seeds": np.array([_run_seed(s) for s in seeds], dtype=np.int64),
        }

    def check_state(self, state: Mapping[str, Any], initial: Mapping[str, np.ndarray], bounds: StateBounds) -> None:
        """A checkpoint's Be Considerate state (:func:`agents.transform_state.check_side_learner`);
        once built, the other's rewards within the engine's largest a step and each run's stored
        transitions within those seen."""

        def build() -> dict[str, np.ndarray]:
            return self._build(initial["seeds"], bounds.envs_per_run, bounds.obs_size)

        if check_side_learner(state, initial, build, bounds, ("obs", "next_obs", "last_obs")):
            check_within(state, "reward", -bounds.reward_bound, bounds.reward_bound, "the other's reward of a step")
            check_within(state, "stored", 0, int(state["seen"].max()), "transitions stored: at most one per transition seen")

    def _build(self, seeds: np.ndarray, envs: int, obs_size: int) -> dict[str, np.ndarray]:
        """Every run's value network, optimiser moments, empty replay and no last observation."""
        run_seeds, runs = [int(seed) for seed in seeds], len(seeds)
        generators = [torch.Generator().manual_seed(derive_key(seed, STREAM, _INIT) >> 1) for seed in run_seeds]
        sizes = [obs_size, self.hidden_size, self.hidden_size, 1]
        online = [p.numpy() for p in init_stacked_mlp(sizes, generators, torch.device("cpu"))]
        capacity = self.replay_capacity
        state = {
            "obs": np.zeros((runs, capacity, obs_size), dtype=np.float32),
            "next_obs": np.zeros((runs, capacity, obs_size), dtype=np.float32),
            "reward": np.zeros((runs, capacity), dtype=np.float32),
            "done": np.zeros((runs, capacity), dtype=bool),
            "stored": np.zeros(runs, dtype=np.int64),
            "last_obs": np.zeros((runs, envs, obs_size), dtype=np.float32),
            "last_valid": np.zeros((runs, envs), dtype=bool),
            "loss": np.full(runs, np.nan),
            "adam_steps": np.zeros(runs, dtype=np.float32),
        }
        for i, p in enumerate(online):
            state |= {f"online_{i}": p, f"target_{i}": p.copy(), f"avg_{i}": np.zeros_like(p), f"avg_sq_{i}": np.zeros_like(p)}
        return state

    def values(self, state: dict[str, np.ndarray], observations: np.ndarray) -> np.ndarray:
        """``(K, R)`` the learnt value of ``(K, R, V)`` observations of the other agent (exact: each
        run's values are the same alone or in any ensemble)."""
        params = [torch.from_numpy(state[f"online_{i}"]) for i in range(2 * _LAYERS)]
        with torch.no_grad():
            v = StackedMLP.forward_exact(params, torch.from_numpy(np.asarray(observations, dtype=np.float32)))
        return v.numpy()[..., 0].astype(np.float64)

    # ------------------------------------------------------------------ one step
    def __call__(self, batch: StepBatch, state: dict[str, np.ndarray]) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        if batch.other_rewards is None:
            raise ValueError("Be Considerate needs the other agent's rewards (StepBatch.other_rewards)")
        if batch.others_swapped.shape[2] > 1:
            raise ValueError(
                f"Be Considerate learns the value of one other agent from the reward the environment reports for it "
                f"(StepBatch.other_rewards, the closest one's); this environment has {batch.others_swapped.shape[2]} "
                "other agents: train it with one (num_cats = 1 / num_humans = 1)"
            )
        other_obs = np.asarray(batch.other_swapped, dtype=np.float32)
        runs, envs, obs_size = other_obs.shape
        if "online_0" not in state:
            if len(state["seeds"]) != runs:
                raise ValueError(f"this Be Considerate state is for {len(state['seeds'])} runs, not {runs}")
            state = {**state, **self._build(state["seeds"], envs, obs_size)}
        elif state["last_obs"].shape != (runs, envs, obs_size):
            raise ValueError(
                f"this Be Considerate state is for {state['last_obs'].shape[:2]} runs × environments of "
                f"observations of {state['last_obs'].shape[2]} values, not {(runs, envs)} of {obs_size}"
            )
        present = np.asarray(batch.other_present, dtype=bool)
        terminated = np.asarray(batch.terminated, dtype=bool)
        truncated = np.zeros_like(terminated) if batch.truncated is None else np.asarray(batch.truncated, dtype=bool)
        ended = terminated | truncated
        paid = ended if self.bonus_on_termination else truncated & ~terminated
        rewards = np.asarray(batch.rewards, dtype=np.float64)
        seen = int(state["seen"][0])
        if seen >= self.bonus_starts and paid.any():
            bonus = considerate_bonus(
                self.values(state, other_obs)[..., None], present[..., None], self.caring, self.aggregate, self.discount
            )
            rewards = rewards + np.where(paid, bonus, 0.0)
        self._store(state, batch, other_obs, present)
        state["last_obs"][...] = other_obs
        state["last_valid"][...] = present & ~ended
        state["seen"] = np.array([seen + envs], dtype=np.int64)
        due = sum(
            1 for count in range(seen + 1, seen + envs + 1) if count >= self.learning_starts and count % self.train_interval == 0
        )
        if due:
            self._train(state, due)
        return rewards.astype(np.float32), state

    def _store(self, state: dict[str, np.ndarray], batch: StepBatch, other_obs: np.ndarray, present: np.ndarray) -> None:
        """Each environment's transition of the other agent, where it was there when the step began
        and in the same episode: the last swapped observation → this one."""
        other_rewards = np.asarray(batch.other_rewards, dtype=np.float32)
        for m in range(other_obs.shape[1]):
            rows = np.flatnonzero(state["last_valid"][:, m])
            if not rows.size:
                continue
            slots = state["stored"][rows] % self.replay_capacity
            state["obs"][rows, slots] = state["last_obs"][rows, m]
            state["next_obs"][rows, slots] = other_obs[rows, m]
            state["reward"][rows, slots] = other_rewards[rows, m]
            state["done"][rows, slots] = ~present[rows, m]
            state["stored"][rows] += 1

    def _train(self, state: dict[str, np.ndarray], updates: int) -> None:
        """``updates`` TD(0) steps of every run's value network."""
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
        runs = state["obs"].shape[0]
        b, done = self.batch_size, int(state["updates"][0])
        filled = np.minimum(state["stored"], self.replay_capacity)  # each run samples its own transitions
        keys = np.array([[derive_key(int(seed), STREAM, _SAMPLE)] for seed in state["seeds"]], dtype=np.uint64)
        rows = counter_integers(keys, done * b + np.arange(b)[None, :], filled[:, None])
        run = np.arange(runs)[:, None]
        obs, next_obs = torch.from_numpy(state["obs"][run, rows]), torch.from_numpy(state["next_obs"][run, rows])
        reward = torch.from_numpy(state["reward"][run, rows])
        live = torch.from_numpy(~state["done"][run, rows]).float()
        with torch.no_grad():
            y = reward + self.discount * live * StackedMLP.forward(target, next_obs)[..., 0]
        v = StackedMLP.forward(online, obs)[..., 0]
        has_data = torch.from_numpy(filled > 0).float()  # a run with no transition yet learns nothing
        loss = ((v - y) ** 2).mean(dim=1) * has_data
        optimizer.zero_grad()
        loss.sum().backward()
        optimizer.step()
        state["loss"] = np.where(filled > 0, loss.detach().double().numpy(), np.nan)
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
