"""The arena's comparisons: the papers' rows, our intervals against their numbers, paired
directions, Games-Howell and Hedges' g, per-scene statistics."""

import numpy as np
import pandas as pd
import pytest

from socialnav.data import DATA_DIR
from socialnav.planners.stack import METHODS

SCENES = sorted((DATA_DIR / "scenes").glob("*.json"))


def test_the_papers_rows_name_known_scenes_and_methods_and_take_ours_from_a_summary():
    from socialnav.evaluation.arena import papers
    from socialnav.jaxsim.scenes.spec import load_scene as load

    scenes = {load(f).name for f in SCENES}
    assert {row[1] for row in papers.PAPER_ROWS} <= scenes
    assert {row[2] for row in papers.PAPER_ROWS} <= set(METHODS)
    summary = pd.DataFrame(
        [{"scene": "casn_crossing", "method": "casn", "d_min_m": 1.5, "intruded_pct": 20.0, "zone_personal": 0.1}]
    )
    compared = papers.comparison(summary)
    assert len(compared) == len(papers.PAPER_ROWS)
    mine = compared[(compared["scene"] == "casn_crossing") & (compared["method"] == "casn")]
    assert dict(zip(mine["metric"], mine["ours"], strict=True)) == {"d_min_m": 1.5, "intruded_pct": 20.0}
    assert compared["ours"].isna().sum() == len(compared) - 2
    # Zone shares are kept as fractions and compared in % (seed 004's Psi).
    summary = pd.DataFrame(
        [{"scene": "snape_walking", "method": "snape_eband", "zone_social": 0.5, "zone_social_lo": 0.4}]
    )
    mine = papers.comparison(summary).dropna(subset=["ours"]).set_index("metric")
    assert mine.loc["zone_social_pct", "ours"] == 50.0 and mine.loc["zone_social_pct", "ours_lo"] == 40.0
    assert mine.loc["zone_social_pct", "paper"] == pytest.approx(5.05345)


def test_the_comparison_gives_our_interval_and_whether_the_paper_lies_in_it():
    from socialnav.evaluation.arena import papers

    summary = pd.DataFrame(
        [
            {"scene": "casn_crossing", "method": "casn", "d_min_m": 1.5, "d_min_m_lo": 1.4, "d_min_m_hi": 1.75},
            {"scene": "gscl_queue", "method": "navfn", "goal_no_collision_pct": 90.0, "goal_no_collision_lo": 82.0,
             "goal_no_collision_hi": 95.0, "social_no_collision_pct": 0.0, "social_no_collision_lo": 0.0,
             "social_no_collision_hi": 4.0, "goal_success_pct": 100.0, "goal_success_lo": 96.0},
        ]
    )  # fmt: skip
    c = papers.comparison(summary).dropna(subset=["ours"]).set_index(["scene", "metric"])
    assert c.loc[("casn_crossing", "d_min_m"), "paper_inside"]  # 1.70 in 1.4-1.75
    # seed 002 counts a collision as a failed run: its rows read the no-collision rates
    assert not c.loc[("gscl_queue", "goal_no_collision_pct"), "paper_inside"]  # 100 outside 82-95
    assert c.loc[("gscl_queue", "social_no_collision_pct"), "paper_inside"]  # 0 in 0-4
    assert c.loc[("gscl_queue", "goal_no_collision_pct"), "ours_hi"] == 95.0
    assert ("gscl_queue", "goal_success_pct") not in c.index


def _paired_episodes(scene, metric, proposed, baseline, a, b):
    rows = [{"scene": scene, "method": proposed, "variant": k, metric: v} for k, v in enumerate(a)]
    rows += [{"scene": scene, "method": baseline, "variant": k, metric: v} for k, v in enumerate(b)]
    return pd.DataFrame(rows)


def test_directions_of_the_held_out_rows_are_their_own():
    from socialnav.evaluation.arena import papers
    from socialnav.evaluation.arena.run import HELD_OUT

    base = np.random.default_rng(2).uniform(0.5, 1.5, 30)
    # CASN farther than SNL on the evaluated variants, nearer on the held-out ones.
    evaluated = _paired_episodes("casn_crossing", "d_min_m", "casn", "snl_matched", base + 0.3, base)
    held_out = _paired_episodes("casn_crossing", "d_min_m", "casn", "snl_matched", base, base + 0.3)
    held_out["scene"] = "casn_crossing" + HELD_OUT
    both = pd.concat([evaluated, held_out], ignore_index=True)
    assert papers.directions(both)["verdict"].tolist() == ["reproduced"]
    row = papers.directions(both, HELD_OUT).iloc[0]
    assert (row["scene"], row["verdict"], row["n_pairs"]) == ("casn_crossing", "opposite", 30)
    assert row["ours_diff"] == pytest.approx(-0.3)
    assert papers.directions(evaluated, HELD_OUT).empty


