"""Stable-Baselines3 DQN and PPO as learning methods of the suite (``sb3_dqn``, ``sb3_ppo``).

Name them as ``baselines.sb3:SB3_DQN`` / ``baselines.sb3:SB3_PPO`` (or register
:data:`SB3_METHODS`); the runner trains them like any method and the suite scores them with its
own metrics. Needs ``pip install -e ".[sb3]"``; Stable-Baselines3 is imported only when a
learner is built, so this module imports without it.

Design: SB3's ``learn()`` owns an environment loop over its own ``VecEnv``, while the runner owns
the suite's loop (lockstep ensembles, per-run seeds, metrics from the engine's events, greedy
evaluation, checkpoints, result files). Rather than a second training path that would copy all
of that, :class:`SB3Learner` plays the part of SB3's ``collect_rollouts`` for one real model per
run and leaves the learning to SB3's own code:

* acting: SB3's own exploration (``_sample_action``: uniform during warm-up, then ε-greedy
  ``predict`` for DQN; a sample of ``policy.forward`` with its value and log-probability for PPO);
* storing: the model's own buffers (``_store_transition`` into the replay buffer, with SB3's
  time-out handling; ``rollout_buffer.add`` with SB3's bootstrap of truncated episodes);
* the per-step bookkeeping of ``learn()`` (``num_timesteps``, progress remaining, DQN's
  ``_on_step``: target copies and ε), and the model's own ``train()`` at the moments ``learn()``
  calls it (DQN every ``train_freq`` steps after ``learning_starts``; PPO when the rollout buffer
  is full, after ``compute_returns_and_advantage`` on the next observation).

The loop is ≈ 40 lines mirroring ``collect_rollouts``; a test checks that it leaves the
networks bit-identical to ``model.learn()`` on the Gymnasium adapter for the same seed. (Rejected:
running ``learn()`` in a thread fed by the runner: a suspended ``learn()`` cannot be
checkpointed, and errors cross threads.) Each run keeps its own numpy-global and torch random
states, swapped in around every call into SB3, so a run draws the same numbers alone or beside
other runs, as the runner promises. SB3 reads only what ``StepBatch`` says happened (the reward
the run trains on, termination, truncation), never the metrics.

Reward transforms: the reward SB3 stores is ``StepBatch.rewards``, which the trainer has already
made the run's method's reward transform of the environment's (:class:`agents.rewards.TrainRewards`),
so SB3 DQN and PPO composed with any transform (``sb3_ppo_harm_penalty``, …:
:mod:`baselines.sb3_transforms`) train on the shaped reward and are scored on the environment's
events as every method is. A transform that prices its costs when sampled (the Lagrangian
method) runs on PPO, which charges each rollout's costs at the run's price when it trains on it
(:meth:`SB3Learner.price_costs`), and is refused on DQN, whose replay SB3 owns.
"""

from __future__ import annotations

import copy
import inspect
import json
import math
import random
from collections.abc import Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field, fields
from typing import Any

import gymnasium
import numpy as np
import torch

from agents.base import Method, StepBatch
from agents.phases import TrainingPhases
from empathy_zoo.extras import install_command
from empathy_zoo.randomness import STREAMS, derive_key
from empathy_zoo.safe_data import from_safe, to_safe

__all__ = [
    "SB3Settings",
    "SB3Learner",
    "SB3_DQN",
    "SB3_PPO",
    "SB3_METHODS",
    "DEFAULT_KWARGS",
    "make_sb3_model",
    "sb3_seed",
    "INSTALL_HINT",
    "PRICED_AT_SAMPLE_ON_DQN",
]

