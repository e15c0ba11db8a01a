"""Seed 000's discovery refereed by the simulator's own graph: the study ``socialnav referee``
runs (its module docstring says what is measured and written).

For each seed the warehouse is simulated once (:func:`jaxsim.logs.simulate_to_parquet`), ``socialnav
learn``'s pipeline runs on its first ``n`` worlds for each ``n``, and each discovery is scored
against the paper's Fig. 8, the simulator's graph at the run's period and the part of it J-PCMCI+
can return; the engine's do()-queries are set beside the simulator's forced-speed interventions.
It lives here, in the composition root, because it joins the causal pipeline to the simulator,
two parts that do not import each other.
"""

from __future__ import annotations

import json
import pathlib
import time

DO_HOURS = 2.0  # simulated per forced speed, from 08:00


class StudyError(ValueError):
    """A seed's logs could not be learned from (the message names the seed and world count)."""


def edge_name(c: str, e: str, lag: int) -> str:
    """``C(t-lag)->E``, or ``C->E`` at lag 0."""
    return f"{c}(t-{lag})->{e}" if lag else f"{c}->{e}"


def found_edges(discovery) -> set:
    """The edges a discovery (:class:`causal.discover.Discovery`) found: ``(cause, effect, lag)``
    for each oriented link, ``("~" + the two names sorted, "", 0)`` for each unoriented one."""
    found = {(k.cause, k.effect, k.lag) for k in discovery.links if k.oriented}
    return found | {("~" + "".join(sorted((k.cause, k.effect))), "", 0) for k in discovery.links if not k.oriented}


def run_study(out: pathlib.Path, scenario, seeds, worlds, duration_s: float, do_worlds: int = 8,
              progress: bool = True, say=print) -> dict:  # fmt: skip
    """The study into ``out``: a seed's logs in ``out/seed<seed>``, each learn in ``learn_w<n>``
    below it (both kept, so a stopped study resumes), then ``referee.csv``, ``do.csv``,
    ``edges.csv`` and ``referee.md``.

    Args:
      scenario: the warehouse (:func:`jaxsim.scenario.load_scenario`).
      seeds: simulation seeds; worlds: world counts learned from (each seed simulates the largest).
      duration_s: simulated from 08:00.
      do_worlds: simulated worlds per forced speed (0: no do()-queries).
      progress: the simulation's progress bar; say: where the one-line-a-run reports go.

    Returns:
      ``{"referee": ..., "edges": ..., "do": ...}``, the three tables (pandas).

    Raises:
      StudyError: a seed's logs could not be learned from.
    """
    import pandas as pd

    from socialnav.causal import discover, simulator_graph
    from socialnav.causal.extract import LogError
    from socialnav.causal.learn import learn
    from socialnav.causal.variables import GROUND_TRUTH
    from socialnav.common.atomic import write_text_atomic
    from socialnav.jaxsim import logs
    from socialnav.jaxsim.route_follower import route_follower
    from socialnav.jaxsim.world import build_world
    from socialnav.planners.warehouse.routes import shortest_path_plan

    n_worlds = max(worlds)
    out = pathlib.Path(out)
    out.mkdir(parents=True, exist_ok=True)
    world = build_world(scenario)
    driver = route_follower(shortest_path_plan(scenario), world)
    rows, found_by_run = [], []
    for seed in seeds:
        logs_dir = out / f"seed{seed}"
        t0 = time.perf_counter()
        if not (logs_dir / "run.json").is_file():
            logs.simulate_to_parquet(scenario, logs_dir, driver, n_worlds=n_worlds, duration_s=duration_s, seed=seed,
                                     progress=progress)  # fmt: skip
            simulate_s = time.perf_counter() - t0
        else:
            simulate_s = float("nan")  # simulated by an earlier call
        for n in sorted(set(worlds)):
            learned = logs_dir / f"learn_w{n}"
            if not (learned / "report.json").is_file():
                try:
                    learn(logs_dir, learned, worlds=list(range(n)), progress=False)
                except LogError as e:
                    raise StudyError(f"seed {seed}, {n} world(s): {e}") from None
            report = json.loads((learned / "report.json").read_text())
            found = discover.Discovery.load(learned / "discovery.json")
            sampled = simulator_graph.pipeline_truth(simulator_graph.sampling_steps(report["period_s"]))
            scores = {
                "fig8": discover.score(found.links, GROUND_TRUTH),
                "simulator": discover.score(found.links, sampled),
                "findable": discover.score(found.links, simulator_graph.findable(sampled)),
            }
            row = {
                "seed": seed,
                "worlds": n,
                "samples": report["samples"],
                "period_s": report["period_s"],
                "simulate_s": round(simulate_s, 1),
                "discover_s": round(report["timings"]["discover_s"], 1),
                "learn_s": round(report["timings"]["total_s"], 1),
            }
            for name, s in scores.items():
                row |= {f"{name}_precision": s["precision"], f"{name}_recall": s["recall"], f"{name}_shd": s["shd"]}
            rows.append(row)
            found_by_run.append(found_edges(found))
            said = "; ".join(
                f"{name} P {sc['precision']:.2f} R {sc['recall']:.2f} SHD {sc['shd']}" for name, sc in scores.items()
            )
            say(f"seed {seed}, {n} world(s): {said}; discovery {row['discover_s']:.0f} s")
    table = pd.DataFrame(rows)
    write_text_atomic(out / "referee.csv", table.to_csv(index=False))
    do_rows = []
    if do_worlds:
        from socialnav.causal.engine import CausalEngine

        fewest = min(worlds)
        for seed in seeds:
            engine = CausalEngine.load(out / f"seed{seed}" / f"learn_w{fewest}")
            do_rows += do_check(engine, scenario.params, world, driver, do_worlds, seed, fewest)
            say(f"seed {seed}: the engine's do()-queries against forced speeds in the simulator")
    do_table = pd.DataFrame(do_rows)
    write_text_atomic(out / "do.csv", do_table.to_csv(index=False))
    edges = edge_table(
        found_by_run,
        GROUND_TRUTH,
        simulator_graph.pipeline_truth(simulator_graph.sampling_steps(float(table.period_s.iloc[0]))),
    )
    write_text_atomic(out / "edges.csv", edges.to_csv(index=False))
    markdown = markdown_table(table) + "\n" + markdown_table(edges)
    write_text_atomic(out / "referee.md", markdown + ("\n" + markdown_table(do_table) if do_rows else ""))
    return {"referee": table, "edges": edges, "do": do_table}


