"""The seeds' published numbers, and ours beside them (from an arena summary).

Each row: the paper's table, the scene it maps to here, the method, the metric, the paper's value
and ours. The mapping of the papers' setups onto this project's scenes and methods is the one
written in the README's arena section; seed 001's SNL is ``snl_matched`` (its cutoff radius set
to CASN's personal radius, 1.2 m, as the paper tuned it); seed 002's baselines are NavFn and the
two SNL settings; seed 004's Tests 1-3 are the three static flat scenes in this order, its
Table 3 the two walking ones.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

# The shares of episodes the arena's summary keeps in % with Wilson 95 % intervals
# (``<key>_pct``, ``_ci``, ``_lo``, ``_hi``; evaluation.arena.report.summary).
RATES = ("goal_success", "social_success", "intruded", "goal_no_collision", "social_no_collision")

# (source, scene, method, metric, paper value). Metrics: d_min_m (mean minimum distance, m),
# intruded_pct (trials with a personal-space intrusion, %), goal_success_pct, social_success_pct,
# goal_no_collision_pct and social_no_collision_pct (the same, a collision failing the run),
# zone_intimate_pct, zone_personal_pct, zone_social_pct (share of time with the nearest person in
# that Hall zone, %), path_length_m, time_s, chc_rad, d_1_m and d_2_m (evaluation.arena.nav_metrics).
PAPER_ROWS: tuple[tuple[str, str, str, str, float], ...] = (
    # Seed 001, Tables 1-3 (CASN vs SNL). Its "i" counts trials with an intrusion (never more than
    # n: SNL 33 of 33 head-on); Table 2's "All" rows (our head-on walkers span its speeds, 0.4-1.35
    # m/s), Table 3's "Slow" rows (our crossing walker is slow, 0.3-0.5 m/s, as Sec. 3.3 sets the
    # scene: "slow enough to force a collision"; the paper's slow walkers 0.38 and 0.51 m/s).
    ("seed 001 Table 1", "casn_static_person", "casn", "d_min_m", 1.29),
    ("seed 001 Table 1", "casn_static_person", "snl_matched", "d_min_m", 1.25),
    ("seed 001 Table 1", "casn_static_person", "casn", "intruded_pct", 100 * 4 / 30),
    ("seed 001 Table 1", "casn_static_person", "snl_matched", "intruded_pct", 100 * 14 / 30),
    ("seed 001 Sec. 4.2", "casn_static_group", "casn", "d_min_m", 1.39),
    ("seed 001 Sec. 4.2", "casn_static_group", "snl_matched", "d_min_m", 0.76),
    ("seed 001 Sec. 4.2", "casn_static_group", "casn", "intruded_pct", 100 * 0 / 10),
    ("seed 001 Sec. 4.2", "casn_static_group", "snl_matched", "intruded_pct", 100 * 10 / 10),
    ("seed 001 Table 2", "casn_head_on", "casn", "d_min_m", 1.11),
    ("seed 001 Table 2", "casn_head_on", "snl_matched", "d_min_m", 0.84),
    ("seed 001 Table 2", "casn_head_on", "casn", "intruded_pct", 100 * 16 / 29),
    ("seed 001 Table 2", "casn_head_on", "snl_matched", "intruded_pct", 100 * 33 / 33),
    ("seed 001 Table 3 slow", "casn_crossing", "casn", "d_min_m", 1.71),
    ("seed 001 Table 3 slow", "casn_crossing", "snl_matched", "d_min_m", 1.02),
    ("seed 001 Table 3 slow", "casn_crossing", "casn", "intruded_pct", 100 * 0 / 5),
    ("seed 001 Table 3 slow", "casn_crossing", "snl_matched", "intruded_pct", 100 * 4 / 5),
    # Seed 002, Table 1 (goal / social success, %). A collision fails the run: the baselines
    # "frequently result in collisions that prevent goal completion" (Sec. 5.3.1).
    *(
        ("seed 002 Table 1", scene, method, metric, value)
        for scene, values in {
            "gscl_l_hallway": {"navfn": (43, 16), "snl_small": (40, 23), "snl_large": (40, 20), "gscl": (100, 100)},
            "gscl_group": {"navfn": (70, 0), "snl_small": (100, 0), "snl_large": (100, 100), "gscl": (100, 100)},
            "gscl_non_group": {
                "navfn": (70, None),
                "snl_small": (100, None),
                "snl_large": (100, None),
                "gscl": (100, None),
            },
            "gscl_crowded_entrance": {
                "navfn": (93, 0),
                "snl_small": (93, 60),
                "snl_large": (97, 36),
                "gscl": (100, 93),
            },
            "gscl_queue": {"navfn": (100, 0), "snl_small": (100, 0), "snl_large": (100, 0), "gscl": (100, 93)},
        }.items()
        for method, (goal, social) in values.items()
        for metric, value in (("goal_no_collision_pct", goal), ("social_no_collision_pct", social))
        if value is not None
    ),
    # Seed 004, Tables 2-3 (social EB vs EB): time in the personal zone, %.
    ("seed 004 Table 2 test 1", "snape_static_person", "snape_social_eband", "zone_personal_pct", 0.0),
    ("seed 004 Table 2 test 1", "snape_static_person", "snape_eband", "zone_personal_pct", 5.45),
    ("seed 004 Table 2 test 2", "snape_static_pair", "snape_social_eband", "zone_personal_pct", 0.0),
    ("seed 004 Table 2 test 2", "snape_static_pair", "snape_eband", "zone_personal_pct", 3.15),
    ("seed 004 Table 2 test 3", "snape_static_table_fridge", "snape_social_eband", "zone_personal_pct", 0.0),
    ("seed 004 Table 2 test 3", "snape_static_table_fridge", "snape_eband", "zone_personal_pct", 0.44),
    ("seed 004 Table 3 test 1", "snape_walking", "snape_social_eband", "zone_personal_pct", 0.0),
    ("seed 004 Table 3 test 1", "snape_walking", "snape_eband", "zone_personal_pct", 0.87),
    ("seed 004 Table 3 test 2", "snape_two_walking", "snape_social_eband", "zone_personal_pct", 3.94),
    ("seed 004 Table 3 test 2", "snape_two_walking", "snape_eband", "zone_personal_pct", 6.33),
    # Seed 004, Table 3: Psi(Social) and Psi(Intimate) (the paper's headline is Test 1's Psi(Social),
    # 2.22 against 5.05 %). Ours is the share of time with the nearest person 1.2-3.6 m away (Hall),
    # which the paper's Table 2 shows it did not measure (docs/arena-results.md, "Seed 004's Psi").
    ("seed 004 Table 3 test 1", "snape_walking", "snape_social_eband", "zone_social_pct", 2.21654),
    ("seed 004 Table 3 test 1", "snape_walking", "snape_eband", "zone_social_pct", 5.05345),
    ("seed 004 Table 3 test 2", "snape_two_walking", "snape_social_eband", "zone_social_pct", 5.38287),
    ("seed 004 Table 3 test 2", "snape_two_walking", "snape_eband", "zone_social_pct", 5.76461),
    *(
        (f"seed 004 Table 3 test {k}", scene, method, "zone_intimate_pct", 0.0)
        for k, scene in ((1, "snape_walking"), (2, "snape_two_walking"))
        for method in ("snape_social_eband", "snape_eband")
    ),
    # Seed 004, Table 2, the rest of each column: d_t (the paper's mm, here m), tau (s), CHC
    # (rad), d_1 and d_2 (m; the distance to each person at the closest), Psi(Social) and
    # Psi(Intimate). The paper's runs are 1.2-1.8 m long in 9-14 s, ours 9-13 m in 18-28 s (its
    # flat's start and goal are not given): d_t and tau compare as directions only.
    *(
        (f"seed 004 Table 2 test {k}", scene, method, metric, value)
        for k, scene, columns in (
            (
                1,
                "snape_static_person",
                ((1.75713, 9.07, 4.68, 1.41677, 1.69081), (1.42802, 10.05, 3.77, 1.3552, 0.67108)),
            ),
            (
                2,
                "snape_static_pair",
                ((1.2533, 13.21, 6.22, 1.01665, 0.87156), (1.19952, 13.52, 5.63, 1.00963, 0.73475)),
            ),
            (
                3,
                "snape_static_table_fridge",
                ((1.52917, 10.76, 4.18, 1.41678, 1.69081), (1.65162, 9.92, 5.22, 0.98521, 1.94939)),
            ),
        )
        for method, values in zip(("snape_social_eband", "snape_eband"), columns, strict=True)
        for metric, value in zip(
            ("path_length_m", "time_s", "chc_rad", "d_1_m", "d_2_m", "zone_social_pct", "zone_intimate_pct"),
            (*values, 0.0, 0.0),
            strict=True,
        )
    ),
)


# Seed 002, Table 2: Games-Howell tests after Welch's ANOVA of the share of time in the intimate
# zone and in the intimate and personal zones together, GSCL against each baseline, among the
# paper's four methods only (the studentized range depends on the number of groups) and its 30
# trials a method: (scene, measure, baseline, p, Hedges' g). "<= .0001" is kept as 1e-4.
PAPER_STATS_METHODS = ("navfn", "snl_small", "snl_large", "gscl")
PAPER_STATS_TRIALS = 30
PAPER_STATS: tuple[tuple[str, str, str, float, float], ...] = tuple(
    (scene, measure, baseline, p, g)
    for scene, cells in (
        ("gscl_l_hallway", ((0.0050, -2.058), (0.0018, -2.497), (0.0043, -2.161),
                            (0.0022, -2.333), (0.0046, -2.305), (0.0189, -1.837))),
        ("gscl_group", ((1e-4, -8.774), (1e-4, -6.641), (0.4680, -0.372),
                        (1e-4, -4.508), (1e-4, -3.535), (0.0010, -1.052))),
        ("gscl_non_group", ((0.0362, -10.770), (1e-4, -2.220), (1e-4, -1.306),
                            (1e-4, -5.926), (1e-4, -4.781), (1e-4, -2.975))),
        ("gscl_crowded_entrance", ((1e-4, -3.195), (1e-4, -2.213), (0.0012, -0.969),
                                   (1e-4, -2.808), (1e-4, -1.340), (0.9977, -0.047))),
    )
    for (measure, baseline), (p, g) in zip(
        [(m, b) for m in ("zone_intimate", "zone_intimate_personal") for b in ("navfn", "snl_small", "snl_large")],
        cells,
        strict=True,
    )
)  # fmt: skip
SIGNIFICANCE = 0.05


def _stats_verdict(p_paper: float, g_paper: float, p_ours: float, g_ours: float) -> str:
    """Does a Games-Howell cell reproduce: the same significance at :data:`SIGNIFICANCE` and, where
    the paper's is significant, Hedges' g of the same sign."""
    if not np.isfinite(p_ours):
        return "not measured here"
    paper_significant, ours_significant = p_paper < SIGNIFICANCE, p_ours < SIGNIFICANCE
    if not paper_significant:
        return "reproduced" if not ours_significant else "differs (significant here)"
    if g_ours == 0:
        return "no difference here"  # both at the same constant (no time in the zone at all)
    if np.sign(g_ours) == np.sign(g_paper):
        return "reproduced" if ours_significant else "same sign, not significant"
    return "opposite" if ours_significant else "opposite, not significant"


def stats_comparison(episodes: pd.DataFrame) -> pd.DataFrame:
    """Seed 002's Table 2 beside ours: for each of its cells, the Games-Howell p and Hedges' g of
    GSCL against the baseline among :data:`PAPER_STATS_METHODS` (the share of time in the
    intimate zone, ``zone_intimate``, or in the intimate and personal zones, their sum), with the
    episodes each method has (the paper: :data:`PAPER_STATS_TRIALS`), and a ``verdict``; each
    cell twice, the zones by ``distance`` "centre to centre" and "body to body" (the paper does
    not say which: :mod:`evaluation.arena.nav_metrics`). Scenes the run lacks, or lacking one of the
    four methods, are left out.

    Args:
      episodes: the arena's episodes (``scene``, ``method``, ``zone_intimate``, ``zone_personal``).
    """
    from socialnav.evaluation.arena import stats as arena_stats

    rows = []
    for distance, prefix in (("centre to centre", "zone_"), ("body to body", "zone_body_")):
        if prefix + "intimate" not in episodes:  # a run from before the body-to-body zones
            continue
        for scene, measure, baseline, p_paper, g_paper in PAPER_STATS:
            g = episodes[(episodes["scene"] == scene) & episodes["method"].isin(PAPER_STATS_METHODS)]
            if set(g["method"]) != set(PAPER_STATS_METHODS):
                continue
            shares = g[prefix + "intimate"] + (g[prefix + "personal"] if measure == "zone_intimate_personal" else 0.0)
            samples = {m: shares[g["method"] == m].to_numpy(float) for m in PAPER_STATS_METHODS}
            with np.errstate(divide="ignore", invalid="ignore"):  # a method always at 0: no variance
                _, p_ours = arena_stats.games_howell(samples, "gscl", baseline)
                g_ours = arena_stats.hedges_g(samples["gscl"], samples[baseline])
            rows.append(
                {
                    "source": "seed 002 Table 2", "scene": scene, "measure": measure, "baseline": baseline,
                    "distance": distance, "n": len(samples["gscl"]), "paper_p": p_paper, "ours_p": p_ours,
                    "paper_g": g_paper, "ours_g": g_ours, "verdict": _stats_verdict(p_paper, g_paper, p_ours, g_ours),
                }
            )  # fmt: skip
    return pd.DataFrame(rows)


def _episode_column(metric: str) -> tuple[str, float]:
    """The episodes frame's column of a paper's metric and its scale to the paper's unit."""
    if metric in ("zone_intimate_pct", "zone_personal_pct", "zone_social_pct"):
        return metric.removesuffix("_pct"), 100.0
    if metric.endswith("_pct") and metric.removesuffix("_pct") in RATES:
        return metric.removesuffix("_pct"), 100.0
    return metric, 1.0


