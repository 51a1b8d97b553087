"""Data runs no code and goes nowhere it should not (issue 25, causes 3 and smaller items).

* A checkpoint's list of runs is compared as data with the runs asked for, never resolved: a
  manifest naming a module imports nothing, and one that cannot be read is set aside, said, and
  never taken for "all its runs are finished" (its checkpoint is kept).
* A label template is plain ``{field}`` placeholders with a short format spec: indexing,
  attributes, conversions, nested fields and huge widths are refused naming file, table and key.
* Nothing is written through a symbolic link inside an output directory.
* A forged checkpoint without the learner's state says it is corrupted, naming it.
* ``LEADERBOARD.md`` escapes labels; a schema-1 file's shaping is a number and a boolean or
  refused; the command line refuses an empty path, an agent fixed twice and a negative seed,
  naming the option; an unknown environment argument is a ``ValueError``.
"""

from __future__ import annotations

import hashlib
import json
import sys
import tomllib
from pathlib import Path

import pytest
from helpers_results import derive_run_id, synthetic_document, synthetic_schema_1
from helpers_resume import TINY_SETTINGS

from empathy_zoo import coexistence_v0, sharing_v0
from empathy_zoo.atomic import write_json_atomic
from empathy_zoo.cli import main
from empathy_zoo.experiment.model import RunSpec
from empathy_zoo.experiment.result_reader import check_result
from empathy_zoo.experiment.sweep_file import parse_sweep
from empathy_zoo.experiment.values import SweepConfigError
from empathy_zoo.gym_adapter import make_single_agent_env
from empathy_zoo.names import confined
from empathy_zoo.result_file import ResultFileError
from empathy_zoo.training import RunnerOptions, train_runs
from empathy_zoo.training.checkpoint import save_checkpoint
from empathy_zoo.training.resume import CHECKPOINT_DIR, checkpoint_path, plan_ensembles
from empathy_zoo.vector import VectorEnv
from leaderboard.report import write_leaderboard

SETTINGS = TINY_SETTINGS


def specs(seeds=(0, 1)):
    return [
        RunSpec.of(settings=SETTINGS, seed=seed, steps=200, eval_interval=100, eval_episodes=1, env_kwargs={"max_cycles": 40})
        for seed in seeds
    ]


def options():
    return RunnerOptions(progress=False, checkpoint_interval=100, max_parallel_runs=4)


# ---------------------------------------------------------------------------- cause 3: checkpoints' lists of runs
SENTINEL = "reliability_sentinel"
"""A module that records being imported: a list of runs naming it must never import it."""


@pytest.fixture
def sentinel(tmp_path, monkeypatch):
    """The path of the file :data:`SENTINEL` writes when it is imported (it must stay absent)."""
    where = tmp_path / "modules"
    where.mkdir()
    marker = tmp_path / "imported"
    (where / f"{SENTINEL}.py").write_text(
        f"from pathlib import Path\nPath({str(marker)!r}).write_text('imported')\nMETHOD = None\nCat = None\n"
    )
    monkeypatch.syspath_prepend(str(where))
    yield marker
    sys.modules.pop(SENTINEL, None)


def digest_name(env, run_ids):
    return f"{env}-{hashlib.sha256('|'.join(run_ids).encode()).hexdigest()[:16]}.pt"


CODE_FIELDS = {
    "method": {"method": f"{SENTINEL}:METHOD"},
    "fixed policy": {"fixed": {"cat_0": f"{SENTINEL}:Cat"}},
    "fixed policy table": {"fixed": {"cat_0": {"policy": f"{SENTINEL}:Cat", "speed": 2}}},
}
"""The fields of a record that name code (the manifests a hostile tester writes)."""


