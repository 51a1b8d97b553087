"""A seventh probe's findings (issue 33, "files from elsewhere are inert"): a partner's arguments
and saved state are numbers in range, never a traceback; a tiny move probability cannot wrap an
index; separation tables are read through one checked reader; ``analyse separation`` never
writes through a link; ``evaluate`` bounds an episode's length and stops on SIGTERM, leaving no
folder or lock of its own; ``watch`` names what lies in a result file's place."""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import signal
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from helpers_results import derive_run_id

from empathy_zoo.cli import main

QUICK = Path(__file__).resolve().parents[1] / "docs" / "results" / "quick" / "runs"
SHIPPED_TABLES = Path(__file__).resolve().parents[1] / "docs" / "results" / "separation"


def _forged_run(tmp_path: Path, run_id: str, change: Any) -> Path:
    """A copy of the quick run ``run_id`` (result and agent file) in ``tmp_path/runs`` whose result
    ``config`` and agent header are both ``change``d, under the run id the changed config gives
    (the files named after it), the agent's SHA-256 recorded anew."""
    import torch

    runs = tmp_path / "runs"
    runs.mkdir(exist_ok=True)
    result = json.loads((QUICK / f"{run_id}.json").read_text())
    agent = torch.load(QUICK / f"{run_id}.agent.pt", weights_only=True)
    change(result["config"])
    change(agent["header"])
    forged = derive_run_id(result)["run_id"]
    agent["header"]["run_id"] = forged
    result["agent"]["file"] = f"{forged}.agent.pt"
    agent_path = runs / result["agent"]["file"]
    torch.save(agent, agent_path)
    result["agent"]["sha256"] = hashlib.sha256(agent_path.read_bytes()).hexdigest()
    (runs / f"{forged}.json").write_text(json.dumps(result))
    return runs / f"{forged}.json"


SHARING = "sharing_v0__empathic_dqn-24777995__s0"
COEXISTENCE = "coexistence_v0__dqn_harm_penalty-684a7c7f__s0"


# ---------------------------------------------------------------------------- partner arguments (#1, #2)
@pytest.mark.parametrize(
    "label, named",
    [
        ("patrol(period=Infinity)", "Infinity is no number a policy takes"),
        ("patrol(period=NaN)", "NaN is no number a policy takes"),
        ("patrol(period=1e+300)", "period must be an int in [1, 1,000,000,000]"),
        ("patrol(period=1000000000000000000000000000000)", "is beyond ±1,000,000,000"),
        ("chase(every=100000000000000000)", "is beyond ±1,000,000,000"),
    ],
)
def test_a_partner_label_with_numbers_out_of_range_is_refused_in_one_line(label: str, named: str) -> None:
    from empathy_zoo.policies import make_policy, parse_entry_label

    with pytest.raises(ValueError, match=re.escape(named)) as refused:
        make_policy(parse_entry_label(label))
    assert "\n" not in str(refused.value)


def test_commands_refuse_a_forged_partner_label_without_a_traceback(tmp_path: Path, capsys) -> None:
    forged = _forged_run(tmp_path, SHARING, lambda config: config.__setitem__("fixed", {"human_0": "patrol(period=1e+300)"}))
    assert main(["evaluate", str(tmp_path), "--episodes", "2", "--progress", "plain"]) == 2
    assert "period must be an int" in capsys.readouterr().err
    assert not (tmp_path / "evaluations").exists()
    assert main(["watch", forged.stem, "--dir", str(tmp_path), "--episodes", "1"]) == 2
    assert "period must be an int" in capsys.readouterr().err


def test_a_tiny_move_probability_moves_rarely_alone_and_batched_alike() -> None:
    from empathy_zoo.partner_policies import SlowWalk

    for p in (1e-300, 0.1, 1.0):
        batch = SlowWalk(p).batched(64)
        batch.reset(np.arange(64), list(range(64)))
        batched = batch.act(None, np.zeros(64, dtype=np.int64), np.ones(64, dtype=bool))
        alone = []
        for seed in range(64):
            walker = SlowWalk(p)
            walker.reset(seed)
            alone.append(walker.act(np.zeros(1), {}))
        assert batched.tolist() == alone, p
        assert batched.min() >= 0 and batched.max() <= 4


@pytest.mark.parametrize("t", [float("inf"), 10**400, 10**30, -5, 1.5, True, "3", None])
def test_a_patrols_saved_step_out_of_range_is_refused(t: Any) -> None:
    from empathy_zoo.builtin_policies import Patrol

    patrol = Patrol()
    with pytest.raises(ValueError, match="a patrol's state holds its step t"):
        patrol.load_state({"t": t})
    patrol.load_state({"t": 12})
    assert patrol.state() == {"t": 12}


# ---------------------------------------------------------------------------- separation tables (#3)
def _table(change: Any) -> dict:
    table = json.loads((SHIPPED_TABLES / "charger_v0.json").read_text())
    change(table)
    return table


