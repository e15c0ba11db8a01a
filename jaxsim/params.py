"""Simulation parameters: a few static sizes and flags, and a pytree of dynamic floats.

:class:`SimParams` is a pytree (``flax.struct``). Its *static* fields (:data:`STATIC_FIELDS`:
the time step, the slot length, the number of workers, the teleport flag) change the compiled
program (array shapes, step counts, branches) and live in the tree's structure; every other
field is a float leaf, an ordinary traced input of ``jax.jit``. So a new value of a dynamic
parameter reuses the compiled step, and a sweep over one is a ``vmap`` over stacked params
(:meth:`SimParams.stack`) in one compilation. Host code (validation, JSON) reads the fields as
plain Python numbers.

The values live in ``data/<scenario>/params.json`` in four sections (``sim``, ``workers``,
``robot``, ``battery``); a field here is the JSON key with the section as prefix
(``workers.radius_m`` -> ``worker_radius_m``; ``sim`` keys keep their name). The JSON file's
``_choices`` entry records where the sources disagreed and what was chosen.
"""

from __future__ import annotations

import dataclasses
import json
import math
import pathlib
from collections.abc import Sequence

from flax import struct

from common.pytree import stack

SECTION_PREFIX = {"sim": "", "workers": "worker_", "robot": "robot_", "battery": "battery_"}
# Fields that shape the compiled program; every other field is a dynamic float.
STATIC_FIELDS = ("dt_s", "slot_length_s", "n_workers", "robot_teleport_on_failure")


def _static():
    return struct.field(pytree_node=False)


