"""One leaderboard of several results directories: rows of both, budgets kept apart, P(improves on
DQN) only against DQN of the same budget, label clashes refused or resolved with a prefix, and the
leaderboard of one directory as it always was."""

from __future__ import annotations

import csv
import io
from pathlib import Path

import pytest
from helpers_results import EVAL_EPISODES, derive_run_id, record, synthetic_document

from empathy_zoo.atomic import write_json_atomic
from empathy_zoo.cli import main
from leaderboard import write_leaderboard
from leaderboard.budgets import RunBudget, budget_of
from leaderboard.improvement import improvements_over_dqn, uncompared_rows
from leaderboard.ordering import label_order
from leaderboard.sources import load_results_dirs, parse_label_option
from leaderboard.tables import COMPARISON_CSV_COLUMNS, CSV_COLUMNS

ENV = "coexistence_v0"
SEEDS = range(5)
"""5 seeds a side: every run of one side beating every run of the other gives a verdict."""
DQN = "empathic_dqn 1.0"
"""The DQN reference's label in its result files."""
SHOWN = "DQN"
"""What the leaderboard calls that row (leaderboard.row_names)."""
EMPATHIC = "empathic_dqn 0.5"
PENALTY = "dqn_harm_penalty 1.0"


def run(method: str, beta: float, seed: int, steps: int = 20000, learning_rate: float | None = None, **means: float) -> dict:
    """A synthetic result of ``steps`` training steps; ``learning_rate`` (in place of the default)
    tells two experiments of one label apart (their configs, so their run ids, differ by more than
    the seed)."""
    result = synthetic_document(ENV, method, beta, seed, **means)
    result["steps"] = steps
    result["config"] = {**result["config"], "steps": steps, "eval_interval": 2000, "eval_episodes": EVAL_EPISODES}
    if learning_rate is not None:
        result["config"]["settings"] = {**result["config"]["settings"], "learning_rate": learning_rate}
    result["eval"] = [{**result["eval"][-1], "step": step} for step in range(2000, steps + 1, 2000)]  # (as trained: every 2,000)
    return derive_run_id(result)


def write_dir(directory: Path, runs: list[dict]) -> Path:
    for result in runs:
        write_json_atomic(directory / "runs" / f"{result['run_id']}.json", result)
    return directory


def dqn(steps: int = 20000, harms: float = 0.1, learning_rate: float | None = None) -> list[dict]:
    return [run("empathic_dqn", 1.0, seed, steps, learning_rate, harms=harms, survival=400.0) for seed in SEEDS]


def empathic(steps: int = 20000, harms: float = 0.5) -> list[dict]:
    return [run("empathic_dqn", 0.5, seed, steps, harms=harms, survival=400.0) for seed in SEEDS]


def penalty(steps: int = 20000, harms: float = 0.05) -> list[dict]:
    return [run("dqn_harm_penalty", 1.0, seed, steps, harms=harms, survival=300.0) for seed in SEEDS]


def table_lines(markdown: str, heading: str) -> list[str]:
    """The rows of the first table under ``### heading``."""
    section = markdown.split(f"### {heading}\n", 1)[1].split("\n### ", 1)[0]
    return [line for line in section.splitlines() if line.startswith("| ") and not line.startswith("| Method")]


def test_two_directories_of_one_budget_make_one_table_with_the_rows_of_both(tmp_path: Path) -> None:
    mine = write_dir(tmp_path / "mine", penalty())
    shipped = write_dir(tmp_path / "shipped", dqn() + empathic())
    paths = write_leaderboard([mine, shipped], tmp_path / "out", command="c")
    markdown = paths["markdown"].read_text(encoding="utf-8")
    rows = table_lines(markdown, "Final greedy evaluation")
    assert [row.split(" | ")[0] for row in rows] == [f"| {PENALTY}", f"| {SHOWN}", f"| {EMPATHIC}"]
    assert f"- `{mine}`: 5 runs, 20,000 steps; empathy-zoo " in markdown and f"- `{shipped}`: 10 runs, 20,000 steps;" in markdown
    assert f"Every run has the same training budget: 20,000 steps, eval 2,000 × {EVAL_EPISODES}" in markdown
    # the other directory's method is compared with the shipped DQN, and the table says so
    compared = table_lines(markdown, "P(improves on DQN): Final greedy evaluation")
    against = [row.split(" | ")[:2] for row in compared]
    assert against == [[f"| {PENALTY}", f"{SHOWN} (5 seeds)"], [f"| {EMPATHIC}", f"{SHOWN} (5 seeds)"]]
    assert not (tmp_path / "mine" / "LEADERBOARD.md").exists() and not (tmp_path / "shipped" / "LEADERBOARD.md").exists()
    table = list(csv.DictReader(io.StringIO(paths["csv"].read_text(encoding="utf-8"))))
    assert tuple(table[0]) == CSV_COLUMNS + COMPARISON_CSV_COLUMNS
    named = ("method_label", *COMPARISON_CSV_COLUMNS)
    facts = {tuple(row[column] for column in named) for row in table}
    assert facts == {
        (PENALTY, "20000", "2000", str(EVAL_EPISODES), str(mine)),
        (EMPATHIC, "20000", "2000", str(EVAL_EPISODES), str(shipped)),
        (SHOWN, "20000", "2000", str(EVAL_EPISODES), str(shipped)),
    }
    assert "Read from 2 results directories" in paths["html"].read_text(encoding="utf-8")


