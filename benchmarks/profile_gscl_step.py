"""Where a GSCL training step's time goes, per XLA kernel.

    python benchmarks/profile_gscl_step.py               # the default model, batch 32
    python benchmarks/profile_gscl_step.py --top 40

One device (``--xla_force_host_platform_device_count=1``, XLA's threads on every core), the
default :class:`models.config.TrainConfig` at ``--batch`` samples, a JAX profiler trace of
``--steps`` training steps after warm-up, summed by XLA kernel name (numbered copies merged) and
by kind: YNNPACK's fusions (XLA's CPU library for convolutions and products), XLA's own
convolutions, the other fusions (batch norm, activations,
the loss, the optimiser), copies and transposes, and the rest. The profiler adds some time of
its own; the shares are what to read.
"""

from __future__ import annotations

import argparse
import collections
import os
import pathlib
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent))
os.environ.setdefault("XLA_FLAGS", "--xla_force_host_platform_device_count=1")

from socialnav.runtime import request_wide_vectors

request_wide_vectors()

import jax  # noqa: E402
import numpy as np  # noqa: E402

from benchmarks.bench_simulator import machine  # noqa: E402
from benchmarks.xla_trace import kernel_times  # noqa: E402
from socialnav.models import dataset, steps  # noqa: E402
from socialnav.models.config import TrainConfig  # noqa: E402


def kind_of(name: str) -> str:
    """The kind of an XLA kernel from its name."""
    lowered = name.lower()
    if lowered.startswith("ynn"):
        return "YNNPACK (convolutions, products)"
    if "conv" in lowered:
        return "convolution (XLA's own)"
    if "copy" in lowered or "transpose" in lowered:
        return "copy / transpose"
    if "fusion" in lowered or "reduce" in lowered:
        return "other fusions and reductions"
    return "other"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--batch", type=int, default=32)
    ap.add_argument("--steps", type=int, default=10)
    ap.add_argument("--top", type=int, default=25)
    args = ap.parse_args()
    print(f"machine: {machine()}")
    config = TrainConfig(batch_size=args.batch)
    state = steps.initial_state(config)
    train_step = steps.compiled(config)[2]
    n = args.batch * (args.steps + 5)
    data = dataset.generate(0, {"queue": n // 2, "group": n - n // 2})
    family = np.zeros(args.batch, np.int32)

    def batch(i):
        sl = slice(i * args.batch, (i + 1) * args.batch)
        return data["inputs"][sl], data["targets"][sl], family

    def run(first=5, count=args.steps):
        nonlocal state
        for i in range(first, first + count):
            state, loss = train_step(state, *batch(i))
        jax.block_until_ready(loss)

    run(0, 5)  # warm-up, compilation included
    t0 = time.perf_counter()
    run()
    untraced_ms = (time.perf_counter() - t0) / args.steps * 1e3
    seconds, calls = kernel_times(run, per=args.steps)
    total = collections.Counter({name: s * 1e3 for name, s in seconds.items()})  # ms per step
    step_ms = sum(total.values())
    print(
        f"default model, batch {args.batch}: {untraced_ms:.1f} ms per step untraced; "
        f"kernels summed over the trace: {step_ms:.1f} ms per step"
    )
    kinds = collections.Counter()
    for name, ms in total.items():
        kinds[kind_of(name)] += ms
    for kind, ms in kinds.most_common():
        print(f"  {kind:<30} {ms:7.1f} ms  {ms / step_ms:5.1%}")
    print(f"the {args.top} costliest kernels (ms per step, share, calls per step):")
    for name, ms in total.most_common(args.top):
        print(f"{ms:8.2f} ms  {ms / step_ms:5.1%}  x{calls[name]:4.1f}  {name}")


if __name__ == "__main__":
    main()
