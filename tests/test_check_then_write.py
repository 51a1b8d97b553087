"""Every command checks everything it reads before it writes anything: a refused leaderboard (a
changed or linked agent file, a partner the environment has no agent for, an unknown environment,
a bad ``--label``) leaves its output directory as it was, and a write that fails mid-way (a full
disk) leaves no half-written page and names the file. Every size has a bound, checked up front
with a message naming it (``tune``'s seeds and sampler seed, ``evaluate --episodes``, a vector
env's environments, the grid and horizon of the exact reference curve). A bad path is one line,
not a traceback. SIGINT or SIGTERM to a sweep of several worker processes stops its workers and
exits non-zero, and the same command resumes it."""

from __future__ import annotations

import errno
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from helpers_results import derive_run_id, record, synthetic_schema_1

import leaderboard.report as report
from empathy_zoo.agent_file import RESULT_FIELD
from empathy_zoo.cli import main
from empathy_zoo.experiment.records import RunResult
from empathy_zoo.limits import MAX_EVAL_EPISODES, MAX_REFERENCE_CYCLES, MAX_REFERENCE_SIZE, MAX_SEEDS, MAX_VECTOR_ENVS
from empathy_zoo.training import RunnerOptions, train_runs
from empathy_zoo.vector import VectorEnv
from leaderboard import write_leaderboard
from leaderboard.reference_curves import reference_curve, reference_refusal

ROOT = Path(__file__).resolve().parents[1]


def one_line_refusal(capsys) -> str:
    err = capsys.readouterr().err
    assert err.startswith("empathy-zoo: error: ") and err.count("\n") == 1 and "Traceback" not in err, err
    return err


def tree(directory: Path) -> dict[str, bytes]:
    """Every file below ``directory`` and its bytes (``{}`` when there is none)."""
    if not directory.exists():
        return {}
    return {p.relative_to(directory).as_posix(): p.read_bytes() for p in sorted(directory.rglob("*")) if p.is_file()}


def write_results(directory: Path, env: str = "coexistence_v0") -> Path:
    """Two methods × two seeds of synthetic result files in ``directory/runs``; ``env`` as each names it."""
    (directory / "runs").mkdir(parents=True, exist_ok=True)
    for method in ("empathic_dqn", "dqn"):
        for seed in (0, 1):
            document = synthetic_schema_1("coexistence_v0", method, 0.5, seed, survival=0.9, harms=0.1)
            if env != "coexistence_v0":
                document["env"] = document["config"]["variant"] = env
                derive_run_id(document)
            (directory / "runs" / f"{document['run_id']}.json").write_text(json.dumps(document))
    return directory


# ---------------------------------------------------------------------------- leaderboard: check, then write
@pytest.fixture(scope="module")
def trained(tmp_path_factory) -> Path:
    """Two tiny runs (DQN, Empathic DQN) that kept their agents."""
    from helpers_heldout import dqn_and_empathic_runs

    out = tmp_path_factory.mktemp("trained")
    train_runs(dqn_and_empathic_runs((0,), 40, 1), out, RunnerOptions(progress=False, checkpoint_interval=0, workers=1))
    return out


def agent_file_of(results: Path, method: str) -> tuple[Path, Path]:
    (run_file,) = (results / "runs").glob(f"coexistence_v0__{method}-*__s0.json")
    return run_file, run_file.with_name(json.loads(run_file.read_text())[RESULT_FIELD]["file"])


def change_agent(results: Path, tmp_path: Path) -> None:
    _, agent = agent_file_of(results, "empathic_dqn")
    data = bytearray(agent.read_bytes())
    data[-20] ^= 0xFF
    agent.write_bytes(bytes(data))


def link_agent(results: Path, tmp_path: Path) -> None:
    _, agent = agent_file_of(results, "empathic_dqn")
    elsewhere = tmp_path / "elsewhere.pt"
    shutil.move(agent, elsewhere)
    agent.symlink_to(elsewhere)


def unknown_partner(results: Path, tmp_path: Path) -> None:
    run_file, _ = agent_file_of(results, "empathic_dqn")
    document = json.loads(run_file.read_text())
    document["config"]["fixed"] = {"cat_9": "stay"}
    run_file.write_text(json.dumps(document))


