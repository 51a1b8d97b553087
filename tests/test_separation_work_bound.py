"""``analyse separation`` bounds the whole table's work (``MAX_SEPARATION_WORK``), counted from its
arguments alone before any model is built or solved: one line naming the work, the bound, the
environment and its arguments, status 2, nothing written. Before, only the joint-state bound
(200,000) was checked, and ``charger_v0 size=21`` (194,481 states) ran for hours until killed."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from baselines import separation, separation_bounds
from empathy_zoo.cli import main as cli_main
from empathy_zoo.environments import ENGINES
from empathy_zoo.limits import BOUNDS, MAX_SEPARATION_WORK
from tests.test_separation_bounds_first import _no_model  # noqa: F401  (the fixture: no model may be built)

SHIPPED = Path(__file__).resolve().parent.parent / "docs" / "results" / "separation"


def _shipped() -> list[tuple[str, dict[str, Any]]]:
    """Every shipped table's environment and arguments, as its JSON records them."""
    tables = []
    for path in sorted(SHIPPED.glob("*.json")):
        data = json.loads(path.read_text(encoding="utf-8"))
        tables.append((data["env"], {str(key): value for key, value in data["arguments"]}))
    return tables


def _work(env: str, arguments: dict[str, Any]) -> int:
    from baselines.separation_bounds import table_work

    return table_work(ENGINES[env](1, **arguments), env)[0]


@pytest.mark.usefixtures("_no_model")
def test_a_table_past_the_work_bound_is_refused_in_one_line_before_any_model(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "o4"
    assert cli_main(["analyse", "separation", "charger_v0", "size=21", "--out", str(out)]) == 2
    stdout, err = capsys.readouterr()
    assert stdout == "" and err.count("\n") == 1
    work = _work("charger_v0", {"size": 21})
    assert work > MAX_SEPARATION_WORK
    assert err.startswith("empathy-zoo: error: the separation table of charger_v0 with {'size': 21} is 194,481 states × (")
    assert f" = {work:,} of work, past the bound of {MAX_SEPARATION_WORK:,} (MAX_SEPARATION_WORK" in err
    assert err.endswith("give a smaller size or max_cycles\n")
    assert not out.exists()


@pytest.mark.usefixtures("_no_model")
def test_the_table_refuses_such_a_model_before_solving_any_row() -> None:
    from types import SimpleNamespace

    model = SimpleNamespace(env="charger_v0", env_kwargs={"size": 21})
    with pytest.raises(ValueError, match=r"^the separation table of charger_v0 .* past the bound of .*max_cycles$"):
        separation.separation_table(model)  # type: ignore[arg-type]


def test_the_bound_is_inclusive(monkeypatch: pytest.MonkeyPatch) -> None:
    work = _work("charger_v0", {"size": 8, "max_cycles": 300})
    monkeypatch.setattr(separation_bounds, "MAX_SEPARATION_WORK", work)
    separation_bounds.check_bounds("charger_v0", {"size": 8, "max_cycles": 300})  # (at the bound: passes)
    monkeypatch.setattr(separation_bounds, "MAX_SEPARATION_WORK", work - 1)
    with pytest.raises(ValueError, match=rf"= {work:,} of work, past the bound of {work - 1:,} "):
        separation_bounds.check_bounds("charger_v0", {"size": 8, "max_cycles": 300})


def test_the_work_grows_with_the_grid_the_episode_and_the_rows() -> None:
    base = _work("charger_v0", {})
    assert _work("charger_v0", {"max_cycles": 501}) > base
    assert _work("charger_v0", {"size": 8}) > base
    from baselines.separation_bounds import table_work

    engine = ENGINES["charger_v0"](1)
    assert table_work(engine, "charger_v0", epsilons=(0.0,))[0] < base < table_work(engine, "charger_v0", (0.5,) * 5)[0]


def test_the_table_passes_its_own_selfishness_and_epsilons(monkeypatch: pytest.MonkeyPatch) -> None:
    seen: list[tuple[Any, ...]] = []

    def recorded(env: str, env_kwargs: Any, selfishness: Any = (), epsilons: Any = (), *, gamma: float = 0.0) -> None:
        seen.append((env, dict(env_kwargs), selfishness, epsilons, gamma))
        raise ValueError("refused")

    from types import SimpleNamespace

    monkeypatch.setattr(separation, "check_bounds", recorded)
    with pytest.raises(ValueError, match="refused"):
        separation.separation_table(SimpleNamespace(env="vase_v0", env_kwargs={}), (0.5,), (0.0, 0.1), gamma=0.9)  # type: ignore[arg-type]
    assert seen == [("vase_v0", {}, (0.5,), (0.0, 0.1), 0.9)]


@pytest.mark.parametrize(("env", "arguments"), _shipped(), ids=lambda value: str(value))
def test_every_shipped_table_passes_with_a_wide_margin(env: str, arguments: dict[str, Any]) -> None:
    separation_bounds.check_bounds(env, arguments)
    assert _work(env, arguments) * 4 <= MAX_SEPARATION_WORK


def test_the_shipped_tables_are_all_there() -> None:
    assert {env for env, _ in _shipped()} == {"charger_v0", "coexistence_v0", "helping_v0", "sharing_v0", "vase_v0"}
    assert len(_shipped()) == 6


def test_the_bound_is_in_the_table_of_bounds() -> None:
    assert BOUNDS["separation table's work"] == MAX_SEPARATION_WORK
    text = (SHIPPED.parent.parent / "limits.md").read_text(encoding="utf-8")
    assert f"| {MAX_SEPARATION_WORK:,} " in text or f"at most {MAX_SEPARATION_WORK:,}" in text
