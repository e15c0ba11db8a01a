"""The social-navigation benchmark's speed on this machine: ``socialnav arena`` itself, timed.

    python benchmarks/bench_arena.py                     # 14 scenes x 11 methods x 100 variants
    python benchmarks/bench_arena.py --held-out          # and every scene's held-out row
    python benchmarks/bench_arena.py --variants 20 --gscl-run runs/gscl
    python benchmarks/bench_arena.py --held-out --summary summary.csv   # and the table it timed
    python benchmarks/bench_arena.py --scenes gscl_group,casn_crossing --variants 20 --skip-profile   # a part of it

Runs the command a user runs (``socialnav arena --held-out`` into a temporary folder, in this
process) with JAX's on-disk compilation cache off, so every program is compiled in the run, as on
a user's first run; prints its wall time (compilation, the files and pictures included),
episodes per second and simulated seconds per wall second. Then where the time goes on one
scene: compilation, one run of each method, and the global planner alone (the same number of
replans as the episodes).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import pathlib
import shutil
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
os.environ["SOCIALNAV_JAX_CACHE"] = "off"  # every program compiled in the run, as on a first run

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402

from benchmarks.bench_simulator import machine  # noqa: E402
from benchmarks.record import record  # noqa: E402
from socialnav import cli  # noqa: E402
from socialnav.cli.arena import DEFAULT_METHODS  # noqa: E402
from socialnav.data import DATA_DIR  # noqa: E402
from socialnav.evaluation.arena import episodes as arena  # noqa: E402
from socialnav.jaxsim.params import TIAGO_RADIUS_M  # noqa: E402
from socialnav.jaxsim.scenes.spec import load_scene  # noqa: E402
from socialnav.jaxsim.scenes.variant import sample_variants  # noqa: E402
from socialnav.planners.layers import costmap  # noqa: E402
from socialnav.planners.reactive.baselines import BASELINES  # noqa: E402
from socialnav.planners.stack import METHODS, global_plan  # noqa: E402


def profile_scene(name: str, variants: int, methods) -> None:
    spec = load_scene(DATA_DIR / "scenes" / f"{name}.json")
    setup = arena.setup_scene(spec)
    crowd = arena.crowd_params()
    batch = jax.tree_util.tree_map(jnp.asarray, sample_variants(spec, 0, variants))
    print(f"profile: {name}, {variants} variants, {setup.n_periods * 10} steps of 0.1 s, grid {setup.grid.shape}")
    for m in methods:
        if m in BASELINES:
            run = arena.baseline_function(setup, m, crowd)
        else:
            run = arena.episode_function(setup, METHODS[m], crowd)
        t0 = time.perf_counter()
        jax.block_until_ready(run(batch))
        first = time.perf_counter() - t0
        t0 = time.perf_counter()
        jax.block_until_ready(run(batch))
        second = time.perf_counter() - t0
        print(f"  {m:<20} compile {first - second:5.1f} s   run {second:5.2f} s")
    # The global planner alone: one replan per second of every episode.
    costs = jnp.broadcast_to(jnp.asarray(setup.obstacle_costs), (variants,) + setup.grid.shape)
    plan = jax.jit(
        jax.vmap(lambda c, s, g: global_plan(METHODS["navfn"], c, s, g, setup.grid, arena.ArenaConfig().max_path_cells))
    )
    starts, goals = jnp.asarray(batch.robot_xy), jnp.asarray(batch.goal_xy)
    jax.block_until_ready(plan(costs, starts, goals))
    t0 = time.perf_counter()
    for _ in range(setup.n_periods):
        jax.block_until_ready(plan(costs, starts, goals))
    print(f"  global planner alone ({setup.n_periods} replans x {variants}): {time.perf_counter() - t0:5.2f} s")
    obstacle = jax.jit(jax.vmap(lambda o: costmap.obstacle_layer(o, setup.grid, TIAGO_RADIUS_M)))
    occ = jnp.broadcast_to(jnp.asarray(setup.occupancy), (variants,) + setup.grid.shape)
    jax.block_until_ready(obstacle(occ))
    t0 = time.perf_counter()
    for _ in range(setup.n_periods):
        jax.block_until_ready(obstacle(occ))
    print(f"  obstacle layer with people, alone ({setup.n_periods} x {variants}): {time.perf_counter() - t0:5.2f} s")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--variants", type=int, default=100)
    parser.add_argument("--scenes", default="", help="comma-separated scene names (default: all built-in)")
    parser.add_argument("--skip-profile", action="store_true", help="only the command, not one scene's profile")
    parser.add_argument("--gscl-run", type=pathlib.Path, default=None)
    parser.add_argument("--profile-only", action="store_true")
    parser.add_argument("--held-out", action="store_true", help="also every scene's held-out row")
    parser.add_argument(
        "--summary", type=pathlib.Path, default=None, help="write the table's summary.csv here (what was timed)"
    )
    args = parser.parse_args()
    print(f"machine: {machine()}")
    if not args.profile_only:
        names = [n for n in args.scenes.split(",") if n] or sorted(p.stem for p in (DATA_DIR / "scenes").glob("*.json"))
        specs = [load_scene(DATA_DIR / "scenes" / f"{n}.json") for n in names]
        rows = 2 if args.held_out else 1
        episodes = len(specs) * rows * len(DEFAULT_METHODS) * args.variants
        simulated = sum(s.timeout_s for s in specs) * rows * len(DEFAULT_METHODS) * args.variants
        with tempfile.TemporaryDirectory() as tmp:
            argv = ["arena", "--out", f"{tmp}/run", "--variants", str(args.variants), "--no-progress"]
            if args.scenes:
                argv += ["--scenes", ",".join(names)]
            if args.held_out:
                argv.append("--held-out")
            if args.gscl_run is not None:
                argv += ["--gscl-run", str(args.gscl_run)]
            t0 = time.perf_counter()
            with contextlib.redirect_stdout(io.StringIO()):  # the command's tables
                code = cli.main(argv)
            wall = time.perf_counter() - t0
            if code != 0:
                sys.exit(f"socialnav {' '.join(argv)} failed ({code})")
            if args.summary is not None:
                shutil.copyfile(f"{tmp}/run/summary.csv", args.summary)
        print(
            f"socialnav arena: {len(specs) * rows} scene rows x {len(DEFAULT_METHODS)} methods x {args.variants} "
            f"variants = {episodes} episodes in {wall / 60:.1f} min: {episodes / wall:.1f} episodes/s, "
            f"{simulated / wall:.0f} simulated s per wall s"
        )
        record("arena", "episodes/s (compilation included)", episodes / wall, "episodes/s", wall_s=round(wall, 1),
               scene_rows=len(specs) * rows, methods=len(DEFAULT_METHODS), variants=args.variants)  # fmt: skip
    if args.skip_profile:
        return
    profile_scene("gscl_group", args.variants, ["navfn", "casn", "snape_social_eband", *BASELINES])


if __name__ == "__main__":
    main()
