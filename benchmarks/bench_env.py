"""The environment's throughput with a trivial actor, beside social-jym's in the same run.

    python benchmarks/bench_env.py                               # ours only
    python benchmarks/bench_env.py --social-jym /path/to/peer    # and social-jym's SocialNav

The scene is social-jym's circular crossing: 10 people on a 7 m circle, each walking to the
opposite point at 1 m/s, the robot crossing the circle from (0, -7) to (0, 7) driven straight at
its goal (:func:`planners.actors.go_to_goal`); ours has a 20 m square room's four walls around
it (social-jym's has none). An env-step is one robot step of 0.1 s with every person moved.
Prints env-steps per second (batch x steps / wall time, compilation excluded, best of
``--repeats``) at each batch, and the machine.

The peer (``--social-jym``: a folder holding the packages ``socialjym``, ``jsfm``, ``jhsfm`` and
``jorca`` from github.com/TommasoVandermeer/social-jym and its three submodules) runs the same
episode in its ``SocialNav`` env: unicycle robot, 10 humans by its default model, the headed
social force (``humans_policy='hsfm'``; JHSFM and JORCA at the commits social-jym pins; JSFM's
pinned commit is not public any more and its newest fails on this JAX), ``robot_dt = humans_dt
= 0.1`` (one human substep per env-step, as ours); its own scripts use ``robot_dt = 0.25,
humans_dt = 0.01`` (25 substeps per env-step of 0.25 s), shown on a second line.
"""

from __future__ import annotations

import argparse
import json
import math
import pathlib
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402

from benchmarks.bench_simulator import machine  # noqa: E402
from benchmarks.record import record  # noqa: E402
from socialnav.jaxsim.scenes import env as env_lib  # noqa: E402
from socialnav.jaxsim.scenes.actor import rollout  # noqa: E402
from socialnav.jaxsim.scenes.spec import load_scene  # noqa: E402
from socialnav.jaxsim.scenes.variant import sample_variants  # noqa: E402
from socialnav.planners import actors  # noqa: E402

N_PEOPLE = 10
RADIUS_M = 7.0


def circular_crossing(folder: pathlib.Path) -> pathlib.Path:
    """Our scene file of social-jym's circular crossing (10 people; angles jittered per variant)."""
    people = []
    for k in range(N_PEOPLE):
        a = 2 * math.pi * (k + 0.25) / N_PEOPLE  # none on the robot's start or goal
        jitter = 0.1
        people.append(
            {
                "behaviour": "walk",
                "from": [[RADIUS_M * math.cos(a) - jitter, RADIUS_M * math.cos(a) + jitter], RADIUS_M * math.sin(a)],
                "to": [-RADIUS_M * math.cos(a), -RADIUS_M * math.sin(a)],
                "speed_mps": 1.0,
            }
        )
    scene = {
        "name": "circular_crossing",
        "source": "social-jym's circular crossing scenario, 10 people on a 7 m circle",
        "bounds_m": [-10, 10, -10, 10],
        "walls": [[-10, 10, -10, -9.9], [-10, 10, 9.9, 10], [-10, -9.9, -10, 10], [9.9, 10, -10, 10]],
        "robot": {"start": [0.0, -RADIUS_M], "yaw_deg": 90, "goal": [0.0, RADIUS_M]},
        "timeout_s": 30,
        "people": people,
        "rule": {"type": "min_distance", "distance_m": 0.45},
    }
    path = folder / "circular_crossing.json"
    path.write_text(json.dumps(scene))
    return path


def best_time(fn, args, repeats: int) -> tuple[float, float]:
    """``(best wall s of repeats, first call's wall s)``: the first call compiles."""
    t0 = time.perf_counter()
    jax.block_until_ready(fn(*args))
    first_s = time.perf_counter() - t0
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        jax.block_until_ready(fn(*args))
        times.append(time.perf_counter() - t0)
    return min(times), first_s


