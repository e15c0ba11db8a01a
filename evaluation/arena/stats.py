"""The arena's statistics, as the seeds ran them and with what they could not give.

* Success rates: Fisher's exact test of each scene's proposed method against each other method
  (2 x 2: success, failure), ``scipy.stats.fisher_exact``; Wilson intervals are in the summary.
* Proxemics (seed 002 Sec. 5.3): Welch's ANOVA of the share of time in each Hall zone across
  methods (``scipy.stats.f_oneway(equal_var=False)``), then the Games-Howell post hoc test of the
  proposed method against each other one, and Hedges' g as the effect size. Welch's ANOVA is NaN
  where a method's share is the same in every episode (zero variance leaves its weight undefined).

scipy is the library used: it has Welch's ANOVA, the exact and chi-square tests and the
studentized range distribution; the Games-Howell statistic on top of that distribution is a few
lines (:func:`games_howell`, checked against scipy's Welch t-test, to which it reduces for two
groups). pingouin has Games-Howell ready-made but would add statsmodels, seaborn and scikit-learn
to every install for one function.
"""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
from scipy import stats

# The method each seed proposes, by scene prefix: compared against every other method there.
PROPOSED = {"casn_": "casn", "gscl_": "gscl", "snape_": "snape_social_eband"}
ZONES = ("zone_intimate", "zone_personal", "zone_social", "zone_public")


def hedges_g(a, b) -> float:
    """Hedges' g of ``a`` against ``b``: the standardised mean difference with the small-sample
    correction ``1 - 3 / (4 (n_a + n_b) - 9)``; 0 when both samples are constant and equal."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    na, nb = len(a), len(b)
    pooled = np.sqrt(((na - 1) * a.var(ddof=1) + (nb - 1) * b.var(ddof=1)) / (na + nb - 2))
    diff = a.mean() - b.mean()
    if pooled == 0:
        return 0.0 if diff == 0 else float(np.sign(diff) * np.inf)
    return float(diff / pooled * (1 - 3 / (4 * (na + nb) - 9)))


def games_howell(groups: dict[str, np.ndarray], a: str, b: str) -> tuple[float, float]:
    """Games-Howell test of groups ``a`` and ``b`` among ``len(groups)`` groups: (mean difference,
    p). ``t = diff / sqrt(v_a / n_a + v_b / n_b)`` with Welch-Satterthwaite degrees of freedom,
    ``p = P(Q > |t| sqrt 2)`` for the studentized range Q of ``k`` groups."""
    x, y = np.asarray(groups[a], float), np.asarray(groups[b], float)
    k = len(groups)
    va, vb = x.var(ddof=1) / len(x), y.var(ddof=1) / len(y)
    diff = float(x.mean() - y.mean())
    se = np.sqrt(va + vb)
    if se == 0:
        return diff, (1.0 if diff == 0 else 0.0)
    df = (va + vb) ** 2 / (va**2 / (len(x) - 1) + vb**2 / (len(y) - 1))
    q = abs(diff) / se * np.sqrt(2)
    return diff, float(stats.studentized_range.sf(q, k, df))


def scene_statistics(episodes: pd.DataFrame) -> pd.DataFrame:
    """One row per (scene, proposed method, other method, measure): the test and its result."""
    rows = []
    for scene, g in episodes.groupby("scene", sort=False):
        proposed = next((m for prefix, m in PROPOSED.items() if scene.startswith(prefix)), None)
        methods = list(dict.fromkeys(g["method"]))
        if proposed not in methods or len(methods) < 2:
            continue  # nothing to compare the scene's proposed method with
        others = [m for m in methods if m != proposed]
        by = {m: g[g["method"] == m] for m in methods}
        for other in others:
            for key in ("goal_success", "social_success"):
                a, b = by[proposed][key].astype(bool), by[other][key].astype(bool)
                table = [[a.sum(), (~a).sum()], [b.sum(), (~b).sum()]]
                _, p = stats.fisher_exact(table)
                rows.append(
                    dict(scene=scene, proposed=proposed, other=other, measure=key, test="Fisher exact",
                         statistic=float(a.mean() - b.mean()), p=float(p), effect=float("nan"))
                )  # fmt: skip
        for zone in ZONES:
            samples = {m: by[m][zone].to_numpy(float) for m in methods}
            if all(np.ptp(s) == 0 for s in samples.values()) and len({float(s[0]) for s in samples.values()}) == 1:
                continue  # the same constant in every method: nothing to test
            with warnings.catch_warnings():  # a constant group (zero variance): Welch's weights undefined, NaN
                warnings.simplefilter("ignore", RuntimeWarning)
                f, p = stats.f_oneway(*samples.values(), equal_var=False)
            rows.append(
                dict(scene=scene, proposed=proposed, other="all", measure=zone, test="Welch ANOVA",
                     statistic=float(f), p=float(p), effect=float("nan"))
            )  # fmt: skip
            for other in others:
                diff, p_gh = games_howell(samples, proposed, other)
                rows.append(
                    dict(scene=scene, proposed=proposed, other=other, measure=zone, test="Games-Howell",
                         statistic=diff, p=p_gh, effect=hedges_g(samples[proposed], samples[other]))
                )  # fmt: skip
    return pd.DataFrame(rows)