def _ours(row: pd.Series, metric: str, suffix: str = "") -> float:
    """A summary row's value of a paper's metric in the paper's unit (``suffix``: ``_lo``, ``_hi``
    for the interval); the summary keeps success rates in % already (``_pct``, ``_lo``, ``_hi``)."""
    column, scale = _episode_column(metric)
    if column in RATES:
        column, scale = column + (suffix or "_pct"), 1.0
    else:
        column += suffix
    return scale * float(row[column]) if column in row else float("nan")


def comparison(summary: pd.DataFrame) -> pd.DataFrame:
    """The papers' rows with ours beside them: ``ours`` and its 95 % interval ``ours_lo``,
    ``ours_hi`` (Wilson for success rates, Student t for means; NaN where the summary has none),
    and ``paper_inside`` (the paper's value lies in our interval). ``ours`` is NaN where the run
    lacks the scene or method.

    Args:
      summary: :func:`evaluation.arena.report.summary`'s frame.
    """
    rows = []
    for source, scene, method, metric, paper in PAPER_ROWS:
        match = summary[(summary["scene"] == scene) & (summary["method"] == method)]
        ours = lo = hi = float("nan")
        if len(match):
            r = match.iloc[0]
            ours, lo, hi = _ours(r, metric), _ours(r, metric, "_lo"), _ours(r, metric, "_hi")
        rows.append(
            {
                "source": source,
                "scene": scene,
                "method": method,
                "metric": metric,
                "paper": paper,
                "ours": ours,
                "ours_lo": lo,
                "ours_hi": hi,
                "paper_inside": bool(lo <= paper <= hi) if lo == lo else None,
            }
        )
    return pd.DataFrame(rows)


