"""Progress reporting: one way for every long job to show a bar, or nothing.

Library code reports through a plain callable ``report(done, total)`` (or takes ``progress:
bool`` and asks :func:`bar` for one), so it never depends on how the caller displays progress;
:func:`bar` makes the tqdm bar the command line shows.
"""

from __future__ import annotations


class Bar:
    """A tqdm bar driven by absolute counts (``update(done, total)``), created on first use.

    Disabled bars do nothing, so callers need no ``if progress`` around every update.
    """

    def __init__(self, desc: str, unit: str = "it", enabled: bool = True):
        self.desc, self.unit, self.enabled = desc, unit, enabled
        self._bar = None

    def update(self, done: float, total: float) -> None:
        if not self.enabled:
            return
        if self._bar is None:
            from tqdm.auto import tqdm

            self._bar = tqdm(total=total, desc=self.desc, unit=self.unit)
        self._bar.update(done - self._bar.n)

    def set_postfix(self, **values) -> None:
        """Show ``key=value`` pairs after the bar (e.g. the current loss)."""
        if self._bar is not None:
            self._bar.set_postfix(**values)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None

    def __enter__(self) -> Bar:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def bar(desc: str, unit: str = "it", enabled: bool = True) -> Bar:
    """A :class:`Bar`; ``enabled=False`` gives one that shows nothing."""
    return Bar(desc, unit, enabled)


def iterate(iterable, desc: str, enabled: bool = True, **kwargs):
    """``tqdm(iterable)`` when enabled, else the iterable itself."""
    if not enabled:
        return iterable
    from tqdm.auto import tqdm

    return tqdm(iterable, desc=desc, **kwargs)


def time_left(history, total: int, bound: str = "") -> str:
    """``"; about 12 min to go"`` for ``total`` steps (a fit's steps or evaluations, a validation's
    draws), ``history``'s ``(k, value, seconds since the start)`` done so far, at the pace of those
    after the first (which compiles); ``""`` before two are done or once all are. ``bound``: words
    before "about" (``"at most "``: a search that may stop before its last)."""
    done = len(history)
    if done < 2 or done >= total:
        return ""
    per_step_s = (history[-1][2] - history[0][2]) / (done - 1)
    left = duration(per_step_s * (total - done))
    return f"; {left} to go" if left == "under a second" else f"; {bound}about {left} to go"


def duration(seconds: float) -> str:
    """``seconds`` in the unit a person reads it in: ``"45 s"``, ``"12 min"``, ``"3.5 h"``
    (``"under a second"`` below half a second, which ``"0 s"`` would misread as done)."""
    if seconds < 0.5:
        return "under a second"
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 90 * 60:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"