@struct.dataclass
class SimParams:
    """Every number of the warehouse simulation. Units are in the names.

    Social force (pedsim, Moussaid et al. 2009 interaction): desired force
    ``(v0 e - v) / relaxation_time_s``; social force with ``lambda``, ``gamma``, ``n``, ``n'``
    scaled by ``social_force_factor``; wall force ``exp(-(d - radius) / obstacle_sigma_m)``
    scaled by ``obstacle_force_factor``; Gaussian random force of ``random_force_std_mps2``.
    Battery (seed 000 Eq. 1): ``L = -dt (K_s + K_d V) [x K_o if O]`` or ``+dt K_c`` when charging.
    """

    # sim (static)
    dt_s: float = _static()
    slot_length_s: float = _static()
    n_workers: int = _static()
    # workers
    worker_radius_m: float
    worker_desired_speed_mean_mps: float
    worker_desired_speed_std_mps: float
    worker_desired_speed_min_mps: float
    worker_max_speed_mps: float
    worker_relaxation_time_s: float
    worker_social_force_factor: float
    worker_social_lambda: float
    worker_social_gamma: float
    worker_social_n: float
    worker_social_n_prime: float
    worker_obstacle_force_factor: float
    worker_obstacle_sigma_m: float
    worker_random_force_std_mps2: float
    worker_robot_force_factor: float
    worker_activity_min_s: float
    worker_activity_max_s: float
    worker_toilet_activity_min_s: float
    worker_toilet_activity_max_s: float
    worker_min_reach_radius_m: float
    worker_stuck_time_s: float
    worker_spawn_dx_m: float
    worker_spawn_dy_m: float
    worker_exit_margin_s: float
    # robot
    robot_radius_m: float
    robot_max_speed_mps: float
    robot_accel_mps2: float
    robot_goal_tolerance_m: float
    robot_block_stop_gap_m: float
    robot_block_slow_gap_m: float
    robot_block_lane_margin_m: float
    robot_leg_deadline_s: float
    robot_obstacle_probability: float
    robot_obstacle_length_m: float
    robot_obstacle_speed_factor_min: float  # per obstacle, speed factor ~ U(min, 1)
    robot_teleport_on_failure: bool = _static()
    # battery (seed 000 Eq. 1-2)
    battery_initial_pct: float
    battery_static_pct_per_s: float  # K_s
    battery_dynamic_pct_per_m: float  # K_d, per (m/s) per s
    battery_obstacle_factor: float  # K_o
    battery_charge_pct_per_s: float  # K_c
    battery_recharge_below_pct: float
    battery_charged_pct: float

    @property
    def steps_per_slot(self) -> int:
        """Simulation steps in one time slot."""
        return int(round(self.slot_length_s / self.dt_s))

    @classmethod
    def dynamic_names(cls) -> tuple[str, ...]:
        """The dynamic (float leaf) fields, in declaration order."""
        return tuple(f.name for f in dataclasses.fields(cls) if f.name not in STATIC_FIELDS)

    @classmethod
    def stack(cls, params: Sequence[SimParams]) -> SimParams:
        """Params with a leading axis on every dynamic field, for a ``vmap`` over settings.

        Raises:
          ValueError: the static fields differ (they would need another compiled program).
        """
        if not params:
            raise ValueError("need at least one SimParams to stack")
        first = params[0]
        for other in params[1:]:
            for name in STATIC_FIELDS:
                if getattr(other, name) != getattr(first, name):
                    raise ValueError(
                        f"cannot stack params with different static field {name!r}: "
                        f"{getattr(first, name)} vs {getattr(other, name)}"
                    )
        return stack(params)

    @classmethod
    def from_json(cls, file: pathlib.Path, error: type[Exception] = ValueError) -> SimParams:
        """Read ``params.json``; ``error(file, field, message)`` is raised on a bad field."""
        if not file.is_file():
            raise error(file, "<file>", "file is missing")
        try:
            raw = json.loads(file.read_text())
        except json.JSONDecodeError as e:
            raise error(file, "<file>", f"invalid JSON: {e}") from None
        types = {f.name: f.type for f in dataclasses.fields(cls)}
        values = {}
        for section, prefix in SECTION_PREFIX.items():
            block = raw.get(section)
            if not isinstance(block, dict):
                raise error(file, section, "missing section")
            for key, value in block.items():
                name = prefix + key
                if name not in types:
                    raise error(file, f"{section}.{key}", "unknown parameter")
                want = types[name]
                if want == "bool":
                    if not isinstance(value, bool):
                        raise error(file, f"{section}.{key}", f"expected true/false, got {value!r}")
                elif isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                    raise error(file, f"{section}.{key}", f"expected a finite number, got {value!r}")
                values[name] = int(value) if want == "int" else value
        missing = sorted(set(types) - set(values))
        if missing:
            name = missing[0]
            section = (
                next(s for s, p in SECTION_PREFIX.items() if p and name.startswith(p))
                if any(p and name.startswith(p) for p in SECTION_PREFIX.values())
                else "sim"
            )
            key = name[len(SECTION_PREFIX[section]) :]
            raise error(file, f"{section}.{key}", "missing field")
        return cls(**values)

    def validate(self, error: type[Exception] = ValueError, file: str = "params.json") -> None:
        """Check ranges; raise ``error(file, field, message)`` on the first bad value."""
        positive = [
            "dt_s",
            "slot_length_s",
            "worker_radius_m",
            "worker_max_speed_mps",
            "worker_relaxation_time_s",
            "worker_obstacle_sigma_m",
            "robot_radius_m",
            "robot_max_speed_mps",
            "robot_leg_deadline_s",
            "battery_charge_pct_per_s",
        ]
        for name in positive:
            if not getattr(self, name) > 0:
                raise error(file, name, f"must be > 0, got {getattr(self, name)}")
        if self.n_workers < 0:
            raise error(file, "n_workers", f"must be >= 0, got {self.n_workers}")
        if not 0 <= self.robot_obstacle_probability <= 1:
            raise error(file, "robot_obstacle_probability", "must be a probability")
        if (
            self.steps_per_slot * self.dt_s != self.slot_length_s
            and abs(self.steps_per_slot * self.dt_s - self.slot_length_s) > 1e-6 * self.slot_length_s
        ):
            raise error(file, "slot_length_s", f"must be a multiple of dt_s={self.dt_s}")
        if self.worker_activity_min_s > self.worker_activity_max_s:
            raise error(file, "worker_activity_min_s", "greater than worker_activity_max_s")
        if self.robot_block_stop_gap_m >= self.robot_block_slow_gap_m:
            raise error(file, "robot_block_stop_gap_m", "must be below robot_block_slow_gap_m")
        if not 0 <= self.battery_recharge_below_pct < self.battery_charged_pct <= 100:
            raise error(file, "battery_recharge_below_pct", "need 0 <= recharge_below < charged <= 100")
