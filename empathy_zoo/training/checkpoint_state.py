"""The environments' state in an ensemble's checkpoint, checked against what its runs would hold.

:func:`check_vector` compares every array of the state of a checkpoint's vector env with the
arrays an environment built with the runs' arguments holds (reset and stepped once): the same
names, dtypes and shapes for the checkpoint's number of runs; every cell on the grid, every clock
within ``max_cycles``, when an agent left and what it collected or harmed within its episode's
clock, its returns within the clock times its engine's largest reward a step, every episode
running (a checkpoint is taken after ended episodes reset); the random streams
(:class:`empathy_zoo.randomness.EnvStreams`) a PCG64 state, the seed each run's training
environments are given, uniform numbers in ``[0, 1)`` and where the next one is; the
last step's events; the observations to act on those of the environments, of their size and range.
Without the runs' settings (no list of runs beside the checkpoint) the same is checked against the
checkpoint's own other fields and the bounds of every run. :func:`bit_generator_problem` checks any
numpy bit generator's state (:func:`rng_states` finds them). Numbers are compared exactly
(:func:`number`): an ``int`` of any size is never made a float.

What is wrong raises :class:`ForgedState`, naming the field; the caller names the checkpoint.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Iterator, Mapping
from dataclasses import asdict, fields
from typing import Any

import numpy as np

from empathy_zoo.actions import Action
from empathy_zoo.engine.base import StepEvents
from empathy_zoo.environments import ENGINES, ENVIRONMENT_TABLE
from empathy_zoo.limits import MAX_CYCLES, MAX_SEED
from empathy_zoo.randomness import STREAMS, derive_key
from empathy_zoo.safe_data import from_safe

__all__ = ["ForgedState", "bit_generator_problem", "check_vector", "number", "rng_states", "shown"]

FLOAT_MAX = sys.float_info.max
"""The largest finite float: a number past it (an ``int`` such as ``10**400``) is no value a result file holds."""


def number(value: Any, low: float | None = None, high: float | None = None, whole: bool = False) -> bool:
    """Whether ``value`` is a number a float holds (an ``int`` where ``whole``) in ``[low, high]``:
    an ``int`` of any size is compared exactly, never made a float (``math.isfinite`` and ``float``
    raise ``OverflowError`` past 1.8e308)."""
    if isinstance(value, bool) or not isinstance(value, int if whole else (int, float)):
        return False
    if isinstance(value, float) and not math.isfinite(value):
        return False
    if not -FLOAT_MAX <= value <= FLOAT_MAX:  # (exact: an int is compared with a float, never made one)
        return False
    return (low is None or value >= low) and (high is None or value <= high)


def shown(value: Any) -> str:
    """``value`` for a message, an integer of many digits by its number of digits."""
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) >= 10**30:  # (str() refuses 4,300 digits)
        return f"an integer of {value.bit_length():,} bits"
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def rng_states(value: Any, where: str) -> Iterator[tuple[str, Any]]:
    """Every state of a numpy bit generator in ``value`` (a table with a ``bit_generator``), with where it is."""
    if isinstance(value, dict):
        if "bit_generator" in value:
            yield where, value
            return
        for key, item in value.items():
            yield from rng_states(item, f"{where}.{key}" if where else str(key))
    elif isinstance(value, list):
        for index, item in enumerate(value):
            yield from rng_states(item, f"{where}[{index}]")


def bit_generator_problem(state: Any) -> str:
    """What is wrong with the state of a numpy bit generator (``""``: nothing): PCG64's (what every
    stream of the suite draws from) checked field by field, whole numbers of their widths and an
    odd increment, as numpy makes them; another kind is set on a new generator of its kind."""
    name = state.get("bit_generator") if isinstance(state, dict) else None
    if name in ("PCG64", "PCG64DXSM"):
        inner = state.get("state")
        if set(state) != {"bit_generator", "state", "has_uint32", "uinteger"} or not isinstance(inner, dict):
            return f"is no state of {name} (bit_generator, state, has_uint32, uinteger)"
        if set(inner) != {"state", "inc"} or not number(inner["state"], 0, 2**128 - 1, whole=True):
            return f"holds {shown(inner.get('state'))} as its state, no whole number of 128 bits"
        if not number(inner["inc"], 1, 2**128 - 1, whole=True) or inner["inc"] % 2 == 0:
            return f"holds {shown(inner['inc'])} as its increment, no odd whole number of 128 bits"
        if not number(state["has_uint32"], 0, 1, whole=True) or not number(state["uinteger"], 0, 2**32 - 1, whole=True):
            return f"holds has_uint32 {shown(state['has_uint32'])}, uinteger {shown(state['uinteger'])}: not 0 or 1 and 32 bits"
        return ""
    if name not in ("MT19937", "Philox", "SFC64"):
        return f"is the state of {shown(name)}, no numpy bit generator"
    if "has_gauss" in state and not (number(state["has_gauss"], 0, 1, whole=True) and number(state.get("gauss"))):
        return "holds has_gauss and gauss that are not 0 or 1 and a finite number"  # (numpy's global state)
    try:
        getattr(np.random, name)().state = from_safe({key: state.get(key) for key in ("bit_generator", "state")})
    except (ValueError, TypeError, KeyError, OverflowError, IndexError, AttributeError) as error:
        return f"is no state of {name} ({error})"
    return ""


class ForgedState(ValueError):
    """What is wrong with a checkpoint's environments, naming the field (:func:`check_vector`)."""


