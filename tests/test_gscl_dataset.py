"""GSCL dataset (seed 002 Sec. 4.1), the families built so far: each rule pinned on generated
samples, plus the encoding, shapes, dtypes and determinism."""

from __future__ import annotations

import jax
import numpy as np
import pytest

from socialnav.models import dataset, families, grid
from socialnav.models import social_costs as sc

N = 64


@pytest.fixture(scope="module")
def data():
    return dataset.generate(0, {name: N for name in dataset.FAMILIES})


def _family(data, name):
    idx = np.flatnonzero(data["family"] == list(data["names"]).index(name))
    return data["inputs"][idx], data["targets"][idx]


@pytest.mark.slow
def test_shapes_codes_and_range(data):
    n = N * len(dataset.FAMILIES)
    assert data["inputs"].shape == (n, 40, 40) and data["inputs"].dtype == np.uint8
    assert data["targets"].shape == (n, 40, 40) and data["targets"].dtype == np.float32
    assert set(np.unique(data["inputs"])) <= set(grid.INPUT_CODES)
    assert data["targets"].min() >= 0.0 and data["targets"].max() <= 1.0


def test_deterministic_by_seed_and_independent_of_other_counts():
    a = dataset.generate(3, {"corner": 5, "group": 4})
    b = dataset.generate(3, {"group": 4, "corner": 5, "proxemics": 2})
    np.testing.assert_array_equal(a["inputs"][a["family"] == 0], b["inputs"][b["family"] == 0])
    c = dataset.generate(4, {"corner": 5})
    assert not np.array_equal(a["inputs"][:5], c["inputs"])
    with pytest.raises(ValueError, match="unknown families"):
        dataset.generate(0, {"corridor": 3})


@pytest.mark.slow
def test_every_person_carries_proxemic_cost_and_a_heading_pixel(data):
    for name in ("proxemics", "group", "non_group"):
        inputs, targets = _family(data, name)
        person = inputs == grid.PERSON
        assert person.any(axis=(1, 2)).all(), name
        # High cost on every person (the cell centre is up to 0.28 m from them: >= exp(-0.28^2 / 0.5)).
        assert (targets[person] > 0.85 * sc.GRADED_TOP).all(), name
        # Each person has its heading pixel among its 8 neighbours.
        for img in inputs[:16]:
            for r, c in zip(*np.nonzero(img == grid.PERSON)):
                patch = img[max(r - 1, 0) : r + 2, max(c - 1, 0) : c + 2]
                assert (patch == grid.HEADING).any() or (patch == grid.PERSON).sum() > 1


@pytest.mark.slow
def test_the_interaction_zone_exists_only_when_people_face_inward():
    """Same layouts (same keys) facing in and out: only facing in fills the circle's centre."""
    keys = dataset.family_keys(0, "group", 32)
    inward = np.asarray(dataset.batched_sampler("group")(keys)[1])
    outward = np.asarray(dataset.batched_sampler("non_group")(keys)[1])
    import jax

    layout = jax.vmap(families.group_layout)(keys)
    cx, cy = np.asarray(layout[4]), np.asarray(layout[5])
    row, col = (np.asarray(v) for v in grid.cell_of(cx, cy))
    centre_in = inward[np.arange(32), row, col]
    centre_out = outward[np.arange(32), row, col]
    assert (centre_in > 0.7 * sc.GRADED_TOP).all()
    assert (centre_in - centre_out > 0.3 * sc.GRADED_TOP).mean() > 0.9  # out: only the people's tails reach it


@pytest.mark.slow
def test_blind_corner_cost_sits_at_the_corner_on_the_free_side(data):
    inputs, targets = _family(data, "corner")
    for img, cost in zip(inputs, targets):
        wall = img == grid.WALL
        assert wall.any() and not wall[19:21, 19:21].all()
        assert (cost[wall] == 0).all()
        peak = np.unravel_index(np.argmax(cost), cost.shape)
        # The highest cost is next to a wall cell (the corner), and it is high.
        r, c = peak
        assert wall[max(r - 2, 0) : r + 3, max(c - 2, 0) : c + 3].any() and cost[peak] > 0.5
        assert cost.sum() > 3.0  # a graded area, not a single cell


