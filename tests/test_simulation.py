"""Invariants of the simulator over many random worlds, and the schedule over a reduced day."""

from __future__ import annotations

import jax
import numpy as np
import pytest
from plans import scipy_shortest_plan

from socialnav.jaxsim import battery, geometry, logs
from socialnav.jaxsim.rollout import init_batch, rollout, run_samples, to_numpy, world_keys
from socialnav.jaxsim.route_follower import route_follower
from socialnav.jaxsim.scenario import load_scenario
from socialnav.jaxsim.state import ACTIVITY, LEFT, WAITING, WALKING
from socialnav.jaxsim.world import build_world

# The wall constraint (jaxsim.crowd.wall_constraint) is first order along the wall normal before
# the move: exact at a straight wall, but at an inside corner, where the nearest surface changes
# during the step, a worker may end a step inside the other wall by up to a step's length
# (1.5 m/s x 0.1 s). Measured over this module's day (1.34 M samples of present workers): one
# sample 0.021 m inside (a T-junction), the next 0.009 m outside; it was 0.02 m or less before
# the social-force kernel's rounding changed (-ffp-contract=off): which crowd meets a corner is
# chance. So: rare, and shallow.
WALL_TOLERANCE_M = 0.05
RARE_INSIDE_SHARE = 1e-5  # of samples more than 1 cm inside a wall


@pytest.fixture(scope="module")
def day_rollout(short_day):
    """24 random worlds through a whole day of 60 s slots, sampled every 0.5 s."""
    scenario, world, controller = short_day
    p = scenario.params
    n_steps = scenario.n_slots * p.steps_per_slot
    final, rec = rollout(p, world, controller, seed=3, n_worlds=24, n_steps=n_steps, sample_every_steps=5)
    return scenario, to_numpy(final), to_numpy(rec)


@pytest.mark.slow
def test_no_nan_and_the_battery_discharges(day_rollout):
    _, final, rec = day_rollout
    for leaf in jax.tree.leaves(final):
        if np.issubdtype(leaf.dtype, np.floating):
            assert not np.isnan(leaf).any()
    for name in ("robot_x_m", "robot_y_m", "robot_speed_mps", "battery_pct", "density_ppm2", "worker_x_m"):
        assert not np.isnan(getattr(rec, name)).any(), name
    logs.check_finite(rec)  # what simulate checks before it writes a chunk: a normal day passes
    assert (np.diff(rec.battery_pct, axis=1) < 0).any()  # it does discharge (its law: the next test)


@pytest.mark.slow
def test_the_battery_follows_eq_1_and_2_step_by_step():
    """Every step's change is Eq. (1) of that step's speed, charging and obstacle, and the next
    level is the last plus that change (Eq. 2), clipped only at 0 and 100 (known answers, not
    bounds a clip guarantees). A robot starting at 21 % so that it also charges."""
    scenario = load_scenario(slot_length_s=60.0, n_workers=4, battery_initial_pct=21.0)
    world = build_world(scenario)
    controller = route_follower(scipy_shortest_plan(scenario), world)
    p = scenario.params
    _, rec = rollout(p, world, controller, seed=5, n_worlds=2, n_steps=6000, sample_every_steps=1)
    rec = to_numpy(rec)
    law = lambda speed: np.asarray(battery.battery_change_pct(p, speed, rec.charging, rec.obstacle))
    same = np.isclose(rec.battery_change_pct, law(rec.robot_speed_mps), rtol=1e-6, atol=1e-9)
    # Where the day's bookkeeping stops the robot after its move (a leg's end), the step drove at
    # some speed and the record shows 0: the change is then a discharge at a speed in [0, v_max].
    stopped = (rec.robot_speed_mps == 0) & ~rec.charging & ~same
    fastest = law(np.full_like(rec.robot_speed_mps, p.robot_max_speed_mps))
    assert (same | stopped).all() and stopped.mean() < 2e-3
    assert (rec.battery_change_pct[stopped] <= law(np.zeros_like(rec.robot_speed_mps))[stopped] + 1e-9).all()
    assert (rec.battery_change_pct[stopped] >= fastest[stopped] - 1e-9).all()
    before, change, after = rec.battery_pct[:, :-1], rec.battery_change_pct[:, 1:], rec.battery_pct[:, 1:]
    inside = (before + change > 0.0) & (before + change < 100.0)
    np.testing.assert_allclose(after[inside], (before + change)[inside], atol=2e-5)
    assert inside.mean() > 0.9 and rec.charging.any() and (~rec.charging).any()