def planted_checkpoint(out, records, run_ids, with_ids):
    """A checkpoint holding ``run_ids`` with a list of runs of ``records`` beside it (format 2
    with the run ids, else format 1)."""
    directory = out / CHECKPOINT_DIR
    checkpoint = directory / digest_name("coexistence_v0", run_ids)
    save_checkpoint(checkpoint, {"run_ids": list(run_ids)})
    runs = [{"run_id": run_id, **record} if with_ids else record for run_id, record in zip(run_ids, records, strict=True)]
    manifest = checkpoint.with_name(checkpoint.stem + ".runs.json")
    write_json_atomic(manifest, {"format": 2 if with_ids else 1, "runs": runs})
    return checkpoint, manifest


@pytest.mark.parametrize("with_asked", [False, True], ids=["alone", "beside-an-asked-run"])
@pytest.mark.parametrize("with_ids", [False, True], ids=["format1", "format2"])
@pytest.mark.parametrize("field", sorted(CODE_FIELDS))
def test_a_list_of_runs_naming_a_module_imports_nothing_and_its_checkpoint_is_kept(
    tmp_path, sentinel, field, with_ids, with_asked
):
    todo = specs()
    evil = {**todo[0].request(), **CODE_FIELDS[field]}
    records = [todo[0].request(), evil] if with_asked else [evil]
    run_ids = ([todo[0].run_id] if with_asked else []) + ["coexistence_v0__forged-0badc0de__s0"]
    out = tmp_path / "out"
    checkpoint, manifest = planted_checkpoint(out, records, run_ids, with_ids)
    notes = []
    chunks = plan_ensembles(todo, out, 4, notes.append)
    assert not sentinel.exists() and SENTINEL not in sys.modules
    assert checkpoint.exists() and manifest.exists()
    assert [[s.run_id for s in chunk] for chunk in chunks] == [[s.run_id for s in todo]]  # trained from scratch
    [note] = notes
    assert note.startswith(f"kept checkpoint {checkpoint}") and "coexistence_v0__forged-0badc0de__s0" in note


def test_a_plain_train_beside_a_manifest_naming_a_module_imports_nothing(tmp_path, sentinel):
    todo = specs(seeds=(0,))
    out = tmp_path / "out"
    checkpoint, _ = planted_checkpoint(out, [{**todo[0].request(), "method": f"{SENTINEL}:METHOD"}], ["x__s0"], False)
    notes = []
    [path] = train_runs(todo, out, options(), on_note=notes.append)
    assert path.is_file() and checkpoint.exists() and not sentinel.exists()
    assert any(note.startswith(f"kept checkpoint {checkpoint}") for note in notes), notes


UNREADABLE = {
    "not json": "{",
    "a list": "[]",
    "runs not a list": '{"format": 1, "runs": "x"}',
    "unknown format": '{"format": 9, "runs": [{}]}',
    "unknown key": '{"format": 1, "runs": [{"env": "coexistence_v0", "code": "os:system"}]}',
    "other run ids": '{"format": 2, "runs": [{"run_id": "a__s0", "env": "coexistence_v0"}]}',
}


@pytest.mark.parametrize("asked", [False, True], ids=["other-runs", "runs-asked"])
@pytest.mark.parametrize("text", list(UNREADABLE.values()), ids=list(UNREADABLE))
def test_an_unreadable_list_of_runs_is_set_aside_and_its_checkpoint_is_never_called_finished(tmp_path, text, asked):
    todo = specs()
    out = tmp_path / "out"
    run_ids = [s.run_id for s in todo] if asked else ["coexistence_v0__other-12345678__s0"]
    checkpoint = checkpoint_path(out, todo) if asked else out / CHECKPOINT_DIR / digest_name("coexistence_v0", run_ids)
    save_checkpoint(checkpoint, {"run_ids": run_ids})
    manifest = checkpoint.with_name(checkpoint.stem + ".runs.json")
    manifest.write_text(text)
    notes = []
    chunks = plan_ensembles(todo, out, 1, notes.append)  # (one run per ensemble: a resume is said)
    assert checkpoint.exists() and not manifest.exists()
    assert manifest.with_name(manifest.name + ".unreadable").read_text() == text
    assert not any("all its runs are finished" in note for note in notes), notes
    assert any(note.startswith(f"set aside {manifest}") and "cannot be read" in note for note in notes), notes
    if asked:  # the checkpoint's own run ids: it resumes
        assert [[s.run_id for s in chunk] for chunk in chunks] == [run_ids]
    else:
        assert any(note.startswith(f"kept checkpoint {checkpoint}") for note in notes), notes


