"""GSCL's U-Net, training loop (resume after a kill), inference helpers and command line."""

from __future__ import annotations

import json

import jax
import jax.numpy as jnp
import numpy as np
import optax
import pytest
from flax import nnx, serialization

from socialnav import cli
from socialnav.common import runfolder
from socialnav.common.machine import compiler_host
from socialnav.models import checkpoints, dataset, evaluation, grid, inference, quality, steps, streams, train, unet
from socialnav.models.config import TrainConfig
from socialnav.planners import layers

TINY = dict(
    features=(4, 4, 8, 8),
    epochs=2,
    batch_size=16,
    train_fraction=0.01,
    test_fraction=0.004,
    warmup_steps=2,
    checkpoint_every_steps=4,
    learning_rate=1e-2,
)


@pytest.mark.slow
def test_unet_shapes_batch_independence_and_paper_size():
    model = unet.UNet((4, 8, 8, 16), rngs=nnx.Rngs(0))
    maps = dataset.generate(0, {"group": 3})["inputs"]
    model.eval()
    out = model(maps)
    assert out.shape == (3, 40, 40) and out.dtype == jnp.float32
    # In evaluation mode batch norm uses its running statistics: a map's costs do not depend on the
    # rest of its batch (in training mode they would).
    np.testing.assert_allclose(np.asarray(model(maps[1:2])), np.asarray(out[1:2]), atol=1e-6)
    paper = nnx.eval_shape(lambda: unet.UNet(unet.PAPER_FEATURES, rngs=nnx.Rngs(0)))
    assert 1.5e6 < unet.parameter_count(paper) < 2.0e6  # the paper: about 1.6 M
    cpu = nnx.eval_shape(lambda: unet.UNet(unet.CPU_FEATURES, rngs=nnx.Rngs(0)))  # shapes only: nothing drawn
    assert unet.parameter_count(cpu) < 0.3 * unet.parameter_count(paper)
    with pytest.raises(ValueError, match="4 positive widths"):
        unet.UNet((8, 8, 8), rngs=nnx.Rngs(0))


def test_a_fresh_state_fits_the_runs_optimiser_whatever_its_schedule_and_data():
    # The fresh state is drawn by a program keyed on the network and the optimiser's structure
    # alone: runs differing in schedule, learning rate, batch, loss weights or seed share it, and
    # its Adam state is the run's own optimiser's, step count included.
    tiny = TrainConfig(**TINY)
    other = TrainConfig(**{**TINY, "schedule": "constant", "learning_rate": 0.5, "batch_size": 8, "pair_weight": 0.0})
    assert steps._StateShape.of(tiny) == steps._StateShape.of(other)
    assert steps._StateShape.of(tiny) != steps._StateShape.of(TrainConfig(**{**TINY, "features": (4, 4, 8, 16)}))
    for config in (tiny, other):
        state = steps.initial_state(config)
        expected = steps.compiled(config)[1].init(state["params"])
        assert jax.tree.structure(state["opt_state"]) == jax.tree.structure(expected)
        jax.tree.map(np.testing.assert_array_equal, state["opt_state"], expected)
        assert state["family_sse"].shape == (len(config.counts),)
    # The same seed draws the same weights; another seed others.
    same = jax.tree.leaves(steps.initial_state(other)["params"])
    for a, b in zip(jax.tree.leaves(steps.initial_state(tiny)["params"]), same):
        np.testing.assert_array_equal(a, b)
    reseeded = steps.initial_state(TrainConfig(**{**TINY, "seed": 1}))["params"]
    assert any(not np.array_equal(a, b) for a, b in zip(jax.tree.leaves(reseeded), same))


def test_input_encoding_is_one_hot_per_code():
    maps = np.zeros((1, 40, 40), np.uint8)
    maps[0, 3, 4], maps[0, 3, 5], maps[0, 10, 10], maps[0, 0, :] = grid.PERSON, grid.HEADING, grid.GOAL, grid.WALL
    x = np.asarray(unet.encode_input(maps, coords=True))
    assert x.shape == (1, 40, 40, 6)
    for c, code in enumerate(unet.INPUT_CHANNEL_CODES):
        np.testing.assert_array_equal(x[0, ..., c], maps[0] == code)
    assert x[0, 0, 0, 4] == -1 and x[0, 0, -1, 4] == 1  # x grows to the right
    assert x[0, 0, 0, 5] == 1 and x[0, -1, 0, 5] == -1  # y grows upwards


def _run(tmp_path, name, **kw):
    config = TrainConfig(**{**TINY, **kw})
    return config, train.train(config, tmp_path / name, progress=False, log=lambda *_: None)