def test_rows_of_different_budgets_are_kept_apart_and_compared_only_with_dqn_of_their_budget(tmp_path: Path) -> None:
    # the short budget's DQN never harms and the method does, the long budget's DQN harms far more:
    # mixing the two DQN groups would flip (or blur) every verdict on harms
    short = write_dir(tmp_path / "short", dqn(20000, harms=0.0) + empathic(20000, harms=1.0))
    long = write_dir(tmp_path / "long", dqn(40000, harms=1.0) + empathic(40000, harms=0.0))  # (one cat: at most 1 an episode)
    read = load_results_dirs([short, long])
    assert (
        read.budgets == (RunBudget(20000, 2000, EVAL_EPISODES), RunBudget(40000, 2000, EVAL_EPISODES)) and read.budget_in_labels
    )
    cells = improvements_over_dqn(read.results, {ENV: ["harms"]})
    verdicts = {(cell.method_label, cell.baseline_label, cell.phase): cell.verdict for cell in cells}
    assert verdicts == {
        (f"{EMPATHIC} · 20,000 steps", f"{DQN} · 20,000 steps", "eval"): "worse",
        (f"{EMPATHIC} · 20,000 steps", f"{DQN} · 20,000 steps", "train_final10"): "worse",
        (f"{EMPATHIC} · 40,000 steps", f"{DQN} · 40,000 steps", "eval"): "better",
        (f"{EMPATHIC} · 40,000 steps", f"{DQN} · 40,000 steps", "train_final10"): "better",
    }
    assert all(cell.n_baseline_seeds == 5 for cell in cells)  # one DQN group each, never both pooled
    markdown = write_leaderboard([short, long], tmp_path / "out", command="c")["markdown"].read_text(encoding="utf-8")
    rows = table_lines(markdown, "Final greedy evaluation")
    assert [row.split(" | ")[:2] for row in rows] == [
        [f"| {SHOWN} · 20,000 steps", "5"],
        [f"| {SHOWN} · 40,000 steps", "5"],
        [f"| {EMPATHIC} · 20,000 steps", "5"],
        [f"| {EMPATHIC} · 40,000 steps", "5"],
    ]
    compared = table_lines(markdown, "P(improves on DQN): Final greedy evaluation")
    assert [row.split(" | ")[1] for row in compared] == [f"{SHOWN} · 20,000 steps (5 seeds)", f"{SHOWN} · 40,000 steps (5 seeds)"]
    harms = [row.split(" | ")[4] for row in compared]  # Method | Against | Seeds | survival | harms | …
    assert harms[0].startswith("▼") and harms[1].startswith("▲")
    assert "The runs have 2 training budgets: each row's label ends with its budget" in markdown


def test_evaluation_settings_join_the_budget_where_they_differ(tmp_path: Path) -> None:
    other = [run("empathic_dqn", 1.0, seed) for seed in SEEDS]
    for result in other:
        result["config"]["eval_episodes"] = 10
        result["eval"] = [
            {key: [values[0]] * 10 if key != "step" else values for key, values in entry.items()} for entry in result["eval"]
        ]
        assert all(len(entry["survival"]) == 10 for entry in result["eval"])  # (ten episodes evaluated)
        derive_run_id(result)
    read = load_results_dirs([write_dir(tmp_path / "a", dqn()), write_dir(tmp_path / "b", other)])
    assert sorted({result.method_label for result in read.results}) == [
        f"{DQN} · 20,000 steps, eval 2,000 × 10",
        f"{DQN} · 20,000 steps, eval 2,000 × {EVAL_EPISODES}",
    ]
    assert budget_of(record(other[0])).text() == "20,000 steps, eval 2,000 × 10"