def test_a_list_of_runs_of_other_seeds_rebuilds_them_from_the_runs_asked_for(tmp_path):
    """The --seeds case: a record equal to a run asked for but for its seed is that run with its
    seed (nothing resolved), and its checkpoint resumes as it was checkpointed."""
    checkpointed = specs(seeds=(0, 1, 2))
    out = tmp_path / "out"
    checkpoint = checkpoint_path(out, checkpointed)
    save_checkpoint(checkpoint, {"run_ids": [s.run_id for s in checkpointed]})
    write_json_atomic(
        checkpoint.with_name(checkpoint.stem + ".runs.json"),
        {"format": 2, "runs": [{"run_id": s.run_id, **s.request()} for s in checkpointed]},
    )
    notes = []
    [chunk] = plan_ensembles(specs(seeds=(0,)), out, 4, notes.append)
    assert [s.run_id for s in chunk] == [s.run_id for s in checkpointed]
    assert chunk == checkpointed
    assert any("not asked for here, but finished and written too" in note for note in notes), notes


@pytest.mark.parametrize("with_manifest", [False, True], ids=["checkpoint-alone", "with-its-list-of-runs"])
def test_a_checkpoint_copied_to_the_name_of_other_runs_is_set_aside_and_they_train(tmp_path, monkeypatch, with_manifest):
    """A checkpoint of run A renamed to the name run B's ensemble would have: it was said "kept"
    (it holds runs not asked for), then B's ensemble found it under its own name and refused it
    as "belongs to other runs". It is set aside (said, with the name that would resume it), and B
    trains to the files it gives without it."""
    import empathy_zoo.training.ensemble as ensemble

    first, second = specs(seeds=(0,)), specs(seeds=(1,))
    expected = json.loads(train_runs(second, tmp_path / "clean", options())[0].read_text())
    out = tmp_path / "out"
    real = ensemble._checkpoint

    def stop_after_the_first_checkpoint(*args, **kwargs):
        real(*args, **kwargs)
        raise KeyboardInterrupt

    with monkeypatch.context() as patch:
        patch.setattr(ensemble, "_checkpoint", stop_after_the_first_checkpoint)
        with pytest.raises(KeyboardInterrupt):
            train_runs(first, out, options())
    own = checkpoint_path(out, first)
    assert own.exists()
    wrong = checkpoint_path(out, second)
    own.rename(wrong)
    manifest = own.with_name(own.stem + ".runs.json")
    if with_manifest:
        manifest.rename(wrong.with_name(wrong.stem + ".runs.json"))
    else:
        manifest.unlink()
    notes: list[str] = []
    [path] = train_runs(second, out, options(), on_note=notes.append)
    unstamped = ("wall_time_s", "created")
    assert {k: v for k, v in json.loads(path.read_text()).items() if k not in unstamped} == {
        k: v for k, v in expected.items() if k not in unstamped
    }
    aside = wrong.with_name(wrong.name + ".misnamed")
    assert aside.exists() and not wrong.exists()
    said = [note for note in notes if note.startswith(f"set aside checkpoint {wrong} as {aside.name}")]
    assert said and first[0].run_id in said[0] and own.name in said[0], notes
    assert not any(note.startswith("kept checkpoint") for note in notes), notes


# ---------------------------------------------------------------------------- cause 3: label templates
SWEEP = """
[sweep]
seeds = 1
steps = 100

[envs.coexistence_v0]

[[methods]]
method = "dqn_inequity_aversion"
label = {label}
"""


def labelled(template: str):
    return parse_sweep(tomllib.loads(SWEEP.format(label=json.dumps(template))), source="labels.toml")


