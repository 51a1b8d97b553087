"""Whether the paper's Coexistence claims depend on the rules the world follows: C1–C4 judged in
each condition (variant) of a sweep by :func:`leaderboard.reproduction.coexistence_claims`, each
against the exact optimum of its own rules (:mod:`empathy_zoo.exact_solver`), and compared.

A condition is a variant of Coexistence in the results (``config.variant``: the paper's rules,
the authors' ``rules="authors"``, …) holding the paper's Coexistence experiments: Empathic DQN at
β = 1, 0.75, 0.5, 0.25 and the −100 harm penalty. For each claim and phase the conditions'
verdicts give one answer (:func:`hinge`): the claim *hinges on the rules* where one condition
reproduces it and another does not, *does not hinge* where every condition gives the same verdict,
and is *undecided* where any condition is undecided or not testable.

``python -m leaderboard.coexistence_sensitivity DIR [--out FILE]`` prints (or writes) the page.
"""

from __future__ import annotations

import argparse
import os
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from empathy_zoo.atomic import write_text_atomic
from empathy_zoo.experiment.records import RunResult
from empathy_zoo.names import check_output_file, terminal_line
from leaderboard.reproduction import (
    BETAS,
    COEXISTENCE,
    PENALTY,
    PHASES,
    Reference,
    Verdict,
    coexistence_claims,
    load_checked_results,
    method_key,
)
from leaderboard.run_facts import check_one_experiment

TITLE = "# Coexistence: do the paper's claims depend on the rules?"
"""The page's first line (a file that does not begin so is no page of this tool: never replaced)."""

__all__ = [
    "reproduction_section",
    "ReferenceOf",
    "condition_runs",
    "exact_reference",
    "hinge",
    "judge_conditions",
    "sensitivity_markdown",
    "write_coexistence_sensitivity",
]

ReferenceOf = Callable[[Mapping[str, Any]], Reference]
"""A condition's environment arguments → the exact optimum its C3 is judged against."""
NEEDED = (*(f"β={b:g}" for b in BETAS), PENALTY)
"""The experiments each condition must hold (as :func:`leaderboard.reproduction.method_key` names them)."""
HINGES, HOLDS, UNDECIDED, ALONE = "hinges on the rules", "does not hinge", "undecided", "one condition only"
"""The answers of :func:`hinge`."""


def exact_reference(env_kwargs: Mapping[str, Any]) -> Reference:
    """The exact optimum of Coexistence built with ``env_kwargs`` (even ties), as
    :func:`leaderboard.reproduction.coexistence_claims` calls a reference; each outcome computed once."""
    from empathy_zoo.exact_solver import optimum, tabular_model

    model = tabular_model(COEXISTENCE, **env_kwargs)
    cache: dict[tuple[float, float, float, int], Any] = {}

    def reference(selfishness: float, epsilon: float, *, gamma: float, max_cycles: int) -> Any:
        key = (float(selfishness), float(epsilon), float(gamma), int(max_cycles))
        if key not in cache:
            cache[key] = optimum(model, selfishness, epsilon, gamma=gamma, max_cycles=max_cycles)
        return cache[key]

    return reference


def condition_runs(results: Sequence[RunResult]) -> dict[str, dict[str, list[RunResult]]]:
    """``{variant: {experiment: runs}}`` of the Coexistence runs in ``results``, by variant in the
    order first met; raises ``ValueError`` naming what a condition lacks, or that none is there."""
    out: dict[str, dict[str, list[RunResult]]] = {}
    for run in results:
        if run.env == COEXISTENCE:
            out.setdefault(str(run.config.variant), {}).setdefault(method_key(run), []).append(run)
    if not out:
        raise ValueError(f"no {COEXISTENCE} runs in these results")
    for variant, runs in out.items():
        missing = [key for key in NEEDED if key not in runs]
        if missing:
            raise ValueError(f"condition {variant!r} lacks the paper's experiments {', '.join(missing)}")
        check_one_experiment({f"the {key} runs of condition {variant!r}": runs[key] for key in NEEDED})
        first = runs[NEEDED[0]][0]
        for run in (run for key in NEEDED for run in runs[key]):
            if dict(run.config.env_kwargs) != dict(first.config.env_kwargs):
                raise ValueError(
                    f"runs {first.run_id} and {run.run_id} are both of condition {variant!r} but of two worlds "
                    f"(env_kwargs {dict(first.config.env_kwargs)} and {dict(run.config.env_kwargs)}): a condition is one world"
                )
    return out


def _arguments(runs: Mapping[str, list[RunResult]]) -> dict[str, Any]:
    """The environment arguments of a condition's runs (one set: a condition is one variant)."""
    return dict(next(iter(runs.values()))[0].config.env_kwargs)


def judge_conditions(
    results: Sequence[RunResult], reference_of: ReferenceOf = exact_reference
) -> dict[str, dict[str, dict[str, Verdict]]]:
    """``{variant: {claim: {phase: verdict}}}``: C1–C4 in each condition, C3 against
    ``reference_of(its environment arguments)``."""
    return {
        variant: coexistence_claims(runs, reference_of(_arguments(runs))) for variant, runs in condition_runs(results).items()
    }


def hinge(verdicts: Sequence[Verdict]) -> str:
    """One claim's answer over the conditions' verdicts in one phase (see the module page);
    :data:`ALONE` with fewer than two conditions, which leave nothing to compare."""
    if len(verdicts) < 2:
        return ALONE
    if any(verdict.undecided or verdict.ok is None for verdict in verdicts):
        return UNDECIDED
    return HOLDS if len({verdict.ok for verdict in verdicts}) == 1 else HINGES


