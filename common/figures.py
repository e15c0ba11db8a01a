"""Figures without pyplot: no backend is chosen or switched at import, so a notebook's backend
stays the user's. Every picture of the toolkit is a :class:`matplotlib.figure.Figure` saved
atomically by :func:`save`."""

from __future__ import annotations

import pathlib

from matplotlib.figure import Figure

from socialnav.common.atomic import write_atomic


def figure(**kwargs) -> Figure:
    """A new figure (``Figure(**kwargs)``), independent of pyplot's state."""
    return Figure(**kwargs)


def save(fig: Figure, path: str | pathlib.Path, dpi: int = 130) -> pathlib.Path:
    """Write ``fig`` to ``path`` (format from the suffix) atomically; returns ``path``."""
    return write_atomic(path, lambda tmp: fig.savefig(tmp, dpi=dpi, bbox_inches="tight"))