@pytest.mark.slow
def test_nobody_inside_walls(day_rollout):
    scenario, _, rec = day_rollout
    present = (rec.worker_status == WALKING) | (rec.worker_status == ACTIVITY)
    sd, _, _ = geometry.box_signed_distance(rec.worker_x_m[present], rec.worker_y_m[present], scenario.boxes_m)
    assert sd.min() > -WALL_TOLERANCE_M, f"a worker is {-sd.min():.3f} m inside a wall"
    assert (sd < -0.01).mean() < RARE_INSIDE_SHARE, f"{(sd < -0.01).sum()} samples more than 1 cm inside a wall"
    rsd, _, _ = geometry.box_signed_distance(rec.robot_x_m, rec.robot_y_m, scenario.boxes_m)
    assert rsd.min() > 0


@pytest.mark.slow
def test_speeds_bounded(day_rollout):
    scenario, final, rec = day_rollout
    p = scenario.params
    speed = np.hypot(final.workers.vx_mps, final.workers.vy_mps)
    assert (speed <= final.workers.desired_speed_mps + 1e-5).all()
    assert (final.workers.desired_speed_mps <= p.worker_max_speed_mps).all()
    assert (rec.robot_speed_mps >= 0).all() and (rec.robot_speed_mps <= p.robot_max_speed_mps + 1e-6).all()
    # Between two samples a walker moves at most max speed x interval (+ wall projection slack).
    both = (rec.worker_status[:, 1:] == WALKING) & (rec.worker_status[:, :-1] == WALKING)
    step = np.hypot(np.diff(rec.worker_x_m, axis=1), np.diff(rec.worker_y_m, axis=1))[both]
    assert step.max() <= p.worker_max_speed_mps * 0.5 + 0.1


@pytest.mark.slow
def test_workers_conserved_and_off_slot_empty(day_rollout):
    scenario, _, rec = day_rollout
    n = scenario.params.n_workers
    counts = sum((rec.worker_status == code).sum(-1) for code in (WAITING, WALKING, ACTIVITY, LEFT))
    assert (counts == n).all()
    assert (rec.n_present == ((rec.worker_status == WALKING) | (rec.worker_status == ACTIVITY)).sum(-1)).all()
    off = rec.slot == scenario.n_slots - 1
    assert rec.n_present[off].max() == 0
    # Everyone has arrived by the end of the first slot, nobody has left before the last working one.
    end_s1 = rec.slot == 1
    assert (rec.worker_status[end_s1] != WAITING).all()
    before_s10 = rec.slot < 9
    assert (rec.worker_status[before_s10] != LEFT).all()
    # Left workers never come back.
    was_left = np.maximum.accumulate(rec.worker_status == LEFT, axis=1)
    assert (rec.worker_status[was_left] == LEFT).all()


@pytest.mark.slow
def test_robot_works(day_rollout):
    _, _, rec = day_rollout
    assert (rec.tasks_succeeded[:, -1] > 0).all()
    assert (np.diff(rec.tasks_started, axis=1) >= 0).all()


@pytest.mark.slow
def test_robot_charges_only_at_the_station_and_standing_still():
    """A robot that starts at 21 % must go and charge (below 20 % after its first legs)."""
    scenario = load_scenario(slot_length_s=60.0, n_workers=4, battery_initial_pct=21.0)
    world = build_world(scenario)
    controller = route_follower(scipy_shortest_plan(scenario), world)
    _, rec = rollout(scenario.params, world, controller, seed=1, n_worlds=4, n_steps=6000, sample_every_steps=5)
    rec = to_numpy(rec)
    charging = rec.charging
    assert charging.any(axis=1).all(), "every world's robot should have charged"
    xy = scenario.waypoint_xy_m[scenario.charging_station]
    assert np.hypot(rec.robot_x_m[charging] - xy[0], rec.robot_y_m[charging] - xy[1]).max() < 0.3
    assert (rec.robot_speed_mps[charging] == 0).all()
    assert (np.diff(rec.battery_pct, axis=1)[charging[:, 1:] & charging[:, :-1]] >= 0).all()  # it charges


