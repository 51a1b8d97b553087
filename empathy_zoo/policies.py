"""Fixed (non-learning) agents: the cat's random walk, the human's patrol, and your own.

A fixed policy is any object with ``reset(seed)`` and ``act(observation, context) -> int``
(:class:`FixedPolicy`, whose documentation lists what ``context`` holds). ``reset`` is called at
the start of every episode: with a seed it reseeds, with ``None`` it continues its random stream.
Register a new one by name in :data:`POLICIES`, or name it as ``"package.module:ClassName"`` in a
config or on the command line; :func:`make_policy` resolves both, and builds it with keyword
arguments from a policy entry ``{"policy": name, **arguments}`` (a sweep file's
``fixed = { cat_0 = { policy = "pkg.mod:Chaser", speed = 2 } }``).

A policy may also offer ``batched(num_envs) -> BatchedPolicy`` to act for many environments
with one numpy call (the training fast path); without it, :func:`batched` runs one copy of the
policy per environment, which is correct but slower.

A policy that keeps anything between steps (a random generator, a memory, a counter) offers
``state()`` and ``load_state(state)`` so a checkpointed training run resumes it exactly; one that
keeps nothing says ``stateless = True``. Training with checkpoints refuses any other (see
:class:`FixedPolicy`).
"""

from __future__ import annotations

import copy
import inspect
import json
from collections.abc import Collection, Iterable, Mapping, Sequence
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np

from empathy_zoo.actions import NUM_ACTIONS, Action, check_action
from empathy_zoo.builtin_policies import Patrol, RandomWalk, Stay
from empathy_zoo.import_names import resolve_name
from empathy_zoo.partner_policies import Chase, KeepAway, NearestBattery, Noisy, Population, SlowWalk
from empathy_zoo.policy_parameters import MAX_POLICY_INT, REGISTRY, UnlistedPlugin, check_arguments, check_policy

if TYPE_CHECKING:
    from empathy_zoo.engine.base import GridEngine

__all__ = [
    "check_allowed_imports_named",
    "parse_entry_label",
    "checked_entry",
    "recorded_entry",
    "MAX_POLICY_INT",
    "FixedPolicy",
    "BatchedPolicy",
    "RandomWalk",
    "Patrol",
    "Stay",
    "POLICIES",
    "CONTEXT_KEYS",
    "PolicyEntry",
    "make_policy",
    "batched",
    "checked_policy_action",
    "policy_context",
    "policy_entry",
    "entry_label",
    "entry_policy_name",
    "policy_name",
    "unsaved_policy",
    "policy_state",
    "load_policy_state",
    "plain_data_problem",
]

PolicyEntry = str | Mapping[str, Any]
"""How a configuration names a fixed policy: a registered name or ``package.module:ClassName``,
or ``{"policy": name, **arguments}`` to build it with keyword arguments."""

CONTEXT_KEYS = ("step", "agent", "size")
"""Keys of every policy context besides the environment's own ``infos`` entry (see :class:`FixedPolicy`)."""


