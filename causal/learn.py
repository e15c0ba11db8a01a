"""The ``learn`` job: simulator logs in; causal graph, inference engine and a report out.

    socialnav learn --logs runs/warehouse --out runs/warehouse/causal

Writes to ``--out``: ``discovery.json`` (links with lag, direction, strength, p-value),
``causal_graph.png`` (like seed 000 Fig. 8), ``engine.bifxml`` + ``engine.json`` (the network),
``engine_tables.npz`` (E[D | do(S), W] and E[L | do(V), C] as arrays for planners) and
``report.json`` (settings, subsampling, score against the simulator's ground truth, timings).
"""

from __future__ import annotations

import dataclasses
import json
import pathlib
import time

import numpy as np

from socialnav.causal import discover, extract, plots, simulator_graph
from socialnav.causal import engine as engine_lib
from socialnav.common.atomic import write_bytes_atomic, write_text_atomic
from socialnav.common.memory import available_bytes, too_big


def write_tables(
    path: str | pathlib.Path, waypoints: list[str], slots: list[str], tables: dict[str, np.ndarray]
) -> pathlib.Path:
    """Write the engine's tables (:meth:`causal.engine.CausalEngine.tables`) with the waypoint and
    slot names they belong to, atomically: ``engine_tables.npz``, the file the planners read with
    their own reader (``planners.warehouse.tables.CausalTables``; ``tests/test_contracts.py`` checks both ends)."""
    return write_bytes_atomic(
        path, lambda h: np.savez(h, waypoints=np.array(waypoints), slots=np.array(slots), **tables)
    )


# Peak memory of a learn per sample of the datasets (the engine's two-slice learning table and
# pyAgrum's copy of it), measured: 2.26 GB for one world's 2.77 M samples, 4.2 GB for two worlds.
ENGINE_BYTES_PER_SAMPLE = 820


def check_memory(n_samples: int, available: int | None) -> None:
    """Raise :class:`causal.extract.LogError` when learning from ``n_samples`` samples needs more
    than :data:`common.memory.USABLE_SHARE` of the ``available`` bytes (None: not known, no check),
    before any work."""
    needed = n_samples * ENGINE_BYTES_PER_SAMPLE
    if too_big(needed, available):
        raise extract.LogError(
            f"{n_samples:,} samples need about {needed / 1e9:.1f} GB to learn from, this machine has "
            f"{available / 1e9:.1f} GB available: learn from fewer worlds (--worlds) or subsample coarser (--step)"
        )


@dataclasses.dataclass
class LearnReport:
    out_dir: pathlib.Path
    report: dict