@pytest.mark.slow
def test_tiny_training_learns_and_resumes_after_a_kill_with_nothing_lost(tmp_path):
    config, line = _run(tmp_path, "straight")
    history = [json.loads(s) for s in (tmp_path / "straight" / "metrics.jsonl").read_text().splitlines()]
    assert [h["epoch"] for h in history] == [1, 2]
    assert all(h["host"] == compiler_host() for h in history)  # where each epoch ran
    # The loss goes down: first steps' batches against the end of training, and the test set
    # against the untrained network.
    _, graphdef, state, _ = checkpoints.restore(tmp_path / "straight")
    s0 = steps.initial_state(config)
    test = streams.test_data(config)
    predict = steps.compiled(config)[3]
    untrained = steps.per_sample_mse(predict, s0["params"], s0["batch_stats"], test["inputs"], test["targets"]).mean()
    zeros = json.loads((tmp_path / "straight" / "baselines.json").read_text())["zeros"]["test_mse"]
    assert line["test_mse"] < 0.8 * min(untrained, zeros)
    assert history[1]["train_mse"] < history[0]["train_mse"]

    # Killed at step 6, mid-epoch, before that step's checkpoint was committed (its folder
    # removed): the run resumes from step 4 and ends with the same weights and metrics as the
    # uninterrupted run.
    killed = tmp_path / "killed"
    cfg = TrainConfig(**TINY)
    assert cfg.steps_per_epoch > 6
    train.train(cfg, killed, progress=False, max_steps=6, log=lambda *_: None)
    assert sorted(int(p.name) for p in (killed / "checkpoints").iterdir() if p.name.isdigit()) == [4, 6]
    import shutil

    shutil.rmtree(killed / "checkpoints" / "6")
    assert not (killed / "metrics.jsonl").exists()
    train.train(cfg, killed, progress=False, log=lambda *_: None)
    _, _, resumed, _ = checkpoints.restore(killed)
    for a, b in zip(jax.tree.leaves(resumed), jax.tree.leaves(state)):
        np.testing.assert_allclose(a, b, rtol=1e-5, atol=1e-6)
    again = [json.loads(s) for s in (killed / "metrics.jsonl").read_text().splitlines()]
    for h, g in zip(history, again):
        assert h["test_mse"] == pytest.approx(g["test_mse"], rel=1e-4)
        assert h["train_mse_by_family"].keys() == g["train_mse_by_family"].keys()
        for k in h["train_mse_by_family"]:
            assert h["train_mse_by_family"][k] == pytest.approx(g["train_mse_by_family"][k], rel=1e-4)

    # The restored checkpoint predicts what the trained state predicts.
    model = inference.SocialCostModel.load(tmp_path / "straight")
    np.testing.assert_allclose(
        np.asarray(model(test["inputs"][:8])),
        np.asarray(predict(state["params"], state["batch_stats"], test["inputs"][:8])),
        rtol=1e-6,
        atol=1e-6,
    )
    assert model(test["inputs"][0]).shape == (40, 40)
    # The weights as an argument: the same answer, and one function for every checkpoint of the
    # network (what a caller's jit caches on), with another checkpoint's own answer.
    maps = jnp.asarray(test["inputs"][:8])
    np.testing.assert_allclose(np.asarray(model.apply(model.weights, maps)), np.asarray(model(maps)), atol=1e-6)
    earlier = inference.SocialCostModel(graphdef, s0["params"], s0["batch_stats"])  # the untrained weights
    assert earlier.apply is model.apply
    assert float(jnp.max(jnp.abs(earlier.apply(earlier.weights, maps) - model.apply(model.weights, maps)))) > 1e-4
    # As a stack's layer: one layer (the same compiled program) whose params are each model's weights.
    assert layers.gscl(earlier) == layers.gscl(model)
    leaves = zip(jax.tree_util.tree_leaves(layers.gscl(model).params), jax.tree_util.tree_leaves(model.weights))
    assert all(a is b for a, b in leaves)
    with pytest.raises(ValueError, match="input maps must be"):
        model(np.zeros((2, 20, 20)))

    # Another configuration in the same folder is refused, nothing overwritten.
    before = (tmp_path / "straight" / "config.json").read_text()
    with pytest.raises(ValueError, match="another configuration"):
        train.train(TrainConfig(**{**TINY, "batch_size": 8}), tmp_path / "straight", progress=False)
    assert (tmp_path / "straight" / "config.json").read_text() == before

    # Evaluation: the same test MSE as the last epoch, per family, and the picture.
    report = evaluation.evaluate_run(tmp_path / "straight", examples=1)
    assert report["test_mse"] == pytest.approx(line["test_mse"], rel=1e-5)
    assert set(report["test_mse_by_family"]) == set(dataset.FAMILIES) - {"hallway_l_closed"}  # not drawn by default
    assert (tmp_path / "straight" / "evaluation" / "predictions.png").stat().st_size > 10_000


def test_trivial_baselines_and_quality_bar():
    rng = np.random.default_rng(0)
    train_set = {"targets": rng.random((10, 40, 40)).astype(np.float32)}
    test = {
        "targets": rng.random((4, 40, 40)).astype(np.float32),
        "family": np.array([0, 0, 1, 1]),
        "names": np.array(["a", "b"]),
    }
    b = quality.trivial_baselines(train_set, test)
    np.testing.assert_allclose(b["zeros"]["test_mse"], np.mean(test["targets"] ** 2), rtol=1e-6)
    mean_map = train_set["targets"].mean(0)
    np.testing.assert_allclose(
        b["mean_map"]["by_family"]["b"], np.mean((test["targets"][2:] - mean_map) ** 2), rtol=1e-6
    )
    best_a = min(b["zeros"]["by_family"]["a"], b["mean_map"]["by_family"]["a"])
    assert quality.meets_quality(0.001, {"a": 0.09 * best_a, "b": 0.001}, b)
    assert not quality.meets_quality(0.001, {"a": 0.11 * best_a, "b": 0.001}, b)
    assert not quality.meets_quality(0.004, {"a": 0.0, "b": 0.0}, b)


@pytest.mark.slow
def test_input_map_from_occupancy_people_and_goal():
    occupancy = np.zeros((400, 400), np.float32)  # 0.05 m cells, origin (-10, -10)
    occupancy[:, 300] = 1.0  # a thin wall at x = 5.0-5.05 m (one fine cell, an eighth of a GSCL cell)
    occupancy[100, :] = 0.5  # below the 0.6 threshold: free
    people = np.array([[2.0, 0.0], [0.0, -20.0]])
    image = np.asarray(
        inference.input_map(
            occupancy,
            0.05,
            np.array([-10.0, -10.0]),
            np.array([0.0, 0.0]),
            people,
            np.array([np.pi / 2, 0.0]),
            np.array([100.0, 0.1]),
        )
    )
    assert set(np.unique(image)) <= set(grid.INPUT_CODES)
    wall_cols = np.flatnonzero((image == grid.WALL).all(axis=0))
    np.testing.assert_array_equal(wall_cols, [32])  # x = 5.0 m lies in column 32 (4.8-5.2 m)
    row, col = (int(v) for v in grid.cell_of(2.0, 0.0))
    assert image[row, col] == grid.PERSON and image[row - 1, col] == grid.HEADING  # facing +y: the pixel above
    assert (image == grid.PERSON).sum() == 1  # the second person is off the window
    goal = np.argwhere(image == grid.GOAL)
    np.testing.assert_array_equal(goal, [[19, 39]])  # far to the right: on the right edge, same row as the robot
    # In the robot's frame (robot facing +y), a person 2 m ahead appears 2 m ahead of the robot.
    image = np.asarray(
        inference.input_map(
            occupancy,
            0.05,
            np.array([-10.0, -10.0]),
            np.array([0.0, 0.0]),
            np.array([[0.0, 2.0]]),
            np.array([np.pi / 2]),
            np.array([0.0, 3.0]),
            robot_yaw_rad=np.pi / 2,
        )
    )
    row, col = (int(v) for v in grid.cell_of(2.0, 0.0))
    assert image[row, col] == grid.PERSON and image[row, col + 1] == grid.HEADING