@pytest.mark.slow
def test_the_robot_follows_the_plan_it_is_given():
    """Any route table drives the robot: a plan whose first leg detours through a waypoint off
    the shortest route makes the robot pass there, and the task still succeeds."""
    scenario = load_scenario(
        slot_length_s=30.0, n_workers=0, robot_obstacle_probability=0.0, robot_leg_deadline_s=200.0
    )  # the first leg (27.7 m) must not time out
    base = scipy_shortest_plan(scenario)
    routes, hops = np.array(base.routes), np.array(base.hops)
    start, via = scenario.robot_start, scenario.waypoint("target-5")
    goal = int(scenario.robot_goals[0][0])
    first, second = routes[0, start, via, : hops[0, start, via]], routes[0, via, goal, : hops[0, via, goal]]
    detour = np.concatenate([first, second])
    assert len(detour) <= routes.shape[-1] + hops[0, via, goal]
    width = max(routes.shape[-1], len(detour))
    routes = np.concatenate([routes, np.repeat(routes[..., -1:], width - routes.shape[-1], -1)], -1)
    routes[:, start, goal, : len(detour)] = detour
    routes[:, start, goal, len(detour) :] = goal
    hops[:, start, goal] = len(detour)
    plan = base.replace(routes=routes, hops=hops)
    _, rec = rollout(
        scenario.params,
        build_world(scenario),
        route_follower(plan, build_world(scenario)),
        seed=0,
        n_worlds=2,
        n_steps=1500,
        sample_every_steps=5,
    )
    rec = to_numpy(rec)
    vx, vy = scenario.waypoint_xy_m[via]
    first_leg = rec.tasks_started == 1
    near = np.hypot(rec.robot_x_m - vx, rec.robot_y_m - vy) < 0.5
    assert (near & first_leg).any(axis=1).all(), "the robot never passed the detour's waypoint"
    assert (rec.tasks_succeeded[:, -1] >= 1).all()
    # The shortest plan does not pass there.
    _, direct = rollout(
        scenario.params,
        build_world(scenario),
        route_follower(base, build_world(scenario)),
        seed=0,
        n_worlds=2,
        n_steps=1500,
        sample_every_steps=5,
    )
    direct = to_numpy(direct)
    assert not (np.hypot(direct.robot_x_m - vx, direct.robot_y_m - vy)[direct.tasks_started == 1] < 0.5).any()


@pytest.mark.slow
def test_same_seed_same_rollout_and_chunk_invariance(short_day):
    scenario, world, controller = short_day
    p = scenario.params
    keys = world_keys(7, 4)
    s0 = init_batch(p, world, controller, keys)
    _, a = run_samples(p, world, controller, s0, keys, 20, 10)
    s1, b1 = run_samples(p, world, controller, s0, keys, 10, 10)
    _, b2 = run_samples(p, world, controller, s1, keys, 10, 10)
    a = to_numpy(a)
    b = jax.tree.map(lambda x, y: np.concatenate([x, y], axis=1), to_numpy(b1), to_numpy(b2))
    for x, y in zip(jax.tree.leaves(a), jax.tree.leaves(b)):
        np.testing.assert_array_equal(x, y)
    # World b is the same world whatever the batch size (to float rounding: XLA may vectorise a
    # reduction differently for another batch shape).
    _, c = run_samples(
        p, world, controller, init_batch(p, world, controller, world_keys(7, 2)), world_keys(7, 2), 20, 10
    )
    np.testing.assert_allclose(to_numpy(c).worker_x_m, a.worker_x_m[:2], rtol=0, atol=1e-4)


