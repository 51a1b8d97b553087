"""How the leaderboard shows its rows: a DQN reference row is called DQN (result files untouched,
two reference rows kept apart), a method keeps its colour from one leaderboard to the next, and a
mean over fewer than 3 seeds is printed without an interval, saying so."""

from __future__ import annotations

import dataclasses
import io
import json
from pathlib import Path

import numpy as np
import pytest
from helpers_results import synthetic_document, synthetic_result
from PIL import Image

from empathy_zoo.atomic import write_json_atomic
from leaderboard import write_leaderboard
from leaderboard.aggregate import MIN_INTERVAL_SEEDS, Curve
from leaderboard.colours import DQN_COLOURS, PALETTE, _slot, label_colours
from leaderboard.plots import render_curves_png, seeds_text
from leaderboard.row_names import dqn_row_names
from leaderboard.tables import NO_INTERVAL_NOTE, format_mean

ENV = "coexistence_v0"


def write_runs(directory: Path, runs: list[tuple[str, float, str | None]], seeds: range = range(3)) -> Path:
    """Result files of ``(method, β, label)`` rows (label ``None``: the synthetic ``"<method> <β>"``)."""
    for method, beta, label in runs:
        for seed in seeds:
            result = synthetic_document(ENV, method, beta, seed, harms=0.5 if beta < 1 else 1.0, survival=400.0)
            if label is not None:
                result["method_label"] = label
            write_json_atomic(directory / "runs" / f"{result['run_id']}.json", result)
    return directory


def rows(markdown: str, heading: str = "Final greedy evaluation") -> list[str]:
    section = markdown.split(f"### {heading}\n", 1)[1].split("\n### ", 1)[0]
    return [
        line.split(" | ")[0][2:] for line in section.splitlines() if line.startswith("| ") and not line.startswith("| Method")
    ]


# ---------------------------------------------------------------------------- DQN is called DQN
def test_empathic_dqn_at_beta_1_is_shown_as_dqn_and_its_files_keep_their_label(tmp_path: Path) -> None:
    directory = write_runs(tmp_path, [("empathic_dqn", 1.0, "Empathic DQN (β=1)"), ("empathic_dqn", 0.5, "Empathic DQN (β=0.5)")])
    before = {path.name: path.read_bytes() for path in (directory / "runs").glob("*.json")}
    paths = write_leaderboard(directory)
    markdown = paths["markdown"].read_text(encoding="utf-8")
    html = paths["html"].read_text(encoding="utf-8")
    assert rows(markdown) == ["DQN", "Empathic DQN (β=0.5)"]
    assert "| Empathic DQN (β=1) |" not in markdown and "<td>Empathic DQN (β=1)</td>" not in html
    for page in (markdown, html):
        assert "Rows named DQN are the DQN reference" in page and "DQN is labelled “Empathic DQN (β=1)”" in page
    assert "DQN (3 seeds)" not in markdown  # (one DQN row: the tables need not name it)
    csv_labels = {line.split(",")[1] for line in paths["csv"].read_text(encoding="utf-8").splitlines()[1:]}
    assert csv_labels == {"DQN", "Empathic DQN (β=0.5)"}
    after = {path.name: path.read_bytes() for path in (directory / "runs").glob("*.json")}
    assert after == before  # nothing written to a result file
    assert {json.loads(data)["method_label"] for data in after.values()} == {"Empathic DQN (β=1)", "Empathic DQN (β=0.5)"}


def test_a_dqn_run_and_an_empathic_dqn_beta_1_run_are_both_dqn_and_kept_apart(tmp_path: Path) -> None:
    directory = write_runs(
        tmp_path,
        [("dqn", 1.0, "DQN"), ("empathic_dqn", 1.0, "Empathic DQN (β=1)"), ("empathic_dqn", 0.5, "Empathic DQN (β=0.5)")],
    )
    markdown = write_leaderboard(directory)["markdown"].read_text(encoding="utf-8")
    assert rows(markdown) == ["DQN", "DQN, as Empathic DQN (β=1)", "Empathic DQN (β=0.5)"]
    compared = rows(markdown, "P(improves on DQN): Final greedy evaluation")
    assert compared == ["DQN", "DQN, as Empathic DQN (β=1)", "Empathic DQN (β=0.5)", "Empathic DQN (β=0.5)"]  # against both
    assert "DQN, as Empathic DQN (β=1) is labelled “Empathic DQN (β=1)”" in markdown


