"""The tenth probe's findings, each fixed at its cause.

* A checkpoint's ``learner.update_kernel`` is one of the kernels, or the checkpoint is refused in
  one line that quotes it through ``shown`` (no terminal escape, bounded).
* A checkpoint's networks, target networks and Adam moments are float32, and Adam's mean of
  squared gradients is never negative (a negative one trains a NaN network).
* An agent file is never written with a weight that is no finite number.
* A checkpoint whose list of runs was edited, but whose name is that of the runs asked for, is
  set aside (``.disowned``): nothing resumes from it, nothing deletes it.
* ``analyse tuning-effect`` and ``analyse heldout-verdicts`` show labels as text.
* A bare ``https://`` or ``www.`` address in data opens no link in Markdown.
"""

from __future__ import annotations

import dataclasses
import json
import re
import shutil
from pathlib import Path

import pytest
import torch
from helpers_results import synthetic_result
from test_checkpoint_forgeries import _first, _set, assert_refused, checkpointed, forged, train_command

from empathy_zoo.agent_file import agent_document
from empathy_zoo.cli import main
from empathy_zoo.markdown_escape import markdown_text
from empathy_zoo.run_ids import run_id
from leaderboard.heldout_verdicts import Reading, verdicts_markdown
from leaderboard.tuning_effect import tuning_effect, tuning_effect_table

__all__ = ["checkpointed"]  # (the fixture, shared with tests/test_checkpoint_forgeries.py)

ESC, BEL = "\x1b", "\x07"
HOSTILE = "Emp <img src=x>[c](javascript:alert(1))![i](http://e.com/i.png)`cd`*em*_u_|pipe"


def live(token: str, text: str) -> bool:
    """Whether ``token`` stands in ``text`` not escaped (no backslash before it)."""
    return re.search(r"(?<!\\)" + re.escape(token), text) is not None


# ---------------------------------------------------------------------------- 1, 2. checkpoints
def test_a_checkpoints_update_kernel_is_a_kernel_quoted_safely(checkpointed, tmp_path, capsys) -> None:
    text = f"numba{ESC}[2J{ESC}]8;;http://evil{BEL}X{BEL}\u202e" + "x" * 100_000
    out, checkpoint = forged(checkpointed, tmp_path, _set("learner.update_kernel", lambda _: text))
    assert_refused(out, checkpoint, "learner.update_kernel", capsys)


def test_the_refusal_of_a_kernel_holds_no_escape_and_is_short(checkpointed, tmp_path, capsys) -> None:
    out, _ = forged(checkpointed, tmp_path, _set("learner.update_kernel", lambda _: f"numba{ESC}[2J" + "x" * 100_000))
    capsys.readouterr()
    assert main(train_command(out)) == 2
    err = capsys.readouterr().err
    assert ESC not in err and len(err) < 2_000


@pytest.mark.parametrize(
    ("path", "value", "field"),
    [
        ("learner.optimizer.exp_avg_sq.0", _first(-1.0), "learner.optimizer.exp_avg_sq[0] holds a negative value"),
        ("learner.online.0", lambda t: t.to(torch.float16), "learner.online[0] has dtype torch.float16"),
        ("learner.online.0", lambda t: t.to(torch.float64), "learner.online[0] has dtype torch.float64"),
        ("learner.target.1", lambda t: t.to(torch.float16), "learner.target[1] has dtype torch.float16"),
        ("learner.optimizer.exp_avg.0", lambda t: t.to(torch.float64), "learner.optimizer.exp_avg[0] has dtype"),
    ],
)
def test_a_checkpoints_networks_are_float32_and_adams_squares_not_negative(checkpointed, tmp_path, capsys, path, value, field):
    out, checkpoint = forged(checkpointed, tmp_path, _set(path, value))
    assert_refused(out, checkpoint, field, capsys)


def test_an_agent_file_is_never_written_with_a_weight_that_is_no_finite_number() -> None:
    heads = {"q": [torch.zeros(4, 3), torch.zeros(3)]}
    heads["q"][0][0, 0] = float("nan")
    with pytest.raises(ValueError, match="head 'q' holds a weight that is no finite number"):
        agent_document({"heads": heads, "acting": "q"}, {})


# ---------------------------------------------------------------------------- 3. a disowned checkpoint
def test_an_edited_list_of_runs_sets_the_checkpoint_aside_and_the_runs_start_again(checkpointed, tmp_path, capsys) -> None:
    out = Path(shutil.copytree(checkpointed, tmp_path / "out"))
    (checkpoint,) = (out / "checkpoints").glob("*.pt")
    runs_list = checkpoint.with_name(checkpoint.stem + ".runs.json")
    records = json.loads(runs_list.read_text())
    records["runs"][0]["steps"] = 99_999_999
    runs_list.write_text(json.dumps(records))
    saved = checkpoint.read_bytes()
    fresh = Path(shutil.copytree(checkpointed, tmp_path / "fresh"))
    shutil.rmtree(fresh / "checkpoints")
    capsys.readouterr()
    assert main(train_command(out)) == 0
    err = capsys.readouterr().err
    assert f"set aside checkpoint {checkpoint} as {checkpoint.name}.disowned" in err
    assert (out / "checkpoints" / f"{checkpoint.name}.disowned").read_bytes() == saved  # (kept, untouched)
    assert (out / "checkpoints" / f"{runs_list.name}.disowned").exists()
    assert main(train_command(fresh)) == 0
    for result in sorted((fresh / "runs").glob("*.json")):  # (trained from scratch: as a run that never had a checkpoint)
        mine, theirs = json.loads((out / "runs" / result.name).read_text()), json.loads(result.read_text())
        assert mine["train"] == theirs["train"] and mine["eval"] == theirs["eval"]


