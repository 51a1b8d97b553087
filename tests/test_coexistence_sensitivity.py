"""The Coexistence sensitivity judge: each condition judged alone by the paper's C1–C4 rules, C3
against its own rules' exact optimum, and one answer per claim and phase from the conditions'
verdicts. Synthetic runs stand in for a sweep; the verdict rules themselves are
tests/test_reproduction.py's."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import pytest
from helpers_results import derive_run_id, record, synthetic_document, synthetic_result

from empathy_zoo.atomic import write_json_atomic
from empathy_zoo.experiment.records import RunResult
from leaderboard.coexistence_sensitivity import (
    ALONE,
    HINGES,
    HOLDS,
    UNDECIDED,
    condition_runs,
    exact_reference,
    hinge,
    judge_conditions,
    main,
    reproduction_section,
    sensitivity_markdown,
)
from leaderboard.reproduction import Verdict

AUTHORS = {"rules": "authors", "max_cycles": 501}
C3 = "The less selfish agents (β = 0.5, 0.25) eventually survive without harming the cat."
C1 = "Harms to the cat fall as β falls."


@dataclass(frozen=True)
class Outcome:
    harms: float
    survival: float


def lenient(env_kwargs: dict[str, Any]):
    """A reference every harm-free, long-surviving run meets, whichever the condition."""
    return lambda selfishness, epsilon, *, gamma, max_cycles: Outcome(0.01, 450.0)


def condition(variant: str, env_kwargs: dict[str, Any], low_beta_harms: float) -> list[RunResult]:
    runs = []
    for seed in range(5):
        rows = ((1.0, 0.9, 490.0), (0.75, 0.5, 480.0), (0.5, low_beta_harms, 475.0), (0.25, low_beta_harms, 470.0))
        made = [synthetic_document("coexistence_v0", "empathic_dqn", b, seed, harms=h, survival=s) for b, h, s in rows]
        made.append(synthetic_document("coexistence_v0", "dqn_harm_penalty", 1.0, seed, harms=0.2, survival=470.0))
        for run in made:
            run["config"] = {**run["config"], "variant": variant, "env_kwargs": dict(env_kwargs)}
            derive_run_id(run)
        runs += [record(run) for run in made]
    return runs


def test_each_condition_is_judged_alone_and_a_differing_verdict_hinges():
    results = condition("coexistence_v0", {}, 0.0) + condition("coexistence_authors", AUTHORS, 1.5)
    judged = judge_conditions(results, lenient)
    assert list(judged) == ["coexistence_v0", "coexistence_authors"]
    paper, authors = judged["coexistence_v0"], judged["coexistence_authors"]
    assert (paper[C3]["greedy"].word, authors[C3]["greedy"].word) == ("reproduced", "not reproduced")
    assert hinge([paper[C3]["greedy"], authors[C3]["greedy"]]) == HINGES
    assert hinge([paper[C1]["training"], paper[C1]["training"]]) == HOLDS


def test_each_condition_is_judged_against_the_optimum_of_its_own_arguments():
    seen: list[dict[str, Any]] = []

    def recording(env_kwargs: dict[str, Any]):
        seen.append(dict(env_kwargs))
        return lenient(env_kwargs)

    judge_conditions(condition("coexistence_v0", {}, 0.0) + condition("coexistence_authors", AUTHORS, 0.0), recording)
    assert seen == [{}, AUTHORS]


def test_an_undecided_or_untestable_verdict_makes_the_answer_undecided():
    reproduced, failed = Verdict(True, ""), Verdict(False, "")
    assert hinge([reproduced, Verdict(None, "", undecided=True)]) == UNDECIDED
    assert hinge([failed, Verdict(None, "")]) == UNDECIDED
    assert hinge([failed, failed]) == HOLDS and hinge([reproduced, failed]) == HINGES
    assert hinge([reproduced]) == ALONE


def test_a_condition_without_the_papers_experiments_is_refused_naming_it():
    results = [run for run in condition("coexistence_authors", AUTHORS, 0.0) if run.method != "dqn_harm_penalty"]
    with pytest.raises(ValueError, match="condition 'coexistence_authors' lacks the paper's experiments dqn_harm_penalty"):
        condition_runs(results)
    with pytest.raises(ValueError, match="no coexistence_v0 runs"):
        condition_runs([synthetic_result("sharing_v0", "empathic_dqn", 1.0, 0)])


def test_the_exact_reference_is_the_solvers_optimum_of_the_authors_rules():
    outcome = exact_reference(AUTHORS)(0.5, 0.0, gamma=0.99, max_cycles=501)
    assert (round(outcome.harms, 4), round(outcome.survival, 1)) == (0.0815, 480.5)  # docs/reference.md's table


def test_the_page_names_each_condition_and_answers_each_claim(tmp_path, capsys):
    results = condition("coexistence_v0", {}, 0.0) + condition("coexistence_authors", AUTHORS, 1.5)
    page = sensitivity_markdown(results, "cmd", lenient)
    assert "- `coexistence_authors`: `max_cycles=501`, `rules=authors`; a time-limit end bootstraps; 5 seeds" in page
    assert f"| {C3} | greedy | reproduced | not reproduced | **{HINGES}** |" in page
    for run in results:
        write_json_atomic(tmp_path / "runs" / f"{run.run_id}.json", run.to_document())
    with pytest.raises(SystemExit) as refused:
        main([str(tmp_path / "nothing")])
    assert refused.value.code == 2 and "error:" in capsys.readouterr().err


def test_the_reproduction_section_holds_the_verdict_table_without_the_evidence():
    results = condition("coexistence_v0", {}, 0.0) + condition("coexistence_authors", AUTHORS, 1.5)
    section = reproduction_section(results, "the command", lenient)
    assert section.startswith("## Do C1–C4 depend on the rules? Coexistence under the authors' rules")
    assert "    the command" in section
    assert f"| {C3} | greedy | reproduced | not reproduced | **{HINGES}** |" in section
    assert "## Evidence" not in section and section.count("- `coexistence_") == 2