def test_directions_pair_by_variant_and_give_a_verdict():
    from scipy import stats

    from socialnav.evaluation.arena import papers

    rng = np.random.default_rng(1)
    base = rng.uniform(0.5, 1.5, 40)
    # Seed 001 Table 3, slow walkers: CASN 1.71 vs SNL 1.02 m. Ours: CASN 0.3 m farther in every variant, plus noise
    # far smaller than the spread between variants (pairing removes that spread).
    casn = base + 0.3 + rng.normal(0, 0.05, 40)
    ep = _paired_episodes("casn_crossing", "d_min_m", "casn", "snl_matched", casn, base)
    d = papers.directions(ep)
    assert len(d) == 1
    row = d.iloc[0]
    assert row["verdict"] == "reproduced" and row["n_pairs"] == 40
    assert row["paper_diff"] == pytest.approx(0.69)
    lo, hi = stats.t.interval(0.95, 39, loc=np.mean(casn - base), scale=stats.sem(casn - base))
    assert (row["ours_diff_lo"], row["ours_diff_hi"]) == (pytest.approx(lo), pytest.approx(hi))
    flipped = papers.directions(_paired_episodes("casn_crossing", "d_min_m", "casn", "snl_matched", base, casn))
    assert flipped.iloc[0]["verdict"] == "opposite"
    noisy = papers.directions(
        _paired_episodes("casn_crossing", "d_min_m", "casn", "snl_matched", base + rng.normal(0, 0.5, 40), base)
    )
    assert noisy.iloc[0]["verdict"] in ("same sign, not significant", "opposite, not significant")
    # Seed 002's queue: goal success 100 for every method in the paper; equal here too -> reproduced.
    ep = _paired_episodes("gscl_queue", "goal_no_collision", "gscl", "navfn", [True] * 10, [True] * 10)
    ep["social_no_collision"] = False
    same = papers.directions(ep).set_index("metric")
    assert same.loc["goal_no_collision_pct", "verdict"] == "reproduced"
    assert same.loc["social_no_collision_pct", "paper_diff"] == 93
    assert same.loc["social_no_collision_pct", "ours_diff"] == 0
    assert same.loc["social_no_collision_pct", "verdict"] == "no difference here"
    # Seed 004 Table 2 test 1: the paper's d_2 (a second person); the scene has one: no pairs, no verdict
    # of a direction. Its Psi(Social) reads the zone share in %: 0 in the paper, equal here -> reproduced.
    ep = _paired_episodes(
        "snape_static_person", "d_2_m", "snape_social_eband", "snape_eband", [np.nan] * 5, [np.nan] * 5
    )
    ep["zone_social"] = 0.25
    by_metric = papers.directions(ep).set_index("metric")
    assert by_metric.loc["d_2_m", "verdict"] == "not measured here" and by_metric.loc["d_2_m", "n_pairs"] == 0
    assert by_metric.loc["zone_social_pct", "verdict"] == "reproduced"
    assert by_metric.loc["zone_social_pct", "paper_diff"] == 0


def _speed_class_frames(casn_d, snl_d, casn_intruded, snl_intruded):
    """A hand-made head-on sweep's summary and pairs: one copy a class, CASN and SNL matched with
    the given distances (m) and intruded shares (%), the pairs their differences with +-0.05 m
    and +-5 points intervals."""
    summary, pairs = [], []
    for k in range(3):
        copy = f"casn_head_on+sweep{k}"
        for method, d, i in (("casn", casn_d[k], casn_intruded[k]), ("snl_matched", snl_d[k], snl_intruded[k])):
            summary.append(
                {"scene": copy, "method": method, "n": 100, "d_min_m": d, "d_min_m_lo": d - 0.1, "d_min_m_hi": d + 0.1,
                 "intruded_pct": i, "intruded_lo": max(i - 10, 0), "intruded_hi": min(i + 10, 100)}
            )  # fmt: skip
        for metric, diff, half in (
            ("d_min_m", casn_d[k] - snl_d[k], 0.05),
            ("intruded", casn_intruded[k] - snl_intruded[k], 5),
        ):
            pairs.append(
                {"scene": copy, "method_a": "casn", "method_b": "snl_matched", "metric": metric, "n": 100,
                 "a - b": diff, "lo": diff - half, "hi": diff + half}
            )  # fmt: skip
    return pd.DataFrame(summary), pd.DataFrame(pairs)


