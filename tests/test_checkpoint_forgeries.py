"""A forged checkpoint is refused before anything is trained or written.

Every counter, clock, seed, random state and array of a checkpoint is checked against what the runs
being resumed would hold (their ``max_cycles``, number of environments, observation size, updates,
seeds) and against the others: an integer of any size is compared exactly (``10**400`` is refused,
never turned into a float), the elapsed time is bounded as a result file's ``wall_time_s`` is
(:data:`~empathy_zoo.limits.MAX_WALL_TIME_S`). A refusal is one line on stderr naming the checkpoint
and the field, exit status 2, and leaves the output directory exactly as it was.
"""

from __future__ import annotations

import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import torch
from test_check_then_write import one_line_refusal
from test_reader_forgeries import listing

from empathy_zoo.cli import main
from empathy_zoo.limits import MAX_WALL_TIME_S
from empathy_zoo.randomness import STREAMS, derive_key
from empathy_zoo.training import ensemble


def train_command(out: Path) -> list[str]:
    """Two runs of Empathic DQN (β = 1) in one ensemble, 300 steps, a checkpoint at step 200."""
    return [
        "train",
        *("--steps", "300", "--eval-interval", "100", "--eval-episodes", "1", "--seeds", "0", "1"),
        *("--learning-starts", "32", "--replay-capacity", "150", "--hidden-size", "8", "--max-cycles", "40"),
        *("--epsilon-decay-steps", "100", "--checkpoint-interval", "200", "--update-kernel", "torch"),
        *("--no-progress", "--out", str(out)),
    ]


