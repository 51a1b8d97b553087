"""Agent files: a trained run's networks kept, read back with ``weights_only=True``, acting and
valuing exactly as the learner did, refused when changed or not an agent file, and usable as a
fixed policy."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import numpy as np
import pytest
import torch

from agents.empathic_dqn import EmpathicDQN
from agents.settings import EmpathicDQNSettings
from baselines.registry import METHODS
from empathy_zoo import FixedAgents, TrainedAgent, coexistence_v0, load_agent
from empathy_zoo.agent_file import FORMAT, agent_path, file_sha256, write_agent_file
from empathy_zoo.policies import FixedPolicy, make_policy
from empathy_zoo.run_ids import run_id
from empathy_zoo.training.ensemble import learner_batch
from empathy_zoo.vector import VectorEnv

TINY = {"learning_starts": 64, "replay_capacity": 2_000, "epsilon_decay_steps": 300, "target_update_interval": 50}
BETAS = (0.5, 1.0, 0.25)
HEADER = {"method": "empathic_dqn", "env": "coexistence_v0"}
STEPS = 300


def header(run: int, beta: float, method: str = "empathic_dqn") -> dict:
    """Run ``run``'s header: its run id the one its fields give (ending with its seed), as the trainer writes it."""
    fields = {
        **HEADER,
        "method": method,
        "settings": {**TINY, "selfishness": beta},
        "env_kwargs": {"max_cycles": 60},
        "seed": run,
    }
    return {"run_id": run_id("coexistence_v0", method, fields, run), **fields}


def drive(learner, venv: VectorEnv, steps: int, seed: int = 0) -> np.ndarray:
    """Train ``learner`` ``steps`` steps on ``venv`` (one env per run) as the trainer does; every
    observation it acted on, ``(steps·K, V)``."""
    k = venv.num_envs
    obs = venv.reset(seed=seed)[:, 0]
    seen = [obs]
    for _ in range(steps):
        actions = learner.act(obs[:, None, :])
        result = venv.step(actions.reshape(k, 1))
        learner.observe(learner_batch(obs, actions, result))
        obs = result.observations[:, 0]
        seen.append(obs)
    return np.concatenate(seen)


def probe_observations(seen: np.ndarray, count: int = 500) -> np.ndarray:
    """What the robot saw in training, and random windows of the observation's values."""
    rng = np.random.default_rng(7)
    random = rng.integers(-1, 2, (count, seen.shape[1])).astype(np.float32)
    return np.concatenate([seen, random])


@pytest.fixture(scope="module")
def trained(tmp_path_factory) -> tuple[EmpathicDQN, np.ndarray, list[Path], list[str]]:
    venv = VectorEnv("coexistence_v0", len(BETAS), fixed={"cat_0": "random_walk"}, max_cycles=60)
    learner = EmpathicDQN([EmpathicDQNSettings(selfishness=b, **TINY) for b in BETAS], [0, 1, 2], venv.obs_size, venv.num_actions)
    seen = drive(learner, venv, STEPS)
    assert learner.grad_steps > 0
    out = tmp_path_factory.mktemp("runs")
    paths, hashes = [], []
    for run, beta in enumerate(BETAS):
        written = write_agent_file(learner, run, out / f"run{run}.agent.pt", header(run, beta))
        assert written is not None
        name, sha = written
        paths.append(out / name)
        hashes.append(sha)
    return learner, probe_observations(seen), paths, hashes


def learner_greedy(learner: EmpathicDQN, observations: np.ndarray) -> np.ndarray:
    """``(K, M)`` greedy actions of every run on the same ``M`` observations."""
    return learner.act(np.repeat(observations[None], learner.num_runs, axis=0), greedy=True)


def learner_values(learner: EmpathicDQN, observations: np.ndarray, which: str) -> np.ndarray:
    obs = torch.as_tensor(np.repeat(observations[None], learner.num_runs, axis=0))
    return learner.q_values(obs, which).numpy()