@runtime_checkable
class FixedPolicy(Protocol):
    """What the suite asks of a non-learning agent.

    **Acting.** ``reset(seed)`` starts each episode; ``act(observation, context)`` is asked for
    the action of every step the agent is in the environment, with its own ``(view·view,)``
    float32 observation and a ``context`` dict that is the same on every path that drives the
    policy (:class:`empathy_zoo.FixedAgents` over the PettingZoo env, the vector env and training):

    | key | type | meaning |
    |---|---|---|
    | `step` | `int` | steps of this episode so far (0 at the first act) |
    | `agent` | `str` | this agent's name (`"cat_0"`) |
    | `size` | `int` | side of the (torus) grid |
    | `harmed_by` | `str` or `None` | Coexistence: who harmed this agent in the last step (`None` after a reset) |
    | `harmed` | `list[str]` | Coexistence: whom this agent harmed in the last step |
    | `batteries` | `int` | Sharing: batteries this agent holds |
    | `positions` | `dict[str, tuple[int, int]]` | only with `needs_state = True`: `(row, col)` of every agent present, this one included |

    The environment's keys are exactly its ``infos[agent]`` entry after the last step (or the
    reset). The window of an observation is small (5×5 by default): a policy that must find an
    agent outside it (a chaser) declares the class attribute ``needs_state = True`` to receive
    ``positions``, the true state; the others do without.

    **Checkpoints.** A policy that keeps anything between steps (a ``np.random.Generator``, a
    memory, a counter) defines ``state() -> dict`` and ``load_state(state) -> None``: ``state``
    returns plain data (numbers, strings, booleans, ``None``, lists, dicts with string keys, numpy
    arrays), which a checkpoint stores and ``load_state`` gets back, with every tuple turned into
    a list; a generator saves ``rng.bit_generator.state`` and loads it by assigning it back. A
    policy that keeps nothing between steps declares ``stateless = True`` instead (a class
    attribute; :class:`Stay` does). Training with checkpoints refuses a policy that does neither
    (train it with ``--checkpoint-interval 0``), since a resumed run would silently act otherwise
    than an uninterrupted one. The per-environment copies of the generic batched path save and
    load each copy's state; a policy's own ``batched()`` object follows the same protocol.
    A policy whose saved state holds a key derived from its seed may define
    ``saved_key_problem(state, seed) -> str | None`` (a batched one: ``(state, seeds)``), as
    :class:`~empathy_zoo.builtin_policies.CounterStream` does: a resumed run refuses a checkpoint
    whose key is not the one its environment's seed gives.
    """

    def reset(self, seed: int | None = None) -> None:
        """Start an episode; reseed when ``seed`` is given, else continue the random stream."""

    def act(self, observation: np.ndarray, info: Mapping[str, Any]) -> int:
        """The action (an int in ``[0, 5)``) for this step, given the observation and the context."""


class BatchedPolicy(Protocol):
    """A fixed policy acting for ``num_envs`` environments at once.

    It may also declare ``needs_context = True``: ``act`` then gets a fourth argument, one
    context (see :class:`FixedPolicy`) per environment (``None`` where the agent is absent), and
    ``needs_state`` as a per-environment policy does. It saves its state like a
    :class:`FixedPolicy` (``state``/``load_state``, or ``stateless = True``)."""

    needs_observation: bool

    def reset(self, env_ids: np.ndarray, seeds: Sequence[int | None]) -> None:
        """Start episodes in ``env_ids`` (seeded like :meth:`FixedPolicy.reset`)."""

    def act(self, observations: np.ndarray | None, steps: np.ndarray, active: np.ndarray) -> np.ndarray:
        """Actions ``(num_envs,)`` given observations ``(num_envs, obs)``, each env's step count and
        where the agent is present (elsewhere the action is ignored and no stream may advance)."""


class _PolicyCopies:
    """One copy of a per-environment policy for each environment (the generic, slower path)."""

    needs_observation = True
    needs_context = True

    def __init__(self, policy: FixedPolicy, num_envs: int, agent: str) -> None:
        self.copies = [copy.deepcopy(policy) for _ in range(num_envs)]
        self.agent = agent
        self.needs_state = bool(getattr(policy, "needs_state", False))

    def reset(self, env_ids: np.ndarray, seeds: Sequence[int | None]) -> None:
        for i, seed in zip(env_ids, seeds, strict=True):
            self.copies[i].reset(seed)

    def act(
        self,
        observations: np.ndarray | None,
        steps: np.ndarray,
        active: np.ndarray,
        contexts: Sequence[Mapping[str, Any] | None] | None = None,
    ) -> np.ndarray:
        """Each active environment's copy acts on its observation and context (``needs_observation``
        and ``needs_context`` are true: both are required, ``None`` only where the agent is absent)."""
        if observations is None or contexts is None:
            raise ValueError(f"the per-environment copies of {self.agent}'s policy act on observations and contexts, got None")
        actions = np.full(len(self.copies), int(Action.STAY), dtype=np.int64)
        for i in np.flatnonzero(active).tolist():
            policy, context = self.copies[i], contexts[i]
            if context is None:
                raise ValueError(f"no context for {self.agent} in environment {i}, where it is present")
            actions[i] = checked_policy_action(policy, self.agent, policy.act(observations[i], context))
        return actions

    def state(self) -> dict[str, Any]:
        return {"copies": [policy_state(policy) for policy in self.copies]}

    def saved_key_problem(self, state: Any, seeds: Sequence[int | None]) -> str | None:
        """What is wrong with the keys of the random streams ``state`` saves, each copy's as its
        policy judges it (its ``saved_key_problem``, given the seed of its environment's last seeded
        reset; a policy without one, or an environment never seeded, is not judged), else ``None``."""
        judge = getattr(self.copies[0], "saved_key_problem", None) if self.copies else None
        if not callable(judge):
            return None
        states = state.get("copies") if isinstance(state, Mapping) else None
        if not isinstance(states, list) or len(states) != len(self.copies):
            return f"copies is no list of {len(self.copies)} states (one per environment)"
        for i, (policy, saved, seed) in enumerate(zip(self.copies, states, seeds, strict=True)):
            problem = None if seed is None else policy.saved_key_problem(saved, seed)  # type: ignore[attr-defined]
            if problem is not None:
                return f"copies[{i}].{problem}"
        return None

    def load_state(self, state: Mapping[str, Any]) -> None:
        states = state["copies"]
        if len(states) != len(self.copies):
            raise ValueError(
                f"state of {len(states)} copies of {policy_name(self.copies[0])} for {len(self.copies)} environments"
            )
        for policy, saved in zip(self.copies, states, strict=True):
            load_policy_state(policy, saved)


