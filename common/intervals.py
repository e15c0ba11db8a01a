"""Confidence intervals shared by the reports (the arena's summary, GSCL's rule suite)."""

from __future__ import annotations

from scipy import stats


def wilson(successes: int, n: int) -> tuple[float, float]:
    """95 % Wilson interval of a proportion (scipy's ``binomtest``); ``(nan, nan)`` when ``n`` is 0."""
    if n == 0:
        return float("nan"), float("nan")
    ci = stats.binomtest(int(successes), int(n)).proportion_ci(0.95, method="wilson")
    return float(ci.low), float(ci.high)
