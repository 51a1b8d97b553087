"""A fixed policy gets one context on every path (FixedAgents over the PettingZoo env, the vector
env, training): the same keys and values step by step for the same seeds; a policy asking for the
true state gets every agent's position (a chaser finds the robot outside its window); and a sweep
file builds a fixed agent with keyword arguments."""

from __future__ import annotations

import json
import tomllib

import numpy as np
import pytest
from helpers_policies import Recorder

import empathy_zoo.training.ensemble as ensemble
from empathy_zoo import FixedAgents, coexistence_v0, sharing_v0
from empathy_zoo.actions import NUM_ACTIONS, Action
from empathy_zoo.experiment.model import RunSpec
from empathy_zoo.experiment.sweep_file import parse_sweep
from empathy_zoo.experiment.values import SweepConfigError
from empathy_zoo.policies import CONTEXT_KEYS, make_policy
from empathy_zoo.randomness import derive_key
from empathy_zoo.training import RunnerOptions, train_runs
from empathy_zoo.vector import VectorEnv

HELPERS = Recorder.__module__  # "helpers_policies", importable because pytest puts tests/ on the path
FIXED = {
    "coexistence_v0": ("cat_0", coexistence_v0, {"harmed_by", "harmed"}),
    "sharing_v0": ("human_0", sharing_v0, {"batteries"}),
}
"""Per environment: the fixed agent, the module, and the keys of its ``infos`` entry."""
RECORDERS = [f"{HELPERS}:Recorder", f"{HELPERS}:RecorderWithState"]


def shown(contexts: list[dict]) -> list[str]:
    """Contexts as text that tells values of different types apart (``3`` from ``np.int64(3)``)."""
    return [repr(sorted(context.items())) for context in contexts]


def fixed_agents_contexts(env: str, policy: str, seed: int, robot_actions, **env_kwargs) -> list[dict]:
    """What ``policy`` is given through FixedAgents from ``reset(seed=seed)`` on, the robot taking
    ``robot_actions`` (a reset without a seed after each episode, as the vector env's autoreset)."""
    agent, module, _ = FIXED[env]
    recorder = make_policy(policy)
    parallel = FixedAgents(module.parallel_env(**env_kwargs), {agent: recorder})
    parallel.reset(seed=seed)
    for action in robot_actions:
        if not parallel.agents:
            parallel.reset()
        parallel.step({"robot_0": int(action)})
    return recorder.seen


@pytest.mark.parametrize("policy", RECORDERS, ids=["context", "with_state"])
@pytest.mark.parametrize("env", sorted(FIXED))
def test_fixed_agents_and_the_vector_env_give_equal_contexts(env, policy):
    agent, _, info_keys = FIXED[env]
    seeds, steps = [3, 4, 5], 200
    actions = np.random.default_rng(1).integers(NUM_ACTIONS, size=(steps, len(seeds), 1))
    venv = VectorEnv(env, len(seeds), fixed={agent: policy}, max_cycles=30)
    venv.reset(seed=seeds)
    for step in actions:
        venv.step(step)
    copies = venv.fixed[venv.agents.index(agent)].copies
    keys = {*CONTEXT_KEYS, *info_keys} | ({"positions"} if policy.endswith("WithState") else set())
    for i, seed in enumerate(seeds):
        vector = copies[i].seen
        assert len(vector) > 30 and all(set(context) == keys for context in vector)
        assert shown(vector) == shown(fixed_agents_contexts(env, policy, seed, actions[:, i, 0], max_cycles=30))
    episodes = [context for copy in copies for context in copy.seen if context["step"] == 0]
    assert len(episodes) > len(seeds), "the comparison should span autoresets"


def test_training_gives_the_policy_the_same_contexts_as_fixed_agents(tmp_path, monkeypatch):
    """The policy inside training (an ensemble of one run) sees what FixedAgents shows it when
    replaying the robot's actions from the same environment seed."""
    built, taken = [], []

    class Watched(VectorEnv):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            built.append(self)

        def step(self, actions):
            taken.append(int(np.asarray(actions).reshape(-1)[0]))
            return super().step(actions)

    monkeypatch.setattr(ensemble, "VectorEnv", Watched)
    policy = f"{HELPERS}:RecorderWithState"
    spec = RunSpec.of(
        settings={"learning_starts": 32, "replay_capacity": 200, "hidden_size": 8},
        seed=2,
        steps=120,
        eval_interval=120,
        eval_episodes=1,
        fixed={"cat_0": policy},
        env_kwargs={"max_cycles": 30},
    )
    train_runs([spec], tmp_path, RunnerOptions(progress=False, checkpoint_interval=50))
    [venv] = built
    [trained] = venv.fixed[venv.agents.index("cat_0")].copies
    assert len(taken) == 120 and len(trained.seen) > 30
    replayed = fixed_agents_contexts("coexistence_v0", policy, derive_key(2, ensemble.STREAM_ENV), taken, max_cycles=30)
    assert shown(trained.seen) == shown(replayed)


