"""Trained runs are read against a separation table only in the world the table models
(``leaderboard.separation_reading.in_table_world``): ``analyse discrimination --results`` and
``analyse separation-reading`` leave a run of another world (another environment argument,
``max_cycles`` included, or partner) out of the table's cells and name it in their notes; the
shipped tables still read the shipped runs."""

from __future__ import annotations

from pathlib import Path

import pytest
from helpers_results import derive_run_id, hand_made_result, record, synthetic_document, synthetic_result

from empathy_zoo.cli import main

ROOT = Path(__file__).resolve().parents[1]
QUICK = ROOT / "docs" / "results" / "quick"
SHIPPED_TABLES = ROOT / "docs" / "results" / "separation"
SMALL = {"size": 5, "view": 3, "max_cycles": 5}
"""The smallest quick Coexistence world: 625 states, 5 steps (the default: 7 × 7, view 5, 500 steps)."""
OTHER_WORLD = "coexistence_v0 at size 7 not 5 and view 5 not 3 and max_cycles 500 not 5"
"""How the notes name a default-world Coexistence run read against the small world's table."""


@pytest.fixture(scope="module")
def small_tables(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder holding the exact separation table of Coexistence in the :data:`SMALL` world, made
    by the library call ``analyse separation`` makes it with (one β, the two ε the readers read, and
    γ = 0.5, so that value iteration ends in about a second rather than 30)."""
    from baselines.separation import separation_table
    from baselines.separation_render import file_name, to_json
    from empathy_zoo.exact_solver import tabular_model

    folder = tmp_path_factory.mktemp("small_tables")
    table = separation_table(tabular_model("coexistence_v0", **SMALL), selfishness=(0.5,), epsilons=(0.0, 0.01), gamma=0.5)
    (folder / f"{file_name('coexistence_v0', SMALL)}.json").write_text(to_json(table))
    return folder


def _small_table(folder: Path) -> dict:
    from baselines.separation_file import read_separation_table

    return read_separation_table(folder / "coexistence_v0.json")


def _small_world_run(method: str, seed: int, harms: list[int], **env_kwargs: int):
    """A run of ``method`` trained in :data:`SMALL` (``env_kwargs`` over it), its final greedy
    evaluation's harms per episode as given."""
    settings = {"selfishness": 0.5} if method == "empathic_dqn" else None
    train = {"episode_end_step": [5, 10]}
    evaluation = [{"step": 10, "harms": harms}]
    return hand_made_result(
        "coexistence_v0", method, seed, train, evaluation, settings=settings, env_kwargs={**SMALL, **env_kwargs}
    )


def test_default_world_runs_are_not_read_against_a_smaller_worlds_table_by_either_tool(
    small_tables: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The probe's case: the quick profile's runs (7 × 7, view 5, 500 steps) against a 5 × 5,
    5-step table. The matrix has no cell left and refuses, naming them; the reading reads none
    of them (0 seeds, not judged) and names them."""
    out = tmp_path / "D.md"
    argv = ["analyse", "discrimination", str(small_tables), "--results", str(QUICK), "--out", str(out)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "make no cell" in err and "runs read: none" in err, err
    assert f"15 runs trained in another world than the task's table models ({OTHER_WORLD}): not read" in err, err
    assert not out.exists()
    assert main(["analyse", "separation-reading", str(QUICK), "--tables", str(small_tables)]) == 0
    page = capsys.readouterr().out
    assert "| `dqn_harm_penalty` | " in page and "| 0 (0) | — | no runs | not judged |" in page
    assert "| 3 (" not in page  # (no seed of the quick runs is read)
    assert "Separates in trained runs: **not judged**" in page
    assert f"* 15 runs trained in another world than the task's table models ({OTHER_WORLD}): not read\n" in page


def test_runs_of_the_tables_world_are_read_and_the_others_named(small_tables: Path) -> None:
    """Runs trained in the table's world make its cells and predictions; beside them, runs of the
    default world are named, never pooled into the cells."""
    from leaderboard.separation_reading import not_read_notes, read_runs, selfish_methods
    from leaderboard.trained_discrimination import method_harms, trained_cells

    table = _small_table(small_tables)
    tables = {"coexistence_v0": table}
    mine = [_small_world_run("dqn", seed, [1, 1]) for seed in range(3)]
    mine += [_small_world_run("dqn_harm_penalty", seed, [0, 0]) for seed in range(3)]
    default = [synthetic_result("coexistence_v0", "dqn_harm_penalty", 1.0, seed, harms=1.0) for seed in range(3, 5)]
    runs = [*mine, *default]
    selfish = selfish_methods(tables)
    harms, shared = method_harms(runs, selfish, tables)
    assert not shared
    assert harms[("coexistence_v0", "dqn")] == [1.0, 1.0, 1.0]
    assert harms[("coexistence_v0", "dqn_harm_penalty")] == [0.0, 0.0, 0.0]  # (the default world's seeds 3, 4 not pooled)
    cells = trained_cells(["coexistence_v0"], ["dqn", "dqn_harm_penalty"], harms, {"coexistence_v0": True})
    assert cells["coexistence_v0", "dqn", "dqn_harm_penalty"].seeds == (3, 3)
    methods = [str(row["method"]) for row in table["rows"]]
    notes = not_read_notes(runs, selfish, ["coexistence_v0"], methods, tables)
    assert notes == [f"2 runs trained in another world than the task's table models ({OTHER_WORLD}): not read"]
    readings = {r.prediction.method: r for r in read_runs(tables, runs)}
    assert (readings["dqn_harm_penalty"].seeds, readings["dqn_harm_penalty"].dqn_seeds) == (3, 3)


def test_a_partner_and_every_argument_are_part_of_the_world() -> None:
    """The one rule (``in_table_world``): the table's environment, every argument with the defaults
    filled in on both sides (an argument set to its default is the default), ``max_cycles`` and
    the world's default partners."""
    from leaderboard.separation_reading import in_table_world, why_not_read, world_difference

    small = {"env": "coexistence_v0", "arguments": [[name, value] for name, value in sorted(SMALL.items())], "max_cycles": 5}
    default = {"env": "coexistence_v0", "arguments": [], "max_cycles": 500}
    tables, shipped_like = {"coexistence_v0": small}, {"coexistence_v0": default}
    run = _small_world_run("dqn", 0, [0, 0])
    assert in_table_world(run, tables) and not in_table_world(run, shipped_like) and not in_table_world(run)
    longer = _small_world_run("dqn", 1, [0, 0], max_cycles=6)
    assert not in_table_world(longer, tables) and why_not_read(longer, {}, tables) == "world"
    assert world_difference(longer, tables) == "coexistence_v0 at max_cycles 6 not 5"
    spelled_out = _small_world_run("dqn", 2, [0, 0], rules="paper", num_cats=1)  # (defaults given: the same world)
    assert in_table_world(spelled_out, tables)
    stays = synthetic_result("coexistence_v0", "dqn", 1.0, 3, fixed={"cat_0": "stay"})
    assert not in_table_world(stays, shipped_like) and why_not_read(stays, {}, shipped_like) == "world"
    assert world_difference(stays, shipped_like) == "coexistence_v0 at cat_0 stay not random_walk"
    assert in_table_world(synthetic_result("coexistence_v0", "dqn", 1.0, 4), shipped_like)
    sharing = {"sharing_v0": {"env": "sharing_v0", "arguments": [["size", 5], ["view", 3]], "max_cycles": 500}}
    assert in_table_world(synthetic_result("sharing_v0", "dqn", 1.0, 5), sharing)  # (no harms: its default world is read)
    document = synthetic_document("sharing_v0", "dqn", 1.0, 6)
    document["config"]["env_kwargs"] = {"start": "centre"}
    centre = record(derive_run_id(document))
    assert world_difference(centre, sharing) == "sharing_v0 at start centre not random against its default world"


def test_the_shipped_tables_read_every_shipped_run_of_a_tasks_own_world() -> None:
    """Every run of the shipped results of a task's own variant is of the world its shipped table is
    read in: the fix leaves out none of them (Sharing's smaller table stands for its default world,
    whose runs are never read for harms)."""
    from baselines.discrimination import load_tables
    from empathy_zoo.training.heldout import results_of
    from leaderboard.separation_reading import in_table_world

    tables = load_tables(SHIPPED_TABLES)
    runs = [run for name in ("methods", "scenarios") for _, run in results_of(ROOT / "docs" / "results" / name)]
    own = [run for run in runs if (run.variant or run.env) == run.env]
    assert own and all(in_table_world(run, tables) for run in own)
    assert {run.env for run in own} <= set(tables)


def test_a_table_recording_no_world_models_the_default_one() -> None:
    """A table that records no ``env``, ``arguments`` or ``max_cycles`` (made by hand) is of its task's
    default world, as before: a default run is read, a small-world run is not."""
    from leaderboard.separation_reading import in_table_world

    bare = {"coexistence_v0": {"rows": [], "outcomes": [], "pairs": []}}
    assert in_table_world(synthetic_result("coexistence_v0", "dqn", 1.0, 0), bare)
    assert not in_table_world(_small_world_run("dqn", 0, [0, 0]), bare)