INSTALL_HINT = f"Stable-Baselines3 is not installed; install it with: {install_command('sb3')}"
PRICED_AT_SAMPLE_ON_DQN = (
    "SB3 DQN cannot train a reward transform that prices its costs when sampled (the Lagrangian method, "
    "priced_at_sample): SB3's DQN samples its updates from a replay buffer and a train() of its own, which hold "
    "each step's reward as it was stored, so a cost could only be charged at the price of the step that stored it, "
    "not at the run's current λ; train it with sb3_ppo_lagrangian (PPO prices each rollout when it trains on it) "
    "or dqn_lagrangian"
)
"""Why SB3 DQN refuses the Lagrangian method (:meth:`SB3Learner.price_costs`, ``sb3_dqn_lagrangian``)."""
STREAM_SB3 = STREAMS["sb3"]
ALGORITHMS = ("dqn", "ppo")

DEFAULT_KWARGS: dict[str, dict[str, Any]] = {
    "dqn": {
        "buffer_size": 500_000,
        "learning_starts": 20_000,
        "train_freq": 1,
        "gradient_steps": 1,
        "target_update_interval": 10_000,
        "exploration_fraction": 1.0,
        "exploration_initial_eps": 1.0,
        "exploration_final_eps": 0.01,
    },
    "ppo": {},
}
"""Keyword arguments of each SB3 class that differ from SB3's defaults: DQN follows the paper's
settings (SPEC §6; ε decays over ``schedule_steps``), PPO keeps SB3's. ``algorithm_kwargs`` overrides them."""

_FIELD_KWARGS = {"learning_rate", "gamma", "batch_size", "seed", "device", "policy", "env", "verbose"}
_LEARN_DEFAULTS = {"dqn": {"learning_rate": 1e-3, "batch_size": 32}, "ppo": {"learning_rate": 3e-4, "batch_size": 64}}


@dataclass(frozen=True)
class SB3Settings:
    """A Stable-Baselines3 model as a method of the suite. One line per field."""

    algorithm: str = "dqn"
    """``"dqn"`` or ``"ppo"`` (fixed by the registered method)."""
    net_arch: tuple[int, ...] = (128, 128)
    """Hidden layer widths (DQN: the Q-network; PPO: the policy and the value network each), as the paper's MLP."""
    learning_rate: float | None = None
    """Adam step size; ``None``: 1e-3 for DQN (the paper's), 3e-4 for PPO (SB3's)."""
    gamma: float = 0.99
    """Discount factor γ."""
    batch_size: int | None = None
    """Minibatch size; ``None``: 32 for DQN (the paper's), 64 for PPO (SB3's)."""
    schedule_steps: int = 1_000_000
    """Env steps over which SB3's progress schedules (ε, learning-rate and clip-range schedules)
    run, i.e. SB3's ``total_timesteps`` (past them, schedules keep their end values); with
    ``exploration_fraction=1`` DQN's ε decays over them."""
    algorithm_kwargs: Mapping[str, Any] = field(default_factory=dict)
    """More keyword arguments of the SB3 class (``buffer_size``, ``n_steps``, ``ent_coef``,
    ``policy_kwargs``, …), over :data:`DEFAULT_KWARGS`."""

    def __post_init__(self) -> None:
        if self.algorithm not in ALGORITHMS:
            raise ValueError(f"algorithm must be one of {ALGORITHMS}, got {self.algorithm!r}")
        arch = tuple(self.net_arch)
        if not arch or any(not isinstance(w, int) or isinstance(w, bool) or w < 1 for w in arch):
            raise ValueError(f"net_arch must be positive layer widths, got {self.net_arch!r}")
        object.__setattr__(self, "net_arch", arch)
        if self.learning_rate is not None and not self.learning_rate > 0:
            raise ValueError(f"learning_rate must be > 0, got {self.learning_rate!r}")
        if not 0.0 <= self.gamma <= 1.0:
            raise ValueError(f"gamma must be in [0, 1], got {self.gamma!r}")
        if self.batch_size is not None and (not isinstance(self.batch_size, int) or self.batch_size < 1):
            raise ValueError(f"batch_size must be a positive int, got {self.batch_size!r}")
        if not isinstance(self.schedule_steps, int) or self.schedule_steps < 1:
            raise ValueError(f"schedule_steps must be a positive int, got {self.schedule_steps!r}")
        if not isinstance(self.algorithm_kwargs, Mapping):
            raise ValueError(f"algorithm_kwargs must be a mapping, got {self.algorithm_kwargs!r}")
        clash = sorted(_FIELD_KWARGS & set(self.algorithm_kwargs))
        if clash:
            raise ValueError(f"algorithm_kwargs may not set {clash}: they are settings fields or set by the suite")
        _check_algorithm_kwargs(self.algorithm, self.algorithm_kwargs)
        object.__setattr__(self, "algorithm_kwargs", dict(self.algorithm_kwargs))

    def model_kwargs(self) -> dict[str, Any]:
        """Every keyword argument of the SB3 class but ``policy``, ``env``, ``seed`` and ``device``."""
        kwargs = {**DEFAULT_KWARGS[self.algorithm], **self.algorithm_kwargs}
        defaults = _LEARN_DEFAULTS[self.algorithm]
        kwargs["learning_rate"] = defaults["learning_rate"] if self.learning_rate is None else self.learning_rate
        kwargs["batch_size"] = defaults["batch_size"] if self.batch_size is None else self.batch_size
        kwargs["gamma"] = self.gamma
        kwargs["policy_kwargs"] = {"net_arch": list(self.net_arch), **dict(kwargs.get("policy_kwargs") or {})}
        return kwargs

    def training_phases(self) -> TrainingPhases | None:
        """DQN's warm-up (SB3's ``learning_starts``) and the env step at which its ε reaches
        ``exploration_final_eps`` (``exploration_fraction × schedule_steps``), checked against a
        run's budget before it trains (:mod:`agents.phases`); PPO declares neither (``None``)."""
        if self.algorithm != "dqn":
            return None
        kwargs = self.model_kwargs()
        fraction = float(kwargs["exploration_fraction"])
        return TrainingPhases(
            learning_starts=int(kwargs["learning_starts"]),
            learning_starts_setting="algorithm_kwargs.learning_starts",
            learning_starts_option="--algorithm-kwargs learning_starts={}",
            exploration_ends=math.ceil(fraction * self.schedule_steps),
            exploration_rule="exploration_fraction × schedule_steps",
            exploration_fix=lambda steps: f"schedule_steps = {max(1, math.floor(steps / fraction)):,}" if fraction > 0 else "",
        )

    def shared(self) -> tuple:
        """Runs of one ensemble share every setting (each run is its own SB3 model anyway)."""
        return tuple(json.dumps(getattr(self, f.name), sort_keys=True, default=str) for f in fields(self))


