"""The arena's episodes: every method reaches an empty scene's goal, determinism, devices, padding
and the programs scenes share."""

import dataclasses
import json

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from socialnav.data import DATA_DIR
from socialnav.evaluation.arena import episodes as arena
from socialnav.jaxsim.scenes import robot as robot_lib
from socialnav.jaxsim.scenes import world as world_lib
from socialnav.jaxsim.scenes.spec import load_scene
from socialnav.jaxsim.scenes.variant import padded_slots, sample_variant, sample_variants
from socialnav.planners.stack import METHODS


def _empty_scene(tmp_path):
    scene = {
        "name": "empty",
        "bounds_m": [-4, 4, -3, 3],
        "walls": [[-4, 4, -3, -2.9], [-4, 4, 2.9, 3], [-4, -3.9, -3, 3], [3.9, 4, -3, 3], [-0.5, 0.5, -1.0, 1.0]],
        "robot": {"start": [-3, [-0.2, 0.2]], "yaw_deg": 0, "goal": [3, 0]},
        "timeout_s": 40,
        "people": [],
        "rule": {"type": "min_distance", "distance_m": 0.45},
    }
    path = tmp_path / "empty.json"
    path.write_text(json.dumps(scene))
    return load_scene(path)


@pytest.mark.slow
def test_every_method_reaches_the_goal_of_a_scene_without_people_and_stays_out_of_walls(tmp_path):
    from flax import nnx

    from socialnav.models import unet

    model = unet.UNet((4, 4, 8, 8), rngs=nnx.Rngs(0))
    model.eval()
    spec = _empty_scene(tmp_path)
    setup = arena.setup_scene(spec)
    variants = jax.tree_util.tree_map(jnp.asarray, sample_variants(spec, 0, 3))
    for name, method in METHODS.items():
        run = arena.episode_function(setup, method, arena.crowd_params(), gscl_model=lambda m: model(m))
        tr = run(variants)
        assert np.all(np.asarray(tr.reached[:, -1])), name
        d = world_lib.wall_distance(tr.robot_xy_m, setup.world.walls_m)[0]
        assert float(jnp.min(d)) >= robot_lib.RobotParams().radius_m - 1e-4, name


@pytest.mark.slow
def test_episodes_are_deterministic_and_the_same_variant_for_every_method():
    spec = load_scene(DATA_DIR / "scenes" / "casn_head_on.json")
    setup = arena.setup_scene(spec)
    variants = jax.tree_util.tree_map(jnp.asarray, sample_variants(spec, 3, 2))
    run = arena.episode_function(setup, METHODS["casn"], arena.crowd_params())
    a, b = run(variants), run(variants)
    for x, y in zip(jax.tree_util.tree_leaves(a), jax.tree_util.tree_leaves(b), strict=True):
        np.testing.assert_array_equal(x, y)
    other = arena.episode_function(setup, METHODS["navfn"], arena.crowd_params())(variants)
    np.testing.assert_array_equal(a.people_xy_m[:, 0], other.people_xy_m[:, 0])  # same start for both


_SPREAD = """
import jax
from socialnav.data import DATA_DIR
from socialnav.evaluation.arena import run as arena_run
from socialnav.jaxsim.scenes.spec import load_scene
spec = load_scene(DATA_DIR / 'scenes' / 'casn_head_on.json')
methods = ['navfn', 'snl_small', 'orca', 'snl_large']
one, _ = arena_run.run_scene(spec, methods, 9, n_devices=1)
two, _ = arena_run.run_scene(spec, methods, 9, n_devices=2)
print(jax.local_device_count(), one.equals(two), one.method.tolist() == two.method.tolist(), len(two))
"""