@pytest.mark.parametrize("spoil", [change_agent, link_agent, unknown_partner], ids=lambda f: f.__name__)
def test_a_refused_leaderboard_writes_nothing(trained, tmp_path, capsys, spoil):
    results = Path(shutil.copytree(trained, tmp_path / "results"))
    spoil(results, tmp_path)
    before = tree(results)
    status = main(["leaderboard", str(results), "--out", str(tmp_path / "out")])
    assert status == 2
    one_line_refusal(capsys)
    assert not (tmp_path / "out").exists()
    assert tree(results) == before


def test_an_unknown_environment_is_refused_before_any_figure(tmp_path, capsys):
    results = write_results(tmp_path / "results", env="nosuch_v0")
    assert main(["leaderboard", str(results), "--out", str(tmp_path / "out")]) == 2
    assert "nosuch_v0" in one_line_refusal(capsys)
    assert not (tmp_path / "out").exists()


def test_a_refusal_leaves_an_older_page_as_it_was(tmp_path, capsys):
    good = write_results(tmp_path / "good")
    out = tmp_path / "out"
    write_leaderboard(good, out)
    before = tree(out)
    assert main(["leaderboard", str(write_results(tmp_path / "bad", env="nosuch_v0")), "--out", str(out)]) == 2
    one_line_refusal(capsys)
    assert tree(out) == before


