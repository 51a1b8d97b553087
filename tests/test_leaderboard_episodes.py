"""The leaderboard's "Greedy episodes" section on tiny trained runs: one GIF per method row, of the
row's lowest seed's agent in its own world, its frames the episode's steps plus the reset; the
section in both pages before the metric definitions; a changed agent file refused naming both
files; a missing one named in a note; several directories each read for their own agents; runs
without agents give no section and no GIF; the file names file-safe and stable."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from helpers_heldout import dqn_and_empathic_runs

from empathy_zoo.agent_file import RESULT_FIELD, load_run_agent
from empathy_zoo.episode_gif import HOLD_MS
from empathy_zoo.experiment import RunSpec
from empathy_zoo.experiment.result_reader import read_result
from empathy_zoo.greedy_episode import play_greedy, watch_env
from empathy_zoo.names import PATH_NAME
from empathy_zoo.training import RunnerOptions, train_runs
from leaderboard import write_leaderboard
from leaderboard.episodes import (
    EPISODE_SEED,
    EPISODE_STEPS,
    GIF_SUFFIX,
    MAX_SLUG,
    SECTION_TITLE,
    episode_file_name,
    episode_slugs,
    row_slug,
    trained_world,
)

MAX_CYCLES = 80
SEEDS = (2, 1)
"""Trained in this order; the section shows seed 1's agent (the lowest)."""
ROWS = {"dqn": "DQN", "empathic_dqn": "Empathic DQN (β=0.5)"}
GIFS = {
    "DQN": "coexistence_v0_dqn_episode.gif",
    "Empathic DQN (β=0.5)": "coexistence_v0_empathic_dqn_beta_0.5_episode.gif",
}


def specs() -> list[RunSpec]:
    """DQN and Empathic DQN (β = 0.5), two seeds each, 600 steps of at most 80-step episodes."""
    return dqn_and_empathic_runs(SEEDS, MAX_CYCLES, 2)


@pytest.fixture(scope="module")
def trained(tmp_path_factory) -> Path:
    """A results directory of four tiny runs with the agent files the trainer kept."""
    out = tmp_path_factory.mktemp("results")
    paths = train_runs(specs(), out, RunnerOptions(progress=False, checkpoint_interval=0, workers=1))
    assert all(json.loads(p.read_text()).get(RESULT_FIELD) for p in paths)
    return out


@pytest.fixture(scope="module")
def board(trained, tmp_path_factory) -> tuple[Path, dict[str, Path]]:
    """The leaderboard of :func:`trained`, written into its own folder."""
    out = tmp_path_factory.mktemp("board")
    return out, write_leaderboard(trained, out)


def result_file(results: Path, method: str, seed: int) -> Path:
    (path,) = (results / "runs").glob(f"coexistence_v0__{method}-*__s{seed}.json")
    return path


def gif_frames(path: Path) -> list[int]:
    """The duration of every frame of the GIF at ``path``."""
    from PIL import Image, ImageSequence

    with Image.open(path) as image:
        return [frame.info["duration"] for frame in ImageSequence.Iterator(image)]


def copy_results(trained: Path, where: Path) -> Path:
    shutil.copytree(trained, where)
    return where


def test_one_gif_per_row_named_for_its_variant_and_label(board):
    out, paths = board
    written = sorted(p.name for p in (out / "figures").glob("*.gif"))
    assert written == sorted(GIFS.values())
    assert {key: path.name for key, path in paths.items() if ":episode_" in key} == {
        "figure:coexistence_v0:episode_dqn": GIFS["DQN"],
        "figure:coexistence_v0:episode_empathic_dqn_beta_0.5": GIFS["Empathic DQN (β=0.5)"],
    }
    for name in written:
        assert PATH_NAME.fullmatch(name)
        assert (out / "figures" / name).stat().st_size < 200_000  # a short episode stays small


