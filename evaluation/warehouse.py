"""Seed 000's evaluation (Sec. 5.2-5.4): causal planner vs shortest-path baseline, many replicas.

:func:`run_evaluation` plays every slot's experiment (:mod:`evaluation.protocol`) for
``replicas`` independent replicas with both methods, the same keys for both (common random
numbers), and returns one row per task; :func:`write_report` writes the tables, tests and figures.

    from socialnav.jaxsim.scenario import load_scenario
    from socialnav.evaluation import warehouse
    from socialnav.planners.warehouse.tables import CausalTables
    scenario = load_scenario()
    tables = CausalTables.load("runs/warehouse/causal/engine_tables.npz")
    result = warehouse.run_evaluation(scenario, tables, replicas=32)
    warehouse.write_report(result, scenario, "runs/warehouse/evaluation")
"""

from __future__ import annotations

import dataclasses
import json
import pathlib
import time

import numpy as np
import pandas as pd

from socialnav.common import progress as progress_lib
from socialnav.common.atomic import write_atomic, write_bytes_atomic, write_text_atomic
from socialnav.evaluation import metrics
from socialnav.evaluation import protocol as ex
from socialnav.evaluation.outcomes import OUTCOMES
from socialnav.jaxsim.actor import Driver
from socialnav.jaxsim.route_follower import route_follower
from socialnav.jaxsim.scenario import Scenario
from socialnav.jaxsim.world import RobotPlan, World, build_world
from socialnav.planners.warehouse.actors import causal_planner
from socialnav.planners.warehouse.routes import shortest_path_plan
from socialnav.planners.warehouse.tables import CausalTables
from socialnav.planners.warehouse.waypoint import MIN_BATTERY_PCT, CausalWeights, causal_plan

METHODS = ("baseline", "causal")


@dataclasses.dataclass
class EvaluationResult:
    """What :func:`run_evaluation` measured.

    Attributes:
      tasks: one row per task (columns in :mod:`evaluation.metrics`), with ``slot_name``,
        ``start``, ``goal`` waypoint names.
      distance_hist: method -> (n_slots, replicas, H) robot-person distance counts during tasks.
      experiment_s: method -> (n_slots, replicas) simulated time from the first task to the last
        task's end.
      distance_bin_m: histogram bin width.
      wall_s: method -> wall-clock seconds (compilation included).
      plans: method -> its :class:`~jaxsim.world.RobotPlan` (for pictures of routes).
      density_ppm2: (S, W) the engine's E[D | do(S), W] the causal planner used.
      config: the protocol settings and sizes, JSON-ready.
    """

    tasks: pd.DataFrame
    distance_hist: dict[str, np.ndarray]
    experiment_s: dict[str, np.ndarray]
    distance_bin_m: float
    wall_s: dict[str, float]
    plans: dict
    density_ppm2: np.ndarray
    config: dict


def method_plans(
    scenario: Scenario, tables: CausalTables, weights: CausalWeights = CausalWeights(), speed_mps: float | None = None
) -> dict[str, tuple[RobotPlan, np.ndarray | None]]:
    """The two methods' routes: shortest path, and causal (Eq. 8-9) with its routes' predicted
    battery use ``C_L`` (Eq. 10)."""
    speed = scenario.params.robot_max_speed_mps if speed_mps is None else speed_mps
    plan, cost = causal_plan(scenario, tables, speed_mps=speed, weights=weights)
    return {"baseline": (shortest_path_plan(scenario), None), "causal": (plan, cost)}


def build_methods(
    plans: dict[str, tuple[RobotPlan, np.ndarray | None]], world: World, min_battery_pct: float = MIN_BATTERY_PCT
) -> dict[str, Driver]:
    """The methods as warehouse actors: a plan without a cost table is followed (the shortest
    path never refuses), one with its table is the causal planner (Eq. 10 below
    ``min_battery_pct``)."""
    return {
        name: route_follower(plan, world) if cost is None else causal_planner(plan, world, cost, min_battery_pct)
        for name, (plan, cost) in plans.items()
    }


def task_table(
    scenario: Scenario, state: ex.ExperimentState, method: str, slots: np.ndarray, replicas: np.ndarray
) -> pd.DataFrame:
    """Rows of every task run in a batch of experiments (host arrays of :func:`run_experiments`)."""
    log = state.log
    ran = log.outcome >= 0
    b_idx, k_idx = np.nonzero(ran)
    ids = np.asarray(scenario.waypoint_ids)
    return pd.DataFrame(
        {
            "method": method,
            "slot": slots[b_idx].astype(np.int32),
            "slot_name": np.asarray(scenario.slot_names)[slots[b_idx]],
            "replica": replicas[b_idx].astype(np.int32),
            "task": k_idx.astype(np.int32),
            "start": ids[log.start_wp[b_idx, k_idx]],
            "goal": ids[log.goal_wp[b_idx, k_idx]],
            "outcome": pd.Categorical.from_codes(log.outcome[b_idx, k_idx], categories=list(OUTCOMES)),
            "refused": log.refused[b_idx, k_idx],
            "time_s": log.time_s[b_idx, k_idx],
            "stalled_s": log.stalled_s[b_idx, k_idx],
            "distance_m": log.distance_m[b_idx, k_idx],
            "planned_m": log.planned_m[b_idx, k_idx],
            "battery_used_pct": log.battery_used_pct[b_idx, k_idx],
            "collisions": log.collisions[b_idx, k_idx],
        }
    )


