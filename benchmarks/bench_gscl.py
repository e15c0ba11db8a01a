"""GSCL on this machine: dataset generation speed, training throughput, and the time for the
U-Net to reach the quality bar (test MSE <= 0.0033 and <= 1/10 of the better trivial predictor
in every family) on the held-out set and the held-out rule suite (every check passing on 95 %
of its scenes, :mod:`models.rules`).

    python benchmarks/bench_gscl.py                          # all three, the default CPU recipe
    python benchmarks/bench_gscl.py --skip-train             # generation and throughput only
    python benchmarks/bench_gscl.py --skip-throughput --stop-after-epochs 2 --no-coords    # an ablation
    python benchmarks/bench_gscl.py --skip-throughput --stop-after-epochs 2 --paper        # the paper's recipe

Time to target counts data generation and training (``wall_s`` of the metrics file), not the
per-epoch test evaluations, which are measurement; the total wall time, evaluations and
compilation included, is printed beside it.
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from socialnav.runtime import request_host_devices, request_wide_vectors  # noqa: E402

request_host_devices()
request_wide_vectors()

import jax  # noqa: E402
import numpy as np  # noqa: E402

from benchmarks.bench_simulator import machine  # noqa: E402
from benchmarks.record import record  # noqa: E402
from socialnav.cli.argtypes import positive_float  # noqa: E402
from socialnav.models import dataset, train, unet  # noqa: E402
from socialnav.models.config import TrainConfig  # noqa: E402
from socialnav.models.quality import quality_table  # noqa: E402
from socialnav.models.steps import abstract_model, batch_sharding, compiled, initial_state  # noqa: E402


def _generate_in_new_process(cache_dir: str | None, fraction: float = 1.0) -> float:
    """Seconds for ``dataset.generate(0, dataset.scaled_counts(fraction))`` in a fresh Python process
    (imports not counted)."""
    code = (
        f"import sys, time; sys.path.insert(0, {str(ROOT)!r}); from models import dataset; "
        f"counts = dataset.scaled_counts({fraction!r}); "
        "t = time.perf_counter(); dataset.generate(0, counts); print(time.perf_counter() - t)"
    )
    env = {k: v for k, v in os.environ.items() if k != "JAX_COMPILATION_CACHE_DIR"}
    if cache_dir is not None:
        env["JAX_COMPILATION_CACHE_DIR"] = cache_dir
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    return float(out.stdout.strip().splitlines()[-1])


def bench_generation(fraction: float = 1.0):
    counts = dataset.scaled_counts(fraction)
    n = sum(counts.values())
    with tempfile.TemporaryDirectory() as cache:
        first = _generate_in_new_process(cache, fraction)  # compiles, fills the empty cache
        cached = _generate_in_new_process(cache, fraction)  # a later process: compiled programs from the cache
    dataset.generate(0, counts)
    warm = []
    for seed in (1, 2, 3):
        t0 = time.perf_counter()
        dataset.generate(seed, counts)
        warm.append(time.perf_counter() - t0)
    print(
        f"generation of {n:,} pairs: {first:.1f} s in a new process (compilation of {len(dataset.FAMILIES)} "
        f"families included), {cached:.1f} s in a later process with JAX's compilation cache "
        f"(on in the socialnav command), {min(warm):.2f} s once compiled ({n / min(warm):,.0f} pairs/s)"
    )
    record("gscl_generate", "pairs/s", n / min(warm), "pairs/s", compile_s=first - min(warm), pairs=n,
           new_process_s=round(first, 2), cached_process_s=round(cached, 2))  # fmt: skip


def _step_flops(step, *args) -> float | None:
    """XLA's count of floating-point operations in one compiled training step (None if the
    backend gives none)."""
    try:
        analysis = step.lower(*args).compile().cost_analysis()
    except Exception:  # a figure for the record, never a reason to stop
        return None
    analysis = analysis[0] if isinstance(analysis, list) else analysis
    return (float(analysis.get("flops", 0.0)) or None) if analysis else None


def bench_throughput(widths, batch_sizes, steps: int = 15):
    print("training throughput (samples/s, compile excluded; XLA's flop count of a step and the rate it ran at):")
    data = dataset.generate(0, dataset.scaled_counts(0.05))
    for features in widths:
        for bs in batch_sizes:
            config = TrainConfig(features=features, batch_size=bs)
            state = initial_state(config)
            step = compiled(config)[2]
            data_sharding, replicated = batch_sharding(bs)
            if replicated is not None:
                state = jax.device_put(state, replicated)

            def batch(i, bs=bs, data_sharding=data_sharding):
                sl = slice((i * bs) % (len(data["family"]) - bs), None)
                b = (data["inputs"][sl][:bs], data["targets"][sl][:bs], data["family"][sl][:bs].astype(np.int32))
                return b if data_sharding is None else jax.device_put(b, data_sharding)

            t0 = time.perf_counter()
            state, loss = step(state, *batch(0))
            loss.block_until_ready()
            compile_s = time.perf_counter() - t0
            t0 = time.perf_counter()
            for i in range(1, steps + 1):
                state, loss = step(state, *batch(i))
            loss.block_until_ready()
            rate = steps * bs / (time.perf_counter() - t0)
            params = unet.parameter_count(abstract_model(config))  # shapes only: nothing drawn
            flops = _step_flops(step, state, *batch(0))
            if flops is not None and data_sharding is not None:
                flops *= jax.device_count()  # XLA counts one device's share of a sharded step
            rate_flops = (
                ""
                if flops is None
                else f", {flops / bs / 1e6:.0f} MFLOP per sample, {flops / bs * rate / 1e9:.1f} GFLOP/s"
            )
            print(
                f"  features {features!s:<22} {params:>10,} params  batch {bs:>4}: {rate:7.1f} samples/s "
                f"(compile {compile_s:.1f} s{rate_flops})"
            )
            record("gscl_throughput", "samples/s", rate, "samples/s", compile_s=compile_s, features=list(features),
                   batch=bs)  # fmt: skip


def bench_time_to_target(config: TrainConfig, stop_after_epochs: int | None = None, keep: pathlib.Path | None = None):
    print(f"time to target: {config}")
    max_steps = None if stop_after_epochs is None else stop_after_epochs * config.steps_per_epoch
    with tempfile.TemporaryDirectory() as tmp:
        run = keep or pathlib.Path(tmp) / "run"
        t0 = time.perf_counter()
        line = train.train(
            config,
            run,
            progress=False,
            stop_when_good=stop_after_epochs is None,
            max_steps=max_steps,
        )
        total = time.perf_counter() - t0
        baselines = json.loads((run / "baselines.json").read_text())
    print(quality_table(line["test_mse"], line["test_mse_by_family"], baselines))
    print("held-out rule suite (models.rules), share of scenes passing per check:")
    for check, share in line["rules_pass_by_check"].items():
        print(f"  {check:<28} {100 * share:5.1f} %")
    history = [json.loads(text) for text in (run / "metrics.jsonl").read_text().splitlines()]
    print(
        "per epoch (wall_s: generation + training so far): "
        + "; ".join(
            f"{h['epoch']}: {h['wall_s']:.0f} s, test {h['test_mse']:.5f}"
            + (" bar" if h["meets_quality"] else "")
            + f", worst check {100 * h['rules_pass_min']:.0f} %"
            for h in history
        )
    )
    both = [h for h in history if h["meets_quality"] and h.get("meets_rules")]
    if both and both[0]["epoch"] != line["epoch"]:
        first = both[0]
        print(f"quality bar and rule suite first met at epoch {first['epoch']} ({first['wall_s'] / 60:.1f} min)")
    # This machine's speed on the day, to set a time against runs of other days: the training
    # throughput of the run itself (samples per second of generation and training).
    print(f"this run's training throughput: {line['samples_seen'] / line['wall_s']:.0f} samples/s")
    if line["meets_quality"] and line["meets_rules"]:
        print(
            f"quality bar and rule suite reached at epoch {line['epoch']} ({line['samples_seen']:,} samples): "
            f"{line['wall_s'] / 60:.1f} min of generation + training, {total / 60:.1f} min in all "
            f"(test evaluations and compilation included)"
        )
    else:
        print(
            f"quality bar {'reached' if line['meets_quality'] else 'NOT reached'}, rule suite "
            f"{'passed' if line['meets_rules'] else 'NOT passed'} (worst check {100 * line['rules_pass_min']:.0f} %) "
            f"in {line['epoch']} epochs ({line['wall_s'] / 60:.1f} min of training, "
            f"{total / 60:.1f} min in all)"
        )


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--skip-train", action="store_true", help="only generation and throughput")
    parser.add_argument("--skip-throughput", action="store_true")
    parser.add_argument(
        "--generation-fraction", type=positive_float, default=1.0, help="this share of the paper's counts (default 1)"
    )
    parser.add_argument("--features", default=None, help="widths for the time-to-target run, e.g. 16,32,64,128")
    parser.add_argument("--batch-size", type=int, default=None)
    parser.add_argument("--epochs", type=int, default=None)
    parser.add_argument("--learning-rate", type=float, default=None)
    parser.add_argument("--schedule", default=None)
    parser.add_argument("--no-fresh-samples", action="store_true")
    parser.add_argument("--no-coords", action="store_true", help="no coordinate input channels")
    parser.add_argument("--composites", type=int, default=None, help="composite samples per 24,200 (default 10000)")
    parser.add_argument("--group-scale", type=int, default=None, help="groups and non-groups times this (default 2)")
    parser.add_argument("--cost-weight", type=float, default=None, help="loss weight 1 + w x target (default 10)")
    parser.add_argument("--pair-weight", type=float, default=None, help="loss weight + w x |target - twin's target|")
    parser.add_argument("--paper", action="store_true", help="the paper's recipe (TrainConfig.paper())")
    parser.add_argument(
        "--keep",
        type=pathlib.Path,
        default=None,
        help="train into this (new) folder and keep it (default: a temporary one)",
    )
    parser.add_argument(
        "--stop-after-epochs",
        type=int,
        default=None,
        help="run exactly this many epochs of the schedule and report them (for ablations), "
        "instead of stopping at the quality bar",
    )
    args = parser.parse_args(argv)
    print(machine())
    bench_generation(args.generation_fraction)
    if not args.skip_throughput:
        bench_throughput([unet.PAPER_FEATURES, (24, 48, 96, 192), unet.CPU_FEATURES, (8, 16, 32, 64)], [32, 64])
    if args.skip_train:
        return
    given = {
        "features": tuple(int(v) for v in args.features.split(",")) if args.features else None,
        "batch_size": args.batch_size,
        "epochs": args.epochs,
        "learning_rate": args.learning_rate,
        "schedule": args.schedule,
        "fresh_samples": False if args.no_fresh_samples else None,
        "coords": False if args.no_coords else None,
        "composites": args.composites,
        "group_scale": args.group_scale,
        "cost_weight": args.cost_weight,
        "pair_weight": args.pair_weight,
    }
    given = {k: v for k, v in given.items() if v is not None}
    config = TrainConfig.paper(**given) if args.paper else TrainConfig(**given)
    if args.keep is not None and args.keep.exists():
        parser.error(f"--keep: {args.keep} exists; give a new folder")
    bench_time_to_target(config, args.stop_after_epochs, args.keep)


if __name__ == "__main__":
    main()
