"""The anticipatory power law of Karamouzas, Skinner & Guy (2014, "Universal power law governing
pedestrian interactions", Physical Review Letters 113, 238701), with the bodies' contact forces
of Helbing, Farkas & Vicsek (2000, "Simulating dynamical features of escape panic", Nature 407,
487-490): a force-based human model whose people avoid each other by when they would collide,
not by how far apart they are.

Second order: a person of unit mass accelerates by

  F_i = (v0_i e_i - v_i) / xi                                           driving force
      + sum_j -grad_x E(tau_ij),   E(tau) = k / tau^2 exp(-tau / tau0)  the power law
      + sum_j [kappa_n g_ij n_ij + kappa_t g_ij (v_j - v_i) . t_ij t_ij]  bodies in contact
      + the same two against the nearest wall

with ``tau_ij`` the time until the two bodies (radii summing to ``R``) would touch if both kept
their velocities, ``g_ij = max(R - d_ij, 0)`` the overlap, ``n_ij`` the unit vector from j to i
and ``t_ij`` its normal. KSG measured ``E`` over pairs of real pedestrians (outdoor and
bottleneck recordings) and found the exponent 2 and ``tau0`` of about 3 s; their reference code (the
``TTC`` sample library that ships with the paper) gives the defaults below: ``k`` 1.5 m²/s²,
``tau0`` 3 s, ``xi`` 0.54 s, the acceleration capped at 20 m/s², neighbours within 10 m, and,
for a pair already overlapping, their separation used as the radius (so an overlap still has a
time to collision while it is shallower than half the bodies). The gradient of ``E`` is the
paper's closed form (its supplement; with ``w = x_j - x_i``, ``v = v_i - v_j``, ``a = v.v``,
``b = w.v``, ``c = w.w - R^2``, ``tau = (b - sqrt(b^2 - a c)) / a``)::

  F_ij = -k exp(-tau/tau0) (v - (b v - a w) / sqrt(b^2 - a c)) / (a tau^2) (2/tau + 1/tau0)

The power law has no force between people walking at the same velocity (no collision ahead),
so it cannot by itself keep bodies apart in a dense crowd; Helbing, Farkas & Vicsek's body
force (stiffness 1.2e5 kg/s², sliding friction 2.4e5 kg/(m s), over their 80 kg: the per-mass
defaults below) is added, as KSG's paper leaves to the simulator and as UMANS (Inria's
simulator) combines them. Walls: the time to collision with the nearest wall (the wall taken as
the plane of its normal in the crowd's distance field) under the same law, the wall's contact
force, and the crowd's hard wall constraint (:func:`jaxsim.crowd.wall_constraint`). The robot
is one more body (its radius, its velocity), felt unless a person ``ignores_robot``.

Choices made here, where the sources leave them open: the body radius is 0.2 m (JuPedSim's
velocity models'; KSG's example programs use 0.3-0.5 m), fitted by ``socialnav humans calibrate
--model power_law``; the step ``dt`` is split into :data:`SUBSTEPS` explicit (symplectic Euler) steps, since the contact
force's stiffness needs a step under 2 / sqrt(1500) = 0.05 s; KSG's cap on the acceleration
bounds what a person does (the driving force and the law), not the contact force, which is
physical (capped too, a pressed crowd's bodies sink into each other); the speed is
capped at ``max_speed_mps`` as the social force's is. No random force: the model is
deterministic.

Everything is a smooth function of positions and velocities where the collision test does not
change (the ``where``s guard the square roots and divisions so a gradient never meets a NaN,
and the law's singularity where two paths just touch is capped: :data:`GRAZING`),
so a loss over a rollout differentiates through it (:mod:`evaluation.humans.calibration`).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from flax import struct

from socialnav.jaxsim.crowd import wall_constraint
from socialnav.jaxsim.grid import Grid
from socialnav.jaxsim.walkers import Aims, RobotDisc, Walkers

_EPS = 1e-6
EXPONENT = 2.0  # the power of the law, KSG's fit to the data (tau^-2)
MIN_TAU_S = 1e-3  # a collision sooner than this is under way: the contact force's, not the law's
SUBSTEPS = 10  # explicit steps per step of the crowd (0.01 s at the toolkit's 0.1 s)
GRAZING = 0.1  # the smallest square root of the time to collision's discriminant, as a share of its largest


@struct.dataclass
class PowerLawParams:
    """The power law's and the contact force's constants (dynamic floats: traced, fittable).

    Karamouzas, Skinner & Guy's reference code: ``strength_m2ps2`` (their ``k``) 1.5,
    ``horizon_s`` (``tau0``) 3 s, ``relaxation_s`` (``ksi``) 0.54 s, ``max_accel_mps2`` 20,
    ``cutoff_m`` (``neighborDist``) 10 m. Helbing, Farkas & Vicsek's body force per unit mass:
    ``contact_stiffness_ps2`` 1.2e5 / 80 = 1500 s^-2, ``contact_friction_pms`` 2.4e5 / 80 = 3000
    m^-1 s^-1. ``radius_m`` 0.2 m (the module's docstring says why). ``min_tau_s``: the law is
    evaluated at no sooner a collision than this (0, the paper's: none; a probe of where the
    law's gradient grows, docs/humans.md)."""

    strength_m2ps2: float = 1.5
    horizon_s: float = 3.0
    relaxation_s: float = 0.54
    radius_m: float = 0.2
    max_accel_mps2: float = 20.0
    cutoff_m: float = 10.0
    contact_stiffness_ps2: float = 1500.0
    contact_friction_pms: float = 3000.0
    min_tau_s: float = 0.0


def _law(params: PowerLawParams, tau, approach):
    """``-dE/dtau`` of the law at ``tau`` (no sooner than ``params.min_tau_s``) where
    ``approach``, else 0."""
    t = jnp.where(approach, jnp.maximum(tau, params.min_tau_s), 1.0)
    k, t0 = params.strength_m2ps2, params.horizon_s
    return jnp.where(approach, k * jnp.exp(-t / t0) / t**EXPONENT * (EXPONENT / t + 1.0 / t0), 0.0)


def pair_forces(params: PowerLawParams, wx, wy, vx, vy, reach, others, substep_s: float = 0.0):
    """The power law's push on each person from the other bodies and the contact force's, each
    summed: ``(lx, ly), (cx, cy)`` (N,) each. ``wx, wy`` (N, M): from i to j (``x_j - x_i``);
    ``vx, vy`` (N, M): ``v_i - v_j``; ``reach`` (N, M): the radii's sum; ``others`` (N, M) bool:
    j counts for i. ``substep_s``: the step the force is applied over; the sliding friction is
    taken linearly implicit there (a rate ``kappa g`` of 300/s at 0.1 m of overlap times a 0.01 s
    step is past explicit Euler's limit of 2, where the slip would flip and grow), 0: Helbing's
    force as written."""
    dist2 = wx * wx + wy * wy
    dist = jnp.sqrt(dist2 + _EPS * _EPS)
    radius = jnp.where(dist < reach, reach - dist, reach)  # KSG: an overlap's separation as the radius
    a = vx * vx + vy * vy
    b = wx * vx + wy * vy
    c = dist2 - radius * radius
    disc = b * b - a * c
    real = (disc > 0.0) & (a > _EPS)
    # disc = a (R^2 - m^2), m the distance by which the two paths miss: where they just touch
    # (m -> R) the law's force and its gradient diverge; the root is held at or above GRAZING of
    # its largest value, a change only for paths that miss by more than 99.5 % of R.
    root = jnp.sqrt(jnp.where(real, jnp.maximum(disc, GRAZING**2 * a * radius * radius), 1.0))
    tau = (b - root) / jnp.where(real, a, 1.0)
    approach = others & real & (tau > MIN_TAU_S)
    scale = -_law(params, tau, approach) / jnp.where(approach, a, 1.0)
    lx = scale * (vx - (b * vx - a * wx) / root)
    ly = scale * (vy - (b * vy - a * wy) / root)

    overlap = jnp.where(others, jnp.maximum(reach - dist, 0.0), 0.0)
    nx, ny = -wx / dist, -wy / dist  # from j to i
    tx, ty = -ny, nx
    slip = -(vx * tx + vy * ty)  # (v_j - v_i) . t
    rate = params.contact_friction_pms * overlap
    rub = rate * slip / (1.0 + 2.0 * rate * substep_s)  # both bodies slow the slip between them
    cx = params.contact_stiffness_ps2 * overlap * nx + rub * tx
    cy = params.contact_stiffness_ps2 * overlap * ny + rub * ty
    return (jnp.sum(lx, axis=1), jnp.sum(ly, axis=1)), (jnp.sum(cx, axis=1), jnp.sum(cy, axis=1))


def wall_forces(params: PowerLawParams, wall, nx, ny, vx, vy, substep_s: float = 0.0):
    """The nearest wall's push, its time to collision under the law and its contact force:
    ``(lx, ly), (cx, cy)`` (N,) each; ``wall`` (N,) the distance to it, ``nx, ny`` its outward
    normal; ``substep_s`` as :func:`pair_forces`'."""
    closing = -(vx * nx + vy * ny)
    gap = wall - params.radius_m
    tau = gap / jnp.where(closing > _EPS, closing, 1.0)
    approach = (closing > _EPS) & (gap > 0.0) & (tau > MIN_TAU_S) & (wall < params.cutoff_m)
    law = _law(params, tau, approach) / jnp.where(approach, closing, 1.0)
    overlap = jnp.maximum(params.radius_m - wall, 0.0)
    slip = vx * -ny + vy * nx  # along the wall
    rate = params.contact_friction_pms * overlap
    push, friction = params.contact_stiffness_ps2 * overlap, rate * slip / (1.0 + rate * substep_s)
    return (law * nx, law * ny), (push * nx + friction * ny, push * ny - friction * nx)


def step_power_law(
    params: PowerLawParams,
    wall_field: Grid,
    dt: float,
    people: Walkers,
    aims: Aims,
    robot: RobotDisc,
    uniforms: tuple[jax.Array, jax.Array] | None = None,
) -> Walkers:
    """One step ``dt`` (s) of N people, :data:`SUBSTEPS` explicit steps of the forces of the
    module's docstring (the human models' signature, :mod:`jaxsim.walkers`; ``uniforms`` is not
    used): the people after the step, the velocity 0 for who does not move. ``aims.max_speed_mps``
    caps the speed; who is not ``people.moving`` keeps their place and is felt at their velocity;
    the robot, a body of ``robot.radius_m`` the people avoid unless ``people.ignores_robot``, keeps
    its place during the step.
    """
    x, y, vx, vy = people.x_m, people.y_m, people.vx_mps, people.vy_mps
    present, moving, ignores_robot = people.present, people.moving, people.ignores_robot
    aim_dx, aim_dy, desired_speed_mps, max_speed_mps = aims.dx_m, aims.dy_m, aims.speed_mps, aims.max_speed_mps
    robot_radius_m = robot.radius_m
    n = x.shape[0]
    rx, ry, rvx, rvy = robot.x_m, robot.y_m, robot.vx_mps, robot.vy_mps
    feels_robot = jnp.ones(n, bool) if ignores_robot is None else ~ignores_robot
    radius = jnp.concatenate([jnp.full(n, params.radius_m), jnp.full(1, robot_radius_m)])
    reach = radius[None, :] + params.radius_m
    source = jnp.concatenate([present, jnp.ones(1, bool)])
    not_self = jnp.arange(n + 1)[None, :] != jnp.arange(n)[:, None]
    felt = not_self & source[None, :]
    felt = felt.at[:, n].set(felt[:, n] & feels_robot)
    h = dt / SUBSTEPS
    aim = jnp.sqrt(aim_dx * aim_dx + aim_dy * aim_dy + _EPS * _EPS)
    speed = jnp.minimum(desired_speed_mps, aim / dt)  # do not overshoot a target that is close
    # the target keeps its place during the step: each substep aims at where it is from there
    target_x, target_y = x + aim_dx, y + aim_dy

    def substep(carry, _):
        px, py, qx, qy = carry
        xs, ys = jnp.concatenate([px, rx[None]]), jnp.concatenate([py, ry[None]])
        vxs, vys = jnp.concatenate([qx, rvx[None]]), jnp.concatenate([qy, rvy[None]])
        wx, wy = xs[None, :] - px[:, None], ys[None, :] - py[:, None]
        others = felt & (wx * wx + wy * wy < params.cutoff_m * params.cutoff_m)
        (lx, ly), (cx, cy) = pair_forces(params, wx, wy, qx[:, None] - vxs[None, :], qy[:, None] - vys[None, :],
                                         reach, others, h)  # fmt: skip
        field = wall_field.lookup(px, py)
        wall, nx, ny = field[..., 0], field[..., 1], field[..., 2]
        (wlx, wly), (wcx, wcy) = wall_forces(params, wall, nx, ny, qx, qy, h)
        ax, ay = target_x - px, target_y - py
        to = jnp.sqrt(ax * ax + ay * ay + _EPS * _EPS)
        # what a person does (drive and avoid) is capped; what bodies in contact do to them is not
        fx = lx + wlx + (speed * ax / to - qx) / params.relaxation_s
        fy = ly + wly + (speed * ay / to - qy) / params.relaxation_s
        force = jnp.sqrt(fx * fx + fy * fy + _EPS * _EPS)
        cap = jnp.minimum(1.0, params.max_accel_mps2 / force)
        nvx, nvy = qx + h * (cap * fx + cx + wcx), qy + h * (cap * fy + cy + wcy)
        now = jnp.sqrt(nvx * nvx + nvy * nvy + _EPS * _EPS)
        slow = jnp.minimum(1.0, max_speed_mps / now)
        nvx, nvy = nvx * slow, nvy * slow
        nx_, ny_, nvx, nvy = wall_constraint(wall, nx, ny, px + h * nvx, py + h * nvy, nvx, nvy, h)
        return (
            jnp.where(moving, nx_, px),
            jnp.where(moving, ny_, py),
            jnp.where(moving, nvx, qx),
            jnp.where(moving, nvy, qy),
        ), None

    # Differentiated, each substep is computed again on the way back instead of keeping its (N, N + 1)
    # intermediates (a calibration's hundreds of substeps of six corridors run out of memory); a
    # forward run is the same program either way.
    carry = (x, y, vx, vy)
    (new_x, new_y, new_vx, new_vy), _ = jax.lax.scan(jax.checkpoint(substep), carry, None, length=SUBSTEPS)
    zero = jnp.zeros_like(new_vx)
    return people.moved(new_x, new_y, jnp.where(moving, new_vx, zero), jnp.where(moving, new_vy, zero))


# Fitted parameters shipped as named human models (``--human-model <name>``): the fit of
# ``socialnav humans calibrate --model power_law`` on the Jülich training runs (seed 0; the values
# its fit.json holds), scored on held-out data in docs/humans.md. The search's (Nelder-Mead) fit
# ships, chosen by its lower *training* loss than the truncated gradient's.
CALIBRATED: dict[str, PowerLawParams] = {
    "power_law_calibrated": PowerLawParams(
        strength_m2ps2=1.3991, horizon_s=4.1402, relaxation_s=0.4731, radius_m=0.2949
    )
}


def params_of(name: str) -> PowerLawParams:
    """The parameters a power-law model's name runs with: its calibrated preset, or the defaults."""
    return CALIBRATED.get(name, PowerLawParams())