@pytest.mark.slow
def test_reduced_day_reproduces_the_schedule():
    """Each working slot's crowded waypoints are its high-probability ones (seed 000 Fig. 7)."""
    scenario = load_scenario(slot_length_s=300.0)
    world = build_world(scenario)
    controller = route_follower(scipy_shortest_plan(scenario), world)
    p = scenario.params
    _, rec = rollout(
        p, world, controller, seed=11, n_worlds=4, n_steps=scenario.n_slots * p.steps_per_slot, sample_every_steps=10
    )
    rec = to_numpy(rec)
    people = rec.density_ppm2 * np.pi * scenario.waypoint_radius_m**2  # people in each disc
    t_in_slot = rec.time_s % p.slot_length_s
    canteen = {scenario.waypoint(n) for n in ("table-12", "table-23", "corridor-canteen-2", "corridor-canteen-3")}
    for s in range(scenario.n_slots - 1):
        # Let the previous slot's crowd move on; in the last working slot people leave, so use all of it.
        late = (rec.slot == s) & ((t_in_slot > p.slot_length_s / 2) | (s == scenario.n_slots - 2))
        mean = people[late].mean(axis=0)
        high = set(np.flatnonzero(scenario.destination_p[s] >= 0.2))
        top = set(np.argsort(-mean)[: len(high)])
        assert top == high, (scenario.slot_names[s], [scenario.waypoint_ids[i] for i in top])
        if s == 5:  # lunch: the canteen holds most of the workers
            assert mean[list(canteen)].sum() > 0.5 * rec.n_present[late].mean()
    assert rec.n_present[rec.slot == scenario.n_slots - 1].max() == 0


@pytest.mark.slow
def test_world_without_workers_runs():
    """The off slot and the Sec. 6 ablation use worlds with nobody in them."""
    scenario = load_scenario(n_workers=0, slot_length_s=30.0)
    world = build_world(scenario)
    controller = route_follower(scipy_shortest_plan(scenario), world)
    final, rec = rollout(scenario.params, world, controller, seed=0, n_worlds=4, n_steps=600, sample_every_steps=10)
    rec = to_numpy(rec)
    assert rec.worker_dist_m.shape == (4, 60, 0) and (rec.n_present == 0).all()
    assert (rec.robot_speed_mps.max(axis=1) > 0.4).all()  # the robot drives


def _record(n_worlds: int = 2, n_samples: int = 10, n_workers: int = 3, n_waypoints: int = 4):
    """A hand-made record of finite values every 0.5 s: worker 0 walking, 1 at an activity, 2 not
    in the building (its position NaN, which the logs may hold for an absent worker)."""
    from dataclasses import fields

    from socialnav.jaxsim.state import Record

    shape = (n_worlds, n_samples)
    per = {"density_ppm2": (n_waypoints,)} | dict.fromkeys(
        ("worker_dist_m", "worker_x_m", "worker_y_m", "worker_status"), (n_workers,)
    )
    arrays = {f.name: np.zeros(shape + per.get(f.name, ())) for f in fields(Record)}
    arrays["time_s"] = np.broadcast_to(np.arange(n_samples) * 0.5, shape)
    arrays["worker_status"] = np.broadcast_to(np.array([WALKING, ACTIVITY, LEFT]), shape + (n_workers,))
    for name in ("worker_x_m", "worker_y_m", "worker_dist_m"):
        arrays[name][..., 2] = np.nan
    return Record(**arrays)


def test_a_diverged_state_stops_the_run():
    """NaN in a logged signal (as extreme force parameters can cause) is an error naming the
    field, the world and the time; absent workers' positions do not count. (A simulated day
    passes: the slow tier checks this module's day, and every ``simulate`` checks its own.)"""
    rec = _record()
    logs.check_finite(rec)  # finite, and the absent worker's NaN does not count
    broken = rec.replace(robot_x_m=rec.robot_x_m.copy())
    broken.robot_x_m[1, 7] = np.nan
    with pytest.raises(logs.SimulationDiverged, match=r"robot_x_m is nan in world 1 at t = 3.5 s"):
        logs.check_finite(broken)
    with pytest.raises(logs.SimulationDiverged, match=r"in world 5 at t = 3.5 s"):  # a shard's first world is 4
        logs.check_finite(broken, first_world=4)
    walker_lost = rec.replace(worker_y_m=rec.worker_y_m.copy())
    walker_lost.worker_y_m[0, 2, 1] = np.inf  # the worker at an activity
    with pytest.raises(logs.SimulationDiverged, match=r"worker_y_m is inf in world 0 at t = 1.0 s"):
        logs.check_finite(walker_lost)
