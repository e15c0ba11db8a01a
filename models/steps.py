"""The pure, jitted pieces of training: train step, prediction, per-sample error, sharding.

Pure ``jax.jit`` train and predict steps over ``nnx.split`` states; the batch is sharded over the
local devices when there are several (the ``socialnav`` command asks XLA for one CPU device per
core; a GPU is used when JAX sees one). Per-family train MSE is accumulated on the device.
"""

from __future__ import annotations

import dataclasses
import functools

import jax
import jax.numpy as jnp
import numpy as np
import optax
from flax import nnx

from socialnav.common import xla
from socialnav.models.config import TrainConfig, learning_rate_schedule, make_model, network_args
from socialnav.models.social_costs import FORBIDDEN, GRADED_TOP
from socialnav.models.unet import BRANCH, UNet, combine_heads


def batch_sharding(batch_size: int):
    """``(data sharding, replicated sharding)`` over the local devices, or ``(None, None)`` on one.

    Raises:
      ValueError: ``batch_size`` is not a multiple of the device count.
    """
    devices = jax.devices()
    n = len(devices)
    if n == 1:
        return None, None
    if batch_size % n:
        raise ValueError(f"batch_size {batch_size} must be a multiple of the {n} devices")
    mesh = jax.sharding.Mesh(np.array(devices), ("batch",))
    return (
        jax.sharding.NamedSharding(mesh, jax.sharding.PartitionSpec("batch")),
        jax.sharding.NamedSharding(mesh, jax.sharding.PartitionSpec()),
    )


def split_targets(targets, contrast=None):
    """``(graded, forbidden, contrast)`` of today's targets (:mod:`models.social_costs`: graded
    shapes up to ``GRADED_TOP``, the queue's U above it up to ``FORBIDDEN``), each (B, 40, 40):
    the graded channel's targets ``min(t, GRADED_TOP) / GRADED_TOP`` in [0, 1], the forbidden
    head's ``(t - GRADED_TOP) / (FORBIDDEN - GRADED_TOP)`` clipped to [0, 1] (the U's soft edges
    give fractions), and the pair contrast on the graded channel's scale (clipped to 1; None
    stays None). Nothing graded reaches above ``GRADED_TOP``, so the split is exact."""
    graded = jnp.minimum(targets, GRADED_TOP) / GRADED_TOP
    forbidden = jnp.clip((targets - GRADED_TOP) / (FORBIDDEN - GRADED_TOP), 0.0, 1.0)
    if contrast is not None:
        contrast = jnp.minimum(contrast / GRADED_TOP, 1.0)
    return graded, forbidden, contrast


def two_channel_loss(
    graded, forbidden_logit, targets, contrast=None, cost_weight=0.0, pair_weight=0.0, forbidden_weight=1.0
):
    """The "maps" loss of a model with the forbidden head: graded (B, 40, 40) in [0, 1] and the
    forbidden logits (B, 40, 40) against today's targets (B, 40, 40), split by
    :func:`split_targets`. The graded channel's squared error is weighed per pixel by ``1 +
    cost_weight * graded target + pair_weight * contrast``, except on the U's own cells (weight
    0: the head decides the output there, so the graded channel is not asked to draw the U as
    well) and on the cells of the twin's U (weight 1: a contrast above any graded cost's is the
    twin's U, not this map's costs); plus ``forbidden_weight`` x the mean binary cross-entropy of
    the logits against the U's share."""
    graded_target, forbidden_target, graded_contrast = split_targets(targets, contrast)
    weight = 1.0 + cost_weight * graded_target
    if pair_weight and contrast is not None:
        weight = weight + pair_weight * graded_contrast
    if contrast is not None:
        weight = jnp.where(contrast > GRADED_TOP + 1e-3, 1.0, weight)
    weight = jnp.where(forbidden_target > 0, 0.0, weight)
    bce = optax.sigmoid_binary_cross_entropy(forbidden_logit, forbidden_target)
    return jnp.mean(weight * (graded - graded_target) ** 2) + forbidden_weight * jnp.mean(bce)