# Each paper's proposed method against the baselines it was compared with.
PROPOSED_BY_SOURCE = {"seed 001": "casn", "seed 002": "gscl", "seed 004": "snape_social_eband"}


def _episode_values(episodes: pd.DataFrame, scene: str, method: str, metric: str) -> pd.Series:
    column, scale = _episode_column(metric)
    g = episodes[(episodes["scene"] == scene) & (episodes["method"] == method)].set_index("variant")
    return scale * g[column].astype(float)


def direction_verdict(paper_diff: float, ours: float, lo: float, hi: float) -> str:
    """Does a paper's difference (proposed - baseline) reproduce, given ours and its 95 % interval
    ``[lo, hi]``: ``reproduced`` (same sign, our interval excludes 0), ``same sign, not
    significant``, ``opposite`` (our interval excludes 0 on the other side), ``opposite, not
    significant``, ``no difference here`` (ours exactly 0); where the paper's difference is 0,
    ``reproduced`` when our interval holds 0, else ``differs``."""
    significant = not (lo <= 0 <= hi)
    if abs(paper_diff) < 1e-9:
        return "differs" if significant else "reproduced"
    if np.sign(ours) == np.sign(paper_diff):
        return "reproduced" if significant else "same sign, not significant"
    if significant:
        return "opposite"
    return "no difference here" if ours == 0 else "opposite, not significant"


