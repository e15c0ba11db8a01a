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

from socialnav.common import strict_json
from socialnav.common.pytree import stack

SECTION_PREFIX = {"sim": "", "workers": "worker_", "robot": "robot_", "battery": "battery_"}
# Fields that shape the compiled program; every other field is a dynamic float.
STATIC_FIELDS = ("dt_s", "slot_length_s", "n_workers", "robot_teleport_on_failure")
# The largest crowd a scenario may ask for: the all-pairs social force traces N/2 shifted
# copies and holds (N/2, N) pair arrays per world.
MAX_WORKERS = 1000
_POSITIVE = (
    "dt_s",
    "slot_length_s",
    "worker_radius_m",
    "worker_desired_speed_mean_mps",
    "worker_desired_speed_min_mps",
    "worker_max_speed_mps",
    "worker_relaxation_time_s",
    "worker_social_gamma",
    "worker_obstacle_sigma_m",
    "worker_min_reach_radius_m",
    "worker_stuck_time_s",
    "robot_radius_m",
    "robot_max_speed_mps",
    "robot_accel_mps2",
    "robot_goal_tolerance_m",
    "robot_block_slow_gap_m",
    "robot_leg_deadline_s",
    "battery_charge_pct_per_s",
)
_NON_NEGATIVE = (
    "worker_desired_speed_std_mps",
    "worker_social_force_factor",
    "worker_social_lambda",
    "worker_social_n",
    "worker_social_n_prime",
    "worker_obstacle_force_factor",
    "worker_random_force_std_mps2",
    "worker_robot_force_factor",
    "worker_activity_min_s",
    "worker_toilet_activity_min_s",
    "worker_spawn_dx_m",
    "worker_spawn_dy_m",
    "worker_exit_margin_s",
    "robot_block_stop_gap_m",
    "robot_block_lane_margin_m",
    "robot_obstacle_length_m",
    "battery_static_pct_per_s",
    "battery_dynamic_pct_per_m",
    "battery_obstacle_factor",
)


# TIAGo's circumscribed radius, the robot of seed 000 and of the warehouse's params.json
# (PeopleFlow's local_planner.yaml: a circular footprint of radius 0.275 m). The default robot
# body of the scenes, the warehouse protocol's collision radius and the figures' robot.
TIAGO_RADIUS_M = 0.275

# A person's body in the arena: the env's contacts and reward, the planners' inflation around a
# person, and the body ORCA's people avoid each other with (Helbing, Farkas and Vicsek 2000 draw
# 0.25-0.35 m). The warehouse's social force keeps its own ``worker_radius_m`` (0.2 m, params.json).
PERSON_RADIUS_M = 0.25

# The longest step (at a worker's top speed, ``workers.max_speed_mps x sim.dt_s``) after which the
# crowd's hard wall constraint (:func:`jaxsim.crowd.wall_constraint`: the distance before the move
# carried along the nearest wall's normal) keeps every worker's centre out of the walls. Measured on
# the shipped warehouse, 4 worlds x 30 min sampled every second (1.5 m/s workers): no centre in a
# wall at sim.dt_s 0.1 and 0.125 s (0.15 and 0.19 m a step); 7, 27, 21, 88 and 1,353 samples (of
# 360,000-400,000) at 0.15, 0.2, 0.25, 0.5 and 1 s (0.225-1.5 m), up to 7.5 cm deep
# (``scripts/walls_at_longer_steps.py``). The bound lies in that bracket; checked by
# :meth:`SimParams.validate`.
WORKER_STEP_MAX_M = 0.2

# Physical ranges of the bodies' radii, checked by :meth:`SimParams.validate`.
BODY_RADIUS_M = {"worker_radius_m": (0.1, 0.5), "robot_radius_m": (0.05, 1.5)}
BODY_RADIUS_SOURCE = {
    "worker_radius_m": "a person: adults' shoulder breadth is about 0.4-0.5 m; the social force model of Helbing, "
    "Farkas and Vicsek (2000) draws 0.25-0.35 m, CrowdNav uses 0.3 m, this warehouse 0.2 m",
    "robot_radius_m": f"a mobile base: TIAGo {TIAGO_RADIUS_M} m (seed 000), a wheelchair or a cart about 0.5-0.8 m",
}


