"""The leaderboard's "Greedy episodes" section: one short greedy episode per environment variant
and method row, as an animated GIF, from the trained agents the runs kept beside their result files.

For every row (variant and label, in the tables' order) whose runs kept their agents
(:data:`empathy_zoo.agent_file.RESULT_FIELD`), the run of the lowest seed that kept one is chosen;
its agent file, beside its result file in the directory it was read from, is loaded checked
against the SHA-256 its result file records (:func:`empathy_zoo.agent_file.load_agent`: a changed
file is refused, the message naming both files). The agent plays one greedy episode in the world
it trained in (its result file's ``config``: ``env``, ``env_kwargs`` and the ``fixed`` partners,
policy labels read back by :func:`empathy_zoo.policies.recorded_entry`: registered policies only,
unless the user allows a plug-in by name), reset with
:data:`EPISODE_SEED`, for at most :data:`EPISODE_STEPS` steps, written atomically as
``figures/<variant>_<row slug>_episode.gif`` by :func:`empathy_zoo.episode_gif.episode_gif`
(:func:`episode_slugs`: file-safe names that depend only on the variant and the label, and
on the labels beside it only where two would share a name).

The section (:func:`episodes_section`) is a table per variant (the run, the steps shown and the
episode's metrics) with each row's GIF, linked from ``LEADERBOARD.md`` and from ``leaderboard.html``
(relative to it: keep ``figures/`` beside the page; its PNG figures stay embedded);
:mod:`leaderboard.report` places it before the metric definitions. A
leaderboard whose runs kept no agent has no such section and no GIF. A row whose agent file is
missing, or is a Stable-Baselines3 agent without Stable-Baselines3 installed, is named in a note
instead of shown.

One episode illustrates what a method's robot does; it measures nothing (the tables above do):
``empathy-zoo watch <run id> --dir DIR`` plays more.
"""

from __future__ import annotations

import hashlib
import unicodedata
from collections.abc import Collection, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from empathy_zoo.agent_file import check_agent_hash, load_agent
from empathy_zoo.environments import default_policies
from empathy_zoo.episode_gif import GIF_STEPS, GifEpisode, episode_gif
from empathy_zoo.experiment.agent_method import check_agent_method
from empathy_zoo.experiment.records import RunResult
from empathy_zoo.metrics import METRIC_NAMES
from empathy_zoo.names import check_path_name, confined
from empathy_zoo.policies import PolicyEntry, make_policy, recorded_entry
from empathy_zoo.result_file import RUNS_DIR
from leaderboard.aggregate import group_runs
from leaderboard.page import Block, Figure, Heading, Paragraph, Section, Table
from leaderboard.page_markdown import markdown_text
from leaderboard.tables import env_metrics

__all__ = [
    "SECTION_TITLE",
    "EPISODE_SEED",
    "EPISODE_STEPS",
    "GIF_SUFFIX",
    "MAX_SLUG",
    "RowEpisode",
    "EpisodeSection",
    "row_slug",
    "episode_slugs",
    "episode_file_name",
    "chosen_runs",
    "trained_world",
    "ForgedWorld",
    "check_row_agent",
    "play_row_episodes",
    "episodes_section",
]

SECTION_TITLE = "Greedy episodes"
"""The section's heading."""
EPISODE_SEED = 0
"""The seed every row's episode is reset with (the same for every row, so rows meet the same start)."""
EPISODE_STEPS = GIF_STEPS
"""Steps an episode shows at most."""
GIF_SUFFIX = "_episode.gif"
"""How an episode's file name ends: ``<variant>_<row slug>_episode.gif``."""
MAX_SLUG = 80
"""Longest row slug, in characters (a longer one is cut and ends with its label's hash)."""
HASH_CHARS = 8
"""Hex digits of the label's SHA-256 that tell apart two labels of one slug."""


@dataclass(frozen=True)
class RowEpisode:
    """One row's greedy episode, as :func:`play_row_episodes` played and wrote it."""

    env: str
    """The row's variant (its table env)."""
    label: str
    """The row's method label."""
    slug: str
    """The row's slug in the GIF's file name (:func:`episode_slugs`)."""
    run_id: str
    """The run whose agent played."""
    run_seed: int
    """That run's seed (the lowest of the row's runs that kept an agent)."""
    result_file: Path
    """The run's result file."""
    agent_file: Path
    """Its agent file, beside it."""
    gif: GifEpisode
    """The episode played and the GIF written (its path, frames, size and bytes)."""