def test_the_section_is_in_both_pages_before_the_metric_definitions(board):
    out, _ = board
    markdown = (out / "LEADERBOARD.md").read_text()
    page = (out / "leaderboard.html").read_text()
    assert markdown.count(f"## {SECTION_TITLE}") == 1
    assert markdown.index(f"## {SECTION_TITLE}") < markdown.index("## Metric definitions")
    assert page.index(f"<h2>{SECTION_TITLE}</h2>") < page.index("<h2>Metric definitions</h2>")
    for label, name in GIFS.items():
        assert f"](figures/{name})" in markdown
        assert f"| {label} |" in markdown
        assert f'src="figures/{name}"' in page and (out / "figures" / name).is_file()  # (linked, not embedded)
    assert "data:image/gif" not in page
    assert "seed 1)" in markdown and "seed 2)" not in markdown


@pytest.mark.parametrize("method", sorted(ROWS))
def test_a_gif_is_the_lowest_seeds_episode_in_its_own_world(trained, board, method):
    """The GIF holds the reset and every step played (the last frame held), and its steps are those
    of the row's seed-1 agent replayed in the world its result file records, from the fixed seed."""
    out, _ = board
    durations = gif_frames(out / "figures" / GIFS[ROWS[method]])
    run_file = result_file(trained, method, min(SEEDS))
    env, env_kwargs, fixed = trained_world(read_result(run_file))
    assert (env, env_kwargs, fixed) == ("coexistence_v0", {"max_cycles": MAX_CYCLES}, {"cat_0": "random_walk"})
    outcome = play_greedy(load_run_agent(run_file), watch_env(env, env_kwargs, fixed), EPISODE_SEED, max_steps=EPISODE_STEPS)
    assert len(durations) == outcome.steps + 1
    assert durations[-1] == HOLD_MS and len(set(durations[:-1])) == 1
    assert outcome.steps <= EPISODE_STEPS
    section = (out / "LEADERBOARD.md").read_text().split(f"## {SECTION_TITLE}")[1]
    row = next(line for line in section.splitlines() if line.startswith(f"| {ROWS[method]} |"))
    assert f"{run_file.stem} (seed {min(SEEDS)})" in row
    assert f"| {outcome.steps}, episode over |" in row if outcome.ended else f"| first {outcome.steps} |" in row


def test_the_gifs_are_written_again_byte_for_byte(trained, board, tmp_path):
    out, _ = board
    write_leaderboard(trained, tmp_path)
    for name in GIFS.values():
        assert (tmp_path / "figures" / name).read_bytes() == (out / "figures" / name).read_bytes()


def test_a_changed_agent_file_is_refused_naming_both_files(trained, tmp_path):
    results = copy_results(trained, tmp_path / "results")
    run_file = result_file(results, "empathic_dqn", min(SEEDS))
    agent_file = run_file.with_name(json.loads(run_file.read_text())[RESULT_FIELD]["file"])
    data = bytearray(agent_file.read_bytes())
    data[-20] ^= 0xFF
    agent_file.write_bytes(bytes(data))
    with pytest.raises(ValueError, match="refusing to load it") as error:
        write_leaderboard(results, tmp_path / "out")
    assert str(agent_file) in str(error.value) and str(run_file) in str(error.value)


def test_a_missing_agent_file_is_named_in_a_note(trained, tmp_path):
    results = copy_results(trained, tmp_path / "results")
    run_file = result_file(results, "dqn", min(SEEDS))
    agent_file = run_file.with_name(json.loads(run_file.read_text())[RESULT_FIELD]["file"])
    agent_file.unlink()
    write_leaderboard(results, tmp_path / "out")
    assert [p.name for p in (tmp_path / "out" / "figures").glob("*.gif")] == [GIFS["Empathic DQN (β=0.5)"]]
    markdown = (tmp_path / "out" / "LEADERBOARD.md").read_text()
    assert f"Note: DQN (coexistence_v0): agent file {agent_file}, named by result file {run_file}, is missing" in markdown


