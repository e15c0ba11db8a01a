"""Where the toolkit keeps what it can compute again (compiled kernels, measured data)."""

from __future__ import annotations

import os
import pathlib


def user_cache_folder(kind: str, variable: str) -> pathlib.Path:
    """``$variable`` if set, else ``$XDG_CACHE_HOME/socialnav-jax/kind`` (``~/.cache`` when
    ``XDG_CACHE_HOME`` is unset)."""
    setting = os.environ.get(variable)
    if setting:
        return pathlib.Path(setting)
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return pathlib.Path(base) / "socialnav-jax" / kind


def folder_problem(folder: str | os.PathLike) -> str | None:
    """Why ``folder`` cannot hold a cache (a file of that name, a folder that cannot be made or
    written), in a few words, creating it where it is missing; None if it can."""
    try:
        os.makedirs(folder, exist_ok=True)
    except FileExistsError:
        return "a file, not a folder"
    except OSError as e:
        return f"cannot be made ({e.strerror or e})"
    if not os.access(folder, os.W_OK | os.X_OK):
        return "not writable"
    return None