def test_seed_001s_speed_classes_sit_beside_a_sweep_with_a_verdict_per_difference():
    """Each of Table 2's classes (slow, medium, fast) against one copy of a head-on sweep: the
    paper's values (d; intrusions as a share of its trials, 5 of 9 = 56 %), ours with whether the
    paper's lies in our interval, the differences and their verdicts; bad sweeps named."""
    from socialnav.evaluation.arena import markdown, papers

    copies = [markdown.sweep_copy_name("casn_head_on", k) for k in range(3)]
    # Slow: the paper's own values (every interval holds them, both differences reproduce);
    # medium: SNL further than CASN (the distance's direction opposite); fast: the same distance
    # for both (no difference) and CASN intruding more (opposite).
    summary, pairs = _speed_class_frames((0.99, 1.0, 1.2), (0.82, 1.3, 1.2), (100 * 5 / 9, 40, 90), (100, 90, 50))
    out = papers.speed_class_comparison(summary, pairs, "casn_head_on", copies)
    assert list(out["speed_class"]) == ["slow", "slow", "medium", "medium", "fast", "fast"]
    assert list(out["metric"]) == ["d_min_m", "intruded_pct"] * 3
    assert out["casn_paper"].tolist() == pytest.approx([0.99, 100 * 5 / 9, 1.18, 60.0, 1.13, 50.0])
    assert out["snl_paper"].tolist() == pytest.approx([0.82, 100.0, 0.85, 100.0, 0.86, 100.0])
    assert out["paper_diff"].tolist() == pytest.approx([0.17, 100 * 5 / 9 - 100, 0.33, -40.0, 0.27, -50.0])
    assert out["casn_inside"].tolist() == [True, True, False, False, True, False]
    assert out["snl_inside"].tolist() == [True, True, False, True, False, False]
    assert out["verdict"].tolist() == [
        "reproduced", "reproduced", "opposite", "reproduced", "no difference here", "opposite",
    ]  # fmt: skip
    assert (out["source"] == "seed 001 Table 2").all() and (out["n_pairs"] == 100).all()
    table = markdown.speed_class_table(out, {"values": [[0.4, 0.55], [0.55, 0.8], [1.1, 1.35]]})
    assert "| slow: 0.47, 0.42; 0.4-0.55 | d min, m | 0.99, 0.99 [0.89, 1.09] |" in table
    assert "Of 6 differences: 3 reproduced, 2 opposite, 1 no difference here." in table
    assert "Of the paper's 12 values, 6 inside our interval." in table

    with pytest.raises(ValueError, match="casn_head_on, casn_crossing only"):
        papers.speed_class_comparison(summary, pairs, "casn_static_person", copies)
    with pytest.raises(ValueError, match="2 copies: a speed-class sweep has one a class"):
        papers.speed_class_comparison(summary, pairs, "casn_head_on", copies[:2])
    with pytest.raises(ValueError, match=r"no summary row for casn_head_on\+sweep2, method snl_matched"):
        papers.speed_class_comparison(summary.iloc[:-1], pairs, "casn_head_on", copies)
    with pytest.raises(ValueError, match=r"no pair casn - snl_matched for casn_head_on\+sweep0, metric intruded"):
        papers.speed_class_comparison(summary, pairs[pairs["metric"] != "intruded"], "casn_head_on", copies)


