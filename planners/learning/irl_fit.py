"""Fit a GSCL cost network to a fixed set of demonstrations (people's tracks, :mod:`planners.learning.tracks`).

The generator-driven "paths" run (``socialnav gscl train --objective paths``) draws fresh maps
every epoch through :func:`models.train.train`; a user's tracks are a fixed set instead, so this
loop draws minibatches from them (with replacement, seeded), minimises the paths objective
(:class:`planners.learning.irl.PathObjective`) with Adam (linear warm-up, cosine decay), and returns a
:class:`models.inference.SocialCostModel` whose :meth:`~models.inference.SocialCostModel.export`
folder the arena and the GSCL layer load like the shipped model (``--gscl-run FOLDER``). It keeps
no checkpoints: a fit of a few thousand steps takes minutes.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import optax
from flax import nnx

from socialnav.common import progress as progress_lib
from socialnav.models.config import TrainConfig
from socialnav.models.inference import SocialCostModel
from socialnav.models.steps import abstract_model, initial_state
from socialnav.planners.learning.irl import Demonstrations, PathObjective


def fit_demonstrations(
    maps: np.ndarray,
    demos: Demonstrations,
    config: TrainConfig | None = None,
    *,
    steps: int = 2000,
    progress: bool = True,
    log=print,
) -> tuple[SocialCostModel, list[float]]:
    """A U-Net (``config``'s widths, seed and batch size; the objective's temperature) fitted to
    demonstrations on input maps (N, 40, 40): ``(model, loss per step)``.

    Raises:
      ValueError: no demonstrations, or a loss that turns NaN (naming the step).
    """
    config = TrainConfig(objective="paths") if config is None else config
    if len(maps) == 0:
        raise ValueError("no demonstrations to fit (every track was left out: see the report)")
    objective = PathObjective.of(config)
    fresh = initial_state(config)  # config's weights drawn by one compiled program
    graphdef, params, batch_stats = nnx.graphdef(abstract_model(config)), fresh["params"], fresh["batch_stats"]
    schedule = optax.warmup_cosine_decay_schedule(
        0.0, config.learning_rate, min(config.warmup_steps, steps - 1), max(steps, 2), config.learning_rate * 0.02
    )
    tx = optax.adam(schedule)
    opt_state = jax.jit(tx.init)(params)  # one program, not one per weight shape

    maps_all, demos_all = jnp.asarray(maps), jax.tree.map(jnp.asarray, demos)

    @jax.jit
    def step(params, batch_stats, opt_state, idx):
        maps_b, demos_b = maps_all[idx], jax.tree.map(lambda a: a[idx], demos_all)

        def loss_fn(p):
            m = nnx.merge(graphdef, p, batch_stats, copy=True)
            m.train()
            value = jnp.mean(objective.loss(m(maps_b), maps_b, demos_b))
            return value, nnx.state(m, nnx.BatchStat)

        (value, new_stats), grads = jax.value_and_grad(loss_fn, has_aux=True)(params)
        updates, opt_state = tx.update(grads, opt_state, params)
        return optax.apply_updates(params, updates), new_stats, opt_state, value

    rng = np.random.default_rng(config.seed)
    history = []
    bar = progress_lib.bar("fit", unit="step", enabled=progress)
    try:
        for i in range(steps):
            idx = rng.integers(0, len(maps), config.batch_size)
            params, batch_stats, opt_state, value = step(params, batch_stats, opt_state, idx)
            bar.update(i + 1, steps)
            if (i + 1) % 20 == 0 or i + 1 == steps:
                v = float(value)
                if not np.isfinite(v):
                    raise ValueError(f"the loss became {v} by step {i + 1}; try a lower learning rate")
                history.append(v)
                bar.set_postfix(nll=f"{v:.3f}")
    finally:
        bar.close()
    return SocialCostModel(graphdef, params, batch_stats, config), history


def demonstrations_figure(model: SocialCostModel, maps: np.ndarray, demos: Demonstrations, path, count: int = 6):
    """A PNG of ``count`` demonstrations (evenly spread over the set): each window's input map and
    the learnt costs with the demonstrated cells over them."""
    from socialnav.common import figures
    from socialnav.models.plots import input_rgb

    pick = np.unique(np.linspace(0, len(maps) - 1, min(count, len(maps))).astype(int))
    costs = np.asarray(model(maps[pick]))
    fig = figures.figure(figsize=(2.2 * len(pick), 4.6))
    axes = fig.subplots(2, len(pick), squeeze=False)
    for col, (i, c) in enumerate(zip(pick, costs, strict=True)):
        visited = np.asarray(demos.moves[i]).sum(0) > 0
        rows, cols = np.nonzero(visited)
        axes[0, col].imshow(input_rgb(maps[i]), interpolation="nearest")
        axes[0, col].set_title(f"demonstration {i}", fontsize=8)
        axes[1, col].imshow(c, cmap="magma", vmin=0.0, vmax=1.0, interpolation="nearest")
        for ax in axes[:, col]:
            ax.plot(cols, rows, "c.", markersize=2.5)
            ax.set_xticks([])
            ax.set_yticks([])
    axes[1, 0].set_ylabel("learnt costs", fontsize=8)
    axes[0, 0].set_ylabel("input, path", fontsize=8)
    return figures.save(fig, path)
