"""PPO's training throughput in the arena (planners/learning/policy_training.py), beside published figures.

    python benchmarks/bench_policy.py                     # the 14 built-in scenes, the defaults
    python benchmarks/bench_policy.py --scenes gscl_group --envs-per-scene 256
    python benchmarks/bench_policy.py --social-layer casn          # the cost of an input channel
    python benchmarks/bench_policy.py --social-layer gscl --gscl-run runs/gscl

Builds the trainer, runs ``--warmup`` updates (compilation: one collector per scene and the
update), then times ``--updates`` more. Prints env-steps per second for the whole update
(collect + PPO epochs), the collection alone, and the compile time, with the machine. The
published figures printed beside them are self-reported by their authors on other machines
(``../shared/notes/social-navigation.md``; the issue): CrowdNav_HEIGHT about 1,100 env-steps/s
(2e8 steps in about 50 h, i9-13900K and an RTX 4090), robot_sf 20-25 steps/s (its benchmark
spec; about 1,000 for its PPO per the issue), RelationalGraphLearning 10,000 episodes in about
20 h.
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import jax  # noqa: E402

from benchmarks.bench_simulator import machine  # noqa: E402
from benchmarks.record import record  # noqa: E402
from socialnav.data import SCENES_DIR  # noqa: E402
from socialnav.jaxsim.scenes.spec import load_scene  # noqa: E402
from socialnav.planners.learning import policy_training  # noqa: E402
from socialnav.planners.learning.policy import PolicyConfig  # noqa: E402
from socialnav.planners.learning.policy_social import SOCIAL_LAYERS  # noqa: E402

PUBLISHED = (
    ("CrowdNav_HEIGHT (PPO, 2e8 steps in ~50 h; i9-13900K + RTX 4090)", 1_100),
    ("robot_sf PPO (the issue's figure)", 1_000),
    ("robot_sf benchmark (self-reported steps/s)", 25),
)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", default="", help="comma-separated scene names (default: all built-in)")
    parser.add_argument("--envs-per-scene", type=int, default=64)
    parser.add_argument("--rollout-steps", type=int, default=64)
    parser.add_argument("--warmup", type=int, default=2)
    parser.add_argument("--updates", type=int, default=5)
    parser.add_argument("--social-layer", choices=SOCIAL_LAYERS, default="none")
    parser.add_argument("--gscl-run", type=pathlib.Path, default=None, help="the GSCL run of --social-layer gscl")
    args = parser.parse_args()
    names = [n for n in args.scenes.split(",") if n] or sorted(p.stem for p in SCENES_DIR.glob("*.json"))
    specs = [load_scene(SCENES_DIR / f"{n}.json") for n in names]
    gscl_run = "" if args.gscl_run is None else str(args.gscl_run.resolve())
    policy = PolicyConfig(social_layer=args.social_layer, gscl_run=gscl_run)
    config = policy_training.PPOConfig(
        envs_per_scene=args.envs_per_scene, rollout_steps=args.rollout_steps, policy=policy
    )
    print(machine())
    print(f"social channel: {args.social_layer}" + (f" ({gscl_run})" if gscl_run else ""))
    t0 = time.perf_counter()
    trainer = policy_training.Trainer(specs, config)
    state = trainer.initial_state()
    for _ in range(args.warmup):
        state, _ = trainer.step(state)
    jax.block_until_ready(state.weights)
    setup_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    for _ in range(args.updates):
        state, _ = trainer.step(state)
    jax.block_until_ready(state.weights)
    update_s = (time.perf_counter() - t0) / args.updates
    # The collection alone: every scene's collector once more with the same weights.
    t0 = time.perf_counter()
    for k, (scene, collect) in enumerate(zip(trainer.scenes, trainer._collect, strict=True)):
        out = collect(scene, state.weights, state.runners[k], jax.random.PRNGKey(k))
        jax.block_until_ready(out)
    collect_s = time.perf_counter() - t0
    n = trainer.transitions_per_update
    print(
        f"{len(specs)} scene(s) x {config.envs_per_scene} episodes x {config.rollout_steps} steps = {n:,} "
        f"env-steps per update; set-up and {args.warmup} warm-up update(s) {setup_s:.1f} s"
    )
    what = f"collect + {config.epochs} epochs x {config.minibatches} minibatches"
    print(f"whole update ({what}): {n / update_s:,.0f} env-steps/s")
    print(f"collection alone (policy forward, sampling, env step, resets, GAE): {n / collect_s:,.0f} env-steps/s")
    size = {"scenes": len(specs), "envs_per_scene": config.envs_per_scene, "rollout_steps": config.rollout_steps}
    record("ppo", "env-steps/s (whole update)", n / update_s, "env-steps/s", compile_s=setup_s, **size,
           note=f"compile_s is the set-up and {args.warmup} warm-up update(s)")  # fmt: skip
    record("ppo", "env-steps/s (collection)", n / collect_s, "env-steps/s", **size)
    for name, rate in PUBLISHED:
        print(f"  published, other machine: {name}: about {rate:,} env-steps/s ({n / update_s / rate:,.0f}x)")


if __name__ == "__main__":
    main()