POLICIES: dict[str, type] = REGISTRY
"""Fixed policies by name (the dict :mod:`empathy_zoo.policy_parameters` checks names against, and
the noisy and population partners build their members from). A registered class declares the
arguments it takes in ``parameters`` (see :mod:`empathy_zoo.policy_parameters`); one that does
not has its argument names checked against its signature."""
POLICIES.update(
    {
        "random_walk": RandomWalk,
        "patrol": Patrol,
        "stay": Stay,
        "slow_walk": SlowWalk,
        "chase": Chase,
        "keep_away": KeepAway,
        "nearest_battery": NearestBattery,
        "noisy": Noisy,
        "population": Population,
    }
)


# ---------------------------------------------------------------------------- naming and building
def policy_entry(entry: Any) -> str | dict[str, Any]:
    """``entry`` (see :data:`PolicyEntry`) checked and in its one form: a name, or
    ``{"policy": name, **arguments}`` with at least one argument (an entry without arguments is
    its name). Arguments are named like Python parameters and hold plain data (numbers, strings,
    booleans, lists, tables with string keys); anything else raises ``ValueError`` naming it."""
    if isinstance(entry, str):
        return entry
    if not isinstance(entry, Mapping):
        raise ValueError(f"a fixed policy is a name or {{'policy': name, <argument>: value, ...}}, got {entry!r}")
    if "policy" not in entry:
        raise ValueError(f"missing key 'policy' (a registered policy or package.module:ClassName) in {dict(entry)}")
    name = entry["policy"]
    if not isinstance(name, str):
        raise ValueError(f"'policy' must be a policy name (a string), got {name!r}")
    arguments = {key: value for key, value in entry.items() if key != "policy"}
    for key, value in arguments.items():
        if not isinstance(key, str) or not key.isidentifier():
            raise ValueError(f"argument {key!r} of fixed policy {name!r} is not a parameter name")
        problem = plain_data_problem(value, arrays=False)
        if problem:
            raise ValueError(f"argument {key!r} of fixed policy {name!r}: {problem}")
    return {"policy": name, **arguments} if arguments else name


def entry_label(entry: PolicyEntry) -> str:
    """A policy entry as one string: its name, or ``name(arg=value, ...)`` (arguments sorted,
    values as JSON), which tells two entries apart exactly when they build different policies."""
    entry = policy_entry(entry)
    if isinstance(entry, str):
        return entry
    arguments = ", ".join(f"{key}={json.dumps(entry[key], sort_keys=True)}" for key in sorted(entry) if key != "policy")
    return f"{entry['policy']}({arguments})"