@pytest.mark.slow
def test_cli_generate_writes_what_generate_makes_and_refuses_bad_input(tmp_path, capsys):
    out = tmp_path / "d.npz"
    assert (
        cli.main(["gscl", "generate", "--out", str(out), "--scale", "0.001", "--count", "queue=5", "--seed", "2"]) == 0
    )
    data = dataset.load(out)
    expected = dataset.generate(2, {**dataset.scaled_counts(0.001), "queue": 5})
    for k in ("inputs", "targets", "family", "names"):
        np.testing.assert_array_equal(data[k], expected[k])
    with pytest.raises(SystemExit, match="must end in .npz"):
        cli.main(["gscl", "generate", "--out", str(tmp_path / "d.csv")])
    with pytest.raises(SystemExit, match="unknown family"):
        cli.main(["gscl", "generate", "--out", str(out), "--count", "corridor=3"])
    with pytest.raises(SystemExit, match=r"d\.npz, .*d\.json exist\(s\); pass --overwrite"):  # never replaced silently
        cli.main(["gscl", "generate", "--out", str(out), "--scale", "0.001"])
    again = ["gscl", "generate", "--out", str(out), "--scale", "0.001", "--count", "queue=5", "--overwrite"]
    assert cli.main(again) == 0
    with pytest.raises(SystemExit):
        cli.main(["gscl", "train", "--features", "8,8"])
    with pytest.raises(SystemExit, match="no checkpoint|no training run"):
        cli.main(["gscl", "evaluate", "--run", str(tmp_path / "nothing")])
    assert not (tmp_path / "d.csv").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d.json", "d.npz"]  # the dataset and how it was made
    # A user's notes.json where the record of notes.npz would go: refused as it is, --overwrite or not.
    (tmp_path / "notes.json").write_text('{"mine": 1}')
    for overwrite in ([], ["--overwrite"]):
        with pytest.raises(SystemExit, match=r"notes\.json is not the record 'gscl generate' writes"):
            cli.main(["gscl", "generate", "--out", str(tmp_path / "notes.npz"), "--count", "queue=1", *overwrite])
    assert (tmp_path / "notes.json").read_text() == '{"mine": 1}' and not (tmp_path / "notes.npz").exists()
    # A run folder with other settings is refused before anything is written to it.
    run = tmp_path / "run"
    run.mkdir()
    (run / "config.json").write_text(json.dumps(TrainConfig().to_json()))
    with pytest.raises(SystemExit, match="another configuration"):
        cli.main(["gscl", "train", "--out", str(run), "--paper"])
    assert sorted(p.name for p in run.iterdir()) == ["config.json"]


