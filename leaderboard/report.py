"""Write the whole leaderboard of a results directory (or of several): Markdown, CSV, HTML and PNG figures."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path

from empathy_zoo.atomic import check_output_dir, remove_stale_temp_files, write_text_atomic
from empathy_zoo.metrics import METRIC_NAMES
from empathy_zoo.provenance import git_commit, package_version
from leaderboard.aggregate import (
    CONFIDENCE,
    DEFAULT_SEED,
    FINAL_FRACTION,
    N_POINTS,
    N_RESAMPLES,
    group_runs,
    score_runs,
    table_env,
)
from leaderboard.budgets import budgets_of
from leaderboard.episodes import add_episodes_section
from leaderboard.heldout import add_heldout_section
from leaderboard.improvement import improvements_over_dqn, uncompared_rows
from leaderboard.plots import plot_learning_curves
from leaderboard.row_names import dqn_rows_of, renaming_note
from leaderboard.sources import load_results_dirs
from leaderboard.tables import (
    TRADEOFF,
    Provenance,
    RowFacts,
    csv_text,
    env_metrics,
    html_report,
    markdown_report,
    markdown_text,
)
from leaderboard.tradeoff import plot_tradeoffs

__all__ = ["MARKDOWN_NAME", "CSV_NAME", "HTML_NAME", "FIGURES_DIR", "write_leaderboard"]

MARKDOWN_NAME = "LEADERBOARD.md"
CSV_NAME = "leaderboard.csv"
HTML_NAME = "leaderboard.html"
FIGURES_DIR = "figures"


def write_leaderboard(
    results_dir: str | os.PathLike[str] | Sequence[str | os.PathLike[str]],
    out_dir: str | os.PathLike[str] | None = None,
    command: str | None = None,
    *,
    labels: Mapping[str | os.PathLike[str], str] | None = None,
    n_points: int = N_POINTS,
    random_state: int = DEFAULT_SEED,
    n_resamples: int = N_RESAMPLES,
    confidence: float = CONFIDENCE,
    final_fraction: float = FINAL_FRACTION,
) -> dict[str, Path]:
    """Score every result file of ``results_dir`` and write the leaderboard into ``out_dir``.

    ``results_dir`` holds the ``*.json`` result files, or is a sweep's output directory with
    them in ``runs/``; or it is a list of such directories, read into one leaderboard
    (:func:`leaderboard.sources.load_results_dirs`: ``labels`` maps a directory to the prefix of
    its labels; rows of different budgets are kept apart). ``out_dir`` defaults to ``results_dir``
    for one directory and is required for several (``ValueError``: nothing is written into a
    directory read unless asked). ``command`` is printed as the command that produced the
    leaderboard (default: the equivalent Python call). A leaderboard of several directories, of
    several budgets or with prefixed labels names every directory read (with the versions and
    commits its files record) and the budgets in its header, each row's DQN row in its
    probability-of-improvement tables, and each row's budget and directories in its CSV
    (:data:`leaderboard.tables.COMPARISON_CSV_COLUMNS`); that of one directory of one budget is
    written as it always was. A DQN reference row is shown as DQN whatever its result files label
    it (:mod:`leaderboard.row_names`; the CSV too, as it shows prefixes), and the pages say which
    rows are the reference and which labels were shown as DQN.

    Writes, all atomically: ``LEADERBOARD.md``, ``leaderboard.csv``, ``leaderboard.html`` and
    ``figures/<env>_<metric>.png`` (learning curves) and ``figures/<env>_tradeoff.png`` (task against
    side effect, :mod:`leaderboard.tradeoff`); where runs kept their trained agents, one greedy
    episode per variant and row, ``figures/<env>_<row slug>_episode.gif``, in a "Greedy episodes"
    section (:mod:`leaderboard.episodes`; an agent file changed since its run wrote it raises
    ``ValueError``). Returns ``{"markdown", "csv", "html": path}`` plus ``"figure:<env>:<metric>": path``
    for every figure (``<metric>`` is ``tradeoff`` for the trade-off, ``episode_<row slug>`` for an
    episode). No result file raises ``ValueError``.
    """
    several = not isinstance(results_dir, (str, os.PathLike))
    dirs: list[str | os.PathLike[str]] = [results_dir] if isinstance(results_dir, (str, os.PathLike)) else list(results_dir)
    if len(dirs) > 1 and out_dir is None:
        raise ValueError(
            f"a leaderboard of {len(dirs)} results directories needs an output directory (--out OUT): "
            "it is written into none of the directories it reads unless asked"
        )
    read = load_results_dirs(dirs, labels, dqn_named=True)
    results = read.results
    dqn_rows = dqn_rows_of(results)
    comparison = len(dirs) > 1 or bool(labels) or read.budget_in_labels
    out = check_output_dir(dirs[0] if out_dir is None else out_dir, (FIGURES_DIR,))
    for directory in (out, out / FIGURES_DIR):  # what writes killed mid-way left here
        remove_stale_temp_files(directory)
    call = repr(str(dirs[0])) if not several else repr([str(directory) for directory in dirs])
    call += f", {str(out_dir)!r}" if several and out_dir is not None else ""
    provenance = Provenance(
        command=command if command is not None else f"leaderboard.write_leaderboard({call})",
        version=package_version(),
        commit=git_commit(),
        n_resamples=n_resamples,
        confidence=confidence,
        random_state=random_state,
        final_fraction=final_fraction,
        directories=read.directories if comparison else (),
        budgets=read.budgets if comparison else (),
    )
    scores = score_runs(
        results, final_fraction=final_fraction, random_state=random_state, n_resamples=n_resamples, confidence=confidence
    )
    curves = plot_learning_curves(
        results, out / FIGURES_DIR, n_points=n_points, random_state=random_state, n_resamples=n_resamples, confidence=confidence
    )
    base_env = {table_env(run): run["env"] for run in results}  # a variant is shown like its env
    improvements = improvements_over_dqn(
        results,
        {env: env_metrics(env, base_env, METRIC_NAMES) for env in base_env},
        random_state=random_state,
        n_resamples=n_resamples,
        confidence=confidence,
    )
    uncompared = uncompared_rows(results) if comparison else []
    rows = None
    if comparison:
        directories = read.row_directories()
        rows = {row: RowFacts(budgets_of(runs)[0], directories[row]) for row, runs in group_runs(results).items()}
    tradeoffs = plot_tradeoffs(scores, out / FIGURES_DIR, base_env, dqn_rows)
    figures = {**{(env, TRADEOFF): path for env, path in tradeoffs.items()}, **curves}
    links = {key: path.relative_to(out).as_posix() for key, path in figures.items()}
    pngs = {key: path.read_bytes() for key, path in figures.items()}
    markdown_note = renaming_note(read.renamed, bool(dqn_rows), markdown_text)
    markdown = markdown_report(
        scores,
        provenance,
        links,
        base_env=base_env,
        improvements=improvements,
        uncompared=uncompared,
        reference_note=markdown_note,
    )
    html = html_report(
        scores,
        provenance,
        pngs,
        base_env=base_env,
        improvements=improvements,
        uncompared=uncompared,
        reference_note=renaming_note(read.renamed, bool(dqn_rows)),
    )
    markdown, html, heldout_figures = add_heldout_section(dirs, results, out, markdown, html, origins=read.origins)
    markdown, html, episode_figures = add_episodes_section(results, out, markdown, html, origins=read.origins)
    paths = {
        "markdown": write_text_atomic(out / MARKDOWN_NAME, markdown),
        "csv": write_text_atomic(out / CSV_NAME, csv_text(scores, provenance, rows)),
        "html": write_text_atomic(out / HTML_NAME, html),
    }
    paths.update({f"figure:{env}:{metric}": path for (env, metric), path in figures.items()})
    paths.update(heldout_figures)
    paths.update(episode_figures)
    return paths