def _check_algorithm_kwargs(algorithm: str, kwargs: Mapping[str, Any]) -> None:
    """Refuse (``ValueError``) a key of ``kwargs`` that the SB3 class of ``algorithm`` does not take,
    read from its signature, so a sweep naming one is refused when it loads, not when its ensemble
    starts. Without Stable-Baselines3 installed there is no signature to read (and no learner can be
    built: building one says how to install it)."""
    try:
        sb3 = _sb3()
    except ImportError:
        return
    cls = {"dqn": sb3.DQN, "ppo": sb3.PPO}[algorithm]
    parameters = inspect.signature(cls.__init__).parameters
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in parameters.values()):
        return
    taken = [name for name in parameters if name != "self" and not name.startswith("_") and name not in _FIELD_KWARGS]
    unknown = sorted(set(kwargs) - set(taken))
    if unknown:
        raise ValueError(
            f"algorithm_kwargs: {', '.join(map(repr, unknown))} is no keyword argument of stable_baselines3.{cls.__name__} "
            f"{sb3.__version__}; {cls.__name__} takes {', '.join(taken)} (learning_rate, gamma and batch_size are "
            "settings of their own)"
        )


def _sb3() -> Any:
    try:
        import stable_baselines3
    except ImportError as error:
        raise ImportError(INSTALL_HINT) from error
    return stable_baselines3


def sb3_seed(seed: int) -> int:
    """The seed the SB3 model of run ``seed`` is built with (SB3 seeds numpy with it: < 2**32)."""
    return derive_key(seed, STREAM_SB3) % (2**31)