def _halves(inputs, targets):
    """Mean cost left and right of the travel direction (robot at the centre -> goal pixel),
    over the corridor around the robot, away (> 2 m) from any person."""
    left, right = [], []
    for img, cost in zip(inputs, targets):
        rows, cols = np.nonzero(img == grid.PERSON)
        clear = np.ones(img.shape, bool)
        for r, c in zip(rows, cols):
            clear &= np.hypot(grid.CELL_X_M - grid.CELL_X_M[r, c], grid.CELL_Y_M - grid.CELL_Y_M[r, c]) > 2.0
        gr, gc = np.argwhere(img == grid.GOAL)[0]
        gx, gy = grid.CELL_X_M[gr, gc], grid.CELL_Y_M[gr, gc]
        side = gx * grid.CELL_Y_M - gy * grid.CELL_X_M  # > 0: left of the line centre -> goal
        near = np.abs(side) / np.hypot(gx, gy) < 2.5  # the corridor around the robot
        left.append(cost[clear & near & (side > 0.3)].mean())
        right.append(cost[clear & near & (side < -0.3)].mean())
    return np.array(left), np.array(right)


@pytest.mark.slow
def test_hallway_cost_is_higher_on_the_left_half(data):
    for name in ("hallway_straight", "hallway_people"):
        inputs, targets = _family(data, name)
        assert ((inputs == grid.GOAL).sum(axis=(1, 2)) == 1).all()
        left, right = _halves(inputs, targets)
        assert (left > right).mean() > 0.95, name
    inputs, targets = _family(data, "hallway_l")
    assert ((inputs == grid.WALL).sum(axis=(1, 2)) > 40).all()
    # The blind inner corner, above the left half's cost.
    assert (targets.max(axis=(1, 2)) > 1.25 * sc.HALLWAY_LEFT_COST).all()


@pytest.mark.slow
def test_the_queue_u_shape_is_there_only_when_the_goal_is_at_the_head(data):
    """Beside the queue as its map shows it, the U at the forbidden level with the goal at the
    head, and graded costs only with the goal elsewhere."""
    import jax
    import jax.numpy as jnp

    keys = dataset.family_keys(0, "queue", 32)
    images, at_head = (np.asarray(a) for a in dataset.batched_sampler("queue")(keys))
    elsewhere = np.asarray(dataset.batched_sampler("non_queue")(keys)[1])
    layout_keys = jax.vmap(lambda k: jax.random.split(k, 3)[0])(keys)  # as _sample_queue splits
    x, y, phi, valid, *_ = jax.vmap(families.queue_layout)(layout_keys)
    drawn = grid.quantise_heading(jnp.broadcast_to(phi[:, None], x.shape))
    hx, hy, phi, tail = (np.asarray(v) for v in jax.vmap(sc.drawn_line)(*grid.snap_to_cell(x, y), drawn, valid))
    checked = 0
    for b in range(32):
        dx, dy = grid.CELL_X_M - hx[b], grid.CELL_Y_M - hy[b]
        lx = dx * np.cos(phi[b]) + dy * np.sin(phi[b])
        ly = np.abs(-dx * np.sin(phi[b]) + dy * np.cos(phi[b]))
        beside = (lx > -tail[b]) & (lx < 0) & (ly > 0.75) & (ly < 1.25) & (images[b] != grid.WALL)
        assert (at_head[b][beside] >= sc.FORBIDDEN_FROM).all(), b
        assert (elsewhere[b][beside] <= sc.GRADED_TOP + 1e-6).all(), b
        assert (at_head[b][images[b] == grid.PERSON] < sc.FORBIDDEN_FROM).all(), b  # the line itself is open
        checked += beside.sum()
    assert checked > 32 * 5
    inputs, _ = _family(data, "non_queue")
    assert ((inputs == grid.GOAL).sum(axis=(1, 2)) <= 1).all()
    people = (_family(data, "queue")[0] == grid.PERSON).sum(axis=(1, 2))
    assert people.min() >= 1 and people.max() <= families.MAX_QUEUE  # 2-12 m at 0.6-1.4 m spacing, or one
    alone = (people == 1).mean()  # the lines of one (QUEUE_ALONE_SHARE)
    assert 0.5 * families.QUEUE_ALONE_SHARE < alone < 2 * families.QUEUE_ALONE_SHARE


