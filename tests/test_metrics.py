"""Metrics and statistics: collisions counted once per encounter, Sec. 5.3's components add up,
tests agree with scipy on raw data and detect a difference that is there (and not one that is not)."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
import pandas as pd
import pytest
from scipy import stats

from socialnav.evaluation import metrics, statistics


def _tasks(rng, n=400):
    outcome = rng.choice(["success", "congestion", "battery"], n, p=[0.7, 0.25, 0.05])
    time_s = rng.uniform(10, 60, n)
    return pd.DataFrame(
        {
            "method": rng.choice(["baseline", "causal"], n),
            "slot": rng.integers(0, 3, n),
            "replica": rng.integers(0, 4, n),
            "outcome": outcome,
            "refused": rng.random(n) < 0.05,
            "time_s": time_s,
            "stalled_s": time_s * rng.uniform(0, 0.5, n),
            "distance_m": rng.uniform(5, 25, n),
            "planned_m": rng.uniform(5, 25, n),
            "battery_used_pct": rng.uniform(0.1, 1.0, n),
            "collisions": rng.poisson(0.3, n),
        }
    )


def test_components_add_up_to_the_totals():
    tasks = _tasks(np.random.default_rng(0))
    runs = metrics.per_run(tasks)
    total = tasks.groupby(["method", "replica"])
    np.testing.assert_allclose(
        runs["active_h"] + runs["stalled_h"] + runs["wasted_h"], total["time_s"].sum().to_numpy() / 3600
    )
    ok = tasks["outcome"] == "success"
    driven = tasks.assign(d=np.where(ok, tasks["distance_m"], 0) + np.where(ok, 0, tasks["distance_m"]))
    np.testing.assert_allclose(
        runs["planned_km"] + runs["extra_km"] + runs["wasted_km"],
        driven.groupby(["method", "replica"])["d"].sum().to_numpy() / 1000,
    )
    np.testing.assert_allclose(
        runs["effective_cycles"] + runs["wasted_cycles"], total["battery_used_pct"].sum().to_numpy() / 100
    )
    assert (runs["success"] + runs["congestion"] + runs["battery"] == runs["tasks"]).all()
    assert runs["collisions"].sum() == tasks["collisions"].sum()


def test_binned_mann_whitney_matches_scipy_on_the_raw_samples():
    rng = np.random.default_rng(1)
    a, b = rng.integers(0, 30, 500), rng.integers(2, 32, 700)  # integer values: many ties
    res = statistics.mann_whitney_binned(np.bincount(a, minlength=40), np.bincount(b, minlength=40))
    ref = stats.mannwhitneyu(a, b, alternative="two-sided", method="asymptotic")
    assert res["statistic"] == pytest.approx(ref.statistic)
    assert res["p_value"] == pytest.approx(ref.pvalue, rel=1e-6)


def test_negative_binomial_test_finds_a_real_difference_and_not_a_fake_one():
    rng = np.random.default_rng(2)
    # Overdispersed counts (NB with mean 6 and 2, dispersion 1), as collisions per run are.
    many, few = rng.negative_binomial(1, 1 / 7, 60), rng.negative_binomial(1, 1 / 3, 60)
    res = statistics.negative_binomial_test(many, few)
    assert res["p_value"] < 1e-3 and res["rate_ratio"] < 1 and res["dispersion_alpha"] > 0.3
    same = statistics.negative_binomial_test(many[:30], many[30:])
    assert same["p_value"] > 0.01
    with pytest.raises(ValueError, match=">= 0"):
        statistics.negative_binomial_test([1, -1], [2])


def test_chi_square_and_intervals():
    rng = np.random.default_rng(3)
    tasks = _tasks(rng)
    res = statistics.chi_square_success(tasks, "baseline", "causal")
    table = np.array(res["table"])
    assert table.sum() == len(tasks)
    assert res["p_value"] == pytest.approx(stats.chi2_contingency(table)[1])
    all_ok = tasks.assign(outcome="success")
    assert statistics.chi_square_success(all_ok, "baseline", "causal")["p_value"] == 1.0
    mean, lo, hi = statistics.mean_ci([1.0, 2.0, 3.0, 4.0])
    # By hand: s = sqrt(5/3), se = s / 2, t(0.975, 3 dof) = 3.182446 (a t-table): 2.5 -+ 2.054260.
    assert mean == 2.5 and (lo, hi) == pytest.approx((2.5 - 2.054260, 2.5 + 2.054260), abs=1e-5)
    assert statistics.mean_ci([1.0, 2.0, 3.0, 4.0], confidence=0.90)[2] == pytest.approx(
        2.5 + 2.353363 * 0.645497, abs=1e-5
    )
    assert statistics.mean_ci([7.0]) == (7.0, 7.0, 7.0)


def test_hall_zone_shares_and_quantiles_of_binned_distances():
    bin_m = 0.1
    hist = np.zeros(100)
    hist[[2, 8, 20, 50, 90]] = 1  # 0.25, 0.85, 2.05, 5.05, 9.05 m: one per zone and one beyond
    shares = metrics.zone_shares(hist, bin_m)
    assert shares == {"intimate": 0.2, "personal": 0.2, "social": 0.2, "public": 0.2, "beyond": 0.2}
    uniform = np.ones(100)
    np.testing.assert_allclose(metrics.hist_quantiles(uniform, bin_m, (0.25, 0.5)), [2.5, 5.0])


def test_a_collision_is_counted_once_per_encounter():
    present = jnp.array([True])
    in_contact, total = jnp.array([False]), 0
    for d in [1.0, 0.4, 0.3, 0.5, 0.6, 0.3, 0.3]:  # radius 0.475, released beyond 0.525
        in_contact, new = metrics.collision_encounters(in_contact, jnp.array([d]), present, 0.475, 0.05)
        total += int(new)
    assert total == 2
    in_contact, new = metrics.collision_encounters(
        jnp.array([False]), jnp.array([0.1]), jnp.array([False]), 0.475, 0.05
    )
    assert int(new) == 0 and not bool(in_contact[0])
