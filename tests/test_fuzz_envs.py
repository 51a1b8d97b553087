"""Property-based attack on both environments through every face (parallel, AEC, FixedAgents,
EmpathyWrapper, the vector env, the Gymnasium adapter): random sizes within the limits, options,
seeds and actions, valid and invalid. Every call either works or raises ``ValueError`` /
``RuntimeError`` (nothing else), and after a rejected call the env is exactly what it was: its
whole state is unchanged, and a twin that never saw the rejected calls answers the same from then on.

Seeded (``derandomize``): the same examples on every run. ``-m slow`` runs a longer variant.
"""

from __future__ import annotations

import warnings
from collections import Counter
from typing import Any

import numpy as np
import pytest
from helpers_envs import env_state, same
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from empathy_zoo import EmpathyWrapper, FixedAgents, coexistence_v0, sharing_v0
from empathy_zoo.engine.base import MAX_SIZE
from empathy_zoo.environments import DEFAULT_POLICIES
from empathy_zoo.gym_adapter import make_single_agent_env
from empathy_zoo.vector import VectorEnv

MODULES = {"coexistence_v0": coexistence_v0, "sharing_v0": sharing_v0}
MIN_SIZE = {"coexistence_v0": 5, "sharing_v0": 3}
FACES = ("parallel", "aec", "fixed", "empathy", "empathy_parallel", "vector", "gym")
TALLY: Counter[str] = Counter()
"""What the attack tried (printed at the end of the module with ``-s``)."""


def make_face(face: str, name: str, size: int, view: int, max_cycles: int) -> Any:
    module, grid = MODULES[name], {"size": size, "view": view, "max_cycles": max_cycles}
    fixed = DEFAULT_POLICIES[name]
    if face == "parallel":
        return module.parallel_env(**grid)
    if face == "aec":
        return module.env(**grid)
    if face == "fixed":
        return FixedAgents(module.parallel_env(**grid), fixed)
    if face == "empathy":
        return EmpathyWrapper(FixedAgents(module.parallel_env(**grid), fixed))
    if face == "empathy_parallel":
        return EmpathyWrapper(module.parallel_env(**grid))
    if face == "vector":
        return VectorEnv(name, 3, fixed=fixed, **grid)
    return make_single_agent_env(name, **grid)


# ---------------------------------------------------------------------------- generated input
GOOD_ACTION = st.integers(0, 4)
BAD_ACTION = st.sampled_from([-1, 5, 9, 2.5, 1.0, "1", None, True, np.float32(2), np.int64(7), [1], {}, np.array([1])])
ACTION = st.one_of(GOOD_ACTION, GOOD_ACTION, GOOD_ACTION, BAD_ACTION)
SEED = st.one_of(st.none(), st.integers(0, 2**32), st.sampled_from([-1, 1.5, "3", True]))


def cell(size: int) -> st.SearchStrategy:
    good = st.tuples(st.integers(0, size - 1), st.integers(0, size - 1))
    bad = st.sampled_from([(size, 0), (0, -1), (1.5, 2), (float("inf"), 0), (float("nan"), 1), "12", (1, 2, 3), None, 5])
    return st.one_of(good, good, good, bad)


@st.composite
def options(draw: st.DrawFn, name: str, size: int) -> Any:
    agents = list(MODULES[name].parallel_env().possible_agents)
    if draw(st.integers(0, 9)) == 0:
        return draw(st.sampled_from(["positions", [("positions", {})], 3]))
    chosen = {}
    names = st.one_of(st.sampled_from(agents), st.just("dog_0"))
    for agent in draw(st.lists(names, max_size=3)):
        chosen[agent] = draw(cell(size))
    result: dict[str, Any] = {"positions": chosen if draw(st.booleans()) else list(chosen.items())}
    if name == "sharing_v0" and draw(st.booleans()):
        result["batteries"] = draw(st.lists(cell(size), max_size=4))
    return result


