"""Write the whole leaderboard of a results directory: Markdown, CSV, HTML and PNG figures."""

from __future__ import annotations

import os
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
    load_results,
    score_runs,
    table_env,
)
from leaderboard.improvement import improvements_over_dqn
from leaderboard.plots import plot_learning_curves
from leaderboard.tables import TRADEOFF, Provenance, csv_text, env_metrics, html_report, markdown_report
from leaderboard.tradeoff import plot_tradeoffs

__all__ = ["MARKDOWN_NAME", "CSV_NAME", "HTML_NAME", "FIGURES_DIR", "write_leaderboard"]

MARKDOWN_NAME = "LEADERBOARD.md"
CSV_NAME = "leaderboard.csv"
HTML_NAME = "leaderboard.html"
FIGURES_DIR = "figures"


def write_leaderboard(
    results_dir: str | os.PathLike[str],
    out_dir: str | os.PathLike[str] | None = None,
    command: str | None = None,
    *,
    n_points: int = N_POINTS,
    random_state: int = DEFAULT_SEED,
    n_resamples: int = N_RESAMPLES,
    confidence: float = CONFIDENCE,
    final_fraction: float = FINAL_FRACTION,
) -> dict[str, Path]:
    """Score every result file of ``results_dir`` and write the leaderboard into ``out_dir``.

    ``results_dir`` holds the ``*.json`` result files, or is a sweep's output directory with
    them in ``runs/``. ``out_dir`` defaults to ``results_dir``. ``command`` is printed as the
    command that produced the leaderboard (default: the equivalent Python call).

    Writes, all atomically: ``LEADERBOARD.md``, ``leaderboard.csv``, ``leaderboard.html`` and
    ``figures/<env>_<metric>.png`` (learning curves) and ``figures/<env>_tradeoff.png`` (task against
    side effect, :mod:`leaderboard.tradeoff`). Returns ``{"markdown", "csv", "html": path}`` plus
    ``"figure:<env>:<metric>": path`` for every figure (``<metric>`` is ``tradeoff`` for the trade-off).
    No result file raises ``ValueError``.
    """
    results = load_results(results_dir)
    out = check_output_dir(results_dir if out_dir is None else out_dir, (FIGURES_DIR,))
    for directory in (out, out / FIGURES_DIR):  # what writes killed mid-way left here
        remove_stale_temp_files(directory)
    provenance = Provenance(
        command=command if command is not None else f"leaderboard.write_leaderboard({str(results_dir)!r})",
        version=package_version(),
        commit=git_commit(),
        n_resamples=n_resamples,
        confidence=confidence,
        random_state=random_state,
        final_fraction=final_fraction,
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
    tradeoffs = plot_tradeoffs(scores, out / FIGURES_DIR, base_env)
    figures = {**{(env, TRADEOFF): path for env, path in tradeoffs.items()}, **curves}
    links = {key: path.relative_to(out).as_posix() for key, path in figures.items()}
    pngs = {key: path.read_bytes() for key, path in figures.items()}
    paths = {
        "markdown": write_text_atomic(
            out / MARKDOWN_NAME, markdown_report(scores, provenance, links, base_env=base_env, improvements=improvements)
        ),
        "csv": write_text_atomic(out / CSV_NAME, csv_text(scores, provenance)),
        "html": write_text_atomic(
            out / HTML_NAME, html_report(scores, provenance, pngs, base_env=base_env, improvements=improvements)
        ),
    }
    paths.update({f"figure:{env}:{metric}": path for (env, metric), path in figures.items()})
    return paths
