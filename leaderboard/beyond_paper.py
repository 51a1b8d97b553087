"""The reproduction report's last section, "Beyond the paper: partners the robot never met": the
held-out evaluation of the paper profile's trained agents (:mod:`leaderboard.heldout`, the same
tables, reading rule and figures as the leaderboard's "Held-out partners"), placed after the
paper's claims and marked as the suite's own question.

    empathy-zoo reproduction docs/results/paper --out REPRODUCTION.md

adds it when ``docs/results/paper/evaluations/`` holds evaluation files (``empathy-zoo evaluate``);
its figures are written beside the leaderboard's, in the results directory's ``figures/``, and
linked relative to the report: the same figures, rows named as the leaderboard names them (β = 1 as
DQN), so either command leaves the same files.
"""

from __future__ import annotations

import os

from empathy_zoo.names import resolved
from leaderboard.heldout import heldout_section
from leaderboard.page_markdown import section_markdown
from leaderboard.sources import load_results_dirs

__all__ = ["BEYOND_TITLE", "BEYOND_LEAD", "beyond_the_paper"]

BEYOND_TITLE = "Beyond the paper: partners the robot never met"
"""The section's heading."""
BEYOND_LEAD = (
    "The suite's own question, not a claim of the paper: does what each robot learnt carry over to partners "
    "it never trained with? Every trained agent of the runs judged above played greedy episodes beside its "
    "own partner and beside each held-out partner of its environment's shipped scenario set; the reading "
    "rule below (docs/heldout.md) was written and tested before any of these evaluations was run."
)
"""The paragraph before its tables."""


def beyond_the_paper(results_dir: str | os.PathLike[str], report_path: str | os.PathLike[str]) -> str:
    """The section's Markdown for the report written to ``report_path`` (``""`` when
    ``results_dir`` holds no evaluation files); its figures go to ``results_dir/figures``."""
    report_dir = resolved(report_path).parent
    figures = resolved(results_dir) / "figures"
    section = heldout_section(
        results_dir,
        list(load_results_dirs([results_dir], dqn_named=True).results),  # (rows named as the leaderboard's)
        report_dir,
        figures_dir=os.path.relpath(figures, report_dir),
        title=BEYOND_TITLE,
        lead=BEYOND_LEAD,
    )
    return "" if section is None else section_markdown(section.section)
