"""Host-device setup that must happen before JAX is imported (this module does not import it)."""

from __future__ import annotations

import os


def request_host_devices(n: int | None = None) -> None:
    """Ask XLA for ``n`` CPU devices (default: the core count) so that ``shard_map`` can use every
    core; measured here: 2 devices on 2 cores nearly double the simulator's throughput.

    Must run before ``import jax``; does nothing if ``XLA_FLAGS`` already sets a device count.
    """
    flags = os.environ.get("XLA_FLAGS", "")
    if "xla_force_host_platform_device_count" in flags:
        return
    n = n or os.cpu_count() or 1
    os.environ["XLA_FLAGS"] = f"{flags} --xla_force_host_platform_device_count={n}".strip()