def run_evaluation(
    scenario: Scenario,
    tables: CausalTables,
    replicas: int = 32,
    slots=None,
    seed: int = 0,
    cfg: ex.ProtocolConfig | None = None,
    weights: CausalWeights = CausalWeights(),
    segment_s: float = 600.0,
    progress: bool = True,
    first_replica: int = 0,
) -> EvaluationResult:
    """Both methods on every slot's experiment, ``replicas`` times, with common random numbers.

    Args:
      tables: the causal engine's tables (:meth:`CausalTables.load` of ``engine_tables.npz``).
      replicas: independent replicas of the whole protocol (>= 1).
      first_replica: the first replica's index (a shard of a larger run: replica ``r`` is the same
        experiment whichever shard runs it; :func:`merge` joins shards).
      slots: slot indices to run (default all).
      cfg: protocol settings (default :meth:`~evaluation.protocol.ProtocolConfig.for_params`).
    """
    if replicas < 1:
        raise ValueError(f"replicas must be >= 1, got {replicas}")
    p = scenario.params
    cfg = ex.ProtocolConfig.for_params(p) if cfg is None else cfg
    slot_ids = np.arange(scenario.n_slots) if slots is None else np.asarray(sorted(set(slots)), np.int32)
    if slot_ids.size == 0 or slot_ids.min() < 0 or slot_ids.max() >= scenario.n_slots:
        raise ValueError(f"slots must be in [0, {scenario.n_slots - 1}], got {slots}")
    world = build_world(scenario)
    plans = method_plans(scenario, tables, weights)
    methods = build_methods(plans, world, cfg.min_battery_pct)
    # Batch order: replica-major, so a slot's experiments spread over the devices evenly.
    rep_grid, slot_grid = np.meshgrid(np.arange(first_replica, first_replica + replicas), slot_ids, indexing="ij")
    b_slots, b_reps = slot_grid.ravel().astype(np.int32), rep_grid.ravel().astype(np.int32)
    keys = ex.experiment_keys(seed, b_slots, b_reps)

    frames, hists, spans, walls = [], {}, {}, {}
    for name, method in methods.items():
        start = time.perf_counter()
        with progress_lib.bar(f"{name:>8}", unit="task", enabled=progress) as bar:
            state = ex.run_experiments(p, world, method, b_slots, keys, cfg, segment_s=segment_s, progress=bar.update)
        walls[name] = time.perf_counter() - start
        frames.append(task_table(scenario, state, name, b_slots, b_reps))
        shape = (replicas, len(slot_ids))
        hists[name] = state.distance_hist.reshape(shape + (-1,)).transpose(1, 0, 2)
        spans[name] = ((state.end_step - cfg.warmup_steps(p)) * p.dt_s).reshape(shape).T
    config = {
        "replicas": replicas,
        "slots": [scenario.slot_names[s] for s in slot_ids],
        "seed": seed,
        "protocol": dataclasses.asdict(cfg),
        "weights": dataclasses.asdict(weights),
        "deadline_s": p.robot_leg_deadline_s,
        "obstacle_probability": p.robot_obstacle_probability,
    }
    return EvaluationResult(
        tasks=pd.concat(frames, ignore_index=True),
        distance_hist=hists,
        experiment_s=spans,
        distance_bin_m=cfg.distance_bin_m,
        wall_s=walls,
        plans={name: plan for name, (plan, _) in plans.items()},
        density_ppm2=tables.density_ppm2,
        config=config,
    )


def merge(parts: list[EvaluationResult]) -> EvaluationResult:
    """One result from shards of replicas (in replica order): tasks concatenated, histograms and
    spans joined along the replica axis, wall times added."""
    first = parts[0]
    if len(parts) == 1:
        return first
    names = list(first.distance_hist)
    return dataclasses.replace(
        first,
        # method-major, then replica order: the rows of one run of every replica
        tasks=pd.concat([r.tasks for r in parts], ignore_index=True)
        .sort_values("method", key=lambda m: m.map(METHODS.index), kind="stable")
        .reset_index(drop=True),
        distance_hist={m: np.concatenate([r.distance_hist[m] for r in parts], axis=1) for m in names},
        experiment_s={m: np.concatenate([r.experiment_s[m] for r in parts], axis=1) for m in names},
        wall_s={m: sum(r.wall_s[m] for r in parts) for m in names},
        config={**first.config, "replicas": sum(r.config["replicas"] for r in parts)},
    )