FLOAT32, FLOAT64 = np.zeros(0, np.float32), np.zeros(0, np.float64)
"""Arrays of the dtypes observations and uniform numbers have (what :func:`_array` compares with)."""
BOOLEAN = {"present": "b", "running": "b"}
"""The engine arrays of booleans (whether each agent is present, each episode running)."""
BASE_AGENT_ARRAYS = ("cells", "present", "inventory", "episode_return", "episode_battery_return", "episode_harms", "left_at")
"""The ``(N, A)`` arrays every engine's state holds (:meth:`empathy_zoo.engine.base.GridEngine.state`), and
``t``, ``running`` ``(N,)``."""


def _template(runs: Mapping[str, Any] | None) -> dict[str, Any] | None:
    """What the environments of the runs hold, from one built with their arguments, reset and
    stepped once: its state, events, observation size and range; ``None`` without the runs' settings."""
    if runs is None:
        return None
    try:
        engine = ENGINES[runs["env"]](1, **runs["env_kwargs"])
        engine.reset(np.zeros(1, dtype=np.int64), [0])
        events = asdict(engine.step(np.full((1, engine.num_agents), int(Action.STAY))))
    except (ValueError, TypeError, KeyError, RuntimeError):
        return None
    low, high = engine.obs_low, engine.obs_high
    return {
        "engine": engine.state(),
        "events": events,
        "obs_size": engine.obs_size,
        "range": (low, high),
        "block": engine.streams.block,
        "reward_bound": engine.step_reward_bound,
        "facts": ENVIRONMENT_TABLE.get(runs["env"]),
    }


def _engine_shape(key: str, array: Any, like: np.ndarray | None, runs: int, agents: int) -> tuple[int, ...]:
    """The shape engine array ``key`` has (``-1``: any size): ``like``'s for ``runs`` environments,
    else that of every engine's arrays, else ``runs`` environments of any further shape."""
    if like is not None:
        return (runs, *like.shape[1:])
    if key in BASE_AGENT_ARRAYS:
        return (runs, agents)
    if key in ("t", "running"):
        return (runs,)
    return (runs, *[-1] * (array.ndim - 1 if isinstance(array, np.ndarray) else 0))


