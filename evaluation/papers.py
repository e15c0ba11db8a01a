"""The seeds' published numbers, and ours beside them (from an arena summary).

Each row: the paper's table, the scene it maps to here, the method, the metric, the paper's value
and ours. The mapping of the papers' setups onto this project's scenes and methods is the one
written in the README's arena section; seed 001's SNL is ``snl_matched`` (its cutoff radius set
to CASN's personal radius, 1.2 m, as the paper tuned it); seed 002's baselines are NavFn and the
two SNL settings; seed 004's Tests 1-3 are the three static flat scenes in this order, its
Table 3 the two walking ones.
"""

from __future__ import annotations

import pandas as pd

# (source, scene, method, metric, paper value). Metrics: d_min_m (mean minimum distance, m),
# intrusions (personal-space intrusions per trial), goal_success_pct, social_success_pct,
# zone_personal_pct (share of time in the nearest person's personal zone, %).
PAPER_ROWS: tuple[tuple[str, str, str, str, float], ...] = (
    # Seed 001, Tables 1-3 (CASN vs SNL); intrusions per trial = count / trials.
    ("seed 001 Table 1", "casn_static_person", "casn", "d_min_m", 1.29),
    ("seed 001 Table 1", "casn_static_person", "snl_matched", "d_min_m", 1.25),
    ("seed 001 Table 1", "casn_static_person", "casn", "intrusions", 4 / 30),
    ("seed 001 Table 1", "casn_static_person", "snl_matched", "intrusions", 14 / 30),
    ("seed 001 Sec. 4.2", "casn_static_group", "casn", "d_min_m", 1.39),
    ("seed 001 Sec. 4.2", "casn_static_group", "snl_matched", "d_min_m", 0.76),
    ("seed 001 Sec. 4.2", "casn_static_group", "casn", "intrusions", 0 / 10),
    ("seed 001 Sec. 4.2", "casn_static_group", "snl_matched", "intrusions", 10 / 10),
    ("seed 001 Table 2", "casn_head_on", "casn", "d_min_m", 1.11),
    ("seed 001 Table 2", "casn_head_on", "snl_matched", "d_min_m", 0.84),
    ("seed 001 Table 3", "casn_crossing", "casn", "d_min_m", 1.70),
    ("seed 001 Table 3", "casn_crossing", "snl_matched", "d_min_m", 0.99),
    ("seed 001 Table 3", "casn_crossing", "casn", "intrusions", 0 / 15),
    ("seed 001 Table 3", "casn_crossing", "snl_matched", "intrusions", 12 / 15),
    # Seed 002, Table 1 (goal / social success, %).
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
        for metric, value in (("goal_success_pct", goal), ("social_success_pct", social))
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
)


def comparison(summary: pd.DataFrame) -> pd.DataFrame:
    """The papers' rows with ours beside them (``ours`` NaN where the run lacks the scene or method).

    Args:
      summary: :func:`evaluation.arena_report.summary`'s frame.
    """
    rows = []
    for source, scene, method, metric, paper in PAPER_ROWS:
        match = summary[(summary["scene"] == scene) & (summary["method"] == method)]
        ours = float("nan")
        if len(match):
            r = match.iloc[0]
            ours = 100.0 * float(r["zone_personal"]) if metric == "zone_personal_pct" else float(r[metric])
        rows.append(
            {"source": source, "scene": scene, "method": method, "metric": metric, "paper": paper, "ours": ours}
        )
    return pd.DataFrame(rows)
