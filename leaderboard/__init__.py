"""The empathy-zoo leaderboard: scores result files into tables (Markdown, CSV, HTML) and figures."""

from __future__ import annotations

from leaderboard.report import write_leaderboard

__all__ = ["write_leaderboard"]