def _array(value: Any, field: str, shape: tuple[int, ...], like: np.ndarray | None = None, kind: str = "") -> np.ndarray:
    """``value`` if it is an array of ``shape`` (``-1``: any size), of ``like``'s dtype (or of a dtype of ``kind``)."""
    if not isinstance(value, np.ndarray):
        raise ForgedState(f"{field} is no array")
    if value.ndim != len(shape) or any(want not in (-1, got) for want, got in zip(shape, value.shape, strict=True)):
        raise ForgedState(f"{field} has shape {value.shape}, not {tuple('any' if n < 0 else n for n in shape)}")
    if (like is not None and value.dtype != like.dtype) or (kind and value.dtype.kind not in kind):
        raise ForgedState(f"{field} has dtype {value.dtype}, not {like.dtype if like is not None else kind}")
    if value.dtype.kind == "f" and not np.isfinite(value).all():
        raise ForgedState(f"{field} holds a value that is no finite number")
    return value


def _within(array: np.ndarray, field: str, low: Any, high: Any, what: str) -> None:
    if array.size and (np.any(array < low) or np.any(array > high)):
        raise ForgedState(f"{field} holds {array.min()} … {array.max()}, not within {what}")


def check_vector(saved: Any, obs: Any, runs: int, settings: Mapping[str, Any] | None, seeds: list[Any] | None) -> None:
    """The environments' state (see the module page), else :class:`ForgedState` naming the field."""
    try:
        state, observations = from_safe(saved), from_safe(obs)
    except (ValueError, TypeError, KeyError, AttributeError) as error:
        raise ForgedState(f"vector cannot be read ({error})") from None
    engine = state.get("engine") if isinstance(state, dict) else None
    if not isinstance(engine, dict):
        raise ForgedState("vector.engine is missing: it holds no state of its environments' engine")
    template = _template(settings)
    expected = template["engine"] if template else dict.fromkeys((*BASE_AGENT_ARRAYS, "t", "running", "streams"))
    missing, extra = sorted(set(expected) - set(engine)), sorted(set(engine) - set(expected)) if template else []
    if missing or extra:
        wrong = ", ".join([*(f"no {shown(key)}" for key in missing), *(shown(key) for key in extra)])
        raise ForgedState(f"vector.engine holds {wrong}: not the arrays of its environments' engine")
    cells = engine.get("cells")
    agents = cells.shape[1] if isinstance(cells, np.ndarray) and cells.ndim == 2 else -1
    for key, array in engine.items():
        if key != "streams":
            like = expected.get(key)
            _array(array, f"vector.engine.{key}", _engine_shape(key, array, like, runs, agents), like, BOOLEAN.get(key, ""))
    for key in ("cells", "t", "left_at", "inventory", "episode_harms"):
        _array(engine[key], f"vector.engine.{key}", engine[key].shape, kind="iu")
    t, agents = engine["t"], engine["cells"].shape[1]
    _within(engine["cells"], "vector.engine.cells", 0, settings["cells"] - 1 if settings else np.inf, "the grid's cells")
    _within(t, "vector.engine.t", 0, settings["max_cycles"] if settings else MAX_CYCLES, "[0, max_cycles] (the episodes' clocks)")
    _within(engine["left_at"], "vector.engine.left_at", 0, t[:, None], "[0, t] (when an agent left its episode)")
    if np.any(engine["present"] & (engine["left_at"] != 0)):
        raise ForgedState(
            "vector.engine.left_at holds a time for an agent still present (vector.engine.present): 0 until it leaves"
        )
    _within(engine["inventory"], "vector.engine.inventory", 0, t[:, None], "[0, t] (a battery a step at most)")
    _within(engine["episode_harms"], "vector.engine.episode_harms", 0, t[:, None] * (agents - 1), "[0, t·others] (harms)")
    facts = template["facts"] if template else None
    if facts is not None and not facts.batteries:  # (the environment table: no agent uses batteries)
        _within(engine["inventory"], "vector.engine.inventory", 0, 0, "0 (its environment has no batteries)")
    if facts is not None and not facts.can_harm:  # (no agent can be harmed)
        _within(engine["episode_harms"], "vector.engine.episode_harms", 0, 0, "0 (no agent of its environment can be harmed)")
    if not engine["running"].all():
        raise ForgedState("vector.engine.running holds False: a checkpoint is taken with every episode running")
    if template:
        bound = template["reward_bound"]
        for key in ("episode_return", "episode_battery_return"):
            limit = t[:, None] * bound
            _within(engine[key], f"vector.engine.{key}", -limit, limit, f"±t·{bound:g} (its engine's largest reward a step)")
    _check_streams(engine["streams"], runs, seeds, template["block"] if template else -1)
    _check_events(state.get("events"), runs, agents, template["events"] if template else None)
    _array(state.get("fresh"), "vector.fresh", (runs,), kind="b")
    size = template["obs_size"] if template else -1
    views = _array(state.get("observations"), "vector.observations", (runs, 1, size), FLOAT32)
    mine = _array(observations, "obs", (runs, views.shape[2]), FLOAT32)
    if not np.array_equal(mine, views[:, 0]):
        raise ForgedState("obs are not the observations of its environments (vector.observations)")
    if template:
        low, high = template["range"]
        _within(mine, "obs", low, high, f"[{low}, {high}] (its environments' observation values)")