def test_a_loaded_agent_acts_exactly_as_its_run(trained) -> None:
    learner, observations, paths, hashes = trained
    greedy = learner_greedy(learner, observations)
    singles = [learner_greedy(learner, o[None])[:, 0] for o in observations[:150]]  # (one observation at a time, as in training)
    for run, (path, sha) in enumerate(zip(paths, hashes, strict=True)):
        agent = load_agent(path, expected_sha256=sha)
        assert np.array_equal(agent.act_batch(observations), greedy[run])
        assert [agent.act(o) for o in observations[:150]] == [int(s[run]) for s in singles]
    assert len({tuple(g) for g in greedy}) == len(BETAS), "the runs act differently: each file holds its own run"


def test_a_loaded_agent_gives_the_learners_values_bit_for_bit(trained) -> None:
    learner, observations, paths, _ = trained
    own, acting = learner_values(learner, observations, "q"), learner_values(learner, observations, "emp")
    for run, (path, beta) in enumerate(zip(paths, BETAS, strict=True)):
        values = load_agent(path).q_values(observations)
        assert set(values) == ({"q"} if beta == 1.0 else {"q", "q_emp"})
        assert values["q"].dtype == np.float32 and np.array_equal(values["q"], own[run])
        if beta < 1.0:
            assert np.array_equal(values["q_emp"], acting[run]) and not np.array_equal(values["q_emp"], values["q"])
        else:
            assert np.array_equal(values["q"], acting[run]), "DQN (β = 1) acts on Q"
        one = load_agent(path).q_values(observations[3])
        assert {name: v.shape for name, v in one.items()} == dict.fromkeys(values, (5,))
        assert all(np.array_equal(one[name], values[name][3]) for name in values)


def test_describe_says_what_the_agent_is(trained) -> None:
    _, _, paths, hashes = trained
    for run, (path, sha, beta) in enumerate(zip(paths, hashes, BETAS, strict=True)):
        d = load_agent(path).describe()
        assert d["method"] == "empathic_dqn" and d["env"] == "coexistence_v0" and d["env_kwargs"] == {"max_cycles": 60}
        assert d["settings"]["selfishness"] == beta and d["seed"] == run and d["run_id"].endswith(f"__s{run}")
        assert (d["obs_size"], d["num_actions"], d["layers"]) == (25, 5, [25, 128, 128, 5])
        assert d["heads"] == (["q"] if beta == 1.0 else ["q", "q_emp"])
        assert d["acting"] == ("q" if beta == 1.0 else "q_emp")
        assert d["file"] == str(path) and d["sha256"] == sha == file_sha256(path)


def test_the_file_is_small_plain_data_and_written_atomically(trained) -> None:
    learner, _, paths, hashes = trained
    document = torch.load(paths[0], weights_only=True)
    assert document["format"] == FORMAT and document["version"] == 1
    assert set(document) == {"format", "version", "header", "obs_size", "num_actions", "activation", "heads", "acting"}
    assert [tuple(t.shape) for t in document["heads"]["q_emp"]] == [(25, 128), (128,), (128, 128), (128,), (128, 5), (5,)]
    parameters = 4 * (25 * 128 + 128 + 128 * 128 + 128 + 128 * 5 + 5)  # float32 bytes of one head
    for path, beta in zip(paths, BETAS, strict=True):
        heads = 1 if beta == 1.0 else 2
        assert heads * parameters < path.stat().st_size < heads * parameters + 12_000  # the networks, nothing more
    assert not [p for p in paths[0].parent.iterdir() if p.name.startswith(".")], "no temporary file is left"
    again = write_agent_file(learner, 0, paths[0].parent / "again.agent.pt", header(0, BETAS[0]))
    assert again == ("again.agent.pt", hashes[0]), "the same run writes the same bytes"


def test_a_paper_sized_agent_file_is_a_few_hundred_kb(tmp_path) -> None:
    settings = [EmpathicDQNSettings(selfishness=b, replay_capacity=64, learning_starts=32) for b in (0.5, 1.0)]
    learner = EmpathicDQN(settings, [0, 1], 25, 5)  # MLP 25→128→128→5, the paper's
    sizes = []
    for run in range(2):
        name, _ = write_agent_file(learner, run, tmp_path / f"r{run}.agent.pt", header(run, settings[run].selfishness))
        sizes.append((tmp_path / name).stat().st_size)
    print(f"paper-sized agent files: Q and Q_emp {sizes[0]:,} bytes, Q alone (β = 1) {sizes[1]:,} bytes")
    head = 4 * (25 * 128 + 128 + 128 * 128 + 128 + 128 * 5 + 5)  # 81,940 bytes of float32 parameters
    assert sizes[0] < 2 * head + 8_192 and sizes[1] < head + 8_192  # 168,063 and 84,885 bytes (torch 2.13)


