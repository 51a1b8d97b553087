"""A checkpoint's reward-transform states are data: each is checked against the state its
transform holds and against the ranges its runs allow, before anything trains, and a forged one
is refused in one line naming the checkpoint and the field."""

from __future__ import annotations

import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import torch
from test_checkpoint_forgeries import listing, one_line_refusal, train_command

from empathy_zoo.cli import main
from empathy_zoo.training import ensemble

METHODS = ("dqn_inequity_aversion", "dqn_lagrangian", "dqn_aup", "dqn_considerate", "dqn_relative_reachability")


def command(method: str, out: Path) -> list[str]:
    return [*train_command(out), "--method", method]


@pytest.fixture(scope="module")
def checkpoints(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """One output directory per method, killed just after its checkpoint at step 200."""
    real = ensemble.save_checkpoint

    def save_then_die(path: Path, payload: dict[str, Any]) -> None:
        real(path, payload)
        raise KeyboardInterrupt

    made = {}
    ensemble.save_checkpoint = save_then_die
    try:
        for method in METHODS:
            out = tmp_path_factory.mktemp(method) / "out"
            assert main(command(method, out)) != 0
            made[method] = out
    finally:
        ensemble.save_checkpoint = real
    return made


def _array(key: str, change: Callable[[torch.Tensor], None]) -> Callable[[dict[str, Any]], None]:
    """A forgery of the first transform state's array ``key``, edited in place by ``change``."""

    def forge(payload: dict[str, Any]) -> None:
        change(payload["rewards"][0][key]["__ndarray__"])

    return forge


def _as_int(key: str) -> Callable[[dict[str, Any]], None]:
    def forge(payload: dict[str, Any]) -> None:
        saved = payload["rewards"][0][key]
        payload["rewards"][0][key] = {"__ndarray__": saved["__ndarray__"].to(torch.int64), "dtype": "int64"}

    return forge


def _fill(key: str, value: float) -> Callable[[dict[str, Any]], None]:
    return _array(key, lambda a: a.__setitem__(slice(None), value))


def _extra(payload: dict[str, Any]) -> None:
    payload["rewards"][0]["evil"] = payload["rewards"][0][next(iter(payload["rewards"][0]))]


FORGERIES: dict[str, tuple[str, Callable[[dict[str, Any]], None], str]] = {
    "ia-own-large": ("dqn_inequity_aversion", _fill("own", 1e5), "own holds"),
    "ia-own-nan": ("dqn_inequity_aversion", _fill("own", float("nan")), "own holds nan"),
    "ia-extra-key": ("dqn_inequity_aversion", _extra, "'evil'"),
    "ia-own-int": ("dqn_inequity_aversion", _as_int("own"), "own is int64"),
    "lagrangian-multiplier": ("dqn_lagrangian", _fill("multiplier", 1e5), "multiplier holds"),
    "lagrangian-negative": ("dqn_lagrangian", _fill("multiplier", -1.0), "multiplier holds"),
    "lagrangian-cost": ("dqn_lagrangian", _fill("episode_cost", -1e12), "episode_cost holds"),
    "rr-nan": ("dqn_relative_reachability", _fill("last_deviation", float("nan")), "last_deviation holds nan"),
    "rr-negative": ("dqn_relative_reachability", _fill("last_deviation", -3.0), "last_deviation holds"),
    "aup-seen": ("dqn_aup", _fill("seen", 10**15), "seen holds"),
    "aup-seeds": ("dqn_aup", _fill("seeds", 7), "seeds is not"),
    "aup-reward-map": ("dqn_aup", _fill("reward_map", 1e30), "reward_map is not"),
    "aup-action": ("dqn_aup", _fill("action", 99), "action holds 99"),
    "aup-loss": ("dqn_aup", _fill("loss", -1.0), "loss holds"),
    "considerate-stored": ("dqn_considerate", _fill("stored", 10**12), "stored holds"),
    "considerate-reward": ("dqn_considerate", _fill("reward", float("nan")), "reward holds nan"),
    "considerate-last-obs": ("dqn_considerate", _fill("last_obs", 1e30), "last_obs holds"),
    "considerate-updates": ("dqn_considerate", _fill("updates", -7), "updates holds"),
}


@pytest.mark.parametrize("name", list(FORGERIES), ids=list(FORGERIES))
def test_a_forged_transform_state_is_refused_naming_it(checkpoints, tmp_path, capsys, name) -> None:
    method, forge, field = FORGERIES[name]
    out = Path(shutil.copytree(checkpoints[method], tmp_path / "out"))
    (checkpoint,) = (out / "checkpoints").glob("*.pt")
    payload = torch.load(checkpoint, weights_only=True)
    forge(payload)
    torch.save(payload, checkpoint)
    before = listing(out)
    capsys.readouterr()
    status = main(command(method, out))
    err = one_line_refusal(capsys)
    assert status == 2, err
    assert str(checkpoint) in err and "rewards[0]" in err and field in err, err
    assert listing(out) == before


@pytest.mark.parametrize("method", METHODS)
def test_an_untouched_transform_state_resumes(checkpoints, tmp_path, capsys, method) -> None:
    out = Path(shutil.copytree(checkpoints[method], tmp_path / "out"))
    assert main(command(method, out)) == 0, capsys.readouterr().err
    assert not list((out / "checkpoints").glob("*.pt"))
