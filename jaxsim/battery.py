"""The robot's battery, seed 000 Eq. (1)-(2).

``L_t = -dt (K_s + K_d V_t)`` when discharging without obstacle, ``x K_o`` with one, and
``+dt K_c`` while charging; ``B_t = B_{t-1} + L_{t-1}``, kept in [0, 100].
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from socialnav.jaxsim.params import SimParams


def battery_change_pct(params: SimParams, speed_mps: jax.Array, charging: jax.Array, obstacle: jax.Array) -> jax.Array:
    """L of Eq. (1) over one step of ``params.dt_s`` (any broadcastable shapes)."""
    discharge = -params.dt_s * (params.battery_static_pct_per_s + params.battery_dynamic_pct_per_m * speed_mps)
    discharge = jnp.where(obstacle, discharge * params.battery_obstacle_factor, discharge)
    return jnp.where(charging, params.dt_s * params.battery_charge_pct_per_s, discharge)


def next_battery_pct(battery_pct: jax.Array, change_pct: jax.Array) -> jax.Array:
    """Eq. (2), clipped to the physical range [0, 100]."""
    return jnp.clip(battery_pct + change_pct, 0.0, 100.0)