def make_sb3_model(settings: SB3Settings, env: Any, seed: int | None, device: str = "cpu") -> Any:
    """The SB3 model ``settings`` describe, on ``env`` (a Gymnasium env or an SB3 ``VecEnv``)."""
    sb3 = _sb3()
    cls = {"dqn": sb3.DQN, "ppo": sb3.PPO}[settings.algorithm]
    return cls("MlpPolicy", env, seed=seed, device=device, verbose=0, **settings.model_kwargs())


class _Spaces(gymnasium.Env):
    """Only the spaces: the runner, not SB3, steps the environments."""

    def __init__(self, obs_size: int, num_actions: int) -> None:
        self.observation_space = gymnasium.spaces.Box(-np.inf, np.inf, (obs_size,), np.float32)
        self.action_space = gymnasium.spaces.Discrete(num_actions)

    def reset(self, *, seed: int | None = None, options: Any = None) -> tuple[np.ndarray, dict]:
        raise RuntimeError("this SB3 model is driven by the empathy-zoo runner, not by learn()")

    def step(self, action: Any) -> tuple:
        raise RuntimeError("this SB3 model is driven by the empathy-zoo runner, not by learn()")


class _RunRandomness:
    """One run's numpy-global and torch random states, swapped in while SB3 code of that run runs."""

    def __init__(self, device: torch.device) -> None:
        self.cuda = device.type == "cuda"
        self.saved = self.capture()

    def capture(self) -> dict[str, Any]:
        state = {"numpy": np.random.get_state(legacy=False), "torch": torch.get_rng_state()}
        if self.cuda:
            state["cuda"] = torch.cuda.get_rng_state()
        return state

    def restore(self, state: Mapping[str, Any]) -> None:
        np.random.set_state(state["numpy"])
        torch.set_rng_state(state["torch"])
        if self.cuda:
            torch.cuda.set_rng_state(state["cuda"])

    @contextmanager
    def active(self) -> Any:
        outer = self.capture()
        self.restore(self.saved)
        try:
            yield
        finally:
            self.saved = self.capture()
            self.restore(outer)


class _OffPolicyRun:
    """``collect_rollouts`` and the training condition of ``OffPolicyAlgorithm.learn`` (DQN), one step at a time."""

    def __init__(self, model: Any, schedule_steps: int) -> None:
        from stable_baselines3.common.type_aliases import TrainFrequencyUnit

        model._convert_train_freq()
        if model.train_freq.unit != TrainFrequencyUnit.STEP:
            raise ValueError("train_freq must count steps (the runner's episodes end at different times per run)")
        self.model, self.schedule_steps = model, schedule_steps
        self.steps_since_train = 0
        self._buffer_actions: np.ndarray | None = None

    def act(self, obs: np.ndarray) -> np.ndarray:
        model = self.model
        model._last_obs = obs
        actions, self._buffer_actions = model._sample_action(model.learning_starts, None, len(obs))
        return actions

    def observe(self, reward: np.ndarray, terminated: np.ndarray, truncated: np.ndarray, next_obs: np.ndarray) -> None:
        model = self.model
        infos = [{"TimeLimit.truncated": bool(cut)} for cut in truncated]
        model._store_transition(model.replay_buffer, self._buffer_actions, next_obs, reward, terminated | truncated, infos)
        model.num_timesteps += len(reward)
        _update_progress(model, self.schedule_steps)
        model._on_step()
        self.steps_since_train += 1
        if self.steps_since_train >= model.train_freq.frequency:
            collected, self.steps_since_train = self.steps_since_train * len(reward), 0
            if model.num_timesteps > model.learning_starts:
                steps = model.gradient_steps if model.gradient_steps >= 0 else collected
                if steps > 0:
                    model.train(batch_size=model.batch_size, gradient_steps=steps)

    def state(self) -> dict[str, Any]:
        return {"steps_since_train": self.steps_since_train}

    def load(self, state: Mapping[str, Any]) -> None:
        self.steps_since_train = int(state["steps_since_train"])


