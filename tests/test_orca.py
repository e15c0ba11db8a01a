"""ORCA's crowd step at scale (issue 66): the same answers as the step it replaced, which solved
every program for everyone against everyone (``tests/orca_reference.py``), with RVO2's
neighbour cap and the third program run only for the people whose second failed."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from socialnav.data import DATA_DIR
from socialnav.evaluation.arena import episodes as arena
from socialnav.jaxsim import humans, orca
from socialnav.jaxsim.grid import Grid
from socialnav.jaxsim.params import PERSON_RADIUS_M
from socialnav.jaxsim.scenes import people as people_lib
from socialnav.jaxsim.scenes.env import EnvConfig
from socialnav.jaxsim.scenes.spec import load_scene
from socialnav.jaxsim.scenes.variant import sample_variant
from socialnav.jaxsim.walkers import Aims, RobotDisc, Walkers
from tests import orca_reference as reference

OPEN = Grid.of_samples(jnp.tile(jnp.array([100.0, 1.0, 0.0]), (4, 4, 1)), -50.0, -50.0, 30.0)
ROBOT = (jnp.float32(0.3), jnp.float32(0.1), jnp.float32(0.2), jnp.float32(0.0))
DT = 0.1


def _new_step(p, field, dt, x, y, vx, vy, aim_dx, aim_dy, speed, present, moving, robot_xyv, robot_radius_m,
              ignores_robot=None):  # fmt: skip
    """The step under test called with the reference's arguments: ``(x, y, vx, vy)``."""
    people = Walkers(x, y, vx, vy, present, moving, ignores_robot)
    robot = RobotDisc(*robot_xyv, robot_radius_m)
    after = orca.step_orca(p, field, dt, people, Aims(aim_dx, aim_dy, speed, speed), robot)
    return after.x_m, after.y_m, after.vx_mps, after.vy_mps


# Both steps compiled, also where a test runs them once: run eagerly, every JAX operation inside
# is compiled on its own (hundreds of small programs a call, most of this file's time).
step = jax.jit(_new_step)
reference_step = jax.jit(reference.step_orca)


def _reference_params(p: orca.ORCAParams) -> reference.ORCAParams:
    return reference.ORCAParams(p.radius_m, p.time_horizon_s, p.time_horizon_obst_s, p.neighbor_dist_m,
                                p.safety_space_m)  # fmt: skip


def _crowd(n: int, seed: int, density: float = 1.0, dtype=jnp.float32):
    """A random crowd crossing itself: (x, y, vx, vy, aim_dx, aim_dy, speed, present, moving)."""
    rng = np.random.default_rng(seed)
    side = np.sqrt(n / density)
    xy = rng.uniform(-side / 2, side / 2, (n, 2))
    v = rng.uniform(-1, 1, (n, 2))
    aim = -2 * xy
    present = rng.uniform(size=n) > 0.1
    moving = present & (rng.uniform(size=n) > 0.2)
    arrays = (xy[:, 0], xy[:, 1], v[:, 0], v[:, 1], aim[:, 0], aim[:, 1], rng.uniform(1.0, 1.4, n))
    return tuple(jnp.asarray(a, dtype) for a in arrays) + (jnp.asarray(present), jnp.asarray(moving))


def _second_program_fails(p, crowd) -> int:
    """How many people of ``crowd`` the second program leaves to the third (the old step's
    lines: everyone against everyone)."""
    return int(_count_second_program_fails(p, crowd))


@jax.jit
def _count_second_program_fails(p, crowd):
    x, y, vx, vy, ax, ay, speed, present, moving = crowd
    n = x.shape[0]
    xy, v = jnp.stack([x, y], -1), jnp.stack([vx, vy], -1)
    d = jnp.hypot(ax, ay)
    pref = jnp.stack([ax, ay], -1) * (jnp.minimum(speed, d / DT) / jnp.maximum(d, 1e-9))[:, None]
    r = p.radius_m + p.safety_space_m

    def one(i):
        ok = present & (jnp.arange(n) != i)
        u, dirs = jax.vmap(orca.orca_line, in_axes=(0, 0, None, None, None, 0))(
            xy - xy[i], v[i] - v, r + p.radius_m, 1.0 / p.time_horizon_s, DT, jnp.where(moving, 0.5, 1.0)
        )
        failed, _ = reference._lp2(v[i] + u, dirs, ok, speed[i], pref[i], False)
        return failed < n

    return jnp.sum(jax.vmap(one)(jnp.arange(n)) & moving)


