"""Typed reads of JSON fields, each failure a :class:`ScenarioError` naming file and field."""

from __future__ import annotations

import json
import pathlib
from typing import Any

import numpy as np

from socialnav.common import strict_json
from socialnav.jaxsim.scenario.errors import ScenarioError


def read_json(file: pathlib.Path) -> dict:
    """The top-level object of ``file``."""
    if not file.is_file():
        raise ScenarioError(file, "<file>", "file is missing")
    try:
        obj = strict_json.loads(file.read_text(encoding="utf-8"))
    except strict_json.DuplicateKeyError as e:
        raise ScenarioError(file, e.key, "given twice in one object: which one was meant?") from None
    except UnicodeDecodeError as e:
        raise ScenarioError(file, "<file>", f"not UTF-8 text ({e.reason} at byte {e.start})") from None
    except json.JSONDecodeError as e:
        raise ScenarioError(file, "<file>", f"invalid JSON: {e}") from None
    except OSError as e:  # a folder of that name, no permission
        raise ScenarioError(file, "<file>", f"cannot be read ({e.strerror or e})") from None
    if not isinstance(obj, dict):
        raise ScenarioError(file, "<file>", "top level must be a JSON object")
    return obj


def _object(obj: Any, file: pathlib.Path, where: str, key: str) -> None:
    """An entry that should be an object holding ``key`` (a string where an object belongs read
    as "missing field" before)."""
    if not isinstance(obj, dict):
        raise ScenarioError(
            file, where or "<file>", f"expected an object with field '{key}', got {type(obj).__name__} {obj!r:.40}"
        )


def field(obj: Any, file: pathlib.Path, where: str, key: str, kind: type) -> Any:
    """``obj[key]``, which must be of type ``kind`` (a bool is not a number)."""
    _object(obj, file, where, key)
    if key not in obj:
        raise ScenarioError(file, f"{where}.{key}" if where else key, "missing field")
    value = obj[key]
    if not isinstance(value, kind) or (kind is not bool and isinstance(value, bool)):
        raise ScenarioError(
            file, f"{where}.{key}" if where else key, f"expected {kind.__name__}, got {type(value).__name__}"
        )
    return value


def number(obj: Any, file: pathlib.Path, where: str, key: str) -> float:
    """``obj[key]`` as a finite float."""
    _object(obj, file, where, key)
    if key not in obj:
        raise ScenarioError(file, f"{where}.{key}", "missing field")
    value = obj[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value):
        raise ScenarioError(file, f"{where}.{key}", f"expected a finite number, got {value!r}")
    return float(value)


def only_fields(obj: Any, file: pathlib.Path, where: str, known: tuple[str, ...]) -> None:
    """Refuse a key of the object ``obj`` that is not one of ``known`` (a misspelt or made-up field
    would be read by nothing and say nothing); a key starting with ``_`` is a note for people
    (the shipped files' ``"_source"``) and is never read."""
    if not isinstance(obj, dict):
        return  # not an object: the field reads that follow refuse it, saying what belongs there
    key = strict_json.unknown_key(obj, known)
    if key is not None:
        hint = strict_json.did_you_mean(key, known)
        raise ScenarioError(
            file, f"{where}.{key}" if where else key, f"unknown field ({hint}the fields: {', '.join(known)})"
        )


def list_field(obj: dict, file: pathlib.Path, key: str) -> list:
    """A top-level list."""
    return field(obj, file, "", key, list)


def waypoint_field(obj: dict, file: pathlib.Path, key: str, index: dict[str, int]) -> int:
    """A top-level waypoint name, as its index."""
    name = field(obj, file, "", key, str)
    if name not in index:
        raise ScenarioError(file, key, f"unknown waypoint {name!r}")
    return index[name]
