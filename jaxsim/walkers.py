"""What every human model steps, as three pytrees of (N,) arrays.

A human model's step is one function of one signature (:class:`HumanStep`; the models'
steps: :data:`jaxsim.humans.STEPS`)::

    step(params, wall_field, dt, people: Walkers, aims: Aims, robot: RobotDisc, uniforms) -> Walkers

``params`` is the model's own constants (a traced pytree), ``wall_field`` the world's distance
field (:class:`~jaxsim.grid.Grid`), ``dt`` the step (s, static) and ``uniforms`` a pair of (N,)
draws in (0, 1] (the social force's random push, the anticipation model's tie-break and creep); a
model ignores what it has no use for (a velocity model the cap ``Aims.max_speed_mps``, the social
force the robot's radius). The warehouse's workers (:func:`jaxsim.workers.move`), the arena's
people (:func:`jaxsim.scenes.people.step_people`) and the validation's corridors
(:func:`evaluation.humans.validation.model_step`) build these three and call
:func:`jaxsim.humans.step_humans`.
"""

from __future__ import annotations

from typing import Any, Protocol

import jax
import jax.numpy as jnp
from flax import struct

from socialnav.jaxsim.grid import Grid


@struct.dataclass
class Walkers:
    """N people at one instant.

    Attributes:
      x_m, y_m: (N,) positions (m).
      vx_mps, vy_mps: (N,) velocities (m/s).
      present: (N,) bool, in the world: felt by the others.
      moving: (N,) bool, stepped by the model; the others keep their place (and, for the social
        force, ORCA and the velocity models, get velocity 0).
      ignores_robot: (N,) bool, people who do not feel the robot; ``None``: everyone feels it
        (the social force then takes the robot as one agent more in its all-pairs sum, a
        different program from the one with the flags).
    """

    x_m: jax.Array
    y_m: jax.Array
    vx_mps: jax.Array
    vy_mps: jax.Array
    present: jax.Array
    moving: jax.Array
    ignores_robot: jax.Array | None = None

    @classmethod
    def of(cls, xy_m: jax.Array, velocity_mps: jax.Array, present: jax.Array, moving: jax.Array,
           ignores_robot: jax.Array | None = None) -> Walkers:  # fmt: skip
        """From (N, 2) positions and velocities."""
        return cls(xy_m[:, 0], xy_m[:, 1], velocity_mps[:, 0], velocity_mps[:, 1], present, moving, ignores_robot)

    def moved(self, x_m: jax.Array, y_m: jax.Array, vx_mps: jax.Array, vy_mps: jax.Array) -> Walkers:
        """The same people at new positions and velocities (a model's step returns this)."""
        return self.replace(x_m=x_m, y_m=y_m, vx_mps=vx_mps, vy_mps=vy_mps)

    @property
    def xy_m(self) -> jax.Array:
        """(N, 2) positions (m)."""
        return jnp.stack([self.x_m, self.y_m], axis=-1)

    @property
    def velocity_mps(self) -> jax.Array:
        """(N, 2) velocities (m/s)."""
        return jnp.stack([self.vx_mps, self.vy_mps], axis=-1)


@struct.dataclass
class Aims:
    """Where N people are going this step (their behaviours decide it; the model moves them).

    Attributes:
      dx_m, dy_m: (N,) from each person to where they are going now (m).
      speed_mps: (N,) the speed each wants (a person settling on a spot slows down).
      max_speed_mps: (N,) the cap on the speed after the step, used by the social force and the
        power law (pedsim's cap; the arena's people and the validation's corridors give the
        desired speed again); the velocity models and ORCA walk at most ``speed_mps``.
    """

    dx_m: jax.Array
    dy_m: jax.Array
    speed_mps: jax.Array
    max_speed_mps: jax.Array


@struct.dataclass
class RobotDisc:
    """The robot as the people see it: a disc they avoid, not moved by their step.

    Attributes:
      x_m, y_m, vx_mps, vy_mps: () its position (m) and velocity (m/s).
      radius_m: its body (m); the social force's pair force has no radius and ignores it.
    """

    x_m: jax.Array
    y_m: jax.Array
    vx_mps: jax.Array
    vy_mps: jax.Array
    radius_m: float | jax.Array

    @classmethod
    def of(cls, xy_m: jax.Array, velocity_mps: jax.Array, radius_m: float | jax.Array) -> RobotDisc:
        """From (2,) position and velocity."""
        return cls(xy_m[0], xy_m[1], velocity_mps[0], velocity_mps[1], radius_m)


class HumanStep(Protocol):
    """A human model's step: ``params`` its constants (a traced pytree), ``wall_field`` the world's
    distance field, ``dt`` the step (s, static), ``uniforms`` two (N,) draws in (0, 1]; the people
    after the step (the same flags, new positions and velocities)."""

    def __call__(
        self,
        params: Any,
        wall_field: Grid,
        dt: float,
        people: Walkers,
        aims: Aims,
        robot: RobotDisc,
        uniforms: tuple[jax.Array, jax.Array],
    ) -> Walkers: ...
