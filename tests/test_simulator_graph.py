"""The simulator's causal graph (causal/simulator_graph.py) refereed by the simulator itself: in a
batch of warehouse worlds, a do() on one variable moves, one and two steps later, only what the
graph can reach from it, and each of its same-step children in some world. A dependency added
to jaxsim that the graph does not show makes a variable move that it says cannot."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from plans import scipy_shortest_plan

from socialnav.causal import discover, simulator_graph
from socialnav.causal.variables import GROUND_TRUTH
from socialnav.jaxsim import step as step_lib
from socialnav.jaxsim.actor import Actor, Driver
from socialnav.jaxsim.rng import world_seed_u32
from socialnav.jaxsim.route_follower import route_follower
from socialnav.jaxsim.scenario import load_scenario
from socialnav.jaxsim.state import CHARGING, TASK
from socialnav.jaxsim.world import build_world

N_WORLDS = 24
WARM_STEPS = 1200  # 2 min of the day: some robots charging, some in an obstacle, workers about


@pytest.fixture(scope="module")
def worlds():
    """Worlds started at 21 % battery (robots go and charge) and run WARM_STEPS steps."""
    scenario = load_scenario(slot_length_s=60.0, battery_initial_pct=21.0)
    world = build_world(scenario)
    driver = route_follower(scipy_shortest_plan(scenario), world)
    params = scenario.params
    keys = jax.vmap(lambda b: jax.random.fold_in(jax.random.key(5), b))(jnp.arange(N_WORLDS))
    seeds = jax.vmap(world_seed_u32)(keys)

    @jax.jit
    def warm(keys, seeds):
        state = jax.vmap(lambda k: step_lib.init_state(params, world, driver, k))(keys)
        one = jax.vmap(lambda s, seed: step_lib.step(params, world, driver, s, seed))
        return jax.lax.fori_loop(0, WARM_STEPS, lambda _, s: one(s, seeds), state)

    return params, world, driver, warm(keys, seeds), seeds


def _variables(params, world, state):
    """The pipeline's variables and B per world. D is read with the workers' positions it counts
    (a density changes only when someone crosses a waypoint's circle; a move of the positions
    is a move of what D summarises)."""
    r = jax.vmap(lambda s: step_lib.measure(params, world, s))(state)
    workers = jnp.concatenate([r.density_ppm2, r.worker_x_m, r.worker_y_m], axis=-1)
    return {
        "V": r.robot_speed_mps,
        "L": r.battery_change_pct,
        "B": r.battery_pct,
        "C": r.charging,
        "O": r.obstacle,
        "S": r.slot,
        "D": jnp.nan_to_num(workers, nan=-1.0),
    }


def _two_steps(params, world, state, seeds, first_driver, driver):
    """The variables after one step (``first_driver`` drives it) and after a second (``driver``)."""
    one = jax.jit(jax.vmap(lambda s, seed, d: step_lib.step(params, world, d, s, seed), in_axes=(0, 0, None)))
    s1 = one(state, seeds, first_driver)
    s2 = one(s1, seeds, driver)
    return _variables(params, world, s1), _variables(params, world, s2)


def _moved(a, b, where):
    """{variable: (worlds,) bool} the variable differs between two runs (in ``where``)."""
    out = {}
    for k in a:
        diff = np.asarray(a[k]) != np.asarray(b[k])
        out[k] = (diff.reshape(diff.shape[0], -1).any(axis=1)) & where
    return out


def _stopping(driver: Driver) -> Driver:
    """``driver`` commanding speed 0 (do(V = 0) for the step it drives)."""

    def act(params, state, obs, key):
        command, state = driver.actor.act(params, state, obs, key)
        return command.replace(speed_mps=jnp.zeros_like(command.speed_mps)), state

    actor = driver.actor
    return Driver(Actor(init=actor.init, act=act, name=actor.name), driver.params)


def _check(intervened: str, start_offset: int, moved_by_step: list[dict], where):
    """Every moved variable is one the graph reaches; every same-step child moves somewhere."""
    levels = simulator_graph.reachable(intervened, start_offset + len(moved_by_step))
    assert where.sum() >= 4, "too few worlds where this do() applies"
    for k, moved in enumerate(moved_by_step):
        allowed = levels[start_offset + k]
        unexplained = {v for v, m in moved.items() if m.any() and v not in allowed}
        assert not unexplained, f"do({intervened}) moved {unexplained} at +{start_offset + k} step(s): not in the graph"
    first = moved_by_step[0]
    if start_offset == 0:
        children = {e.effect for e in simulator_graph.EDGES if e.cause == intervened and e.lag == 0} - {"D", "S", "W"}
        quiet = {c for c in children if not first[c].any()}
        assert not quiet, f"do({intervened}) never moved its same-step children {quiet}"


def _with_obstacle(params, state):
    """Every robot at the start of an obstacle (one on a task leg is in it at the next step)."""
    r = state.robot
    return state.replace(
        robot=r.replace(
            obstacle_at_share=jnp.zeros_like(r.obstacle_at_share),
            obstacle_left_m=jnp.full_like(r.obstacle_left_m, params.robot_obstacle_length_m),
            obstacle_speed_factor=jnp.full_like(r.obstacle_speed_factor, 0.5),
        )
    )


@pytest.mark.slow
def test_do_charging_moves_only_what_the_graph_reaches(worlds):
    params, world, driver, state, seeds = worlds
    # Robots on a task leg in an obstacle (so that charging has an obstacle to rule out).
    state = _with_obstacle(params, state)
    not_charging = np.asarray(state.robot.mode) != CHARGING
    forced = state.replace(robot=state.robot.replace(mode=jnp.full_like(state.robot.mode, CHARGING)))
    base = _two_steps(params, world, state, seeds, driver, driver)
    do = _two_steps(params, world, forced, seeds, driver, driver)
    _check("C", 0, [_moved(b, d, not_charging) for b, d in zip(base, do, strict=True)], not_charging)


@pytest.mark.slow
def test_do_obstacle_moves_only_what_the_graph_reaches(worlds):
    params, world, driver, state, seeds = worlds
    r = state.robot
    free_task = (np.asarray(r.mode) == TASK) & ~np.asarray(r.obstacle) & (np.asarray(r.speed_mps) > 0.1)
    forced = _with_obstacle(params, state)
    base = _two_steps(params, world, state, seeds, driver, driver)
    do = _two_steps(params, world, forced, seeds, driver, driver)
    _check("O", 0, [_moved(b, d, free_task) for b, d in zip(base, do, strict=True)], free_task)


@pytest.mark.slow
def test_do_speed_moves_only_what_the_graph_reaches(worlds):
    params, world, driver, state, seeds = worlds
    moving = np.asarray(state.robot.speed_mps) > 0.1
    base = _two_steps(params, world, state, seeds, driver, driver)
    do = _two_steps(params, world, state, seeds, _stopping(driver), driver)
    moved = [_moved(b, d, moving) for b, d in zip(base, do, strict=True)]
    _check("V", 0, moved, moving)
    # The next step: the speed carries over (V -> V) and the workers feel the robot (V -> D).
    assert moved[1]["V"].any() and moved[1]["D"].any() and not moved[0]["D"].any()


@pytest.mark.slow
def test_do_empty_battery_moves_only_what_the_graph_reaches(worlds):
    params, world, driver, state, seeds = worlds
    moving = np.asarray(state.robot.speed_mps) > 0.1
    forced = state.replace(robot=state.robot.replace(battery_pct=jnp.zeros_like(state.robot.battery_pct)))
    base = _two_steps(params, world, state, seeds, driver, driver)
    do = _two_steps(params, world, forced, seeds, driver, driver)
    # B is set in the state the step starts from: the do() is on B(t-1), the records are t, t+1.
    moved = [_moved(b, d, moving) for b, d in zip(base, do, strict=True)]
    _check("B", 1, moved, moving)
    assert moved[0]["V"][moving].all() and moved[0]["B"][moving].all()  # B(t-1) -> V: an empty battery stops it


def test_the_graph_reaches_what_a_missing_edge_would_hide():
    # The referee itself: with V -> L removed, a do(V) may no longer move L, so the check
    # above would fail on the simulator (L moves); and the closure follows lags.
    without = tuple(e for e in simulator_graph.EDGES if (e.cause, e.effect) != ("V", "L"))
    assert "L" in simulator_graph.reachable("V", 0)[0] and "L" not in simulator_graph.reachable("V", 0, without)[0]
    levels = simulator_graph.reachable("O", 2)
    assert levels[0] == {"O", "V", "L", "B"} and "D" not in levels[0] and "D" in levels[1] and "S" not in levels[2]


def test_pipeline_truth_projects_the_battery_out_and_holds_the_papers_graph():
    truth = simulator_graph.pipeline_truth()
    assert all("B" not in (c, e) for c, e, _ in truth)
    assert ("L", "C", 1) in truth and ("L", "V", 1) in truth  # through B
    # Every edge of the paper's Fig. 8 is one the simulator's code makes.
    assert GROUND_TRUTH <= truth, GROUND_TRUTH - truth
    extra = truth - GROUND_TRUTH
    assert ("C", "C", 1) in extra and ("V", "D", 1) in extra
    # Scored against itself the graph is perfect; Fig. 8 against it misses the extra edges.
    links = [discover.Link(c, e, lag, 1.0, 0.0) for c, e, lag in sorted(GROUND_TRUTH)]
    s = discover.score(links, truth)
    assert s["precision"] == 1.0 and s["recall"] == pytest.approx(len(GROUND_TRUTH) / len(truth))
    assert s["shd"] == len(extra)


def test_sampled_graph_has_same_time_feedback_counted_once_and_what_jpcmci_can_find():
    assert simulator_graph.STEP_S == load_scenario().params.dt_s
    assert simulator_graph.sampling_steps(14.0) == 140 and simulator_graph.sampling_steps(0.05) == 1
    sampled = simulator_graph.pipeline_truth(140)  # the main job's 14 s period
    assert {("V", "C", 0), ("C", "V", 0), ("V", "D", 0), ("D", "V", 0)} <= sampled
    assert ("V", "V", 1) in sampled and ("V", "V", 0) not in sampled  # memory stays one sample back
    pairs = {(frozenset((c, e)), lag) for c, e, lag in sampled}
    one = discover.score([discover.Link("C", "V", 0, 1.0, 0.0)], sampled)
    assert one["precision"] == 1.0 and one["recall"] == pytest.approx(1 / len(pairs))
    findable = simulator_graph.findable(sampled)
    assert all(e in ("V", "L", "D") for _, e, _ in findable)
    assert all(lag == 0 for c, _, lag in findable if c in ("W", "S", "C", "O"))
    assert ("V", "C", 0) not in findable and ("C", "V", 0) in findable
    with pytest.raises(ValueError, match="sampling_steps"):
        simulator_graph.pipeline_truth(0)


def test_the_referees_edge_table_counts_runs_per_edge():
    from socialnav.causal.discover import Discovery, Link
    from socialnav.referee_study import edge_table, found_edges

    links = [Link("V", "L", 0, 0.5, 0.01), Link("C", "C", 1, 0.9, 0.0), Link("V", "D", 0, 0.2, 0.03, oriented=False)]
    found = found_edges(Discovery(links, "parcorr", 0.05, 1, 100, 1.0))
    assert found == {("V", "L", 0), ("C", "C", 1), ("~DV", "", 0)}  # an unoriented pair by its sorted names

    runs = [{("V", "L", 0), ("D", "V", 0)}, {("D", "V", 0), ("~LV", "", 0)}]
    table = edge_table(runs, {("V", "L", 0)}, {("V", "L", 0), ("D", "V", 0)}).set_index("edge")
    assert table.loc["D->V", "found_oriented"] == 2 and not table.loc["D->V", "fig8"] and table.loc["D->V", "simulator"]
    assert table.loc["V->L", "found_oriented"] == 1 and table.loc["V->L", "found_unoriented"] == 1
    assert set(table["runs"]) == {2}


@pytest.mark.slow
def test_referee_command_scores_discovery_against_both_graphs_and_resumes(tmp_path, capsys):
    import pandas as pd

    from socialnav.cli import main

    argv = ["referee", "--out", str(tmp_path / "r"), "--seeds", "0", "--worlds", "2"]  # world 0 alone: no obstacle
    argv += ["--slot-length-s", "60", "--battery-initial-pct", "21", "--do-worlds", "2", "--no-progress"]
    assert main(argv) == 0
    table = pd.read_csv(tmp_path / "r" / "referee.csv")
    assert len(table) == 1 and table.loc[0, "samples"] > 0 and table.loc[0, "simulate_s"] > 0
    for graph in ("fig8", "simulator", "findable"):
        assert 0.0 <= table.loc[0, f"{graph}_precision"] <= 1.0 and table.loc[0, f"{graph}_shd"] >= 0
    edges = pd.read_csv(tmp_path / "r" / "edges.csv").set_index("edge")
    assert edges.loc["O->V", "fig8"] and edges.loc["O->V", "simulator"] and not edges.loc["C(t-1)->C", "fig8"]
    assert "| seed |" in (tmp_path / "r" / "referee.md").read_text()
    do = pd.read_csv(tmp_path / "r" / "do.csv")
    assert len(do) >= 2 and np.all(np.isfinite(do[["engine_do", "simulated_do"]].to_numpy()))
    # Forced faster, the battery drains faster in the simulator (Eq. 1).
    do = do.sort_values("v_mps")
    assert do.simulated_do.iloc[-1] < do.simulated_do.iloc[0]
    # ... and meets obstacles at least as often (V -> O, which the engine's context O does not have)
    assert do.obstacle_share_simulated.iloc[-1] >= do.obstacle_share_simulated.iloc[0]
    assert ((do.seen_share > 0) & (do.seen_share <= 1)).all() and do.obstacle_share_engine.between(0, 1).all()
    capsys.readouterr()
    assert main(argv) == 0  # resumed: the logs and the learned run are kept
    assert np.isnan(pd.read_csv(tmp_path / "r" / "referee.csv").loc[0, "simulate_s"])
    assert main(["referee", "--out", str(tmp_path / "bad"), "--worlds", "0"]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


@pytest.mark.slow
def test_a_forced_speed_is_the_speed_whatever_the_crowd_or_the_obstacle(worlds):
    from socialnav.referee_study import forced_speed_driver

    params, world, driver, state, seeds = worlds
    state = _with_obstacle(params, state)  # every task leg in an obstacle (speed factor 0.5)
    can_move = (np.asarray(state.robot.mode) != CHARGING) & (np.asarray(state.robot.battery_pct) > 0)
    forced = forced_speed_driver(driver)(0.3)
    after, _ = _two_steps(params, world, state, seeds, forced, forced)
    speed = np.asarray(after["V"])
    np.testing.assert_allclose(speed[can_move], 0.3, rtol=1e-6)
    free, _ = _two_steps(params, world, state, seeds, driver, driver)
    assert np.any(np.asarray(free["V"])[can_move] < 0.29)  # unforced: the obstacle and the crowd slow it
