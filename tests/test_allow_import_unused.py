"""``--allow-import NAME`` that no partner of the files read names is refused in one line before
anything is written (``leaderboard``, ``evaluate``, ``watch``): it would allow nothing, and a
misspelt one would leave the intended plug-in refused without a word. Before, it was accepted
silently, even for a module that does not exist."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from empathy_zoo.cli import main

RUNS = Path(__file__).resolve().parents[1] / "docs" / "results" / "quick" / "runs"
RUN = "coexistence_v0__empathic_dqn-10853fdf__s0"


@pytest.mark.parametrize(
    ("argv", "where"),
    [
        (["leaderboard", "r", "--out", "lb"], "of the result files read"),
        (["evaluate", "r", "--episodes", "1", "--no-progress"], "of the result files in r"),
        (["watch", f"r/runs/{RUN}.agent.pt", "--episodes", "1"], "of the agent file or --fixed"),
    ],
)
def test_an_allow_import_no_file_names_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch, argv: list[str], where: str
) -> None:
    (tmp_path / "r" / "runs").mkdir(parents=True)
    for path in RUNS.glob(f"{RUN}.*"):
        shutil.copy(path, tmp_path / "r" / "runs" / path.name)
    monkeypatch.chdir(tmp_path)
    before = sorted(tmp_path.rglob("*"))
    capsys.readouterr()
    assert main([*argv, "--allow-import", "nosuch.mod:Y"]) == 2
    out, err = capsys.readouterr()
    assert err.count("\n") == 1 and f"--allow-import nosuch.mod:Y: no partner {where} names it" in err, (out, err)
    assert sorted(tmp_path.rglob("*")) == before


def test_a_name_a_label_records_is_accepted_nested_arguments_and_all() -> None:
    from empathy_zoo.policies import check_allowed_imports_named

    labels = ["random_walk", "mine.partners:Cat(speed=2)", {"policy": "other.mod:Dog"}]
    check_allowed_imports_named({"mine.partners:Cat", "other.mod:Dog"}, labels, "here")
    check_allowed_imports_named((), [], "here")
    with pytest.raises(
        ValueError,
        match=r"--allow-import x.y:Z: no partner here names it, so it allows nothing "
        r"\(plug-in partners named there: mine.partners:Cat\)",
    ):
        check_allowed_imports_named({"mine.partners:Cat", "x.y:Z"}, labels[:2], "here")
