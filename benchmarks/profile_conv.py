"""One 3x3 convolution of the GSCL U-Net, forward and backward, at each of its four shapes:
float32 against bfloat16, NHWC (Flax's layout, what the model uses) against NCHW.

    python benchmarks/profile_conv.py            # batch 32, one device (XLA's threads on every core)

For the speed issue's profile of the training step (docs/gscl.md): whether the convolutions'
layout or precision would buy the step anything. Best of 5 calls after one that compiles; GFLOP/s
counts the forward and both gradients (3 x 2 x N H W C_in C_out 9).
"""

from __future__ import annotations

import os
import pathlib
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent))
os.environ.setdefault("XLA_FLAGS", "--xla_force_host_platform_device_count=1")

from socialnav.runtime import request_wide_vectors

request_wide_vectors()

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402

from benchmarks.bench_simulator import machine  # noqa: E402

SHAPES = ((40, 16), (20, 32), (10, 64), (5, 128))  # (side, channels) of the U-Net's levels (CPU_FEATURES)


def time_conv(dtype, layout: str, batch: int, side: int, channels: int) -> tuple[float, float]:
    """(seconds, GFLOP/s) of one conv's forward and gradients (kernel and input)."""
    key = jax.random.PRNGKey(0)
    if layout == "NHWC":
        x = jax.random.normal(key, (batch, side, side, channels), dtype)
        w = jax.random.normal(key, (3, 3, channels, channels), dtype) * 0.1
        numbers = ("NHWC", "HWIO", "NHWC")
    else:
        x = jax.random.normal(key, (batch, channels, side, side), dtype)
        w = jax.random.normal(key, (channels, channels, 3, 3), dtype) * 0.1
        numbers = ("NCHW", "OIHW", "NCHW")

    def loss(w, x):
        y = jax.lax.conv_general_dilated(x, w, (1, 1), "SAME", dimension_numbers=numbers)
        return jnp.sum(y.astype(jnp.float32) ** 2)

    grad = jax.jit(jax.grad(loss, argnums=(0, 1)))
    jax.block_until_ready(grad(w, x))
    best = float("inf")
    for _ in range(5):
        t0 = time.perf_counter()
        jax.block_until_ready(grad(w, x))
        best = min(best, time.perf_counter() - t0)
    return best, 3 * 2 * batch * side * side * channels * channels * 9 / best / 1e9


def main() -> None:
    print(f"machine: {machine()}")
    print("3x3 conv, forward + gradients, batch 32: ms (GFLOP/s)")
    for side, channels in SHAPES:
        cells = []
        for dtype in (jnp.float32, jnp.bfloat16):
            for layout in ("NHWC", "NCHW"):
                seconds, rate = time_conv(dtype, layout, 32, side, channels)
                cells.append(f"{jnp.dtype(dtype).name} {layout} {seconds * 1e3:6.2f} ({rate:5.1f})")
        print(f"  {side:>2}x{side:<2}x{channels:<3} " + " | ".join(cells), flush=True)


if __name__ == "__main__":
    main()