def directions(episodes: pd.DataFrame, suffix: str = "") -> pd.DataFrame:
    """Does each paper's direction reproduce? For every paper row of a proposed method and each
    baseline the paper compared it with on that scene and metric: the paper's difference
    (proposed - baseline), ours, and ours' 95 % interval, paired by variant (common random
    numbers: variant k is the same scene for both; a Student t interval of the per-variant
    differences, for success rates the paired difference of proportions).

    ``verdict``: ``reproduced`` (same sign, our interval excludes 0), ``same sign, not
    significant``, ``opposite`` (our interval excludes 0 on the other side), ``opposite, not
    significant`` (``no difference here`` where every pair is equal); where the paper reports no
    difference, ``reproduced`` when our interval holds 0,
    else ``differs``; ``not measured here`` where no variant has the metric (seed 004's d_2 in a
    scene with one person).

    ``suffix``: the claims on the scene rows named ``<scene><suffix>`` instead: ``""`` the
    evaluated rows, ``"@held_out"`` (:data:`evaluation.arena.run.HELD_OUT`) the held-out mirrors
    (each scene mirrored with its ranges exceeded; the rows keep the scene's name).
    """
    from socialnav.evaluation.arena.report import mean_interval

    if suffix:
        episodes = episodes[episodes["scene"].str.endswith(suffix)]
        episodes = episodes.assign(scene=episodes["scene"].str.removesuffix(suffix))

    paper = {(src, scene, method, metric): value for src, scene, method, metric, value in PAPER_ROWS}
    have = set(zip(episodes["scene"], episodes["method"], strict=True))
    rows = []
    for (src, scene, method, metric), value in paper.items():
        proposed = PROPOSED_BY_SOURCE[src[:8]]
        if method == proposed or (scene, proposed) not in have or (scene, method) not in have:
            continue
        if (src, scene, proposed, metric) not in paper or _episode_column(metric)[0] not in episodes:
            continue
        a = _episode_values(episodes, scene, proposed, metric)
        b = _episode_values(episodes, scene, method, metric)
        both = a.index.intersection(b.index)
        d = (a[both] - b[both]).replace([np.inf, -np.inf], np.nan).dropna()
        ours = float(d.mean()) if len(d) else float("nan")
        lo, hi = mean_interval(d)
        paper_diff = paper[(src, scene, proposed, metric)] - value
        verdict = direction_verdict(paper_diff, ours, lo, hi) if len(d) else "not measured here"
        rows.append(
            {
                "source": src,
                "scene": scene,
                "metric": metric,
                "proposed": proposed,
                "baseline": method,
                "paper_diff": paper_diff,
                "ours_diff": ours,
                "ours_diff_lo": lo,
                "ours_diff_hi": hi,
                "n_pairs": len(d),
                "verdict": verdict,
            }
        )
    return pd.DataFrame(rows)