def make_policy(spec: PolicyEntry | FixedPolicy, **kwargs: Any) -> FixedPolicy:
    """A policy from a registered name, a ``package.module:ClassName`` string, a policy entry
    ``{"policy": name, **arguments}``, or an instance; ``kwargs`` are constructor arguments."""
    if isinstance(spec, Mapping):
        entry = policy_entry(spec)
        name, arguments = (entry, {}) if isinstance(entry, str) else (entry["policy"], dict(entry))
        arguments.pop("policy", None)
        overlap = sorted(arguments.keys() & kwargs.keys())
        if overlap:
            raise ValueError(f"argument(s) {overlap} of fixed policy {name!r} given twice")
        return make_policy(name, **arguments, **kwargs)
    if not isinstance(spec, str):
        if kwargs:
            raise ValueError("keyword arguments are only accepted with a policy name")
        policy = spec
    else:
        factory = check_policy(spec, kwargs, plugins=None)  # (the rule a recorded label is read by)
        if factory is None:  # a package.module:Name: imported, then checked like a registered one
            factory = resolve_name(spec, POLICIES, "fixed policy")
            _check_factory(spec, factory)
            check_arguments(spec, factory, kwargs)
        try:
            policy = factory(**kwargs)
        except (TypeError, OverflowError) as error:
            raise ValueError(f"cannot build fixed policy {spec!r} with {kwargs!r:.200}: {error}") from error
    if not isinstance(policy, FixedPolicy):
        raise ValueError(f"{spec!r} is not a fixed policy: it needs reset(seed) and act(observation, info)")
    return policy


def _check_factory(spec: str, factory: Any) -> None:
    """Raise ``ValueError`` unless ``factory`` is a class whose instances have ``reset`` and
    ``act`` methods: what a name resolves to is checked before it is called."""
    if not inspect.isclass(factory):
        raise ValueError(f"{spec!r} is not a fixed policy: it names a {type(factory).__name__}, not a class")
    missing = [name for name in ("reset", "act") if not callable(getattr(factory, name, None))]
    if missing:
        raise ValueError(
            f"{spec!r} is not a fixed policy: it needs reset(seed) and act(observation, info) (no {', '.join(missing)})"
        )


def policy_name(policy: Any) -> str:
    """``module:qualname`` of ``policy``'s class (how errors name a policy)."""
    return f"{type(policy).__module__}:{type(policy).__qualname__}"


def checked_policy_action(policy: Any, agent: str, action: Any, num_actions: int = NUM_ACTIONS) -> int:
    """``action`` (what ``policy`` chose for ``agent``) as an ``int``, or a ``ValueError`` naming the
    policy: a fixed policy is held to the same rule as every action (never truncated)."""
    try:
        return check_action(agent, action, num_actions)
    except ValueError as error:
        raise ValueError(f"fixed policy {policy_name(policy)} of {agent} chose an invalid action: {error}") from None


def batched(policy: FixedPolicy, num_envs: int, agent: str = "a fixed agent") -> BatchedPolicy:
    """The policy acting for ``num_envs`` environments as ``agent`` (its own fast path when it has one)."""
    if hasattr(policy, "batched"):
        return policy.batched(num_envs)
    return _PolicyCopies(policy, num_envs, agent)


# ---------------------------------------------------------------------------- the context
def policy_context(engine: GridEngine, env_id: int, agent: int, info: Mapping[str, Any], with_positions: bool) -> dict[str, Any]:
    """The context (see :class:`FixedPolicy`) of agent index ``agent`` in environment ``env_id``
    of ``engine``, whose ``infos`` entry after the last step is ``info``."""
    context = {**info, "step": int(engine.t[env_id]), "agent": engine.agents[agent], "size": engine.size}
    if with_positions:
        cells = engine.pos[env_id].tolist()
        present = engine.present[env_id].tolist()
        context["positions"] = {name: tuple(cells[i]) for i, name in enumerate(engine.agents) if present[i]}
    return context


# ---------------------------------------------------------------------------- checkpoints
def unsaved_policy(policy: Any) -> Any | None:
    """What a checkpoint of ``policy`` would lose: ``None`` when it has ``state``/``load_state``
    or declares ``stateless = True``, else the policy lacking them (for the per-environment
    copies of the generic batched path, the copied policy)."""
    if isinstance(policy, _PolicyCopies):
        return unsaved_policy(policy.copies[0]) if policy.copies else None
    if getattr(policy, "stateless", False) is True:
        return None
    if callable(getattr(policy, "state", None)) and callable(getattr(policy, "load_state", None)):
        return None
    return policy