class _OnPolicyRun:
    """``collect_rollouts`` and the training step of ``OnPolicyAlgorithm.learn`` (PPO), one step at a time.

    A full rollout is finished (returns on the value of the next observation, then ``train()``)
    at the next :meth:`act`, which is when that observation is known, as in ``learn()``."""

    def __init__(self, model: Any, schedule_steps: int) -> None:
        self.model, self.schedule_steps = model, schedule_steps
        self.episode_starts = np.ones(model.n_envs, dtype=bool)
        self._pending: tuple[np.ndarray, np.ndarray, torch.Tensor, torch.Tensor] | None = None
        """What :meth:`act` chose and :meth:`observe` stores: observations, actions ``(n, 1)``,
        values and log-probabilities (``None`` before the first act)."""
        self.costs: np.ndarray | None = None
        """``(n_steps, n_envs)`` float32 each stored step's cost, beside the rollout buffer's rewards,
        where the run prices costs (:meth:`price_costs`); else ``None``."""
        self.price = 0.0
        """The run's latest price of one unit of cost (``StepBatch.prices``)."""

    def price_costs(self) -> None:
        """Keep each step's cost beside its reward and charge the rollout's costs at the price of
        the moment it is trained on (OmniSafe's PPO-Lag prices each batch afresh)."""
        self.costs = np.zeros(self.model.rollout_buffer.rewards.shape, dtype=np.float32)

    def act(self, obs: np.ndarray) -> np.ndarray:
        from stable_baselines3.common.utils import obs_as_tensor

        model = self.model
        if model.rollout_buffer.full:
            if self.costs is not None:  # the whole rollout priced now, before its returns are computed
                model.rollout_buffer.rewards -= np.float32(self.price) * self.costs
            with torch.no_grad():
                last_values = model.policy.predict_values(obs_as_tensor(obs, model.device))
            model.rollout_buffer.compute_returns_and_advantage(last_values=last_values, dones=self.episode_starts)
            _update_progress(model, self.schedule_steps)
            model.train()
            model.rollout_buffer.reset()
        model.policy.set_training_mode(False)
        with torch.no_grad():
            actions, values, log_probs = model.policy(obs_as_tensor(obs, model.device))
        actions = actions.cpu().numpy()
        self._pending = (obs.copy(), actions.reshape(-1, 1), values, log_probs)
        return actions

    def observe(
        self,
        reward: np.ndarray,
        terminated: np.ndarray,
        truncated: np.ndarray,
        next_obs: np.ndarray,
        cost: np.ndarray | None = None,
        price: float = 0.0,
    ) -> None:
        model = self.model
        if self._pending is None:
            raise RuntimeError("observe() before act(): no step of the rollout to store")
        if self.costs is not None:
            if cost is None:
                raise ValueError("this run prices costs when they are sampled: its StepBatch must carry costs and prices")
            self.costs[model.rollout_buffer.pos] = cost
            self.price = float(price)
        obs, actions, values, log_probs = self._pending
        reward = reward.astype(np.float32)
        for i in np.flatnonzero(truncated & ~terminated):  # bootstrap a time-out, as SB3 does (same float32 arithmetic)
            with torch.no_grad():
                terminal_value = model.policy.predict_values(model.policy.obs_to_tensor(next_obs[i])[0])[0]
            reward[i] += model.gamma * terminal_value
        model.rollout_buffer.add(obs, actions, reward, self.episode_starts, values, log_probs)
        self.episode_starts = terminated | truncated
        model.num_timesteps += len(reward)

    def state(self) -> dict[str, Any]:
        if self.costs is None:
            return {"episode_starts": self.episode_starts.copy()}
        return {"episode_starts": self.episode_starts.copy(), "costs": self.costs.copy(), "price": self.price}

    def load(self, state: Mapping[str, Any]) -> None:
        self.episode_starts = np.asarray(state["episode_starts"], dtype=bool).copy()
        if ("costs" in state) != (self.costs is not None):
            raise ValueError("this checkpoint's PPO run was made with another choice of pricing costs; move it away to restart")
        if self.costs is not None:
            self.costs = np.asarray(state["costs"], dtype=np.float32).copy()
            self.price = float(state["price"])


