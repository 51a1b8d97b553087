"""Fixed-policy labels read back from files (empathy_zoo.policies.parse_entry_label): a label
nested past the parser's recursion, a label of megabytes, and arguments no partner takes are each
one ``ValueError`` with a short message, never a traceback of another kind."""

from __future__ import annotations

import pytest

from empathy_zoo.policies import MAX_LABEL_CHARS, make_policy, parse_entry_label


def test_a_label_nested_past_the_recursion_limit_is_a_value_error() -> None:
    label = "random_walk(a=" + "[" * 1_500 + "]" * 1_500 + ")"
    assert len(label) <= MAX_LABEL_CHARS
    with pytest.raises(ValueError, match="nested too deep"):
        parse_entry_label(label)


def test_a_label_of_megabytes_is_refused_by_its_length_with_a_short_message() -> None:
    label = "random_walk(" + "a=1, " * 400_000 + "a=1)"
    with pytest.raises(ValueError, match=f"at most {MAX_LABEL_CHARS:,} characters") as refused:
        parse_entry_label(label)
    assert len(str(refused.value)) < 200


@pytest.mark.parametrize(
    "label",
    [
        "noisy(noise=1" + "0" * 400 + ', partner="chase")',
        'population(members=["chase", "stay"], weights=[1, 1' + "0" * 400 + "])",
    ],
)
def test_a_huge_number_in_a_partners_label_is_a_value_error(label: str) -> None:
    with pytest.raises(ValueError):
        make_policy(parse_entry_label(label))


@pytest.mark.parametrize(
    "fixed, says",
    [
        ({"cat_7": "random_walk"}, "config.fixed: coexistence_v0 as the run built it has no agent cat_7"),
    ],
)
def test_the_trained_world_names_the_run_and_field_of_bad_partner_arguments(fixed: dict, says: str) -> None:
    """A partner the reader takes but its world has no agent for is named with the run and field
    when the world is built. (A nested plug-in name, ``noisy(partner="os:system")``, is refused by
    the reader itself: ``tests/test_recorded_partner_entries.py``.)"""
    import json
    from pathlib import Path

    from helpers_results import derive_run_id, record

    from leaderboard.episodes import trained_world

    quick = Path(__file__).resolve().parents[1] / "docs" / "results" / "quick" / "runs"
    path = next(quick.glob("coexistence_v0__*__s0.json"))
    document = json.loads(path.read_text())
    document["config"]["fixed"] = fixed  # (labels the result-file checker reads as text: they resolve here)
    derive_run_id(document)  # (the run of that config: its id, and its agent file named after it)
    if document.get("agent"):
        document["agent"]["file"] = f"{document['run_id']}.agent.pt"
    run = record(document, str(path))
    with pytest.raises(ValueError, match=f"run {run.run_id}: {says}"):
        trained_world(run)


def test_a_prefix_that_makes_a_label_too_long_is_refused(tmp_path) -> None:
    import shutil
    from pathlib import Path

    from leaderboard.sources import load_results_dirs

    quick = Path(__file__).resolve().parents[1] / "docs" / "results" / "quick"
    other = tmp_path / "other"
    shutil.copytree(quick / "runs", other / "runs")
    with pytest.raises(ValueError, match="with its prefix"):
        load_results_dirs([quick, other], labels={str(other): "p" * 195})