def test_a_full_disk_names_the_file_and_leaves_no_half_written_page(tmp_path, capsys, monkeypatch):
    results = write_results(tmp_path / "results")
    out = tmp_path / "out"
    write_leaderboard(results, out)
    before = tree(out)
    real = report.write_text_atomic

    def full(path, text):
        if Path(path).name == report.HTML_NAME:
            raise OSError(
                errno.ENOSPC, os.strerror(errno.ENOSPC), str(Path(path).with_name(".leaderboard.html.123.0a1b2c3d.tmp"))
            )
        return real(path, text)

    monkeypatch.setattr(report, "write_text_atomic", full)
    (results / "runs" / next(iter(os.listdir(results / "runs")))).unlink()  # (a page that would differ)
    assert main(["leaderboard", str(results), "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert err.startswith("empathy-zoo: error: ") and err.count("\n") == 1, err
    assert str(out / report.HTML_NAME) in err and "No space left" in err
    assert tree(out) == before  # the older complete page, and nothing beside it


def test_a_new_leaderboard_is_what_it_always_was(tmp_path):
    results = write_results(tmp_path / "results")
    paths = write_leaderboard(results, tmp_path / "one")
    write_leaderboard(results, tmp_path / "two")
    assert tree(tmp_path / "one").keys() == tree(tmp_path / "two").keys()
    assert all(path.is_file() and path.is_relative_to(tmp_path / "one") for path in paths.values())
    assert not list((tmp_path / "one").rglob(".*"))  # no staging left behind


@pytest.mark.parametrize(
    "prefix", ["a\rb", "a\x1bb", "a\x07b", "a\u202eb", "x" * 5000], ids=["CR", "ESC", "BEL", "RLO", "5000 characters"]
)
def test_every_label_prefix_is_a_label(tmp_path, capsys, prefix):
    results = write_results(tmp_path / "results")
    status = main(["leaderboard", str(results), "--out", str(tmp_path / "out"), "--label", f"{results}={prefix}"])
    assert status == 2
    assert "--label" in one_line_refusal(capsys)
    assert not (tmp_path / "out").exists()


# ---------------------------------------------------------------------------- tune
TUNE = ["--method", "dqn", "--param", "learning_rate=log:1e-4:1e-3", "--trials", "1", "--no-progress"]


@pytest.mark.parametrize(
    "option, value, named",
    [
        ("--sampler-seed", "-1", "sampler"),
        ("--tuning-seeds", "100000", f"{MAX_SEEDS:,}"),
        ("--trials", "1000000000", "trials"),
        ("--startup-trials", "1000000000", "startup"),
        ("--budget", "10000000000", "budget"),
    ],
)
def test_tune_checks_every_argument_before_writing(tmp_path, capsys, option, value, named):
    from helpers_sweeps import TINY_SWEEP

    pytest.importorskip("optuna")
    sweep = tmp_path / "tiny.toml"
    sweep.write_text(TINY_SWEEP)
    out = tmp_path / "study"
    argv = ["tune", str(sweep), *TUNE, "--out", str(out)]
    if option in argv:
        at = argv.index(option)
        argv = argv[:at] + argv[at + 2 :]
    assert main([*argv, option, value]) == 2
    assert named in one_line_refusal(capsys)
    assert not out.exists()


# ---------------------------------------------------------------------------- sizes
def test_evaluate_bounds_its_episodes_before_creating_anything(tmp_path, capsys):
    results = write_results(tmp_path / "results")
    before = tree(results)
    assert main(["evaluate", str(results), "--episodes", "100000000", "--no-progress"]) == 2
    assert f"{MAX_EVAL_EPISODES:,}" in one_line_refusal(capsys)
    assert tree(results) == before and not (results / "evaluations").exists()


def test_a_vector_env_bounds_its_environments():
    with pytest.raises(ValueError, match=f"{MAX_VECTOR_ENVS:,}"):
        VectorEnv("coexistence_v0", 10**12)
    with pytest.raises(ValueError, match="num_envs"):
        VectorEnv("coexistence_v0", 0)


def test_training_refuses_an_evaluation_of_too_many_environments_before_it_starts(tmp_path, capsys):
    from helpers_sweeps import TINY_TRAIN

    argv = ["train", *TINY_TRAIN, "--out", str(tmp_path / "out"), "--seeds", *map(str, range(101))]
    at = argv.index("--eval-episodes")
    argv[at + 1] = str(MAX_EVAL_EPISODES)
    assert main([*argv, "--max-parallel-runs", "101"]) == 2
    assert f"{MAX_VECTOR_ENVS:,}" in one_line_refusal(capsys)
    assert not (tmp_path / "out").exists()


def reference_runs(**env_kwargs: int) -> list[RunResult]:
    runs = []
    for seed in range(2):
        document = synthetic_schema_1("coexistence_v0", "empathic_dqn", 0.5, seed, harms=0.1, survival=400)
        document["config"]["env_kwargs"] = env_kwargs
        runs.append(record(derive_run_id(document)))
    return runs


@pytest.mark.parametrize(
    "env_kwargs, named",
    [
        ({"size": 255}, f"size 255 is beyond {MAX_REFERENCE_SIZE}"),
        ({"max_cycles": 10**9}, f"max_cycles {10**9:,} is beyond {MAX_REFERENCE_CYCLES:,}"),
    ],
)
def test_no_reference_curve_beyond_its_bounds(monkeypatch, env_kwargs, named):
    import empathy_zoo.reference as reference

    def never(*args, **kwargs):
        raise AssertionError("the reference was computed")

    monkeypatch.setattr(reference, "coexistence_optimum", never)
    runs = reference_runs(**env_kwargs)
    assert reference_curve(runs, "harms", np.array([100.0])) is None
    why = reference_refusal(runs)
    assert why is not None and named in why and "\n" not in why


def test_the_leaderboard_says_why_a_run_has_no_reference_curve(tmp_path, capsys):
    (tmp_path / "runs").mkdir()
    for run in reference_runs(size=MAX_REFERENCE_SIZE + 2):
        (tmp_path / "runs" / f"{run.run_id}.json").write_text(json.dumps(synthetic_schema_1_of(run)))
    notes: list[str] = []
    write_leaderboard(tmp_path, tmp_path / "out", on_note=notes.append)
    assert len(notes) == 1 and f"beyond {MAX_REFERENCE_SIZE}" in notes[0] and "reference" in notes[0]
    assert reference_refusal(reference_runs()) is None


def synthetic_schema_1_of(run: RunResult) -> dict:
    document = synthetic_schema_1("coexistence_v0", "empathic_dqn", 0.5, run.seed, harms=0.1, survival=400)
    document["config"]["env_kwargs"] = dict(run.config.env_kwargs)
    return derive_run_id(document)


# ---------------------------------------------------------------------------- paths
def test_train_refuses_a_config_directory_in_one_line(tmp_path, capsys):
    assert main(["train", "--config", str(tmp_path), "--out", str(tmp_path / "out")]) == 2
    assert "directory" in one_line_refusal(capsys)
    assert not (tmp_path / "out").exists()


# ---------------------------------------------------------------------------- interrupting a sweep
SLOW_AND_FAST = """
[sweep]
seeds = 1
steps = {steps}
eval_interval = {steps}
eval_episodes = 1

[settings]
learning_starts = 32
replay_capacity = 300

[envs.coexistence_v0]
max_cycles = 50

[[methods]]
method = "dqn"
hidden_size = 8

[[methods]]
method = "empathic_dqn"
selfishness = 0.5
hidden_size = 256
batch_size = 256
learning_starts = 256
"""


def workers_of(parent: int) -> list[int]:
    """The worker processes (``spawn_main``) whose parent is ``parent``."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
            command = (entry / "cmdline").read_bytes()
        except OSError:
            continue
        if int(stat.rsplit(")", 1)[1].split()[1]) == parent and b"spawn_main" in command:
            found.append(int(entry.name))
    return found


def alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def interrupted_sweep(tmp_path: Path, sent: int) -> tuple[list[str], subprocess.CompletedProcess, list[int]]:
    """A sweep of a fast and a slow run on two workers, started with SIGINT ignored (as a job
    started with ``&`` by a script is), sent ``sent`` once the fast run's result file is there
    (the slow run is training then); its command, what it did, and its workers."""
    sweep = tmp_path / "sweep.toml"
    sweep.write_text(SLOW_AND_FAST.format(steps=2000))
    out = tmp_path / "out"
    argv = [sys.executable, "-m", "empathy_zoo.cli", "reproduce", "--profile", str(sweep), "--out", str(out)]
    argv += ["--no-progress", "--workers", "2", "--threads", "1", "--checkpoint-interval", "100"]
    process = subprocess.Popen(
        argv,
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_IGN),
    )
    try:
        deadline = time.monotonic() + 300
        while not list((out / "runs").glob("*.json")):
            assert process.poll() is None, process.communicate()
            assert time.monotonic() < deadline
            time.sleep(0.05)
        workers = workers_of(process.pid)
        process.send_signal(sent)
        stdout, stderr = process.communicate(timeout=60)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    return argv, subprocess.CompletedProcess(argv, process.returncode, stdout, stderr), workers


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="reads the process table in /proc")
@pytest.mark.parametrize("sent, status", [(signal.SIGINT, 130), (signal.SIGTERM, 143)], ids=["SIGINT", "SIGTERM"])
def test_a_signal_stops_every_worker_and_keeps_what_is_finished(tmp_path, sent, status):
    _, done, workers = interrupted_sweep(tmp_path, sent)
    assert done.returncode == status, done.stderr
    assert "Traceback" not in done.stderr and "interrupted" in done.stderr
    assert workers and not [pid for pid in workers if alive(pid)]
    assert len(list((tmp_path / "out" / "runs").glob("*.json"))) == 1
    assert list((tmp_path / "out" / "checkpoints").glob("*.pt"))  # the slow run's last checkpoint


@pytest.mark.slow
@pytest.mark.skipif(not Path("/proc").is_dir(), reason="reads the process table in /proc")
def test_the_same_command_resumes_an_interrupted_sweep(tmp_path):
    argv, done, _ = interrupted_sweep(tmp_path, signal.SIGINT)
    assert done.returncode == 130, done.stderr
    runs = tmp_path / "out" / "runs"
    finished = {p.name: p.read_bytes() for p in runs.glob("*.json")}
    again = subprocess.run(argv, cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert again.returncode == 0, again.stderr
    assert "1 already finished" in again.stdout
    results = {p.name: p.read_bytes() for p in runs.glob("*.json")}
    assert len(results) == 2 and all(results[name] == data for name, data in finished.items())
    assert not list((tmp_path / "out" / "checkpoints").glob("*.pt"))