def per_slot_table(result: EvaluationResult) -> pd.DataFrame:
    """Per method and slot: means over replicas of the outcome counts, success %, collisions
    (with 95 % intervals), time and distance components."""
    runs = metrics.per_run(result.tasks, by=("method", "slot", "slot_name", "replica"))
    rows = []
    for (method, _slot, slot_name), g in runs.groupby(["method", "slot", "slot_name"], sort=True):
        row = {"slot": slot_name, "method": method, "tasks": g["tasks"].mean()}
        for col in ("success_pct", "collisions"):
            m, lo, hi = metrics.mean_ci(g[col])
            row[col] = m
            row[f"{col}_ci"] = f"[{lo:.1f}, {hi:.1f}]"
        for col in ("congestion", "battery", "refused", "wasted_km", "wasted_h"):
            row[col] = g[col].mean()
        rows.append(row)
    table = pd.DataFrame(rows)
    order = {name: i for i, name in enumerate(result.config["slots"])}
    return table.sort_values(
        ["slot", "method"], key=lambda s: s.map(order) if s.name == "slot" else s, ignore_index=True
    )


def overall(result: EvaluationResult) -> dict:
    """The headline per method (means and 95 % intervals over runs) and the statistical tests."""
    runs = metrics.per_run(result.tasks)
    ci = metrics.summary_with_ci(runs)
    head = {}
    for method, g in ci.groupby("method", sort=False):
        head[method] = {r.metric: {"mean": r.mean, "ci95": [r.ci_low, r.ci_high]} for r in g.itertuples()}
    hist = {m: h.sum(axis=(0, 1)) for m, h in result.distance_hist.items()}
    for m, h in hist.items():
        head[m]["distance_quantiles_m"] = dict(
            zip(["q05", "q25", "q50", "q75", "q95"], metrics.hist_quantiles(h, result.distance_bin_m).tolist())
        )
        head[m]["hall_zone_shares"] = metrics.zone_shares(h, result.distance_bin_m)
        head[m]["tasks_per_run"] = float(runs[runs["method"] == m]["tasks"].mean())
    tests = metrics.compare(result.tasks, hist, result.distance_bin_m) if set(METHODS) <= set(hist) else {}
    return {"per_method": head, "tests": tests, "config": result.config, "wall_s": result.wall_s}


def write_report(result: EvaluationResult, scenario: Scenario, out_dir: str | pathlib.Path) -> list[pathlib.Path]:
    """Write tasks.parquet, distance_hist.npz, per_slot.csv, summary.json and the figures.

    Every file is written to a temporary name and renamed, so an interrupted report leaves no
    half-written file.
    """
    from socialnav.evaluation import plots

    out = pathlib.Path(out_dir)
    table = per_slot_table(result)
    summary = overall(result)
    return [
        write_atomic(out / "tasks.parquet", lambda f: result.tasks.to_parquet(f, index=False)),
        write_bytes_atomic(
            out / "distance_hist.npz", lambda h: np.savez(h, bin_m=result.distance_bin_m, **result.distance_hist)
        ),
        write_atomic(out / "per_slot.csv", lambda f: table.to_csv(f, index=False, float_format="%.3f")),
        write_text_atomic(out / "summary.json", json.dumps(summary, indent=1, default=_json_default)),
        plots.efficiency_figure(result, out / "fig9_efficiency.png"),
        plots.safety_figure(result, out / "fig10_safety.png"),
        plots.route_figure(result, scenario, out / "fig11_routes.png"),
    ]


def _json_default(x):
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, (np.floating,)):
        return float(x)
    if isinstance(x, np.ndarray):
        return x.tolist()
    raise TypeError(f"not JSON serialisable: {type(x)}")


def format_overall(summary: dict) -> str:
    """The headline as text (one line per metric, both methods side by side)."""
    pm = summary["per_method"]
    names = [m for m in METHODS if m in pm]
    lines = [f"{'per run (mean [95% CI])':<22}" + "".join(f"{m:>28}" for m in names)]
    for metric, fmt in (
        ("success_pct", "{:.1f}"),
        ("congestion", "{:.1f}"),
        ("battery", "{:.2f}"),
        ("refused", "{:.2f}"),
        ("collisions", "{:.1f}"),
        ("wasted_distance_pct", "{:.1f}"),
        ("wasted_time_pct", "{:.1f}"),
        ("wasted_battery_pct", "{:.1f}"),
        ("wasted_km", "{:.2f}"),
        ("planned_km", "{:.2f}"),
        ("wasted_h", "{:.2f}"),
        ("effective_cycles", "{:.2f}"),
        ("wasted_cycles", "{:.2f}"),
    ):
        cells = []
        for m in names:
            v = pm[m][metric]
            cells.append(f"{fmt.format(v['mean'])} [{fmt.format(v['ci95'][0])}, {fmt.format(v['ci95'][1])}]")
        lines.append(f"{metric:<22}" + "".join(f"{c:>28}" for c in cells))
    for m in names:
        q = pm[m]["distance_quantiles_m"]
        lines.append(f"robot-person distance {m}: median {q['q50']:.2f} m, IQR [{q['q25']:.2f}, {q['q75']:.2f}] m")
    for name, t in summary["tests"].items():
        lines.append(f"test {name:<26} {t['test']:<24} p = {t['p_value']:.3g}")
    return "\n".join(lines)