def make_train_step(
    graphdef,
    tx: optax.GradientTransformation,
    n_families: int,
    cost_weight: float = 0.0,
    pair_weight: float = 0.0,
    objective=None,
    forbidden_weight: float = 0.0,
    freeze_graded: bool = False,
):
    """``step(state, inputs, targets, family, contrast=None, key=None) -> (state, loss)``; ``state``
    is a dict with ``params``, ``batch_stats``, ``opt_state``, ``family_sse`` (F,) and
    ``family_count`` (F,); ``contrast`` (B, 40, 40) is :func:`models.dataset.pair_contrast` of the
    batch.

    With ``objective`` None (the "maps" objective) and a model with one output, the loss is the
    mean over pixels of ``(1 + cost_weight * target + pair_weight * contrast) * error**2`` (the
    plain MSE with both at 0 or no contrast given). With the forbidden head
    (:mod:`models.unet`), :func:`two_channel_loss`. With an ``objective`` (the "paths" one,
    ``planners.learning.irl.PathObjective``: ``prepare(key, inputs, targets)`` and ``loss(costs, inputs,
    prepared) -> (B,)``), ``key`` draws the batch's demonstrations and the loss and ``loss`` are
    the mean of ``objective.loss``. The returned ``loss`` and the per-family accumulators are
    always the plain MSE of the model's output (the combined map) against the targets.

    With ``freeze_graded`` (a model with a separate forbidden branch,
    :attr:`models.config.TrainConfig.freeze_graded`) the graded layers run with batch norm in
    inference mode and no gradient, their statistics stay as they are, and the loss is
    ``forbidden_weight`` x the forbidden logits' mean cross-entropy alone (``tx`` must leave the
    graded weights unchanged: :func:`frozen_graded_tx`)."""

    def pixel_weight_and_error(costs, targets, contrast):
        squared = (costs - targets) ** 2
        weight = 1.0 + cost_weight * targets
        if pair_weight and contrast is not None:
            weight = weight + pair_weight * contrast
        return weight, squared

    def loss_fn(params, batch_stats, inputs, targets, contrast, prepared):
        model = nnx.merge(graphdef, params, batch_stats, copy=True)
        if freeze_graded:  # every layer in inference mode but the branch's
            model.eval()
            model.forbidden_branch.train()
        else:
            model.train()
        graded, forbidden_logit = model.heads(inputs)
        if freeze_graded:
            graded = jax.lax.stop_gradient(graded)
        costs = graded if forbidden_logit is None else combine_heads(graded, forbidden_logit)
        per_sample = jnp.mean((costs - targets) ** 2, axis=(1, 2))
        aux = (per_sample, nnx.state(model, nnx.BatchStat))
        if freeze_graded:
            _, forbidden_target, _ = split_targets(targets)
            bce = optax.sigmoid_binary_cross_entropy(forbidden_logit, forbidden_target)
            return forbidden_weight * jnp.mean(bce), aux
        if objective is not None:
            return jnp.mean(objective.loss(costs, inputs, prepared)), aux
        if forbidden_logit is None:
            weight, squared = pixel_weight_and_error(costs, targets, contrast)
            return jnp.mean(weight * squared), aux
        return two_channel_loss(
            graded, forbidden_logit, targets, contrast, cost_weight, pair_weight, forbidden_weight
        ), aux

    @jax.jit
    def step(state, inputs, targets, family, contrast=None, key=None):
        prepared = None
        if objective is not None:
            prepared = objective.prepare(key, inputs, targets)  # data: outside the differentiated arguments
        (value, (per_sample, batch_stats)), grads = jax.value_and_grad(loss_fn, has_aux=True)(
            state["params"], state["batch_stats"], inputs, targets, contrast, prepared
        )
        updates, opt_state = tx.update(grads, state["opt_state"], state["params"])
        onehot = jax.nn.one_hot(family, n_families, dtype=jnp.float32)
        return {
            "params": optax.apply_updates(state["params"], updates),
            "batch_stats": batch_stats,
            "opt_state": opt_state,
            "family_sse": state["family_sse"] + onehot.T @ per_sample,
            "family_count": state["family_count"] + onehot.sum(0),
        }, jnp.mean(per_sample) if objective is None else value

    return step


def make_predict(graphdef):
    """``predict(params, batch_stats, maps) -> costs`` (B, 40, 40), jitted, batch norm in eval mode."""

    @jax.jit
    def predict(params, batch_stats, maps):
        model = nnx.merge(graphdef, params, batch_stats, copy=True)
        model.eval()
        return model(maps)

    return predict