def policy_state(policy: Any) -> Any:
    """``policy.state()``, checked to be plain data (``{}`` for a stateless policy without one);
    a policy that saves no state raises ``ValueError`` naming it."""
    if unsaved_policy(policy) is not None:
        raise ValueError(
            f"fixed policy {policy_name(unsaved_policy(policy))} saves no state: give it state() and "
            "load_state(state), or declare stateless = True (see empathy_zoo.policies.FixedPolicy)"
        )
    if not callable(getattr(policy, "state", None)):
        return {}
    state = policy.state()
    problem = plain_data_problem(state, arrays=True)
    if problem:
        raise ValueError(f"state() of fixed policy {policy_name(policy)} is not plain data: {problem}")
    return state


def load_policy_state(policy: Any, state: Any) -> None:
    """Give ``policy`` the ``state`` :func:`policy_state` took."""
    if callable(getattr(policy, "load_state", None)):
        policy.load_state(state)
    elif state != {}:
        raise ValueError(f"fixed policy {policy_name(policy)} has no load_state() for its saved state")


PLAIN_SCALARS = (type(None), bool, int, float, str)
"""Scalars plain data may hold."""


def plain_data_problem(value: Any, arrays: bool, where: str = "the value") -> str | None:
    """What keeps ``value`` from being plain data (numbers, strings, booleans, ``None``, lists,
    tuples, dicts with string keys, and numeric numpy arrays and scalars when ``arrays``), or
    ``None`` when it is."""
    if isinstance(value, PLAIN_SCALARS) or (arrays and isinstance(value, np.generic) and value.dtype.kind in "biuf"):
        return None
    if arrays and isinstance(value, np.ndarray):
        return None if value.dtype.kind in "biuf" else f"{where} is an array of {value.dtype}"
    if isinstance(value, (list, tuple)):
        return next((p for i, item in enumerate(value) if (p := plain_data_problem(item, arrays, f"{where}[{i}]"))), None)
    if isinstance(value, Mapping):
        for key, item in value.items():
            if not isinstance(key, str):
                return f"{where} has a key {key!r} that is not a string"
            problem = plain_data_problem(item, arrays, f"{where}[{key!r}]")
            if problem:
                return problem
        return None
    allowed = "numbers, strings, booleans, None, lists and tables" + (", numeric numpy arrays" if arrays else "")
    return f"{where} is a {type(value).__module__}.{type(value).__qualname__} (plain data is {allowed})"


def check_allowed_imports_named(allowed_imports: Collection[str], labels: Iterable[Any], where: str) -> None:
    """Refuse (``ValueError`` naming it) a name of ``allowed_imports`` (``--allow-import``) that no
    partner label of ``labels`` (those recorded in ``where``, and any given on the command line)
    names as its policy: it would allow nothing, and a misspelt one would leave the intended
    plug-in refused without a word. A label that does not parse names nothing here (its reader
    refuses it)."""
    if not allowed_imports:
        return
    named = set()
    for label in labels:
        try:
            named.add(entry_policy_name(parse_entry_label(label) if isinstance(label, str) else label))
        except (ValueError, KeyError, TypeError):
            continue
    unused = sorted(set(allowed_imports) - named)
    if unused:
        plugins = sorted(name for name in named if ":" in name)
        raise ValueError(
            f"--allow-import {unused[0]}: no partner {where} names it, so it allows nothing "
            f"(plug-in partners named there: {', '.join(plugins) if plugins else 'none'})"
        )


def entry_policy_name(entry: PolicyEntry) -> str:
    """The policy name of a policy entry (a registered name or ``package.module:ClassName``)."""
    return entry if isinstance(entry, str) else str(entry["policy"])


