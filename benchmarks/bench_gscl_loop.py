"""The GSCL training step as ``models.train.train`` calls it: an epoch's batches with the pair
term's contrast, sharded over the devices before the call, the state replicated; samples per second
over rounds of steps, compilation excluded.

    python benchmarks/bench_gscl_loop.py                       # the default model
    python benchmarks/bench_gscl_loop.py --transposed-conv     # the decoder's upsampling as nnx.ConvTranspose
    python benchmarks/bench_gscl_loop.py --features 12,24,48,96 --batch-size 16   # another width or batch

Run the variants as separate processes, interleaved, and compare them only within one session:
this machine's speed moves by 10 % or more within an hour. ``bench_gscl.py``'s throughput table
calls the step on a small mixed dataset without the contrast; this is the loop that training runs.
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent))

from socialnav.cli.argtypes import positive_int, unet_widths
from socialnav.runtime import request_host_devices, request_wide_vectors

request_host_devices()
request_wide_vectors()

import jax  # noqa: E402
from flax import nnx  # noqa: E402

from benchmarks.bench_simulator import machine  # noqa: E402
from benchmarks.record import record  # noqa: E402
from socialnav.models import steps, train, unet  # noqa: E402
from socialnav.models.config import TrainConfig  # noqa: E402


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rounds", type=positive_int, default=3)
    parser.add_argument("--steps", type=positive_int, default=100, help="steps per round")
    parser.add_argument(
        "--transposed-conv", action="store_true", help="the decoder's upsampling as nnx.ConvTranspose (before UpConv)"
    )
    parser.add_argument("--features", type=unet_widths, default=None, help="U-Net widths, e.g. 12,24,48,96")
    parser.add_argument(
        "--batch-size", type=positive_int, default=None, help="samples per step (default: the recipe's)"
    )
    args = parser.parse_args(argv)
    if args.transposed_conv:
        unet.UpConv.__call__ = nnx.ConvTranspose.__call__
    print(machine())
    config = TrainConfig(
        **({} if args.features is None else {"features": args.features}),
        **({} if args.batch_size is None else {"batch_size": args.batch_size}),
    )
    bs = config.batch_size
    if (args.rounds * args.steps + 1) * bs > sum(config.train_counts.values()):
        parser.error("rounds x steps is more than one epoch's batches")
    data_sharding, replicated = steps.batch_sharding(bs)
    state = steps.initial_state(config)
    if replicated is not None:
        state = jax.device_put(state, replicated)
    train_step = steps.compiled(config)[2]
    data = train.epoch_data(config, 0)

    def batch(b):
        return train.epoch_batch(data, b, bs, data_sharding)

    t0 = time.perf_counter()
    state, loss = train_step(state, *batch(0), None)
    jax.block_until_ready(loss)
    first_s = time.perf_counter() - t0
    rates, b = [], 1
    for _ in range(args.rounds):
        t0 = time.perf_counter()
        for _ in range(args.steps):
            state, loss = train_step(state, *batch(b), None)
            b += 1
        jax.block_until_ready(loss)
        rates.append(args.steps * bs / (time.perf_counter() - t0))
    upsampling = "nnx.ConvTranspose" if args.transposed_conv else "UpConv"
    print(
        f"model {config.features}, batch {bs}, {jax.device_count()} device(s), upsampling {upsampling}: "
        f"samples/s per round of {args.steps} steps: {', '.join(f'{r:.0f}' for r in rates)} (loss {float(loss):.6f}); "
        f"the first step (compiling it) {first_s:.1f} s"
    )
    record("gscl_train", "samples/s", max(rates), "samples/s", compile_s=first_s, features=list(config.features),
           batch=bs)  # fmt: skip


if __name__ == "__main__":
    main()