def learn(
    logs_dir: str | pathlib.Path,
    out_dir: str | pathlib.Path,
    *,
    test: str = "parcorr",
    alpha: float = 0.01,
    step: int | None = None,
    max_samples: int = 200_000,
    worlds: list[int] | None = None,
    waypoints: list[str] | None = None,
    compare_subsampling: bool = False,
    progress: bool = True,
    shown_as: str | pathlib.Path | None = None,
) -> LearnReport:
    """Run extraction, discovery, parameter learning and the do-queries on a run's logs.

    Args:
      logs_dir: a folder written by ``socialnav simulate`` (:mod:`common.logschema`).
      test, alpha: J-PCMCI+ settings (see :func:`causal.discover.run_jpcmciplus`).
      step: subsampling step in logged samples (default: the Nyquist rule).
      max_samples: discovery's sample budget (J-PCMCI+ time grows with it): discovery runs on
        the datasets it holds (:func:`causal.extract.discovery_subset`), the engine on all;
        None or 0 for no budget.
      worlds: world ids to learn from (default: all).
      waypoints: waypoints to learn (default: all whose density changes).
      compare_subsampling: also run discovery on every dataset (no budget) and report both.
      shown_as: the folder named in the closing message (default ``out_dir``; the command line
        writes into a staging folder that becomes ``out_dir`` when the run is complete).

    Raises:
      extract.LogError: the logs lack a column, a variable is constant, a waypoint is empty.
    """
    logs_dir, out = pathlib.Path(logs_dir), pathlib.Path(out_dir)
    timings = {}
    t0 = time.perf_counter()
    say = print if progress else (lambda *a, **k: None)

    say("reading logs ...", flush=True)
    df, meta = extract.read_run(logs_dir, waypoints)
    names, slots = meta["waypoints"], meta["slots"]
    datasets = extract.build_datasets(df, names, waypoints=waypoints, step=step, worlds=worlds)
    timings["extract_s"] = time.perf_counter() - t0
    n_samples = sum(len(a) for a in datasets.data.values())
    check_memory(n_samples, available_bytes())
    subset = extract.discovery_subset(datasets, max_samples)
    n_discovery = sum(len(datasets.data[k]) for k in subset)
    say(
        f"  {len(datasets.data)} datasets ({len(set(datasets.waypoints.values()))} waypoints x "
        f"{len(set(datasets.worlds.values()))} worlds), {n_samples} samples after subsampling every "
        f"{datasets.step} sample(s) ({datasets.period_s:g} s; the Nyquist rule asks for "
        f"{datasets.nyquist_step}); dropped empty waypoints: "
        f"{', '.join(datasets.dropped_waypoints) or 'none'}",
        flush=True,
    )

    say(
        f"J-PCMCI+ ({test}, alpha {alpha}) on {len(subset)} of the {len(datasets.data)} datasets "
        f"({n_discovery} samples; the sample budget --max-samples {max_samples or 'none'}) ...",
        flush=True,
    )
    t = time.perf_counter()
    found = discover.run_jpcmciplus({k: datasets.data[k] for k in subset}, test=test, alpha=alpha)
    timings["discover_s"] = time.perf_counter() - t
    quality = discover.score(found.links)
    simulator_truth = simulator_graph.pipeline_truth(simulator_graph.sampling_steps(datasets.period_s))
    against_simulator = discover.score(found.links, simulator_truth)
    say(
        f"  {len(found.links)} links in {found.seconds:.1f} s: precision {quality['precision']:.2f}, "
        f"recall {quality['recall']:.2f}, SHD {quality['shd']} against the paper's Fig. 8; "
        f"{against_simulator['precision']:.2f}, {against_simulator['recall']:.2f}, SHD {against_simulator['shd']} "
        "against the simulator's own graph (causal/simulator_graph.py)",
        flush=True,
    )

    comparison = None
    if compare_subsampling and len(subset) < len(datasets.data):
        say(f"J-PCMCI+ on all {len(datasets.data)} datasets, for comparison ...", flush=True)
        found_full = discover.run_jpcmciplus(datasets.data, test=test, alpha=alpha)
        comparison = {
            "datasets": len(datasets.data),
            "links": [k.label for k in found_full.links],
            "score": discover.score(found_full.links),
            "score_against_simulator": discover.score(found_full.links, simulator_truth),
            "seconds": found_full.seconds,
        }

    say("learning the inference engine ...", flush=True)
    t = time.perf_counter()
    eng = engine_lib.CausalEngine.fit(datasets, found, n_slots=len(slots))
    timings["fit_s"] = time.perf_counter() - t
    t = time.perf_counter()
    tables = eng.tables(names, progress=progress)
    timings["queries_s"] = time.perf_counter() - t

    out.mkdir(parents=True, exist_ok=True)
    found.save(out / "discovery.json")
    plots.graph_figure(found, out / "causal_graph.png")
    eng.save(out)
    write_tables(out / engine_lib.TABLES_FILE, names, slots, tables)
    timings["total_s"] = time.perf_counter() - t0
    report = {
        "logs": str(logs_dir),
        "test": test,
        "alpha": alpha,
        "subsampling_step": datasets.step,
        "nyquist_step": datasets.nyquist_step,
        "period_s": datasets.period_s,
        "highest_frequency_hz": datasets.frequencies_hz,
        "dropped_waypoints": list(datasets.dropped_waypoints),
        "datasets": len(datasets.data),
        "samples": n_samples,
        "discovery_datasets": [f"{datasets.waypoints[k]}@world{datasets.worlds[k]}" for k in subset],
        "discovery_samples": n_discovery,
        "links": [k.label for k in found.links],
        "score": quality,
        "score_against_simulator": against_simulator,
        "on_all_datasets": comparison,
        "bins": {k: len(b.means) for k, b in eng.bins.items()},
        "battery_pct_per_s": tables["battery_pct_per_s"].tolist(),
        "speed_mps": tables["speed_mps"].tolist(),
        "timings": timings,
    }
    write_text_atomic(out / "report.json", json.dumps(report, indent=1))
    say(
        f"learn finished in {timings['total_s']:.1f} s (extract {timings['extract_s']:.1f}, discover "
        f"{timings['discover_s']:.1f}, fit {timings['fit_s']:.1f}, queries {timings['queries_s']:.1f}); "
        f"wrote {shown_as or out}/{{discovery.json, causal_graph.png, engine.bifxml, engine.json, engine_tables.npz, "
        f"report.json}}",
        flush=True,
    )
    return LearnReport(out, report)
