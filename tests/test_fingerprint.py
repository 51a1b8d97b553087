"""A finished run is reused only when the code that made it is the code that runs now: the same
empathy-zoo version and the same source of its plug-in modules (the commit does not count)."""

from __future__ import annotations

import hashlib
import importlib
import json
import re
import shutil
import sys
import types
from dataclasses import replace
from pathlib import Path

import pytest

from empathy_zoo.experiment.model import RunSpec
from empathy_zoo.experiment.result_reader import check_result, read_result
from empathy_zoo.provenance import package_version
from empathy_zoo.result_file import ResultFileError
from empathy_zoo.training import RunnerOptions, fingerprint, runner, train_runs
from empathy_zoo.training.fingerprint import CodeFingerprint, module_sha256, plugin_names
from empathy_zoo.training.results import write_result

MODULE = "fingerprint_user_method"
"""The user's own method module, written to a test's directory."""
SOURCE = '''"""A user's method: the built-in DQN under its own name."""

from dataclasses import replace

from baselines.registry import METHODS

MY_DQN = replace(METHODS["dqn"], name="my_dqn", label=lambda settings: "My DQN")
'''
EDITED = SOURCE + "\n# tuned: the same configuration, other code\n"
TINY = {"learning_starts": 64, "replay_capacity": 1_000, "epsilon_decay_steps": 200, "target_update_interval": 50}
OPTIONS = RunnerOptions(progress=False, threads=1, checkpoint_interval=0)
RERUN = replace(OPTIONS, rerun_changed=True)


def sha256(text: str) -> str:
    return hashlib.sha256(text.encode()).hexdigest()


def run(method: str) -> RunSpec:
    return RunSpec.of(env="coexistence_v0", method=method, settings=TINY, steps=300, eval_interval=150, eval_episodes=2)


def files_below(path: Path) -> dict[str, bytes]:
    return {str(p.relative_to(path)): p.read_bytes() for p in sorted(path.rglob("*")) if p.is_file()}


def no_training(*args, **kwargs):
    raise AssertionError("a finished run made by this code was trained again")


@pytest.fixture
def write_plugin(tmp_path, monkeypatch):
    """``write_plugin(source)``: (re)write the user's module; the next import reads the new source."""
    directory = tmp_path / "user"
    directory.mkdir()
    monkeypatch.syspath_prepend(str(directory))
    monkeypatch.setattr(sys, "dont_write_bytecode", True)

    def write(source: str) -> None:
        (directory / f"{MODULE}.py").write_text(source)
        sys.modules.pop(MODULE, None)
        importlib.invalidate_caches()

    yield write
    sys.modules.pop(MODULE, None)


@pytest.fixture(scope="module")
def finished_dqn(tmp_path_factory) -> Path:
    """An output directory holding one finished built-in run (copy it before changing it)."""
    out = tmp_path_factory.mktemp("dqn")
    train_runs([run("dqn")], out, OPTIONS)
    return out


def rewrite(path: Path, drop: str | None = None, **fields) -> dict:
    """Rewrite the result file ``path`` with ``fields`` set and ``drop`` removed, as another version wrote it."""
    result = {**json.loads(path.read_text()), **fields}
    if drop is not None:
        del result[drop]
    path.write_text(json.dumps(result))
    return result


def copy_of(out: Path, tmp_path: Path) -> tuple[Path, Path]:
    copy = tmp_path / "out"
    shutil.copytree(out, copy)
    return copy, copy / "runs" / f"{run('dqn').run_id}.json"


def test_an_edited_plugin_method_is_refused_then_retrained_on_request(write_plugin, tmp_path):
    write_plugin(SOURCE)
    out = tmp_path / "out"
    [path] = train_runs([run(f"{MODULE}:MY_DQN")], out, OPTIONS)
    assert json.loads(path.read_text())["plugin_sha256"] == {MODULE: sha256(SOURCE)}

    write_plugin(EDITED)
    spec = run(f"{MODULE}:MY_DQN")
    assert spec.run_id == path.stem, "the edit leaves the configuration, hence the run id, as it was"
    before = files_below(out)
    with pytest.raises(ValueError) as refused:
        train_runs([spec], out, OPTIONS)
    message = str(refused.value)
    assert spec.run_id in message
    assert (
        f"plug-in module {MODULE} changed since these results were made "
        f"(source hash {sha256(SOURCE)[:12]}… → {sha256(EDITED)[:12]}…)"
    ) in message
    assert "--out" in message and "delete those result files" in message and "rerun_changed=True" in message
    assert files_below(out) == before, "a refused call changes nothing"

    notes: list[str] = []
    assert train_runs([spec], out, RERUN, on_note=notes.append) == [path]
    assert json.loads(path.read_text())["plugin_sha256"] == {MODULE: sha256(EDITED)}
    assert any(note.startswith("retraining") and spec.run_id in note for note in notes), notes
    kept = [path.with_name(spec.run_id + ".agent.pt").name, path.name]
    assert sorted(p.name for p in path.parent.iterdir()) == kept, "the old files are gone, nothing set aside"


