"""XLA kernel times from a JAX profiler trace, for the profiling scripts (profile_step.py,
profile_gscl_step.py)."""

from __future__ import annotations

import collections
import gzip
import json
import os
import re
import tempfile
from collections.abc import Callable

import jax

# Trace events that are not kernels: the executor's own spans, the jitted call around the kernels,
# loop bodies (their kernels are listed apart).
_SKIP_PREFIXES = ("ThunkExecutor", "$", "end:", "jit_")


def kernel_times(run: Callable[[], object], per: int) -> tuple[collections.Counter, collections.Counter]:
    """``(seconds, calls)`` per XLA kernel name (numbered copies merged), each divided by ``per``,
    of what ``run()`` executes under a profiler trace (``run`` blocks until its results are ready)."""
    with tempfile.TemporaryDirectory() as folder:
        jax.profiler.start_trace(folder, create_perfetto_trace=True)
        run()
        jax.profiler.stop_trace()
        path = next(os.path.join(d, f) for d, _, fs in os.walk(folder) for f in fs if f.endswith(".trace.json.gz"))
        with gzip.open(path) as f:
            events = json.load(f)
    events = events["traceEvents"] if isinstance(events, dict) else events
    seconds, calls = collections.Counter(), collections.Counter()
    for e in events:
        name = e.get("name", "")
        skipped = name.startswith(_SKIP_PREFIXES) or "Execute" in name or "Pjit" in name or "while" in name.lower()
        if e.get("ph") != "X" or skipped:
            continue
        key = re.sub(r"\.\d+$", "", name)
        seconds[key] += e.get("dur", 0) * 1e-6 / per
        calls[key] += 1 / per
    return seconds, calls
