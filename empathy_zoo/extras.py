"""The command that installs an optional extra of the suite (``tune``, ``sb3``, ``ray``, …), for
messages and help texts: the suite is installed from its checkout (the README's quick start), so
an extra is installed there too."""

from __future__ import annotations

__all__ = ["install_command"]


def install_command(extra: str) -> str:
    """``pip install -e ".[extra]"`` and where to run it: what installs ``extra`` over the README's
    install (``pip install "empathy-zoo[extra]"`` would look for a package index release)."""
    return f'pip install -e ".[{extra}]" (in the empathy-zoo checkout)'
