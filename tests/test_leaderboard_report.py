"""Leaderboard formatting and the full ``write_leaderboard`` on synthetic result files."""

from __future__ import annotations

import csv
import io
import json
import os
import re
from pathlib import Path

import numpy as np
import pytest
from helpers_results import derive_run_id, schema_1_document, within_env, within_episodes

from empathy_zoo.metrics import INTEGER_METRICS, METRIC_DEFINITIONS, METRIC_NAMES
from empathy_zoo.provenance import package_version
from leaderboard import write_leaderboard
from leaderboard.aggregate import Score
from leaderboard.leaderboard_page import report_page
from leaderboard.page_html import to_html
from leaderboard.page_markdown import to_markdown
from leaderboard.tables import (
    CSV_COLUMNS,
    NO_INTERVAL_NOTE,
    Provenance,
    csv_text,
    format_interval,
    markdown_table,
    table_rows,
)

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
PROVENANCE = Provenance(command="empathy-zoo leaderboard out", version="0.1.0", commit="abc1234")
METHODS = {"dqn": "DQN", "empathic_dqn": "Empathic DQN (β=0.5)"}


def write_synthetic_results(
    directory: Path,
    envs: tuple[str, ...] = ("coexistence_v0", "sharing_v0"),
    seeds: tuple[int, ...] = (0, 1, 2),
    steps: int = 2000,
) -> list[Path]:
    """Write one plausible schema-1 result file per (env, method, seed) into ``directory``."""
    paths = []
    for env in envs:
        for m, (method, label) in enumerate(METHODS.items()):
            for seed in seeds:
                rng = np.random.default_rng([m, seed])
                end_steps = np.cumsum(rng.integers(20, 80, size=60))
                end_steps = end_steps[end_steps <= steps].tolist()
                n = len(end_steps)
                progress = np.linspace(0.0, 1.0, n)

                def columns(
                    k: int, n=n, m=m, progress=progress, rng=rng, env=env
                ) -> dict[str, list[float]]:  # (this iteration's)
                    base = progress if k == n else np.ones(k)
                    noise = rng.normal(0.0, 0.1, size=k)
                    values = {
                        "survival": 40 * base + m + noise,
                        "harms": 1 - base / 2 + noise,
                        "batteries": 3 * base + noise,
                        "other_batteries": 4 - base + noise,
                        "equality": 0.5 + base / 4 + noise,
                        "return": base + noise,
                        "other_return": 2 - base + noise,
                    }  # (within what an episode gives: the result-file checker refuses the rest)
                    clipped = {name: np.clip(value, 0.0, 1.0 if name == "equality" else None) for name, value in values.items()}
                    whole = {
                        name: (np.round(value) if name in INTEGER_METRICS else value).tolist() for name, value in clipped.items()
                    }
                    return within_env(env, whole)  # (a count's episodes are whole numbers, within what its environment gives)

                result = schema_1_document(
                    env,
                    method,
                    label,
                    seed,
                    steps,
                    {"settings": {"selfishness": 0.5} if method == "empathic_dqn" else {}, "env_kwargs": {}, "fixed": {}},
                    {"episode_end_step": end_steps, **within_episodes(end_steps, columns(n))},
                    [{"step": s, **columns(5)} for s in (steps // 2, steps)],
                    wall_time_s=1.0,
                    version="0.1.0",
                    commit=None,
                    created="2026-01-01T00:00:00Z",
                )
                path = directory / f"{result['run_id']}.json"
                path.parent.mkdir(parents=True, exist_ok=True)
                path.write_text(json.dumps(result), encoding="utf-8")
                paths.append(path)
    return paths


def tiny_scores() -> list[Score]:
    return [
        Score("coexistence_v0", "DQN", "dqn", "eval", "survival", 12.5, 10.0, 15.0, 3),
        Score("coexistence_v0", "DQN", "dqn", "eval", "harms", 0.5, 0.0, 1.0, 3),
        Score("coexistence_v0", "Empathic DQN (β=0.5)", "empathic_dqn", "eval", "survival", 7.0, 7.0, 7.0, 1),
        Score(
            "coexistence_v0", "Empathic DQN (β=0.5)", "empathic_dqn", "eval", "harms", float("nan"), float("nan"), float("nan"), 0
        ),
    ]


def test_format_interval() -> None:
    assert format_interval(1.0, 0.25, 1.755) == "1.00 [0.25, 1.75]"
    assert format_interval(1.0, 0.5, 2.0, digits=0) == "1 [0, 2]"
    assert format_interval(float("nan"), float("nan"), float("nan")) == "n/a"


def test_markdown_table_exact_lines() -> None:
    header, rows = table_rows(tiny_scores(), "coexistence_v0", "eval", metrics=("survival", "harms"))
    assert markdown_table(header, rows).splitlines() == [
        "| Method | Seeds | survival | harms |",
        "|:---|---:|---:|---:|",
        "| DQN | 3 | 12.50 [10.00, 15.00] | 0.50 [0.00, 1.00] |",
        "| Empathic DQN (β=0.5) | 1† | 7.00 (n=1: no interval) | n/a |",
    ]
    assert table_rows(tiny_scores(), "coexistence_v0", "train_final10")[1] == []


def test_markdown_table_escapes_pipes() -> None:
    assert markdown_table(["a|b"], [["c"]]).splitlines()[0] == "| a\\|b |"


def test_csv_exact_lines() -> None:
    lines = csv_text(tiny_scores(), PROVENANCE).splitlines()
    assert lines[0] == ",".join(CSV_COLUMNS)
    tail = "empathy-zoo leaderboard out,0.1.0,abc1234"
    assert lines[1] == f"coexistence_v0,DQN,dqn,eval,survival,12.5,10.0,15.0,3,{METRIC_DEFINITIONS['survival']},{tail}"
    assert lines[4] == (f"coexistence_v0,Empathic DQN (β=0.5),empathic_dqn,eval,harms,,,,0,{METRIC_DEFINITIONS['harms']},{tail}")
    assert len(lines) == 5


def test_markdown_and_html_pages_carry_definitions_provenance_and_single_seed_note() -> None:
    page = to_markdown(report_page(tiny_scores(), PROVENANCE, {("coexistence_v0", "survival"): ("figures/x.png", None)}))
    html = to_html(report_page(tiny_scores(), Provenance("cmd <&>", "0.1.0", None), {("coexistence_v0", "harms"): ("", b"PNG")}))
    for text in (page, html):
        assert "single seed" in text and "Final greedy evaluation" in text
        assert all(METRIC_DEFINITIONS[metric].split("·")[0] in text for metric in METRIC_NAMES)
    assert "`empathy-zoo leaderboard out`" in page and "commit `abc1234`" in page
    assert "![coexistence_v0: survival vs training steps](figures/x.png)" in page
    assert "<code>cmd &lt;&amp;&gt;</code>" in html and "commit <code>unknown</code>" in html
    assert 'src="data:image/png;base64,UE5H"' in html


def test_write_leaderboard_writes_every_file(tmp_path: Path) -> None:
    write_synthetic_results(tmp_path / "sweep" / "runs")
    paths = write_leaderboard(tmp_path / "sweep", command="empathy-zoo leaderboard sweep")
    out = tmp_path / "sweep"
    assert paths["markdown"] == out / "LEADERBOARD.md"
    assert paths["csv"] == out / "leaderboard.csv" and paths["html"] == out / "leaderboard.html"
    figures = {key: path for key, path in paths.items() if key.startswith("figure:")}
    assert sorted(figures) == [
        "figure:coexistence_v0:harms",
        "figure:coexistence_v0:profiles",
        "figure:coexistence_v0:survival",
        "figure:coexistence_v0:tradeoff",
        "figure:sharing_v0:batteries",
        "figure:sharing_v0:equality",
        "figure:sharing_v0:profiles",
        "figure:sharing_v0:tradeoff",
    ]
    for path in paths.values():
        assert path.is_file() and path.stat().st_size > 0
    for path in figures.values():
        assert path.parent == out / "figures" and path.read_bytes().startswith(PNG_SIGNATURE)
    markdown = paths["markdown"].read_text(encoding="utf-8")
    assert "`empathy-zoo leaderboard sweep`" in markdown and f"empathy-zoo {package_version()}" in markdown
    for path in figures.values():
        assert f"]({path.relative_to(out).as_posix()})" in markdown
    tables = markdown.split("## Performance profiles and optimality gap", 1)[0]
    assert tables.count("| DQN | 3 |") == 4 and "single seed" not in markdown
    rows = list(csv.DictReader(io.StringIO(paths["csv"].read_text(encoding="utf-8"))))
    assert len(rows) == 2 * 2 * 2 * len(METRIC_NAMES)
    assert {row["n_seeds"] for row in rows} == {"3"} and all(row["command"] == "empathy-zoo leaderboard sweep" for row in rows)
    for row in rows:
        assert float(row["ci_low"]) <= float(row["mean"]) <= float(row["ci_high"])
    html = paths["html"].read_text(encoding="utf-8")
    assert html.count('<img alt="') == len(figures) and "<style>" in html
    assert (
        markdown.count("### Task against side effect") == 2
        and html.count("<h3>Task against side effect</h3>") == 2
        and "empathy-zoo leaderboard sweep" in html
    )
    assert not [p.name for p in out.rglob(".*")], "temporary files left behind"


def test_write_leaderboard_is_deterministic_and_writes_to_out_dir(tmp_path: Path) -> None:
    write_synthetic_results(tmp_path / "runs", envs=("sharing_v0",), seeds=(0, 1))
    first = write_leaderboard(tmp_path / "runs", tmp_path / "a", command="x")
    second = write_leaderboard(tmp_path / "runs", tmp_path / "b", command="x")
    for key in ("markdown", "csv", "html", "figure:sharing_v0:equality"):
        assert first[key].read_bytes() == second[key].read_bytes()
    assert not (tmp_path / "runs" / "LEADERBOARD.md").exists()


def test_write_leaderboard_single_seed_note(tmp_path: Path) -> None:
    write_synthetic_results(tmp_path, envs=("coexistence_v0",), seeds=(4,))
    markdown = write_leaderboard(tmp_path)["markdown"].read_text(encoding="utf-8")
    assert "| DQN | 1† | " in markdown and "† a single seed: no spread to measure." in markdown
    assert " (n=1: no interval) |" in markdown and NO_INTERVAL_NOTE in markdown
    assert "leaderboard.write_leaderboard(" in markdown


def test_write_leaderboard_rejects_an_empty_directory(tmp_path: Path) -> None:
    (tmp_path / ".partial.json.tmp").write_text("{", encoding="utf-8")
    with pytest.raises(ValueError, match="no result files"):
        write_leaderboard(tmp_path)
    assert not (tmp_path / "LEADERBOARD.md").exists()


def test_write_leaderboard_names_a_corrupted_file(tmp_path: Path) -> None:
    write_synthetic_results(tmp_path, envs=("coexistence_v0",), seeds=(0,))
    (tmp_path / "zz_bad.json").write_bytes(b'{"schema": 1,')
    with pytest.raises(ValueError, match=re.escape("zz_bad.json")):
        write_leaderboard(tmp_path)


def test_a_failing_write_leaves_the_old_files_intact(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    write_synthetic_results(tmp_path / "runs", envs=("coexistence_v0",), seeds=(0, 1))
    paths = write_leaderboard(tmp_path, command="first")
    before = {key: path.read_bytes() for key, path in paths.items()}

    import leaderboard.report as report

    real_fsync, real_check, checking = os.fsync, report.check_output_dir, []

    def check_output_dir(*args: object) -> Path:  # the up-front directory check still passes
        checking.append(True)
        try:
            return real_check(*args)
        finally:
            checking.pop()

    def failing_fsync(fd: int) -> None:
        if checking:
            return real_fsync(fd)
        raise OSError("disk full")

    monkeypatch.setattr(report, "check_output_dir", check_output_dir)
    monkeypatch.setattr(os, "fsync", failing_fsync)
    with pytest.raises(OSError, match="disk full"):
        write_leaderboard(tmp_path, command="second")
    monkeypatch.undo()
    assert {key: path.read_bytes() for key, path in paths.items()} == before
    assert not [p.name for p in tmp_path.rglob(".*")], "temporary files left behind"


def test_each_environment_s_tables_show_its_own_metrics_a_variant_its_environment_s(tmp_path: Path) -> None:
    paths = write_synthetic_results(tmp_path / "sweep" / "runs")
    variant = json.loads(paths[-1].read_text(encoding="utf-8"))  # a sharing_v0 run, as a variant
    variant.update(variant="sharing_centre", method_label="Centre")
    run_id = derive_run_id(variant)["run_id"]
    (tmp_path / "sweep" / "runs" / f"{run_id}.json").write_text(json.dumps(variant), encoding="utf-8")
    markdown = write_leaderboard(tmp_path / "sweep", command="c")["markdown"].read_text(encoding="utf-8")
    headers = {}
    for section in markdown.split("\n## ")[1:]:
        env = section.split("\n", 1)[0]
        tables = [line for line in section.splitlines() if line.startswith("| Method")]
        if tables:
            headers[env] = tables[0]
    assert headers["coexistence_v0"] == "| Method | Seeds | survival | harms | other_return |"
    assert (
        headers["sharing_v0"]
        == headers["sharing_centre"]
        == ("| Method | Seeds | batteries | other_batteries | equality | return | other_return |")
    )
    csv_metrics = {row.split(",")[4] for row in (tmp_path / "sweep" / "leaderboard.csv").read_text().splitlines()[1:]}
    assert csv_metrics == set(METRIC_NAMES)  # the CSV keeps every metric