TABLE_FORGERIES = {
    "no rows": (lambda t: t.pop("rows"), "field rows: missing"),
    "rows null": (lambda t: t.__setitem__("rows", None), "field rows: expected an array"),
    "a row without a name": (lambda t: t["rows"][3].pop("name"), r"field rows\[3\]\.name: missing"),
    "a β that is a list": (lambda t: t["rows"][7].__setitem__("selfishness", [1]), r"rows\[7\]\.selfishness"),
    "harms of 10**400": (lambda t: t["outcomes"][0].__setitem__("harms", 10**400), r"outcomes\[0\]\.harms"),
    "harms of -inf": (lambda t: t["outcomes"][0].__setitem__("harms", float("-inf")), r"outcomes\[0\]\.harms"),
    "harms NaN": (lambda t: t["outcomes"][0].__setitem__("harms", float("nan")), r"outcomes\[0\]\.harms"),
    "an outcome of no row": (lambda t: t["outcomes"][0].__setitem__("row", "nobody"), r"outcomes\[0\]\.row"),
    "a pair that is a string": (lambda t: t["pairs"].__setitem__(0, "x"), r"pairs\[0\]: expected an object"),
    "differ a number": (lambda t: t["pairs"][0].__setitem__("differ", 1), r"pairs\[0\]\.differ"),
}


def test_the_shipped_tables_pass_the_reader() -> None:
    from baselines.separation_file import read_separation_table

    for path in sorted(SHIPPED_TABLES.glob("*.json")):
        read_separation_table(path)


@pytest.mark.parametrize("name", list(TABLE_FORGERIES))
def test_a_forged_separation_table_is_refused_naming_file_and_field(tmp_path: Path, capsys, name: str) -> None:
    change, field = TABLE_FORGERIES[name]
    tables = tmp_path / "tables"
    tables.mkdir()
    (tables / "charger_v0.json").write_text(json.dumps(_table(change)))
    assert main(["analyse", "discrimination", str(tables), "--out", str(tmp_path / "d.md")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "charger_v0.json" in err
    assert re.search(field, err), err
    assert not (tmp_path / "d.md").exists()


def test_a_deeply_nested_table_and_a_fifo_in_a_tables_place_are_refused(tmp_path: Path, capsys) -> None:
    from baselines.separation_file import read_separation_table

    deep = tmp_path / "deep.json"
    deep.write_text("[" * 100_000 + "]" * 100_000)
    with pytest.raises(ValueError, match="nests arrays and objects more than"):
        read_separation_table(deep)
    tables = tmp_path / "tables"
    tables.mkdir()
    os.mkfifo(tables / "coexistence_v0.json")
    assert main(["analyse", "separation-reading", str(QUICK.parent), "--tables", str(tables)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "coexistence_v0.json" in err and "FIFO" in err


# ---------------------------------------------------------------------------- analyse separation's writes (#4)
def test_analyse_separation_never_writes_through_a_link_nor_removes_a_users_file(tmp_path: Path, capsys) -> None:
    victim = tmp_path / "victim.txt"
    victim.write_text("precious")
    out = tmp_path / "out"
    out.mkdir()
    (out / "charger_v0.json").symlink_to(victim)
    (out / "charger_v0.md.partial").write_text("mine")
    assert main(["analyse", "separation", "charger_v0", "--out", str(out)]) == 2
    assert "symbolic link" in capsys.readouterr().err
    assert victim.read_text() == "precious" and (out / "charger_v0.md.partial").read_text() == "mine"
    assert sorted(p.name for p in out.iterdir()) == ["charger_v0.json", "charger_v0.md.partial"]


# ---------------------------------------------------------------------------- evaluate (#5, #7)
def test_evaluate_refuses_an_episode_longer_than_its_bound_before_writing(tmp_path: Path, capsys) -> None:
    from empathy_zoo.limits import MAX_EVALUATE_CYCLES

    _forged_run(tmp_path, COEXISTENCE, lambda config: config.__setitem__("env_kwargs", {"max_cycles": 10**9}))
    assert main(["evaluate", str(tmp_path), "--episodes", "1", "--progress", "plain"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "max_cycles 1,000,000,000" in err and f"{MAX_EVALUATE_CYCLES:,}" in err
    assert not (tmp_path / "evaluations").exists()


def test_evaluate_stopped_by_sigterm_exits_143_and_leaves_no_folder_or_lock(tmp_path: Path, monkeypatch, capsys) -> None:
    import empathy_zoo.training.heldout as heldout

    runs = tmp_path / "runs"
    runs.mkdir()
    for suffix in (".json", ".agent.pt"):
        shutil.copy(QUICK / f"{COEXISTENCE}{suffix}", runs / f"{COEXISTENCE}{suffix}")

    def terminated(*args: Any, **kwargs: Any) -> Any:
        os.kill(os.getpid(), signal.SIGTERM)  # (delivered at once to this, the main thread)
        raise AssertionError("SIGTERM did not stop evaluate")

    monkeypatch.setattr(heldout, "evaluate_run", terminated)
    before = signal.getsignal(signal.SIGTERM)
    assert main(["evaluate", str(tmp_path), "--scenarios", "coexistence_v0", "--episodes", "1", "--progress", "plain"]) == 143
    assert "interrupted" in capsys.readouterr().err
    assert not (tmp_path / "evaluations").exists()
    assert signal.getsignal(signal.SIGTERM) is before


# ---------------------------------------------------------------------------- watch's run ids (#8)
def test_watch_names_what_lies_in_a_result_files_place(tmp_path: Path, capsys) -> None:
    runs = tmp_path / "runs"
    runs.mkdir()
    os.mkfifo(runs / "fifo_run.json")
    (runs / "dir_run.json").mkdir()
    (runs / "dangling_run.json").symlink_to(tmp_path / "nowhere.json")
    for run_id, named in (("fifo_run", "FIFO"), ("dir_run", "director"), ("dangling_run", "link")):
        assert main(["watch", run_id, "--dir", str(tmp_path)]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "unknown run id" not in err and named in err, err