def torus_distance(a, b, size: int) -> int:
    return sum(min((x - y) % size, (y - x) % size) for x, y in zip(a, b, strict=True))


def test_a_chaser_that_asks_for_positions_walks_to_a_robot_it_cannot_see():
    size = 11
    env = FixedAgents(coexistence_v0.parallel_env(size=size), {"cat_0": f"{HELPERS}:Chaser"})
    env.reset(seed=0, options={"positions": {"robot_0": (0, 0), "cat_0": (5, 6)}})
    engine = env.unwrapped.engine
    distances = [torus_distance(*engine.pos[0].tolist(), size)]
    harmed = False
    while not harmed:
        _, _, _, _, infos = env.step({"robot_0": int(Action.STAY)})
        harmed = infos["robot_0"]["harmed"] != [] or infos["robot_0"]["harmed_by"] is not None
        distances.append(torus_distance(*engine.pos[0].tolist(), size))
    assert distances[0] == 10 and distances[:-1] == list(range(10, 10 - len(distances) + 1, -1)), distances


def test_a_chaser_in_the_vector_env_closes_in_on_the_robot():
    size = 11
    venv = VectorEnv("coexistence_v0", 8, fixed={"cat_0": f"{HELPERS}:Chaser"}, size=size)
    venv.reset(seed=0)
    engine = venv.engine
    for _ in range(4):
        before = [torus_distance(*pos, size) for pos in engine.pos.tolist()]
        step = venv.step(np.full((8, 1), int(Action.STAY)))
        after = [torus_distance(*pos, size) for pos in engine.pos.tolist()]
        for i in np.flatnonzero(~step.episode_over & engine.present[:, 1]):
            assert after[i] == before[i] - 1, (i, before[i], after[i])


SWEEP = """
[sweep]
seeds = 1
steps = 100

[envs.coexistence_v0]
fixed = {fixed}

[[methods]]
method = "dqn"
"""


def sweep(fixed: str):
    return parse_sweep(tomllib.loads(SWEEP.format(fixed=fixed)), source="chase.toml")


def test_a_sweep_builds_a_fixed_agent_with_keyword_arguments():
    [every_two] = sweep(f'{{ cat_0 = {{ policy = "{HELPERS}:Chaser", every = 2 }} }}')
    [every_three] = sweep(f'{{ cat_0 = {{ policy = "{HELPERS}:Chaser", every = 3 }} }}')
    assert every_two.fixed_policies() == {"cat_0": {"policy": f"{HELPERS}:Chaser", "every": 2}}
    assert every_two.config()["fixed"] == {"cat_0": f"{HELPERS}:Chaser(every=2)"}
    assert every_two.run_id != every_three.run_id
    venv = VectorEnv("coexistence_v0", 1, fixed=every_two.fixed_policies())
    assert venv.fixed[1].copies[0].every == 2


def test_a_string_entry_and_an_entry_without_arguments_are_the_same_run():
    [named] = sweep('{ cat_0 = "random_walk" }')
    [table] = sweep('{ cat_0 = { policy = "random_walk" } }')
    [default] = sweep("{}")
    assert named.config()["fixed"] == {"cat_0": "random_walk"} == table.config()["fixed"]
    assert named.variant.fixed == table.variant.fixed == {"cat_0": "random_walk"}
    assert named.run_id == table.run_id == default.run_id


def test_a_run_spec_with_arguments_keeps_its_id_through_its_record():
    spec = RunSpec.of(fixed={"cat_0": {"policy": f"{HELPERS}:Chaser", "every": 2}})
    record = json.loads(json.dumps(spec.request()))
    assert RunSpec.of(**record).run_id == spec.run_id


@pytest.mark.parametrize(
    "entry, names",
    [
        (f'{{ policy = "{HELPERS}:Chaser", speed = 2 }}', ["takes no argument 'speed'", "its arguments: target, every"]),
        ("{ every = 2 }", ["missing key 'policy'"]),
        ("{ policy = 3 }", ["'policy' must be a policy name"]),
        (f'{{ policy = "{HELPERS}:Chaser", every = 0 }}', ["every must be positive"]),
        (f'{{ policy = "{HELPERS}:Chaser", every = 1979-05-27 }}', ["argument 'every'", "datetime.date"]),
        ('{ policy = "teleport", every = 2 }', ["unknown fixed policy 'teleport'"]),
    ],
)
def test_bad_arguments_name_file_table_and_key(entry, names):
    with pytest.raises(SweepConfigError) as refused:
        sweep(f"{{ cat_0 = {entry} }}")
    message = str(refused.value)
    for part in ("chase.toml: [envs.coexistence_v0] fixed.cat_0: ", *names):
        assert part in message, message