# Seed 001, Tables 2 (head-on) and 3 (crossing) by the walker's speed class, in the order slow,
# medium, fast: per method (n trials, the walkers' mean speed v in m/s, the mean minimum distance
# d in m, i the trials with an intrusion into the personal space). The "All" rows are in
# :data:`PAPER_ROWS` (Table 2's against the head-on scene, Table 3's slow row against the
# crossing); these are compared with a sweep of the scene's walker speed, one copy a class
# (``scripts/scene_sweep.py SCENE people.speed_mps ...``, docs/arena-results.md).
SPEED_CLASSES = ("slow", "medium", "fast")
PAPER_SPEED_CLASSES: dict[str, tuple[str, dict[str, tuple[tuple[int, float, float, int], ...]]]] = {
    "casn_head_on": (
        "seed 001 Table 2",
        {
            "casn": ((9, 0.47, 0.99, 5), (10, 0.69, 1.18, 6), (10, 1.35, 1.13, 5)),
            "snl_matched": ((11, 0.42, 0.82, 11), (11, 0.66, 0.85, 11), (11, 1.33, 0.86, 11)),
        },
    ),
    "casn_crossing": (
        "seed 001 Table 3",
        {
            "casn": ((5, 0.38, 1.71, 0), (5, 0.61, 1.69, 0), (5, 1.00, 1.72, 0)),
            "snl_matched": ((5, 0.51, 1.02, 4), (5, 0.67, 0.73, 5), (5, 0.91, 1.21, 3)),
        },
    ),
}
# The metrics a speed class reports: (the summary's metric, the pairs' metric, the paper's value
# from (n, v, d, i)).
_SPEED_CLASS_METRICS = (
    ("d_min_m", "d_min_m", lambda n, v, d, i: d),
    ("intruded_pct", "intruded", lambda n, v, d, i: 100.0 * i / n),
)


