"""Sweep files (empathy_zoo/experiment/sweep_file.py): every validation error names file, table and key; grids,
seeds and the shipped profiles expand to the expected runs."""

from __future__ import annotations

import textwrap
from dataclasses import asdict, fields

import pytest

from agents.empathic_dqn import linear_epsilon
from agents.settings import PER_RUN_FIELDS, EmpathicDQNSettings
from baselines.shaping import HarmPenalty
from empathy_zoo.experiment.sweep_file import load_sweep, profile_path, profiles
from empathy_zoo.experiment.values import SweepConfigError

BASE = """
[sweep]
seeds = 2
steps = 1000
eval_interval = 500
eval_episodes = 2

[envs.coexistence_v0]

[envs.sharing_v0]

[[methods]]
method = "empathic_dqn"
selfishness = [1.0, 0.5]
"""


def write(tmp_path, text: str, name: str = "sweep.toml"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    return path


def error_of(tmp_path, text: str) -> str:
    path = write(tmp_path, text)
    with pytest.raises(SweepConfigError) as caught:
        load_sweep(path)
    message = str(caught.value)
    assert str(path) in message, message
    return message


# ---------------------------------------------------------------------------- expansion
def test_base_sweep_expands_grid_times_envs_times_seeds(tmp_path):
    specs = load_sweep(write(tmp_path, BASE))
    assert len(specs) == 2 * 2 * 2
    assert {(s.variant.label, s.method_settings().selfishness, s.seed) for s in specs} == {
        (v, b, seed) for v in ("coexistence_v0", "sharing_v0") for b in (1.0, 0.5) for seed in (0, 1)
    }
    spec = next(s for s in specs if s.method_settings().selfishness == 0.5)
    assert spec.entry.label is None and spec.display_label() == "Empathic DQN (β=0.5)"
    assert (spec.steps, spec.eval_interval, spec.eval_episodes) == (1000, 500, 2)
    assert spec.variant.fixed is None and dict(spec.env_kwargs) == {}


def test_two_grids_give_every_combination(tmp_path):
    specs = load_sweep(
        write(
            tmp_path,
            BASE.replace(
                "selfishness = [1.0, 0.5]",
                "selfishness = [1.0, 0.5]\nlearning_rate = [1e-3, 5e-4, 1e-4]\n"
                'label = "E (β={selfishness:g}, lr={learning_rate:g})"',
            ),
        )
    )
    assert len(specs) == 2 * (2 * 3) * 2
    assert len({(s.variant.label, s.display_label()) for s in specs}) == 12
    assert {s.display_label() for s in specs if s.variant.label == "sharing_v0" and s.seed == 0} == {
        f"E (β={b:g}, lr={lr:g})" for b in (1.0, 0.5) for lr in (1e-3, 5e-4, 1e-4)
    }


def test_settings_precedence_and_presets(tmp_path):
    text = (
        BASE
        + """
[settings]
learning_rate = 0.002
selfishness = 0.75
hidden_size = 64

[[methods]]
method = "dqn_harm_penalty"
envs = ["coexistence_v0"]
hidden_size = 32
"""
    )
    specs = load_sweep(write(tmp_path, text))
    empathic = [s for s in specs if s.method == "empathic_dqn"]
    assert {s.method_settings().learning_rate for s in specs} == {0.002}
    assert {s.method_settings().hidden_size for s in empathic} == {64}
    assert {s.method_settings().selfishness for s in empathic} == {1.0, 0.5}  # the entry's grid wins
    penalty = [s for s in specs if s.method == "dqn_harm_penalty"]
    assert len(penalty) == 2 and {s.variant.label for s in penalty} == {"coexistence_v0"}
    settings = penalty[0].method_settings()
    assert (settings.hidden_size, settings.selfishness) == (32, 1.0)  # preset kept
    assert penalty[0].method_object().reward == HarmPenalty(-100.0) and penalty[0].config()["reward"] == {
        "name": "harm_penalty",
        "penalty": -100.0,
    }


def test_env_variant_fixed_policy_and_methods_filter(tmp_path):
    text = (
        BASE
        + """
[envs.big]
env = "coexistence_v0"
size = 9
max_cycles = 100
fixed = { cat_0 = "empathy_zoo.policies:Stay" }
methods = ["dqn"]

[[methods]]
method = "dqn"
envs = ["big"]
"""
    )
    specs = load_sweep(write(tmp_path, text))
    big = [s for s in specs if s.variant.label == "big"]
    assert len(big) == 2 and {s.method for s in big} == {"dqn"}
    assert dict(big[0].env_kwargs) == {"size": 9, "max_cycles": 100}
    assert big[0].fixed_policies() == {"cat_0": "empathy_zoo.policies:Stay"}
    assert big[0].run_id.startswith("big__dqn-")
    assert big[0].config()["variant"] == "big"


def test_seeds_list_and_override(tmp_path):
    path = write(tmp_path, BASE.replace("seeds = 2", "seeds = [3, 7]"))
    assert {s.seed for s in load_sweep(path)} == {3, 7}
    assert {s.seed for s in load_sweep(path, seeds=3)} == {0, 1, 2}
    assert len(load_sweep(path, seeds=1)) == 4
    with pytest.raises(SweepConfigError, match="--seeds must be a positive int"):
        load_sweep(path, seeds=0)


def test_paper_profile_is_the_papers_protocol():
    specs = load_sweep(profile_path("paper"))
    assert len(specs) == 2 * 5 * 10 == 100  # the paper ran 5 seeds; measured coverage asks 10
    assert {s.seed for s in specs} == set(range(10))
    assert {(s.steps, s.eval_interval, s.eval_episodes) for s in specs} == {(1_000_000, 50_000, 10)}
    defaults = asdict(EmpathicDQNSettings())
    for spec in specs:
        settings = asdict(spec.method_settings())
        assert {k: v for k, v in settings.items() if k not in PER_RUN_FIELDS} == {
            k: v for k, v in defaults.items() if k not in PER_RUN_FIELDS
        }
    for spec in specs:  # ε reaches its floor exactly at the last step, not after it (SPEC §6)
        settings = spec.method_settings()
        assert linear_epsilon(settings, spec.steps) == pytest.approx(0.01, abs=1e-12)
        assert linear_epsilon(settings, spec.steps - 1000) > 0.01 + 1e-6
    labels = {(s.variant.label, s.display_label()) for s in specs}
    assert labels == {
        *((env, f"Empathic DQN (β={b:g})") for env in ("coexistence_v0", "sharing_v0") for b in (1.0, 0.75, 0.5, 0.25)),
        ("coexistence_v0", "DQN + harm penalty (−100)"),
        ("sharing_v0", "DQN × equality"),
    }


def test_quick_and_example_profiles_parse():
    assert {"quick", "paper", "example_custom"} <= set(profiles())
    quick = load_sweep(profile_path("quick"))
    assert len(quick) == 2 * 5 * 3
    assert {s.method_settings().learning_starts for s in quick} == {2_000}
    example = load_sweep(profile_path("example_custom"))
    nine = [s for s in example if s.variant.label == "coexistence_9x9"]
    assert nine and {s.env_kwargs["size"] for s in nine} == {9}
    assert {s.fixed_policies()["cat_0"] for s in nine} == {"empathy_zoo.policies:Stay"}


def test_profile_path_accepts_a_file_and_rejects_unknown_names(tmp_path):
    path = write(tmp_path, BASE)
    assert profile_path(str(path)) == path
    with pytest.raises(SweepConfigError, match=r"unknown profile 'nope'.*quick"):
        profile_path("nope")
    with pytest.raises(SweepConfigError, match="does not exist"):
        profile_path(str(tmp_path / "missing.toml"))


# ---------------------------------------------------------------------------- validation errors
def test_unknown_top_level_table(tmp_path):
    message = error_of(tmp_path, BASE + "\n[sweeps]\nsteps = 3\n")
    assert "top level" in message and "'sweeps'" in message and "allowed keys: sweep, settings, envs, methods" in message


def test_unknown_key_in_sweep_lists_allowed(tmp_path):
    message = error_of(tmp_path, BASE.replace("steps = 1000", "step = 1000"))
    assert "[sweep]" in message and "'step'" in message
    assert "allowed keys: name, seeds, steps, eval_interval, eval_episodes" in message


def test_unknown_key_in_env_table(tmp_path):
    message = error_of(tmp_path, BASE.replace("[envs.sharing_v0]", "[envs.sharing_v0]\ngrid_size = 9"))
    assert "[envs.sharing_v0]" in message and "'grid_size'" in message and "size, view, max_cycles" in message


def test_unknown_key_in_method_entry_lists_settings_fields(tmp_path):
    message = error_of(tmp_path, BASE.replace("selfishness = [1.0, 0.5]", "selfishnes = 0.5"))
    assert "[[methods]] #1 (empathic_dqn)" in message and "'selfishnes'" in message
    assert all(f.name in message for f in fields(EmpathicDQNSettings))


def test_unknown_key_in_settings(tmp_path):
    message = error_of(tmp_path, BASE + "\n[settings]\nlr = 0.1\n")
    assert "[settings]" in message and "'lr'" in message and "learning_rate" in message


@pytest.mark.parametrize(
    ("old", "new", "where", "expected"),
    [
        ("steps = 1000", 'steps = "many"', "[sweep] steps", "expected int, got str 'many'"),
        ("steps = 1000", "steps = 1000.0", "[sweep] steps", "expected int, got float"),
        ("eval_episodes = 2", "eval_episodes = true", "[sweep] eval_episodes", "expected int, got bool"),
        ("seeds = 2", 'seeds = "3"', "[sweep] seeds", "expected int (number of seeds) or list"),
        ("selfishness = [1.0, 0.5]", 'selfishness = "high"', "[[methods]] #1 (empathic_dqn) selfishness", "expected float"),
        ("selfishness = [1.0, 0.5]", "hidden_size = 1.5", "[[methods]] #1 (empathic_dqn) hidden_size", "expected int"),
        ("selfishness = [1.0, 0.5]", 'hidden_size = "big"', "[[methods]] #1 (empathic_dqn) hidden_size", "expected int"),
        ("selfishness = [1.0, 0.5]", 'selfishness = [1.0, "x"]', "selfishness", "expected float, got str 'x'"),
        ("selfishness = [1.0, 0.5]", 'envs = "sharing_v0"', "envs", "expected list of strings"),
        ("[envs.sharing_v0]", '[envs.sharing_v0]\nsize = "9"', "[envs.sharing_v0] size", "expected int"),
        (
            "[envs.sharing_v0]",
            "[envs.sharing_v0]\nfixed = { human_0 = 3 }",
            "[envs.sharing_v0] fixed",
            "expected table of strings",
        ),
    ],
)
def test_wrong_types_name_key_and_expected_type(tmp_path, old, new, where, expected):
    assert old in BASE
    message = error_of(tmp_path, BASE.replace(old, new, 1))
    assert where in message and expected in message, message


def test_values_out_of_range(tmp_path):
    assert "expected a positive int, got 0" in error_of(tmp_path, BASE.replace("steps = 1000", "steps = 0"))
    assert "positive number of seeds" in error_of(tmp_path, BASE.replace("seeds = 2", "seeds = 0"))
    assert "listed twice" in error_of(tmp_path, BASE.replace("seeds = 2", "seeds = [1, 1]"))
    message = error_of(tmp_path, BASE.replace("[1.0, 0.5]", "[1.0, 2.0]"))
    assert "[[methods]] #1 (empathic_dqn)" in message and "selfishness must be in [0, 1]" in message
    message = error_of(tmp_path, BASE.replace("[envs.sharing_v0]", "[envs.sharing_v0]\nsize = 2"))
    assert "[envs.sharing_v0]" in message


def test_unknown_method_env_and_policy(tmp_path):
    message = error_of(tmp_path, BASE.replace('"empathic_dqn"', '"no_such_method"'))
    assert "[[methods]] #1 (no_such_method) method" in message and "unknown method" in message and "dqn_equality" in message
    message = error_of(tmp_path, BASE.replace('"empathic_dqn"', '"no_such_module:THING"'))
    assert "cannot import module 'no_such_module'" in message
    message = error_of(tmp_path, BASE.replace("[envs.sharing_v0]", "[envs.sharing_v9]"))
    assert "[envs.sharing_v9]" in message and "unknown environment 'sharing_v9'" in message
    message = error_of(tmp_path, BASE.replace("[envs.sharing_v0]", '[envs.mine]\nenv = "chess_v0"'))
    assert "[envs.mine] env" in message and "unknown environment 'chess_v0'" in message
    message = error_of(tmp_path, BASE.replace("[envs.sharing_v0]", '[envs.sharing_v0]\nfixed = { human_0 = "sleepy" }'))
    assert "[envs.sharing_v0] fixed.human_0" in message and "unknown fixed policy 'sleepy'" in message
    message = error_of(tmp_path, BASE.replace("[envs.sharing_v0]", '[envs.sharing_v0]\nfixed = { cat_0 = "stay" }'))
    assert "unknown agent(s) ['cat_0']" in message and "human_0" in message
    message = error_of(
        tmp_path, BASE.replace("[envs.sharing_v0]", '[envs.sharing_v0]\nfixed = { human_0 = "empathy_zoo.policies:Nobody" }')
    )
    assert "has no 'Nobody'" in message


def test_cross_references(tmp_path):
    message = error_of(tmp_path, BASE + 'envs = ["coexistence"]\n')
    assert "[[methods]] #1 (empathic_dqn) envs" in message and "unknown variant(s) ['coexistence']" in message
    message = error_of(tmp_path, BASE.replace("[envs.sharing_v0]", '[envs.sharing_v0]\nmethods = ["dqn"]'))
    assert "[envs.sharing_v0] methods" in message and "['dqn'] not declared" in message
    message = error_of(
        tmp_path,
        BASE
        + '\n[[methods]]\nmethod = "dqn"\nenvs = ["sharing_v0"]\n'
        + '\n[envs.other]\nenv = "sharing_v0"\nmethods = ["dqn"]\n',
    )
    assert "[envs.other] has no method to run" in message


def test_grids_and_duplicates(tmp_path):
    message = error_of(tmp_path, BASE.replace("[1.0, 0.5]", "[]"))
    assert "[[methods]] #1 (empathic_dqn) selfishness: empty grid" in message
    message = error_of(tmp_path, BASE.replace("[1.0, 0.5]", "[0.5, 0.5]"))
    assert "value listed twice" in message
    message = error_of(tmp_path, BASE + '\n[[methods]]\nmethod = "empathic_dqn"\nselfishness = 0.5\n')
    assert "[[methods]] #2 (empathic_dqn)" in message and "#1 (empathic_dqn)" in message and "same label" in message
    message = error_of(tmp_path, BASE + '\n[[methods]]\nmethod = "empathic_dqn"\nselfishness = 0.5\nlabel = "Other"\n')
    assert "[[methods]] #2 (empathic_dqn)" in message and "duplicates" in message and "[[methods]] #1" in message
    message = error_of(tmp_path, BASE.replace("selfishness = [1.0, 0.5]", 'selfishness = [1.0, 0.5]\nlabel = "Mine"'))
    assert "same label 'Mine'" in message and "placeholders" in message
    message = error_of(tmp_path, BASE + "\n[settings]\nlearning_rate = [0.1, 0.2]\n")
    assert "[settings] learning_rate" in message and "grid" in message


def test_presets_and_placeholders(tmp_path):
    message = error_of(tmp_path, BASE + '\n[[methods]]\nmethod = "dqn"\nselfishness = 0.5\n')
    assert "[[methods]] #2 (dqn)" in message and "fixes selfishness=1.0" in message
    message = error_of(tmp_path, BASE.replace("selfishness = [1.0, 0.5]", 'selfishness = [1.0, 0.5]\nlabel = "E {beta}"'))
    assert "[[methods]] #1 (empathic_dqn) on [envs.coexistence_v0]" in message and "label" in message and "'beta'" in message


def test_structure_errors(tmp_path):
    assert "at least one [[methods]]" in error_of(tmp_path, BASE.split("[[methods]]")[0])
    assert "at least one [envs.<variant>]" in error_of(
        tmp_path, BASE.replace("[envs.coexistence_v0]", "").replace("[envs.sharing_v0]", "")
    )
    assert "missing key 'method'" in error_of(tmp_path, BASE.replace('method = "empathic_dqn"', ""))
    assert "[envs.size]: must be a table" in error_of(tmp_path, BASE.replace("[envs.coexistence_v0]", "[envs]\nsize = 9"))
    assert "[envs.bad name]" in error_of(tmp_path, BASE.replace("[envs.sharing_v0]", '[envs."bad name"]\nenv = "sharing_v0"'))
    assert "not valid TOML" in error_of(tmp_path, BASE + "\nsteps = = 3\n")
    with pytest.raises(SweepConfigError, match="does not exist"):
        load_sweep(tmp_path / "missing.toml")


def test_variants_of_one_env_are_tabled_apart():
    import dataclasses

    from helpers_results import synthetic_result

    from leaderboard.aggregate import group_runs

    run = dataclasses.replace(synthetic_result("coexistence_v0", "dqn", 1.0, 0), method_label="DQN")
    runs = [dataclasses.replace(run, variant=variant) for variant in ("coexistence_v0", "coexistence_9x9")]
    assert list(group_runs(runs)) == [("coexistence_9x9", "DQN"), ("coexistence_v0", "DQN")]


@pytest.mark.parametrize("key, value", [("learning_starts", "100"), ("replay_capacity", "500"), ("epsilon_decay_steps", "900")])
def test_a_shared_setting_a_method_does_not_take_is_refused_not_dropped(tmp_path, key, value):
    """[settings] are defaults for every method: one a method has no field for is an error."""
    text = BASE + f'\n[settings]\n{key} = {value}\n\n[[methods]]\nmethod = "baselines.sb3:SB3_DQN"\n'
    message = error_of(tmp_path, text)
    assert f"[settings] {key}" in message and "[[methods]] #2 (baselines.sb3:SB3_DQN)" in message, message
    assert "algorithm_kwargs" in message and "[[methods]] entries" in message, message


def test_a_shared_setting_every_method_takes_is_applied_to_every_method(tmp_path):
    text = BASE + '\n[settings]\nlearning_rate = 0.002\ngamma = 0.9\n\n[[methods]]\nmethod = "baselines.sb3:SB3_DQN"\n'
    specs = load_sweep(write(tmp_path, text))
    assert {s.method_settings().learning_rate for s in specs} == {0.002}
    assert {s.method_settings().gamma for s in specs} == {0.9}


def test_a_train_config_setting_an_sb3_method_does_not_take_is_refused(tmp_path, capsys):
    from empathy_zoo.cli import main

    config = write(tmp_path, "[settings]\nlearning_starts = 100\n", "run.toml")
    argv = ["train", "--config", str(config), "--method", "baselines.sb3:SB3_DQN", "--out", str(tmp_path / "out")]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "[settings]: unknown key 'learning_starts'; allowed keys: algorithm" in err and "Traceback" not in err, err
    assert not (tmp_path / "out").exists()
