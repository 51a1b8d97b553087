"""``empathy-zoo watch`` and episode GIFs: a trained agent's greedy episodes scored as the
environment scores them, its GIF showing the env's frames and a legend of the engine's colours,
and the agent files it refuses (changed since the run, unknown run, a run that kept no agent)."""

from __future__ import annotations

import argparse
import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from empathy_zoo import FixedAgents, load_agent
from empathy_zoo.cli.watch import add_watch, find_agent
from empathy_zoo.environments import face_module
from empathy_zoo.episode_gif import GIF_STEPS, HOLD_MS, MARGIN, SWATCH, episode_gif, grid_scale
from empathy_zoo.greedy_episode import agent_env, play_greedy, watch_env
from empathy_zoo.metrics import METRIC_NAMES
from empathy_zoo.render import legend, scaled
from empathy_zoo.result_file import RUNS_DIR

TINY = {"learning_starts": 64, "replay_capacity": 2_000, "epsilon_decay_steps": 300, "target_update_interval": 50}
STEPS = 300
MAX_CYCLES = 60
ENVS = {"coexistence_v0": {"cat_0": "random_walk"}, "sharing_v0": {"human_0": {"policy": "patrol", "period": 3}}}
"""The fixed agents each run trains beside (its agent file records their labels, as a result file's ``config.fixed``)."""
SHIPPED = Path(__file__).resolve().parents[1] / "docs" / "results" / "quick" / RUNS_DIR
NO_AGENT = "coexistence_v0__dqn_harm_penalty-684a7c7f__s0"
"""A shipped run whose result file is copied with its ``agent`` entry ``null``: a real result file of a run that kept no agent."""


def spec(env: str):
    """The tiny one-run Empathic DQN on ``env`` (``STEPS`` steps, episodes of ``MAX_CYCLES``) beside its fixed agents."""
    from empathy_zoo.experiment import RunSpec

    return RunSpec.of(
        env=env,
        method="empathic_dqn",
        settings={**TINY, "selfishness": 0.5},
        steps=STEPS,
        eval_interval=STEPS,
        eval_episodes=1,
        fixed=ENVS[env],
        env_kwargs={"max_cycles": MAX_CYCLES},
    )


def run_id(env: str) -> str:
    """The run id the trainer names the run on ``env``."""
    return spec(env).run_id


@pytest.fixture(scope="module")
def results(tmp_path_factory) -> Path:
    """A results directory as ``train --out`` writes it: the tiny run on each of ``ENVS`` trained by
    the runner (result file and agent file), and a result file of a run that kept no agent."""
    from empathy_zoo.training.runner import RunnerOptions, train_runs

    out = tmp_path_factory.mktemp("results")
    options = RunnerOptions(progress=False, checkpoint_interval=0)
    written = train_runs([spec(env) for env in ENVS], out, options, on_note=lambda _: None)
    assert sorted(path.name for path in written) == sorted(f"{run_id(env)}.json" for env in ENVS)
    kept = json.loads((SHIPPED / f"{NO_AGENT}.json").read_text())
    (out / RUNS_DIR / f"{NO_AGENT}.json").write_text(json.dumps({**kept, "agent": None}))
    return out


def agent_file(results: Path, env: str = "coexistence_v0") -> Path:
    return results / RUNS_DIR / f"{run_id(env)}.agent.pt"