def test_seed_002s_table_2_is_tested_among_its_four_methods_and_gets_a_verdict_per_cell():
    from socialnav.evaluation.arena import papers
    from socialnav.evaluation.arena import stats as arena_stats

    rng = np.random.default_rng(2)
    n = papers.PAPER_STATS_TRIALS
    shares = {"gscl": (0.0, 0.05), "navfn": (0.10, 0.2), "snl_small": (0.08, 0.15), "snl_large": (0.01, 0.06)}
    rows = [
        {"scene": "gscl_group", "method": m, "variant": k, "zone_intimate": rng.uniform(0, hi / 4),
         "zone_personal": rng.uniform(lo, hi)}
        for m, (lo, hi) in {**shares, "orca": (0.3, 0.4)}.items()
        for k in range(n)
    ]  # fmt: skip
    episodes = pd.DataFrame(rows)
    both_ways = papers.stats_comparison(episodes.assign(zone_body_intimate=0.0, zone_body_personal=0.1))
    assert len(both_ways) == 12 and set(both_ways["distance"]) == {"centre to centre", "body to body"}
    body = both_ways[both_ways["distance"] == "body to body"].set_index(["measure", "baseline"])
    assert body.loc[("zone_intimate", "navfn"), "verdict"] == "no difference here"  # 0 for every method
    t = papers.stats_comparison(episodes).set_index(["measure", "baseline"])
    assert len(t) == 6 and set(t["scene"]) == {"gscl_group"} and (t["n"] == n).all()
    # Among the paper's four methods only (orca, a fifth here, left out of the studentized range).
    g = episodes[episodes["method"] != "orca"]
    both = g["zone_intimate"] + g["zone_personal"]
    samples = {m: both[g["method"] == m].to_numpy() for m in papers.PAPER_STATS_METHODS}
    _, p = arena_stats.games_howell(samples, "gscl", "navfn")
    assert t.loc[("zone_intimate_personal", "navfn"), "ours_p"] == pytest.approx(p)
    assert t.loc[("zone_intimate_personal", "navfn"), "ours_g"] == pytest.approx(
        arena_stats.hedges_g(samples["gscl"], samples["navfn"])
    )
    assert t.loc[("zone_intimate_personal", "navfn"), "verdict"] == "reproduced"  # paper: g -4.5, p <= .0001
    # The paper's group cell GSCL - SNL large (intimate) is not significant (p 0.468): reproduced only if ours is not.
    assert t.loc[("zone_intimate", "snl_large"), "paper_p"] == 0.4680
    expected = "reproduced" if t.loc[("zone_intimate", "snl_large"), "ours_p"] >= 0.05 else "differs (significant here)"
    assert t.loc[("zone_intimate", "snl_large"), "verdict"] == expected
    assert papers._stats_verdict(0.001, -2.0, 0.001, 1.5) == "opposite"
    assert papers._stats_verdict(0.001, -2.0, 0.2, -0.3) == "same sign, not significant"
    # A scene without one of the four methods is left out.
    assert papers.stats_comparison(episodes[episodes["method"] != "snl_small"]).empty


def test_games_howell_reduces_to_welchs_t_test_for_two_groups_and_hedges_g_by_hand():
    from scipy import stats

    from socialnav.evaluation.arena import stats as arena_stats

    rng = np.random.default_rng(0)
    a, b = rng.normal(0, 1, 30), rng.normal(0.5, 2, 40)
    diff, p = arena_stats.games_howell({"a": a, "b": b}, "a", "b")
    assert diff == pytest.approx(a.mean() - b.mean())
    assert p == pytest.approx(stats.ttest_ind(a, b, equal_var=False).pvalue, rel=1e-6)
    # Three groups: the studentized range of 3 is stricter than two groups' t test.
    _, p3 = arena_stats.games_howell({"a": a, "b": b, "c": b + 1}, "a", "b")
    assert p3 > p
    x, y = np.array([1.0, 2.0, 3.0, 4.0]), np.array([2.0, 4.0, 6.0])
    pooled = np.sqrt((3 * x.var(ddof=1) + 2 * y.var(ddof=1)) / 5)
    assert arena_stats.hedges_g(x, y) == pytest.approx((2.5 - 4.0) / pooled * (1 - 3 / (4 * 7 - 9)))


def test_scene_statistics_compare_the_proposed_method_with_the_others():
    from socialnav.evaluation.arena import stats as arena_stats

    rng = np.random.default_rng(1)
    rows = []
    for method, succeed, personal in (("casn", 0.95, 0.02), ("navfn", 0.3, 0.2)):
        for k in range(60):
            share = float(np.clip(rng.normal(personal, 0.02), 0, 1))
            rows.append(dict(scene="casn_x", method=method, variant=k, goal_success=True,
                             social_success=rng.uniform() < succeed, zone_intimate=0.0, zone_personal=share,
                             zone_social=0.5, zone_public=0.5 - share))  # fmt: skip
    table = arena_stats.scene_statistics(pd.DataFrame(rows))
    social = table[(table["measure"] == "social_success")].iloc[0]
    assert social["other"] == "navfn" and social["p"] < 1e-6 and social["statistic"] > 0.4
    gh = table[(table["measure"] == "zone_personal") & (table["test"] == "Games-Howell")].iloc[0]
    assert gh["p"] < 1e-6 and gh["effect"] < -3
    assert not ((table["measure"] == "zone_intimate").any())  # the same constant everywhere: not tested
    # A run of the proposed method alone (socialnav arena --methods casn) has nothing to compare.
    alone = arena_stats.scene_statistics(pd.DataFrame([r for r in rows if r["method"] == "casn"]))
    assert alone.empty


