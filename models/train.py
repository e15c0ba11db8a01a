"""Training of the GSCL U-Net (seed 002 Sec. 4.2) with optax and orbax, resumable after a kill.

Data. Every epoch draws its training samples from :func:`models.dataset.generate` with a key
folded from ``(seed, "train", epoch)`` (:attr:`TrainConfig.fresh_samples`; with it off, epoch 0's
samples are reused every epoch, the paper's fixed 70 % split). The held-out test set comes from
``(seed, "test")``, a key no training epoch uses, in the proportions of the paper's 30 %. Making an
epoch of 16,940 pairs takes about a second, less than reading it from disk would.

Loop. Pure ``jax.jit`` train and predict steps over ``nnx.split`` states; the batch is sharded
over the local devices when there are several (the CLI asks XLA for one CPU device per core; a
GPU is used when JAX sees one). Per-family train MSE is accumulated on the device.

Files in ``out``:

* ``config.json`` - the :class:`TrainConfig` (a resumed run must match it);
* ``checkpoints/<step>/`` - orbax checkpoints (model, optimiser, accumulators, metrics so far),
  written every :attr:`TrainConfig.checkpoint_every_steps` steps and at every epoch end;
  orbax commits a checkpoint by renaming it, so a kill loses at most the steps since the last;
* ``metrics.jsonl`` - one line per epoch: train and test MSE, overall and per family, samples
  seen and wall time; rewritten atomically from the checkpoint, so it never disagrees with it;
* ``baselines.json`` - the test MSE of two trivial predictors (all zeros; the mean training
  map), overall and per family.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import os
import pathlib
import time
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
import optax
from flax import nnx

from models import dataset, unet

PAPER_TEST_MSE = 0.0033
TRIVIAL_RATIO = 0.1  # the model's test MSE must be at most a tenth of the better trivial predictor's


@dataclasses.dataclass(frozen=True)
class TrainConfig:
    """Static configuration of a training run.

    Attributes:
      features: U-Net widths (3 encoder blocks, bottleneck); :data:`models.unet.CPU_FEATURES` by
        default, :data:`models.unet.PAPER_FEATURES` for the paper's size.
      coords: add the coordinate channels to the input (:mod:`models.unet`).
      epochs: number of epochs (the paper: 20).
      batch_size: samples per step (split over the devices; a multiple of their number).
      learning_rate: Adam's peak learning rate (the paper: 1e-3, constant).
      schedule: ``"constant"`` (the paper) or ``"cosine"`` (linear warm-up, cosine decay to
        ``final_lr_fraction`` of the peak at the last step).
      warmup_steps / final_lr_fraction: of the cosine schedule.
      train_fraction / test_fraction: epoch and test-set sizes as fractions of the paper's
        24,200 samples, family by family (the paper's 70 / 30 split).
      fresh_samples: new training samples every epoch (True) or epoch 0's reused (the paper).
      seed: seeds the data streams and the initialisation.
      checkpoint_every_steps: orbax checkpoint interval within an epoch (epochs' ends always).
      keep_checkpoints: how many checkpoints orbax keeps.
    """

    features: tuple[int, int, int, int] = unet.CPU_FEATURES
    coords: bool = True
    epochs: int = 10
    batch_size: int = 32
    learning_rate: float = 3e-3
    schedule: str = "cosine"
    warmup_steps: int = 200
    final_lr_fraction: float = 0.02
    train_fraction: float = 0.7
    test_fraction: float = 0.3
    fresh_samples: bool = True
    seed: int = 0
    checkpoint_every_steps: int = 500
    keep_checkpoints: int = 2

    def __post_init__(self):
        object.__setattr__(self, "features", tuple(int(f) for f in self.features))
        if self.schedule not in ("constant", "cosine"):
            raise ValueError(f"schedule must be 'constant' or 'cosine', got {self.schedule!r}")
        for name in ("epochs", "batch_size", "checkpoint_every_steps", "keep_checkpoints"):
            if getattr(self, name) < 1:
                raise ValueError(f"{name} must be >= 1, got {getattr(self, name)}")
        if not (0 < self.train_fraction and 0 < self.test_fraction):
            raise ValueError("train_fraction and test_fraction must be > 0")
        if not self.learning_rate > 0:
            raise ValueError(f"learning_rate must be > 0, got {self.learning_rate}")

    @classmethod
    def paper(cls, **overrides) -> "TrainConfig":
        """The paper's recipe: 32/64/128/256, batch 32, Adam 1e-3 constant, 20 epochs over one
        fixed 70 % split (batch size not given in the paper; 32 assumed)."""
        base = dict(features=unet.PAPER_FEATURES, batch_size=32, learning_rate=1e-3, schedule="constant",
                    fresh_samples=False, epochs=20)
        return cls(**{**base, **overrides})

    @property
    def train_counts(self) -> dict[str, int]:
        return dataset.scaled_counts(self.train_fraction)

    @property
    def test_counts(self) -> dict[str, int]:
        return dataset.scaled_counts(self.test_fraction)

    @property
    def steps_per_epoch(self) -> int:
        return max(1, sum(self.train_counts.values()) // self.batch_size)

    @property
    def total_steps(self) -> int:
        return self.epochs * self.steps_per_epoch

    def to_json(self) -> dict[str, Any]:
        d = dataclasses.asdict(self)
        d["features"] = list(self.features)
        return d

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> "TrainConfig":
        return cls(**{**d, "features": tuple(d["features"])})


def learning_rate_schedule(config: TrainConfig) -> optax.Schedule:
    if config.schedule == "constant":
        return optax.constant_schedule(config.learning_rate)
    warmup = min(config.warmup_steps, max(config.total_steps - 1, 0))
    return optax.warmup_cosine_decay_schedule(
        0.0, config.learning_rate, warmup, max(config.total_steps, warmup + 1),
        end_value=config.learning_rate * config.final_lr_fraction)


def make_model(config: TrainConfig) -> unet.UNet:
    return unet.UNet(config.features, config.coords, rngs=nnx.Rngs(config.seed))


# ---------------------------------------------------------------------------------------------
# Data streams.

def _stream_key(seed: int, stream: str, index: int = 0) -> jax.Array:
    return jax.random.fold_in(jax.random.fold_in(jax.random.key(seed), ("train", "test").index(stream)), index)


@functools.lru_cache(maxsize=1)  # epoch 0 serves the trivial baselines and then the first epoch
def epoch_data(config: TrainConfig, epoch: int) -> dict[str, np.ndarray]:
    """The shuffled training samples of ``epoch`` (epoch 0's for every epoch without fresh samples)."""
    e = epoch if config.fresh_samples else 0
    data = dataset.generate(_stream_key(config.seed, "train", e), config.train_counts)
    order = np.random.default_rng([config.seed, epoch]).permutation(len(data["family"]))
    return {**{k: data[k][order] for k in ("inputs", "targets", "family")}, "names": data["names"]}


def test_data(config: TrainConfig) -> dict[str, np.ndarray]:
    """The held-out test set (a key no training epoch uses)."""
    return dataset.generate(_stream_key(config.seed, "test"), config.test_counts)


# ---------------------------------------------------------------------------------------------
# Pure steps.

def _sharding(batch_size: int):
    devices = jax.devices()
    n = len(devices)
    if n == 1:
        return None, None
    if batch_size % n:
        raise ValueError(f"batch_size {batch_size} must be a multiple of the {n} devices")
    mesh = jax.sharding.Mesh(np.array(devices), ("batch",))
    return (jax.sharding.NamedSharding(mesh, jax.sharding.PartitionSpec("batch")),
            jax.sharding.NamedSharding(mesh, jax.sharding.PartitionSpec()))


def make_train_step(graphdef, tx: optax.GradientTransformation, n_families: int):
    """``step(state, inputs, targets, family) -> (state, loss)``; ``state`` is a dict with
    ``params``, ``batch_stats``, ``opt_state``, ``family_sse`` (F,) and ``family_count`` (F,)."""

    def loss_fn(params, batch_stats, inputs, targets):
        model = nnx.merge(graphdef, params, batch_stats, copy=True)
        model.train()
        per_sample = jnp.mean((model(inputs) - targets) ** 2, axis=(1, 2))
        return jnp.mean(per_sample), (per_sample, nnx.state(model, nnx.BatchStat))

    @jax.jit
    def step(state, inputs, targets, family):
        (loss, (per_sample, batch_stats)), grads = jax.value_and_grad(loss_fn, has_aux=True)(
            state["params"], state["batch_stats"], inputs, targets)
        updates, opt_state = tx.update(grads, state["opt_state"], state["params"])
        onehot = jax.nn.one_hot(family, n_families, dtype=jnp.float32)
        return {"params": optax.apply_updates(state["params"], updates), "batch_stats": batch_stats,
                "opt_state": opt_state,
                "family_sse": state["family_sse"] + onehot.T @ per_sample,
                "family_count": state["family_count"] + onehot.sum(0)}, loss

    return step


def make_predict(graphdef):
    """``predict(params, batch_stats, maps) -> costs`` (B, 40, 40), jitted, batch norm in eval mode."""

    @jax.jit
    def predict(params, batch_stats, maps):
        model = nnx.merge(graphdef, params, batch_stats, copy=True)
        model.eval()
        return model(maps)

    return predict


def per_sample_mse(predict, params, batch_stats, inputs: np.ndarray, targets: np.ndarray,
                   batch_size: int = 512) -> np.ndarray:
    """(N,) pixel MSE of the model on a dataset, in fixed-size batches (the last one padded, so
    one compilation serves every call), split over the local devices when there are several."""
    n_devices = len(jax.devices())
    batch_size = -(-batch_size // n_devices) * n_devices
    data_sharding, replicated = _sharding(batch_size)
    if replicated is not None:
        params, batch_stats = jax.device_put((params, batch_stats), replicated)
    out = np.empty(len(inputs), np.float64)
    for start in range(0, len(inputs), batch_size):
        x = inputs[start:start + batch_size]
        n = len(x)
        if n < batch_size:
            x = np.concatenate([x, np.zeros((batch_size - n,) + x.shape[1:], x.dtype)])
        if data_sharding is not None:
            x = jax.device_put(x, data_sharding)
        pred = np.asarray(predict(params, batch_stats, x))[:n]
        out[start:start + n] = np.mean((pred - targets[start:start + n]) ** 2, axis=(1, 2))
    return out


def by_family(values: np.ndarray, family: np.ndarray, names) -> dict[str, float]:
    """Mean of ``values`` per family name."""
    return {str(name): float(values[family == i].mean()) for i, name in enumerate(names) if np.any(family == i)}


def trivial_baselines(train: dict, test: dict) -> dict[str, dict]:
    """Test MSE (overall and per family) of predicting all zeros and of the mean training map."""
    mean_map = train["targets"].mean(axis=0)
    result = {}
    for name, pred in (("zeros", np.zeros_like(mean_map)), ("mean_map", mean_map)):
        mse = np.mean((test["targets"] - pred) ** 2, axis=(1, 2))
        result[name] = {"test_mse": float(mse.mean()), "by_family": by_family(mse, test["family"], test["names"])}
    return result


def meets_quality(test_mse: float, test_by_family: dict[str, float], baselines: dict[str, dict],
                  target_mse: float = PAPER_TEST_MSE, ratio: float = TRIVIAL_RATIO) -> bool:
    """The issue's bar: overall test MSE <= ``target_mse`` and, in every family, at most ``ratio``
    times the better trivial predictor's MSE."""
    if not test_mse <= target_mse:
        return False
    for name, mse in test_by_family.items():
        best = min(b["by_family"][name] for b in baselines.values())
        if not mse <= ratio * best:
            return False
    return True


# ---------------------------------------------------------------------------------------------
# Files.

def _write_atomic(path: pathlib.Path, text: str) -> None:
    tmp = path.with_name(f".tmp-{path.name}")
    tmp.write_text(text)
    os.replace(tmp, path)


def _write_metrics(out: pathlib.Path, meta: dict) -> None:
    if meta["history"]:
        _write_atomic(out / "metrics.jsonl", "".join(json.dumps(h) + "\n" for h in meta["history"]))


def _checkpoint_manager(out: pathlib.Path, config: TrainConfig, read_only: bool = False):
    import orbax.checkpoint as ocp

    options = ocp.CheckpointManagerOptions(max_to_keep=config.keep_checkpoints, create=not read_only,
                                           enable_async_checkpointing=False, read_only=read_only)
    return ocp.CheckpointManager((out / "checkpoints").absolute(), options=options)


def _host(tree):
    return jax.tree.map(np.asarray, tree)


@functools.lru_cache(maxsize=8)
def compiled(config: TrainConfig):
    """``(graphdef, tx, train_step, predict)`` of a configuration, built once per process so that
    resuming, restoring and evaluating in one process do not compile again."""
    graphdef = nnx.graphdef(make_model(config))
    tx = optax.adam(learning_rate_schedule(config))
    return graphdef, tx, make_train_step(graphdef, tx, len(dataset.FAMILIES)), make_predict(graphdef)


def initial_state(config: TrainConfig) -> dict:
    """The training state before the first step: fresh weights, Adam's state, zero accumulators."""
    _, params, batch_stats = nnx.split(make_model(config), nnx.Param, nnx.BatchStat)
    n = len(dataset.FAMILIES)
    return {"params": params, "batch_stats": batch_stats, "opt_state": compiled(config)[1].init(params),
            "family_sse": jnp.zeros(n), "family_count": jnp.zeros(n)}


def load_config(out) -> TrainConfig:
    path = pathlib.Path(out) / "config.json"
    if not path.exists():
        raise FileNotFoundError(f"{out} holds no training run (no config.json)")
    return TrainConfig.from_json(json.loads(path.read_text()))


def check_run_folder(out, config: TrainConfig) -> None:
    """Raise ValueError if ``out`` holds a run with another configuration."""
    path = pathlib.Path(out) / "config.json"
    if path.exists() and load_config(out) != config:
        raise ValueError(f"{out} holds a run with another configuration ({path}); "
                         "resume it with the same settings or choose another output folder")


def restore(out, step: int | None = None):
    """``(config, graphdef, state, meta)`` of a run's checkpoint (the latest by default)."""
    import orbax.checkpoint as ocp

    out = pathlib.Path(out)
    config = load_config(out)
    graphdef = compiled(config)[0]
    template = initial_state(config)
    with _checkpoint_manager(out, config, read_only=True) as manager:
        step = manager.latest_step() if step is None else step
        if step is None:
            raise FileNotFoundError(f"{out} has no checkpoint yet")
        restored = manager.restore(step, args=ocp.args.Composite(
            state=ocp.args.StandardRestore(_host(template)), meta=ocp.args.JsonRestore()))
    return config, graphdef, restored["state"], restored["meta"]


# ---------------------------------------------------------------------------------------------
# The loop.

def train(config: TrainConfig, out, *, progress: bool = True, stop_when_good: bool = False,
          max_steps: int | None = None, log=print) -> dict[str, Any]:
    """Train (or resume) a run in ``out``; returns the last epoch's metrics line.

    Args:
      stop_when_good: stop at the first epoch end that :func:`meets_quality` (for benchmarks).
      max_steps: stop after this many steps in all (a checkpoint is written there), e.g. to
        test resuming; the run resumes from it when called again.
    """
    import orbax.checkpoint as ocp
    from tqdm.auto import tqdm

    data_sharding, replicated = _sharding(config.batch_size)  # a bad batch size fails before any file
    out = pathlib.Path(out)
    out.mkdir(parents=True, exist_ok=True)
    config_path = out / "config.json"
    check_run_folder(out, config)
    if not config_path.exists():
        _write_atomic(config_path, json.dumps(config.to_json(), indent=1))

    schedule = learning_rate_schedule(config)
    names = list(dataset.FAMILIES)
    _, _, train_step, predict = compiled(config)
    state = initial_state(config)
    test = test_data(config)
    meta = {"step": 0, "wall_s": 0.0, "history": [], "baselines": None}

    manager = _checkpoint_manager(out, config)
    latest = manager.latest_step()
    if latest is not None:
        restored = manager.restore(latest, args=ocp.args.Composite(
            state=ocp.args.StandardRestore(_host(state)), meta=ocp.args.JsonRestore()))
        state, meta = restored["state"], restored["meta"]
        log(f"resuming {out} at step {latest} (epoch {latest // config.steps_per_epoch})")
        _write_metrics(out, meta)  # a kill between a checkpoint and its metrics line loses nothing
    if meta["baselines"] is None:
        meta["baselines"] = trivial_baselines(epoch_data(config, 0), test)
        _write_atomic(out / "baselines.json", json.dumps(meta["baselines"], indent=1))
    if replicated is not None:
        state = jax.device_put(state, replicated)

    spe = config.steps_per_epoch
    step = int(meta["step"])
    last_step = config.total_steps if max_steps is None else min(config.total_steps, max_steps)

    def save(step):
        meta["step"] = step
        manager.save(step, args=ocp.args.Composite(state=ocp.args.StandardSave(_host(state)),
                                                   meta=ocp.args.JsonSave(meta)), force=True)
        manager.wait_until_finished()

    bar = tqdm(total=config.total_steps, initial=step, unit="step", disable=not progress, desc="train")
    line = meta["history"][-1] if meta["history"] else {}
    try:
        while step < last_step:
            epoch = step // spe
            t_start = time.perf_counter()  # wall_s counts data generation and training, not evaluation
            data = epoch_data(config, epoch)
            for b in range(step % spe, spe):
                sl = slice(b * config.batch_size, (b + 1) * config.batch_size)
                batch = (data["inputs"][sl], data["targets"][sl], data["family"][sl].astype(np.int32))
                if data_sharding is not None:
                    batch = jax.device_put(batch, data_sharding)
                state, loss = train_step(state, *batch)
                step += 1
                bar.update(1)
                if step % 20 == 0:
                    bar.set_postfix(loss=f"{float(loss):.5f}", epoch=epoch + 1)
                epoch_done = step % spe == 0
                if epoch_done or step % config.checkpoint_every_steps == 0 or step == last_step:
                    meta["wall_s"] += time.perf_counter() - t_start
                    t_start = time.perf_counter()
                    if epoch_done:
                        line = _end_epoch(config, meta, state, predict, test, names, epoch, step, schedule)
                        state = {**state, "family_sse": jnp.zeros_like(state["family_sse"]),
                                 "family_count": jnp.zeros_like(state["family_count"])}
                        if replicated is not None:
                            state = jax.device_put(state, replicated)
                    save(step)
                    if epoch_done:
                        _write_metrics(out, meta)
                        log(f"epoch {epoch + 1}/{config.epochs}: train {line['train_mse']:.5f} "
                            f"test {line['test_mse']:.5f} ({line['wall_s']:.0f} s)"
                            + ("  meets the quality bar" if line["meets_quality"] else ""))
                        if stop_when_good and line["meets_quality"]:
                            return line
                    t_start = time.perf_counter()
                if step >= last_step:
                    break
    finally:
        bar.close()
        manager.close()
    return line


def _end_epoch(config, meta, state, predict, test, names, epoch, step, schedule) -> dict:
    sse, count = np.asarray(state["family_sse"]), np.asarray(state["family_count"])
    train_by_family = {names[i]: float(sse[i] / count[i]) for i in range(len(names)) if count[i] > 0}
    t0 = time.perf_counter()
    mse = per_sample_mse(predict, state["params"], state["batch_stats"], test["inputs"], test["targets"])
    test_by_family = by_family(mse, test["family"], test["names"])
    line = {"epoch": epoch + 1, "step": step, "samples_seen": step * config.batch_size,
            "wall_s": round(meta["wall_s"], 2), "eval_s": round(time.perf_counter() - t0, 2),
            "learning_rate": float(schedule(step)),
            "train_mse": float(sse.sum() / max(count.sum(), 1)), "test_mse": float(mse.mean()),
            "train_mse_by_family": train_by_family, "test_mse_by_family": test_by_family}
    line["meets_quality"] = meets_quality(line["test_mse"], test_by_family, meta["baselines"])
    meta["history"].append(line)
    return line


def quality_table(test_mse: float, test_by_family: dict[str, float], baselines: dict) -> str:
    """A text table: model vs the two trivial predictors per family, and the ratio to the better."""
    rows = [f"{'family':<18}{'model':>10}{'zeros':>10}{'mean map':>10}{'ratio':>8}"]
    for name, mse in test_by_family.items():
        z, m = baselines["zeros"]["by_family"][name], baselines["mean_map"]["by_family"][name]
        rows.append(f"{name:<18}{mse:>10.5f}{z:>10.5f}{m:>10.5f}{mse / min(z, m):>8.3f}")
    z, m = baselines["zeros"]["test_mse"], baselines["mean_map"]["test_mse"]
    rows.append(f"{'all':<18}{test_mse:>10.5f}{z:>10.5f}{m:>10.5f}{test_mse / min(z, m):>8.3f}")
    return "\n".join(rows)

