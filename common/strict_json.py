"""JSON as a person writes it: a key given twice in one object is an error, not the last one
kept; a key no reader knows is named with the one that was likely meant.

``json.loads`` keeps the last of two equal keys without a word, so a scene file edited by adding
``"timeout_s": 60`` below an existing ``"timeout_s": 40`` runs with one of them and says nothing
of the other. The input files people write (scene files, the warehouse's scenario folder) are
read through :func:`loads`; files the toolkit writes itself are not.
"""

from __future__ import annotations

import difflib
import json
from typing import Any


class DuplicateKeyError(ValueError):
    """One object of the text holds ``key`` twice."""

    def __init__(self, key: str):
        super().__init__(f"{key!r} is given twice in one object")
        self.key = key


def _unique(pairs: list[tuple[str, Any]]) -> dict:
    obj: dict = {}
    for key, value in pairs:
        if key in obj:
            raise DuplicateKeyError(key)
        obj[key] = value
    return obj


def unknown_key(obj: dict, known) -> str | None:
    """The first key of ``obj`` that is not one of ``known``, or None; a key starting with ``_`` is
    a note for people (``"_source"``, ``"_comment"``) and is never read, so never unknown."""
    return next((str(k) for k in obj if k not in known and not str(k).startswith("_")), None)


def did_you_mean(key: str, known) -> str:
    """``"did you mean 'x'? "`` for the one of ``known`` closest to a key no reader knows (a
    misspelling), or "" when none is close (:func:`difflib.get_close_matches`)."""
    close = difflib.get_close_matches(str(key), list(known), n=1)
    return f"did you mean {close[0]!r}? " if close else ""


def loads(text: str | bytes) -> Any:
    """``json.loads(text)``, refusing a key given twice in one object (:class:`DuplicateKeyError`);
    bad JSON raises ``json.JSONDecodeError`` as ``json.loads`` does."""
    return json.loads(text, object_pairs_hook=_unique)
