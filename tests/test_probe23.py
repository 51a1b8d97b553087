"""What a fresh probe of the files from elsewhere left: an e-mail address in data opens no link, and
a ``--label`` option whose directory is not read says where it was split."""

from __future__ import annotations

from pathlib import Path

import pytest

from empathy_zoo.markdown_escape import markdown_text
from leaderboard.page_html import html_inline
from leaderboard.sources import load_results_dirs, parse_label_option

QUICK = Path(__file__).resolve().parents[1] / "docs/results/quick"


@pytest.mark.parametrize(
    ("text", "shown"),
    [
        ("mail me@evil.example.com now", "mail me\\@evil.example.com now"),
        ("mailto:a.b+c@x.org", "mailto:a.b+c\\@x.org"),
        ("a run @ 3 seeds", "a run @ 3 seeds"),
        ("x@", "x@"),
    ],
)
def test_an_email_address_in_data_opens_no_link(text: str, shown: str) -> None:
    assert markdown_text(text) == shown
    assert html_inline(markdown_text(text)) == text.replace("&", "&amp;")  # (the HTML page shows it as it is)


def test_a_label_option_is_split_at_its_last_equals_sign_and_says_so() -> None:
    assert parse_label_option("a=b=mine") == ("a=b", "mine")
    with pytest.raises(ValueError, match="split at its last '='"):
        load_results_dirs([QUICK], {f"{QUICK}=x": "y"})
    with pytest.raises(ValueError, match=r"is not one of the results directories read \([^)]*\)$"):
        load_results_dirs([QUICK], {"elsewhere": "y"})  # (no '=' in it: no word on splitting)


def test_an_empty_file_in_an_outputs_place_is_replaced_as_tune_replaces_one(tmp_path: Path) -> None:
    from empathy_zoo.cli import main

    page = tmp_path / "DISCRIMINATION.md"
    page.touch()  # (a placeholder: nothing in it to lose)
    argv = ["analyse", "discrimination", str(QUICK.parent / "separation"), "--out", str(page)]
    assert main(argv) == 0
    assert page.read_bytes().startswith(b"# Discrimination matrix")


def test_an_exact_model_of_astronomically_many_states_is_refused_by_its_bound(capsys) -> None:
    from empathy_zoo.cli import main

    assert main(["analyse", "exact", "sharing_v0", "size=255"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "joint states, more than 200,000" in err and "about 10^" in err


def test_equivalence_shows_a_cell_without_values_as_a_dash(recwarn) -> None:
    import numpy as np

    from leaderboard.equivalence import _mean_text

    assert _mean_text(np.array([np.nan, np.nan])) == "—" and _mean_text([1.0, np.nan, 2.0]) == "1.500"
    assert not [w for w in recwarn if issubclass(w.category, RuntimeWarning)]


def test_tuning_effect_refuses_a_missing_directory_in_one_line_under_its_own_name(capsys) -> None:
    from empathy_zoo.cli import main

    assert main(["analyse", "tuning-effect", "/nonexistent/untuned", str(QUICK)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("empathy-zoo analyse tuning-effect: error:") and "does not exist" in err


def test_an_exact_table_past_its_work_bound_is_refused_before_anything_is_computed(capsys, monkeypatch) -> None:
    from empathy_zoo import exact_solver
    from empathy_zoo.cli import main

    monkeypatch.setattr(exact_solver, "outcome_table", lambda *_: pytest.fail("computed past the bound"))
    assert main(["analyse", "exact", "coexistence_v0", "size=21", "max_cycles=10000"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "194,481 states × 10,000 steps" in err and "past the bound of 100,000,000" in err


@pytest.mark.parametrize("tool", ["exact", "separation"])
def test_an_exact_model_argument_given_twice_is_refused(tool: str, capsys) -> None:
    from empathy_zoo.cli import main

    assert main(["analyse", tool, "coexistence_v0", "size=5", "size=7"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "size is given twice (5 and '7')" in err
