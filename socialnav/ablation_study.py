"""Seed 000's ablation's data (Sec. 6): the simplified warehouse simulated for every obstacle
probability and seed, handed to the causal pipeline's estimates (:mod:`causal.ablation`).

It lives in the composition root because it joins the simulator to the causal pipeline, two parts
that do not import each other: the causal code never simulates, the simulator never estimates.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from socialnav.causal import ablation as causal_ablation
from socialnav.jaxsim import rollout
from socialnav.jaxsim.params import SimParams
from socialnav.jaxsim.route_follower import route_follower
from socialnav.jaxsim.scenario import load_scenario
from socialnav.jaxsim.world import build_world
from socialnav.planners.warehouse.routes import shortest_path_plan

# What one world holds a sample (one probability, one seed), measured with ``socialnav ablation`` at
# the default hour of 1 s samples: peak resident 3.14 GB at 200 seeds and 10.85 GB at 800 (5
# probabilities each), 714 bytes a world-sample, plus about half a gigabyte of programs and
# libraries (0.73 GB at 8 seeds); the batch's records on the device, their host copy and the float64
# series the estimates read.
BYTES_PER_WORLD_SAMPLE = 720
BASE_BYTES = 0.8e9


def memory_bytes(
    n_probabilities: int, n_seeds: int, duration_s: float = 3600.0, sample_interval_s: float = 1.0
) -> float:
    """What :func:`ablation_series` holds at once (an upper estimate from the measurements above):
    every world of the one batch, ``n_probabilities x n_seeds``, with its whole series."""
    samples = round(duration_s / sample_interval_s)
    return BASE_BYTES + BYTES_PER_WORLD_SAMPLE * n_probabilities * n_seeds * samples


def memory_problem(
    n_probabilities: int, n_seeds: int, duration_s: float = 3600.0, sample_interval_s: float = 1.0
) -> str | None:
    """Why the batch cannot run here (None: it can): it would hold more than 80 % of the memory
    available (:func:`memory_bytes`); the message says how many seeds would fit."""
    from socialnav.common.memory import shortfall, units_that_fit

    needed = memory_bytes(n_probabilities, n_seeds, duration_s, sample_interval_s)
    available = shortfall(needed)
    if available is None:
        return None
    per_seed = memory_bytes(n_probabilities, 1, duration_s, sample_interval_s) - BASE_BYTES
    fits = units_that_fit(available, BASE_BYTES, per_seed)
    return (
        f"{n_probabilities} probabilities x {n_seeds:,} seeds in one batch, {duration_s / 3600:g} h each, hold "
        f"about {needed / 1e9:.1f} GB at once, this machine has {available / 1e9:.1f} GB available; about "
        f"{fits:,} seeds fit"
    )


def ablation_series(
    probabilities,
    n_seeds: int,
    seed: int = 0,
    duration_s: float = 3600.0,
    sample_interval_s: float = 1.0,
    obstacle_length_m: float = causal_ablation.OBSTACLE_LENGTH_M,
) -> dict[float, causal_ablation.Series]:
    """The simplified scenario (no workers) for every obstacle probability and seed, in one
    batched rollout: the probability is a dynamic parameter, so the whole sweep is one ``vmap``
    over stacked params and one compilation. Seed ``k`` has the same world key for every
    probability (common random numbers).

    Returns:
      probability -> its (V, L, O) series, ``(n_seeds, samples)`` each.

    Raises:
      ValueError: the batch would hold more than 80 % of the memory available (:func:`memory_bytes`).
    """
    problem = memory_problem(len(probabilities), n_seeds, duration_s, sample_interval_s)
    if problem:
        raise ValueError(f"ablation_series: {problem}")
    base = load_scenario(n_workers=0, robot_obstacle_length_m=obstacle_length_m)
    settings = [base.params.replace(robot_obstacle_probability=float(p)) for p in probabilities]
    params = SimParams.stack([s for s in settings for _ in range(n_seeds)])
    world = build_world(base)
    controller = route_follower(shortest_path_plan(base), world)
    keys = rollout.world_keys(seed, n_seeds)[jnp.tile(jnp.arange(n_seeds), len(settings))]
    states = rollout.init_batch(params, world, controller, keys, params_batched=True)
    every = int(round(sample_interval_s / base.params.dt_s))
    n_samples = int(round(duration_s / sample_interval_s))
    _, rec = rollout.run_samples(params, world, controller, states, keys, n_samples, every, params_batched=True)
    rec = rollout.to_numpy(rec)
    series = {}
    for i, (p, prm) in enumerate(zip(probabilities, settings, strict=True)):
        rows = slice(i * n_seeds, (i + 1) * n_seeds)
        battery = np.concatenate([np.full((n_seeds, 1), prm.battery_initial_pct), rec.battery_pct[rows]], axis=1)
        series[float(p)] = causal_ablation.Series(
            speed_mps=rec.robot_speed_mps[rows].astype(np.float64),
            battery_change_pct=np.diff(battery.astype(np.float64), axis=1),
            obstacle=rec.obstacle[rows].astype(np.float64),
            battery=prm,
        )
    return series