def test_a_name_another_row_has_is_never_given() -> None:
    runs = [synthetic_result(ENV, "empathic_dqn", 1.0, 0), synthetic_result(ENV, "dqn_harm_penalty", 1.0, 0)]
    runs[1] = dataclasses.replace(runs[1], method_label="DQN")  # a user's label on a row that is no reference
    assert dqn_row_names(runs) == {}
    runs[1] = dataclasses.replace(runs[1], method_label="penalty")
    assert dqn_row_names(runs) == {(ENV, "empathic_dqn 1.0"): "DQN"}


# ---------------------------------------------------------------------------- stable colours
def test_a_label_has_the_same_colour_in_leaderboards_of_other_methods() -> None:
    one = label_colours(["DQN", "Empathic DQN (β=0.5)", "DQN + harm penalty (−100)"], {"DQN"})
    other = label_colours(
        ["Empathic DQN in view (β=0.5)", "DQN × equality", "Empathic DQN (β=0.5)", "DQN", "DQN + inequity aversion"], {"DQN"}
    )
    assert one["DQN"] == other["DQN"] == DQN_COLOURS[0]
    assert one["Empathic DQN (β=0.5)"] == other["Empathic DQN (β=0.5)"] == PALETTE[_slot("Empathic DQN (β=0.5)")]
    assert len(set(other.values())) == len(other)


def test_labels_that_hash_to_one_colour_are_told_apart_the_same_way_every_time() -> None:
    by_slot: dict[int, list[str]] = {}
    for i in range(100):
        by_slot.setdefault(_slot(f"method {i}"), []).append(f"method {i}")
    first, second = next(labels for labels in by_slot.values() if len(labels) >= 2)[:2]
    colours = label_colours([second, first])
    assert colours == label_colours([first, second])  # whatever order the figure draws them in
    assert colours[first] == PALETTE[_slot(first)] and colours[second] != colours[first]


def _png_colours(png: bytes) -> set[tuple[int, int, int]]:
    pixels = np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).reshape(-1, 3)
    return {tuple(int(v) for v in pixel) for pixel in np.unique(pixels, axis=0)}


def _curve(label: str, n_seeds: int = 3) -> Curve:
    steps = np.linspace(0, 1000, 20)
    mean = np.linspace(0.0, 1.0, 20) + len(label) % 5
    return Curve(ENV, label, "harms", steps, mean, mean - 0.2, mean + 0.2, n_seeds)


def _rgb(colour: str) -> tuple[int, int, int]:
    return tuple(int(colour[i : i + 2], 16) for i in (1, 3, 5))  # type: ignore[return-value]


def test_every_learning_curve_figure_draws_a_label_in_its_colour() -> None:
    label = "Empathic DQN (β=0.5)"
    first = render_curves_png([_curve("DQN"), _curve(label)], title="a", ylabel="y", dqn_labels={"DQN"})
    second = render_curves_png([_curve(label), _curve("DQN × equality")], title="b", ylabel="y")
    colour = _rgb(label_colours([label])[label])
    assert colour in _png_colours(first) and colour in _png_colours(second)


# ---------------------------------------------------------------------------- no interval below 3 seeds
def test_a_mean_over_two_seeds_is_printed_without_an_interval() -> None:
    assert MIN_INTERVAL_SEEDS == 3
    assert format_mean(0.5, -3.0, 4.0, 2) == "0.50 (n=2: no interval)"
    assert format_mean(0.5, 0.25, 0.75, 3) == "0.50 [0.25, 0.75]"
    assert seeds_text(2) == "n=2: no interval" and seeds_text(3) == "n=3"


@pytest.mark.parametrize("seeds, said", [(range(2), True), (range(3), False)])
def test_the_pages_say_when_a_row_has_too_few_seeds_for_an_interval(tmp_path: Path, seeds: range, said: bool) -> None:
    directory = write_runs(tmp_path, [("empathic_dqn", 1.0, None), ("empathic_dqn", 0.5, None)], seeds)
    paths = write_leaderboard(directory)
    for page in (paths["markdown"].read_text(encoding="utf-8"), paths["html"].read_text(encoding="utf-8")):
        assert ("(n=2: no interval)" in page) is said and (NO_INTERVAL_NOTE in page) is said