@pytest.mark.parametrize(
    "n", [pytest.param(2, marks=pytest.mark.slow), 7, 16, pytest.param(40, marks=pytest.mark.slow)]
)
@pytest.mark.slow
def test_equal_to_the_step_that_solved_everything_for_everyone(n):
    """In float64 the same answers to 1e-9 (the same programs, in another layout and order of
    work). In float32, as the step runs, a third program that is ill-conditioned (its answer at
    a near-tie between two lines) rounds either way, in the old step as in the new: measured
    against the float64 answer, the new step's positions are nowhere further off than the old
    one's by more than 1e-5 m (the old step was 1.7 cm off for one person of seed 3 at 40 people
    and 0.6 mm for one of seed 0 at 16, the new one 8e-7 m and 8e-6 m; at 7 people, seed 2, both
    3.4 mm)."""
    p = orca.ORCAParams(max_neighbors=n)  # the cap above the crowd: nobody is left out
    fails = 0
    for seed in range(4):
        crowd = _crowd(n, seed, density=2.0)
        fails += _second_program_fails(p, crowd)
        ours = step(p, OPEN, DT, *crowd, ROBOT, 0.3)
        before = reference_step(_reference_params(p), OPEN, DT, *crowd, ROBOT, 0.3)
        with jax.enable_x64(True):
            crowd = _crowd(n, seed, density=2.0, dtype=jnp.float64)
            exact = step(p, OPEN, DT, *crowd, ROBOT, 0.3)
            old = reference_step(_reference_params(p), OPEN, DT, *crowd, ROBOT, 0.3)
            assert exact[0].dtype == jnp.float64
            np.testing.assert_allclose(np.asarray(exact), np.asarray(old), atol=1e-9)

        truth = np.asarray(exact[:2])
        ours_off_m, before_off_m = (np.abs(np.asarray(a[:2], np.float64) - truth).max(axis=0) for a in (ours, before))
        assert np.all(ours_off_m <= before_off_m + 1e-5)
    if n >= 16:
        assert fails > 0  # the dense crowds reach the third program: the fallback was compared too


@pytest.mark.slow
def test_batched_over_worlds_equals_one_world_at_a_time():
    p = orca.ORCAParams()
    crowds = [_crowd(24, seed, density=2.0) for seed in range(3)]
    batched = jax.vmap(lambda *c: _new_step(p, OPEN, DT, *c, ROBOT, 0.3))(
        *(jnp.stack(a) for a in zip(*crowds)))  # fmt: skip
    for w, crowd in enumerate(crowds):
        alone = _new_step(p, OPEN, DT, *crowd, ROBOT, 0.3)  # both eager, as they were written
        for got, want in zip(batched, alone):
            np.testing.assert_allclose(np.asarray(got[w]), np.asarray(want), atol=1e-6)


@pytest.mark.slow
def test_a_person_feels_only_its_nearest_neighbors():
    n, cap = 20, 3
    x, y, vx, vy, ax, ay, speed, present, moving = _crowd(n, 5, density=1.5)
    present = jnp.ones(n, bool)
    moving = jnp.ones(n, bool)
    capped = step(orca.ORCAParams(max_neighbors=cap), OPEN, DT, x, y, vx, vy, ax, ay, speed, present,
                            moving, ROBOT, 0.3)  # fmt: skip
    d = np.hypot(np.asarray(x - x[0]), np.asarray(y - y[0]))
    d[0] = np.inf
    only_nearest = jnp.asarray(np.isin(np.arange(n), np.argsort(d)[:cap]) | (np.arange(n) == 0))
    alone = reference_step(reference.ORCAParams(radius_m=PERSON_RADIUS_M), OPEN, DT, x, y, vx, vy, ax, ay, speed,
                                only_nearest, moving, ROBOT, 0.3)  # fmt: skip
    for got, want in zip(capped, alone):
        np.testing.assert_allclose(float(got[0]), float(want[0]), atol=1e-5)
    everyone = step(orca.ORCAParams(max_neighbors=n), OPEN, DT, x, y, vx, vy, ax, ay, speed, present,
                              moving, ROBOT, 0.3)  # fmt: skip
    assert not np.allclose(np.asarray(everyone[2]), np.asarray(capped[2]), atol=1e-4)  # the cap changed someone


