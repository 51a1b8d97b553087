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
