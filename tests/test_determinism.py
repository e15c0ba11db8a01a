"""The same seed and settings give the same day bit for bit, whatever the batch size and the
number of XLA host devices (issue 17: one world alone, or one per device, used to drift from
the same world in a batch from step 2,140 on).

The comparison is a hash of every logged field of worlds 0..1 over 2,600 steps (past the old
divergence), taken in this process for several batch sizes and in subprocesses that ask XLA for
1, 2 and 4 host devices.
"""

from __future__ import annotations

import hashlib
import os
import pathlib
import subprocess
import sys

import jax
import numpy as np
import pytest

from socialnav.jaxsim.rollout import rollout
from socialnav.jaxsim.route_follower import route_follower
from socialnav.jaxsim.scenario import load_scenario
from socialnav.jaxsim.world import build_world
from socialnav.planners.warehouse.routes import shortest_path_plan

ROOT = pathlib.Path(__file__).resolve().parents[1]
N_STEPS, EVERY, COMPARED = 2600, 20, 2


def day_digest(n_worlds: int) -> str:
    """SHA-256 of every logged field of worlds 0..COMPARED-1 of a batch of ``n_worlds``."""
    scenario = load_scenario()
    world = build_world(scenario)
    controller = route_follower(shortest_path_plan(scenario), world)
    _, records = rollout(scenario.params, world, controller, 7, n_worlds, N_STEPS, EVERY)
    digest = hashlib.sha256()
    for leaf in jax.tree.leaves(records):
        digest.update(np.ascontiguousarray(np.asarray(leaf)[:COMPARED]).tobytes())
    return digest.hexdigest()


@pytest.mark.slow
def test_same_day_whatever_the_batch_size():
    digests = {b: day_digest(b) for b in (2, 3, 5, 8)}
    assert len(set(digests.values())) == 1, digests


def test_a_world_alone_is_the_same_world_as_in_a_batch():
    """World 0 simulated alone against world 0 of a batch of 3 (the case that drifted)."""
    scenario = load_scenario()
    world = build_world(scenario)
    controller = route_follower(shortest_path_plan(scenario), world)
    _, alone = rollout(scenario.params, world, controller, 7, 1, N_STEPS, EVERY)
    _, batch = rollout(scenario.params, world, controller, 7, 3, N_STEPS, EVERY)
    for a, b in zip(jax.tree.leaves(alone), jax.tree.leaves(batch), strict=True):
        np.testing.assert_array_equal(np.asarray(a)[0], np.asarray(b)[0])


@pytest.mark.slow
@pytest.mark.parametrize("n_devices", [1, 2, 4])
def test_same_day_whatever_the_number_of_host_devices(n_devices):
    """A subprocess with ``n_devices`` XLA host devices (batches of 2 and 4, so that 4 devices
    hold one world each) gives this process's digest."""
    code = (
        "import sys; sys.path.insert(0, 'tests'); from test_determinism import day_digest; "
        "import jax; print(jax.local_device_count(), day_digest(2), day_digest(4))"
    )
    env = dict(os.environ, XLA_FLAGS=f"--xla_force_host_platform_device_count={n_devices}")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True, check=True)
    count, two, four = out.stdout.split()
    assert int(count) == n_devices
    here = day_digest(2)
    assert two == here and four == here