def test_nearest_neighbors_by_index_the_far_and_absent_left_out():
    xy = jnp.array([[0.0, 0.0], [5.0, 0.0], [1.0, 0.0], [2.0, 0.0], [0.5, 0.0]])
    eligible = jnp.array([[j != i and j != 3 for j in range(5)] for i in range(5)])  # person 3 absent
    index, valid = orca.nearest_neighbors(xy, eligible, 2, 10.0)
    assert index[0].tolist() == [2, 4] and valid[0].all()  # the two nearest of 0, listed by index
    assert index[1].tolist() == [2, 4]  # 3 is nearer to 1 than 4 is, but absent
    index, valid = orca.nearest_neighbors(xy, eligible, 3, 4.2)
    assert index[1].tolist()[0] == 2 and valid[1].tolist() == [True, False, False]  # only 2 within 4.2 m of 1
    lone = orca.nearest_neighbors(xy[:1], jnp.zeros((1, 1), bool), 1, 10.0)
    assert not bool(lone[1].any())


@pytest.mark.slow
@pytest.mark.parametrize("scene", ["casn_crossing", "gscl_crowded_entrance", "snape_two_walking", "gscl_queue"])
def test_equal_to_the_old_step_on_the_arena_scenes(scene):
    spec = load_scene(DATA_DIR / "scenes" / f"{scene}.json")
    setup = arena.setup_scene(spec, arena.ArenaConfig.of("orca"))
    env = setup.env
    p = env.orca  # the default cap: no seed scene has more than 11 people at once
    v = jax.tree_util.tree_map(jnp.asarray, sample_variant(spec, 0, 3, n_slots=setup.n_slots))
    field, dt = env.world.wall_field, env.crowd.dt_s
    robot_xy, robot_v = jnp.asarray(v.robot_xy, jnp.float32), jnp.array([0.3, 0.0], jnp.float32)
    robot = (robot_xy[0], robot_xy[1], robot_v[0], robot_v[1])

    @jax.jit
    def both(s, step):
        target, speed, mobile = people_lib.targets(v, s, step.astype(jnp.float32) * dt)
        args = (field, dt, s.xy[:, 0], s.xy[:, 1], s.velocity[:, 0], s.velocity[:, 1], target[:, 0] - s.xy[:, 0],
                target[:, 1] - s.xy[:, 1], speed, s.present, mobile, robot, env.robot.radius_m)  # fmt: skip
        new = _new_step(p, *args, ignores_robot=v.ignore_robot)
        old = reference.step_orca(_reference_params(p), *args, ignores_robot=v.ignore_robot)
        constants = humans.human_params("orca", env.crowd, p)
        disc = RobotDisc.of(robot_xy, robot_v, env.robot.radius_m)
        nxt = people_lib.step_people("orca", constants, env.world, v, s, disc, step)
        return new, old, nxt

    s = people_lib.init_people(v)
    for step in range(0, 80):
        new, old, s = both(s, jnp.int32(step))
        np.testing.assert_allclose(np.asarray(new[:2]), np.asarray(old[:2]), atol=1e-5)


@pytest.mark.slow
def test_the_radius_is_the_toolkits_person_and_traced():
    assert orca.ORCAParams().radius_m == PERSON_RADIUS_M
    spec = load_scene(DATA_DIR / "scenes" / "casn_head_on.json")
    env = arena.setup_scene(spec, arena.ArenaConfig(env=EnvConfig(human_model="orca", person_radius_m=0.3))).env
    assert env.orca.radius_m == 0.3  # the env's people: the body it counts contacts with
    crowd = _crowd(10, 1, density=2.0)

    def final_x(radius):
        p = orca.ORCAParams(radius_m=radius)
        return jnp.sum(_new_step(p, OPEN, DT, *crowd, ROBOT, 0.3)[0])

    # Traced: one compiled program for every radius, and a forward-mode derivative through it.
    _, slope = jax.jit(lambda r, t: jax.jvp(final_x, (r,), (t,)))(jnp.float32(0.25), jnp.float32(1.0))
    assert np.isfinite(float(slope)) and abs(float(slope)) > 0
