"""How often people end a step inside a wall as the simulation step grows: the measurement behind
``jaxsim.params.WORKER_STEP_MAX_M`` (the warehouse) and docs/robustness.md's round five (the arena).

    python scripts/walls_at_longer_steps.py warehouse 0.1 0.125 0.15 0.2 --past-the-bound   # sim.dt_s, ~1 min each
    python scripts/walls_at_longer_steps.py arena 0.1 0.25 0.5                               # EnvConfig.dt_s

``warehouse``: the shipped warehouse, 4 worlds x 30 min (10-minute slots), the robot following
the shortest-path planner; every worker's centre sampled about once a second against the wall
boxes, and the robot's. ``arena``: 32 variants each of the L-hallway, the group and the crowded
entrance with no robot (the arena's counterfactual run), every person's centre at every step.
Prints, per step size, the samples, how many centres lie inside a wall box and the least signed
distance (negative: inside). A step the configuration refuses is reported as refused;
``--past-the-bound`` lifts the warehouse's bound (``WORKER_STEP_MAX_M``) for this process, so that
the steps past it can be measured as they were when it was set.
"""

from __future__ import annotations

import argparse

import numpy as np


def warehouse(dt_s: float) -> str:
    from socialnav.jaxsim import geometry
    from socialnav.jaxsim.rollout import rollout, to_numpy
    from socialnav.jaxsim.route_follower import route_follower
    from socialnav.jaxsim.scenario import ScenarioError, load_scenario
    from socialnav.jaxsim.world import build_world
    from socialnav.planners.warehouse.routes import shortest_path_plan

    try:
        scenario = load_scenario(slot_length_s=600.0, dt_s=dt_s)
    except ScenarioError as e:
        return f"sim.dt_s {dt_s}: refused ({e.field})"
    world = build_world(scenario)
    driver = route_follower(shortest_path_plan(scenario), world)
    n_steps = int(round(1800 / dt_s))
    every = max(1, int(round(1.0 / dt_s)))
    while n_steps % every:
        every -= 1
    _, records = rollout(scenario.params, world, driver, seed=0, n_worlds=4, n_steps=n_steps, sample_every_steps=every)
    records = to_numpy(records)
    walls = np.asarray(scenario.boxes_m)
    workers = geometry.box_signed_distance(records.worker_x_m.ravel(), records.worker_y_m.ravel(), walls)[0]
    robot = geometry.box_signed_distance(records.robot_x_m.ravel(), records.robot_y_m.ravel(), walls)[0]
    return (
        f"sim.dt_s {dt_s}: worker samples {workers.size:,}, inside a wall {int((workers < 0).sum()):,}, "
        f"least distance {workers.min():.3f} m; the robot's least distance {robot.min():.3f} m"
    )


def arena(dt_s: float) -> str:
    import jax
    import jax.numpy as jnp

    from socialnav.data import SCENES_DIR
    from socialnav.evaluation.arena import episodes
    from socialnav.jaxsim.scenes import env as env_lib
    from socialnav.jaxsim.scenes.spec import load_scene
    from socialnav.jaxsim.scenes.variant import sample_variants
    from socialnav.jaxsim.scenes.world import wall_distance

    lines = []
    for scene in ("gscl_l_hallway", "gscl_group", "gscl_crowded_entrance"):
        spec = load_scene(SCENES_DIR / f"{scene}.json")
        try:
            setup = episodes.setup_scene(spec, episodes.ArenaConfig(env=env_lib.EnvConfig(dt_s=dt_s)))
        except ValueError as e:
            lines.append(f"{scene} EnvConfig.dt_s {dt_s}: refused ({str(e).split(':')[0]})")
            continue
        variants = jax.tree_util.tree_map(jnp.asarray, sample_variants(spec, 0, 32, 0, False, setup.n_slots))
        run = episodes.counterfactual_function(setup)(variants)
        xy = np.asarray(run.people_xy_m).reshape(-1, 2)[np.asarray(run.people_present).ravel()]
        to_wall = jax.vmap(lambda p, walls=setup.env.world.walls_m: wall_distance(p, walls)[0])
        distance = np.asarray(to_wall(jnp.asarray(xy)))
        lines.append(
            f"{scene} EnvConfig.dt_s {dt_s}: person samples {distance.size:,}, inside a wall "
            f"{int((distance < 0).sum()):,}, least distance {distance.min():.3f} m"
        )
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("world", choices=("warehouse", "arena"))
    parser.add_argument("dt_s", type=float, nargs="+", help="step sizes (s)")
    parser.add_argument("--past-the-bound", action="store_true", help="lift WORKER_STEP_MAX_M to measure past it")
    args = parser.parse_args()
    if args.past_the_bound:
        from socialnav.jaxsim import params

        params.WORKER_STEP_MAX_M = float("inf")  # read by SimParams.validate when a scenario loads
    for dt_s in args.dt_s:
        print((warehouse if args.world == "warehouse" else arena)(dt_s), flush=True)


if __name__ == "__main__":
    main()
