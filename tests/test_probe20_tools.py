"""The twentieth probe's findings on the analysis tools: two experiments that one tool's key cannot
tell apart are refused (never one matched or pooled and the other dropped), and a page's label
holding an escaped ``|`` is read as one cell."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from empathy_zoo.run_ids import run_id

ROOT = Path(__file__).resolve().parents[1]
QUICK = ROOT / "docs" / "results" / "quick"
EXPERIMENT = "coexistence_v0__dqn_harm_penalty-684a7c7f"


def _copy(directory: Path, gamma: float | None = None, label: str | None = None) -> None:
    """The quick profile's three runs of :data:`EXPERIMENT` into ``directory/runs``; with ``gamma``,
    as another experiment that differs only in γ (and its label); with ``label``, so labelled."""
    (directory / "runs").mkdir(parents=True, exist_ok=True)
    for source in sorted((QUICK / "runs").glob(f"{EXPERIMENT}__s*.json")):
        document = json.loads(source.read_text(encoding="utf-8"))
        document["agent"] = None
        if gamma is not None:
            config = document["config"]
            config["settings"]["gamma"] = config["description"]["gamma"] = gamma
            config["label"] = document["method_label"] = f"γ {gamma}"
        if label is not None:
            document["config"]["label"] = document["method_label"] = label
        if gamma is not None or label is not None:
            document["run_id"] = run_id(document["variant"], document["method"], document["config"], document["seed"])
        (directory / "runs" / f"{document['run_id']}.json").write_text(json.dumps(document), encoding="utf-8")


@pytest.mark.parametrize("module", ["compare_runs", "equivalence"])
def test_two_experiments_one_key_cannot_tell_apart_are_refused(tmp_path: Path, module: str) -> None:
    _copy(tmp_path / "one")
    _copy(tmp_path / "two")
    _copy(tmp_path / "two", gamma=0.98)
    done = subprocess.run(
        [sys.executable, "-m", f"leaderboard.{module}", str(tmp_path / "one"), str(tmp_path / "two")],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    assert done.returncode == 2 and done.stdout == "", done
    assert done.stderr.count("\n") == 1 and "are one experiment's seed" in done.stderr and EXPERIMENT in done.stderr


def test_one_experiment_each_still_compares(tmp_path: Path) -> None:
    from leaderboard.aggregate import load_results
    from leaderboard.compare_runs import compare_runs

    _copy(tmp_path / "one")
    _copy(tmp_path / "two")
    outcome = compare_runs(load_results(tmp_path / "one"), load_results(tmp_path / "two"))
    assert [len(outcome[k]) for k in ("same", "different", "only_old", "only_new")] == [3, 0, 0, 0]


PAGE = """## coexistence_v0

### P(improves on DQN): Final greedy evaluation

