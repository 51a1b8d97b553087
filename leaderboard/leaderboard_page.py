"""The leaderboard page's own sections, built once from computed scores: its header, a section per
environment (tables, their legends, P(improves on DQN), figures), the notes on its marks, and the
metric definitions.

:func:`score_sections` and :func:`definitions_section` give them as :mod:`leaderboard.page`
sections; :mod:`leaderboard.report` puts the other modules' sections between them and renders the
page once per format. :func:`report_page` is a page of these sections alone.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from typing import Literal

from empathy_zoo.markdown_escape import code_span
from empathy_zoo.metrics import METRIC_DEFINITIONS, METRIC_NAMES
from leaderboard.aggregate import MIN_INTERVAL_SEEDS, PHASES, Score
from leaderboard.improvement import Improvement
from leaderboard.legends import IMPROVEMENT_NOTE, coverage_note, multiplicity_note, resolve_coverage
from leaderboard.measured_coverage import MeasuredCoverage
from leaderboard.page import Block, BulletList, DefinitionList, Figure, Heading, Page, Paragraph, Section, Table
from leaderboard.page_markdown import markdown_text
from leaderboard.tables import (
    NO_INTERVAL_NOTE,
    PHASE_TITLES,
    SINGLE_SEED_MARK,
    ZERO_WIDTH_MARK,
    ZERO_WIDTH_NOTE,
    Provenance,
    env_metrics,
    improvement_sections,
    names_baselines,
    table_rows,
    table_seeds,
    uncompared_note,
)

__all__ = [
    "TITLE",
    "TRADEOFF",
    "FigureFile",
    "header_section",
    "environment_sections",
    "notes_section",
    "score_sections",
    "definitions_section",
    "leaderboard_page",
    "report_page",
]

TITLE = "empathy-zoo leaderboard"
"""The page's title and level-1 heading."""
TRADEOFF = "tradeoff"
"""The figure key (in place of a metric) of an env's task-against-side-effect figure."""
FigureFile = tuple[str, bytes | None]
"""A figure of the page: its link relative to the page and its PNG bytes (``None``: linked, not embedded)."""


def header_section(provenance: Provenance, reference_note: str = "") -> Section:
    """What the page says before its tables: who made it, what it read, what a cell means, and
    which rows are the DQN reference (``reference_note``, Markdown)."""
    blocks: list[Block] = [
        Paragraph(
            f"Produced by {code_span(provenance.command)} with empathy-zoo {markdown_text(provenance.version)}, "
            f"commit {code_span(provenance.commit_text())}."
        )
    ]
    if provenance.comparison():
        heading, directories, budget = provenance.source_lines()
        blocks += [Paragraph(heading), BulletList(directories), *([Paragraph(budget)] if budget else [])]
    blocks.append(Paragraph(provenance.method_text(), note=True))
    blocks += [Paragraph(reference_note, note=True)] if reference_note else []
    return Section("", blocks)


def _tables(
    scores: Sequence[Score], metrics: Sequence[str], digits: int, base_env: Mapping[str, str] | None
) -> Iterator[tuple[str, str, list[str], list[list[str]]]]:
    """``(env, phase, header, rows)`` of every table of scores, by env, then phase."""
    for env in sorted({score.env for score in scores}):
        for phase in PHASES:
            header, rows = table_rows(scores, env, phase, env_metrics(env, base_env, metrics), digits)
            if rows:
                yield env, phase, header, rows


def _figure_blocks(figures: Mapping[tuple[str, str], FigureFile], env: str) -> list[Block]:
    """``env``'s figures under their headings: its trade-off, then its learning curves."""
    mine = [(metric, figure) for (figure_env, metric), figure in figures.items() if figure_env == env]
    tradeoff = [(f"{env}: task against side effect", figure) for metric, figure in mine if metric == TRADEOFF]
    curves = [(f"{env}: {metric} vs training steps", figure) for metric, figure in mine if metric != TRADEOFF]
    blocks: list[Block] = []
    for heading, items in (("Task against side effect", tradeoff), ("Learning curves", curves)):
        if items:
            blocks.append(Heading(heading))
            blocks += [Figure(alt, link, png) for alt, (link, png) in items]
    return blocks


def _improvement_blocks(
    cells: Sequence[Improvement], env: str, digits: int, against: bool, uncompared: Sequence[tuple[str, str]]
) -> list[Block]:
    """``env``'s P(improves on DQN) tables, their legends, and the rows compared with no DQN row."""
    blocks: list[Block] = []
    for phase, header, rows in improvement_sections(cells, env, digits, against):
        blocks += [Heading(f"P(improves on DQN): {PHASE_TITLES[phase]}"), Table(header, rows, 2 if against else 1)]
    if blocks:
        blocks += [Paragraph(IMPROVEMENT_NOTE, note=True), Paragraph(multiplicity_note(cells), note=True)]
    note = uncompared_note(uncompared, env, markdown=True)
    return blocks + ([Paragraph(note, note=True)] if note else [])