def _check_streams(streams: Any, runs: int, seeds: list[Any] | None, block: int) -> None:
    """The environments' random streams (:class:`empathy_zoo.randomness.EnvStreams`): a PCG64 state
    and the seed its run's training environment is given per run, the numbers drawn and where
    the next one is."""
    if not isinstance(streams, dict) or set(streams) != {"bit_generators", "seeds", "buffer", "position"}:
        raise ForgedState("vector.engine.streams is no table of bit_generators, seeds, buffer and position")
    generators, given = streams["bit_generators"], streams["seeds"]
    if not isinstance(generators, list) or len(generators) != runs or not isinstance(given, list) or len(given) != runs:
        raise ForgedState(f"vector.engine.streams: bit_generators and seeds are no lists of {runs} (one per environment)")
    for i, generator in enumerate(generators):
        if not isinstance(generator, dict) or generator.get("bit_generator") != "PCG64":
            raise ForgedState(f"vector.engine.streams.bit_generators[{i}] is no state of PCG64")
    for i, seed in enumerate(given):
        wanted = (
            None if seeds is None or not number(seeds[i], 0, MAX_SEED, whole=True) else derive_key(seeds[i], STREAMS["train_env"])
        )
        if not number(seed, 0, 2**64 - 1, whole=True) or (wanted is not None and seed != wanted):
            raise ForgedState(
                f"vector.engine.streams.seeds[{i}] is {shown(seed)}, not the seed of its run's training environments"
            )
    buffer = _array(streams["buffer"], "vector.engine.streams.buffer", (runs, block), FLOAT64)
    _within(buffer, "vector.engine.streams.buffer", 0.0, np.nextafter(1.0, 0.0), "[0, 1) (uniform numbers)")
    position = _array(streams["position"], "vector.engine.streams.position", (runs,), kind="iu")
    _within(position, "vector.engine.streams.position", 0, buffer.shape[1], f"[0, {buffer.shape[1]}] (its buffer's numbers)")
    if buffer.shape[1] < 1:
        raise ForgedState("vector.engine.streams.buffer holds no numbers")


def _check_events(events: Any, runs: int, agents: int, template: Mapping[str, np.ndarray] | None) -> None:
    """The last step's events (:class:`empathy_zoo.engine.base.StepEvents`) of every environment."""
    names = [field.name for field in fields(StepEvents)]
    if not isinstance(events, dict) or sorted(events) != sorted(names):
        raise ForgedState(f"vector.events is no table of the last step's {', '.join(names)}")
    for name, array in events.items():
        like = template[name] if template else None
        shape = (runs, *like.shape[1:]) if like is not None else (runs,) if name == "episode_over" else (runs, agents)
        _array(array, f"vector.events.{name}", shape, like, "iu" if name == "harmed_by" else "")
    _within(events["harmed_by"], "vector.events.harmed_by", -1, agents - 1, f"[-1, {agents - 1}] (an agent, or nobody)")
