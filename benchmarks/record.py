"""The benchmarks' headline figures as JSON lines, for ``benchmarks/run_all.py`` to gather.

Each benchmark prints its figures for a person to read and, through :func:`record`, appends each
headline figure as one JSON object to the file named by ``$SOCIALNAV_BENCH_RECORD`` (nothing when
it is unset, so a benchmark run by hand writes no file). The platform, the device and JAX's
version are added here, so every figure names the hardware it was measured on.
"""

from __future__ import annotations

import json
import os

RECORD_VARIABLE = "SOCIALNAV_BENCH_RECORD"


def record(job: str, figure: str, value: float, unit: str, *, compile_s: float | None = None, **detail) -> None:
    """Append one figure of ``job`` (``value`` in ``unit``; ``compile_s``: the seconds its programs
    took to compile, apart from the timed run, where the benchmark measures them; ``detail``: the
    size it ran at, e.g. ``batch=1024``) to ``$SOCIALNAV_BENCH_RECORD``. Imports JAX only when
    recording, after the benchmark has set up its devices."""
    path = os.environ.get(RECORD_VARIABLE)
    if not path:
        return
    import jax

    device = jax.devices()[0]
    row = {
        "job": job,
        "figure": figure,
        "value": float(value),
        "unit": unit,
        "compile_s": None if compile_s is None else round(float(compile_s), 3),
        "platform": device.platform,
        "device": getattr(device, "device_kind", device.platform),
        "devices": jax.device_count(),
        "jax": jax.__version__,
        **detail,
    }
    with open(path, "a", encoding="utf-8") as f:
        f.write(json.dumps(row) + "\n")