def watch(argv: list[str], capsys) -> list[str]:
    """Run ``empathy-zoo watch ARGV``; its printed lines."""
    parser = argparse.ArgumentParser(prog="empathy-zoo")
    add_watch(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(["watch", *argv])
    assert args.handler(args, "empathy-zoo watch") == 0
    return capsys.readouterr().out.splitlines()


def env_episode(agent, env: str, seed: int, fixed: dict[str, str]) -> tuple[dict[str, float], list[int]]:
    """The episode ``agent`` plays greedily over ``FixedAgents`` as the README shows: the env's
    ``infos[robot]["episode"]``, and the actions."""
    wrapped = FixedAgents(face_module(env).parallel_env(max_cycles=MAX_CYCLES), fixed)
    observations, infos = wrapped.reset(seed=seed)
    actions = []
    while wrapped.agents:
        actions.append(agent.act(observations["robot_0"]))
        observations, _, _, _, infos = wrapped.step({"robot_0": actions[-1]})
    return infos["robot_0"]["episode"], actions


def printed(episode: int, seed: int, metrics: dict[str, float]) -> str:
    return f"episode {episode} (seed {seed}): " + ", ".join(f"{name} {float(metrics[name]):g}" for name in METRIC_NAMES)


def test_watch_prints_the_metrics_the_env_gives_for_the_same_seed(results, capsys) -> None:
    lines = watch([run_id("coexistence_v0"), "--dir", str(results), "--episodes", "3", "--seed", "5"], capsys)
    assert (
        lines[0].startswith(f"empathic_dqn agent of run {run_id('coexistence_v0')} (") and "beside cat_0=random_walk" in lines[0]
    )
    agent = load_agent(agent_file(results))
    episodes = [env_episode(agent, "coexistence_v0", seed, ENVS["coexistence_v0"]) for seed in (5, 6, 7)]
    assert lines[1:] == [printed(k, 5 + k, metrics) for k, (metrics, _) in enumerate(episodes)]
    played = play_greedy(agent, watch_env("coexistence_v0", {"max_cycles": MAX_CYCLES}), 5)
    assert played.actions == episodes[0][1] and played.ended
    assert played.metrics == {name: float(episodes[0][0][name]) for name in METRIC_NAMES}


def test_the_recorded_partners_play_unless_fixed_replaces_them(results, capsys) -> None:
    agent = load_agent(agent_file(results, "sharing_v0"))
    lines = watch([str(agent_file(results, "sharing_v0")), "--seed", "2"], capsys)  # (a path: loaded directly)
    assert "beside human_0=patrol(period=3)" in lines[0], "the run's own partner, with its arguments"
    assert lines[1:] == [printed(0, 2, env_episode(agent, "sharing_v0", 2, ENVS["sharing_v0"])[0])]
    lines = watch([str(agent_file(results, "sharing_v0")), "--seed", "2", "--fixed", "human_0=stay"], capsys)
    assert "beside human_0=stay" in lines[0]
    assert lines[1:] == [printed(0, 2, env_episode(agent, "sharing_v0", 2, {"human_0": "stay"})[0])]
    assert env_episode(agent, "sharing_v0", 2, {"human_0": "stay"}) != env_episode(agent, "sharing_v0", 2, ENVS["sharing_v0"])


def test_render_ansi_prints_the_grid_every_step(results, capsys) -> None:
    lines = watch([run_id("coexistence_v0"), "--dir", str(results), "--render", "ansi", "--seed", "5"], capsys)
    _, actions = env_episode(load_agent(agent_file(results)), "coexistence_v0", 5, ENVS["coexistence_v0"])
    grids = [line for line in lines if line and line[0] in ".RC*"]
    assert len(grids) == 7 * (len(actions) + 1)


def gif_frames(path: Path) -> tuple[list[np.ndarray], list[int]]:
    with Image.open(path) as image:
        frames, durations = [], []
        for k in range(image.n_frames):
            image.seek(k)
            frames.append(np.asarray(image.convert("RGB")))
            durations.append(image.info["duration"])
    return frames, durations


@pytest.mark.parametrize("env", list(ENVS))
def test_the_gif_shows_the_env_frames_a_legend_and_holds_the_last(results, tmp_path, env) -> None:
    agent = load_agent(agent_file(results, env))
    path = tmp_path / "sub" / "episode.gif"
    gif = episode_gif(agent, path, seed=3, max_steps=25)
    frames, durations = gif_frames(path)
    assert gif.outcome.steps == min(25, len(env_episode(agent, env, 3, ENVS[env])[1]))
    assert len(frames) == gif.frames == gif.outcome.steps + 1
    assert path.stat().st_size == gif.bytes < 300_000 and not [p for p in path.parent.iterdir() if p.name.startswith(".")]
    assert all(frame.shape == (gif.size[1], gif.size[0], 3) for frame in frames)
    assert durations == [200] * (len(frames) - 1) + [HOLD_MS], "one tick of render_fps = 5 per step, the last held"

    face = watch_env(env, {"max_cycles": MAX_CYCLES}, render_mode="rgb_array")
    face.reset(seed=3)
    factor = grid_scale(face.render().shape[1])
    grid = scaled(face.render(), factor)
    rows, cols = grid.shape[:2]
    assert np.array_equal(frames[0][MARGIN : MARGIN + rows, MARGIN : MARGIN + cols], grid), "the env's own rgb_array frame"
    entries = legend(face.unwrapped.engine)
    assert [e.label for e in entries] == list(face.unwrapped.possible_agents) + (["battery"] if env == "sharing_v0" else [])
    panel = frames[0][:, MARGIN + cols + factor :]
    for entry in entries:  # each swatch is a square of its colour in the panel, drawn as the grid draws it
        ys, xs = np.nonzero((panel == entry.color).all(axis=2))
        side = SWATCH - 2 * (SWATCH // 4 if entry.battery else 2)
        assert (ys.max() - ys.min() + 1, xs.max() - xs.min() + 1, len(ys)) == (side, side, side * side), entry.label


def test_watch_writes_a_gif_of_the_first_episode(results, tmp_path, capsys) -> None:
    path = tmp_path / "watch.gif"
    lines = watch([run_id("coexistence_v0"), "--dir", str(results), "--episodes", "2", "--gif", str(path)], capsys)
    _, actions = env_episode(load_agent(agent_file(results)), "coexistence_v0", 0, ENVS["coexistence_v0"])
    frames, _ = gif_frames(path)
    assert len(frames) == min(GIF_STEPS, len(actions)) + 1
    assert lines[-1].startswith(f"empathy-zoo: wrote {path} ({len(frames)} frames")
    print(f"watch GIF: {len(frames)} frames, {frames[0].shape[1]}×{frames[0].shape[0]}, {path.stat().st_size:,} bytes")


def test_a_changed_agent_file_is_refused_naming_both_files(results, tmp_path) -> None:
    copy = tmp_path / "copy"
    shutil.copytree(results, copy)
    changed = agent_file(copy)
    data = bytearray(changed.read_bytes())
    data[len(data) // 2] ^= 0x01
    changed.write_bytes(bytes(data))
    result = copy / RUNS_DIR / f"{run_id('coexistence_v0')}.json"
    for target in (run_id("coexistence_v0"), str(changed), str(result)):
        with pytest.raises(ValueError, match=rf"agent file {changed} has SHA-256 .* its result file {result} records"):
            find_agent(target, copy)


def test_unknown_runs_runs_without_agents_and_other_files_are_refused(results, tmp_path) -> None:
    with pytest.raises(
        ValueError, match=rf"unknown run id 'coexistence_v0__empathic_dqn-wach__s0'.*runs there: {run_id('coexistence_v0')}"
    ):
        find_agent("coexistence_v0__empathic_dqn-wach__s0", results)
    with pytest.raises(ValueError, match=r"there is no .*nowhere/runs"):
        find_agent(run_id("coexistence_v0"), tmp_path / "nowhere")
    with pytest.raises(ValueError, match=rf"{NO_AGENT}\.json names no agent file: its run kept no trained agent"):
        find_agent(NO_AGENT, results)
    text = tmp_path / "notes.agent.pt"
    text.write_text("not an agent\n")
    with pytest.raises(ValueError, match=rf"{text} is not an empathy-zoo agent file"):
        find_agent(str(text))
    with pytest.raises(ValueError, match=r"no agent file .*missing\.agent\.pt"):
        find_agent(str(tmp_path / "missing.agent.pt"))
    gone = tmp_path / "gone"
    shutil.copytree(results, gone)
    agent_file(gone).unlink()
    with pytest.raises(ValueError, match=rf"names agent file {run_id('coexistence_v0')}\.agent\.pt, which is missing"):
        find_agent(run_id("coexistence_v0"), gone)
    agent = load_agent(agent_file(results))
    with pytest.raises(ValueError, match="robot_0 is the trained agent's"):
        episode_gif(agent, tmp_path / "x.gif", fixed={"robot_0": "stay"})
    assert not (tmp_path / "x.gif").exists()


def test_watch_a_run_the_trainer_kept(tmp_path, capsys) -> None:
    """End to end: ``train_runs`` keeps the agent, ``watch`` plays it by its run id."""
    from empathy_zoo.experiment import RunSpec
    from empathy_zoo.training.runner import RunnerOptions, train_runs

    spec = RunSpec.of(
        env="coexistence_v0",
        settings=TINY,
        steps=STEPS,
        eval_interval=STEPS,
        eval_episodes=1,
        env_kwargs={"max_cycles": MAX_CYCLES},
    )
    (result_file,) = train_runs([spec], tmp_path, RunnerOptions(progress=False, checkpoint_interval=0), on_note=lambda _: None)
    assert json.loads(result_file.read_text())["agent"]["file"] == f"{spec.run_id}.agent.pt"
    lines = watch([spec.run_id, "--dir", str(tmp_path)], capsys)
    metrics, _ = env_episode(
        load_agent(result_file.with_name(f"{spec.run_id}.agent.pt")), "coexistence_v0", 0, ENVS["coexistence_v0"]
    )
    assert lines[1:] == [printed(0, 0, metrics)]


def test_an_environment_the_agent_cannot_act_in_is_refused() -> None:
    class Described:
        def __init__(self, **changes) -> None:
            base = {"env": "coexistence_v0", "env_kwargs": {}, "obs_size": 25, "fixed": {"cat_0": "random_walk"}}
            self.description = {**base, **changes}

        def describe(self) -> dict:
            return dict(self.description)

    assert agent_env(Described()).possible_agents == ["robot_0"]
    with pytest.raises(ValueError, match=r"no_such_policy.*the run trained beside \{'cat_0': 'no_such_policy'\}"):
        agent_env(Described(fixed={"cat_0": "no_such_policy"}))
    assert (
        agent_env(Described(fixed={"cat_0": "no_such_policy"}), {"cat_0": "stay"}).policies["cat_0"].__class__.__name__ == "Stay"
    )
    with pytest.raises(
        ValueError, match=re.escape("takes observations of 25 values, but coexistence_v0 with {'view': 3} gives 9")
    ):
        agent_env(Described(env_kwargs={"view": 3}))
    with pytest.raises(ValueError, match="takes no argument"):
        agent_env(Described(env_kwargs={"colour": 3}))
    with pytest.raises(
        ValueError, match=r"robot_0 is the trained agent's; fixed policies are for the other agents \['cat_0', 'cat_1'\]"
    ):
        watch_env("coexistence_v0", {"num_cats": 2}, {"robot_0": "stay"})