def checked_entry(label: Any, allowed_imports: Collection[str] | None = None) -> PolicyEntry:
    """The policy entry ``label`` records (a label, :func:`parse_entry_label`, or an entry,
    :func:`policy_entry`), checked by the rule every fixed policy is built by
    (:func:`~empathy_zoo.policy_parameters.check_policy`), importing and building nothing: a
    registered policy with arguments it takes, of their type and range, every partner it names
    registered; or a ``package.module:Name`` (with any arguments, unchecked until it is imported)
    when ``allowed_imports`` is ``None`` (kept as text) or holds it. Otherwise ``ValueError``
    (:class:`~empathy_zoo.policy_parameters.UnlistedPlugin` for a ``package.module:Name`` not allowed)."""
    entry = parse_entry_label(label) if isinstance(label, str) else policy_entry(label)
    arguments = {} if isinstance(entry, str) else {key: value for key, value in entry.items() if key != "policy"}
    check_policy(entry_policy_name(entry), arguments, allowed_imports)
    return entry


def recorded_entry(label: Any, where: str, allowed_imports: Collection[str] = ()) -> PolicyEntry:
    """The policy entry a file records as ``label``, checked by :func:`checked_entry` to be a
    registered policy it may build or one of ``allowed_imports``: a file is data, so a
    ``package.module:Name`` it records is never imported unless the user named it
    (``--allow-import``). Otherwise ``ValueError`` naming ``where`` (the file and field) and what
    to do; nothing is imported."""
    try:
        return checked_entry(label, allowed_imports)
    except UnlistedPlugin as error:
        raise ValueError(
            f"{where} names fixed policy {error.name!r}, which is not registered: a file never makes the suite import "
            f"code; if you trust that module, pass --allow-import {error.name} (or name the policy yourself: --fixed AGENT=POLICY)"
        ) from None
    except ValueError as error:
        raise ValueError(f"{where}: {error}") from None


MAX_LABEL_CHARS = 4_096
"""The longest fixed policy's label read back (a population of 16 members takes a few hundred)."""


def _no_constant(name: str) -> Any:
    """Refuse JSON's non-standard constants (``NaN``, ``Infinity``) in a label's values."""
    raise ValueError(f"{name} is no number a policy takes")


def parse_entry_label(label: str) -> PolicyEntry:
    """The policy entry whose :func:`~empathy_zoo.policies.entry_label` is ``label`` (what a result
    file's ``config.fixed`` records): ``"patrol"`` → ``"patrol"``, ``"patrol(period=3)"`` →
    ``{"policy": "patrol", "period": 3}``; ``ValueError`` for a label no entry gives, or one longer
    than :data:`MAX_LABEL_CHARS` (its message shows the label's start only)."""
    if not isinstance(label, str) or not label:
        raise ValueError(f"a fixed policy's label is a non-empty string, got {label!r:.80}")
    if len(label) > MAX_LABEL_CHARS:
        raise ValueError(
            f"a fixed policy's label is at most {MAX_LABEL_CHARS:,} characters, got {len(label):,} ({label[:40]!r}...)"
        )
    if not label.endswith(")"):
        if "(" in label or ")" in label:
            raise ValueError(f"{label!r:.80} is not a fixed policy's label (name or name(argument=value, ...))")
        return policy_entry(label)
    name, bracket, body = label[:-1].partition("(")
    if not bracket or not name:
        raise ValueError(f"{label!r:.80} is not a fixed policy's label (name or name(argument=value, ...))")
    decoder = json.JSONDecoder(parse_constant=_no_constant)
    entry: dict[str, Any] = {"policy": name}
    position = 0
    while position < len(body):
        equals = body.find("=", position)
        key = body[position:] if equals < 0 else body[position:equals]
        if equals < 0 or not key.isidentifier():
            raise ValueError(f"{label!r:.80} is not a fixed policy's label: expected argument=value at {body[position:]!r:.40}")
        try:
            value, end = decoder.raw_decode(body, equals + 1)
        except (json.JSONDecodeError, RecursionError, ValueError) as error:
            why = "nested too deep" if isinstance(error, RecursionError) else str(error)
            raise ValueError(f"{label!r:.80} is not a fixed policy's label: the value of {key!r} is not JSON ({why})") from None
        entry[key] = value
        if end < len(body) and not body.startswith(", ", end):
            raise ValueError(f"{label!r:.80} is not a fixed policy's label: expected ', ' after the value of {key!r}")
        position = end + 2 if end < len(body) else end
    parsed = policy_entry(entry)
    if entry_label(parsed) != label:
        raise ValueError(f"{label!r:.80} is not a fixed policy's label (it reads back as {entry_label(parsed)!r:.80})")
    return parsed
