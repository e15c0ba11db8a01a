"""The recorded runs' measures kept on disk between processes.

The data's side of the validation (the Jülich runs' Voronoi points, the bi-directional run's
counterflow) is the same for every model and every run of ``socialnav humans validate`` or
``calibrate``, and PedPy takes about a minute to draw it; :func:`kept` stores such a function's
value and reads it back in a later process.

A value is read back only if everything it was computed from is unchanged: the key holds the
function's name and arguments, every file of the shipped data (``data/pedestrians``), the source
of the modules that read and measure it, and the versions of PedPy, shapely, pandas and NumPy. An
unreadable or foreign file is computed again and replaced. The folder is
``$SOCIALNAV_HUMANS_CACHE``, else ``socialnav-jax/humans`` in the user's cache folder
(:func:`socialnav.common.cache.user_cache_folder`); ``SOCIALNAV_HUMANS_CACHE=off``
computes every time. A home that cannot be written computes every time and says nothing.
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import pathlib
from collections.abc import Callable

import pandas as pd

from socialnav.common.atomic import write_text_atomic
from socialnav.common.cache import folder_problem, user_cache_folder

_OFF = ("off", "0", "none", "false")


def folder() -> pathlib.Path | None:
    """Where values are kept (None: switched off, or a folder that cannot hold them: a file, not
    writable, said once in a warning naming it)."""
    if os.environ.get("SOCIALNAV_HUMANS_CACHE", "").lower() in _OFF:
        return None
    where = user_cache_folder("humans", "SOCIALNAV_HUMANS_CACHE")
    problem = folder_problem(where)
    if problem:
        _warn_once(f"the pedestrian data's cache {where}: {problem}; its measures are computed again in every run "
                   "(SOCIALNAV_HUMANS_CACHE names another folder, or 'off')")  # fmt: skip
        return None
    return where


@functools.cache
def _warn_once(message: str) -> None:
    import sys

    print(f"socialnav: warning: {message}", file=sys.stderr)


@functools.lru_cache(maxsize=1)
def inputs_digest() -> str:
    """SHA-256 of what the data's measures are computed from (the module docstring's list)."""
    import numpy
    import pedpy
    import shapely

    from socialnav.data import recorded
    from socialnav.evaluation.humans import measures, validation

    digest = hashlib.sha256()
    sources = [pathlib.Path(m.__file__) for m in (recorded, measures, validation)]
    for path in sorted(recorded.PEDESTRIANS_DIR.iterdir()) + sources:
        if path.is_file():
            digest.update(path.name.encode() + b"\0" + path.read_bytes())
    versions = (pedpy.__version__, shapely.__version__, pd.__version__, numpy.__version__)
    digest.update(json.dumps(versions).encode())
    return digest.hexdigest()


def _encode(value) -> dict:
    if isinstance(value, pd.DataFrame):
        return {
            "frame": {str(c): value[c].tolist() for c in value.columns},
            "dtypes": {str(c): str(t) for c, t in value.dtypes.items()},
        }
    return {"dict": {str(k): float(v) for k, v in value.items()}}


def _decode(stored: dict):
    if "frame" in stored:
        return pd.DataFrame(stored["frame"]).astype(stored["dtypes"])
    return dict(stored["dict"])


def kept(function: Callable) -> Callable:
    """``function(*args, **kwargs)`` (JSON-able arguments; a DataFrame of numbers and strings, or
    a dict of floats) computed once and read back from :func:`folder` in later calls and
    processes. JSON keeps a float's every bit (Python writes the shortest repr that reads back the
    same)."""

    @functools.wraps(function)
    def wrapper(*args, **kwargs):
        where = folder()
        if where is None:
            return function(*args, **kwargs)
        called = [list(args), sorted(kwargs.items())]
        key = json.dumps([function.__module__, function.__qualname__, called, inputs_digest()])
        path = where / f"{function.__name__.strip('_')}-{hashlib.sha256(key.encode()).hexdigest()[:24]}.json"
        try:
            stored = json.loads(path.read_text(encoding="utf-8"))
            if stored.get("key") == key:
                return _decode(stored)
        except (OSError, ValueError, KeyError, TypeError, AttributeError):
            pass  # absent, half a file from elsewhere, or foreign: computed again below
        value = function(*args, **kwargs)
        try:
            write_text_atomic(path, json.dumps({"key": key, **_encode(value)}))
        except OSError:
            pass  # a folder that cannot be written: the value is computed again next time
        return value

    return wrapper
