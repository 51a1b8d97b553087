"""``--allow-import MODULE:NAME``: the one way a command lets a name read from a file import code.

A result, evaluation or agent file may record the fixed policy a run trained beside as a
``package.module:ClassName`` plug-in. Files are data: such a name is refused unless the user
repeats it here, on the command line (docs/limits.md, "Inputs that run code").
"""

from __future__ import annotations

import argparse

from empathy_zoo.import_names import PLUGIN_NAME

__all__ = ["add_allow_import", "plugin_name"]


def plugin_name(text: str) -> str:
    """``text`` if it is a ``package.module:Name`` (an argparse type), else an argparse error."""
    if not PLUGIN_NAME.fullmatch(text):
        raise argparse.ArgumentTypeError(f"{text!r} is not a 'package.module:Name' (dotted module path, a colon, a name)")
    return text


def add_allow_import(parser: argparse.ArgumentParser) -> None:
    """Add ``--allow-import MODULE:NAME`` (repeatable) to ``parser``."""
    parser.add_argument(
        "--allow-import",
        action="append",
        type=plugin_name,
        metavar="MODULE:NAME",
        help="a plug-in fixed policy that the files read may name and that may be imported (repeat for several); "
        "without it, a file naming one is refused: files never make the suite import code",
    )