@pytest.mark.parametrize(
    "template",
    [
        "{gamma[0]}",
        "{gamma.real}",
        "{selfishness.__class__.__mro__}",
        "{reward.__class__}",
        "{reward.disadvantageous.__class__}",
        "{selfishness:>300000000}",
        "{selfishness:>100}",
        "{selfishness:.300f}",
        "{selfishness:{gamma}}",
        "{selfishness!r}",
        "{selfishness!s:>3}",
        "{}",
        "{0}",
        "{nosuch}",
        "{reward}",
        "open {",
        "close }",
        "{gamma:d}",
        "{others:.2f}",
    ],
)
def test_a_label_template_is_plain_placeholders_or_refused_naming_file_table_and_key(template):
    with pytest.raises(SweepConfigError) as caught:
        labelled(template)
    message = str(caught.value)
    assert message.startswith("labels.toml: [[methods]] #1 (dqn_inequity_aversion)") and " label: " in message
    assert len(message) < 2000


@pytest.mark.parametrize(
    "template, label",
    [
        ("IA {disadvantageous:g}", "IA 5"),
        ("IA {reward.smoothing:.2f}, γ={gamma}", "IA 0.94, γ=0.99"),
        ("{{literal}} {selfishness:+.1f}", "{literal} +1.0"),
        ("{hidden_size:>5d}|{hidden_size:<4}|{learning_rate:.0e}", "  128|128 |1e-03"),
        ("no placeholder", "no placeholder"),
    ],
)
def test_plain_placeholders_with_a_short_format_spec_are_expanded(template, label):
    [spec] = labelled(template)
    assert spec.display_label() == label


# ---------------------------------------------------------------------------- cause 3: no write through a link
SEEDS = range(3)


def leaderboard_dir(directory: Path, label: str | None = None) -> Path:
    for method, beta in (("empathic_dqn", 1.0), ("empathic_dqn", 0.5)):
        for seed in SEEDS:
            result = synthetic_document("coexistence_v0", method, beta, seed, harms=beta, survival=300.0 + 100 * beta)
            if label is not None and beta == 0.5:
                result["method_label"] = label
            write_json_atomic(directory / "runs" / f"{result['run_id']}.json", result)
    return directory


def test_the_leaderboard_writes_nothing_through_a_linked_figures_directory(tmp_path):
    out = leaderboard_dir(tmp_path / "out")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (out / "figures").symlink_to(elsewhere, target_is_directory=True)
    with pytest.raises(ValueError, match=f"{out / 'figures'} is a symbolic link"):
        write_leaderboard(out)
    assert list(elsewhere.iterdir()) == [] and not (out / "LEADERBOARD.md").exists()


@pytest.mark.parametrize("linked", ["runs", "checkpoints"])
def test_training_writes_nothing_through_a_linked_directory_of_the_output(tmp_path, linked):
    out, elsewhere = tmp_path / "out", tmp_path / "elsewhere"
    elsewhere.mkdir()
    out.mkdir()
    (out / linked).symlink_to(elsewhere, target_is_directory=True)
    with pytest.raises(ValueError, match=f"{out / linked} is a symbolic link"):
        train_runs(specs(seeds=(0,)), out, options())
    assert list(elsewhere.iterdir()) == []


def test_evaluate_writes_nothing_through_a_linked_evaluations_directory(tmp_path):
    from empathy_zoo.training.heldout import evaluate_results

    results = tmp_path / "results"
    train_runs(specs(seeds=(0,)), results, RunnerOptions(progress=False, checkpoint_interval=0))
    out, elsewhere = tmp_path / "out", tmp_path / "elsewhere"
    elsewhere.mkdir()
    out.mkdir()
    (out / "evaluations").symlink_to(elsewhere, target_is_directory=True)
    with pytest.raises(ValueError, match=f"{out / 'evaluations'} is a symbolic link"):
        evaluate_results(results, episodes=1, out_dir=out, progress=False)
    assert list(elsewhere.iterdir()) == []