def test_runs_without_agents_give_no_section_and_no_gif(trained, tmp_path):
    """Result files made before runs kept their agents (no ``agent`` field) and runs whose method
    kept none (``null``): the pages are those of a leaderboard without the section."""
    results = copy_results(trained, tmp_path / "results")
    for k, path in enumerate(sorted((results / "runs").glob("*.json"))):
        document = json.loads(path.read_text())
        (path.parent / document[RESULT_FIELD]["file"]).unlink()
        if k % 2:
            del document[RESULT_FIELD]
        else:
            document[RESULT_FIELD] = None
        path.write_text(json.dumps(document))
    write_leaderboard(results, tmp_path / "out")
    assert not list((tmp_path / "out" / "figures").glob("*.gif"))
    assert SECTION_TITLE not in (tmp_path / "out" / "LEADERBOARD.md").read_text()
    assert SECTION_TITLE not in (tmp_path / "out" / "leaderboard.html").read_text()
    assert "image/gif" not in (tmp_path / "out" / "leaderboard.html").read_text()


def test_several_directories_each_give_their_own_agents(trained, tmp_path):
    """DQN's runs in one directory, Empathic DQN's in another: each row's agent is read from the
    directory its result file came from."""
    mine, theirs = tmp_path / "mine" / "runs", tmp_path / "theirs" / "runs"
    for folder, method in ((mine, "dqn"), (theirs, "empathic_dqn")):
        folder.mkdir(parents=True)
        for path in (trained / "runs").glob(f"coexistence_v0__{method}-*"):
            shutil.copy(path, folder / path.name)
    paths = write_leaderboard([mine.parent, theirs.parent], tmp_path / "out", labels={mine.parent: "mine:"})
    assert sorted(p.name for p in (tmp_path / "out" / "figures").glob("*.gif")) == [
        "coexistence_v0_empathic_dqn_beta_0.5_episode.gif",
        "coexistence_v0_mine_dqn_episode.gif",
    ]
    assert "figure:coexistence_v0:episode_mine_dqn" in paths
    assert "Note:" not in (tmp_path / "out" / "LEADERBOARD.md").read_text().split(f"## {SECTION_TITLE}")[1]


def test_row_slugs_are_file_safe_and_stable():
    assert row_slug("Empathic DQN (β=0.5)") == "empathic_dqn_beta_0.5"
    assert row_slug("DQN · 30,000 steps") == "dqn_30_000_steps"
    assert row_slug("mine: AUP (λ=0.01, n=5)") == "mine_aup_lamda_0.01_n_5"  # (Unicode spells λ "lamda")
    assert row_slug("Café / ../x") == "cafe_.._x"
    assert row_slug("★ ✓") == "row"
    long = row_slug("Empathic DQN " * 20)
    assert len(long) <= MAX_SLUG and long != row_slug("Empathic DQN " * 21)
    slugs = episode_slugs([("coexistence_v0", "A B"), ("coexistence_v0", "A_B"), ("sharing_v0", "A B"), ("coexistence_v0", "C")])
    assert slugs[("sharing_v0", "A B")] == "a_b" and slugs[("coexistence_v0", "C")] == "c"
    assert slugs[("coexistence_v0", "A B")].startswith("a_b-") and slugs[("coexistence_v0", "A_B")].startswith("a_b-")
    assert slugs[("coexistence_v0", "A B")] != slugs[("coexistence_v0", "A_B")]
    assert slugs == episode_slugs(list(reversed(list(slugs))))
    for (env, _), slug in slugs.items():
        assert PATH_NAME.fullmatch(episode_file_name(env, slug)) and episode_file_name(env, slug).endswith(GIF_SUFFIX)
    with pytest.raises(ValueError, match="variant"):
        episode_file_name("../x", "a")


def test_the_leaderboard_imports_no_method():
    code = "import sys, leaderboard.report; print([m for m in sys.modules if m.startswith(('baselines', 'agents'))])"
    printed = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert printed.strip() == "[]"