def _truncate_biggest_file(folder):
    files = [p for p in folder.rglob("*") if p.is_file()]
    biggest = max(files, key=lambda p: p.stat().st_size)
    biggest.write_bytes(biggest.read_bytes()[: biggest.stat().st_size // 3])


@pytest.mark.slow
def test_a_damaged_checkpoint_falls_back_and_a_foreign_config_is_named(tmp_path):
    """Killed at step 6 (checkpoints 4 and 6 kept): the newest damaged, the older one is used with
    a warning; every one damaged, or a config.json naming other widths, is one error naming it."""
    run = tmp_path / "run"
    config = TrainConfig(**TINY)
    train.train(config, run, progress=False, max_steps=6, log=lambda *_: None)
    _truncate_biggest_file(run / "checkpoints" / "6")
    warnings = []
    _, _, state, meta = checkpoints.restore(run, log=warnings.append)
    assert meta["step"] == 4 and "skipped unreadable checkpoint" in warnings[0] and "step 6" in warnings[0]
    # Resuming trains on from the good checkpoint instead of failing, the unreadable one removed
    # (it stopped every resume that saved step 6 again, "Checkpoint for step 6 already exists");
    # run to step 6 exactly, then on: each resume continues.
    train.train(config, run, progress=False, max_steps=6, log=warnings.append)
    assert any("resuming" in w and "step 4" in w for w in warnings)
    assert any("removed the unreadable checkpoint of step 6" in w for w in warnings)
    assert checkpoints.restore(run, log=warnings.append)[3]["step"] == 6
    train.train(config, run, progress=False, max_steps=8, log=warnings.append)
    assert sorted(int(p.name) for p in (run / "checkpoints").iterdir() if p.name.isdigit()) == [6, 8]

    foreign = tmp_path / "foreign"
    train.train(config, foreign, progress=False, max_steps=4, log=lambda *_: None)
    cfg = json.loads((foreign / "config.json").read_text())
    (foreign / "config.json").write_text(json.dumps({**cfg, "features": [8, 8, 8, 8]}))
    with pytest.raises(checkpoints.CheckpointError, match=r"config\.json \(features \[8, 8, 8, 8\]\)"):
        inference.SocialCostModel.load(foreign)


@pytest.mark.slow
def test_training_stops_when_the_loss_turns_nan(tmp_path):
    config = TrainConfig(**{**TINY, "learning_rate": 1e30, "schedule": "constant"})
    with pytest.raises(train.TrainingDiverged, match="became nan"):
        train.train(config, tmp_path / "nan", progress=False, log=lambda *_: None)


def test_model_inputs_outside_the_pixel_encoding_are_refused():
    good = np.zeros((2, 40, 40), np.uint8)
    good[0, 5, 5] = grid.PERSON
    np.testing.assert_array_equal(np.asarray(inference.check_maps(good.astype(np.float32))), good)
    cases = {
        "outside the pixel encoding": np.ones((1, 40, 40), np.float32) * 0.5,
        "254": np.full((1, 40, 40), 254, np.uint8),
        "NaN": np.full((1, 40, 40), np.nan, np.float32),
        "bool": np.zeros((1, 40, 40), bool),
        "shape": np.zeros((1, 30, 40), np.uint8),
    }
    for words, maps in cases.items():
        with pytest.raises(ValueError, match=words):
            inference.check_maps(maps)
    with pytest.raises(ValueError, match="people_xy_m holds NaN"):
        inference.input_map(np.zeros((50, 50)), 0.1, (0.0, 0.0), (2.5, 2.5), [[np.nan, 1.0]], [0.0], (4.0, 2.5))
    # Resolutions and shapes: each refused naming the argument (they divided by zero, erased the
    # walls, broadcast one heading over two people, failed deep in a broadcast).
    good = dict(occupancy=np.zeros((50, 50)), resolution_m=0.1, origin_xy_m=(0.0, 0.0), robot_xy_m=(2.5, 2.5))
    good |= dict(people_xy_m=[[1.0, 1.0], [2.0, 2.0]], people_heading_rad=[0.0, 1.0], goal_xy_m=(4.0, 2.5))
    assert inference.input_map(**good).shape == (40, 40)
    for change, words in (
        ({"resolution_m": 0}, "resolution_m must be a positive"),
        ({"resolution_m": -0.05}, "resolution_m must be a positive"),
        ({"resolution_m": float("nan")}, "resolution_m must be a positive"),
        ({"people_heading_rad": [0.0]}, r"people_heading_rad must be \(2,\)"),
        ({"people_valid": [True, False, True]}, r"people_valid must be \(2,\)"),
        ({"occupancy": np.zeros((2, 50, 50))}, "occupancy must be a 2-D"),
        ({"people_xy_m": [1.0, 2.0, 3.0]}, r"people_xy_m must be \(P, 2\)"),
        ({"goal_xy_m": (1.0, 2.0, 3.0)}, "goal_xy_m must be"),
    ):
        with pytest.raises(ValueError, match=words):
            inference.input_map(**(good | change))


@pytest.mark.slow
def test_the_cost_weighted_loss_changes_only_what_it_weighs():
    """``cost_weight`` weighs a pixel's error by 1 + w x target: on maps whose targets are all zero
    the step is the plain-MSE step exactly; on costed maps the update differs, and the loss the step
    reports is the plain MSE either way. Bad weights are refused; runs saved before it read as 0."""
    first_step_moves = {**TINY, "schedule": "constant"}  # the warm-up's first learning rate is 0
    plain = TrainConfig(**{**first_step_moves, "cost_weight": 0.0})
    weighted = TrainConfig(**{**first_step_moves, "cost_weight": 4.0})
    data = dataset.generate(3, {"group": 16})
    family = np.zeros(16, np.int32)

    def step(config, targets):
        state = steps.initial_state(config)  # the same seed: the same weights
        new, loss = steps.compiled(config)[2](state, data["inputs"], targets, family)
        return jax.tree.leaves(new["params"]), float(loss)

    zeros = np.zeros_like(data["targets"])
    before = jax.tree.leaves(steps.initial_state(plain)["params"])
    after_plain, after_weighted = step(plain, zeros)[0], step(weighted, zeros)[0]
    assert any(np.any(a != b) for a, b in zip(after_plain, before, strict=True))  # the step moved
    for a, b in zip(after_plain, after_weighted, strict=True):
        np.testing.assert_array_equal(a, b)
    (p_plain, loss_plain), (p_weighted, loss_weighted) = step(plain, data["targets"]), step(weighted, data["targets"])
    assert loss_plain == pytest.approx(loss_weighted, rel=1e-6)
    assert max(float(np.max(np.abs(a - b))) for a, b in zip(p_plain, p_weighted, strict=True)) > 1e-6
    for bad in (-1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="cost_weight"):
            TrainConfig(cost_weight=bad)
    old = TrainConfig().to_json()
    del old["cost_weight"]
    assert TrainConfig.from_json(old).cost_weight == 0.0


@pytest.mark.slow
def test_the_rotation_average_turns_with_the_map():
    """The average over quarter turns is equivariant to them (to float rounding); the network alone
    is not, so the check could fail; 1 rotation is the function itself; other counts are refused."""
    model = unet.UNet((4, 4, 8, 8), rngs=nnx.Rngs(3))
    graphdef, params, batch_stats = nnx.split(model, nnx.Param, nnx.BatchStat)
    predict = steps.make_predict(graphdef)

    def plain(maps):
        return predict(params, batch_stats, maps)

    codes = np.array(grid.INPUT_CODES, np.uint8)
    maps = jnp.asarray(codes[np.random.default_rng(0).integers(0, len(codes), (3, 40, 40))])
    averaged = inference.rotation_averaged(plain, 4)
    for k in (1, 2, 3):
        turned = jnp.rot90(maps, k, axes=(1, 2))
        np.testing.assert_allclose(averaged(turned), jnp.rot90(averaged(maps), k, axes=(1, 2)), atol=1e-6)
    alone = plain(jnp.rot90(maps, 1, axes=(1, 2))) - jnp.rot90(plain(maps), 1, axes=(1, 2))
    assert float(jnp.max(jnp.abs(alone))) > 1e-3
    assert inference.rotation_averaged(plain, 1) is plain
    with pytest.raises(ValueError, match="rotations must be one of"):
        inference.rotation_averaged(plain, 2)


@pytest.mark.slow
def test_pair_contrast_is_the_twins_difference_on_both_twins_and_zero_elsewhere():
    """Sample i of ``non_group`` is sample i of ``group`` facing out: the contrast of both is
    |target_group - target_non_group|, positive in the circle's middle (the zone is there only
    facing in) and zero for families without a twin; counts that differ pair the first ones."""
    data = dataset.generate(5, {"corner": 3, "group": 4, "non_group": 6})
    contrast = dataset.pair_contrast(data)
    names = list(data["names"])
    g = np.flatnonzero(data["family"] == names.index("group"))
    ng = np.flatnonzero(data["family"] == names.index("non_group"))
    np.testing.assert_array_equal(contrast[data["family"] == names.index("corner")], 0.0)
    expected = np.abs(data["targets"][g] - data["targets"][ng[:4]])
    np.testing.assert_array_equal(contrast[g], expected)
    np.testing.assert_array_equal(contrast[ng[:4]], expected)
    np.testing.assert_array_equal(contrast[ng[4:]], 0.0)  # no twin drawn for these
    # the zone: where the group's target exceeds its twin's by more than proxemics could
    assert all(c.max() > 0.3 for c in contrast[g])
    assert dataset.pair_contrast(dataset.generate(5, {"corner": 2})).sum() == 0.0


@pytest.mark.slow
def test_the_pair_weighted_loss_weighs_only_the_contrast():
    """``pair_weight`` adds w x contrast to each pixel's weight: with a zero contrast (or none) the
    step is the unweighted step exactly; with the twins' contrast the update differs and the
    reported loss stays the plain MSE. Bad weights are refused; runs saved before it read as 0."""
    first_step_moves = {**TINY, "schedule": "constant", "cost_weight": 0.0, "pair_weight": 0.0}
    plain = TrainConfig(**first_step_moves)
    paired = TrainConfig(**{**first_step_moves, "pair_weight": 20.0})
    data = dataset.generate(3, {"group": 8, "non_group": 8})
    contrast = dataset.pair_contrast(data)
    family = data["family"].astype(np.int32)

    def step(config, *extra):
        state = steps.initial_state(config)
        new, loss = steps.compiled(config)[2](state, data["inputs"], data["targets"], family, *extra)
        return jax.tree.leaves(new["params"]), float(loss)

    p_plain, loss_plain = step(plain)
    for extra in ((), (np.zeros_like(contrast),)):
        for a, b in zip(p_plain, step(paired, *extra)[0], strict=True):
            np.testing.assert_allclose(a, b, rtol=1e-6, atol=1e-7)
    p_paired, loss_paired = step(paired, contrast)
    assert loss_paired == pytest.approx(loss_plain, rel=1e-6)
    assert max(float(np.max(np.abs(a - b))) for a, b in zip(p_plain, p_paired, strict=True)) > 1e-6
    for bad in (-1.0, float("nan")):
        with pytest.raises(ValueError, match="pair_weight"):
            TrainConfig(pair_weight=bad)
    old = TrainConfig().to_json()
    del old["pair_weight"]
    assert TrainConfig.from_json(old).pair_weight == 0.0
    assert TrainConfig.paper().pair_weight == 0.0


@pytest.mark.slow
def test_the_forbidden_head_learns_the_queues_u_as_a_classification_beside_the_graded_costs():
    """Today's targets split exactly into the graded channel's targets and the forbidden head's
    (the U on queues with the goal at the head, nothing on groups); the combined output is
    FORBIDDEN where the head's logit is >= 0 and GRADED_TOP x graded elsewhere; the head exists
    only for "maps" runs on today's targets; its loss weight moves the step only where it acts."""
    from socialnav.models import social_costs as sc

    queues, groups = dataset.generate(3, {"queue": 16}), dataset.generate(3, {"group": 16})
    t = jnp.asarray(queues["targets"])
    graded, forbidden, _ = steps.split_targets(t)
    assert float(forbidden.max()) > 0.95 and float(graded.max()) <= 1.0 and float(graded.min()) >= 0.0
    rebuilt = jnp.where(
        forbidden > 0, sc.GRADED_TOP + forbidden * (sc.FORBIDDEN - sc.GRADED_TOP), sc.GRADED_TOP * graded
    )
    np.testing.assert_allclose(np.asarray(rebuilt), queues["targets"], atol=1e-6)
    assert float(steps.split_targets(jnp.asarray(groups["targets"]))[1].max()) == 0.0
    assert steps.split_targets(t, None)[2] is None

    # The graded channel's loss ignores the U's own cells (the head decides there) and counts
    # every other cell.
    logit = jnp.zeros_like(t)
    base_loss = steps.two_channel_loss(graded, logit, t, cost_weight=10.0)
    bce = float(jnp.mean(optax.sigmoid_binary_cross_entropy(logit, forbidden)))
    three = float(steps.two_channel_loss(graded, logit, t, cost_weight=10.0, forbidden_weight=3.0))
    assert three - float(base_loss) == pytest.approx(2 * bce, rel=1e-5)
    in_u, off_u = forbidden > 0, (forbidden == 0) & (graded > 0.1)
    assert float(steps.two_channel_loss(jnp.where(in_u, 0.0, graded), logit, t, cost_weight=10.0)) == pytest.approx(
        float(base_loss)
    )
    assert float(steps.two_channel_loss(jnp.where(off_u, 0.0, graded), logit, t, cost_weight=10.0)) > float(base_loss)

    combined = unet.combine_heads(jnp.array([0.5, 0.5, 1.0]), jnp.array([-0.1, 0.0, 2.0]))
    np.testing.assert_allclose(np.asarray(combined), [0.5 * sc.GRADED_TOP, sc.FORBIDDEN, sc.FORBIDDEN])

    def head_outputs(config):
        return steps.weight_shapes(config)[0]["head"]["kernel"].shape[-1]

    base = {**TINY, "schedule": "constant"}
    assert head_outputs(TrainConfig(**base)) == 2
    assert head_outputs(TrainConfig(**base, objective="paths")) == 1
    old = TrainConfig().to_json()
    del old["forbidden_weight"], old["targets"]
    assert (TrainConfig.from_json(old).forbidden_weight, head_outputs(TrainConfig.from_json(old))) == (0.0, 1)
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(ValueError, match="forbidden_weight"):
            TrainConfig(forbidden_weight=bad)
    assert TrainConfig(forbidden_weight=0.0, objective="paths").forbidden_weight == 0.0
    assert TrainConfig.paper().forbidden_weight == TrainConfig().forbidden_weight

    def step(data, **settings):
        config = TrainConfig(**{**base, **settings})
        state = steps.initial_state(config)
        new, loss = steps.compiled(config)[2](state, data["inputs"], data["targets"], np.zeros(16, np.int32))
        return new["params"], float(loss)

    (one, loss_one), (three, loss_three) = step(queues, forbidden_weight=1.0), step(queues, forbidden_weight=3.0)
    assert loss_one == loss_three  # the reported loss is the plain MSE of the output before the step
    # Adam's first step is the gradient's sign on a parameter one loss alone moves (the head's own
    # kernel); the shared layers, moved by both, change with the weight.
    assert not all(np.allclose(a, b) for a, b in zip(jax.tree.leaves(one), jax.tree.leaves(three), strict=True))


@pytest.mark.slow
def test_an_epoch_carries_its_contrast_through_the_shuffle():
    """``epoch_data`` computes the twins' contrast before it shuffles, and shuffles it with its
    samples: the same rows as :func:`dataset.pair_contrast` of the unshuffled epoch; runs without a
    pair weight carry none."""
    config = TrainConfig(**{**TINY, "pair_weight": 5.0, "train_fraction": 0.002, "composites": 0})
    streams.epoch_data.cache_clear()
    data = streams.epoch_data(config, 1)
    raw = dataset.generate(streams._stream_key(config.seed, "train", 1), config.train_counts)
    contrast = dataset.pair_contrast(raw)
    # match rows by input map (the dataset has no duplicates at this size)
    where = {raw["inputs"][i].tobytes(): i for i in range(len(raw["inputs"]))}
    assert len(where) == len(raw["inputs"]) == len(data["inputs"])
    rows = [where[x.tobytes()] for x in data["inputs"]]
    np.testing.assert_array_equal(data["contrast"], contrast[rows])
    np.testing.assert_array_equal(data["targets"], raw["targets"][rows])
    assert data["contrast"].max() > 0.3
    streams.epoch_data.cache_clear()
    assert "contrast" not in streams.epoch_data(TrainConfig(**{**TINY, "composites": 0, "pair_weight": 0.0}), 1)


@pytest.mark.slow
def test_an_exported_model_predicts_what_the_run_predicts_and_bad_folders_are_named(tmp_path):
    """socialnav gscl export's folder: the weights alone (no optimiser state), read back into the
    same predictions; a folder that is no model, or weights of another network, fail in one line."""
    config = TrainConfig(**TINY)
    state = steps.initial_state(config)
    # weights that are not the initial ones, so that a load that kept the template would differ
    params = jax.tree.map(lambda a: a + 0.01 * jnp.arange(a.size, dtype=a.dtype).reshape(a.shape), state["params"])
    model = inference.SocialCostModel(steps.compiled(config)[0], params, state["batch_stats"], config)
    model.export(tmp_path / "m", {"note": "tiny"})
    assert inference.model_problem(tmp_path / "m") is None
    again = inference.SocialCostModel.load(tmp_path / "m")
    maps = dataset.generate(0, {"group": 2, "queue": 2})["inputs"]
    np.testing.assert_array_equal(np.asarray(again(maps)), np.asarray(model(maps)))
    assert json.loads((tmp_path / "m" / inference.CARD_FILE).read_text()) == {"note": "tiny"}
    assert inference.model_identity(tmp_path / "m") == inference.model_identity(tmp_path / "m")
    with pytest.raises(ValueError, match="neither a GSCL training run"):
        inference.SocialCostModel.load(tmp_path)
    weights = (tmp_path / "m" / inference.WEIGHTS_FILE).read_bytes()
    pure = serialization.msgpack_restore(weights)
    del pure["params"][next(iter(pure["params"]))]  # a layer missing: named, not left unset
    (tmp_path / "m" / inference.WEIGHTS_FILE).write_bytes(serialization.msgpack_serialize(pure))
    with pytest.raises(ValueError, match="weights.msgpack: has no"):
        inference.SocialCostModel.load(tmp_path / "m")
    (tmp_path / "m" / inference.WEIGHTS_FILE).write_bytes(weights)
    other = TrainConfig(**{**TINY, "features": (4, 4, 8, 16)})
    (tmp_path / "m" / "config.json").write_text(json.dumps(other.to_json()))
    with pytest.raises(ValueError, match="weights.msgpack"):
        inference.SocialCostModel.load(tmp_path / "m")
    (tmp_path / "m" / inference.WEIGHTS_FILE).write_bytes(b"not msgpack")
    with pytest.raises(ValueError, match="weights.msgpack"):
        inference.SocialCostModel.load(tmp_path / "m")


@pytest.mark.slow
def test_a_model_of_graded_targets_is_read_in_the_graded_range_and_cannot_be_trained_on(tmp_path):
    """A run saved before the targets had a forbidden level (its config.json has no 'targets')
    and a "paths" run learnt graded costs only: they have one output, and loaded, their costs are
    scaled by GRADED_TOP, so that the GSCL layer reads their peak as the top of the graded range,
    never as forbidden. A model with the forbidden head is read as it outputs."""
    from socialnav.models import social_costs as sc

    now = TrainConfig(**TINY)
    old = TrainConfig.from_json({k: v for k, v in now.to_json().items() if k != "targets"})
    assert (now.targets, old.targets) == ("graded_forbidden", "graded")
    assert now.reads_forbidden and not old.reads_forbidden
    assert not TrainConfig(**TINY, objective="paths").reads_forbidden
    assert old.reading == "graded" and not TrainConfig(**TINY, objective="paths").reads_lethal
    # A "paths" model learnt as the layer reads costs has one output, read as it is.
    layer = TrainConfig(**TINY, objective="paths", reading="layer")
    assert layer.reads_lethal and not layer.reads_forbidden
    assert inference.output_scale(layer) == 1.0
    maps = dataset.generate(0, {"queue": 2})["inputs"]
    for config, scale in ((old, sc.GRADED_TOP), (now, 1.0)):
        state = steps.initial_state(config)
        graphdef = steps.compiled(config)[0]
        raw = np.asarray(inference.SocialCostModel(graphdef, state["params"], state["batch_stats"])(maps))
        model = inference.SocialCostModel(graphdef, state["params"], state["batch_stats"], config)
        np.testing.assert_allclose(np.asarray(model(maps)), scale * raw, rtol=1e-6)
        np.testing.assert_allclose(np.asarray(model.apply(model.weights, maps)), scale * raw, rtol=1e-6)
    with pytest.raises(ValueError, match="targets: 'graded'"):
        train.train(old, tmp_path / "old", progress=False)
    assert not (tmp_path / "old").exists()  # refused before any file


@pytest.mark.slow
def test_a_warm_start_copies_the_source_and_grows_a_head_and_bad_sources_are_named(tmp_path):
    """--init-from: a one-output model (an older run's, like the package's model before the
    forbidden head) starts a head model: every weight copied, the head's graded channel equal to
    the source's output, the forbidden channel fresh; so the first graded prediction is the
    source's. A source of other widths, or no model, fails in one line before any file; a resumed
    run never reads its source again."""
    from socialnav.models import warm_start

    now = TrainConfig(**TINY)
    old = TrainConfig.from_json({k: v for k, v in now.to_json().items() if k != "targets"})
    state = steps.initial_state(old)
    params = jax.tree.map(lambda a: a + 0.01 * jnp.arange(a.size, dtype=a.dtype).reshape(a.shape), state["params"])
    source = inference.SocialCostModel(steps.compiled(old)[0], params, state["batch_stats"], old)
    source.export(tmp_path / "src")

    fresh = steps.initial_state(now)
    started = warm_start.warm_started(fresh, tmp_path / "src")
    mine, theirs, new = (nnx.to_pure_dict(s) for s in (started["params"], params, fresh["params"]))
    assert mine["head"]["kernel"].shape[-1] == 2 and theirs["head"]["kernel"].shape[-1] == 1
    np.testing.assert_array_equal(mine["head"]["kernel"][..., :1], theirs["head"]["kernel"])
    np.testing.assert_array_equal(mine["head"]["kernel"][..., 1], new["head"]["kernel"][..., 1])
    np.testing.assert_array_equal(mine["enc"][0]["conv1"]["kernel"], theirs["enc"][0]["conv1"]["kernel"])
    assert not np.array_equal(
        nnx.to_pure_dict(fresh["params"])["enc"][0]["conv1"]["kernel"], mine["enc"][0]["conv1"]["kernel"]
    )
    maps = dataset.generate(0, {"corner": 2, "queue": 2})["inputs"]
    model = nnx.merge(steps.compiled(now)[0], started["params"], started["batch_stats"])
    model.eval()
    graded, _ = model.heads(jnp.asarray(maps))
    raw = inference.SocialCostModel(steps.compiled(old)[0], params, state["batch_stats"])(maps)
    np.testing.assert_allclose(np.asarray(graded), np.asarray(raw), atol=1e-6)

    # Trained from it: the run starts there, and a resume reads the checkpoint, not the source.
    run = tmp_path / "run"
    config = TrainConfig(**{**TINY, "init_from": str(tmp_path / "src")})
    logs = []
    train.train(config, run, progress=False, max_steps=4, log=logs.append)
    assert any("starting from the weights of" in line for line in logs)
    source_id = inference.model_identity(tmp_path / "src")
    assert json.loads((run / warm_start.SOURCE_FILE).read_text())["identity"] == source_id
    (tmp_path / "src" / inference.WEIGHTS_FILE).unlink()
    train.train(config, run, progress=False, max_steps=6, log=logs.append)
    assert any("resuming" in line for line in logs)
    # The exported model's card names the source, which its folder no longer holds.
    assert cli.main(["gscl", "export", "--run", str(run), "--out", str(tmp_path / "exp"), "--scenes", "1"]) == 0
    card = json.loads((tmp_path / "exp" / inference.CARD_FILE).read_text())
    assert card["init_from"]["identity"] == source_id and "started from the model in init_from" in card["made_by"]
    assert card["trained_on"] == []  # no epoch ended in its 6 steps, so none recorded its host
    # A second export into the same folder: refused without --overwrite (it replaced the first
    # without a word), replaced whole with it; the manifest lists exactly the model's files.
    again = ["gscl", "export", "--run", str(run), "--out", str(tmp_path / "exp"), "--scenes", "1", "--step", "4"]
    with pytest.raises(SystemExit, match="holds a previous run.*--overwrite"):
        cli.main(again)
    assert json.loads((tmp_path / "exp" / inference.CARD_FILE).read_text()) == card
    assert cli.main([*again, "--overwrite"]) == 0
    assert json.loads((tmp_path / "exp" / inference.CARD_FILE).read_text())["step"] == 4
    assert sorted(runfolder.read_manifest(tmp_path / "exp").files) == ["config.json", "model.json", "weights.msgpack"]

    other = TrainConfig(**{**TINY, "features": (4, 4, 8, 16)})
    with pytest.raises(ValueError, match=r"init_from: .*src2's .*shaped"):
        source.export(tmp_path / "src2")
        warm_start.warm_started(steps.initial_state(other), tmp_path / "src2")
    with pytest.raises(ValueError, match="init_from: .*neither a GSCL training run"):
        train.train(TrainConfig(**{**TINY, "init_from": str(tmp_path / "nothing")}), tmp_path / "bad", progress=False)
    assert not (tmp_path / "bad").exists()
    with pytest.raises(ValueError, match="field 'init_from'"):
        TrainConfig.from_json({**now.to_json(), "init_from": 3})


@pytest.mark.slow
def test_a_frozen_graded_network_keeps_the_sources_costs_while_the_forbidden_branch_learns(tmp_path):
    """--forbidden-features with --freeze-graded: the forbidden logit comes from a separate U-Net;
    started from a one-output source, every graded weight and batch statistic stays the source's
    through training steps (so the graded prediction stays the source's), the branch's weights
    and statistics move, and the loss is the branch's cross-entropy alone. The settings are
    checked on construction, and a config.json written before them reads as the shared head."""
    from socialnav.models import warm_start

    old = TrainConfig.from_json({k: v for k, v in TrainConfig(**TINY).to_json().items() if k != "targets"})
    state = steps.initial_state(old)
    params = jax.tree.map(lambda a: a + 0.01 * jnp.arange(a.size, dtype=a.dtype).reshape(a.shape), state["params"])
    source = inference.SocialCostModel(steps.compiled(old)[0], params, state["batch_stats"], old)
    source.export(tmp_path / "src")

    config = TrainConfig(
        **{**TINY, "init_from": str(tmp_path / "src"), "forbidden_features": (4, 4, 4, 8), "freeze_graded": True}
    )
    started = warm_start.warm_started(steps.initial_state(config), config.init_from)
    fresh_branch = nnx.to_pure_dict(steps.initial_state(config)["params"])["forbidden_branch"]
    for a, b in zip(
        jax.tree.leaves(nnx.to_pure_dict(started["params"])["forbidden_branch"]), jax.tree.leaves(fresh_branch)
    ):
        np.testing.assert_array_equal(a, b)  # other widths than the source's: the branch starts fresh
    # A branch of the source's widths starts as a copy of the source's layers, its output layer fresh.
    same = TrainConfig(**{**TINY, "init_from": str(tmp_path / "src"), "forbidden_features": TINY["features"]})
    copied = nnx.to_pure_dict(warm_start.warm_started(steps.initial_state(same), same.init_from)["params"])
    theirs = nnx.to_pure_dict(params)
    np.testing.assert_array_equal(
        copied["forbidden_branch"]["dec"][1]["conv2"]["kernel"], theirs["dec"][1]["conv2"]["kernel"]
    )
    np.testing.assert_array_equal(copied["forbidden_branch"]["head"]["bias"], [unet.HEAD_BIAS])
    assert not np.array_equal(copied["forbidden_branch"]["head"]["kernel"], theirs["head"]["kernel"])
    data = dataset.generate(5, {"queue": 8, "corner": 8})
    step = steps.compiled(config)[2]
    new = started
    for _ in range(3):
        new, _ = step(new, data["inputs"], data["targets"], np.zeros(16, np.int32))
    before, after = (nnx.to_pure_dict(s["params"]) for s in (started, new))
    stats_before, stats_after = (nnx.to_pure_dict(s["batch_stats"]) for s in (started, new))
    for name in ("enc", "bottleneck", "up", "dec", "head"):
        for a, b in zip(jax.tree.leaves(before[name]), jax.tree.leaves(after[name]), strict=True):
            np.testing.assert_array_equal(a, b)
    for name in ("enc", "bottleneck"):
        for a, b in zip(jax.tree.leaves(stats_before[name]), jax.tree.leaves(stats_after[name]), strict=True):
            np.testing.assert_array_equal(a, b)
    moved = [
        not np.array_equal(a, b)
        for a, b in zip(jax.tree.leaves(before["forbidden_branch"]), jax.tree.leaves(after["forbidden_branch"]))
    ]
    assert all(moved)
    assert not np.array_equal(
        stats_before["forbidden_branch"]["enc"][0]["norm1"]["mean"],
        stats_after["forbidden_branch"]["enc"][0]["norm1"]["mean"],
    )
    model = nnx.merge(steps.compiled(config)[0], new["params"], new["batch_stats"])
    model.eval()
    graded, forbidden_logit = model.heads(jnp.asarray(data["inputs"]))
    np.testing.assert_allclose(np.asarray(graded), np.asarray(source(data["inputs"])) / source._scale, atol=1e-6)
    assert forbidden_logit.shape == graded.shape

    # The loss is the branch's cross-entropy alone: targets with every graded cost removed (the
    # U kept) move the branch exactly as the full targets do.
    _, forbidden_target, _ = steps.split_targets(jnp.asarray(data["targets"]))
    u_only = np.where(np.asarray(forbidden_target) > 0, data["targets"], 0.0).astype(np.float32)
    assert not np.array_equal(u_only, data["targets"])
    family = np.zeros(16, np.int32)
    full, _ = step(started, data["inputs"], data["targets"], family)
    bare, _ = step(started, data["inputs"], u_only, family)
    for a, b in zip(jax.tree.leaves(full["params"]), jax.tree.leaves(bare["params"]), strict=True):
        np.testing.assert_allclose(np.asarray(a), np.asarray(b), atol=1e-7)

    for bad, match in (
        ({"freeze_graded": True, "forbidden_features": (4, 4, 4, 8)}, "freeze_graded needs init_from"),
        ({"freeze_graded": True, "init_from": "x"}, "freeze_graded needs"),
        ({"forbidden_features": (4, 4, 4)}, "forbidden_features must be"),
        ({"forbidden_features": (4, 4, 4, 8), "objective": "paths"}, "forbidden_features needs"),
    ):
        with pytest.raises(ValueError, match=match):
            TrainConfig(**{**TINY, **bad})
    before_fields = {k: v for k, v in config.to_json().items() if k not in ("forbidden_features", "freeze_graded")}
    read = TrainConfig.from_json(before_fields)
    assert (read.forbidden_features, read.freeze_graded) == ((), False)
    assert TrainConfig.from_json(config.to_json()) == config


@pytest.mark.slow
def test_the_decoders_upsampling_is_flaxs_transposed_convolution_with_the_same_parameters():
    """UpConv computes nnx.ConvTranspose(in, out, (2, 2), strides=(2, 2)) as one product: the same
    parameters (names, shapes, initial values: checkpoints load unchanged), the same outputs and
    gradients to float rounding, a bias-free layer included."""
    x = jax.random.normal(jax.random.PRNGKey(1), (3, 5, 7, 12))
    for use_bias in (True, False):
        ours = unet.UpConv(12, 8, use_bias=use_bias, rngs=nnx.Rngs(0))
        flax_ = nnx.ConvTranspose(12, 8, (2, 2), strides=(2, 2), use_bias=use_bias, rngs=nnx.Rngs(0))
        ours_state, flax_state = nnx.state(ours), nnx.state(flax_)
        assert jax.tree.structure(ours_state) == jax.tree.structure(flax_state)
        assert all(np.array_equal(a, b) for a, b in zip(jax.tree.leaves(ours_state), jax.tree.leaves(flax_state)))
        y = ours(x)
        assert y.shape == (3, 10, 14, 8)
        np.testing.assert_allclose(y, flax_(x), atol=2e-6)

        def loss(model, x):
            return jnp.sum(jnp.sin(model(x)))

        grads_ours = nnx.grad(loss, argnums=(0, 1))(ours, x)
        grads_flax = nnx.grad(loss, argnums=(0, 1))(flax_, x)
        for a, b in zip(jax.tree.leaves(grads_ours), jax.tree.leaves(grads_flax)):
            np.testing.assert_allclose(a, b, atol=2e-5)
    # The U-Net's decoder uses it.
    model = unet.UNet((4, 4, 8, 8), rngs=nnx.Rngs(0))
    assert all(isinstance(layer, unet.UpConv) for layer in model.up)