def test_a_changed_file_is_refused_naming_it_and_its_result_file(trained, tmp_path) -> None:
    _, observations, paths, hashes = trained
    data = bytearray(paths[0].read_bytes())
    data[len(data) // 2] ^= 0x01  # one bit of one weight
    changed = tmp_path / "run0.agent.pt"
    changed.write_bytes(bytes(data))
    with pytest.raises(ValueError, match=rf"agent file {changed}.*result file run0\.json records {hashes[0]}"):
        load_agent(changed, expected_sha256=hashes[0], result_file="run0.json")
    with pytest.raises(ValueError, match=rf"agent file {changed} has SHA-256"):
        load_agent(changed, expected_sha256=hashes[0])
    load_agent(changed)  # (still an agent file: only the recorded hash tells)
    assert load_agent(paths[0], expected_sha256=hashes[0].upper()).act(observations[0]) in range(5)


def test_what_is_not_an_agent_file_is_refused(tmp_path) -> None:
    cases = {
        "text.agent.pt": None,
        "checkpoint.agent.pt": {"online": [torch.zeros(2)], "env_steps": 3},
        "other.agent.pt": {"format": "something_else", "version": 1},
        "newer.agent.pt": {"format": FORMAT, "version": 99},
        "broken.agent.pt": {"format": FORMAT, "version": 1, "heads": {"q": [torch.zeros(25, 5)]}, "acting": "q", "header": {}},
    }
    messages = {
        "text.agent.pt": "is not an empathy-zoo agent file",
        "checkpoint.agent.pt": "is not an empathy-zoo agent file",
        "other.agent.pt": "format 'something_else'",
        "newer.agent.pt": "format version 99",
        "broken.agent.pt": "is malformed: head 'q' must be a list",
    }
    for name, document in cases.items():
        path = tmp_path / name
        if document is None:
            path.write_text("not a torch file\n")
        else:
            torch.save(document, path)
        with pytest.raises(ValueError, match=rf"{path}.*{messages[name]}"):
            load_agent(path)


def test_bad_agent_states_and_headers_are_refused(tmp_path) -> None:
    class Plain:
        def __init__(self, state: dict) -> None:
            self.state = state

        def agent_state(self, run: int) -> dict:
            return self.state

    good = {"heads": {"q": [np.zeros((25, 5), np.float32), np.zeros(5, np.float32)]}, "acting": "q"}
    full = header(0, 1.0)
    path = tmp_path / "a.agent.pt"
    assert write_agent_file(Plain(good), 0, path, full) == ("a.agent.pt", file_sha256(path))
    assert load_agent(path).act(np.zeros(25)) == 0, "all values tie: the first action, as argmax"
    bad = {
        "float64": ({"heads": {"q": [np.zeros((25, 5)), np.zeros(5)]}, "acting": "q"}, full, "not float32"),
        "chain": (
            {"heads": {"q": [torch.zeros(25, 8), torch.zeros(8), torch.zeros(9, 5), torch.zeros(5)]}, "acting": "q"},
            full,
            "takes 9 inputs",
        ),
        "acting": ({**good, "acting": "q_emp"}, full, "'acting' must name one of the heads"),
        "keys": ({**good, "replay": 1}, full, "must return"),
        "header": (good, {"method": "x"}, "missing settings, env, env_kwargs"),
        "plain": (good, {**full, "when": object()}, "plain data"),
    }
    for name, (state, head, message) in bad.items():
        with pytest.raises(ValueError, match=message):
            write_agent_file(Plain(state), 0, tmp_path / f"{name}.agent.pt", head)
        assert not (tmp_path / f"{name}.agent.pt").exists()
    with pytest.raises(ValueError, match=re.escape("ends in .agent.pt")):
        write_agent_file(Plain(good), 0, tmp_path / "a.pt", full)


def test_a_learner_without_agent_state_keeps_no_agent(tmp_path) -> None:
    class NoAgent:
        def act(self, observations, greedy=False):
            return np.zeros(observations.shape[:2], dtype=np.int64)

    assert write_agent_file(NoAgent(), 0, tmp_path / "x.agent.pt", header(0, 1.0)) is None
    assert list(tmp_path.iterdir()) == []


def test_agent_path_sits_beside_the_result_file() -> None:
    assert agent_path(Path("out/runs/coexistence_v0__dqn-1a2b__s3.json")) == Path(
        "out/runs/coexistence_v0__dqn-1a2b__s3.agent.pt"
    )
    with pytest.raises(ValueError, match="not a result file"):
        agent_path("out/runs/x.agent.pt")


@pytest.mark.parametrize("method", sorted(name for name, m in METHODS.items() if hasattr(m.learner, "agent_state")))
def test_every_method_built_on_empathic_dqn_acts_on_its_own_acting_head(method: str, tmp_path) -> None:
    m = METHODS[method]
    beta = m.preset.get("selfishness", 0.5)
    learner = m.learner(
        [
            m.make_settings(
                {"replay_capacity": 64, "learning_starts": 32, "hidden_size": 16}
                | ({} if "selfishness" in m.preset else {"selfishness": beta})
            )
        ],
        [5],
        25,
        5,
    )
    name, sha = write_agent_file(learner, 0, tmp_path / "m.agent.pt", header(0, beta, method))
    agent = load_agent(tmp_path / name, expected_sha256=sha)
    observations = np.random.default_rng(3).integers(-1, 2, (300, 25)).astype(np.float32)
    assert np.array_equal(agent.act_batch(observations), learner_greedy(learner, observations)[0])
    assert agent.describe()["acting"] == ("q_emp" if learner.empathic_runs[0] else "q")


def test_a_loaded_agent_is_a_fixed_policy_driving_robot_0(trained) -> None:
    _, _, paths, _ = trained
    agent = load_agent(paths[0])
    assert isinstance(agent, TrainedAgent) and isinstance(agent, FixedPolicy) and make_policy(agent) is agent
    # the README's loop: the trained robot in the PettingZoo env, the cat random
    env = FixedAgents(coexistence_v0.parallel_env(max_cycles=80), {"cat_0": "random_walk"})
    observations, infos = env.reset(seed=4)
    robot = []
    while env.agents:
        robot.append(agent.act(observations["robot_0"]))
        observations, rewards, _terminations, _truncations, infos = env.step({"robot_0": robot[-1]})
    assert infos["robot_0"]["episode"]["survival"] == len(robot) or infos["robot_0"]["episode"]["harms"] >= 0
    # the same robot as a fixed agent inside FixedAgents, the cat stepped by hand: the same episode
    fixed = FixedAgents(coexistence_v0.parallel_env(max_cycles=80), {"robot_0": agent})
    plain = coexistence_v0.parallel_env(max_cycles=80)
    (seen, _), (plain_obs, _) = fixed.reset(seed=9), plain.reset(seed=9)
    cat = np.random.default_rng(0)
    while fixed.agents:
        move = int(cat.integers(5))
        seen, rewards, *_ = fixed.step({"cat_0": move})
        plain_obs, plain_rewards, *_ = plain.step({"robot_0": agent.act(plain_obs["robot_0"]), "cat_0": move})
        assert np.array_equal(seen["cat_0"], plain_obs["cat_0"]) and rewards["cat_0"] == plain_rewards["cat_0"]
    assert not plain.agents or plain.agents == ["robot_0"]


def test_act_refuses_an_observation_of_the_wrong_shape(trained) -> None:
    agent = load_agent(trained[2][0])
    with pytest.raises(ValueError, match=r"one observation of shape \(25,\)"):
        agent.act(np.zeros((2, 25)))
    with pytest.raises(ValueError, match=r"shape \(B, 25\)"):
        agent.act_batch(np.zeros(24))


# ---------------------------------------------------------------------------- Stable-Baselines3
needs_sb3 = pytest.mark.skipif(importlib.util.find_spec("stable_baselines3") is None, reason="stable-baselines3 not installed")


@needs_sb3
@pytest.mark.parametrize("algorithm", ["dqn", "ppo"])
def test_an_sb3_agent_round_trips_through_sb3s_own_format(algorithm: str, tmp_path, monkeypatch) -> None:
    import cloudpickle

    from baselines.sb3 import SB3Learner, SB3Settings

    small = {
        "dqn": {"buffer_size": 1_000, "learning_starts": 50, "target_update_interval": 40},
        "ppo": {"n_steps": 64, "n_epochs": 2},
    }
    settings = SB3Settings(algorithm=algorithm, algorithm_kwargs=small[algorithm], batch_size=32)
    venv = VectorEnv("coexistence_v0", 2, fixed={"cat_0": "random_walk"}, max_cycles=60)
    learner = SB3Learner([settings] * 2, [0, 1], venv.obs_size, venv.num_actions)
    observations = probe_observations(drive(learner, venv, 150), 300)
    greedy = learner.act(np.repeat(observations[None], 2, axis=0), greedy=True)
    head = {"method": f"sb3_{algorithm}", "settings": {"algorithm": algorithm}, "env": "coexistence_v0", "env_kwargs": {}}
    name, sha = write_agent_file(learner, 1, tmp_path / "r.agent.pt", head)
    assert name == "r.agent.zip" and not (tmp_path / "r.agent.pt").exists()

    def refuse(*args, **kwargs):
        raise AssertionError("loading an agent file unpickles nothing")

    monkeypatch.setattr(cloudpickle, "loads", refuse)
    agent = load_agent(tmp_path / name, expected_sha256=sha)
    assert np.array_equal(agent.act_batch(observations), greedy[1]) and not np.array_equal(greedy[0], greedy[1])
    assert agent.act(observations[0]) == int(learner.act(observations[None, :1].repeat(2, 0), greedy=True)[1, 0])
    d = agent.describe()
    assert (d["library"], d["algorithm"], d["obs_size"], d["num_actions"]) == ("stable_baselines3", algorithm.upper(), 25, 5)
    if algorithm == "dqn":
        assert d["heads"] == ["q"] and d["acting"] == "q"
        with torch.no_grad():
            expected = learner.models[1].q_net(torch.as_tensor(observations)).numpy()
        assert np.array_equal(agent.q_values(observations)["q"], expected)
    else:
        assert d["heads"] == [] and d["acting"] == "policy"
        with pytest.raises(ValueError, match="PPO learns no Q-values"):
            agent.q_values(observations[0])
    data = bytearray((tmp_path / name).read_bytes())
    data[len(data) // 2] ^= 0x01
    (tmp_path / name).write_bytes(bytes(data))
    with pytest.raises(ValueError, match=rf"agent file {tmp_path / name}.*result file r\.json records"):
        load_agent(tmp_path / name, expected_sha256=sha, result_file="r.json")


def test_import_empathy_zoo_still_imports_no_torch() -> None:
    import subprocess
    import sys

    code = "import sys, empathy_zoo; assert 'torch' not in sys.modules; empathy_zoo.load_agent; assert 'torch' in sys.modules"
    subprocess.run([sys.executable, "-c", code], check=True)


def test_a_result_file_names_its_agent_and_the_reader_checks_it(trained, tmp_path) -> None:
    import json

    from empathy_zoo.agent_file import load_run_agent, result_entry

    learner, observations, _, _ = trained
    result = tmp_path / "runs" / f"{header(2, BETAS[2])['run_id']}.json"
    written = write_agent_file(learner, 2, agent_path(result), header(2, BETAS[2]))
    result.write_text(json.dumps({"run_id": result.stem, "agent": result_entry(written)}))
    agent = load_run_agent(result)
    assert np.array_equal(agent.act_batch(observations), learner_greedy(learner, observations)[2])
    data = bytearray(agent_path(result).read_bytes())
    data[-100] ^= 0xFF
    agent_path(result).write_bytes(bytes(data))
    with pytest.raises(ValueError, match=rf"agent file {agent_path(result)} .* result file {result} records"):
        load_run_agent(result)
    result.write_text(json.dumps({"run_id": result.stem, "agent": result_entry(None)}))
    with pytest.raises(ValueError, match="its run kept no trained agent"):
        load_run_agent(result)
