"""Every numeric field of a reward transform is bounded when the transform is configured
(:func:`agents.transform_fields.configure_transform`), so a field that would shape rewards past what the
replay memory holds (:data:`agents.replay.MAX_ABS_REWARD`) is refused up front, naming the file,
the table and the key, on every way in: a sweep file (at ``--dry-run``), ``train --config``,
``train``'s options, a result file read back, a tuning range's ends."""

from __future__ import annotations

import dataclasses
import math
import warnings
from pathlib import Path

import pytest
from helpers_results import synthetic_document

from baselines.registry import METHODS, get_method
from empathy_zoo.cli import main
from empathy_zoo.experiment.model import RunSpec
from empathy_zoo.experiment.result_reader import check_result
from empathy_zoo.result_file import ResultFileError

SWEEP = """\
[sweep]
name = "t"
seeds = 1
steps = 600
eval_interval = 300
eval_episodes = 2
[settings]
learning_starts = 100
replay_capacity = 1000
hidden_size = 16
[envs.coexistence_v0]
max_cycles = 50
[[methods]]
method = "dqn_harm_penalty"
penalty = {penalty}
"""


def _bound() -> float:
    from agents.transform_fields import MAX_TRANSFORM_WEIGHT

    return MAX_TRANSFORM_WEIGHT


def _float_fields() -> list[tuple[str, str]]:
    """``(method, field)`` of every float field of every registered method's reward transform."""
    from agents.transform_fields import transform_fields

    return [
        (name, field)
        for name, method in METHODS.items()
        for field, kind in transform_fields(method.reward).items()
        if kind is float
    ]


def test_the_bound_keeps_a_shaped_reward_of_one_harm_within_the_replay_memory():
    from agents.replay import MAX_ABS_REWARD

    largest_step_reward = 2.0  # (Vase's cat: the largest reward of a step of any environment at its defaults)
    assert largest_step_reward + _bound() * 2 * math.pi <= MAX_ABS_REWARD


@pytest.mark.parametrize("penalty", ["2e6", "1e300", "-1e300"])
def test_a_sweep_file_past_the_bound_is_refused_at_dry_run(tmp_path, capsys, penalty):
    path = tmp_path / "pen.toml"
    path.write_text(SWEEP.format(penalty=penalty))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # (no numpy warning may come of it)
        assert main(["reproduce", "--profile", str(path), "--dry-run", "--out", str(tmp_path / "o_pen")]) == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in captured.err and "Warning" not in captured.err
    assert str(path) in lines[0] and "[[methods]] #1 (dqn_harm_penalty) penalty:" in lines[0]
    assert f"{_bound():,g}" in lines[0]
    assert not (tmp_path / "o_pen").exists()


def test_a_sweep_file_at_the_bound_is_planned(tmp_path, capsys):
    path = tmp_path / "pen.toml"
    path.write_text(SWEEP.format(penalty=f"-{_bound():g}"))
    assert main(["reproduce", "--profile", str(path), "--dry-run", "--out", str(tmp_path / "o_pen")]) == 0


def test_a_grid_value_past_the_bound_is_refused_naming_the_key(tmp_path, capsys):
    path = tmp_path / "grid.toml"
    path.write_text(SWEEP.format(penalty=f"[-100.0, {_bound() * 10:g}]"))
    assert main(["reproduce", "--profile", str(path), "--dry-run", "--out", str(tmp_path / "o")]) == 2
    assert "[[methods]] #1 (dqn_harm_penalty) penalty:" in capsys.readouterr().err


def test_train_config_past_the_bound_is_refused_before_any_output(tmp_path, capsys):
    out = tmp_path / "o_tr"
    path = tmp_path / "tr.toml"
    path.write_text(f'env = "coexistence_v0"\nmethod = "dqn_harm_penalty"\nout = "{out.as_posix()}"\n[reward]\npenalty = 2e6\n')
    assert main(["train", "--config", str(path)]) == 2
    err = capsys.readouterr().err
    assert f"{path}: [reward] penalty:" in err and "Traceback" not in err
    assert not out.exists()