# ---------------------------------------------------------------------------- 4. labels in two tools
def test_tuning_effect_shows_labels_as_text() -> None:
    def rows(method: str, beta: float, label: str, harms: float) -> list:
        return [
            dataclasses.replace(synthetic_result("coexistence_v0", method, beta, s, harms=harms), method_label=label)
            for s in range(5)
        ]

    untuned = rows("dqn", 1.0, "DQN", 0.9) + rows("empathic_dqn", 0.5, HOSTILE, 0.1)
    tuned = rows("dqn", 1.0, "DQN, tuned", 0.9) + rows("empathic_dqn", 0.5, HOSTILE + ", tuned", 0.1)
    tuned += rows("dqn_harm_penalty", 1.0, HOSTILE + " alone, tuned", 0.1)
    text = tuning_effect_table(tuning_effect(untuned, tuned, {"coexistence_v0": ("harms",)}))
    assert HOSTILE.split("<")[0] in text
    for token in ("<img", "[c](", "[i](", "`cd`", "*em*", "_u_", "|pipe", "http://"):
        assert not live(token, text), token


def test_heldout_verdicts_shows_labels_and_names_as_text() -> None:
    fields = {f.name for f in dataclasses.fields(Reading)}
    values = dict.fromkeys(fields, "x") | {"env": "coexistence_v0", "method_label": HOSTILE, "scenario": "s"}
    values |= {"trained_versus_dqn": None, "versus_dqn": None, "old_verdict": "a", "verdict": "a"}
    text = verdicts_markdown([Reading(**values)])
    for token in ("<img", "[c](", "[i](", "`cd`", "*em*", "_u_", "|pipe", "http://"):
        assert not live(token, text), token


# ---------------------------------------------------------------------------- 5. bare addresses
@pytest.mark.parametrize(
    ("text", "shown"),
    [
        ("see https://evil.example.com/x", "see https\\://evil.example.com/x"),
        ("HTTP://x", "HTTP\\://x"),
        ("www.evil.com", "www\\.evil.com"),
        ("at www.evil.com now", "at www\\.evil.com now"),
        ("a ratio 3:2 and a//b", "a ratio 3:2 and a//b"),
        ("Empathic DQN (β=0.5)", "Empathic DQN (β=0.5)"),
    ],
)
def test_a_bare_address_in_data_opens_no_link(text, shown) -> None:
    assert markdown_text(text) == shown


# ---------------------------------------------------------------------------- 6. a table's arguments
@pytest.mark.parametrize("arguments", [[["size", f"5{ESC}[2J"]], [["size"]], "size=5", [["size", 10**30]], [["a", 1]] * 21])
def test_a_separation_tables_arguments_are_checked(tmp_path, arguments) -> None:
    from baselines.separation_file import SeparationTableError, read_separation_table

    document = json.loads((Path(__file__).resolve().parents[1] / "docs/results/separation/sharing_v0.json").read_text())
    document["arguments"] = arguments
    (tmp_path / "t.json").write_text(json.dumps(document))
    with pytest.raises(SeparationTableError, match=r"field arguments"):
        read_separation_table(tmp_path / "t.json")


def test_a_column_of_a_smaller_variant_names_it() -> None:
    from leaderboard.discrimination_section import _column

    assert _column("sharing_v0", {"arguments": [["size", 5], ["view", 3]]}) == "sharing_v0 (exact: size=5, view=3)"
    assert _column("coexistence_v0", {"arguments": []}) == "coexistence_v0"


# ---------------------------------------------------------------------------- 7. an agent's settings
SHIPPED_AGENT = Path(__file__).resolve().parents[1] / "docs/results/quick/runs"


@pytest.mark.parametrize("settings", [{"selfishness": float("nan")}, {"selfishness": -3}, {"selfishness": "x"}, {"__class__": 1}])
def test_watch_refuses_an_agent_whose_settings_are_out_of_range(tmp_path, capsys, settings) -> None:
    source = sorted(SHIPPED_AGENT.glob("*empathic_dqn*.agent.pt"))[0]
    document = torch.load(source, weights_only=True)
    header = document["header"]
    header["settings"] = {**header["settings"], **settings}
    config = {key: value for key, value in header.items() if key != "run_id"}
    header["run_id"] = run_id(header["variant"], header["method"], config, header["seed"])  # (a forgery consistent with itself)
    forged_file = tmp_path / source.name
    torch.save(document, forged_file)
    capsys.readouterr()
    assert main(["watch", str(forged_file), "--episodes", "1"]) == 2
    err = capsys.readouterr().err
    assert "field header.settings" in err and err.count("\n") == 1


def test_tuning_effect_refuses_one_directory_given_twice(tmp_path, capsys) -> None:
    from leaderboard.tuning_effect import main as tuning_effect_main

    assert tuning_effect_main([str(tmp_path), str(tmp_path / ".")]) == 2
    err = capsys.readouterr().err
    assert "are one directory" in err and err.count("\n") == 1, err
