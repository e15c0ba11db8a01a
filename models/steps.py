"""The pure, jitted pieces of training: train step, prediction, per-sample error, sharding.

Pure ``jax.jit`` train and predict steps over ``nnx.split`` states; the batch is sharded over the
local devices when there are several (the ``socialnav`` command asks XLA for one CPU device per
core; a GPU is used when JAX sees one). Per-family train MSE is accumulated on the device.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np
import optax
from flax import nnx

from socialnav.models.config import TrainConfig, learning_rate_schedule, make_model


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


def make_train_step(
    graphdef,
    tx: optax.GradientTransformation,
    n_families: int,
    cost_weight: float = 0.0,
    pair_weight: float = 0.0,
    objective=None,
):
    """``step(state, inputs, targets, family, contrast=None, key=None) -> (state, loss)``; ``state``
    is a dict with ``params``, ``batch_stats``, ``opt_state``, ``family_sse`` (F,) and
    ``family_count`` (F,); ``contrast`` (B, 40, 40) is :func:`models.dataset.pair_contrast` of the
    batch.

    With ``objective`` None (the "maps" objective) the loss is the mean over pixels of ``(1 +
    cost_weight * target + pair_weight * contrast) * error**2`` (the plain MSE with both at 0 or no
    contrast given), and ``loss`` is the plain MSE. With an ``objective`` (the "paths" one,
    ``planners.irl.PathObjective``: ``prepare(key, inputs, targets)`` and ``loss(costs, inputs,
    prepared) -> (B,)``), ``key`` draws the batch's demonstrations and the loss and ``loss`` are
    the mean of ``objective.loss``. The per-family accumulators are the plain MSE either way."""

    def loss_fn(params, batch_stats, inputs, targets, contrast, prepared):
        model = nnx.merge(graphdef, params, batch_stats, copy=True)
        model.train()
        costs = model(inputs)
        squared = (costs - targets) ** 2
        per_sample = jnp.mean(squared, axis=(1, 2))
        if objective is not None:
            return jnp.mean(objective.loss(costs, inputs, prepared)), (per_sample, nnx.state(model, nnx.BatchStat))
        weight = 1.0 + cost_weight * targets
        if pair_weight and contrast is not None:
            weight = weight + pair_weight * contrast
        weighted = jnp.mean(weight * squared) if (cost_weight or pair_weight) else jnp.mean(per_sample)
        return weighted, (per_sample, nnx.state(model, nnx.BatchStat))

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
        }, (value if objective is not None else jnp.mean(per_sample))

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
    graphdef = nnx.graphdef(_abstract_model(config))
    tx = optax.adam(learning_rate_schedule(config))
    return (
        graphdef,
        tx,
        make_train_step(graphdef, tx, len(config.counts), config.cost_weight, config.pair_weight, objective),
        make_predict(graphdef),
    )


def _abstract_model(config: TrainConfig):
    """``config``'s model with ``jax.ShapeDtypeStruct`` leaves: its structure without drawing
    weights (drawing the random initial weights eagerly took 3.8 s, a compiled operation per
    layer's shape; tracing them abstractly takes a fraction)."""
    return nnx.eval_shape(lambda: make_model(config))


def weight_shapes(config: TrainConfig):
    """``(params, batch_stats)`` of ``config``'s model as shapes only, a template to load weights
    into."""
    _, params, batch_stats = nnx.split(_abstract_model(config), nnx.Param, nnx.BatchStat)
    return params, batch_stats


def initial_state(config: TrainConfig) -> dict:
    """The training state before the first step: fresh weights, Adam's state, zero accumulators."""
    _, params, batch_stats = nnx.split(make_model(config), nnx.Param, nnx.BatchStat)
    n = len(config.counts)  # the families this run draws (runs before the composites: 9)
    return {
        "params": params,
        "batch_stats": batch_stats,
        "opt_state": compiled(config)[1].init(params),
        "family_sse": jnp.zeros(n),
        "family_count": jnp.zeros(n),
    }