@pytest.fixture(scope="module")
def checkpointed(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The output directory of :func:`train_command`, killed just after its checkpoint at step 200."""
    out = tmp_path_factory.mktemp("checkpointed") / "out"
    real = ensemble.save_checkpoint

    def save_then_die(path: Path, payload: dict[str, Any]) -> None:
        real(path, payload)
        raise KeyboardInterrupt

    ensemble.save_checkpoint = save_then_die
    try:
        assert main(train_command(out)) != 0
    finally:
        ensemble.save_checkpoint = real
    assert len(list((out / "checkpoints").glob("*.pt"))) == 1
    return out


def _set(path: str, value: Callable[[Any], Any]) -> Callable[[dict[str, Any]], None]:
    """A forgery: the value at the dotted ``path`` of the checkpoint replaced by ``value(old)``."""

    def change(payload: dict[str, Any]) -> None:
        *parents, last = path.split(".")
        table: Any = payload
        for key in parents:
            table = table[int(key)] if isinstance(table, list) else table[key]
        key_of: Any = int(last) if isinstance(table, list) else last
        table[key_of] = value(table[key_of])

    return change


def _first(value: Any) -> Callable[[torch.Tensor], torch.Tensor]:
    def change(tensor: torch.Tensor) -> torch.Tensor:
        tensor = tensor.clone()
        tensor.view(-1)[0] = value
        return tensor

    return change


def _full(value: Any) -> Callable[[torch.Tensor], torch.Tensor]:
    return lambda tensor: torch.full_like(tensor, value)


def _both(*changes: Callable[[dict[str, Any]], None]) -> Callable[[dict[str, Any]], None]:
    def change(payload: dict[str, Any]) -> None:
        for one in changes:
            one(payload)

    return change


def _left_while_present(payload: dict[str, Any]) -> None:
    """A forgery: every agent still present given its run's clock as the time it left (within [0, t])."""
    engine = payload["vector"]["engine"]
    present, t = engine["present"]["__ndarray__"], engine["t"]["__ndarray__"]
    assert bool((present & (t[:, None] > 0)).any()), "a present agent on a clock past 0 to forge"
    engine["left_at"]["__ndarray__"] = torch.where(present, t[:, None].expand_as(present), engine["left_at"]["__ndarray__"])


def _battery_in_coexistence(payload: dict[str, Any]) -> None:
    """A forgery: the robot of each run given as many batteries as its clock (within [0, t]), in
    Coexistence, where no agent uses batteries."""
    engine = payload["vector"]["engine"]
    t = engine["t"]["__ndarray__"]
    assert bool((t > 0).any()), "a clock past 0 to forge"
    engine["inventory"]["__ndarray__"][:, 0] = t


ENGINE = "vector.engine"
STREAM = f"{ENGINE}.streams"
GENERATOR = f"{STREAM}.bit_generators.0"
HUGE = 10**400
"""An integer beyond the range of a float (``float(HUGE)`` raises ``OverflowError``)."""

FORGERIES: dict[str, tuple[Callable[[dict[str, Any]], None], str]] = {
    # 1: integers beyond the range of a float
    "log survival 10**400": (_set("logs.0.survival.0", lambda _: HUGE), "logs[0]['survival'][0]"),
    "log return 10**400": (_set("logs.0.return.0", lambda _: HUGE), "logs[0]['return'][0]"),
    "evaluation survival 10**400": (_set("evaluations.0.0.survival.0", lambda _: HUGE), "evaluations[0][0]['survival']"),
    "evaluation return 10**400": (_set("evaluations.1.1.return.0", lambda _: HUGE), "evaluations[1][1]['return']"),
    "elapsed 10**400": (_set("elapsed", lambda _: HUGE), "elapsed"),
    "step 10**600": (_set("step", lambda _: 10**600), "step"),
    # 2: random states and observations the trainer cannot take
    "PCG64 state 2**200": (_set(f"{GENERATOR}.state.state", lambda _: 2**200), "bit_generators[0]"),
    "PCG64 state negative": (_set(f"{GENERATOR}.state.state", lambda _: -1), "bit_generators[0]"),
    "PCG64 increment even": (_set(f"{GENERATOR}.state.inc", lambda inc: inc - 1), "bit_generators[0]"),
    "PCG64 has_uint32 5": (_set(f"{GENERATOR}.has_uint32", lambda _: 5), "bit_generators[0]"),
    "PCG64 uinteger 2**40": (_set(f"{GENERATOR}.uinteger", lambda _: 2**40), "bit_generators[0]"),
    "another bit generator": (_set(f"{GENERATOR}.bit_generator", lambda _: "MT19937"), "bit_generators[0]"),
    "no generator": (_set(GENERATOR, lambda _: None), "bit_generators[0]"),
    "observations of 24 values": (_set("obs.__ndarray__", lambda _: torch.zeros(2, 24)), "obs"),
    "observations of 3 runs": (_set("obs.__ndarray__", lambda _: torch.zeros(3, 25)), "obs"),
    "observations not the environments'": (_set("obs.__ndarray__", _first(0.5)), "obs"),
    "observations out of range": (
        _both(_set("obs.__ndarray__", _full(7.0)), _set("vector.observations.__ndarray__", _full(7.0))),
        "obs holds",
    ),
    "no observations": (_set("obs", lambda _: None), "obs"),
    "environments' observations of 24 values": (
        _set("vector.observations.__ndarray__", lambda _: torch.zeros(2, 1, 24)),
        "vector.observations",
    ),
    # 3: an elapsed time no result file may record
    "elapsed 1e300": (_set("elapsed", lambda _: 1e300), "elapsed"),
    "elapsed past ten years": (_set("elapsed", lambda _: MAX_WALL_TIME_S + 1), "elapsed"),
    # 4: counters, clocks and seeds out of their range
    "Adam step count negative": (_set("learner.optimizer.steps", _first(-3.0)), "learner.optimizer.steps"),
    "Adam step count not the updates'": (_set("learner.optimizer.steps", _first(5.0)), "learner.optimizer.steps"),
    "Adam step count 1e30": (_set("learner.optimizer.steps", _full(1e30)), "learner.optimizer.steps"),
    "Adam step counts of one run": (_set("learner.optimizer.steps", lambda t: t[:1].clone()), "learner.optimizer.steps"),
    "Adam moments of another shape": (
        _set("learner.optimizer.exp_avg.0", lambda t: t[:1].clone()),
        "learner.optimizer.exp_avg[0]",
    ),
    "target network of another shape": (_set("learner.target.0", lambda t: t[:1].clone()), "learner.target[0]"),
    "learner's steps a float": (_set("learner.env_steps", float), "env_steps"),
    "replay position not the steps'": (_set("learner.replay.position", lambda _: 3), "replay"),
    "left_at beyond max_cycles": (_set(f"{ENGINE}.left_at.__ndarray__", _full(10**9)), "left_at"),
    "left_at after the clock": (_set(f"{ENGINE}.left_at.__ndarray__", _full(39)), "left_at"),
    "left_at negative": (_set(f"{ENGINE}.left_at.__ndarray__", _first(-1)), "left_at"),
    "left_at of a present agent": (_left_while_present, "left_at holds a time for an agent still present"),
    "inventory 10**6": (_set(f"{ENGINE}.inventory.__ndarray__", _first(10**6)), "inventory"),
    "harms negative": (_set(f"{ENGINE}.episode_harms.__ndarray__", _first(-1)), "episode_harms"),
    "a battery in Coexistence": (_battery_in_coexistence, "its environment has no batteries"),
    "cells of one agent": (_set(f"{ENGINE}.cells.__ndarray__", lambda t: t[:, :1].clone()), "cells"),
    "presence as integers": (
        _set(f"{ENGINE}.present", lambda _: {"__ndarray__": torch.ones(2, 2, dtype=torch.int64), "dtype": "int64"}),
        "present",
    ),
    "an engine array too many": (_set(ENGINE, lambda engine: {**engine, "extra": engine["t"]}), "extra"),
    "seed -1": (_set(f"{STREAM}.seeds.0", lambda _: -1), "seeds"),
    "seed 10**400": (_set(f"{STREAM}.seeds.0", lambda _: HUGE), "seeds"),
    "seed of another run": (_set(f"{STREAM}.seeds.0", lambda _: derive_key(7, STREAMS["train_env"])), "seeds"),
    "stream position past its block": (_set(f"{STREAM}.position.__ndarray__", _first(10**6)), "streams.position"),
    "stream buffer of one number": (_set(f"{STREAM}.buffer.__ndarray__", lambda t: t[:, :1].clone()), "streams.buffer"),
    "stream number not in [0, 1)": (_set(f"{STREAM}.buffer.__ndarray__", _first(2.0)), "streams.buffer"),
    "harmed by agent 99": (_set("vector.events.harmed_by.__ndarray__", _first(99)), "events.harmed_by"),
    "events of one agent": (
        _set("vector.events.rewards.__ndarray__", lambda t: t[:, :1].clone()),
        "events.rewards",
    ),
    # 5 (probe 5, #6): a fixed policy's stream key changed within its range (rederived from the run's seed)
    "a cat's stream key of another seed": (
        _set("vector.policies.cat_0.keys.__ndarray__", _first(12345)),
        "vector.policies.cat_0.keys[0] is 12345",
    ),
    "fresh of 3 environments": (
        _set("vector.fresh", lambda _: {"__ndarray__": torch.ones(3, dtype=torch.bool), "dtype": "bool"}),
        "vector.fresh",
    ),
}


def forged(checkpointed: Path, tmp_path: Path, change: Callable[[dict[str, Any]], None]) -> tuple[Path, Path]:
    """A copy of ``checkpointed`` whose checkpoint ``change`` forged, and that checkpoint."""
    out = Path(shutil.copytree(checkpointed, tmp_path / "out"))
    (checkpoint,) = (out / "checkpoints").glob("*.pt")
    payload = torch.load(checkpoint, weights_only=True)
    change(payload)
    torch.save(payload, checkpoint)
    return out, checkpoint


def assert_refused(out: Path, checkpoint: Path, field: str, capsys: pytest.CaptureFixture[str]) -> None:
    """Training ``out`` again is refused in one line naming ``checkpoint`` and ``field``, and changes nothing."""
    before = listing(out)
    capsys.readouterr()
    status = main(train_command(out))
    err = one_line_refusal(capsys)
    assert status == 2, err
    assert str(checkpoint) in err and field in err, err
    assert listing(out) == before


@pytest.mark.parametrize("forgery", list(FORGERIES), ids=list(FORGERIES))
def test_a_forged_checkpoint_is_refused_in_one_line_naming_it_and_its_field(checkpointed, tmp_path, capsys, forgery):
    change, field = FORGERIES[forgery]
    out, checkpoint = forged(checkpointed, tmp_path, change)
    assert_refused(out, checkpoint, field, capsys)


WITHOUT_RUNS_LIST = [
    "log survival 10**400",
    "elapsed 1e300",
    "PCG64 state 2**200",
    "observations of 24 values",
    "observations not the environments'",
    "Adam step count negative",
    "left_at beyond max_cycles",
    "seed -1",
    "seed of another run",
    "stream position past its block",
    "harmed by agent 99",
    "a cat's stream key of another seed",
]
"""Forgeries refused from the checkpoint alone: by the bounds every run has and by its other fields."""


@pytest.mark.parametrize("forgery", WITHOUT_RUNS_LIST)
def test_a_forged_checkpoint_without_its_list_of_runs_is_refused(checkpointed, tmp_path, capsys, forgery):
    change, field = FORGERIES[forgery]
    out, checkpoint = forged(checkpointed, tmp_path, change)
    checkpoint.with_name(checkpoint.stem + ".runs.json").unlink()
    assert_refused(out, checkpoint, field, capsys)


def test_the_checkpoint_the_suite_wrote_resumes_and_is_then_removed(checkpointed, tmp_path, capsys):
    out = Path(shutil.copytree(checkpointed, tmp_path / "out"))
    assert main(train_command(out)) == 0, capsys.readouterr().err
    assert len(list((out / "runs").glob("*.json"))) == 2 and not list((out / "checkpoints").glob("*.pt"))


def test_a_checkpoint_without_its_list_of_runs_still_resumes(checkpointed, tmp_path, capsys):
    out = Path(shutil.copytree(checkpointed, tmp_path / "out"))
    (checkpoint,) = (out / "checkpoints").glob("*.pt")
    checkpoint.with_name(checkpoint.stem + ".runs.json").unlink()
    assert main(train_command(out)) == 0, capsys.readouterr().err
    assert len(list((out / "runs").glob("*.json"))) == 2


def test_a_stable_baselines3_checkpoint_resumes_exactly(tmp_path, monkeypatch):
    """Its numpy state (MT19937, a uint32 key) is a random state like any other, not a forgery."""
    pytest.importorskip("stable_baselines3")
    from helpers_resume import whole_and_resumed

    from empathy_zoo.experiment.model import RunSpec

    spec = RunSpec.of(
        method="sb3_ppo", steps=300, eval_interval=150, eval_episodes=1, settings={"net_arch": [8]}, env_kwargs={"max_cycles": 30}
    )
    whole, resumed = whole_and_resumed(spec, tmp_path, monkeypatch, checkpoint_interval=200)
    assert whole["train"] == resumed["train"] and whole["eval"] == resumed["eval"]
