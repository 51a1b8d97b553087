"""The ninth probe's findings, each fixed at its cause.

* A separation table's work is bounded: at most 1,000 rows, each table's pairs read once per page
  (not once per pair of methods), and at most 200 methods in the matrix.
* A refusal of a table names its task, and its free text (``env``, reasons, ``identical_to``,
  ``by_construction``) is one line of printable text or refused.
* ``analyse verdict-changes`` shows the names it copies from a page as text: no HTML, link, code
  or terminal escape of the page's reaches its output.
* A scenario's reason and a method's label reach the leaderboard's Markdown as text.
* ``analyse exact`` and ``analyse separation`` read a signed or long integer as an integer, so the
  environment names its bound; an integer past 100 digits is refused in one line.
* ``analyse tuning-summary`` refuses an empty ``--figure`` or ``DIR``.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import pytest
from helpers_heldout import scenario_set, synthetic_run, write_synthetic

from baselines import discrimination
from baselines.separation_file import MAX_ROWS, SeparationTableError, read_separation_table
from empathy_zoo import exact_solver
from empathy_zoo.cli import main as cli
from leaderboard import tuning_summary
from leaderboard.heldout import heldout_section
from leaderboard.page_markdown import section_markdown
from leaderboard.verdict_changes import changes_markdown

ESC, BEL = "\x1b", "\x07"
HOSTILE = f"<img src=x onerror=alert(1)> [x](javascript:alert(1)) ![i](http://e/i.png) `c` *e* _u_ {ESC}[2J{BEL}"


def table(rows: int = 3, methods: int = 3) -> dict[str, Any]:
    """A valid separation table: ``rows`` rows of ``methods`` methods (β 0.5 each), every pair at ε 0.01."""
    names = [f"r{i}" for i in range(rows)]
    return {
        "rows": [{"name": n, "method": f"m{i % methods}", "selfishness": 0.5} for i, n in enumerate(names)],
        "outcomes": [{"row": n, "epsilon": 0.01, "harms": 0.1, "robot_harmed": 0.0} for n in names],
        "pairs": [
            {"first": a, "second": b, "epsilon": 0.01, "differ": True, "differing_states": 3, "harms_difference": 0.0}
            | {"by_construction": ""}
            for i, a in enumerate(names)
            for b in names[i + 1 :]
        ],
    }


def live(token: str, text: str) -> bool:
    """Whether ``token`` stands in ``text`` not escaped (no backslash before it)."""
    return re.search(r"(?<!\\)" + re.escape(token), text) is not None


def written(tmp_path: Path, document: dict[str, Any], name: str = "toy_v0") -> Path:
    path = tmp_path / f"{name}.json"
    path.write_text(json.dumps(document))
    return path


# ---------------------------------------------------------------------------- 1. bounded work
def test_a_table_of_more_rows_than_the_bound_is_refused_naming_it(tmp_path) -> None:
    document = table(rows=3)
    document["rows"] += [{"name": f"x{i}", "method": "m0"} for i in range(MAX_ROWS)]
    with pytest.raises(SeparationTableError, match=rf"field rows: expected an array of at most {MAX_ROWS:,} objects"):
        read_separation_table(written(tmp_path, document))


class CountedList(list):  # type: ignore[type-arg]
    """A list that counts how often it is walked."""

    walks = 0

    def __iter__(self):  # type: ignore[no-untyped-def]
        CountedList.walks += 1
        return super().__iter__()


def test_the_page_walks_each_tables_pairs_a_fixed_number_of_times_whatever_the_methods() -> None:
    counted = {}
    for methods in (3, 8):
        document = table(rows=methods, methods=methods)
        document["pairs"] = CountedList(document["pairs"])
        CountedList.walks = 0
        page = discrimination.discrimination_markdown({"toy_v0": document}, 0.01, "cmd")
        counted[methods] = CountedList.walks
        assert page.count("separated (3 states") == methods * (methods - 1) // 2
    assert counted[3] == counted[8] <= 2


def test_a_matrix_of_more_methods_than_its_bound_is_refused() -> None:
    many = discrimination.MAX_METHODS + 1
    with pytest.raises(ValueError, match=rf"{many:,} methods; the matrix holds at most {discrimination.MAX_METHODS}"):
        discrimination.discrimination_markdown({"toy_v0": table(rows=many, methods=many)}, 0.01, "cmd")


def test_beta_rows_of_one_method_joined_by_a_long_chain_make_one_group() -> None:
    document = table(rows=400, methods=1)
    for pair in document["pairs"]:
        pair["differ"] = int(pair["second"][1:]) - int(pair["first"][1:]) != 1  # (only neighbours share an optimum)
    assert discrimination.beta_groups(document, "m0", 0.01) == 1


# ---------------------------------------------------------------------------- 4. names and free text
def test_a_missing_pair_is_refused_naming_the_task(tmp_path, capsys) -> None:
    document = table()
    document["pairs"] = document["pairs"][1:]
    written(tmp_path, document, "mytask_v0")
    assert discrimination.main([str(tmp_path), "--out", str(tmp_path / "D.md")]) == 2
    error = capsys.readouterr().err
    assert "in the table of 'mytask_v0'" in error and "None" not in error
    assert f"separation table {tmp_path / 'mytask_v0.json'}: no pair" in error
    assert not (tmp_path / "D.md").exists()


@pytest.mark.parametrize(
    ("field", "where"),
    [
        (("env",), "env"),
        (("rows", 1, "reason"), r"rows\[1\]\.reason"),
        (("rows", 1, "identical_to"), r"rows\[1\]\.identical_to"),
        (("pairs", 0, "by_construction"), r"pairs\[0\]\.by_construction"),
    ],
)
@pytest.mark.parametrize("text", [f"toy{ESC}[31m", "two\nlines", f"bell{BEL}", "rtl\u202e"])
def test_free_text_in_a_table_is_one_printable_line(tmp_path, field, where, text) -> None:
    document = table()
    target: Any = document
    for key in field[:-1]:
        target = target[key]
    target[field[-1]] = text
    expected = "(one line of printable text|a non-empty one-line string)"
    with pytest.raises(SeparationTableError, match=rf"toy_v0\.json: field {where}: expected {expected}"):
        read_separation_table(written(tmp_path, document))


def test_an_empty_reason_or_construction_stays_allowed(tmp_path) -> None:
    document = table()
    document["rows"][1]["reason"] = ""
    assert read_separation_table(written(tmp_path, document))["pairs"][0]["by_construction"] == ""


# ---------------------------------------------------------------------------- 2. verdict-changes
def page(method: str, mark: str) -> str:
    return "\n".join(
        [
            "## coexistence_v0",
            "### P(improves on DQN): Final greedy evaluation",
            "| Method | Seeds | harms |",
            "|:---|---:|---:|",
            f"| {method} | 10 | {mark} 0.90 [0.70, 1.00] |",
        ]
    )


def test_verdict_changes_shows_a_pages_names_as_text() -> None:
    out = changes_markdown(page(HOSTILE, ""), page(HOSTILE, "▲"))
    assert "1 marks differ" in out
    for token in ("<img", "](javascript", "[i](", "`c`", "*e*", "_u_", ESC, BEL):
        assert not live(token, out)
    assert "\\\\x1b" in out and "\\\\x07" in out  # (each shown as its code)


def test_verdict_changes_keeps_a_genuine_name_as_it_was() -> None:
    out = changes_markdown(page("Empathic DQN (β=0.5)", ""), page("Empathic DQN (β=0.5)", "▼"))
    assert "| coexistence_v0 | Final greedy evaluation | Empathic DQN (β=0.5) | harms | – | ▼ | new mark |" in out


# ---------------------------------------------------------------------------- 3. reasons on the page
def test_a_scenarios_reason_reaches_the_leaderboard_as_text(tmp_path) -> None:
    hostile = "Keeps away [see](javascript:alert(1)) ![i](http://e/i.png) `code` *loud* _u_."
    definition = scenario_set("coexistence_v0", {"kept": {"cat_0": "stay"}})
    definition["scenarios"][0]["reason"] = hostile
    pairs = []
    for seed in range(3):
        for method, beta in (("dqn", 1.0), ("empathic_dqn", 0.5)):
            run = synthetic_run("coexistence_v0", method, beta, seed)
            pairs.append((run, {s: {"harms": 0.1, "survival": 300.0} for s in ("trained_with", "kept")}))
    write_synthetic(tmp_path, pairs, definition, {"cat_0": "random_walk"})
    found = heldout_section(tmp_path, [run for run, _ in pairs], tmp_path)
    assert found is not None
    text = section_markdown(found.section)
    (line,) = [line for line in text.splitlines() if line.startswith("| kept |")]
    for token in ("[see](", "[i](", "`code`", "*loud*", "_u_"):
        assert not live(token, line)
    assert "\\[see\\]" in line and "\\`code\\`" in line


# ---------------------------------------------------------------------------- 5. integer arguments
@pytest.mark.parametrize(
    ("argument", "said"),
    [
        ("size=-5", "size must be at least 5"),
        ("size=1000000000000000000", "size must be at most 255"),
        ("max_cycles=-1", "max_cycles must be positive"),
        ("num_cats=1000000000000000000", "num_cats is at most"),
        ("size=" + "9" * 101, "size is an integer of 101 digits; arguments have at most 100"),
    ],
)
def test_analyse_exact_and_separation_name_the_bound(tmp_path, capsys, argument, said) -> None:
    assert exact_solver.main(["coexistence_v0", argument]) == 2
    assert said in capsys.readouterr().err
    assert cli(["analyse", "separation", "coexistence_v0", argument, "--out", str(tmp_path / "out")]) == 2
    assert said in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_a_signed_integer_argument_is_an_int() -> None:
    parsed = exact_solver.command_line_arguments(["size=+7", "max_cycles=-1", "name=a-1"])
    assert parsed == {"size": 7, "max_cycles": -1, "name": "a-1"}


# ---------------------------------------------------------------------------- 6. empty paths
@pytest.mark.parametrize("argv", [["docs", "--figure", ""], [""]])
def test_tuning_summary_refuses_an_empty_path(capsys, argv) -> None:
    with pytest.raises(SystemExit) as stopped:
        tuning_summary.main(argv)
    assert stopped.value.code == 2
    assert "an empty path" in capsys.readouterr().err