@pytest.mark.slow
def test_a_composites_contrast_is_its_scenes_twin_difference():
    """A group moved beside nothing else (the pair group + corner keeps the group where it was
    drawn): the composite's contrast is |group - the same circle facing out| of scene A, 0 on walls;
    pairs without a twin (corner + proxemics) have none; ``pair_contrast`` fills composites from the
    dataset's seed and leaves them at 0 without it."""
    keys = dataset.family_keys(11, "composite", dataset.CHUNK)  # a chunk: generate's compiled shape
    split = jax.vmap(lambda k: jax.random.split(k, 4))(keys)  # k_pair, k_a, k_b, k_shift as drawn
    pair_of = jax.vmap(lambda k: jax.random.randint(k, (), 0, len(families.COMPOSITE_PAIRS)))(split[:, 0])
    pairs = [families.COMPOSITE_PAIRS[int(i)] for i in pair_of]
    group_first = pairs.index(("group", "corner"))
    images, _, contrasts = dataset.batched_composite(keys)  # the generator's own program
    image, contrast = images[group_first], contrasts[group_first]
    facing = [jax.jit(f)(split[group_first, 1])[1] for f in (families.sample_group, families.sample_non_group)]
    expected = np.abs(np.asarray(facing[0]) - np.asarray(facing[1]))
    np.testing.assert_allclose(np.asarray(contrast), np.where(np.asarray(image) == grid.WALL, 0.0, expected), atol=1e-6)
    assert np.asarray(contrast).max() > 0.3
    no_twin = pairs.index(("corner", "proxemics"))
    assert np.asarray(contrasts[no_twin]).max() == 0.0

    data = dataset.generate(11, {"corner": 2, "composite": 40})
    rows = data["family"] == list(data["names"]).index("composite")
    with_seed = dataset.pair_contrast(data, 11)
    # samples 0-39 of the family: the same keys, in the same program and chunk, the same bits
    np.testing.assert_array_equal(with_seed[rows], np.asarray(contrasts[:40]))
    assert with_seed[~rows].max() == 0.0 and dataset.pair_contrast(data).max() == 0.0


@pytest.mark.slow
def test_a_closed_l_is_the_open_one_cut_at_a_wall_past_its_goal():
    """``hallway_l_closed`` from a key is ``hallway_l`` from that key with its second leg ended by
    a wall: a wall pixel the open L lacks, and no cost the open L lacks (beyond the wall the cost
    is gone, before it the same). Off by default: the default recipe draws none."""
    import jax.numpy as jnp

    from socialnav.models.config import TrainConfig

    keys = dataset.family_keys(0, "hallway_l", 64)
    open_x, open_y = (np.asarray(a) for a in jax.vmap(families.sample_hallway_l)(keys))
    shut_x, shut_y = (np.asarray(a) for a in jax.vmap(families.sample_hallway_l_closed)(keys))
    assert np.all(shut_y <= open_y + 1e-6)
    assert (shut_y < open_y - 1e-3).any(axis=(1, 2)).mean() > 0.5  # cost cut beyond the wall in most
    new_wall = (shut_x == grid.WALL) & (open_x != grid.WALL)
    assert new_wall.any(axis=(1, 2)).mean() > 0.9  # the end wall (off the image in a few)
    assert np.array_equal(shut_x == grid.GOAL, open_x == grid.GOAL)
    assert families.CLOSED_L not in TrainConfig().counts
    assert TrainConfig(closed_l_hallways=5).counts[families.CLOSED_L] == 5
    assert float(jnp.max(shut_y)) <= 1.0