def test_a_row_without_dqn_of_its_budget_is_named_not_compared(tmp_path: Path) -> None:
    shipped = write_dir(tmp_path / "shipped", dqn(20000))
    mine = write_dir(tmp_path / "mine", empathic(40000))
    read = load_results_dirs([mine, shipped])
    assert improvements_over_dqn(read.results, {ENV: ["harms"]}) == []
    assert uncompared_rows(read.results) == [(ENV, f"{EMPATHIC} · 40,000 steps")]
    markdown = write_leaderboard([mine, shipped], tmp_path / "out")["markdown"].read_text(encoding="utf-8")
    assert f"Not compared with DQN (no DQN row of their variant, world and budget): {EMPATHIC} · 40,000 steps." in markdown
    assert "### P(improves on DQN)" not in markdown


def test_a_label_clash_between_directories_is_refused_naming_both_and_the_option(tmp_path: Path) -> None:
    first = write_dir(tmp_path / "first", dqn() + empathic())
    second = write_dir(tmp_path / "second", dqn(learning_rate=0.0005, harms=0.9))
    with pytest.raises(ValueError) as refused:
        write_leaderboard([first, second], tmp_path / "out")
    message = str(refused.value)
    assert f"two results directories, {first} and {second}" in message and f"--label {second}=PREFIX" in message
    assert f"the same label {DQN!r} on {ENV}" in message
    assert not (tmp_path / "out").exists()  # refused before anything is written


def test_a_label_prefix_resolves_the_clash_and_each_row_is_compared_with_both_dqn_rows(tmp_path: Path) -> None:
    first = write_dir(tmp_path / "first", dqn() + empathic())
    second = write_dir(tmp_path / "second", dqn(learning_rate=0.0005, harms=0.9))
    paths = write_leaderboard([first, second], tmp_path / "out", labels={second: "mine:"})
    markdown = paths["markdown"].read_text(encoding="utf-8")
    rows = [row.split(" | ")[0] for row in table_lines(markdown, "Final greedy evaluation")]
    assert rows == [f"| {SHOWN}", f"| {EMPATHIC}", f"| mine: {SHOWN}"]
    assert f"- `{second}`, labels prefixed `mine:`: 5 runs" in markdown
    compared = [row.split(" | ")[:2] for row in table_lines(markdown, "P(improves on DQN): Final greedy evaluation")]
    assert compared == [
        [f"| {SHOWN}", f"mine: {SHOWN} (5 seeds)"],
        [f"| {EMPATHIC}", f"{SHOWN} (5 seeds)"],
        [f"| {EMPATHIC}", f"mine: {SHOWN} (5 seeds)"],
        [f"| mine: {SHOWN}", f"{SHOWN} (5 seeds)"],
    ]
    assert (tmp_path / "first" / "runs").is_dir() and not (tmp_path / "first" / "LEADERBOARD.md").exists()


def test_one_experiment_in_two_directories_is_one_row_and_one_run_twice_is_refused(tmp_path: Path) -> None:
    runs = dqn()
    read = load_results_dirs([write_dir(tmp_path / "a", runs[:3]), write_dir(tmp_path / "b", runs[3:])])
    assert {result.method_label for result in read.results} == {DQN} and len(read.results) == 5
    assert read.row_directories() == {(ENV, DQN): (str(tmp_path / "a"), str(tmp_path / "b"))}
    with pytest.raises(ValueError, match=r"are the same run .* two results directories"):
        load_results_dirs([tmp_path / "a", write_dir(tmp_path / "c", runs[:1])])