@dataclass
class EpisodeSection:
    """The section, and the GIFs it shows."""

    section: Section
    figures: dict[str, Path]
    """``{"figure:<variant>:episode_<row slug>": path}`` of every GIF written."""
    episodes: list[RowEpisode]
    """Every row's episode, in the section's order."""


# ---------------------------------------------------------------------------- file names
def _letter_name(char: str) -> str:
    """A non-ASCII letter as a word: ``β`` → ``beta`` (the last word of its Unicode name)."""
    name = unicodedata.name(char, "")
    return name.rsplit(" ", 1)[-1].lower() if name else ""


def row_slug(label: str) -> str:
    """``label`` as part of a file name: lower-case ASCII letters, digits, ``.`` and ``-`` kept,
    a non-ASCII letter spelled by its Unicode name (``β`` → ``beta``), anything else one ``_``;
    ``"Empathic DQN (β=0.5)"`` → ``"empathic_dqn_beta_0.5"``. A slug longer than :data:`MAX_SLUG`
    is cut and ends with the label's hash; a label with nothing to keep gives ``"row"``."""
    pieces: list[str] = []
    for char in unicodedata.normalize("NFKD", label):
        if unicodedata.combining(char):
            continue
        if char.isascii() and (char.isalnum() or char in ".-"):
            pieces.append(char.lower())
        elif not char.isascii() and char.isalpha():
            pieces.append(f"_{_letter_name(char)}_")
        else:
            pieces.append("_")
    slug = "_".join(part for part in "".join(pieces).split("_") if part).strip(".-_")
    if len(slug) > MAX_SLUG:
        slug = slug[: MAX_SLUG - HASH_CHARS - 1].rstrip(".-_") + "-" + _label_hash(label)
    return slug or "row"


def _label_hash(label: str) -> str:
    return hashlib.sha256(label.encode("utf-8")).hexdigest()[:HASH_CHARS]


def episode_slugs(rows: Sequence[tuple[str, str]]) -> dict[tuple[str, str], str]:
    """``{(variant, label): row slug}`` of ``rows`` (:func:`row_slug`); where two labels of one
    variant share a slug (``"A B"`` and ``"A_B"``), each such slug ends with ``-`` and the first
    :data:`HASH_CHARS` hex digits of its label's SHA-256."""
    slugs = {row: row_slug(row[1]) for row in rows}
    counts: dict[tuple[str, str], int] = {}
    for (env, _), slug in slugs.items():
        counts[env, slug] = counts.get((env, slug), 0) + 1
    return {
        (env, label): slug + "-" + _label_hash(label) if counts[env, slug] > 1 else slug for (env, label), slug in slugs.items()
    }


def episode_file_name(env: str, slug: str) -> str:
    """``<variant>_<row slug>_episode.gif``; a variant that cannot be part of a file name raises
    ``ValueError`` (:func:`empathy_zoo.names.check_path_name`)."""
    return check_path_name(f"{check_path_name(env, 'variant')}_{slug}{GIF_SUFFIX}", "episode file name")


# ---------------------------------------------------------------------------- which run, which world
def chosen_runs(results: Sequence[RunResult], origins: Sequence[str]) -> dict[tuple[str, str], tuple[RunResult, str]]:
    """``{(variant, label): (run, directory)}``: each row's run of the lowest seed that kept an agent,
    and the directory (as given) it was read from (``origins``, one per result:
    :attr:`leaderboard.sources.ResultSet.origins`); rows whose runs kept none are left out. Rows
    are in the tables' order (:func:`leaderboard.aggregate.group_runs`)."""
    if len(origins) != len(results):
        raise ValueError(f"{len(origins)} origins for {len(results)} results")
    origin_of = {id(run): origin for run, origin in zip(results, origins, strict=True)}
    chosen = {}
    for row, runs in group_runs(results).items():
        kept = [run for run in runs if run.agent is not None]
        if kept:
            run = min(kept, key=lambda run: run.seed)
            chosen[row] = (run, origin_of[id(run)])
    return chosen