def test_the_papers_tables_script_prints_a_runs_tables_with_their_source_and_counts(tmp_path, capsys, monkeypatch):
    """scripts/papers_tables.py: a run folder's papers.csv and directions.csv as the docs' Markdown
    tables, under the line naming the run; a folder without run.json is refused in one line."""
    import json
    import sys

    import script_loader

    from socialnav.evaluation.arena import papers

    run = tmp_path / "arena"
    run.mkdir()
    (run / "run.json").write_text(json.dumps({"socialnav_version": "9.9", "metrics_version": "m", "variants": 40}))
    summary = pd.DataFrame(
        [{"scene": "casn_crossing", "method": "casn", "d_min_m": 1.5, "d_min_m_lo": 1.4, "d_min_m_hi": 1.75}]
    )
    papers.comparison(summary).dropna(subset=["ours"]).to_csv(run / "papers.csv", index=False)
    rng = np.random.default_rng(3)
    base = rng.uniform(0.5, 1.5, 40)
    papers.directions(_paired_episodes("casn_crossing", "d_min_m", "casn", "snl_matched", base + 0.3, base)).to_csv(
        run / "directions.csv", index=False
    )
    script = script_loader.load("papers_tables")
    monkeypatch.setattr(sys, "argv", ["papers_tables.py", str(run)])
    script.main()
    said = capsys.readouterr().out
    assert said.startswith("From `arena`: commit not recorded, socialnav 9.9, m,") and "40 variants" in said
    assert "| seed 001 Table 3 slow | `casn_crossing` | casn | d_min_m | 1.71 | 1.50 [1.40, 1.75] | yes |" in said
    assert "1 of 1 published numbers inside our intervals." in said
    assert "| casn - snl_matched | +0.69 | +0.30 [" in said and "Of 1 differences: 1 reproduced." in said
    monkeypatch.setattr(sys, "argv", ["papers_tables.py", str(tmp_path)])
    with pytest.raises(SystemExit, match="no run.json"):
        script.main()


def test_the_turned_table_pairs_a_scenes_turned_row_by_variant():
    """``turned_pairs`` and ``turned_table``: own -> turned success per scene and method, the
    paired change with its interval, and a count of the methods' cells the turn moved;
    ``verdict_changes`` lists the papers' differences whose verdict the turn changed."""
    from socialnav.evaluation.arena import markdown as script

    rows = []
    for v in range(10):
        for scene, social in (("s", v < 8), ("s@turned", v < 3)):  # 80 % -> 30 %: moved
            rows.append({"scene": scene, "method": "gscl", "variant": v, "social_no_collision": social})
        for scene in ("s", "s@turned"):  # the same episodes turned: unmoved
            rows.append({"scene": scene, "method": "navfn", "variant": v, "social_no_collision": v < 5})
    rows = [{**r, "goal_no_collision": True} for r in rows]
    pairs = script.turned_pairs(pd.DataFrame(rows))
    assert len(pairs) == 4 and set(pairs["metric"]) == {"social_no_collision", "goal_no_collision"}
    said = script.turned_table(pairs)
    assert "| `s` | gscl | 80 -> 30, -50 [" in said and "| 100 -> 100, +0 [+0, +0] |" in said
    assert "| `s` | navfn | 50 -> 50, +0 [+0, +0] |" in said
    assert "scenes per method: gscl 1 of 1, navfn 0 of 1." in said
    moved = script.turned_table(pairs, moved_only=True)
    assert "| `s` | gscl |" in moved and "navfn |" not in moved and "navfn 0 of 1" in moved
    key = {"source": "seed 002", "scene": "s", "metric": "social_success_pct", "proposed": "gscl", "baseline": "navfn"}
    own = pd.DataFrame([{**key, "verdict": "reproduced", "ours_diff": 30.0}])
    turned = pd.DataFrame([{**key, "verdict": "opposite", "ours_diff": -20.0}])
    said = script.verdict_changes(own, turned)
    assert said.startswith("1 of 1 verdicts change") and "reproduced (+30.00) -> opposite (-20.00)" in said
    assert script.verdict_changes(own, own).startswith("0 of 1 verdicts change")