def _update_progress(model: Any, schedule_steps: int) -> None:
    model._update_current_progress_remaining(model.num_timesteps, max(schedule_steps, model.num_timesteps))


_COUNTERS = ("num_timesteps", "_n_updates", "_n_calls", "exploration_rate", "_current_progress_remaining", "_episode_num")


def _check_saved(owner: Any, name: str, value: Any, allowed: tuple[str, ...], what: str) -> None:
    """Refuse a checkpoint's ``value`` for ``owner.name`` unless ``name`` is one the checkpoint
    writes (``allowed``) and ``value`` has the current value's type (an array: shape and dtype)."""
    if name not in allowed or not hasattr(owner, name):
        raise ValueError(f"checkpoint holds an unknown SB3 {what} {name!r} (known: {', '.join(allowed)})")
    current = getattr(owner, name)
    if isinstance(current, np.ndarray):
        if not isinstance(value, np.ndarray) or value.shape != current.shape or value.dtype != current.dtype:
            raise ValueError(f"checkpoint's SB3 {what} {name!r} is not a {current.dtype} array of shape {current.shape}")
    elif type(value) is not type(current) and not (isinstance(current, float) and type(value) is int):
        raise ValueError(f"checkpoint's SB3 {what} {name!r} is a {type(value).__name__}, not a {type(current).__name__}")


