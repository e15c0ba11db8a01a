"""The simulators' precision: float32, whatever JAX's x64 switch says.

Every program of the toolkit is written, seeded and measured in float32: its random draws, its
tables and the figures in the docs are float32's. Under JAX's x64 switch (``JAX_ENABLE_X64=1``,
``jax.config.update("jax_enable_x64", True)``) Python floats and random draws turn float64 and
meet float32 arrays: measured, the warehouse day from seed 0 gives other numbers, and the arena's
episode and the human models' corridors fail to trace (a ``lax.cond`` or ``lax.scan`` whose two
sides differ in dtype). So the simulators refuse to trace under it, in one sentence that says how
to run them; the command line (:mod:`socialnav.runtime`) turns the switch off for its own process.
"""

from __future__ import annotations

import jax

__all__ = ["require_float32"]


def require_float32(where: str) -> None:
    """Raise a one-line ``RuntimeError`` naming ``where`` if JAX's x64 switch is on.

    Called where a simulation is traced (the control loop of both worlds, the step of the
    people), so it costs nothing when the program runs."""
    if jax.config.jax_enable_x64:
        raise RuntimeError(
            f"{where}: the toolkit's simulations run in float32 (its seeds' numbers and tables are "
            "float32's) but jax_enable_x64 is on (JAX_ENABLE_X64 or jax.config.update): call it "
            "inside 'with jax.enable_x64(False):', or turn x64 off"
        )
