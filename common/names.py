"""Names that become file names: one safe pattern for every name a user gives that reaches a path
(a scene's ``name``, a waypoint id, a method, a run), so that no name can step out of a folder
(``../../victim``), hide a file (``.x``), pass for an option (``-x``) or exceed a file system's limit."""

from __future__ import annotations

import re

SAFE_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.@+-]{0,99}$")
SAFE_NAME_RULE = "letters, digits and _ . @ + -, starting with a letter or digit, no '..', at most 100 characters"


def is_safe_name(name: object) -> bool:
    """Whether ``name`` can be one component of a file name as it is."""
    return isinstance(name, str) and bool(SAFE_NAME.match(name)) and ".." not in name


def check_name(name: object, what: str) -> str:
    """``name`` if :func:`is_safe_name`, else ValueError naming ``what`` and the rule."""
    if not is_safe_name(name):
        raise ValueError(f"{what}: {name!r} cannot name a file: use {SAFE_NAME_RULE}")
    return name  # type: ignore[return-value]
