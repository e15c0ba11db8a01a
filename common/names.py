"""Names that become file names: one safe pattern for every name a user gives that reaches a path
(a scene's ``name``, a waypoint id, a method, a run), so that no name can step out of a folder
(``../../victim``), hide a file (``.x``), pass for an option (``-x``) or exceed a file system's limit."""

from __future__ import annotations

import re

# \w: the letters and digits of any script (str.isalnum) and "_"; a waypoint called "Küche" or
# "出口" names a file as well as "kitchen" does.
SAFE_NAME = re.compile(r"^[^\W_][\w.@+-]{0,99}$")
MAX_NAME_BYTES = 200  # a file system's limit is 255 bytes; room left for a prefix and a suffix
SAFE_NAME_RULE = (
    "letters and digits (of any script) and _ . @ + -, starting with a letter or digit, no '..', "
    f"at most 100 characters and {MAX_NAME_BYTES} bytes as UTF-8"
)


def is_safe_name(name: object) -> bool:
    """Whether ``name`` can be one component of a file name as it is."""
    return (
        isinstance(name, str)
        and bool(SAFE_NAME.match(name))
        and ".." not in name
        and len(name.encode("utf-8")) <= MAX_NAME_BYTES
    )


def name_problem(name: object) -> str:
    """Why ``name`` is not :func:`is_safe_name` ('' when it is), naming the characters refused."""
    if is_safe_name(name):
        return ""
    if not isinstance(name, str):
        return f"expected a text, got {type(name).__name__}"
    refused = [c for c in dict.fromkeys(name) if not (c.isalnum() or c in "_.@+-")]
    if refused:
        return f"the character(s) {', '.join(repr(c) for c in refused)} are not allowed"
    if not name:
        return "it is empty"
    if not (name[0].isalnum()):
        return f"it starts with {name[0]!r}"
    if ".." in name:
        return "it holds '..'"
    return "it is too long"


def check_name(name: object, what: str) -> str:
    """``name`` if :func:`is_safe_name`, else ValueError naming ``what``, what is wrong and the rule."""
    if not is_safe_name(name):
        raise ValueError(f"{what}: {name!r} cannot name a file ({name_problem(name)}): use {SAFE_NAME_RULE}")
    return name  # type: ignore[return-value]
