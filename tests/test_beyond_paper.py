"""REPRODUCTION.md's last section, "Beyond the paper: partners the robot never met": the held-out
evaluation of the judged runs, with the leaderboard's tables and reading rule, its figures linked
relative to the report."""

from __future__ import annotations

from pathlib import Path

from helpers_heldout import scenario_set, synthetic_run, write_synthetic

from empathy_zoo.atomic import write_json_atomic
from empathy_zoo.experiment.records import RunResult
from leaderboard.beyond_paper import BEYOND_TITLE, beyond_the_paper
from leaderboard.reproduction import write_reproduction

OWN = {"cat_0": "random_walk"}
SET = scenario_set("coexistence_v0", {"cat_stays": {"cat_0": "stay"}, "cat_chases": {"cat_0": "chase"}})


def _results(out: Path) -> list[RunResult]:
    runs = [synthetic_run("coexistence_v0", "empathic_dqn", beta, seed) for beta in (1.0, 0.5) for seed in range(5)]
    for run in runs:
        write_json_atomic(out / "runs" / f"{run.run_id}.json", run.to_document())
    harms = {1.0: 0.45, 0.5: 0.1}  # (a chasing cat doubles them, within the one cat: at most 1 an episode)
    values = [
        (
            run,
            {
                "trained with": {"harms": harms[run.config.settings["selfishness"]] + 0.01 * run.seed},
                "cat_stays": {"harms": 0.0},
                "cat_chases": {"harms": 2 * harms[run.config.settings["selfishness"]] + 0.01 * run.seed},
            },
        )
        for run in runs
    ]
    write_synthetic(out, values, SET, OWN)
    return runs


def test_the_section_holds_the_heldout_tables_and_links_its_figures_from_the_report(tmp_path: Path) -> None:
    results = tmp_path / "docs" / "results" / "paper"
    _results(results)
    report = tmp_path / "REPRODUCTION.md"
    text = beyond_the_paper(results, report)
    assert text.startswith(f"## {BEYOND_TITLE}")
    assert "not a claim of the paper" in text
    assert "cat_chases" in text and "Does its harm avoidance generalise?" in text
    links = [line.split("](")[1].rstrip(")") for line in text.splitlines() if line.startswith("![")]
    assert links and all(link.startswith("docs/results/paper/figures/") for link in links)
    assert all((tmp_path / link).is_file() for link in links)


def test_without_evaluations_there_is_no_section(tmp_path: Path) -> None:
    run = synthetic_run("coexistence_v0", "empathic_dqn", 0.5, 0)
    write_json_atomic(tmp_path / "runs" / f"{run.run_id}.json", run.to_document())
    assert beyond_the_paper(tmp_path, tmp_path / "REPRODUCTION.md") == ""


def test_the_report_places_it_after_the_claims(tmp_path: Path) -> None:
    from test_reproduction import _paper_like, fake_reference

    for run in _paper_like():
        write_json_atomic(tmp_path / "runs" / f"{run.run_id}.json", {**run.to_document(), "agent": None})
    extra = tmp_path / "extra"
    _results(extra)
    section = beyond_the_paper(extra, tmp_path / "REPRODUCTION.md")
    text = write_reproduction(tmp_path, appendix=section, reference=fake_reference).read_text()
    assert text.index("## Harms to the cat fall as β falls.") < text.index(f"## {BEYOND_TITLE}")
