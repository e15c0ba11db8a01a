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
