"""An eighth probe's findings (issue 33, "files from elsewhere are inert"): text read from files
(labels, errors naming them, scenario set descriptions, commits and versions, separation tables'
names and reasons) reaches every Markdown page escaped, so it opens no HTML, link or code span;
an exact model refuses an argument it does not take and an episode past its bound in one line."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from empathy_zoo.cli import main
from empathy_zoo.markdown_escape import code_span, markdown_text

QUICK = Path(__file__).resolve().parents[1] / "docs" / "results" / "quick"
RUN = "coexistence_v0__dqn_harm_penalty-684a7c7f__s0"
HOSTILE = "<img src=x onerror=alert(1)> [c](javascript:alert(2)) *e* `t` | &amp;"


def _raw_html(text: str) -> bool:
    """Whether ``text`` holds an unescaped ``<img`` or ``<script`` (one Markdown would render)."""
    return any(f"{tag}" in text.replace(f"\\{tag}", "") for tag in ("<img", "<script"))


def test_data_escaped_for_markdown_opens_nothing() -> None:
    assert not _raw_html(markdown_text(HOSTILE)) and "](" not in markdown_text(HOSTILE).replace("\\](", "")
    assert code_span("abc123") == "`abc123`"
    assert not code_span("abc` <img src=x> `").startswith("`") and not _raw_html(code_span("abc` <img src=x> `"))
    assert "\n" not in code_span("a\nb") and "\n" not in markdown_text("a\nb")


def _copy_run(tmp_path: Path) -> Path:
    runs = tmp_path / "runs"
    runs.mkdir()
    for suffix in (".json", ".agent.pt"):
        shutil.copy(QUICK / "runs" / f"{RUN}{suffix}", runs / f"{RUN}{suffix}")
    return runs / f"{RUN}.json"


def test_a_hostile_commit_version_and_missing_agents_note_stay_escaped_on_the_page(tmp_path: Path) -> None:
    from leaderboard import write_leaderboard

    result = _copy_run(tmp_path)
    document = json.loads(result.read_text())
    document.update(commit="abc` <img src=x onerror=alert(1)> `", version="<script>alert(2)</script>")
    result.write_text(json.dumps(document))
    (result.parent / f"{RUN}.agent.pt").unlink()  # (the page notes it, naming the run's row)
    notes: list[str] = []
    written = write_leaderboard([tmp_path], tmp_path / "out", labels={tmp_path: "p` <script>x</script> `"}, on_note=notes.append)
    page = written["markdown"].read_text()
    assert "Note:" in page and not _raw_html(page), [line for line in page.splitlines() if _raw_html(line)]


def test_a_hostile_scenario_set_description_stays_escaped_on_the_page(tmp_path: Path) -> None:
    from leaderboard import write_leaderboard

    _copy_run(tmp_path)
    source = QUICK / "evaluations" / "coexistence_v0" / f"{RUN}.json"
    evaluation = json.loads(source.read_text())
    evaluation["scenario_set"]["description"] = "<script>alert(2)</script> [x](javascript:y)"
    target = tmp_path / "evaluations" / "coexistence_v0" / f"{RUN}.json"
    target.parent.mkdir(parents=True)
    target.write_text(json.dumps(evaluation))
    page = write_leaderboard(tmp_path, tmp_path / "out")["markdown"].read_text()
    assert "alert(2)" in page and not _raw_html(page)


def test_a_hostile_separation_table_stays_escaped_in_both_readers(tmp_path: Path, capsys) -> None:
    table = json.loads((QUICK.parent / "separation" / "coexistence_v0.json").read_text())
    table["omitted"].append(
        {"method": "x` <img src=y onerror=alert(4)> `", "reason": "<script>alert(2)</script> | [a](javascript:b)"}
    )
    tables = tmp_path / "tables"
    tables.mkdir()
    (tables / "coexistence_v0.json").write_text(json.dumps(table))
    assert main(["analyse", "discrimination", str(tables), "--out", str(tmp_path / "d.md")]) == 0
    page = (tmp_path / "d.md").read_text()
    assert "alert(2)" in page and "alert(4)" in page and not _raw_html(page)


@pytest.mark.parametrize(
    "tool, argument, named",
    [
        ("exact", "bogus=1", "takes no argument(s) ['bogus']"),
        ("exact", "max_cycles=1000000000", "is beyond 10,000 (MAX_REFERENCE_CYCLES)"),
        ("separation", "bogus=1", "takes no argument(s) ['bogus']"),
        ("separation", "max_cycles=1000000000", "is beyond 10,000 (MAX_REFERENCE_CYCLES)"),
    ],
)
def test_an_exact_model_refuses_what_it_cannot_model_in_one_line(
    tmp_path: Path, capsys, tool: str, argument: str, named: str
) -> None:
    assert main(["analyse", tool, "coexistence_v0", argument, *(["--out", str(tmp_path)] if tool == "separation" else [])]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and named in err and "Traceback" not in err
    assert not list(tmp_path.iterdir())