def test_an_unchanged_plugin_reuses_its_result_even_at_another_commit(write_plugin, tmp_path, monkeypatch):
    write_plugin(SOURCE)
    out = tmp_path / "out"
    [path] = train_runs([run(f"{MODULE}:MY_DQN")], out, OPTIONS)
    before = path.read_bytes()
    write_plugin(SOURCE)  # imported again: the same source
    monkeypatch.setattr(runner, "train_ensemble", no_training)
    monkeypatch.setattr(fingerprint, "git_commit", lambda: "0123abc")  # provenance only
    notes: list[str] = []
    assert train_runs([run(f"{MODULE}:MY_DQN")], out, OPTIONS, on_note=notes.append) == [path]
    assert path.read_bytes() == before and notes == []


def test_another_package_version_is_refused_naming_both(finished_dqn, tmp_path, monkeypatch):
    out, _path = copy_of(finished_dqn, tmp_path)
    made_by = package_version()
    monkeypatch.setattr(fingerprint, "package_version", lambda: "99.0.0")
    monkeypatch.setattr(runner, "train_ensemble", no_training)
    with pytest.raises(ValueError, match=f"made by empathy-zoo {made_by}, this is 99.0.0 \\(run {run('dqn').run_id}\\)"):
        train_runs([run("dqn")], out, OPTIONS)
    assert files_below(out) == files_below(finished_dqn)


def test_a_file_older_than_plugin_hashes_is_reused_with_a_note_or_retrained_on_request(write_plugin, tmp_path):
    write_plugin(SOURCE)
    out = tmp_path / "out"
    spec = run(f"{MODULE}:MY_DQN")
    [path] = train_runs([spec], out, OPTIONS)
    older = rewrite(path, drop="plugin_sha256")
    notes: list[str] = []
    assert train_runs([spec], out, OPTIONS, on_note=notes.append) == [path]
    assert json.loads(path.read_text()) == older
    [note] = notes
    assert note.startswith("reusing") and MODULE in note and spec.run_id in note and "rerun_changed" in note
    train_runs([spec], out, RERUN, on_note=notes.append)
    assert json.loads(path.read_text())["plugin_sha256"] == {MODULE: sha256(SOURCE)}


def test_a_builtin_run_older_than_plugin_hashes_is_reused_at_its_version(finished_dqn, tmp_path, monkeypatch):
    out, path = copy_of(finished_dqn, tmp_path)
    rewrite(path, drop="plugin_sha256")
    monkeypatch.setattr(runner, "train_ensemble", no_training)
    notes: list[str] = []
    assert train_runs([run("dqn")], out, OPTIONS, on_note=notes.append) == [path]
    assert notes == []
    rewrite(path, version="0.0.1")
    with pytest.raises(ValueError, match=f"made by empathy-zoo 0.0.1, this is {package_version()}"):
        train_runs([run("dqn")], out, OPTIONS)


class FakeRay:
    """Stands in for an initialised Ray (no Ray is started)."""

    @staticmethod
    def is_initialized() -> bool:
        return True


def test_the_ray_backend_is_checked_and_retrains_alike(finished_dqn, tmp_path, monkeypatch):
    """The Ray driver never writes over a result file: a retrained run's file is out of its way."""
    out, path = copy_of(finished_dqn, tmp_path)
    rewrite(path, version="0.0.1")
    dispatched: list[list[str]] = []

    def driver(chunks, out_dir, options, on_result=None):
        dispatched.append([spec.run_id for chunk in chunks for spec in chunk])
        for chunk in chunks:
            for result in runner.train_ensemble(chunk, out_dir, replace(options, backend="local"), write_results=False):
                if not (Path(out_dir) / "runs" / f"{result['run_id']}.json").exists():  # as the driver does
                    write_result(Path(out_dir), result)
                    on_result(result)

    monkeypatch.setattr(runner, "import_ray", lambda: FakeRay)
    monkeypatch.setattr(runner, "train_with_ray", driver)
    ray = replace(OPTIONS, backend="ray")
    with pytest.raises(ValueError, match=re.escape("made by empathy-zoo 0.0.1")):
        train_runs([run("dqn")], out, ray)
    assert dispatched == []
    written: list[str] = []
    train_runs([run("dqn")], out, replace(ray, rerun_changed=True), on_result=lambda r: written.append(r["run_id"]))
    assert dispatched == [[run("dqn").run_id]] and written == [run("dqn").run_id]
    assert json.loads(path.read_text())["version"] == package_version()
    assert sorted(p.name for p in path.parent.iterdir()) == [path.with_name(path.stem + ".agent.pt").name, path.name]