@pytest.mark.parametrize("parts", [("a", "x.png"), ("a", "b", "x.png"), ("x.png",)])
def test_a_confined_path_through_a_link_below_its_root_is_refused(tmp_path, parts):
    root, elsewhere = tmp_path / "root", tmp_path / "root" / "inside"
    elsewhere.mkdir(parents=True)
    (elsewhere / "b").mkdir()
    link = root / parts[0]
    link.symlink_to(elsewhere if len(parts) > 1 else elsewhere / "x.png")
    with pytest.raises(ValueError, match=f"{link} is a symbolic link"):
        confined(root, *parts)


def test_an_output_directory_that_is_itself_a_link_is_written_to(tmp_path):
    real = leaderboard_dir(tmp_path / "real")
    link = tmp_path / "link"
    link.symlink_to(real, target_is_directory=True)
    paths = write_leaderboard(link)
    assert (real / "LEADERBOARD.md").is_file() and (real / "figures").is_dir() and not (real / "figures").is_symlink()
    assert paths["markdown"] == link / "LEADERBOARD.md"


# ---------------------------------------------------------------------------- forged checkpoints
def forged(run_ids, **fields):
    base = {
        "run_ids": run_ids,
        "step": 100,
        "elapsed": 1.0,
        "learner": {},
        "vector": {},
        "obs": [],
        "logs": [{} for _ in run_ids],
        "evaluations": [[] for _ in run_ids],
    }
    return {key: value for key, value in {**base, **fields}.items() if value is not None}


FORGED = {
    "only run ids": lambda ids: {"run_ids": ids},
    "no learner": lambda ids: forged(ids, learner=None),
    "empty learner state": lambda ids: forged(ids),
    "no vector state": lambda ids: forged(ids, vector=None),
    "step not a number": lambda ids: forged(ids, step="many"),
    "logs of other runs": lambda ids: forged(ids, logs=[]),
}


@pytest.mark.parametrize("payload", list(FORGED.values()), ids=list(FORGED))
def test_a_forged_checkpoint_without_the_learners_state_is_said_corrupted_naming_it(tmp_path, payload):
    todo = specs()
    out = tmp_path / "out"
    checkpoint = checkpoint_path(out, todo)
    save_checkpoint(checkpoint, payload([s.run_id for s in todo]))
    with pytest.raises(ValueError, match="corrupted") as caught:
        train_runs(todo, out, options())
    assert str(checkpoint) in str(caught.value) and checkpoint.exists()
    assert not list((out / "runs").glob("*.json"))


# ---------------------------------------------------------------------------- LEADERBOARD.md escapes labels
@pytest.mark.parametrize(
    "label, escaped",
    [
        ("<script>alert(1)</script>", r"\<script\>alert(1)\</script\>"),
        ("[click](javascript:alert(1))", r"\[click\](javascript:alert(1))"),
        ("![x](http://example.com/x.png)", r"!\[x\](http\://example.com/x.png)"),
        ("*bold* _it_ `code` ~~gone~~", r"\*bold\* \_it\_ \`code\` \~\~gone\~\~"),
        ("<img src=x onerror=alert(1)> &amp; a|b", r"\<img src=x onerror=alert(1)\> \&amp; a\|b"),
    ],
)
def test_leaderboard_markdown_escapes_labels(tmp_path, label, escaped):
    out = leaderboard_dir(tmp_path / "out", label=label)
    paths = write_leaderboard(out)
    markdown = paths["markdown"].read_text(encoding="utf-8")
    assert label not in markdown
    assert f"| {escaped} | 3 |" in markdown
    assert "| DQN | 3 |" in markdown and "other_return" in markdown  # (plain text stays as it is; β = 1 is shown as DQN)


# ---------------------------------------------------------------------------- schema-1 shaping
@pytest.mark.parametrize(
    "field, value",
    [
        ("equality_shaping", "yes"),
        ("equality_shaping", 1),
        ("equality_shaping", None),
        ("harm_penalty", "-100"),
        ("harm_penalty", True),
        ("harm_penalty", float("inf")),
        ("harm_penalty", None),
    ],
)
def test_a_schema_1_file_with_shaping_of_the_wrong_type_is_refused_naming_the_field(field, value):
    document = synthetic_schema_1("sharing_v0", "dqn_equality", 1.0, 0)
    document["config"]["settings"][field] = value
    with pytest.raises(ResultFileError, match=f"x.json: field config.settings.{field}"):
        check_result(document, "x.json")


