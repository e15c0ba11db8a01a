"""The one crowd function: a step of N people by the human model a run chose, for the warehouse
(:func:`jaxsim.workers.move`), the arena (:func:`jaxsim.scenes.people.step_people`) and the
validation against real pedestrians (:mod:`evaluation.humans.validation`) alike.

The models (``docs/humans.md`` measures each against the Jülich corridors and ETH/UCY):

- ``social_force``: pedsim's social force with the warehouse's constants
  (:func:`jaxsim.crowd.step_crowd`), the default;
- ``orca``: RVO2's reciprocal velocity obstacles (:func:`jaxsim.orca.step_orca`);
- ``collision_free_speed`` and ``anticipation``: first-order velocity models with bodies
  (:mod:`jaxsim.speed_model`), and their ``_calibrated`` fits to the Jülich training runs;
- ``steering_speed``: the collision-free speed model with Moussaïd et al. 2011's choice of
  heading, so that people overtake (:func:`jaxsim.speed_model.step_speed_model`'s ``headings``);
- ``power_law``: Karamouzas, Skinner & Guy 2014's anticipatory time-to-collision law with
  Helbing, Farkas & Vicsek 2000's contact forces (:func:`jaxsim.power_law.step_power_law`), and
  its ``_calibrated`` fit to the Jülich training runs.

Every model's step has one signature (:mod:`jaxsim.walkers`: the people, their aims and the
robot as pytrees in, the people after the step out; :data:`STEPS`); ``model`` is static (a
change recompiles), the constants in :class:`HumanParams` are traced. People who walk together
(``group_id``) get Moussaïd et al. 2010's group terms on top of any model
(:mod:`jaxsim.groups`).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Mapping

import jax
from flax import struct

from socialnav.jaxsim import crowd, groups, orca, power_law, speed_model
from socialnav.jaxsim.grid import Grid
from socialnav.jaxsim.params import SimParams
from socialnav.jaxsim.precision import require_float32
from socialnav.jaxsim.walkers import Aims, HumanStep, RobotDisc, Walkers

HUMAN_MODELS = (
    "social_force",
    "orca",
    "collision_free_speed",
    "anticipation",
    "steering_speed",
    "collision_free_speed_calibrated",
    "anticipation_calibrated",
    "steering_speed_calibrated",
    "power_law",
    "power_law_calibrated",
)


def check_model(model: str) -> str:
    """``model`` if it is one of :data:`HUMAN_MODELS`, else a one-line ``ValueError``."""
    if model not in HUMAN_MODELS:
        raise ValueError(f"human model must be one of {', '.join(HUMAN_MODELS)}, got {model!r}")
    return model


def kind_of(model: str) -> str:
    """The model a human model's name runs: a ``_calibrated`` name its base model's."""
    return model.removesuffix("_calibrated")


@struct.dataclass
class HumanParams:
    """The traced constants of the human models: ``crowd`` (the social force's
    :class:`~jaxsim.params.SimParams`, whose static ``dt_s`` is every model's step), ``orca``
    (:class:`~jaxsim.orca.ORCAParams`), ``speed`` and ``anticipation`` (the velocity models'),
    ``group`` (the walking groups' terms, :class:`~jaxsim.groups.GroupParams`), ``power_law``
    (:class:`~jaxsim.power_law.PowerLawParams`)."""

    crowd: SimParams
    orca: orca.ORCAParams
    speed: speed_model.SpeedModelParams
    anticipation: speed_model.AnticipationParams
    group: groups.GroupParams = groups.GroupParams()
    power_law: power_law.PowerLawParams = power_law.PowerLawParams()


def human_params(model: str, crowd_params: SimParams, orca_params: orca.ORCAParams | None = None,
                 velocity=None, group: groups.GroupParams | None = None) -> HumanParams:  # fmt: skip
    """The constants ``model`` runs with: ORCA's defaults unless ``orca_params``; a velocity
    model's (or the power law's) ``velocity`` parameters, else its name's own
    (:func:`jaxsim.speed_model.params_of`: a ``_calibrated`` name its fit); the walking groups'
    ``group`` terms, Moussaïd's unless given."""
    kind = kind_of(check_model(model))
    speed, anticipation = speed_model.SpeedModelParams(), speed_model.AnticipationParams()
    if kind in speed_model.VELOCITY_MODELS:
        chosen = speed_model.params_of(model) if velocity is None else velocity
        speed, anticipation = (chosen, anticipation) if speed_model.uses_speed_params(kind) else (speed, chosen)
    power = power_law.PowerLawParams()
    if kind == "power_law":
        power = power_law.params_of(model) if velocity is None else velocity
    chosen_orca = orca.ORCAParams() if orca_params is None else orca_params
    chosen_group = groups.GroupParams() if group is None else group
    return HumanParams(crowd_params, chosen_orca, speed, anticipation, chosen_group, power)


# The widest body radius a fit may set: the fits here find 0.15-0.30 m (docs/humans.md), and a body
# wider than a scene's corridors is no person (the speed model's step gives NaN from about 3 m in
# gscl_group's corridor); 1 m leaves any measured person inside it.
MAX_BODY_RADIUS_M = 1.0


def parts_of(model: str) -> tuple[str, ...]:
    """The fields of :class:`HumanParams` whose constants human ``model`` reads: its own and the
    walking groups' (every model steps by ``crowd.dt_s``, the run's step, which no fit sets)."""
    return (PARAMS_OF[kind_of(check_model(model))], "group")


def values_problem(model: str, values: Mapping[str, float]) -> str | None:
    """Why ``values`` (``"<part>.<field>"`` -> number, the form a calibration's ``fit.json`` holds)
    cannot set human ``model``'s constants: a part the model does not read (:func:`parts_of`), a
    field its part does not have, a value that is not a finite positive number, a body radius past
    :data:`MAX_BODY_RADIUS_M`; None if it can."""
    for path, value in values.items():
        part, _, field = str(path).partition(".")
        if part not in parts_of(model):
            return f"{path}: {model} reads {' and '.join(parts_of(model))}, not {part!r}"
        known = [f.name for f in dataclasses.fields(_PART_TYPES[part]) if f.name != "dt_s"]
        if field not in known:
            return f"{path}: not a field of {part} ({', '.join(known)})"
        if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value) or value <= 0:
            return f"{path}: {value!r} is not a finite positive number"
        if field == "radius_m" and value > MAX_BODY_RADIUS_M:
            return f"{path}: {value!r} m is wider than a person's body (at most {MAX_BODY_RADIUS_M:g} m)"
    return None


def with_values(model: str, params: HumanParams, values: Mapping[str, float]) -> HumanParams:
    """``params`` with each ``"<part>.<field>"`` of ``values`` set (a fit of human ``model``, as
    ``socialnav humans calibrate`` writes them); raises ``ValueError`` naming the first value
    :func:`values_problem` refuses."""
    problem = values_problem(model, values)
    if problem is not None:
        raise ValueError(problem)
    parts = by_part({path: float(value) for path, value in values.items()})
    return params.replace(**{part: getattr(params, part).replace(**fields) for part, fields in parts.items()})


def by_part(values: Mapping[str, object]) -> dict[str, dict[str, object]]:
    """``{"<part>.<field>": value}`` as ``{part: {field: value}}`` (the values as given: numbers,
    or traced arrays in a fit), for ``params.replace(part=params.part.replace(**fields))``."""
    parts: dict[str, dict[str, object]] = {}
    for path, value in values.items():
        part, _, field = path.partition(".")
        parts.setdefault(part, {})[field] = value
    return parts


_PART_TYPES = {
    "crowd": SimParams,
    "orca": orca.ORCAParams,
    "speed": speed_model.SpeedModelParams,
    "anticipation": speed_model.AnticipationParams,
    "group": groups.GroupParams,
    "power_law": power_law.PowerLawParams,
}


# Each model's step (the one signature of :mod:`jaxsim.walkers`) and the field of
# :class:`HumanParams` that holds its constants.
STEPS: dict[str, HumanStep] = {
    "social_force": crowd.step_crowd,
    "orca": orca.step_orca,
    "collision_free_speed": speed_model.step_speed_model,
    "steering_speed": functools.partial(speed_model.step_speed_model, headings=speed_model.STEERING_HEADINGS),
    "anticipation": speed_model.step_anticipation,
    "power_law": power_law.step_power_law,
}
PARAMS_OF: dict[str, str] = {
    "social_force": "crowd",
    "orca": "orca",
    "collision_free_speed": "speed",
    "steering_speed": "speed",
    "anticipation": "anticipation",
    "power_law": "power_law",
}


def step_humans(
    model: str,
    params: HumanParams,
    wall_field: Grid,
    people: Walkers,
    aims: Aims,
    robot: RobotDisc,
    uniforms: tuple[jax.Array, jax.Array],
    group_id: jax.Array | None = None,
) -> Walkers:
    """One step of ``params.crowd.dt_s`` of N people by human ``model``: the people after it.

    Args:
      model: static, one of :data:`HUMAN_MODELS`.
      people: (N,) positions, velocities, who is present (felt by the others), who is moving
        (stepped; the others stay) and who ignores the robot (:class:`~jaxsim.walkers.Walkers`).
      aims: (N,) towards each person's target, the desired speed and the social force's and
        power law's speed cap (:class:`~jaxsim.walkers.Aims`).
      robot: the disc everyone avoids but those who ignore it (:class:`~jaxsim.walkers.RobotDisc`;
        the social force's pair force has no radius).
      uniforms: two (N,) draws in (0, 1]: the social force's random force, the anticipation
        model's tie-break and creep.
      group_id: (N,) int32, people walking together share a non-negative id (-1 alone): their
        aims and speeds get the group terms (:func:`jaxsim.groups.group_aim`). ``None``: no
        groups, and nothing computed for them.
    """
    require_float32("jaxsim.humans.step_humans")
    kind = kind_of(check_model(model))
    if group_id is not None:
        aims = groups.group_aim(params.group, people, aims, group_id)
    return STEPS[kind](getattr(params, PARAMS_OF[kind]), wall_field, params.crowd.dt_s, people, aims, robot, uniforms)