def test_a_set_aside_file_is_put_back_when_its_run_fails(finished_dqn, tmp_path, monkeypatch):
    out, path = copy_of(finished_dqn, tmp_path)
    rewrite(path, version="0.0.1")
    before = files_below(out)

    def crash(chunk, *args, **kwargs):
        assert not path.exists(), "set aside while it trains"
        raise KeyboardInterrupt

    monkeypatch.setattr(runner, "train_ensemble", crash)
    with pytest.raises(KeyboardInterrupt):
        train_runs([run("dqn")], out, RERUN)
    assert files_below(out) == before


def test_fixed_policies_by_module_path_are_fingerprinted_in_either_form():
    spec = types.SimpleNamespace(
        method="dqn",
        fixed_policies=lambda: {
            "cat_0": "helpers_policies:AlwaysLeft",
            "cat_1": {"policy": "helpers_crash:Crash", "speed": 2},
            "human_0": "patrol",
            "human_1": {"policy": "random_walk"},
        },
    )
    assert plugin_names(spec) == {
        "helpers_policies": ("helpers_policies:AlwaysLeft", "fixed policy"),
        "helpers_crash": ("helpers_crash:Crash", "fixed policy"),
    }
    spec = types.SimpleNamespace(method="dqn", fixed_policies=lambda: {"cat_0": {"speed": 2}})
    with pytest.raises(ValueError, match="missing key 'policy'"):
        plugin_names(spec)


def test_a_module_without_a_file_has_no_hash():
    assert module_sha256(types.ModuleType("built_in_memory")) is None
    assert module_sha256(sys) is None  # built into the interpreter
    assert module_sha256(json) == hashlib.sha256(Path(json.__file__).read_bytes()).hexdigest()


def test_a_plugin_without_a_file_cannot_be_told_and_the_commit_never_counts():
    now = CodeFingerprint("0.1.0", "0123abc", {"built": None, "edited": sha256("new")})
    made = CodeFingerprint("0.1.0", "4567def-dirty", {"built": None, "edited": sha256("new")})
    assert now.changes_since(made) == ([], ["plug-in module built has no source file to hash: whether it changed cannot be told"])
    made = CodeFingerprint("0.1.0", "0123abc", {"built": sha256("old"), "edited": sha256("old")})
    changed, unknown = now.changes_since(made)
    assert [reason.split(" (")[0] for reason in changed] == ["plug-in module edited changed since these results were made"]
    assert unknown == ["plug-in module built has no source file to hash: whether it changed cannot be told"]


def test_the_result_file_checks_plugin_hashes_when_present(finished_dqn):
    [path] = (finished_dqn / "runs").glob("*.json")
    result = read_result(path).to_document()
    check_result({**result, "plugin_sha256": {MODULE: None, "other": sha256("x")}}, path)
    check_result({key: value for key, value in result.items() if key != "plugin_sha256"}, path)
    with pytest.raises(ResultFileError, match=f"field plugin_sha256.{MODULE}: expected a SHA-256"):
        check_result({**result, "plugin_sha256": {MODULE: "abc"}}, path)
    with pytest.raises(ResultFileError, match="field plugin_sha256: expected an object"):
        check_result({**result, "plugin_sha256": ["abc"]}, path)


def test_the_command_line_refuses_results_of_other_code_or_retrains_them_with_rerun_changed(
    finished_dqn, tmp_path, monkeypatch, capsys
):
    from empathy_zoo.cli import main

    out, path = copy_of(finished_dqn, tmp_path)
    made = json.loads(path.read_text())
    monkeypatch.setattr(fingerprint, "package_version", lambda: "99.0.0")
    argv = [
        "train",
        "--method",
        "dqn",
        "--steps",
        "300",
        "--eval-interval",
        "150",
        "--eval-episodes",
        "2",
        "--out",
        str(out),
        "--checkpoint-interval",
        "0",
        "--no-progress",
        *[f"--{key.replace('_', '-')}={value}" for key, value in TINY.items()],
    ]
    assert main(argv) == 2
    assert "made by empathy-zoo" in capsys.readouterr().err and json.loads(path.read_text()) == made
    assert main([*argv, "--rerun-changed"]) == 0
    assert json.loads(path.read_text())["version"] == "99.0.0"