@pytest.mark.slow
def test_methods_spread_over_two_host_devices_give_the_same_table_as_one_after_the_other():
    """``arena.run_spread``: with two XLA host devices the programs are dealt to devices 0, 1, 0, ...
    (the two SNL variants share one, on one device) and run at once; the episodes are the same
    bits as one after the other on one."""
    import os
    import subprocess
    import sys

    env = dict(os.environ, XLA_FLAGS="--xla_force_host_platform_device_count=2")  # the session's cache, inherited
    root = DATA_DIR.parent
    out = subprocess.run([sys.executable, "-c", _SPREAD], cwd=root, env=env, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.split() == ["2", "True", "True", "36"]


def test_run_spread_yields_in_order_and_raises_a_methods_error():
    variants = jnp.arange(4.0)
    ok = list(arena.run_spread([lambda v: v + 1, lambda v: v * 2, lambda v: -v], variants))
    np.testing.assert_array_equal(ok[1], [0, 2, 4, 6])
    assert [float(r[3]) for r in ok] == [4.0, 6.0, -3.0]

    def broken(v):
        raise ValueError("method broke")

    with pytest.raises(ValueError, match="method broke"):
        list(arena.run_spread([lambda v: v, broken], variants))


def test_the_snl_variants_share_one_program_with_their_own_covariances():
    """The three SNL methods differ only in traced covariances, so they run one compiled program
    (``planners.stack.program_config``), each with its own parameters; the other methods keep
    their own programs."""
    setup = arena.setup_scene(load_scene(DATA_DIR / "scenes" / "casn_head_on.json"))
    runs = {m: arena.episode_function(setup, METHODS[m]) for m in ("snl_small", "snl_large", "snl_matched", "navfn")}
    assert runs["snl_small"].func is runs["snl_large"].func is runs["snl_matched"].func
    assert runs["navfn"].func is not runs["snl_small"].func
    sigmas = [jax.tree_util.tree_leaves(runs[m].args[1].layer) for m in ("snl_small", "snl_large", "snl_matched")]
    assert not np.allclose(sigmas[0], sigmas[1]) and not np.allclose(sigmas[1], sigmas[2])


@pytest.mark.slow
def test_a_shared_snl_program_gives_the_episodes_of_the_methods_own():
    """snl_large run by the shared program gives the same bits as by a program built for it."""
    from socialnav.planners import actors

    spec = load_scene(DATA_DIR / "scenes" / "casn_head_on.json")
    setup = arena.setup_scene(spec)
    variants = jax.tree_util.tree_map(jnp.asarray, sample_variants(spec, 0, 8, n_slots=setup.n_slots))
    shared = arena.episode_function(setup, METHODS["snl_large"])
    config = arena.ArenaConfig()
    radius = float(robot_lib.RobotParams().radius_m)
    own_actor = actors.stack_actor(
        METHODS["snl_large"], setup.grid, radius, config.replan_every_steps, config.max_path_cells
    )
    own = arena.actor_function(setup, own_actor, shared.args[1], shared.args[0])
    assert own.func is not shared.func
    for a, b in zip(jax.tree_util.tree_leaves(shared(variants)), jax.tree_util.tree_leaves(own(variants)), strict=True):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))


def test_padded_slots_is_a_power_of_two_of_at_least_two():
    assert [padded_slots(n) for n in (1, 2, 3, 4, 5, 6, 8, 9)] == [2, 2, 4, 4, 8, 8, 8, 16]


def test_padding_the_people_slots_keeps_the_draws_and_adds_empty_slots():
    spec = load_scene(DATA_DIR / "scenes" / "gscl_queue.json")
    own = sample_variant(spec, 4, 2)
    padded = sample_variant(spec, 4, 2, n_slots=8)
    n = spec.n_people_slots
    assert padded.valid.shape == (8,) and own.valid.shape == (n,)
    np.testing.assert_array_equal(padded.xy0[:n], own.xy0)
    np.testing.assert_array_equal(padded.speed_mps[:n], own.speed_mps)
    assert padded.seed_u32 == own.seed_u32 and not padded.valid[n:].any()
    assert np.all(padded.group[n:] == -1) and np.all(np.isinf(padded.turn_at_s[n:]))
    assert sample_variant(spec, 4, 2, n_slots=1).valid.shape == (n,)  # never fewer than the scene's own