class SB3Learner:
    """``K`` runs, one SB3 model each, driven by the runner (see the module documentation)."""

    settings_class = SB3Settings

    def __init__(
        self,
        settings: Sequence[SB3Settings],
        seeds: Sequence[int],
        obs_size: int,
        num_actions: int = 5,
        device: str = "cpu",
        envs_per_run: int = 1,
        *,
        num_others: int = 1,  # (every learner is told it; SB3's agents see only the robot's observation)
    ) -> None:
        if len(settings) != len(seeds) or not settings:
            raise ValueError("give one settings object per seed, and at least one run")
        _sb3()
        from stable_baselines3.common.logger import Logger
        from stable_baselines3.common.off_policy_algorithm import OffPolicyAlgorithm
        from stable_baselines3.common.vec_env import DummyVecEnv

        self.settings = list(settings)
        self.seeds = [int(s) for s in seeds]
        self.envs_per_run = int(envs_per_run)
        self.device = torch.device(device)
        self.models: list[Any] = []
        """The SB3 model of every run."""
        self._runs: list[_OffPolicyRun | _OnPolicyRun] = []
        self._randomness: list[_RunRandomness] = []
        outer_python = random.getstate()
        outer = _RunRandomness(self.device)
        for config, seed in zip(self.settings, self.seeds, strict=True):
            env = DummyVecEnv([lambda: _Spaces(obs_size, num_actions)] * self.envs_per_run)
            model = make_sb3_model(config, env, sb3_seed(seed), device)  # seeds the global generators
            model.set_logger(Logger(folder=None, output_formats=[]))
            self._randomness.append(_RunRandomness(self.device))
            run_class = _OffPolicyRun if isinstance(model, OffPolicyAlgorithm) else _OnPolicyRun
            self._runs.append(run_class(model, config.schedule_steps))
            self.models.append(model)
        outer.restore(outer.saved)
        random.setstate(outer_python)

    # ------------------------------------------------------------------ acting
    def act(self, observations: np.ndarray, greedy: bool = False) -> np.ndarray:
        k, m = observations.shape[:2]
        actions = np.empty((k, m), dtype=np.int64)
        for r, (model, run, rng) in enumerate(zip(self.models, self._runs, self._randomness, strict=True)):
            obs = np.asarray(observations[r], dtype=np.float32)
            if greedy:
                actions[r] = model.policy.predict(obs, deterministic=True)[0]
                continue
            if m != self.envs_per_run:
                raise ValueError(f"training steps {self.envs_per_run} env(s) per run, got {m}")
            with rng.active():
                actions[r] = run.act(obs)
        return actions

    # ------------------------------------------------------------------ learning
    def observe(self, batch: StepBatch) -> None:
        """Store one step in every run's SB3 buffer, with ``batch.rewards`` as its reward: the
        reward the run trains on (its method's reward transform of the environment's, where it has
        one: :class:`agents.rewards.TrainRewards` made it), and train where ``learn()`` would."""
        truncated = getattr(batch, "truncated", None)
        if truncated is None:
            raise ValueError("SB3 learners need StepBatch.truncated (the time-limit flag) from the runner")
        for r, (run, rng) in enumerate(zip(self._runs, self._randomness, strict=True)):
            signals = (
                np.asarray(batch.rewards[r], dtype=np.float32),
                np.asarray(batch.terminated[r], dtype=bool),
                np.asarray(truncated[r], dtype=bool),
                np.asarray(batch.next_obs[r], dtype=np.float32),
            )
            with rng.active():
                if isinstance(run, _OnPolicyRun) and run.costs is not None:
                    costs, prices = batch.costs, batch.prices
                    run.observe(
                        *signals,
                        None if costs is None else np.asarray(costs[r], dtype=np.float32),
                        0.0 if prices is None else float(prices[r]),
                    )
                else:
                    run.observe(*signals)

    def price_costs(self, runs: Sequence[bool]) -> None:
        """Train the runs ``runs`` says on ``reward − price·cost`` (a reward transform that prices
        its costs when sampled, :class:`agents.rewards.PricedTransform`: the Lagrangian method).
        SB3 PPO keeps each step's cost beside the rollout buffer's reward and charges the whole
        rollout at the run's price when it trains on it (its update samples nothing older). SB3
        DQN cannot: its replay buffer and its ``train()`` are SB3's, and they sample a stored
        reward, fixed when the step was stored; a ``ValueError`` says so
        (:data:`PRICED_AT_SAMPLE_ON_DQN`)."""
        if len(runs) != len(self._runs):
            raise ValueError(f"price_costs: got {len(runs)} flags for {len(self._runs)} runs")
        for priced, run in zip(runs, self._runs, strict=True):
            if not priced:
                continue
            if not isinstance(run, _OnPolicyRun):
                raise ValueError(PRICED_AT_SAMPLE_ON_DQN)
            if run.model.num_timesteps:
                raise ValueError("price_costs() must come before the first step is stored")
            run.price_costs()

    # ------------------------------------------------------------------ bookkeeping
    def live_stats(self) -> dict[str, float]:
        stats = {"loss": _nanmean([model.logger.name_to_value.get("train/loss", math.nan) for model in self.models])}
        if hasattr(self.models[0], "exploration_rate"):
            stats["eps"] = float(np.mean([model.exploration_rate for model in self.models]))
        return stats

    def memory_bytes_per_run(self) -> int:
        model = self.models[0]
        buffer = getattr(model, "replay_buffer", None) or model.rollout_buffer
        stored = sum(v.nbytes for v in vars(buffer).values() if isinstance(v, np.ndarray))
        params = sum(t.numel() * t.element_size() for t in model.policy.state_dict().values())
        trained = sum(p.numel() * p.element_size() for p in model.policy.parameters() if p.requires_grad)
        return stored + params + 2 * trained  # + Adam's two moments

    def state_dict(self) -> dict[str, Any]:

        runs = []
        for model, run, rng in zip(self.models, self._runs, self._randomness, strict=True):
            buffer = getattr(model, "replay_buffer", None) or model.rollout_buffer
            runs.append(
                {
                    "policy": {k: v.detach().clone() for k, v in model.policy.state_dict().items()},
                    "optimizer": copy.deepcopy(model.policy.optimizer.state_dict()),
                    "counters": {name: getattr(model, name) for name in _COUNTERS if hasattr(model, name)},
                    "buffer": to_safe({k: v for k, v in vars(buffer).items() if isinstance(v, (np.ndarray, bool, int, float))}),
                    "driver": to_safe(run.state()),
                    "random": to_safe({**rng.saved, "action_space": model.action_space.np_random.bit_generator.state}),
                }
            )
        return {"seeds": list(self.seeds), "runs": runs}

    def load_state_dict(self, state: dict[str, Any]) -> None:

        if list(state["seeds"]) != self.seeds:
            raise ValueError(f"checkpoint is for seeds {state['seeds']}, not {self.seeds}")
        for model, run, rng, saved in zip(self.models, self._runs, self._randomness, state["runs"], strict=True):
            model.policy.load_state_dict(saved["policy"])
            model.policy.optimizer.load_state_dict(saved["optimizer"])
            for name, value in saved["counters"].items():
                _check_saved(model, name, value, _COUNTERS, "counter")
                setattr(model, name, value)
            buffer = getattr(model, "replay_buffer", None) or model.rollout_buffer
            own = tuple(k for k, v in vars(buffer).items() if isinstance(v, (np.ndarray, bool, int, float)))
            for name, value in from_safe(saved["buffer"]).items():
                _check_saved(buffer, name, value, own, "buffer field")
                setattr(buffer, name, value.copy() if isinstance(value, np.ndarray) else value)
            run.load(from_safe(saved["driver"]))
            randomness = from_safe(saved["random"])
            model.action_space.np_random.bit_generator.state = randomness.pop("action_space")
            rng.saved = randomness

    # ------------------------------------------------------------------ keeping a trained agent
    def save_agent(self, run: int, file: Any) -> dict[str, Any]:
        """Write run ``run``'s model to the binary ``file`` in SB3's own format (``model.save``: its
        zip, with the policy's networks and optimiser, without the replay or rollout buffer) and
        return what :func:`empathy_zoo.load_agent` needs to read it back with SB3's ``load``: the
        library, the SB3 class, its policy, the sizes, and the value heads (DQN: ``["q"]``, its
        ``q_net``, which it acts on; PPO: none, it acts on its policy). The writer,
        :func:`empathy_zoo.agent_file.write_agent_file`, names the file ``<run id>.agent.zip``."""
        if not 0 <= run < len(self.models):
            raise ValueError(f"run must be in [0, {len(self.models)}), got {run!r}")
        model = self.models[run]
        model.save(file)
        dqn = hasattr(model.policy, "q_net")
        return {
            "library": "stable_baselines3",
            "algorithm": type(model).__name__,
            "policy": "MlpPolicy",
            "obs_size": int(model.observation_space.shape[0]),
            "num_actions": int(model.action_space.n),
            "heads": ["q"] if dqn else [],
            "acting": "q" if dqn else "policy",
        }


def _nanmean(values: list[float]) -> float:
    finite = [v for v in values if not math.isnan(v)]
    return float(np.mean(finite)) if finite else math.nan


SB3_DQN = Method(
    name="sb3_dqn",
    learner=SB3Learner,
    settings=SB3Settings,
    preset={"algorithm": "dqn"},
    family="sb3",
    label=lambda s: "SB3 DQN",
    description="Stable-Baselines3 DQN (its own loss, targets and schedules), paper-sized MLP and replay",
)
"""Stable-Baselines3 DQN; name it ``baselines.sb3:SB3_DQN``."""

SB3_PPO = Method(
    name="sb3_ppo",
    learner=SB3Learner,
    settings=SB3Settings,
    preset={"algorithm": "ppo"},
    family="sb3",
    label=lambda s: "SB3 PPO",
    description="Stable-Baselines3 PPO (SB3's default hyper-parameters), paper-sized MLP",
)
"""Stable-Baselines3 PPO; name it ``baselines.sb3:SB3_PPO``."""

SB3_METHODS: dict[str, Method] = {"sb3_dqn": SB3_DQN, "sb3_ppo": SB3_PPO}
"""Both, by registry name (for ``baselines.registry.METHODS``)."""