| Method | Seeds | survival | harms | other_return |
|:---|---:|---:|---:|---:|
| a\\|b | 5 | {mark}0.90 [0.6, 1.0] · IQM 1 | 0.50 [0.2, 0.8] · IQM 0 | 0.50 [0.2, 0.8] · IQM 0 |
| a\\|c | 5 | 0.50 [0.2, 0.8] · IQM 1 | 0.50 [0.2, 0.8] · IQM 0 | 0.50 [0.2, 0.8] · IQM 0 |
"""


def test_verdict_changes_reads_an_escaped_bar_as_part_of_the_label(tmp_path: Path) -> None:
    from leaderboard.verdict_changes import verdicts

    old, new = tmp_path / "old.md", tmp_path / "new.md"
    old.write_text(PAGE.format(mark="▲ "), encoding="utf-8")
    new.write_text(PAGE.format(mark=""), encoding="utf-8")
    before, after = verdicts(old.read_text(encoding="utf-8")), verdicts(new.read_text(encoding="utf-8"))
    assert len(before) == len(after) == 6
    changed = {key: (before[key], after[key]) for key in before if before[key] != after[key]}
    assert len(changed) == 1
    ((key, (was, now)),) = changed.items()
    assert "a|b" in key and "survival" in key and was == "▲" and now != "▲"


LOOKALIKES = [
    "DQN",
    "DQN\u00a0",
    "\uff24\uff31\uff2e",
    "DQN\u3164",
    "DQN ",
    "DQN, as Mine",
    "Mine ≡ DQN",
    "Mine = DQN's runs",
    "DQN\u034f",
    "DQ\u039d",
    "\u0500QN",
    "DQN\u0301",
    "dqn",
    "x ≣ DQN",
    "x ≡ DQ\u039d",
    "DQ\u039d, as Empathic DQN (β=1)",
    "Mine = DQN\u2019s runs",
]


@pytest.mark.parametrize("label", LOOKALIKES, ids=[ascii(label) for label in LOOKALIKES])
def test_a_label_that_reads_as_a_name_the_leaderboard_gives_is_refused(tmp_path: Path, capsys, label: str) -> None:
    from empathy_zoo.cli import main

    _copy(tmp_path / "dir", label=label)
    capsys.readouterr()
    assert main(["leaderboard", str(tmp_path / "dir"), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--label DIR=PREFIX" in err and "result file" in err, err
    assert not (tmp_path / "out").exists()


def test_a_prefix_sets_such_a_label_apart(tmp_path: Path) -> None:
    from leaderboard.sources import load_results_dirs

    _copy(tmp_path / "dir", label="DQN")
    read = load_results_dirs([tmp_path / "dir"], {tmp_path / "dir": "Theirs"}, dqn_named=True)
    assert {run.method_label for run in read.results} == {"Theirs DQN"}


@pytest.mark.parametrize(
    ("columns", "rows", "words"), [(2_000, 1, "more than 1,000 cells"), (500, 300, "more than 100,000 verdict")]
)
def test_verdict_changes_bounds_the_cells_of_a_page(tmp_path: Path, capsys, columns: int, rows: int, words: str) -> None:
    from leaderboard.verdict_changes import main

    header = "| M | S |" + "|".join(f"m{i}" for i in range(columns)) + "|\n"
    body = "".join(f"| r{r} | 5 |" + "▲|" * columns + "\n" for r in range(rows))
    page = tmp_path / "big.md"
    page.write_text(f"## v\n\n### P(improves on DQN): x\n\n{header}|---|\n{body}", encoding="utf-8")
    assert main([str(page), str(page)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words in err and str(page) in err, err


def test_discrimination_finds_the_shipped_tables_from_any_folder(tmp_path: Path, monkeypatch) -> None:
    from empathy_zoo.cli import main

    monkeypatch.chdir(tmp_path)
    assert main(["analyse", "discrimination", "--out", str(tmp_path / "page.md")]) == 0
    assert (tmp_path / "page.md").read_text(encoding="utf-8").startswith("# Discrimination matrix")


@pytest.mark.parametrize("seed", [2**64, 10**4000, -1])
def test_an_environment_seed_is_at_most_64_bits(seed: int) -> None:
    from empathy_zoo import coexistence_v0

    env = coexistence_v0.parallel_env()
    with pytest.raises(ValueError, match="seed must be an int in 0 … 2⁶⁴ − 1"):
        env.reset(seed=seed)
    env.reset(seed=2**64 - 1)


@pytest.mark.parametrize("cells", [{(1, 1): 1, (2, 2): 5}, {(1, 1), (2, 2)}, "11"])
def test_sharing_takes_its_batteries_as_a_list_of_cells_only(cells: object) -> None:
    from empathy_zoo import sharing_v0

    env = sharing_v0.parallel_env()
    with pytest.raises(ValueError, match=r"options\['batteries'\] must be a list of \(row, col\) cells"):
        env.reset(seed=0, options={"batteries": cells})
    env.reset(seed=0, options={"batteries": [(1, 1), (2, 2)]})