def edge_table(found_by_run: list[set], fig8, simulator):
    """Every edge in either graph or found in any run, in which graph it is, how often found."""
    import pandas as pd

    candidates = set(fig8) | set(simulator)
    for found in found_by_run:
        candidates |= {t for t in found if t[1]}
    rows = []
    for c, e, lag in sorted(candidates):
        oriented = sum((c, e, lag) in found for found in found_by_run)
        unoriented = sum(lag == 0 and ("~" + "".join(sorted((c, e))), "", 0) in found for found in found_by_run)
        rows.append(
            {
                "edge": edge_name(c, e, lag),
                "fig8": (c, e, lag) in fig8,
                "simulator": (c, e, lag) in simulator,
                "found_oriented": oriented,
                "found_unoriented": unoriented,
                "runs": len(found_by_run),
            }
        )
    return pd.DataFrame(rows)


def markdown_table(frame) -> str:
    """A GitHub table (no tabulate needed)."""
    cells = [[f"{v:.2f}" if isinstance(v, float) else str(v) for v in row] for row in frame.itertuples(index=False)]
    lines = ["| " + " | ".join(frame.columns) + " |", "|" + "---|" * len(frame.columns)]
    return "\n".join(lines + ["| " + " | ".join(r) + " |" for r in cells]) + "\n"


def forced_speed_driver(driver):
    """``driver`` (the route follower) with its command's speed forced: params ``(driver's params,
    v)``, v () m/s, traced (one compiled program for every speed)."""
    import jax.numpy as jnp

    from socialnav.jaxsim.actor import Actor, Driver

    inner = driver.actor

    def act(params, state, obs, key):
        command, state = inner.act(params[0], state, obs, key)
        return command.replace(speed_mps=params[1], force_speed=jnp.array(True)), state

    actor = Actor(init=inner.init, act=act, name="forced")
    return lambda v: Driver(actor=actor, params=(driver.params, jnp.float32(v)))


def mean_interval(values, mask) -> tuple[float, float]:
    """Mean over worlds of each world's mean of ``values[mask]`` (worlds, periods), with the
    half-width of its 95 % t-interval."""
    import numpy as np
    from scipy import stats

    per_world = np.array([values[w][mask[w]].mean() for w in range(len(values)) if mask[w].any()])
    if len(per_world) < 2:
        return (float(per_world.mean()) if len(per_world) else float("nan")), float("nan")
    half = stats.t.ppf(0.975, len(per_world) - 1) * per_world.std(ddof=1) / np.sqrt(len(per_world))
    return float(per_world.mean()), float(half)


def do_check(engine, params, world, driver, n_worlds: int, seed: int, worlds: int) -> list[dict]:
    """One row per speed bin: the engine's do() and conditional answers and the simulator's
    interventional mean of L (per sampling period, C = 0) with its 95 % interval over worlds."""
    import numpy as np

    from socialnav.jaxsim import rollout

    period_steps = max(1, round(engine.period_s / params.dt_s))
    n_steps = int(DO_HOURS * 3600 / params.dt_s) // period_steps * period_steps
    forced = forced_speed_driver(driver)
    rows = []
    for k, v in enumerate(engine.bins["V"].means):
        _, rec = rollout.rollout(params, world, forced(float(v)), 10_000 + seed, n_worlds, n_steps, period_steps)
        battery = np.asarray(rec.battery_pct, np.float64)
        charging = np.asarray(rec.charging, bool)
        obstacle = np.asarray(rec.obstacle, bool)
        change = np.diff(battery, axis=1)  # L_t = B_t - B_{t-1} over one period
        keep = ~charging[:, 1:]
        clear = keep & ~obstacle[:, 1:] & ~obstacle[:, :-1]
        mean, half = mean_interval(change, keep)
        mean_clear, half_clear = mean_interval(change, clear)
        sustained = engine.battery_do(k, 0)
        engine_do = sustained.value
        rows.append(
            {
                "seed": seed,
                "worlds": worlds,
                "speed_bin": k,
                "v_mps": round(float(v), 3),
                "engine_do": engine_do,
                "engine_do_one_step": engine.battery_do(k, 0, sustained=False).value,
                "engine_do_pyagrum": engine.expected_battery_do_pyagrum(k, 0),
                "seen_share": sustained.seen_share,
                "engine_given": engine.expected_battery_given(k),
                "simulated_do": mean,
                "simulated_lo": mean - half,
                "simulated_hi": mean + half,
                "inside": abs(engine_do - mean) <= half,
                "obstacle_share_engine": engine.obstacle_share(0),
                "obstacle_share_simulated": float(obstacle[:, 1:][keep].mean()),
                "engine_do_no_obstacle": engine.battery_do(k, 0, obstacle=0).value,
                "simulated_no_obstacle": mean_clear,
                "simulated_no_obstacle_half": half_clear,
            }
        )
    return rows
