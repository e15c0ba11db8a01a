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

Every model takes the same arrays and returns ``(x, y, vx, vy)``; ``model`` is static (a
change recompiles), the constants in :class:`HumanParams` are traced. People who walk together
(``group_id``) get Moussaïd et al. 2010's group terms on top of any model
(:mod:`jaxsim.groups`).
"""

from __future__ import annotations

import jax
from flax import struct

from socialnav.jaxsim import crowd, groups, orca, power_law, speed_model
from socialnav.jaxsim.params import SimParams

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


def step_humans(
    model: str,
    params: HumanParams,
    wall_field,
    x: jax.Array,
    y: jax.Array,
    vx: jax.Array,
    vy: jax.Array,
    aim_dx: jax.Array,
    aim_dy: jax.Array,
    speed_mps: jax.Array,
    max_speed_mps: jax.Array,
    present: jax.Array,
    moving: jax.Array,
    robot_xyv: tuple[jax.Array, jax.Array, jax.Array, jax.Array],
    robot_radius_m,
    u1: jax.Array,
    u2: jax.Array,
    ignores_robot: jax.Array | None = None,
    group_id: jax.Array | None = None,
):
    """One step of ``params.crowd.dt_s`` of N people by human ``model``: ``(x, y, vx, vy)``, (N,) each.

    Args:
      x, y, vx, vy: (N,) positions (m) and velocities (m/s).
      aim_dx, aim_dy: (N,) towards each person's target (m).
      speed_mps: (N,) desired speeds; max_speed_mps: (N,) the social force's speed cap (the
        velocity models and ORCA walk at most ``speed_mps``).
      present, moving: (N,) bool: in the world (felt by the others); stepped (the others stay).
      robot_xyv: the robot's x, y, vx, vy, an agent the people avoid unless ``ignores_robot``
        (N,) bool; ``robot_radius_m`` its body (the social force's pair force has no radius).
      u1, u2: (N,) uniforms in (0, 1]: the social force's random force, the anticipation
        model's reaction noise.
      group_id: (N,) int32, people walking together share a non-negative id (-1 alone): their
        aims and speeds get the group terms (:func:`jaxsim.groups.group_aim`). ``None``: no
        groups, and nothing computed for them.
    """
    kind = kind_of(check_model(model))
    dt = params.crowd.dt_s
    if group_id is not None:
        aim_dx, aim_dy, speed_mps = groups.group_aim(
            params.group, x, y, aim_dx, aim_dy, speed_mps, max_speed_mps, group_id, present
        )
    if speed_model.uses_speed_params(kind):
        headings = speed_model.STEERING_HEADINGS if kind == "steering_speed" else 1
        return speed_model.step_speed_model(
            params.speed, wall_field, dt, x, y, vx, vy, aim_dx, aim_dy, speed_mps, present, moving, robot_xyv,
            robot_radius_m, ignores_robot=ignores_robot, headings=headings,
        )  # fmt: skip
    if kind == "anticipation":
        return speed_model.step_anticipation(
            params.anticipation, wall_field, dt, x, y, vx, vy, aim_dx, aim_dy, speed_mps, present, moving, robot_xyv,
            robot_radius_m, u1, u2, ignores_robot=ignores_robot,
        )  # fmt: skip
    if kind == "power_law":
        return power_law.step_power_law(
            params.power_law, wall_field, dt, x, y, vx, vy, aim_dx, aim_dy, speed_mps, max_speed_mps, present, moving,
            robot_xyv, robot_radius_m, ignores_robot=ignores_robot,
        )  # fmt: skip
    if kind == "orca":
        return orca.step_orca(
            params.orca, wall_field, dt, x, y, vx, vy, aim_dx, aim_dy, speed_mps, present, moving, robot_xyv,
            robot_radius_m, ignores_robot=ignores_robot,
        )  # fmt: skip
    return crowd.step_crowd(
        params.crowd, wall_field, x, y, vx, vy, aim_dx, aim_dy, speed_mps, max_speed_mps, present, moving, robot_xyv,
        u1, u2, ignores_robot=ignores_robot,
    )  # fmt: skip
