"""``watch`` reads a result file as every reader does before it loads the agent the file names:
a JSON file that only holds an ``agent`` entry (written by hand, an evaluation file) is refused in
one line naming the file and the field, given itself or found beside the agent file it names."""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import pytest

from empathy_zoo.cli import main

RUNS = Path(__file__).resolve().parents[1] / "docs" / "results" / "quick"
RUN = "coexistence_v0__dqn_harm_penalty-684a7c7f__s0"
AGENT = f"{RUN}.agent.pt"


def one_error_line(capsys: pytest.CaptureFixture[str]) -> str:
    """The one line the command wrote to stderr."""
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1, lines
    return lines[0]


def beside_agent(folder: Path, name: str, document: dict) -> Path:
    """``document`` written to ``folder/name`` with the shipped run's agent file copied beside it."""
    folder.mkdir(parents=True, exist_ok=True)
    shutil.copy(RUNS / "runs" / AGENT, folder / AGENT)
    path = folder / name
    path.write_text(json.dumps(document))
    return path


def test_a_json_file_with_only_an_agent_entry_is_refused_naming_it(tmp_path: Path, capsys) -> None:
    real = json.loads((RUNS / "runs" / f"{RUN}.json").read_text())
    renamed = beside_agent(tmp_path / "one", "R.json", real)  # (a real result file under another name: still watched)
    assert main(["watch", str(renamed), "--episodes", "1"]) == 0
    assert capsys.readouterr().out.startswith(f"dqn_harm_penalty agent of run {RUN} (")
    fake = beside_agent(tmp_path / "w2", "fake.json", {"agent": real["agent"], "wall_time_s": math.nan, "eval": "bogus"})
    assert main(["watch", str(fake)]) == 2
    line = one_error_line(capsys)
    assert line.startswith(f"empathy-zoo: error: {fake}: field ") and "result file" in line
    named = beside_agent(tmp_path / "w3", f"{RUN}.json", {"agent": real["agent"], "eval": "bogus"})
    assert main(["watch", str(named.with_name(AGENT))]) == 2, "the file beside the agent file that names it is read too"
    assert one_error_line(capsys).startswith(f"empathy-zoo: error: {named}: field ")
    broken = beside_agent(tmp_path / "w4", f"{RUN}.json", {**real, "eval": "bogus"})
    assert main(["watch", str(broken)]) == 2
    assert one_error_line(capsys).startswith(f"empathy-zoo: error: {broken}: field eval")


def test_an_evaluation_file_is_no_result_file_to_watch(tmp_path: Path, capsys) -> None:
    evaluation = json.loads((RUNS / "evaluations" / "coexistence_v0" / f"{RUN}.json").read_text())
    assert evaluation["agent"]["file"] == AGENT
    path = beside_agent(tmp_path / "evaluations" / "coexistence_v0", f"{RUN}.json", evaluation)
    for target in (path, path.with_name(AGENT)):
        assert main(["watch", str(target)]) == 2
        assert one_error_line(capsys).startswith(f"empathy-zoo: error: {path}: field ")


def test_dir_with_a_path_is_refused_as_an_option_that_cannot_act(tmp_path, capsys) -> None:
    from pathlib import Path

    from empathy_zoo.cli import main

    agent = next((Path(__file__).resolve().parents[1] / "docs" / "results" / "quick" / "runs").glob("*.agent.pt"))
    capsys.readouterr()
    assert main(["watch", str(agent), "--dir", str(tmp_path), "--episodes", "1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"--dir names where a run id is looked up; {agent} is a path" in err, err