@st.composite
def calls(draw: st.DrawFn, face: str, name: str, size: int) -> list[tuple[str, Any]]:
    program = []
    for _ in range(draw(st.integers(1, 25))):
        kind = draw(st.sampled_from(["step"] * 6 + ["reset", "reset_options"]))
        if kind == "reset":
            program.append(("reset", (draw(SEED), None)))
        elif kind == "reset_options":
            program.append(("reset", (draw(st.integers(0, 99)), draw(options(name, size)))))
        elif face == "vector":
            shape = draw(st.sampled_from([(3, 1), (3, 1), (3, 1), (3,), (2, 1), (3, 2)]))
            dtype = draw(st.sampled_from([np.int64, np.int64, np.int32, np.float64, np.bool_]))
            values = draw(st.lists(st.integers(-1, 5), min_size=int(np.prod(shape)), max_size=int(np.prod(shape))))
            program.append(("step", (np.array(values).reshape(shape).astype(dtype), 0)))
        else:
            program.append(("step", (draw(ACTION), draw(st.integers(0, 9)))))
    return program


# ---------------------------------------------------------------------------- driving a face
def joint_action(env: Any, face: str, action: Any, twist: int) -> Any:
    """The action of a step on ``face``; ``twist`` sometimes breaks the dict around it."""
    if face == "gym":
        return action
    if face == "aec":
        if not env.agents:
            return action
        agent = env.agent_selection
        done = env.terminations[agent] or env.truncations[agent]
        return (None if twist else action) if done else action
    agents = list(env.agents)
    actions = {agent: action if i == 0 else twist % 5 for i, agent in enumerate(agents)}
    if twist == 7:
        actions.pop(agents[0], None) if agents else None
    if twist == 8:
        actions["dog_0"] = 1
    if twist == 9:
        return list(actions.values())
    return actions


def call(env: Any, face: str, kind: str, argument: Any) -> Any:
    if kind == "reset":
        seed, option = argument
        if face == "vector":
            return env.reset(seed=seed)
        return env.reset(seed=seed, options=option)
    if face == "vector":
        return env.step(argument[0])
    return env.step(joint_action(env, face, *argument))


def outcome(env: Any, face: str, kind: str, argument: Any) -> tuple[str, Any]:
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # (unknown reset options are ignored with a warning)
            answer = call(env, face, kind, argument)
    except (ValueError, RuntimeError) as error:
        return "rejected", type(error).__name__
    return "accepted", (env.last() if env.agents else None) if face == "aec" else answer


@st.composite
def scenario(draw: st.DrawFn) -> tuple[str, str, int, int, int, list]:
    face, name = draw(st.sampled_from(FACES)), draw(st.sampled_from(sorted(MODULES)))
    size = draw(st.one_of(st.integers(MIN_SIZE[name], 13), st.integers(14, 41), st.just(MAX_SIZE)))
    view = draw(st.sampled_from([v for v in (1, 3, 5, 7, 9) if v < size]))
    max_cycles = draw(st.integers(1, 12))
    return face, name, size, view, max_cycles, draw(calls(face, name, size))


def episode_over(env: Any, face: str) -> bool:
    if face == "vector":
        return False  # (it resets finished episodes itself)
    if face == "gym":
        return not env._running
    return not env.agents


def attack(face: str, name: str, size: int, view: int, max_cycles: int, program: list) -> None:
    """Play ``program`` on a face and on its twin, which gets only the calls the face accepted.
    The first call is a seeded reset, so ``reset()`` without a seed continues seeded streams; a
    step after the end of an episode starts a new one first, except one in ten (which must fail)."""
    env, twin = make_face(face, name, size, view, max_cycles), make_face(face, name, size, view, max_cycles)
    TALLY["programs"] += 1
    for kind, argument in [("reset", (size, None)), *program]:
        if kind == "step" and episode_over(env, face) and argument[1] != 6:
            for e in (env, twin):
                e.reset()
            TALLY["reset between episodes"] += 1
        before = env_state(env)
        result, answer = outcome(env, face, kind, argument)
        TALLY[f"{kind} {result}"] += 1
        if result == "rejected":
            assert same(env_state(env), before), (face, kind, argument, answer)
            continue
        twin_result, twin_answer = outcome(twin, face, kind, argument)
        assert twin_result == "accepted" and same(answer, twin_answer), (face, kind, argument)
        assert same(env_state(env), env_state(twin))


@settings(max_examples=120, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(scenario())
def test_every_face_accepts_or_refuses_and_a_refusal_changes_nothing(case):
    attack(*case)


@pytest.mark.slow
@settings(max_examples=3000, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(scenario())
def test_every_face_accepts_or_refuses_and_a_refusal_changes_nothing_long(case):
    attack(*case)


@pytest.fixture(scope="module", autouse=True)
def report_tally():
    yield
    if TALLY:
        print(f"\nenv fuzz: {dict(sorted(TALLY.items()))}")
