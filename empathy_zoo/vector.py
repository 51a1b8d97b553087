"""The vector face of the engines: ``N`` environments as arrays, with autoreset.

``VectorEnv("coexistence_v0", num_envs=64, fixed={"cat_0": "random_walk"})`` steps 64
Coexistence environments at once; the learning agents (those not in ``fixed``) act through an
``(N, L)`` action array, the fixed ones act inside with their batched policies. Environment
``i`` is seeded with ``seeds[i]`` (or ``seed + i`` for an int), exactly as
``parallel_env().reset(seed=seeds[i])`` would be, and its fixed agents are seeded exactly as
:class:`empathy_zoo.FixedAgents` seeds them: the same seeds and actions give the same
trajectories on both faces. An environment whose episode ends is reset in the same step; its
last observation stays available in :attr:`VectorStep.final_observations`. Keyword arguments
beyond ``size``, ``view`` and ``max_cycles`` are the environment's own (e.g. Sharing's ``start``
and ``inventory_encoding``, and ``num_cats`` / ``num_humans``), exactly as the PettingZoo env
takes them. With several other agents, give each fixed one its policy
(``fixed={f"cat_{i}": "random_walk" for i in range(3)}``); an agent left out learns.

A fixed policy gets the same context here as through :class:`empathy_zoo.FixedAgents` (see
:class:`empathy_zoo.policies.FixedPolicy`), and :meth:`VectorEnv.state` saves each one's own state
(``state()``), so a run resumed from a checkpoint continues exactly; :meth:`VectorEnv.check_checkpointable`
says up front which policy could not be saved.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass
from typing import Any, Protocol

import numpy as np

from empathy_zoo.actions import check_action_array
from empathy_zoo.closest_other import ClosestOther
from empathy_zoo.engine import GridEngine
from empathy_zoo.engine.base import StepEvents, check_env_arguments
from empathy_zoo.environments import ENGINES
from empathy_zoo.fixed_agents import policy_seed, undo_point
from empathy_zoo.limits import MAX_VECTOR_ENVS, check_at_most
from empathy_zoo.metrics import METRIC_NAMES
from empathy_zoo.policies import (
    BatchedPolicy,
    FixedPolicy,
    PolicyEntry,
    batched,
    load_policy_state,
    make_policy,
    policy_context,
    policy_name,
    policy_state,
    unsaved_policy,
)
from empathy_zoo.randomness import check_seed

__all__ = ["STATE_LAYOUT", "EngineWatcher", "VectorEnv", "VectorStep"]

STATE_LAYOUT = 2
"""Layout of :meth:`VectorEnv.state` (1, unmarked: policies' numeric attributes by agent index;
2: each policy's own ``state()`` by agent name, and the last step's events)."""


@dataclass
class VectorStep(ClosestOther):
    """One step of every environment, as arrays.

    Each learner's other agents lie on one axis ``O``, in agent order (``VectorEnv.others[l]``;
    with one other agent, an axis of one): the ``others_*`` fields hold one entry per other agent.
    :attr:`closest` is a place on that axis, and each ``other_*`` property is its ``others_*``
    field there (:meth:`of_closest`): what is said of the closest other agent is said of that one
    entry, never stored twice."""

    observations: np.ndarray
    """(N, L, V) float32: observations to act on next (after any autoreset)."""
    final_observations: np.ndarray
    """(N, L, V) float32: observations at the end of this step, before any autoreset."""
    closest: np.ndarray
    """(N, L) int64: each learner's closest other agent *when the step began*, as its place on the
    ``O`` axis (SPEC §3b: among the others present then, at the least torus distance, ties to the
    lower index; the first other agent when none was present), so one harmed in this step is the
    one swapped with, and has no picture."""
    others_swapped: np.ndarray
    """(N, L, O, V) float32: each learner's swapped observation with each of its other agents at
    the end of this step (before autoreset); zeros where :attr:`others_seen` is False."""
    others_seen: np.ndarray
    """(N, L, O) bool: that other agent is present at the end of this step (and in view, with
    ``in_view_only``): :attr:`others_swapped` holds its picture."""
    others_terminated: np.ndarray
    """(N, L, O) bool: that other agent's episode ended for good this step (a harmed cat; the
    human when the last battery is taken). A time-limit truncation is not termination."""
    others_live: np.ndarray
    """(N, L, O) bool: that other agent was in the environment when this step began (an agent
    harmed earlier has left; one harmed in this step was live)."""
    others_unseen: np.ndarray
    """(N, L, O) bool: that other agent is present and not terminal but out of the learner's
    window (``in_view_only`` only; always False otherwise): *unseen*, not harmed (SPEC §4), so an
    in-view empathic target uses no other-term for it."""
    others_rewards: np.ndarray
    """(N, L, O) float32: the environment's reward of each other agent this step."""
    others_battery_return: np.ndarray
    """(N, L, O) float64: each other agent's battery reward so far in the episode, this step
    included (taken before any autoreset)."""
    rewards: np.ndarray
    """(N, A) float32: the environment's rewards of all agents."""
    terminated: np.ndarray
    """(N, A) bool."""
    truncated: np.ndarray
    """(N, A) bool."""
    episode_over: np.ndarray
    """(N,) bool: the episode ended this step (the environment has been reset)."""
    harmed_by: np.ndarray
    """(N, A) int64: index of the agent that harmed each agent this step, else -1."""
    collected: np.ndarray
    """(N, A) bool: the agent collected a battery this step."""
    battery_return: np.ndarray
    """(N, A) float64: each agent's battery reward so far in the episode, this step included
    (taken before any autoreset)."""
    learner_rewards: np.ndarray
    """(N, L) float32: the learners' rewards (the columns of :attr:`rewards` of :attr:`VectorEnv.learners`)."""
    learner_terminated: np.ndarray
    """(N, L) bool: the learners' episodes ended for good this step."""
    learner_truncated: np.ndarray
    """(N, L) bool: the learners' episodes were cut short this step (time limit, or the episode ended)."""
    harms: np.ndarray
    """(N, L) int64: how many agents each learner harmed this step."""
    learner_battery_return: np.ndarray
    """(N, L) float64: each learner's battery reward so far in the episode, this step included."""
    finished: dict[str, np.ndarray]
    """The episodes that ended this step: ``"env"`` (``(F,)`` environment indices), each SPEC §5
    metric of the first learner (``survival``, ``harms``, …, as :data:`empathy_zoo.metrics.METRIC_NAMES`)
    and ``"length"`` (steps), each an ``(F,)`` array."""

    @property
    def others_present(self) -> np.ndarray:
        """(N, L, O) bool: that other agent is present and not terminal at the end of this step
        (and in view, with ``in_view_only``): the others an empathic target may bootstrap from
        (``others_seen & ~others_terminated``)."""
        return self.others_seen & ~self.others_terminated

    @property
    def other_seen(self) -> np.ndarray:
        """(N, L) bool: :attr:`others_seen` of the closest other agent."""
        return self.of_closest(self.others_seen)

    @property
    def other_terminated(self) -> np.ndarray:
        """(N, L) bool: :attr:`others_terminated` of the closest other agent."""
        return self.of_closest(self.others_terminated)

    @property
    def other_rewards(self) -> np.ndarray:
        """(N, L) float32: :attr:`others_rewards` of the closest other agent."""
        return self.of_closest(self.others_rewards)