def json_field(name: str) -> str:
    """A field's name as written in ``params.json``: ``robot_accel_mps2`` -> ``robot.accel_mps2``."""
    for section, prefix in SECTION_PREFIX.items():
        if prefix and name.startswith(prefix):
            return f"{section}.{name[len(prefix) :]}"
    return f"sim.{name}"


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
            raw = strict_json.loads(file.read_text(encoding="utf-8"))
        except strict_json.DuplicateKeyError as e:
            raise error(file, e.key, "given twice in one object: which one was meant?") from None
        except UnicodeDecodeError as e:
            raise error(file, "<file>", f"not UTF-8 text ({e.reason} at byte {e.start})") from None
        except json.JSONDecodeError as e:
            raise error(file, "<file>", f"invalid JSON: {e}") from None
        except OSError as e:
            raise error(file, "<file>", f"cannot be read ({e.strerror or e})") from None
        if not isinstance(raw, dict):
            raise error(file, "<file>", f"top level must be a JSON object, got {type(raw).__name__}")
        section = strict_json.unknown_key(raw, SECTION_PREFIX)
        if section is not None:
            hint = strict_json.did_you_mean(section, SECTION_PREFIX)
            raise error(file, section, f"unknown section ({hint}the sections: {', '.join(SECTION_PREFIX)})")
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
                if want == "int" and value != int(value):
                    raise error(file, f"{section}.{key}", f"expected a whole number, got {value!r}")
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
        """Check ranges and consistency; raise ``error(file, field, message)`` on the first bad
        value, ``field`` as written in ``params.json`` (``robot.accel_mps2``)."""

        def fail(name: str, message: str):
            raise error(file, json_field(name), f"{message}, got {getattr(self, name)!r}")

        for name in _POSITIVE:
            if not getattr(self, name) > 0:
                fail(name, "must be > 0")
        for name in _NON_NEGATIVE:
            if not getattr(self, name) >= 0:
                fail(name, "must be >= 0")
        if not 0 <= self.n_workers <= MAX_WORKERS:
            fail(
                "n_workers",
                f"must be in 0..{MAX_WORKERS} (the all-pairs social force is O(N^2) in memory and "
                "compile time; a larger crowd needs a neighbour structure this simulator does not have)",
            )
        for name, (low, high) in BODY_RADIUS_M.items():
            if not low <= getattr(self, name) <= high:
                fail(name, f"must be a body radius in [{low}, {high}] m ({BODY_RADIUS_SOURCE[name]})")
        if not 0 <= self.robot_obstacle_probability <= 1:
            fail("robot_obstacle_probability", "must be a probability in [0, 1]")
        if not 0 < self.robot_obstacle_speed_factor_min <= 1:
            fail("robot_obstacle_speed_factor_min", "must be in (0, 1]")
        if not 0 <= self.battery_initial_pct <= 100:
            fail("battery_initial_pct", "must be a charge in [0, 100] %")
        if (
            self.steps_per_slot * self.dt_s != self.slot_length_s
            and abs(self.steps_per_slot * self.dt_s - self.slot_length_s) > 1e-6 * self.slot_length_s
        ):
            fail("slot_length_s", f"must be a multiple of sim.dt_s={self.dt_s}")
        ordered = [
            ("worker_activity_min_s", "worker_activity_max_s"),
            ("worker_toilet_activity_min_s", "worker_toilet_activity_max_s"),
            ("worker_desired_speed_min_mps", "worker_max_speed_mps"),
        ]
        for low, high in ordered:
            if getattr(self, low) > getattr(self, high):
                fail(low, f"must be <= {json_field(high)} = {getattr(self, high)!r}")
        step_m = self.worker_max_speed_mps * self.dt_s
        if not step_m <= WORKER_STEP_MAX_M:
            fail(
                "dt_s",
                f"a step moves a worker at workers.max_speed_mps = {self.worker_max_speed_mps!r} by {step_m:.3g} m, "
                f"more than {WORKER_STEP_MAX_M} m, the longest step after which the wall constraint keeps every "
                "worker's centre out of the walls (measured on this warehouse: centres inside walls from 0.225 m a "
                "step, none at 0.19 m); at most "
                f"{WORKER_STEP_MAX_M / self.worker_max_speed_mps:.3g} s at this speed",
            )
        if self.robot_block_stop_gap_m >= self.robot_block_slow_gap_m:
            fail("robot_block_stop_gap_m", f"must be below robot.block_slow_gap_m = {self.robot_block_slow_gap_m!r}")
        if not 0 <= self.battery_recharge_below_pct < self.battery_charged_pct <= 100:
            fail(
                "battery_recharge_below_pct",
                f"need 0 <= battery.recharge_below_pct < battery.charged_pct = {self.battery_charged_pct!r} <= 100",
            )
