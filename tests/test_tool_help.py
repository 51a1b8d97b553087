"""``--help`` of the positional analysis tools prints their usage and their page: what each reads,
matches and refuses (the module's docstring), its cross-references as plain names."""

from __future__ import annotations

import importlib

import pytest

from empathy_zoo.names import tool_help


@pytest.mark.parametrize("tool", ["compare_runs", "equivalence", "versus_dqn"])
def test_help_prints_the_usage_and_the_tool_s_page(tool: str, capsys) -> None:
    module = importlib.import_module(f"leaderboard.{tool}")
    assert module.main(["--help"]) == 0
    out = capsys.readouterr().out
    assert out.startswith(f"usage: python -m leaderboard.{tool} ")
    paragraphs = [part for part in (module.__doc__ or "").split("\n\n") if part.strip()]
    assert len(paragraphs) > 1 and len(out.splitlines()) > 5  # (the whole page, not its first line)
    assert ":func:`" not in out and ":data:`" not in out


def test_cross_references_read_as_plain_names() -> None:
    doc = "See :func:`~pkg.mod.f` and\n:attr:`Options.kernel <pkg.options.Options.kernel>`.\n\n    tool DIR\n"
    assert tool_help("usage: tool DIR", doc) == "usage: tool DIR\n\nSee pkg.mod.f and\nOptions.kernel.\n\n    tool DIR"
    assert tool_help("usage: tool DIR", None) == "usage: tool DIR"
