"""Statistics of the evaluations: intervals and the tests seed 000 reports (Sec. 5.3).

scipy provides the distributions and the rank test; two pieces are written here because no
maintained library has them in the form needed: a negative binomial likelihood-ratio test with
the dispersion profiled out (statsmodels' NB2 GLM takes the dispersion as fixed), and a
Mann-Whitney U test over binned samples (millions of robot-person distances compared without
materialising them; equal to scipy's asymptotic test on the raw samples, which the test checks).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from scipy import optimize, special, stats

from socialnav.evaluation.outcomes import OUTCOME_NAMES, SUCCESS


def mean_ci(values, confidence: float = 0.95) -> tuple[float, float, float]:
    """(mean, low, high): Student-t interval of the mean (the mean alone for one value)."""
    v = np.asarray(values, np.float64)
    if v.size == 0:
        raise ValueError("no values")
    m = float(v.mean())
    if v.size < 2:
        return m, m, m
    half = float(stats.t.ppf(0.5 + confidence / 2, v.size - 1) * v.std(ddof=1) / np.sqrt(v.size))
    return m, m - half, m + half


def chi_square_success(tasks: pd.DataFrame, a: str, b: str) -> dict:
    """Chi-square test of independence of method and success/failure (2 x 2, Yates-corrected)."""
    table = np.array(
        [
            [
                ((tasks["method"] == m) & (tasks["outcome"] == OUTCOME_NAMES[SUCCESS])).sum(),
                ((tasks["method"] == m) & (tasks["outcome"] != OUTCOME_NAMES[SUCCESS])).sum(),
            ]
            for m in (a, b)
        ]
    )
    if (table.sum(axis=0) == 0).any():  # all succeed (or all fail): no difference to test
        return {"test": "chi-square", "statistic": 0.0, "p_value": 1.0, "table": table.tolist()}
    chi2, p, dof, _ = stats.chi2_contingency(table)
    return {
        "test": "chi-square",
        "statistic": float(chi2),
        "p_value": float(p),
        "dof": int(dof),
        "table": table.tolist(),
    }


def _nb_loglik(y: np.ndarray, mu: np.ndarray, alpha: float) -> float:
    """NB2 log-likelihood (variance mu + alpha mu^2)."""
    r = 1.0 / alpha
    return float(
        np.sum(
            special.gammaln(y + r)
            - special.gammaln(r)
            - special.gammaln(y + 1)
            + r * np.log(r / (r + mu))
            + y * np.log(np.where(mu > 0, mu / (r + mu), 1.0))
        )
    )


def _nb_profile(y: np.ndarray, mu: np.ndarray) -> tuple[float, float]:
    """(max log-likelihood over alpha, alpha) with the means fixed; Poisson limit as alpha -> 0."""
    res = optimize.minimize_scalar(lambda la: -_nb_loglik(y, mu, np.exp(la)), bounds=(-12.0, 6.0), method="bounded")
    return -float(res.fun), float(np.exp(res.x))


def negative_binomial_test(counts_a, counts_b) -> dict:
    """Likelihood-ratio test that two groups of counts have the same mean, under NB2.

    An NB2 model with one mean per group (log link, group indicator: the MLE of each mean is
    the group's sample mean) against one common mean, the dispersion profiled out in both;
    the LR statistic is chi-square with 1 dof. Also returns the rate ratio b / a.
    """
    ya, yb = np.asarray(counts_a, np.float64), np.asarray(counts_b, np.float64)
    if ya.size == 0 or yb.size == 0:
        raise ValueError("both groups need counts")
    if (ya < 0).any() or (yb < 0).any():
        raise ValueError("counts must be >= 0")
    y = np.concatenate([ya, yb])
    if y.sum() == 0:
        return {"test": "negative binomial LR", "statistic": 0.0, "p_value": 1.0, "rate_ratio": float("nan")}
    mu1 = np.concatenate([np.full(ya.size, ya.mean()), np.full(yb.size, yb.mean())])
    ll1, alpha = _nb_profile(y, mu1)
    ll0, _ = _nb_profile(y, np.full(y.size, y.mean()))
    lr = max(0.0, 2.0 * (ll1 - ll0))
    ratio = float(yb.mean() / ya.mean()) if ya.mean() > 0 else float("inf")
    return {
        "test": "negative binomial LR",
        "statistic": lr,
        "p_value": float(stats.chi2.sf(lr, 1)),
        "dispersion_alpha": alpha,
        "rate_ratio": ratio,
    }


def mann_whitney(x, y) -> dict:
    """Two-sided Mann-Whitney U test (scipy, asymptotic with tie correction)."""
    x, y = np.asarray(x, np.float64), np.asarray(y, np.float64)
    if x.size == 0 or y.size == 0:
        return {"test": "Mann-Whitney U", "statistic": float("nan"), "p_value": float("nan")}
    res = stats.mannwhitneyu(x, y, alternative="two-sided", method="asymptotic")
    return {
        "test": "Mann-Whitney U",
        "statistic": float(res.statistic),
        "p_value": float(res.pvalue),
        "median_a": float(np.median(x)),
        "median_b": float(np.median(y)),
    }


def mann_whitney_binned(hist_a, hist_b) -> dict:
    """Mann-Whitney U test of two samples given as counts over the same ordered bins.

    Values in one bin are ties (midranks); two-sided normal approximation with tie and
    continuity correction, as scipy's asymptotic method computes it on the raw samples. Lets
    millions of robot-person distances be compared without materialising them.
    """
    a, b = np.asarray(hist_a, np.float64), np.asarray(hist_b, np.float64)
    if a.shape != b.shape:
        raise ValueError(f"histograms differ in shape: {a.shape} vs {b.shape}")
    n1, n2 = a.sum(), b.sum()
    if n1 == 0 or n2 == 0:
        return {"test": "Mann-Whitney U (binned)", "statistic": float("nan"), "p_value": float("nan")}
    below_b = np.cumsum(b) - b
    u1 = float(np.sum(a * (below_b + 0.5 * b)))
    t = a + b
    n = n1 + n2
    mu = n1 * n2 / 2.0
    var = n1 * n2 / 12.0 * ((n + 1) - np.sum(t**3 - t) / (n * (n - 1)))
    if var <= 0:
        return {"test": "Mann-Whitney U (binned)", "statistic": u1, "p_value": 1.0}
    z = (abs(u1 - mu) - 0.5) / np.sqrt(var)
    return {"test": "Mann-Whitney U (binned)", "statistic": u1, "p_value": float(min(1.0, 2 * stats.norm.sf(z)))}