class EngineWatcher(Protocol):
    """What watches the engine steps of a :class:`VectorEnv` (:meth:`VectorEnv.watch_engine`)."""

    def before_engine_step(self, engine: GridEngine, actions: np.ndarray) -> None:
        """Called just before ``engine`` steps with the ``(N, A)`` joint actions (the learners'
        and the fixed agents'; read them, do not change them)."""

    def after_engine_step(self, engine: GridEngine, actions: np.ndarray, events: StepEvents) -> None:
        """Called just after that step, before any autoreset: ``engine`` holds the states the step
        ended in, ``events`` what happened in it."""


class VectorEnv:
    """``num_envs`` environments of one kind stepped as arrays (see the module documentation); at
    most :data:`~empathy_zoo.limits.MAX_VECTOR_ENVS` of them (a ``ValueError`` states the bound)."""

    def __init__(
        self,
        env: str | type[GridEngine],
        num_envs: int,
        *,
        fixed: Mapping[str, FixedPolicy | PolicyEntry] | None = None,
        in_view_only: bool = False,
        size: int | None = None,
        view: int | None = None,
        max_cycles: int | None = None,
        **env_options: Any,
    ) -> None:
        """``size``, ``view`` and ``max_cycles`` left ``None`` are the environment's defaults (its
        entry's ``arguments``), as every other argument in ``env_options``."""
        if isinstance(num_envs, bool) or not isinstance(num_envs, (int, np.integer)) or num_envs < 1:
            raise ValueError(f"num_envs must be a positive int, got {num_envs!r}")
        check_at_most("num_envs", int(num_envs), MAX_VECTOR_ENVS, "environments one vector env steps at once")
        if isinstance(env, str):
            if env not in ENGINES:
                raise ValueError(f"unknown environment {env!r}; registered: {sorted(ENGINES)}")
            env = ENGINES[env]
        check_env_arguments(env, env_options)
        given = {"size": size, "view": view, "max_cycles": max_cycles}
        self.engine: GridEngine = env(num_envs, **{k: v for k, v in given.items() if v is not None}, **env_options)
        self.num_envs = self.engine.num_envs
        self.agents = list(self.engine.agents)
        fixed = dict(fixed or {})
        unknown = [agent for agent in fixed if agent not in self.agents]
        if unknown:
            raise ValueError(f"fixed policies given for unknown agent(s) {unknown}; agents are {self.agents}")
        self.learners = [agent for agent in self.agents if agent not in fixed]
        if not self.learners:
            raise ValueError("every agent is fixed; leave at least one agent to learn")
        self.learner_index = [self.agents.index(agent) for agent in self.learners]
        self.others: list[list[str]] = [[self.agents[o] for o in self.engine.other_agents[index]] for index in self.learner_index]
        """``[l]``: the other agents of learner ``l``, in agent order (the ``O`` axis of the
        :class:`VectorStep` fields ``others_*``)."""
        self._other_columns = np.concatenate([self.engine.other_agents[index] for index in self.learner_index])
        """The ``(L·O,)`` agent indices of every learner's other agents, learner by learner."""
        self._only_other: dict[int, int] = (
            {index: int(self.engine.other_agents[index][0]) for index in self.learner_index}
            if self.engine.num_agents == 2
            else {}
        )
        """Learner index -> its one other agent (when there are two agents; else empty)."""
        self.fixed: dict[int, BatchedPolicy] = {
            self.agents.index(agent): batched(make_policy(policy), self.num_envs, agent) for agent, policy in fixed.items()
        }
        self.in_view_only = bool(in_view_only)
        self.obs_size = self.engine.obs_size
        self.num_actions = self.engine.num_actions
        self._observations: np.ndarray | None = None
        self._events: StepEvents | None = None
        """The last step's events (the fixed agents' contexts tell them), or ``None`` before a step."""
        self._fresh = np.ones(self.num_envs, dtype=bool)
        """(N,) bool: the environment was reset after :attr:`_events` (its context is the reset's)."""
        self._watchers: list[EngineWatcher] = []
        """What :meth:`watch_engine` was given, in order."""
        self._seeds: list[int | None] = [None] * self.num_envs
        """The seed each environment was last reset with by :meth:`reset` (``None``: without one):
        its fixed policies' keys derive from it (:meth:`saved_key_problem`)."""

    # ------------------------------------------------------------------ episode
    def reset(self, seed: int | Sequence[int] | None = None) -> np.ndarray:
        """Reset every environment; returns ``(N, L, V)`` observations."""
        if seed is None:
            seeds: list[int | None] = [None] * self.num_envs
        elif isinstance(seed, (int, np.integer)) and not isinstance(seed, bool):
            check_seed(seed)
            seeds = [int(seed) + i for i in range(self.num_envs)]
        else:
            if isinstance(seed, (str, bytes, bool)) or not hasattr(seed, "__len__"):
                raise ValueError(f"seed must be a non-negative int or a list of them, got {seed!r}")
            seeds = [check_seed(s) for s in seed]
            if len(seeds) != self.num_envs:
                raise ValueError(f"got {len(seeds)} seeds for {self.num_envs} environments")
        ids = np.arange(self.num_envs)
        self.engine.reset(ids, seeds)
        for index, policy in self.fixed.items():
            policy.reset(ids, [None if s is None else policy_seed(s, index) for s in seeds])
        self._seeds = seeds
        self._events, self._fresh[:] = None, True
        self._observations = self._observe_learners()
        return self._observations

    def step(self, actions: np.ndarray) -> VectorStep:
        """Step with ``(N, L)`` learner actions; ends and resets finished episodes."""
        if self._observations is None:
            raise RuntimeError("call reset() before step()")
        actions = np.asarray(actions)
        if actions.ndim == 1 and len(self.learners) == 1:
            actions = actions[:, None]
        engine = self.engine
        # checked before the fixed agents act, so a bad action changes nothing
        actions = check_action_array(
            actions, (self.num_envs, len(self.learners)), self.learners, engine.present[:, self.learner_index]
        )
        full = np.full((self.num_envs, engine.num_agents), 4, dtype=np.int64)
        full[:, self.learner_index] = actions
        undo = [undo_point(policy) for policy in self.fixed.values()]
        try:  # every fixed agent's actions are chosen and checked before anything moves
            for index, policy in self.fixed.items():
                full[:, index] = self._fixed_actions(index, policy)
        except BaseException:
            for restore in undo:  # (an earlier policy's stream has moved: put it back)
                restore()
            raise
        # the closest other agent of each learner, chosen among the others present when the step
        # begins (SPEC §3b): a cat harmed in the step stays the one swapped with
        closest = self._closest_places()
        for watcher in self._watchers:
            watcher.before_engine_step(engine, full)
        events = engine.step(full)
        for watcher in self._watchers:
            watcher.after_engine_step(engine, full, events)
        self._events, self._fresh = events, events.episode_over.copy()
        battery_return = engine.episode_battery_return.copy()
        final = self._observe_learners()
        swapped, seen, unseen = self._swaps()
        columns, shape = self._other_columns, seen.shape
        others_terminated = events.terminated[:, columns].reshape(shape)
        unseen &= ~others_terminated
        over = events.episode_over
        done_ids = np.flatnonzero(over)
        finished: dict[str, np.ndarray] = {"env": done_ids}
        if done_ids.size:
            metrics = engine.episode_metrics(done_ids, self.learner_index[0])
            finished.update({name: metrics[name] for name in (*METRIC_NAMES, "length")})
            engine.reset(done_ids)
            for policy in self.fixed.values():
                policy.reset(done_ids, [None] * done_ids.size)
            observations = final.copy()
            observations[done_ids] = self._observe_learners(done_ids)
        else:
            observations = final
        self._observations = observations
        learners = self.learner_index
        return VectorStep(
            observations=observations,
            final_observations=final,
            closest=closest,
            others_swapped=swapped,
            others_seen=seen,
            others_terminated=others_terminated,
            others_live=events.present_before[:, columns].reshape(shape),
            others_unseen=unseen,
            others_rewards=events.rewards[:, columns].reshape(shape),
            others_battery_return=battery_return[:, columns].reshape(shape),
            rewards=events.rewards,
            terminated=events.terminated,
            truncated=events.truncated,
            episode_over=over,
            harmed_by=events.harmed_by,
            collected=events.collected,
            battery_return=battery_return,
            learner_rewards=events.rewards[:, learners],
            learner_terminated=events.terminated[:, learners],
            learner_truncated=events.truncated[:, learners],
            harms=(events.harmed_by[:, None, :] == np.asarray(learners)[None, :, None]).sum(axis=2),
            learner_battery_return=battery_return[:, learners],
            finished=finished,
        )

    def _fixed_actions(self, index: int, policy: BatchedPolicy) -> np.ndarray:
        """The ``(N,)`` actions fixed agent ``index`` chooses this step, checked: integers in
        ``[0, num_actions)`` where it is present (``ValueError`` naming the policy otherwise)."""
        engine = self.engine
        observations = engine.observe(index) if policy.needs_observation else None
        present = engine.present[:, index]
        if getattr(policy, "needs_context", False):
            act_in_context: Callable[..., np.ndarray] = policy.act  # (with a fourth argument, the contexts)
            chosen = act_in_context(observations, engine.t, present, self._contexts(index, policy))
        else:
            chosen = policy.act(observations, engine.t, present)
        agent, chosen = self.agents[index], np.asarray(chosen)
        try:
            if chosen.shape != (self.num_envs,):
                raise ValueError(f"actions must have shape ({self.num_envs},), got {chosen.shape}")
            return check_action_array(chosen[:, None], (self.num_envs, 1), [agent], present[:, None], self.num_actions)[:, 0]
        except ValueError as error:
            raise ValueError(f"fixed policy {policy_name(policy)} of {agent} chose an invalid action: {error}") from None

    def watch_engine(self, watcher: EngineWatcher) -> None:
        """Have ``watcher`` see every engine step of :meth:`step` from now on: its
        ``before_engine_step(engine, actions)`` is called just before the engine steps with the
        ``(N, A)`` joint actions, and ``after_engine_step(engine, actions, events)`` just after,
        before any autoreset (see :class:`EngineWatcher`; the stepwise inaction baseline,
        :class:`baselines.inaction_baseline.InactionBaseline`, is one). Watchers are called in the
        order they were given; a watcher must not change the engine's state."""
        for method in ("before_engine_step", "after_engine_step"):
            if not callable(getattr(watcher, method, None)):
                raise TypeError(f"an engine watcher needs a method {method}(...); {type(watcher).__name__} has none")
        self._watchers.append(watcher)

    def _contexts(self, index: int, policy: BatchedPolicy) -> list[dict[str, Any] | None]:
        """Each environment's context of fixed agent ``index`` (``None`` where it is absent), as
        :class:`empathy_zoo.FixedAgents` builds it from the env's ``infos``."""
        engine, events = self.engine, self._events
        with_positions = bool(getattr(policy, "needs_state", False))
        contexts: list[dict[str, Any] | None] = []
        for env_id, (present, fresh) in enumerate(zip(engine.present[:, index].tolist(), self._fresh.tolist(), strict=True)):
            if not present:
                contexts.append(None)
                continue
            info = engine.reset_info(env_id, index) if fresh or events is None else engine.step_info(events, env_id, index)
            contexts.append(policy_context(engine, env_id, index, info, with_positions))
        return contexts

    # ------------------------------------------------------------------ observations
    def _observe_learners(self, env_ids: np.ndarray | None = None) -> np.ndarray:
        """``(n, L, V)`` observations of the learners (in ``env_ids``, default all)."""
        return _by_learner([self.engine.observe(viewer, env_ids) for viewer in self.learner_index])

    def _closest_places(self) -> np.ndarray:
        """``(N, L)`` int64: each learner's closest other agent now (among the others present; the
        first when none is), as its place among the learner's other agents (:attr:`others`)."""
        if self._only_other:  # (each learner's one other agent)
            return np.zeros((self.num_envs, len(self.learner_index)), dtype=np.int64)
        closest = np.stack([self.engine.closest_other(viewer)[0] for viewer in self.learner_index], axis=1)
        return closest - (closest > np.asarray(self.learner_index)[None, :])  # (the learner is not among its others)

    def _swaps(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Each learner's swapped observations with every other agent, ``(N, L, O, V)`` (zeros
        where not seen), where they are seen (present, and in view with ``in_view_only``) and
        where they are present but out of view, each ``(N, L, O)``."""
        if self._only_other:  # (one other agent: no stacking)
            swapped, valid, hidden = (
                _by_learner(list(x))
                for x in zip(*(self._swap(viewer, self._only_other[viewer]) for viewer in self.learner_index), strict=True)
            )
            return swapped[:, :, None], valid[:, :, None], hidden[:, :, None]
        pictures, seen, unseen = [], [], []
        for viewer in self.learner_index:
            each, each_seen, each_unseen = zip(
                *(self._swap(viewer, other) for other in self.engine.other_agents[viewer].tolist()), strict=True
            )
            pictures.append(np.stack(each, axis=1))
            seen.append(np.stack(each_seen, axis=1))
            unseen.append(np.stack(each_unseen, axis=1))
        return _by_learner(pictures), np.stack(seen, axis=1), np.stack(unseen, axis=1)

    def _swap(self, viewer: int, other: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``viewer``'s swapped observation with ``other`` in every environment, ``(N, V)``, zeros
        where ``other`` is not seen; where it is seen (present, and in view with
        ``in_view_only``), ``(N,)``; and where it is present but out of view (``in_view_only``), ``(N,)``."""
        engine = self.engine
        present = engine.present[:, other]
        seen = present.copy()
        unseen = np.zeros_like(seen)
        if self.in_view_only:
            seen &= engine.in_view(viewer, other)
            unseen = present & ~seen
        picture = engine.observe_swapped(viewer, other)
        picture[~seen] = 0.0
        return picture, seen, unseen

    def swapped_observations(self, viewer: str) -> tuple[np.ndarray, np.ndarray]:
        """``(N, A, V)`` swapped observations of ``viewer`` with every agent, and an ``(N, A)``
        mask of those that exist (other agent present, in view with ``in_view_only``; never self)."""
        v = self.agents.index(viewer)
        engine = self.engine
        out = np.zeros((self.num_envs, engine.num_agents, self.obs_size), dtype=np.float32)
        mask = np.zeros((self.num_envs, engine.num_agents), dtype=bool)
        for o in engine.other_agents[v].tolist():
            out[:, o], mask[:, o], _ = self._swap(v, o)
        return out, mask

    # ------------------------------------------------------------------ checkpoint
    def check_checkpointable(self) -> None:
        """Raise ``ValueError`` naming the first fixed policy (and its agent) whose state a
        checkpoint could not save: one without ``state()``/``load_state()`` that does not declare
        ``stateless = True`` (see :class:`empathy_zoo.policies.FixedPolicy`) and, once the
        environments were reset, one whose ``state()`` (taken once here, as a checkpoint takes it;
        nothing changes) is not plain data. Asked before training, it refuses what the first
        checkpoint would."""
        self._check_saveable()
        if self._observations is None:
            return
        for index, policy in self.fixed.items():
            try:
                policy_state(policy)
            except ValueError as error:
                raise ValueError(
                    f"{error}; fixed agent {self.agents[index]} cannot be checkpointed (a checkpoint holds plain data "
                    "only): make state() return numbers, strings, lists and tables (a generator's "
                    "bit_generator.state, not the generator), or train without checkpoints (--checkpoint-interval 0)"
                ) from None

    def _check_saveable(self) -> None:
        """The first part of :meth:`check_checkpointable`: every fixed policy has a state to save."""
        for index, policy in self.fixed.items():
            unsaved = unsaved_policy(policy)
            if unsaved is not None:
                raise ValueError(
                    f"fixed policy {policy_name(unsaved)} of {self.agents[index]} cannot be checkpointed: a resumed run "
                    "would not continue it exactly. Give it state() -> dict (plain data) and load_state(state), or "
                    "declare stateless = True if it keeps nothing between steps (see empathy_zoo.policies.FixedPolicy); "
                    "or train without checkpoints (--checkpoint-interval 0)"
                )

    def state(self) -> dict[str, Any]:
        """Everything needed to continue exactly (for checkpoints): the engine, each fixed policy's
        own state (by agent name), the last step's events and the observations to act on.
        Raises ``ValueError`` as :meth:`check_checkpointable` does."""
        self._check_saveable()
        policies = {self.agents[index]: policy_state(policy) for index, policy in self.fixed.items()}
        observations = None if self._observations is None else self._observations.copy()
        return {
            "layout": STATE_LAYOUT,
            "engine": self.engine.state(),
            "policies": policies,
            "events": None if self._events is None else asdict(self._events),
            "fresh": self._fresh.copy(),
            "observations": observations,
        }

    def saved_key_problem(self, state: Mapping[str, Any]) -> str | None:
        """What is wrong with the keys of the fixed policies' random streams in ``state`` (what
        :meth:`state` saved), given this env was reset with the seeds the saved one was (a resumed
        run's, freshly reset): each key rederived from its environment's seed and its agent
        (:func:`~empathy_zoo.fixed_agents.policy_seed`, then the policy's ``saved_key_problem``). One
        line naming the field (``policies.cat_0.keys[1] is …``), or ``None``; a policy without
        ``saved_key_problem`` and an environment reset without a seed are not judged."""
        policies = state.get("policies")
        if not isinstance(policies, Mapping):
            return "policies is no table of the fixed agents' states"
        for index, policy in self.fixed.items():
            judge, name = getattr(policy, "saved_key_problem", None), self.agents[index]
            if callable(judge) and name in policies:  # (one missing: load_state refuses it)
                problem = judge(policies[name], [None if s is None else policy_seed(s, index) for s in self._seeds])
                if problem is not None:
                    return f"policies.{name}.{problem}"
        return None

    def load_state(self, state: Mapping[str, Any]) -> None:
        """Continue from :meth:`state`; a state of another layout (an earlier version's
        checkpoint) raises ``ValueError``."""
        if state.get("layout") != STATE_LAYOUT:
            raise ValueError(
                f"this vector env state has layout {state.get('layout', 1)}, this version reads layout {STATE_LAYOUT} "
                "(it saves each fixed policy's own state): a checkpoint written by an earlier version cannot be "
                "resumed; delete or move it to restart those runs"
            )
        names = {self.agents[index] for index in self.fixed}
        if set(state["policies"]) != names:
            raise ValueError(f"the state holds fixed policies of {sorted(state['policies'])}, this env fixes {sorted(names)}")
        self.engine.load_state(state["engine"])
        for index, policy in self.fixed.items():
            load_policy_state(policy, state["policies"][self.agents[index]])
        events = state["events"]
        self._events = None if events is None else StepEvents(**{key: np.asarray(value) for key, value in events.items()})
        fresh = np.array(state["fresh"], dtype=bool)
        if fresh.shape != (self.num_envs,):
            raise ValueError(f"the state is of {fresh.size} environments, this vector env has {self.num_envs}")
        self._fresh = fresh
        if state["observations"] is not None:
            self._observations = np.array(state["observations"], dtype=np.float32)


def _by_learner(columns: list[np.ndarray]) -> np.ndarray:
    """Stack per-learner ``(n, ...)`` arrays to ``(n, L, ...)`` (without a copy for one learner)."""
    return columns[0][:, None] if len(columns) == 1 else np.stack(columns, axis=1)