def ours(batches, steps: int, repeats: int) -> dict[int, float]:
    with tempfile.TemporaryDirectory() as tmp:
        spec = load_scene(circular_crossing(pathlib.Path(tmp)))
    env = env_lib.make_env(spec, env_lib.EnvConfig(max_steps=steps))
    actor = actors.go_to_goal()

    @jax.jit
    def run(env, variants, keys):
        def one(v, k):
            (state, _), records = rollout(env, actor, env.robot, v, k, record=lambda o, a, s, t: t.reward)
            return state.robot.xy, records.sum()

        return jax.vmap(one)(variants, keys)

    rates = {}
    for b in batches:
        variants = jax.tree_util.tree_map(jnp.asarray, sample_variants(spec, 0, b))
        keys = jax.random.split(jax.random.key(0), b)
        t, first_s = best_time(run, (env, variants, keys), repeats)
        rates[b] = b * steps / t
        record("env", "env-steps/s", rates[b], "env-steps/s", compile_s=first_s - t, batch=b, steps=steps)
    return rates


def social_jym(folder: pathlib.Path, batches, steps: int, repeats: int, robot_dt: float, humans_dt: float):
    sys.path.insert(0, str(folder))
    from socialjym.envs.socialnav import SocialNav
    from socialjym.utils.rewards.socialnav_rewards.dummy_reward import DummyReward

    env = SocialNav(
        robot_radius=0.3,
        robot_dt=robot_dt,
        humans_dt=humans_dt,
        scenario="circular_crossing",
        n_humans=N_PEOPLE,
        reward_function=DummyReward(kinematics="unicycle"),
        humans_policy="hsfm",
        kinematics="unicycle",
        circle_radius=RADIUS_M,
    )

    def episode(key):
        state, _, _, info, _ = env.reset(key)

        def body(carry, _):
            state, info = carry
            robot = state[-1]
            to_goal = info["robot_goal"] - robot[:2]
            error = jnp.arctan2(to_goal[1], to_goal[0]) - robot[4]
            error = jnp.arctan2(jnp.sin(error), jnp.cos(error))
            action = jnp.array([jnp.clip(jnp.cos(error), 0.0, 1.0), jnp.clip(2.0 * error, -1.0, 1.0)])
            state, _, info, reward, _, _ = env.step(state, info, action)
            return (state, info), reward

        (state, _), rewards = jax.lax.scan(body, (state, info), None, length=steps)
        return state[-1, :2], rewards.sum()

    run = jax.jit(jax.vmap(episode))
    rates = {}
    for b in batches:
        keys = jax.random.split(jax.random.PRNGKey(0), b)
        rates[b] = b * steps / best_time(run, (keys,), repeats)[0]
    return rates


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--batches", type=int, nargs="+", default=[1, 64, 1024])
    parser.add_argument("--steps", type=int, default=100, help="env-steps per episode (default 100)")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--social-jym", type=pathlib.Path, default=None, help="folder of the peer's packages")
    args = parser.parse_args()
    print(machine())
    print(f"circular crossing, {N_PEOPLE} people, trivial actor, {args.steps} env-steps of 0.1 s per episode")
    rows = [("socialnav (ours)", ours(args.batches, args.steps, args.repeats))]
    if args.social_jym is not None:
        for label, robot_dt, humans_dt in (("1 substep", 0.1, 0.1), ("25 substeps", 0.25, 0.01)):
            rates = social_jym(args.social_jym, args.batches, args.steps, args.repeats, robot_dt, humans_dt)
            rows.append((f"social-jym HSFM, {label}", rates))
    print(f"{'env-steps/s at batch':30s}" + "".join(f"{b:>14d}" for b in args.batches))
    for name, rates in rows:
        print(f"{name:30s}" + "".join(f"{rates[b]:14,.0f}" for b in args.batches))


if __name__ == "__main__":
    main()