def test_bad_directory_lists_and_labels_are_refused(tmp_path: Path) -> None:
    a = write_dir(tmp_path / "a", dqn())
    with pytest.raises(ValueError, match="needs an output directory"):
        write_leaderboard([a, write_dir(tmp_path / "b", empathic())])
    with pytest.raises(ValueError, match="given twice"):
        load_results_dirs([a, tmp_path / "x" / ".." / "a"])
    with pytest.raises(ValueError, match="is not one of the results directories read"):
        load_results_dirs([a], {tmp_path / "elsewhere": "p"})
    with pytest.raises(ValueError, match="non-empty one-line"):
        load_results_dirs([a], {a: "  "})
    assert parse_label_option("runs/a=b=mine") == ("runs/a=b", "mine")
    for bad in ("runs/a", "=mine", "runs/a="):
        with pytest.raises(ValueError, match="--label takes DIR=PREFIX"):
            parse_label_option(bad)


@pytest.mark.parametrize("second", ["runs", "dotted"])
def test_one_directory_given_two_prefixes_is_refused(tmp_path: Path, second: str) -> None:
    a = write_dir(tmp_path / "a", dqn())
    b = write_dir(tmp_path / "b", empathic())
    again = {"runs": a / "runs", "dotted": tmp_path / "b" / ".." / "a"}[second]
    with pytest.raises(
        ValueError, match=rf"--label {again}=Y: {again} is the directory {a} is, which has a prefix already \('X'\)"
    ):
        load_results_dirs([a, b], {a: "X", again: "Y"})


def test_one_directory_as_it_was_no_comparison_header_columns_or_against(tmp_path: Path) -> None:
    directory = write_dir(tmp_path / "one", dqn() + empathic())
    paths = write_leaderboard(directory)
    markdown = paths["markdown"].read_text(encoding="utf-8")
    assert paths["markdown"].parent == directory and "Read from" not in markdown and "Against" not in markdown
    assert "| empathic_dqn 0.5 | 5 |" in markdown and "·  20,000" not in markdown
    assert next(csv.reader(io.StringIO(paths["csv"].read_text(encoding="utf-8")))) == list(CSV_COLUMNS)


def test_the_committed_quick_leaderboard_is_what_one_directory_gives(tmp_path: Path) -> None:
    """``docs/results/quick`` written again: its Markdown and CSV are the committed ones but for the
    commit and version of the code that wrote them."""
    shipped = Path(__file__).resolve().parents[1] / "docs" / "results" / "quick"
    paths = write_leaderboard(shipped, tmp_path, command="empathy-zoo leaderboard docs/results/quick")
    committed = (shipped / "LEADERBOARD.md").read_text(encoding="utf-8").splitlines()
    written = paths["markdown"].read_text(encoding="utf-8").splitlines()
    assert committed[3:] == written[3:] and committed[:2] == written[:2]

    def rows(text: str) -> list[list[str]]:
        return [row[: CSV_COLUMNS.index("version")] for row in csv.reader(io.StringIO(text))]

    assert rows((shipped / "leaderboard.csv").read_text(encoding="utf-8")) == rows(paths["csv"].read_text(encoding="utf-8"))


def test_budgets_in_labels_sort_by_value() -> None:
    labels = ["DQN · 1,000,000 steps", "DQN · 30,000 steps", "DQN · 100,000 steps"]
    assert sorted(labels, key=label_order) == ["DQN · 30,000 steps", "DQN · 100,000 steps", "DQN · 1,000,000 steps"]


def test_the_command_line_reads_two_directories(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    first = write_dir(tmp_path / "first", dqn() + empathic())
    second = write_dir(tmp_path / "second", dqn(learning_rate=0.0005, harms=0.9))
    out = tmp_path / "out"
    assert main(["leaderboard", str(first), str(second)]) == 2
    assert "--out OUT" in capsys.readouterr().err
    assert main(["leaderboard", str(first), str(second), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("empathy-zoo: error: ") and str(first) in err and str(second) in err and "--label" in err
    assert main(["leaderboard", str(first), str(second), "--out", str(out), "--label", f"{second}=mine"]) == 0
    printed = capsys.readouterr().out
    assert f"wrote {out / 'LEADERBOARD.md'}" in printed and f"wrote {out / 'leaderboard.html'}" in printed
    markdown = (out / "LEADERBOARD.md").read_text(encoding="utf-8")
    command = f"empathy-zoo leaderboard {first} {second} --out {out} --label {second}=mine"
    assert f"Produced by `{command}`" in markdown and f"- `{first}`: 10 runs" in markdown
    assert f"| mine {SHOWN} | 5 |" in markdown
    assert main(["leaderboard", str(first), "--label", f"{tmp_path / 'nowhere'}=x"]) == 2
    assert "is not one of the results directories read" in capsys.readouterr().err