def per_sample_mse(
    predict, params, batch_stats, inputs: np.ndarray, targets: np.ndarray, batch_size: int = 512
) -> np.ndarray:
    """(N,) pixel MSE of the model on a dataset, in fixed-size batches (the last one padded, so
    one compilation serves every call), split over the local devices when there are several."""
    n_devices = len(jax.devices())
    batch_size = -(-batch_size // n_devices) * n_devices
    data_sharding, replicated = batch_sharding(batch_size)
    if replicated is not None:
        params, batch_stats = jax.device_put((params, batch_stats), replicated)
    out = np.empty(len(inputs), np.float64)
    for start in range(0, len(inputs), batch_size):
        x = inputs[start : start + batch_size]
        n = len(x)
        if n < batch_size:
            x = np.concatenate([x, np.zeros((batch_size - n,) + x.shape[1:], x.dtype)])
        if data_sharding is not None:
            x = jax.device_put(x, data_sharding)
        pred = np.asarray(predict(params, batch_stats, x))[:n]
        out[start : start + n] = np.mean((pred - targets[start : start + n]) ** 2, axis=(1, 2))
    return out


@functools.lru_cache(maxsize=8)
def compiled(config: TrainConfig, objective=None):
    """``(graphdef, tx, train_step, predict)`` of a configuration (and training objective, see
    :func:`make_train_step`), built once per process so that resuming, restoring and evaluating in
    one process do not compile again."""
    graphdef = nnx.graphdef(abstract_model(config))
    tx = optimizer(learning_rate_schedule(config), config.freeze_graded)
    return (
        graphdef,
        tx,
        make_train_step(
            graphdef,
            tx,
            len(config.counts),
            config.cost_weight,
            config.pair_weight,
            objective,
            config.forbidden_weight,
            config.freeze_graded,
        ),
        make_predict(graphdef),
    )


def optimizer(schedule: optax.Schedule, freeze_graded: bool) -> optax.GradientTransformation:
    """Adam on ``schedule``; on the forbidden branch alone with ``freeze_graded``
    (:func:`frozen_graded_tx`)."""
    tx = optax.adam(schedule)
    return frozen_graded_tx(tx) if freeze_graded else tx


def frozen_graded_tx(tx: optax.GradientTransformation) -> optax.GradientTransformation:
    """``tx`` on the forbidden branch's weights (paths through :data:`BRANCH`), zero updates on
    every other weight (the graded network, kept as its source drew it)."""

    def labels(params):
        return jax.tree_util.tree_map_with_path(
            lambda path, _: "train" if BRANCH in jax.tree_util.keystr(path) else "frozen", params
        )

    return optax.multi_transform({"train": tx, "frozen": optax.set_to_zero()}, labels)


def abstract_model(config: TrainConfig):
    """``config``'s model with ``jax.ShapeDtypeStruct`` leaves: its structure without drawing
    weights (drawn eagerly, every layer's initialiser is a program of its own shape to compile
    and run; traced abstractly, nothing is compiled)."""
    return nnx.eval_shape(lambda: make_model(config))


def weight_shapes(config: TrainConfig):
    """``(params, batch_stats)`` of ``config``'s model as shapes only, a template to load weights
    into."""
    _, params, batch_stats = nnx.split(abstract_model(config), nnx.Param, nnx.BatchStat)
    return params, batch_stats


def initial_state(config: TrainConfig) -> dict:
    """The training state before the first step: fresh weights, Adam's state, zero accumulators.

    Drawn by one compiled program (:func:`_initial_state`, the seed traced), the same bits as
    drawing eagerly, where each layer's initialiser was a program of its own shape to compile
    (docs/performance.md, "Compile time")."""
    return _initial_state(_StateShape.of(config), jax.random.key(config.seed))


@dataclasses.dataclass(frozen=True)
class _StateShape:
    """What a fresh training state depends on besides its key: the network's arguments
    (:func:`models.config.network_args`), whether the graded network is frozen (the optimiser's
    structure) and the number of families counted. A run's other fields (its data, loss weights,
    schedule and seed) do not enter it, so runs that differ only there share one program."""

    network: tuple[tuple[str, object], ...]
    freeze_graded: bool
    n_families: int

    @classmethod
    def of(cls, config: TrainConfig) -> _StateShape:
        return cls(network_args(config), config.freeze_graded, len(config.counts))


@functools.partial(jax.jit, static_argnums=0, compiler_options=xla.ONCE_PER_RUN)  # see common.xla
def _initial_state(shape: _StateShape, key) -> dict:
    """:func:`initial_state` of a configuration of ``shape`` drawn from ``key``
    (``jax.random.key(seed)``)."""
    model = UNet(**dict(shape.network), rngs=nnx.Rngs(key))
    _, params, batch_stats = nnx.split(model, nnx.Param, nnx.BatchStat)
    # Adam's state holds moments and a step count, not the schedule's values: any schedule gives
    # the same state as the run's own (compiled(config)'s optimiser).
    tx = optimizer(optax.constant_schedule(0.0), shape.freeze_graded)
    return {
        "params": params,
        "batch_stats": batch_stats,
        "opt_state": tx.init(params),
        "family_sse": jnp.zeros(shape.n_families),  # the families this run draws
        "family_count": jnp.zeros(shape.n_families),
    }


def state_template(config: TrainConfig) -> dict:
    """:func:`initial_state`'s tree and shapes as host zeros, without drawing anything: what a
    checkpoint is restored into."""
    shapes = jax.eval_shape(_initial_state, _StateShape.of(config), jax.random.key(0))
    return jax.tree.map(lambda a: np.zeros(a.shape, a.dtype), shapes)