def environment_sections(
    scores: Sequence[Score],
    figures: Mapping[tuple[str, str], FigureFile] | None = None,
    metrics: Sequence[str] = METRIC_NAMES,
    digits: int = 2,
    base_env: Mapping[str, str] | None = None,
    improvements: Sequence[Improvement] = (),
    uncompared: Sequence[tuple[str, str]] = (),
    coverage: MeasuredCoverage | Literal["committed"] | None = "committed",
    against: bool = False,
) -> list[Section]:
    """A section per environment with a table: per phase its table and the coverage its intervals
    were measured to have, then its P(improves on DQN) tables (naming each row's DQN row with
    ``against``), then its figures (``figures``: by ``(env, metric)``, :data:`TRADEOFF` for the trade-off)."""
    measured = resolve_coverage(coverage)
    by_env: dict[str, list[Block]] = {}
    for env, phase, header, rows in _tables(scores, metrics, digits, base_env):
        blocks = by_env.setdefault(env, [])
        blocks += [Heading(PHASE_TITLES[phase]), Table(header, rows)]
        note = coverage_note(measured, phase, header[2:], table_seeds(scores, env, phase))
        blocks += [Paragraph(note, note=True)] if note else []
    return [
        Section(
            markdown_text(env),
            [*blocks, *_improvement_blocks(improvements, env, digits, against, uncompared), *_figure_blocks(figures or {}, env)],
        )
        for env, blocks in by_env.items()
    ]


def notes_section(
    scores: Sequence[Score], metrics: Sequence[str] = METRIC_NAMES, digits: int = 2, base_env: Mapping[str, str] | None = None
) -> Section:
    """The legends of the marks the tables carry (a single seed, a zero-width interval, a mean
    without its interval), where they carry any; no heading."""
    zero_width = any(
        cell.endswith(f" {ZERO_WIDTH_MARK}")
        for *_, rows in _tables(scores, metrics, digits, base_env)
        for row in rows
        for cell in row[2:]
    )
    notes = [
        f"{SINGLE_SEED_MARK} a single seed: no spread to measure." if any(score.n_seeds == 1 for score in scores) else "",
        ZERO_WIDTH_NOTE if zero_width else "",
        NO_INTERVAL_NOTE if any(0 < score.n_seeds < MIN_INTERVAL_SEEDS for score in scores) else "",
    ]
    return Section("", [Paragraph(note, note=True) for note in notes if note])


def score_sections(
    scores: Sequence[Score],
    provenance: Provenance,
    figures: Mapping[tuple[str, str], FigureFile] | None = None,
    metrics: Sequence[str] = METRIC_NAMES,
    digits: int = 2,
    base_env: Mapping[str, str] | None = None,
    improvements: Sequence[Improvement] = (),
    uncompared: Sequence[tuple[str, str]] = (),
    reference_note: str = "",
    coverage: MeasuredCoverage | Literal["committed"] | None = "committed",
) -> list[Section]:
    """The header, a section per environment and the notes (:func:`header_section`,
    :func:`environment_sections`, :func:`notes_section`): everything the page shows of ``scores``.

    ``uncompared`` names the ``(env, label)`` rows no DQN row is compared with; ``reference_note``
    (Markdown) says which rows are the DQN reference (:func:`leaderboard.row_names.renaming_note`);
    ``coverage``: the measured coverage each table's legend quotes (:func:`leaderboard.legends.coverage_note`;
    by default the committed figures)."""
    against = names_baselines(provenance, improvements)
    return [
        header_section(provenance, reference_note),
        *environment_sections(scores, figures, metrics, digits, base_env, improvements, uncompared, coverage, against),
        notes_section(scores, metrics, digits, base_env),
    ]


def definitions_section(metrics: Sequence[str] = METRIC_NAMES) -> Section:
    """The page's last section: what each metric means."""
    return Section(
        "Metric definitions",
        [DefinitionList([(metric, METRIC_DEFINITIONS.get(metric, "(no definition)")) for metric in metrics])],
    )


def leaderboard_page(sections: Sequence[Section]) -> Page:
    """The leaderboard page of ``sections``, in order."""
    return Page(TITLE, sections)


def report_page(
    scores: Sequence[Score],
    provenance: Provenance,
    figures: Mapping[tuple[str, str], FigureFile] | None = None,
    metrics: Sequence[str] = METRIC_NAMES,
    digits: int = 2,
    base_env: Mapping[str, str] | None = None,
    improvements: Sequence[Improvement] = (),
    uncompared: Sequence[tuple[str, str]] = (),
    reference_note: str = "",
    coverage: MeasuredCoverage | Literal["committed"] | None = "committed",
) -> Page:
    """The page of :func:`score_sections` and the metric definitions alone, for either renderer
    (:func:`~leaderboard.page_markdown.to_markdown`, :func:`~leaderboard.page_html.to_html`);
    ``figures`` maps ``(env, metric)`` to its link and PNG bytes; the rest as :func:`score_sections`."""
    sections = score_sections(
        scores, provenance, dict(figures or {}), metrics, digits, base_env, improvements, uncompared, reference_note, coverage
    )
    return leaderboard_page([*sections, definitions_section(metrics)])