def speed_class_comparison(summary: pd.DataFrame, pairs: pd.DataFrame, scene: str, copies) -> pd.DataFrame:
    """Seed 001's rows by walker speed beside a sweep of ``scene``'s walker speed: for each class
    and metric (``d_min_m``, ``intruded_pct``) the paper's CASN and SNL values, ours with their
    95 % intervals and whether the paper's value lies in ours (``casn_inside``,
    ``snl_inside``), the paper's difference CASN - SNL and ours paired by variant, and the
    difference's ``verdict`` (:func:`direction_verdict`).

    Args:
      summary: the sweep's summary (:func:`evaluation.arena.report.summary`), rows named by copy.
      pairs: the sweep's paired differences CASN - SNL matched
        (:func:`evaluation.arena.markdown.method_pairs`: ``scene``, ``method_a``, ``method_b``,
        ``metric``, ``a - b``, ``lo``, ``hi``, ``n``).
      scene: ``casn_head_on`` or ``casn_crossing``.
      copies: the sweep's copy names, one a class in the order of :data:`SPEED_CLASSES`.

    Raises ValueError naming what is missing: another scene, another number of copies, or a copy,
    method or metric the frames lack.
    """
    if scene not in PAPER_SPEED_CLASSES:
        raise ValueError(f"scene {scene}: seed 001 reports speed classes for {', '.join(PAPER_SPEED_CLASSES)} only")
    copies = list(copies)
    if len(copies) != len(SPEED_CLASSES):
        raise ValueError(f"{len(copies)} copies: a speed-class sweep has one a class ({', '.join(SPEED_CLASSES)})")
    source, paper = PAPER_SPEED_CLASSES[scene]
    rows = []
    for k, (cls, copy) in enumerate(zip(SPEED_CLASSES, copies, strict=True)):
        mine = {}
        for method in paper:
            match = summary[(summary["scene"] == copy) & (summary["method"] == method)]
            if match.empty:
                raise ValueError(f"no summary row for {copy}, method {method}")
            mine[method] = match.iloc[0]
        for metric, pair_metric, of in _SPEED_CLASS_METRICS:
            pair = pairs[
                (pairs["scene"] == copy)
                & (pairs["method_a"] == "casn")
                & (pairs["method_b"] == "snl_matched")
                & (pairs["metric"] == pair_metric)
            ]
            if pair.empty:
                raise ValueError(f"no pair casn - snl_matched for {copy}, metric {pair_metric}")
            pair = pair.iloc[0]
            row = {"source": source, "scene": scene, "speed_class": cls, "copy": copy, "metric": metric}
            for method, short in (("casn", "casn"), ("snl_matched", "snl")):
                n, speed_mps, d, i = paper[method][k]
                value = of(n, speed_mps, d, i)
                ours, lo, hi = (_ours(mine[method], metric, suffix) for suffix in ("", "_lo", "_hi"))
                row |= {
                    f"{short}_paper_speed_mps": speed_mps,
                    f"{short}_paper": value,
                    f"{short}_ours": ours,
                    f"{short}_lo": lo,
                    f"{short}_hi": hi,
                    f"{short}_inside": bool(lo <= value <= hi),
                }
            diff, lo, hi = (float(pair[c]) for c in ("a - b", "lo", "hi"))
            row |= {
                "paper_diff": row["casn_paper"] - row["snl_paper"],
                "ours_diff": diff,
                "ours_diff_lo": lo,
                "ours_diff_hi": hi,
                "n_pairs": int(pair["n"]),
            }
            row["verdict"] = direction_verdict(row["paper_diff"], diff, lo, hi)
            rows.append(row)
    return pd.DataFrame(rows)
