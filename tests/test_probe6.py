"""A sixth probe's findings (issue 33, "files from elsewhere are inert"): a bounded read reserves
memory for the bytes it reads, not for its cap; a list of runs set aside twice never replaces the
first; checked files whose fields contradict each other are refused naming file and field; a
refused command leaves a lock file it did not create as it was."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import textwrap
from pathlib import Path
from typing import Any

import pytest

from empathy_zoo import limits
from empathy_zoo.bounded_read import read_data
from empathy_zoo.limits import read_bounded


# ---------------------------------------------------------------------------- bounded reads (#1)
class _Recording:
    """A file object that records every size asked of ``read`` (and refuses a large one)."""

    def __init__(self, handle: Any, asked: list[int], most: int) -> None:
        self.handle, self.asked, self.most = handle, asked, most

    def read(self, size: int = -1) -> bytes:
        self.asked.append(size)
        if size < 0 or size > self.most:
            raise AssertionError(f"read({size}) reserves more than the {self.most} bytes the file can hold")
        return self.handle.read(size)

    def fileno(self) -> int:
        return self.handle.fileno()

    def __enter__(self) -> _Recording:
        return self

    def __exit__(self, *_: object) -> None:
        self.handle.close()


def test_a_small_file_read_under_a_huge_cap_asks_for_its_size(tmp_path: Path, monkeypatch) -> None:
    path = tmp_path / "small.json"
    path.write_bytes(b"x" * 6000)
    asked: list[int] = []
    real = limits.open_regular
    monkeypatch.setattr(limits, "open_regular", lambda p, what: _Recording(real(p, what), asked, 6001))
    assert read_bounded(path, 10**12, "agent file") == b"x" * 6000
    assert asked and max(asked) <= 6001, asked


def test_a_file_whose_size_says_nothing_is_read_in_chunks_to_its_cap() -> None:
    status = Path("/proc/self/status")
    if not status.is_file() or status.stat().st_size:
        pytest.skip("needs a /proc file whose stated size is 0")
    assert b"VmSize" in read_bounded(status, 10**12, "note")
    with pytest.raises(ValueError, match=r"note /proc/self/status is larger than 100 bytes"):
        read_bounded(status, 100, "note")


def test_a_bounded_read_fits_in_little_memory(tmp_path: Path) -> None:
    """``read(n)`` reserves ``n`` bytes first: under an address-space limit of 1 GiB more than the
    interpreter holds, a 6 KB agent file is read under its 4 GB cap, and a file under 1 TB's."""
    if sys.platform != "linux":
        pytest.skip("RLIMIT_AS and /proc/self/status are Linux's")
    path = tmp_path / "x.agent.pt"
    path.write_bytes(b"a" * 6000)
    script = textwrap.dedent(
        f"""
        import resource
        from empathy_zoo.bounded_read import read_data
        from empathy_zoo.limits import read_bounded
        size = next(int(line.split()[1]) for line in open("/proc/self/status") if line.startswith("VmSize:")) * 1024
        resource.setrlimit(resource.RLIMIT_AS, (size + (1 << 30), resource.getrlimit(resource.RLIMIT_AS)[1]))
        assert len(read_data({str(path)!r}, "agent file")) == 6000
        assert len(read_bounded({str(path)!r}, 1 << 40, "checkpoint")) == 6000
        print("read")
        """
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and done.stdout.strip() == "read", done.stderr[-2000:]


def test_a_file_past_its_cap_and_a_device_are_still_refused(tmp_path: Path) -> None:
    path = tmp_path / "big.json"
    path.write_bytes(b"y" * 101)
    with pytest.raises(ValueError, match=rf"result file {path} is larger than 100 bytes"):
        read_bounded(path, 100, "result file")
    assert read_bounded(path, 101, "result file") == b"y" * 101
    if os.path.exists("/dev/zero"):
        with pytest.raises(ValueError, match="/dev/zero is a character device, not a regular file"):
            read_data("/dev/zero", "agent file")
        with pytest.raises(ValueError, match="/dev/zero is a character device"):
            read_bounded("/dev/zero", 10**12, "note")


# ---------------------------------------------------------------------------- lists of runs set aside (#2)
def _planted(out: Path, run_ids: list[str] | None = None) -> tuple[list[Any], Path]:
    """A run to do and its checkpoint in ``out`` (holding ``run_ids``, else the run's own); the checkpoint."""
    from empathy_zoo.experiment.model import RunSpec
    from empathy_zoo.training.checkpoint import save_checkpoint
    from empathy_zoo.training.resume import checkpoint_path

    todo = [RunSpec.of(steps=100, eval_interval=100, eval_episodes=1, seed=0)]
    checkpoint = checkpoint_path(out, todo)
    save_checkpoint(checkpoint, {"run_ids": run_ids or [spec.run_id for spec in todo]})
    return todo, checkpoint


def test_a_second_unreadable_list_of_runs_never_replaces_the_first(tmp_path: Path) -> None:
    from empathy_zoo.training.resume import plan_ensembles

    out = tmp_path / "out"
    todo, checkpoint = _planted(out)
    manifest = checkpoint.with_name(checkpoint.stem + ".runs.json")
    first = manifest.with_name(manifest.name + ".unreadable")
    first.write_text("PRECIOUS: a user's file\n")
    for number, text in enumerate(["{", "[]", '{"format": 9}'], start=2):
        manifest.write_text(text)
        notes: list[str] = []
        plan_ensembles(todo, out, 1, notes.append)
        aside = manifest.with_name(f"{manifest.name}.unreadable.{number}")
        assert aside.read_text() == text and not manifest.exists()
        assert any(note.startswith(f"set aside {manifest} as {aside.name}:") for note in notes), notes
    assert first.read_text() == "PRECIOUS: a user's file\n"


def test_a_set_aside_skips_a_dangling_link_a_folder_and_a_file(tmp_path: Path) -> None:
    from empathy_zoo.training.resume import plan_ensembles

    out = tmp_path / "out"
    todo, checkpoint = _planted(out)
    manifest = checkpoint.with_name(checkpoint.stem + ".runs.json")
    manifest.write_text("{")
    taken = [manifest.with_name(manifest.name + tail) for tail in (".unreadable", ".unreadable.2", ".unreadable.3")]
    taken[0].symlink_to(tmp_path / "nowhere")
    taken[1].mkdir()
    taken[2].write_text("mine")
    notes: list[str] = []
    plan_ensembles(todo, out, 1, notes.append)
    assert manifest.with_name(manifest.name + ".unreadable.4").read_text() == "{"
    assert taken[0].is_symlink() and taken[1].is_dir() and taken[2].read_text() == "mine"
    assert any(f"as {manifest.name}.unreadable.4:" in note for note in notes), notes


def test_a_misnamed_checkpoint_is_never_set_aside_over_a_dangling_link(tmp_path: Path) -> None:
    from empathy_zoo.training.resume import plan_ensembles

    out = tmp_path / "out"
    todo, checkpoint = _planted(out, ["coexistence_v0__other-12345678__s0"])
    link = checkpoint.with_name(checkpoint.name + ".misnamed")
    link.symlink_to(tmp_path / "nowhere")
    notes: list[str] = []
    plan_ensembles(todo, out, 1, notes.append)
    assert link.is_symlink() and os.readlink(link) == str(tmp_path / "nowhere")
    assert checkpoint.with_name(checkpoint.name + ".misnamed.2").is_file() and not checkpoint.exists()
    assert any(f"as {checkpoint.name}.misnamed.2:" in note for note in notes), notes


# ---------------------------------------------------------------------------- lock files (#4)
STALE = b'{"pid": 12345, "host": "elsewhere", "command": "empathy-zoo train --out out", "since": 0}'
"""A lock file a killed holder left: the suite's own, taken over by the next command."""


def _stale_lock(out: Path, data: bytes) -> tuple[Path, os.stat_result]:
    from empathy_zoo.output_lock import LOCK_NAME

    out.mkdir(parents=True, exist_ok=True)
    lock = out / LOCK_NAME
    lock.write_bytes(data)
    os.utime(lock, ns=(1_000_000_000, 2_000_000_000))
    return lock, lock.stat()


@pytest.mark.parametrize("data", [STALE, b""], ids=["a-holder's-record", "empty"])
def test_a_block_refused_under_a_lock_it_took_over_leaves_the_file_as_it_was(tmp_path: Path, data: bytes) -> None:
    from empathy_zoo.output_lock import hold_output_dir

    lock, before = _stale_lock(tmp_path / "out", data)
    with pytest.raises(ValueError, match="refused"), hold_output_dir(lock.parent, "empathy-zoo train"):
        assert b"empathy-zoo train" in lock.read_bytes()  # (held: a second process is told who holds it)
        raise ValueError("refused")
    after = lock.stat()
    assert lock.read_bytes() == data
    assert (after.st_ino, after.st_mtime_ns, after.st_atime_ns) == (before.st_ino, before.st_mtime_ns, before.st_atime_ns)


def test_a_refused_train_leaves_a_lock_file_it_did_not_create_byte_for_byte(tmp_path: Path, capsys) -> None:
    from empathy_zoo.cli import main

    out = tmp_path / "out"
    lock, before = _stale_lock(out, STALE)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (out / "runs").symlink_to(elsewhere)  # (refused once the lock is held: a link where runs are written)
    train = ["train", "--steps", "200", "--eval-interval", "100", "--learning-starts", "50", "--hidden-size", "16"]
    assert main([*train, "--max-cycles", "50", "--out", str(out), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{out / 'runs'}" in err and "link" in err, err
    assert lock.read_bytes() == STALE and lock.stat().st_mtime_ns == before.st_mtime_ns
    assert sorted(path.name for path in out.iterdir()) == [lock.name, "runs"] and not list(elsewhere.iterdir())


def test_a_command_that_finishes_still_removes_the_lock_file_it_took_over(tmp_path: Path) -> None:
    from empathy_zoo.output_lock import hold_output_dir

    lock, _ = _stale_lock(tmp_path / "out", STALE)
    with hold_output_dir(lock.parent, "empathy-zoo train"):
        pass
    assert not lock.exists()


# ---------------------------------------------------------------------------- result files (#3)
RESULTS = Path(__file__).resolve().parents[1] / "docs" / "results" / "quick"
RUN = RESULTS / "runs" / "coexistence_v0__dqn_harm_penalty-684a7c7f__s0.json"
"""A shipped result file (and, beside it in ``evaluations/``, its evaluation; its agent file)."""


def _result() -> dict[str, Any]:
    return json.loads(RUN.read_text())


def test_the_shipped_result_passes() -> None:
    from empathy_zoo.experiment.result_reader import check_result

    check_result(_result(), RUN)


@pytest.mark.parametrize(
    "field, value, named",
    [
        ("memory_bytes", {"replay_per_run": 1, "learner_per_run": 2, "zzz": 5}, "memory_bytes (the name 'zzz')"),
        ("memory_bytes", {"replay": 1}, "memory_bytes (the name 'replay')"),
        ("created", "not a date", "created"),
        ("created", "99999-01-01T00:00:00+00:00", "created"),
        ("created", "9999-12-31T23:00:00+00:00", "created"),
        ("created", "1970-12-31T23:59:59+00:00", "created"),
        ("created", "2026-11-29T22:32:30", "created"),  # (no offset from UTC)
        ("created", "2026-11-29", "created"),
        ("created", 20261129, "created"),
        ("created", "2026-11-29T22:32:30+00:00" + " " * 60, "created"),
    ],
)
def test_a_result_files_memory_figures_and_date_are_the_writers(field: str, value: Any, named: str) -> None:
    from empathy_zoo.experiment.result_reader import check_result

    document = _result()
    document[field] = value
    with pytest.raises(ValueError, match=rf"^{re.escape(str(RUN))}: field {re.escape(named)}: expected") as refused:
        check_result(document, RUN)
    assert "\n" not in str(refused.value)


@pytest.mark.parametrize("created", ["2026-11-29T22:32:30+00:00", "1971-01-01T05:00:00+05:00", "9998-12-31T22:59:59-01:00"])
def test_a_result_files_date_within_its_range_is_read(created: str) -> None:
    from empathy_zoo.experiment.result_reader import check_result

    document = _result()
    document["created"] = created
    check_result(document, RUN)
    del document["created"]
    check_result(document, RUN)  # (a field the schema does not require)


# ---------------------------------------------------------------------------- study files (#3)
STUDY = RESULTS.parent / "methods" / "tuning" / "coexistence_v0" / "dqn" / "study.json"
"""A shipped study: survival over the curve, tuning seeds 10000 and 10001, 50,000 steps evaluated
every 10,000; trial 1 (finished) the best, trial 3 pruned."""


def _forged_study(change: Any) -> dict[str, Any]:
    document = json.loads(STUDY.read_text())
    change(document)
    return document


def _trial(number: int, change: Any) -> Any:
    return lambda document: change(document["trials"][number])


STUDY_CONTRADICTIONS = {
    "trial value past a float's range of survival": (_trial(0, lambda t: t.__setitem__("value", 1e308)), "trials[0].value"),
    "trial value below survival's": (_trial(0, lambda t: t.__setitem__("value", -3.0)), "trials[0].value"),
    "last value past max_cycles": (_trial(3, lambda t: t.__setitem__("last_value", 2e9)), "trials[3].last_value"),
    "curve value negative": (_trial(0, lambda t: t["curve"][1].__setitem__("value", -1.0)), "trials[0].curve[1].value"),
    "per_seed of three seeds": (
        _trial(0, lambda t: t["curve"][0].__setitem__("per_seed", [1, 2, 3])),
        "trials[0].curve[0].per_seed",
    ),
    "per_seed value negative": (_trial(0, lambda t: t["curve"][0].__setitem__("per_seed", [1.0, -5.0])), "per_seed[1]"),
    "curve step negative": (_trial(0, lambda t: t["curve"][0].__setitem__("step", -5)), "trials[0].curve[0].step"),
    "curve step off the schedule": (_trial(0, lambda t: t["curve"][1].__setitem__("step", 25_000)), "trials[0].curve[1].step"),
    "curve step skipped": (_trial(0, lambda t: t["curve"].pop(0)), "trials[0].curve[0].step"),
    "curve past the budget": (
        _trial(0, lambda t: t["curve"].append({"step": 60_000, "value": 1.0, "per_seed": [1.0, 1.0]})),
        "trials[0].curve",
    ),
    "no trials": (lambda d: d.__setitem__("trials", []), "field trials"),
    "trial numbered twice": (_trial(2, lambda t: t.__setitem__("number", 1)), "trials[2].number"),
    "best of a trial not there": (lambda d: d["best"].__setitem__("number", 99), "best.number"),
    "best of a pruned trial": (lambda d: d["best"].__setitem__("number", 3), "best.number"),
    "best without its number": (lambda d: d["best"].pop("number"), "best.number"),
    "best value not its trial's": (lambda d: d["best"].__setitem__("value", 499.0), "best.value"),
    "best parameters not its trial's": (lambda d: d["best"]["params"].__setitem__("learning_rate", 0.002), "best.params"),
    "best value past max_cycles": (lambda d: d["best"].__setitem__("value", 1e10), "best.value"),
    "no tuning seeds": (lambda d: d["plan"].pop("tuning_seeds"), "plan.tuning_seeds"),
    "tuning seeds twice": (lambda d: d["plan"].__setitem__("tuning_seeds", [10000, 10000]), "plan.tuning_seeds"),
    "no evaluation interval": (lambda d: d["plan"]["budget"].pop("eval_interval"), "plan.budget.eval_interval"),
}


def test_every_shipped_study_passes() -> None:
    from leaderboard.study_file import check_study

    shipped = sorted((RESULTS.parent).rglob("study.json"))
    assert STUDY in shipped
    for path in shipped:
        check_study(json.loads(path.read_text()), path)


@pytest.mark.parametrize("name", list(STUDY_CONTRADICTIONS))
def test_a_study_whose_fields_contradict_each_other_is_refused(tmp_path: Path, capsys, name: str) -> None:
    from empathy_zoo.cli import main

    change, field = STUDY_CONTRADICTIONS[name]
    path = tmp_path / "study" / "study.json"
    path.parent.mkdir()
    path.write_text(json.dumps(_forged_study(change)))
    assert main(["analyse", "tuning-summary", str(tmp_path)]) == 2
    captured = capsys.readouterr()
    assert not captured.out and captured.err.count("\n") == 1, captured.err
    assert f"{path}: field {field}" in captured.err or (field in captured.err and str(path) in captured.err), captured.err


# ---------------------------------------------------------------------------- evaluation files (#3)
EVALUATION = RESULTS / "evaluations" / "coexistence_v0" / RUN.name
"""The shipped evaluation of :data:`RUN` (one cat, 7×7): ``scenarios[1]`` cat_stays, ``[5]``
two_random_cats (``num_cats = 2``), ``[6]`` three_random_cats, ``[7]`` larger_grid (``size = 11``)."""


def _played(i: int, key: str, value: Any) -> Any:
    return lambda document: document["scenarios"][i].__setitem__(key, value)


def _both(i: int, key: str, value: Any) -> Any:
    """The played scenario ``i`` and its definition in the set changed alike."""

    def change(document: dict[str, Any]) -> None:
        document["scenarios"][i][key] = value
        document["scenario_set"]["scenarios"][i - 1][key] = value

    return change


EVALUATION_CONTRADICTIONS = {
    "partner not the definition's": (_played(1, "fixed", {"cat_0": "chase"}), "scenarios[1].fixed"),
    "44 cats, one partner": (_played(1, "env_kwargs", {"num_cats": 44}), "scenarios[1].fixed"),
    "44 cats, one partner, defined so": (_both(1, "env_kwargs", {"num_cats": 44}), "scenarios[1].fixed"),
    "3 cats, 2 partners": (_played(5, "env_kwargs", {"num_cats": 3}), "scenarios[5].fixed"),
    "3 cats and partners where the definition has 2": (
        lambda d: (_played(5, "env_kwargs", {"num_cats": 3})(d), _played(5, "fixed", d["scenarios"][6]["fixed"])(d)),
        "scenarios[5].env_kwargs.num_cats",
    ),
    "2 cats, one defined": (
        lambda d: d["scenario_set"]["scenarios"][4].__setitem__("fixed", {"cat_0": "random_walk"}),
        "scenario_set.scenarios[4].fixed",
    ),
    "grid not the definition's": (_played(7, "env_kwargs", {"size": 9}), "scenarios[7].env_kwargs.size"),
    "an argument the run did not have": (_played(1, "env_kwargs", {"max_cycles": 1000}), "scenarios[1].env_kwargs.max_cycles"),
    "the run's argument left out": (
        lambda d: d["scenarios"][0].__setitem__("env_kwargs", {"max_cycles": 500}),
        "scenarios[1].env_kwargs.max_cycles",
    ),
    "reason not the definition's": (_played(1, "reason", "Something else."), "scenarios[1].reason"),
}


def test_the_shipped_evaluation_passes() -> None:
    from empathy_zoo.evaluation_file import read_evaluation

    read_evaluation(EVALUATION)


@pytest.mark.parametrize("name", list(EVALUATION_CONTRADICTIONS))
def test_an_evaluation_whose_scenarios_contradict_its_set_is_refused(name: str) -> None:
    from empathy_zoo.evaluation_file import EvaluationFileError, check_evaluation

    change, field = EVALUATION_CONTRADICTIONS[name]
    document = json.loads(EVALUATION.read_text())
    change(document)
    with pytest.raises(
        EvaluationFileError, match=rf"^{re.escape(str(EVALUATION))}: field {re.escape(field)}: expected"
    ) as refused:
        check_evaluation(document, EVALUATION)
    assert "\n" not in str(refused.value)


# ---------------------------------------------------------------------------- agent files (#3)
AGENT = RUN.with_name(RUN.stem + ".agent.pt")
"""The agent file of :data:`RUN`: DQN with a harm penalty, ``hidden_size = 128``, on a 7×7 grid."""


def _forged_agent(tmp_path: Path, change: Any, beside: bool = False) -> Path:
    """A copy of :data:`AGENT` whose header ``change(header)`` edited; with ``beside``, in
    ``tmp_path/runs`` beside a copy of :data:`RUN` that records its SHA-256 (its run's own file)."""
    import hashlib

    import torch

    folder = tmp_path / "runs"
    folder.mkdir(exist_ok=True)
    document = torch.load(AGENT, weights_only=True)
    change(document["header"])
    path = folder / AGENT.name
    torch.save(document, path)
    if beside:
        result = _result()
        result["agent"]["sha256"] = hashlib.sha256(path.read_bytes()).hexdigest()
        (folder / RUN.name).write_text(json.dumps(result))
    return path


def _consistent(change: Any) -> Any:
    """``change`` of a header, then the run id the changed header gives (a forgery consistent with itself)."""
    from empathy_zoo.run_ids import run_id

    def changed(header: dict) -> None:
        change(header)
        config = {key: value for key, value in header.items() if key != "run_id"}
        header["run_id"] = run_id(header["variant"], header["method"], config, header["seed"])

    return changed


AGENT_FORGERIES = {
    "unknown header key": (lambda h: h.__setitem__("zzz", 1), "header (the key 'zzz')"),
    "hidden_size not its networks'": (lambda h: h["settings"].__setitem__("hidden_size", 64), "header.settings.hidden_size"),
    "hidden_size past its bound": (lambda h: h["settings"].__setitem__("hidden_size", 10**6), "header.settings.hidden_size"),
    "hidden_size not a number": (lambda h: h["settings"].__setitem__("hidden_size", "128"), "header.settings.hidden_size"),
    "method no name": (lambda h: h.__setitem__("method", "dqn; rm -rf"), "header.method"),
    "method a path": (lambda h: h.__setitem__("method", "../x:Y"), "header.method"),
}


def test_the_shipped_agent_passes_alone_and_beside_its_result() -> None:
    from empathy_zoo.agent_file import load_agent, load_run_agent

    assert load_agent(AGENT).describe()["method"] == "dqn_harm_penalty"
    load_run_agent(RUN)


@pytest.mark.parametrize("name", list(AGENT_FORGERIES))
def test_an_agent_header_that_contradicts_itself_or_its_weights_is_refused(tmp_path: Path, capsys, name: str) -> None:
    from empathy_zoo.agent_file import AgentFileError, load_agent
    from empathy_zoo.cli import main

    change, field = AGENT_FORGERIES[name]
    path = _forged_agent(tmp_path, change)
    with pytest.raises(AgentFileError, match=rf"^{re.escape(str(path))}: field {re.escape(field)}: expected") as refused:
        load_agent(path)
    assert "\n" not in str(refused.value)
    assert main(["watch", str(path)]) == 2
    captured = capsys.readouterr()
    assert not captured.out and captured.err.count("\n") == 1 and field in captured.err


def test_a_plug_in_method_is_kept_as_text_and_an_unregistered_name_is_refused(tmp_path: Path, capsys) -> None:
    from empathy_zoo.agent_file import load_agent
    from empathy_zoo.cli import main
    from empathy_zoo.experiment.agent_method import check_agent_method

    plug_in = _forged_agent(tmp_path, _consistent(lambda h: h.__setitem__("method", "probe6_never_imported.module:Method")))
    agent = load_agent(plug_in)
    assert check_agent_method(agent) is agent and "probe6_never_imported" not in sys.modules
    unregistered = _forged_agent(tmp_path, _consistent(lambda h: h.__setitem__("method", "no_such_method")))
    load_agent(unregistered)  # (the reader below the registry checks the name's shape only)
    assert main(["watch", str(unregistered)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"agent file {unregistered}: field header.method" in err and "'no_such_method'" in err


@pytest.mark.parametrize(
    "key, value",
    [
        ("env_kwargs", {"size": 255}),
        ("env_kwargs", {"max_cycles": 7}),
        ("fixed", {"cat_0": "stay"}),
        ("method", "dqn"),
        ("seed", 3),
        ("steps", 40_000),
        ("run_id", "coexistence_v0__dqn_harm_penalty-684a7c7f__s1"),
        ("label", "another label"),
    ],
)
def test_an_agent_header_that_is_not_its_result_files_run_is_refused(tmp_path: Path, capsys, key: str, value: Any) -> None:
    from empathy_zoo.agent_file import AgentFileError, load_agent, load_run_agent
    from empathy_zoo.cli import main

    path = _forged_agent(tmp_path, lambda h: h.__setitem__(key, value), beside=True)
    result = path.with_name(RUN.name)
    field = f"agent file {path}: field header.{key}:"
    with pytest.raises(AgentFileError, match=re.escape(field)) as refused:
        load_run_agent(result)
    assert str(result) in str(refused.value) and "\n" not in str(refused.value)
    with pytest.raises(AgentFileError, match=re.escape(field)):  # (as the leaderboard loads it)
        load_agent(path, json.loads(result.read_text())["agent"]["sha256"], result_file=result)
    assert main(["watch", str(result)]) == 2
    assert field in capsys.readouterr().err
    with pytest.raises(AgentFileError, match=re.escape(f"{path}: field header.run_id: expected")):
        load_agent(path)  # (alone, the header contradicts the run id it holds)
