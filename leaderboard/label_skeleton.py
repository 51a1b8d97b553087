"""What a label reads as, for telling a run's label from a name the leaderboard gives its rows.

:func:`skeleton` folds a label to what a reader sees: its compatibility form (a full-width or
mathematical letter is the letter), without combining marks, spaces, format characters or letters
that draw as nothing, Greek and Cyrillic letters that look like Latin ones written as those, in
lower case. ``"DQ\\u039d"`` (a Greek Nu), ``"\\uff24\\uff31\\uff2e"`` (full width) and ``"dqn"``
all read as ``"dqn"``. It is a screen against lookalikes, not a full confusables table.
"""

from __future__ import annotations

import unicodedata

__all__ = ["skeleton"]

_INVISIBLE = frozenset("\u115f\u1160\u3164\uffa0")
"""Hangul fillers: letters (category Lo) that draw as nothing."""
_LOOKALIKES = str.maketrans(
    {
        # Greek capitals and small letters drawn as Latin ones
        **dict(zip("ΑΒΕΖΗΙΚΜΝΟΡΤΥΧϜϺ", "ABEZHIKMNOPTYXFM", strict=True)),
        **dict(zip("αιικνοτυϲϳ", "aiikvotucj", strict=True)),
        # Cyrillic capitals and small letters drawn as Latin ones
        **dict(zip("АВЕЅІЈКМНОРСТХУԀԚԜҮ", "ABESIJKMHOPCTXYDQWY", strict=True)),
        **dict(zip("аеѕіјорсхуԁԛԝһпг", "aesijopcxydqwhnr", strict=True)),
        # Latin letters drawn as others: small capitals, dotless i
        **dict(zip("ɴǫʀᴅᴀꜱıȷ", "nqrdasij", strict=True)),
        # apostrophes
        **dict.fromkeys("’ʼ′‘`´", "'"),
    }
)


def skeleton(label: str) -> str:
    """``label`` as it reads (see the module page)."""
    kept = "".join(
        c
        for c in unicodedata.normalize("NFKD", label)
        if unicodedata.category(c) not in ("Mn", "Me", "Cf")
        and not unicodedata.category(c).startswith("Z")
        and not c.isspace()
        and c not in _INVISIBLE
    )
    return unicodedata.normalize("NFKC", kept.translate(_LOOKALIKES)).casefold()