def _runs_root(directory: str) -> Path:
    """Where ``directory``'s result files are (its ``runs/`` if it has one, as the leaderboard reads it)."""
    root = Path(directory)
    return root / RUNS_DIR if (root / RUNS_DIR).is_dir() else root


class ForgedWorld(ValueError):
    """A result file's world no run of the suite trained in: a partner for an agent the world lacks,
    or arguments its policy does not take. The leaderboard refuses the file (a plug-in partner not
    allowed is a note instead: the user may allow it)."""


def trained_world(run: RunResult, allowed_imports: Collection[str] = ()) -> tuple[str, dict[str, Any], dict[str, PolicyEntry]]:
    """``(env, env_kwargs, fixed)`` the run trained in, from its result file's ``config``: the
    fixed partners' policy labels read back as policy entries, each a registered policy or one of
    ``allowed_imports`` (:func:`empathy_zoo.policies.recorded_entry`: a result file never makes
    the leaderboard import code), else ``ValueError`` naming the field; nothing is imported."""
    where = f"run {run.run_id}: config.fixed"
    fixed = {agent: recorded_entry(entry, f"{where}.{agent}", allowed_imports) for agent, entry in run.config.fixed.items()}
    env, env_kwargs = run.config.env or run.env, dict(run.config.env_kwargs)
    unknown = sorted(set(fixed) - set(default_policies(env, env_kwargs)))
    if unknown:
        raise ForgedWorld(f"{where}: {env} as the run built it has no agent {', '.join(unknown)}")
    for agent, entry in fixed.items():
        try:
            make_policy(entry)  # (its arguments checked: a registered policy, or one of allowed_imports)
        except (ValueError, TypeError) as error:
            raise ForgedWorld(f"{where}.{agent}: {error}") from None
    return env, env_kwargs, fixed


def _row_inputs(
    run: RunResult, origin: str, allowed_imports: Collection[str]
) -> tuple[Path, Path, tuple[str, dict[str, Any], dict[str, PolicyEntry]]] | str:
    """``(result file, agent file, world)`` of a row's chosen ``run`` (read from ``origin``), or why it
    shows no episode (a note: its agent file is missing, its partner is a plug-in not allowed); a
    forged world raises ``ValueError`` naming the result file. Its agent file is not read."""
    root = _runs_root(origin)
    entry = run.agent
    assert entry is not None
    result_file = root / f"{check_path_name(run.run_id, 'run id')}.json"
    agent_file = confined(root, entry.file)
    if not agent_file.is_file():
        return f"agent file {agent_file}, named by result file {result_file}, is missing"
    try:
        world = trained_world(run, allowed_imports)
    except ForgedWorld as error:
        raise ValueError(f"{result_file}: {error}") from None
    except ValueError as error:
        return str(error)
    return result_file, agent_file, world


def check_row_agent(run: RunResult, origin: str, allowed_imports: Collection[str] = ()) -> None:
    """Refuse now what :func:`play_row_episodes` refuses of ``run`` when it is its row's chosen run
    (:func:`chosen_runs`; ``origin``: the directory it was read from): a forged world, and an agent
    file whose SHA-256 is not the one its result file records (the same ``ValueError``, naming both
    files). The agent is not loaded, only its file hashed
    (:func:`empathy_zoo.agent_file.check_agent_hash`); a run that would get a note passes."""
    inputs = _row_inputs(run, origin, allowed_imports)
    if not isinstance(inputs, str):
        assert run.agent is not None
        check_agent_hash(inputs[1], run.agent.sha256, result_file=inputs[0])