def _condition_text(runs: Mapping[str, list[RunResult]]) -> str:
    arguments = ", ".join(f"`{name}={value}`" for name, value in sorted(_arguments(runs).items())) or "the defaults"
    settings = next(iter(runs.values()))[0].config.settings
    time_limit = settings.get("time_limit", "bootstrap")
    return f"{arguments}; a time-limit end {'bootstraps' if time_limit == 'bootstrap' else 'is terminal'}"


def _conditions_and_answers(
    conditions: Mapping[str, Mapping[str, list[RunResult]]], judged: Mapping[str, Mapping[str, Mapping[str, Verdict]]]
) -> list[str]:
    """The conditions, then one table of every claim's verdict per condition and phase, and its answer."""
    variants = list(judged)
    lines = ["**Conditions.**", ""]
    for variant in variants:
        runs = conditions[variant]
        seeds = min(len(group) for group in runs.values())
        steps = next(iter(runs.values()))[0].steps
        lines.append(f"- `{variant}`: {_condition_text(runs)}; {seeds} seeds, {steps:,} steps per run.")
    header = " | ".join(f"`{variant}`" for variant in variants)
    lines += ["", f"| claim | phase | {header} | answer |", "|---|---|" + "---|" * len(variants) + "---|"]
    claims = list(judged[variants[0]])
    for claim in claims:
        for phase in PHASES:
            verdicts = [judged[variant][claim][phase] for variant in variants]
            words = " | ".join(verdict.word for verdict in verdicts)
            lines.append(f"| {claim} | {phase} | {words} | **{hinge(verdicts)}** |")
    return lines


def sensitivity_markdown(results: Sequence[RunResult], command: str, reference_of: ReferenceOf = exact_reference) -> str:
    """The page: the conditions, one table of verdicts and answers, then each verdict's evidence."""
    conditions = condition_runs(results)
    judged = judge_conditions(results, reference_of)
    variants = list(judged)
    claims = list(judged[variants[0]])
    lines = [
        TITLE,
        "",
        f"Generated by `{command}` (`leaderboard/coexistence_sensitivity.py`). Each condition is judged",
        "alone by the rules of REPRODUCTION.md (C3 against the exact optimum of its own rules), on",
        "the last greedy evaluation and on the final 10 % of training episodes.",
        "",
        *_conditions_and_answers(conditions, judged),
    ]
    lines += ["", "## Evidence", ""]
    for claim in claims:
        lines += [f"### {claim}", ""]
        for variant in variants:
            for phase in PHASES:
                verdict = judged[variant][claim][phase]
                lines.append(f"* `{variant}`, {phase}: {verdict.word}. {verdict.evidence}")
        lines.append("")
    return "\n".join(lines)


def reproduction_section(
    results: Sequence[RunResult], command: str, reference_of: ReferenceOf = exact_reference, least_conditions: int = 1
) -> str:
    """REPRODUCTION.md's section on the rules: the conditions and the table of verdicts and answers
    (the evidence is on the study's own page, ``SENSITIVITY.md``, beside its results). Results of
    fewer than ``least_conditions`` conditions raise ``ValueError`` (one condition compares nothing)."""
    conditions = condition_runs(results)
    if len(conditions) < least_conditions:
        raise ValueError(
            f"these results hold {len(conditions)} condition(s) of {COEXISTENCE} ({', '.join(conditions)}), not the "
            f"{least_conditions} or more a rules sweep compares (profile coexistence_sensitivity trains 2)"
        )
    judged = judge_conditions(results, reference_of)
    return "\n".join(
        [
            "## Do C1–C4 depend on the rules? Coexistence under the authors' rules",
            "",
            "The paper's Coexistence sweep under the paper's rules and under the authors' code's (SPEC §2,",
            '`rules="authors"`), each judged alone by this report\'s rules (C3 against the exact optimum of',
            "its own rules). Produced by:",
            "",
            f"    {command}",
            "",
            *_conditions_and_answers(conditions, judged),
            "",
            "**does not hinge**: the same verdict under both rule sets. The evidence of each verdict is in the",
            "study's SENSITIVITY.md, beside its results.",
        ]
    )


def write_coexistence_sensitivity(results_dir: str | os.PathLike[str], out_path: str | os.PathLike[str], command: str) -> Path:
    """Judge ``results_dir`` and write the page to ``out_path``; nothing is written on a refusal.
    ``out_path`` must be a Markdown file name (``.md``: never a result or agent file the page is
    made of, :func:`empathy_zoo.names.check_output_file`), checked before anything is read."""
    path = check_output_file(out_path, "Markdown", ".md", "COEXISTENCE_SENSITIVITY.md", TITLE.encode())
    text = sensitivity_markdown(load_checked_results(results_dir), command)
    write_text_atomic(path, text + "\n")
    return path


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m leaderboard.coexistence_sensitivity DIR [--out FILE]``."""
    parser = argparse.ArgumentParser(prog="python -m leaderboard.coexistence_sensitivity", description=__doc__.split("\n\n")[0])
    parser.add_argument("results_dir")
    parser.add_argument("--out", help="write the page here (default: print it)")
    args = parser.parse_args(argv)
    command = f"empathy-zoo analyse coexistence-sensitivity {args.results_dir}" + (f" --out {args.out}" if args.out else "")
    try:
        if args.out == "":  # (not taken for "print it": an empty path names no file)
            raise ValueError("argument --out: an empty path; name the Markdown file to write, or leave --out out to print")
        if args.out:
            write_coexistence_sensitivity(args.results_dir, args.out, command)
        else:
            print(sensitivity_markdown(load_checked_results(args.results_dir), command))
    except ValueError as error:
        parser.exit(2, f"{parser.prog}: error: {terminal_line(error)}\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