def test_schema_1_shaping_of_the_right_types_is_read_as_before():
    document = synthetic_schema_1("sharing_v0", "dqn_equality", 1.0, 0)
    assert check_result(document, "x.json")["config"]["reward"] == {"name": "equality_scaling"}
    document = synthetic_schema_1("coexistence_v0", "dqn_harm_penalty", 1.0, 0)
    document["config"]["settings"]["harm_penalty"] = -100  # (an int is a number)
    assert check_result(derive_run_id(document), "x.json")["config"]["reward"] == {"name": "harm_penalty", "penalty": -100}


# ---------------------------------------------------------------------------- the command line
TRAIN = ["train", "--steps", "20", "--eval-interval", "20", "--eval-episodes", "1", "--no-progress"]


@pytest.mark.parametrize(
    "argv, message",
    [
        (["train", "--out", ""], "argument --out: an empty path"),
        (["leaderboard", ""], "argument DIR: an empty path"),
        (["leaderboard", "somewhere", "--out", ""], "argument --out: an empty path"),
        (["reproduce", "--profile", "quick", "--out", ""], "argument --out: an empty path"),
        (["train", "--fixed", "cat_0=stay", "--fixed", "cat_0=random_walk"], "argument --fixed: cat_0 is given twice"),
        (["play", "--fixed", "cat_0=stay", "--fixed", "cat_0=stay"], "argument --fixed: cat_0 is given twice"),
        (["play", "--seed", "-5"], "--seed must be non-negative, got -5"),
    ],
)
def test_the_command_line_refuses_an_empty_path_an_agent_fixed_twice_and_a_negative_seed(
    tmp_path, monkeypatch, capsys, argv, message
):
    monkeypatch.chdir(tmp_path)
    if argv[0] == "train":
        argv = [*TRAIN, *argv[1:], *([] if "--out" in argv else ["--out", "out"])]
    assert main(argv) == 2
    assert message in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_a_config_file_with_an_empty_out_is_refused(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    Path("run.toml").write_text('out = ""\n')
    assert main([*TRAIN, "--config", "run.toml"]) == 2
    assert "run.toml: out: an empty path" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.toml"]


def test_leaderboard_of_a_file_says_it_is_a_file(tmp_path, capsys):
    (tmp_path / "a.json").write_text("{}")
    assert main(["leaderboard", str(tmp_path / "a.json")]) == 2
    assert f"results directory {tmp_path / 'a.json'} is a file, not a directory" in capsys.readouterr().err


@pytest.mark.parametrize(
    "make",
    [
        lambda: coexistence_v0.parallel_env(bogus=1),
        lambda: sharing_v0.parallel_env(bogus=1),
        lambda: coexistence_v0.env(bogus=1),
        lambda: sharing_v0.env(bogus=1),
        lambda: VectorEnv("sharing_v0", 2, bogus=1),
        lambda: make_single_agent_env("sharing_v0", bogus=1),
    ],
    ids=["coexistence parallel", "sharing parallel", "coexistence aec", "sharing aec", "vector", "gymnasium"],
)
def test_an_unknown_environment_argument_is_a_value_error_naming_it(make):
    with pytest.raises(ValueError, match=r"takes no argument\(s\) \['bogus'\]") as caught:
        make()
    assert isinstance(caught.value, TypeError)  # (as Python's own for an unexpected keyword)


def test_a_record_of_a_list_of_runs_is_the_request_of_its_run():
    """What a record is compared with: a run's ``request()``, written as JSON, rebuilds that very
    run (its run id), so the comparison as data finds every run a list of runs holds."""
    for spec in specs(seeds=(0, 3)):
        assert RunSpec.of(**json.loads(json.dumps(spec.request()))).run_id == spec.run_id
