"""The composition root's joins: the ablation's sweep over obstacle probabilities is one batched
rollout (a vmap over stacked dynamic parameters) that gives what separate runs give, and the
causal estimates from it show seed 000 Sec. 6's effect."""

from __future__ import annotations

import numpy as np
import pytest

from socialnav.ablation_study import ablation_series
from socialnav.causal import ablation
from socialnav.common.memory import available_bytes
from socialnav.jaxsim import rollout
from socialnav.jaxsim.route_follower import route_follower
from socialnav.jaxsim.scenario import load_scenario
from socialnav.jaxsim.world import build_world
from socialnav.planners.warehouse.routes import shortest_path_plan


def test_one_batched_sweep_equals_separate_runs():
    """Two obstacle probabilities x 2 seeds in one compiled batch, against one rollout per probability."""
    probabilities, n_seeds, duration_s = (0.2, 0.6), 2, 300.0
    swept = ablation_series(probabilities, n_seeds, seed=3, duration_s=duration_s)
    for p in probabilities:
        s = load_scenario(n_workers=0, robot_obstacle_probability=p, robot_obstacle_length_m=ablation.OBSTACLE_LENGTH_M)
        _, rec = rollout.rollout(
            s.params,
            build_world(s),
            route_follower(shortest_path_plan(s), build_world(s)),
            seed=3,
            n_worlds=n_seeds,
            n_steps=int(duration_s / s.params.dt_s),
            sample_every_steps=10,
        )
        rec = rollout.to_numpy(rec)
        np.testing.assert_allclose(swept[p].speed_mps, rec.robot_speed_mps, atol=1e-5)
        np.testing.assert_array_equal(swept[p].obstacle, rec.obstacle)
    # The probability matters: more obstacles, more time in them.
    assert swept[0.6].obstacle.mean() > swept[0.2].obstacle.mean()


@pytest.mark.slow
def test_ablation_causal_beats_bayesian_on_the_simulator():
    """Seed 000 Sec. 6 on a short run: conditioning on a fast robot hides obstacles, do() does not."""
    series = ablation_series([0.4], n_seeds=2, duration_s=1800.0)[0.4]
    for k in range(2):
        est = ablation.estimate(
            series.speed_mps[k], series.battery_change_pct[k], series.obstacle[k], series.battery, 1.0, 0.4, k
        )
        assert est.reference < est.causal < 0 and est.reference < est.bayesian < 0
        assert est.error_causal < est.error_bayesian
        assert est.bayesian > est.causal  # the Bayesian answer underestimates the consumption


@pytest.mark.skipif(available_bytes() is None, reason="no /proc/meminfo here: the command runs what it is given")
def test_an_ablation_too_large_for_the_machine_is_refused_before_anything_is_written(tmp_path, capsys):
    """A billion seeds an hour each (was: the batch allocated until the machine killed it)."""
    from socialnav import ablation_study, cli

    out = tmp_path / "ablation"
    assert cli.main(["ablation", "--seeds", "1000000000", "--out", str(out), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "--seeds 1000000000" in err and "GB at once" in err and len(err.strip().splitlines()) == 1
    assert not out.exists()
    # the estimate: one batch of every probability and seed, linear in each
    one = ablation_study.memory_bytes(5, 1) - ablation_study.memory_bytes(5, 0)
    assert ablation_study.memory_bytes(5, 800) == pytest.approx(ablation_study.BASE_BYTES + 800 * one)
    assert ablation_study.memory_bytes(5, 8, duration_s=1800.0) < ablation_study.memory_bytes(5, 8)
    with pytest.raises(ValueError, match=r"ablation_series: 5 probabilities x 1,000,000,000 seeds .* GB at once"):
        ablation_series([0.1, 0.2, 0.3, 0.4, 0.5], 10**9)  # the Python entry refuses it too
