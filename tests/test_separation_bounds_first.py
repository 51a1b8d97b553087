"""``analyse separation`` checks the reachability table's size bound (relative reachability's row
under Coexistence's paper rules builds it, for grids up to 9) from its arguments alone, before any
model is built or solved: one line naming the bound, status 2, nothing written. Before, the bound
was met only when that row was reached, after the model was built and other rows were solved
(seconds at size=10, minutes at size=21)."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace
from typing import Any, NoReturn

import pytest

from empathy_zoo.cli import main as cli_main


def _never(*args: Any, **kwargs: Any) -> NoReturn:
    raise AssertionError("a model was built or solved before the bound was checked")


@pytest.fixture
def _no_model(monkeypatch: pytest.MonkeyPatch) -> None:
    """Building or solving any model fails the test: the refusal must come first."""
    from baselines import reachability_table, separation, separation_render

    monkeypatch.setattr(separation_render, "tabular_model", _never)
    for name in ("optimal_values", "episode_steps", "relative_reachability_reward", "empathic_values"):
        monkeypatch.setattr(separation, name, _never)
    monkeypatch.setattr(reachability_table, "_successors", _never)


@pytest.mark.usefixtures("_no_model")
@pytest.mark.parametrize(("arguments", "mb"), [(["size=10"], 90), (["size=21"], 36970), (["size=10", "rules=paper"], 90)])
def test_a_grid_past_the_reachability_tables_bound_is_refused_before_any_model(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], arguments: list[str], mb: int
) -> None:
    out = tmp_path / "o2"
    assert cli_main(["analyse", "separation", "coexistence_v0", *arguments, "--out", str(out)]) == 2
    stdout, err = capsys.readouterr()
    size = arguments[0].removeprefix("size=")
    assert stdout == "" and err.count("\n") == 1
    assert err == (
        f"empathy-zoo: error: an exact reachability table of Coexistence on size={size} would hold about {mb} MB; "
        "it is built for sizes up to 9\n"
    )
    assert not out.exists()


@pytest.mark.usefixtures("_no_model")
def test_the_table_refuses_such_a_model_before_solving_any_row() -> None:
    from baselines.separation import separation_table

    model = SimpleNamespace(env="coexistence_v0", env_kwargs={"size": 10})
    with pytest.raises(ValueError, match=r"^an exact reachability table of Coexistence on size=10 .* up to 9$"):
        separation_table(model)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("env", "arguments"),
    [
        ("coexistence_v0", {}),
        ("coexistence_v0", {"size": 9}),
        ("coexistence_v0", {"size": 10, "rules": "authors"}),  # (no reachability table: the world rows' own bounds omit)
        ("sharing_v0", {"size": 12}),
        ("no_such_env", {"size": 10}),  # (left to tabular_model to name, as before)
    ],
)
def test_arguments_within_every_bound_pass_the_check(env: str, arguments: dict[str, Any]) -> None:
    from baselines.separation_bounds import check_bounds

    check_bounds(env, arguments)


def test_an_argument_the_engine_refuses_is_refused_in_its_own_words() -> None:
    from baselines.separation_bounds import check_bounds

    with pytest.raises(ValueError, match="takes no argument"):
        check_bounds("coexistence_v0", {"sise": 10})