def test_scenes_of_a_family_share_one_program_shape():
    """Seed 001's four scenes (1 or 2 people, the same room) pad to one set of shapes, so jit
    compiles each method once for all four; seed 002's queue (5 people) pads to 8 slots."""
    names = ("casn_static_person", "casn_static_group")
    setups = [arena.setup_scene(load_scene(DATA_DIR / "scenes" / f"{n}.json")) for n in names]
    arrays = [(s.env, s.map) for s in setups]
    shapes = [jax.tree_util.tree_map(lambda a: (np.shape(a), np.asarray(a).dtype), a) for a in arrays]
    assert jax.tree_util.tree_structure(arrays[0]) == jax.tree_util.tree_structure(arrays[1])
    assert shapes[0] == shapes[1]
    assert {s.n_slots for s in setups} == {2} and setups[0].grid == setups[1].grid
    assert setups[0].env.world.walls_m.shape[0] % 8 == 0
    assert arena.setup_scene(load_scene(DATA_DIR / "scenes" / "gscl_queue.json")).n_slots == 8


@pytest.mark.slow
def test_padding_walls_changes_no_episode_and_padding_people_only_rounding():
    spec = load_scene(DATA_DIR / "scenes" / "snape_static_pair.json")  # 7 walls -> 8, 2 objects -> 4
    setup = arena.setup_scene(spec)
    n_walls = len(spec.walls_m)
    assert setup.env.world.walls_m.shape[0] == 8 and n_walls < 8
    bare_env = setup.env.replace(world=setup.env.world.replace(walls_m=setup.env.world.walls_m[:n_walls]))
    m = setup.map
    bare_map = m.replace(
        walls_m=m.walls_m[:n_walls],
        objects_xy_m=m.objects_xy_m[:2],
        objects_cost=m.objects_cost[:2],
        objects_valid=m.objects_valid[:2],
    )
    unpadded = dataclasses.replace(setup, env=bare_env, map=bare_map)
    variants = jax.tree_util.tree_map(jnp.asarray, sample_variants(spec, 1, 2, n_slots=setup.n_slots))
    a = arena.episode_function(setup, METHODS["snape_social_eband"], arena.crowd_params())(variants)
    b = arena.episode_function(unpadded, METHODS["snape_social_eband"], arena.crowd_params())(variants)
    for x, y in zip(jax.tree_util.tree_leaves(a), jax.tree_util.tree_leaves(b), strict=True):
        np.testing.assert_array_equal(x, y)
    wide = jax.tree_util.tree_map(jnp.asarray, sample_variants(spec, 1, 2, n_slots=4))
    c = arena.episode_function(setup, METHODS["snape_social_eband"], arena.crowd_params())(wide)
    np.testing.assert_allclose(c.robot_xy_m, a.robot_xy_m, atol=1e-3)
    np.testing.assert_allclose(c.people_xy_m[:, :, :2], a.people_xy_m, atol=1e-3)
    assert not np.asarray(c.people_present[:, :, 2:]).any()


@pytest.mark.slow
def test_a_turned_scene_runs_the_scenes_episodes_turned():
    """The crossing turned a quarter turn: NavFn's robot and the walkers follow the scene's own
    paths, turned, to float rounding for the first 3 s (after that the closed loop may grow the
    rounding; where a point lies on a cell boundary, a grid planner may also pick the other cell,
    which is part of what the turned row measures)."""
    from socialnav.jaxsim.scenes.spec import turn, turn_bounds_m, turn_points

    spec = load_scene(DATA_DIR / "scenes" / "casn_crossing.json")
    trajectories = []
    for scene in (spec, turn(spec)):
        setup = arena.setup_scene(scene)
        variants = jax.tree_util.tree_map(jnp.asarray, sample_variants(scene, 0, 2, n_slots=setup.n_slots))
        trajectories.append(arena.episode_function(setup, METHODS["navfn"], arena.crowd_params())(variants))
    own, turned = trajectories
    about = turn_bounds_m(spec.bounds_m)
    steps = 30
    np.testing.assert_allclose(
        np.asarray(turned.robot_xy_m[:, :steps]), turn_points(np.asarray(own.robot_xy_m[:, :steps]), about), atol=1e-3
    )
    present = np.asarray(own.people_present[:, :steps])
    people = turn_points(np.asarray(own.people_xy_m[:, :steps]), about)
    np.testing.assert_allclose(np.asarray(turned.people_xy_m[:, :steps])[present], people[present], atol=1e-3)
    np.testing.assert_array_equal(np.asarray(turned.people_present[:, :steps]), present)