def test_a_train_option_past_the_bound_is_refused_naming_field_and_method(tmp_path, capsys):
    out = tmp_path / "o_cli"
    assert main(["train", "--method", "dqn_harm_penalty", "--penalty", "1e300", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "penalty must be a number within" in err and "dqn_harm_penalty" in err and "Traceback" not in err
    assert not out.exists()


def test_a_result_file_past_the_bound_is_refused_by_the_reader():
    document = synthetic_document("coexistence_v0", "dqn_harm_penalty", 1.0, 0)
    assert document["config"]["reward"]["name"] == "harm_penalty"
    document["config"]["reward"]["penalty"] = 2e6
    with pytest.raises(ResultFileError, match=r"field config\.reward\.penalty: expected a number within"):
        check_result(document, "x.json")


def test_configure_transform_accepts_the_bound_and_refuses_just_above():
    from agents.transform_fields import TransformFieldError, configure_transform

    transform = get_method("dqn_harm_penalty").reward
    for value in (_bound(), -_bound(), int(_bound())):
        assert configure_transform(transform, {"penalty": value}, "dqn_harm_penalty").penalty == value
    for value in (math.nextafter(_bound(), math.inf), -_bound() - 1e-6, int(_bound()) + 1, 2e6, 1e300, 10**400):
        with pytest.raises(TransformFieldError, match=r"penalty must be a number within .*dqn_harm_penalty"):
            configure_transform(transform, {"penalty": value}, "dqn_harm_penalty")


@pytest.mark.parametrize(("method", "field"), _float_fields())
def test_every_float_field_of_every_transform_is_refused_past_the_bound(method, field):
    from agents.transform_fields import TransformFieldError

    for value in (_bound() + 1, -(_bound() + 1)):
        with pytest.raises(TransformFieldError, match=f"^{field} must be a number within"):
            RunSpec.of(method=method, reward={field: value})


def test_the_generator_covers_every_shipped_transform_with_float_fields():
    names = {type(METHODS[method].reward).__name__ for method, _ in _float_fields()}
    assert {"HarmPenalty", "InequityAversion", "NegativeRewardEmpathy", "SocialValueOrientation"} <= names
    assert {"RelativeReachability", "AttainableUtility", "Considerate", "Lagrangian"} <= names


def test_an_int_field_past_its_bound_is_refused():
    from agents.transform_fields import MAX_TRANSFORM_COUNT, TransformFieldError

    with pytest.raises(TransformFieldError, match="replay_capacity must be an int within"):
        RunSpec.of(method="dqn_aup", reward={"replay_capacity": MAX_TRANSFORM_COUNT + 1})


def test_inequity_aversion_bounds_the_weight_of_its_smoothed_rewards():
    from agents.transform_fields import MAX_TRANSFORM_WEIGHT

    with pytest.raises(ValueError, match=r"smoothing must be in \[0, 1\)"):
        RunSpec.of(method="dqn_inequity_aversion", reward={"smoothing": 2.0})
    with pytest.raises(ValueError, match="must be at most"):
        RunSpec.of(method="dqn_inequity_aversion", reward={"disadvantageous": 5.0, "smoothing": 0.99999})
    at_bound = {"disadvantageous": MAX_TRANSFORM_WEIGHT / 2, "smoothing": 0.5}
    assert RunSpec.of(method="dqn_inequity_aversion", reward=at_bound).reward_transform() is not None


def test_a_tuning_range_past_the_bound_is_refused_before_a_study(tmp_path):
    from empathy_zoo.experiment.search_space import check_ends, parse_param

    base = RunSpec.of(method="dqn_harm_penalty")
    spec = parse_param(f"penalty=float:-{_bound() * 10:g}:-100", get_method("dqn_harm_penalty"))
    with pytest.raises(ValueError, match="refuses penalty"):
        check_ends(base, [spec])
    inside = parse_param(f"penalty=float:-{_bound():g}:-100", get_method("dqn_harm_penalty"))
    check_ends(base, [inside])


def test_relative_reachabilitys_fields_have_their_types():
    from agents.transform_fields import transform_fields

    kinds = transform_fields(get_method("dqn_relative_reachability").reward)
    assert kinds == {"weight": float, "discount": float, "final_penalty": str}


def test_the_default_transforms_are_within_the_bound():
    for method in METHODS.values():
        if method.reward is None or not dataclasses.is_dataclass(method.reward):
            continue
        for field in dataclasses.fields(method.reward):
            value = getattr(method.reward, field.name)
            if isinstance(value, float):
                assert abs(value) <= _bound(), (method.name, field.name)


def test_the_shipped_profiles_and_results_hold_fields_within_the_bound():
    import json

    root = Path(__file__).resolve().parents[1]
    for path in sorted((root / "docs" / "results").glob("**/runs/*.json"))[::25]:  # (a sample: the full read is slow)
        reward = json.loads(path.read_text()).get("config", {}).get("reward") or {}
        for name, value in reward.items():
            if isinstance(value, float):
                assert abs(value) <= _bound(), (path, name)