# ---------------------------------------------------------------------------- playing
def play_row_episodes(
    results: Sequence[RunResult],
    out_dir: str | Path,
    origins: Sequence[str],
    figures_dir: str = "figures",
    allowed_imports: Collection[str] = (),
) -> tuple[list[RowEpisode], list[str]]:
    """Play and write every row's greedy episode (see the module page) into ``out_dir / figures_dir``;
    returns the episodes and notes on rows left out (an agent file that is missing, needs a
    library not installed, or a run whose partner is a plug-in policy not in ``allowed_imports``).
    Every row's agent file and world are checked before the first GIF is written: an agent file
    whose SHA-256 is not the one its result file records raises ``ValueError`` naming both files,
    and nothing is written."""
    chosen = chosen_runs(results, origins)
    slugs = episode_slugs(list(chosen))
    folder = Path(out_dir) / figures_dir
    notes: list[str] = []
    ready = []
    for (env, label), (run, origin) in chosen.items():
        inputs = _row_inputs(run, origin, allowed_imports)
        if isinstance(inputs, str):
            notes.append(f"{label} ({env}): {inputs}; no episode shown")
            continue
        result_file, agent_file, world = inputs
        assert run.agent is not None
        try:
            agent = check_agent_method(load_agent(agent_file, run.agent.sha256, result_file=result_file))
        except ImportError as error:
            notes.append(f"{label} ({env}): {error}; no episode shown")
            continue
        ready.append((env, label, run, result_file, agent_file, agent, world))
    episodes: list[RowEpisode] = []
    for env, label, run, result_file, agent_file, agent, (world_env, env_kwargs, fixed) in ready:
        gif = episode_gif(
            agent,
            confined(folder, episode_file_name(env, slugs[env, label])),
            env=world_env,
            env_kwargs=env_kwargs,
            fixed=fixed,
            seed=EPISODE_SEED,
            max_steps=EPISODE_STEPS,
            title=label,
        )
        episodes.append(RowEpisode(env, label, slugs[env, label], run.run_id, run.seed, result_file, agent_file, gif))
    return episodes, notes


# ---------------------------------------------------------------------------- the section
def _intro() -> str:
    return (
        "One greedy episode per row: the trained agent of the row's lowest seed (kept beside its result file, "
        "checked against the SHA-256 the result file records), in the world it trained in (its environment, "
        f"arguments and fixed partners), reset with seed {EPISODE_SEED} and shown for at most {EPISODE_STEPS} steps; "
        "beside the grid, the step, the robot's action, a legend and the episode's metrics so far. One episode "
        "illustrates what a robot does and measures nothing (the tables above do); "
        "`empathy-zoo watch <run id> --dir <results dir>` plays more."
    )


def _value(name: str, value: float) -> str:
    return f"{value:.2f}" if name == "equality" else f"{value:g}"


def _steps_text(episode: RowEpisode) -> str:
    outcome = episode.gif.outcome
    return f"{outcome.steps}, episode over" if outcome.ended else f"first {outcome.steps}"


def _table(episodes: Sequence[RowEpisode], metrics: Sequence[str]) -> tuple[list[str], list[list[str]]]:
    header = ["Method", "Run", "Steps shown", *metrics]
    rows = [
        [
            episode.label,
            f"{episode.run_id} (seed {episode.run_seed})",
            _steps_text(episode),
            *(_value(name, episode.gif.outcome.metrics[name]) for name in metrics),
        ]
        for episode in episodes
    ]
    return header, rows


def _alt(episode: RowEpisode) -> str:
    return f"{episode.label}: a greedy episode of {episode.run_id}"


def episodes_section(
    results: Sequence[RunResult],
    out_dir: str | Path,
    origins: Sequence[str],
    figures_dir: str = "figures",
    allowed_imports: Collection[str] = (),
) -> EpisodeSection | None:
    """The "Greedy episodes" section of ``results`` (``origins``: the directory each was read
    from), its GIFs written into ``out_dir / figures_dir`` and linked relative to ``out_dir``;
    ``None`` when no run kept an agent."""
    episodes, notes = play_row_episodes(results, out_dir, origins, figures_dir, allowed_imports)
    if not episodes and not notes:
        return None
    out = Path(out_dir)
    base_env = {run.table_env: run.env for run in results}
    blocks: list[Block] = [Paragraph(_intro(), note=True)]
    figures: dict[str, Path] = {}
    for env in dict.fromkeys(episode.env for episode in episodes):
        mine = [episode for episode in episodes if episode.env == env]
        header, rows = _table(mine, env_metrics(env, base_env, METRIC_NAMES))
        blocks += [Heading(markdown_text(env)), Table(header, rows)]
        for episode in mine:
            path = episode.gif.path
            figures[f"figure:{env}:episode_{episode.slug}"] = path
            blocks.append(Figure(_alt(episode), path.relative_to(out).as_posix()))  # (its GIF draws the label as its title)
    blocks += [Paragraph(f"Note: {markdown_text(note)}", note=True) for note in notes]  # (labels and errors are data)
    return EpisodeSection(Section(SECTION_TITLE, blocks), figures, episodes)
