"""Training of the GSCL U-Net (seed 002 Sec. 4.2) with optax and orbax, resumable after a kill.

The loop alone; its parts have a file each: the configuration (:mod:`models.config`), the data
streams (:mod:`models.streams`), the jitted steps (:mod:`models.steps`), the quality bar
(:mod:`models.quality`) and the run folder's files (:mod:`models.checkpoints`).

Files in ``out``:

* ``config.json`` - the :class:`TrainConfig` (a resumed run must match it);
* ``checkpoints/<step>/`` - orbax checkpoints (model, optimiser, accumulators, metrics so far),
  written every :attr:`TrainConfig.checkpoint_every_steps` steps and at every epoch end;
  orbax commits a checkpoint by renaming it, so a kill loses at most the steps since the last;
* ``metrics.jsonl`` - one line per epoch: train and test MSE, overall and per family, samples
  seen, wall time and the host it ran on (:func:`common.machine.compiler_host`); rewritten
  atomically from the checkpoint, so it never disagrees with it;
* ``baselines.json`` - the test MSE of two trivial predictors (all zeros; the mean training
  map), overall and per family;
* ``init_from.json`` - a warm-started run's source model (:func:`models.warm_start.source_record`).
"""

from __future__ import annotations

import json
import pathlib
import time
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from socialnav.common import progress as progress_lib
from socialnav.common.atomic import write_text_atomic
from socialnav.common.machine import compiler_host
from socialnav.models import dataset, rules
from socialnav.models.checkpoints import (
    check_run_folder,
    checkpoint_manager,
    drop_unreadable,
    host,
    restore_state,
    write_metrics,
)
from socialnav.models.config import TARGETS, TrainConfig, learning_rate_schedule
from socialnav.models.inference import output_scale
from socialnav.models.quality import by_family, meets_quality, trivial_baselines
from socialnav.models.steps import batch_sharding, compiled, initial_state, per_sample_mse
from socialnav.models.streams import demonstration_key, epoch_data, test_data

RULE_SCENES = 100  # scenes of each kind of the rule suite checked at every epoch's end


def train(
    config: TrainConfig,
    out,
    *,
    progress: bool = True,
    stop_when_good: bool = False,
    max_steps: int | None = None,
    objective=None,
    log=print,
) -> dict[str, Any]:
    """Train (or resume) a run in ``out``; returns the last epoch's metrics line.

    Args:
      stop_when_good: stop at the first epoch end that :func:`meets_quality` and whose every
        check of the held-out rule suite (:mod:`models.rules`, :data:`RULE_SCENES` scenes of each
        kind) passes on 95 % of its cases (for benchmarks).
      max_steps: stop after this many steps in all (a checkpoint is written there), e.g. to
        test resuming; the run resumes from it when called again.
      objective: the training objective of a ``config.objective == "paths"`` run
        (``planners.learning.irl.PathObjective.of(config)``; see :func:`models.steps.make_train_step`);
        None for the "maps" objective.

    Raises:
      ValueError: ``objective`` does not match ``config.objective``, or ``config.targets`` is
        not the targets the generator draws (an older run's "graded").
    """
    import orbax.checkpoint as ocp

    if config.targets != TARGETS[0]:
        raise ValueError(
            f"targets: {config.targets!r} runs learnt the generator's earlier targets, which it no longer "
            f"draws; such a run can be read, not trained (start a new run, targets {TARGETS[0]!r})"
        )
    if (objective is None) != (config.objective == "maps"):
        raise ValueError(
            f"objective: a {config.objective!r} run needs "
            + ("socialnav.planners.learning.irl.PathObjective.of(config)" if objective is None else "no objective")
        )
    data_sharding, replicated = batch_sharding(config.batch_size)  # a bad batch size fails before any file
    out = pathlib.Path(out)
    state, source = initial_state(config), None
    resuming = (out / "checkpoints").is_dir() and checkpoint_manager(out, config, True).latest_step() is not None
    if config.init_from and not resuming:  # a source that cannot start this run fails before any file
        from socialnav.models.inference import model_problem
        from socialnav.models.warm_start import source_record, warm_started

        problem = model_problem(config.init_from)
        if problem:
            raise ValueError(f"init_from: {problem}")
        state, source = warm_started(state, config.init_from), source_record(config.init_from)
    out.mkdir(parents=True, exist_ok=True)
    config_path = out / "config.json"
    check_run_folder(out, config)
    if not config_path.exists():
        write_text_atomic(config_path, json.dumps(config.to_json(), indent=1))

    schedule = learning_rate_schedule(config)
    # The family index of a training sample counts the families this run draws, in FAMILIES order
    # (as dataset.generate numbers them).
    names = [f for f in dataset.FAMILIES if config.train_counts.get(f, 0) > 0]
    _, _, train_step, predict = compiled(config, objective)
    test = test_data(config)
    meta = {"step": 0, "wall_s": 0.0, "history": [], "baselines": None}

    manager = checkpoint_manager(out, config)
    if manager.latest_step() is not None:
        latest, state, meta = restore_state(manager, state, out, config, log=log)
        drop_unreadable(manager, latest, log, out)
        log(f"resuming {out} at step {latest} (epoch {latest // config.steps_per_epoch})")
        write_metrics(out, meta)  # a kill between a checkpoint and its metrics line loses nothing
    elif source is not None:
        from socialnav.models.warm_start import SOURCE_FILE

        write_text_atomic(out / SOURCE_FILE, json.dumps(source, indent=1))
        log(f"starting from the weights of {config.init_from}")
    if meta["baselines"] is None:
        meta["baselines"] = trivial_baselines(epoch_data(config, 0), test)
        write_text_atomic(out / "baselines.json", json.dumps(meta["baselines"], indent=1))
    if replicated is not None:
        state = jax.device_put(state, replicated)

    spe = config.steps_per_epoch
    step = int(meta["step"])
    last_step = config.total_steps if max_steps is None else min(config.total_steps, max_steps)

    def save(step):
        meta["step"] = step
        manager.save(
            step,
            args=ocp.args.Composite(state=ocp.args.StandardSave(host(state)), meta=ocp.args.JsonSave(meta)),
            force=True,
        )
        manager.wait_until_finished()

    bar = progress_lib.bar("train", unit="step", enabled=progress)
    line = meta["history"][-1] if meta["history"] else {}
    try:
        while step < last_step:
            epoch = step // spe
            t_start = time.perf_counter()  # wall_s counts data generation and training, not evaluation
            data = epoch_data(config, epoch)
            for b in range(step % spe, spe):
                batch = epoch_batch(data, b, config.batch_size, data_sharding)
                key = demonstration_key(config, step) if objective is not None else None
                state, loss = train_step(state, *batch, key)
                step += 1
                bar.update(step, config.total_steps)
                if step % 20 == 0:
                    _check_finite(loss, step, manager, out)
                    bar.set_postfix(loss=f"{float(loss):.5f}", epoch=epoch + 1)
                epoch_done = step % spe == 0
                if epoch_done or step % config.checkpoint_every_steps == 0 or step == last_step:
                    _check_finite(loss, step, manager, out)  # a diverged state is never saved
                    meta["wall_s"] += time.perf_counter() - t_start
                    t_start = time.perf_counter()
                    if epoch_done:
                        line = _end_epoch(config, meta, state, predict, test, names, epoch, step, schedule)
                        state = {
                            **state,
                            "family_sse": jnp.zeros_like(state["family_sse"]),
                            "family_count": jnp.zeros_like(state["family_count"]),
                        }
                        if replicated is not None:
                            state = jax.device_put(state, replicated)
                    save(step)
                    if epoch_done:
                        write_metrics(out, meta)
                        log(
                            f"epoch {epoch + 1}/{config.epochs}: train {line['train_mse']:.5f} "
                            f"test {line['test_mse']:.5f} ({line['wall_s']:.0f} s)"
                            + ("  meets the quality bar" if line["meets_quality"] else "")
                            + f"; rule suite: worst check {100 * line['rules_pass_min']:.0f} %"
                        )
                        if stop_when_good and line["meets_quality"] and line["meets_rules"]:
                            return line
                    t_start = time.perf_counter()
                if step >= last_step:
                    break
    finally:
        bar.close()
        manager.close()
    return line


def epoch_batch(data: dict, index: int, batch_size: int, data_sharding=None) -> tuple:
    """Batch ``index`` of an epoch's data (:func:`epoch_data`) as the training step takes it:
    ``(inputs, targets, family int32, contrast or None)``, put on ``data_sharding`` when given."""
    sl = slice(index * batch_size, (index + 1) * batch_size)
    batch = (data["inputs"][sl], data["targets"][sl], data["family"][sl].astype(np.int32))
    batch = (*batch, data["contrast"][sl] if "contrast" in data else None)
    return batch if data_sharding is None else jax.device_put(batch, data_sharding)


class TrainingDiverged(ValueError):
    """The training loss became NaN or infinite; the message names the step and the last checkpoint."""


def _check_finite(loss, step: int, manager, out) -> None:
    value = float(loss)
    if not np.isfinite(value):
        last = manager.latest_step()
        raise TrainingDiverged(
            f"the training loss became {value} by step {step}; stopped without saving it. "
            + (f"The last good checkpoint in {out} is step {last}. " if last is not None else "")
            + "Try a lower --learning-rate."
        )


def _end_epoch(config, meta, state, predict, test, names, epoch, step, schedule) -> dict:
    sse, count = np.asarray(state["family_sse"]), np.asarray(state["family_count"])
    train_by_family = {names[i]: float(sse[i] / count[i]) for i in range(len(names)) if count[i] > 0}
    t0 = time.perf_counter()
    mse = per_sample_mse(predict, state["params"], state["batch_stats"], test["inputs"], test["targets"])
    test_by_family = by_family(mse, test["family"], test["names"])
    line = {
        "epoch": epoch + 1,
        "step": step,
        "samples_seen": step * config.batch_size,
        "wall_s": round(meta["wall_s"], 2),
        "eval_s": round(time.perf_counter() - t0, 2),
        "learning_rate": float(schedule(step)),
        "train_mse": float(sse.sum() / max(count.sum(), 1)),
        "test_mse": float(mse.mean()),
        "train_mse_by_family": train_by_family,
        "test_mse_by_family": test_by_family,
        # Where the epoch ran: another processor rounds differently, so one command and seed train
        # another draw of the recipe there (a resumed run may span machines; the export's card lists them).
        "host": compiler_host(),
    }
    line["meets_quality"] = meets_quality(line["test_mse"], test_by_family, meta["baselines"])
    t0 = time.perf_counter()
    scale = output_scale(config)  # the costs as the layer reads them (1 for a model with the forbidden head)

    def layer_costs(maps):
        costs = predict(state["params"], state["batch_stats"], maps)
        return costs if scale == 1.0 else scale * costs

    suite = rules.evaluate(layer_costs, rules.build_suite(RULE_SCENES))
    line["rules_pass_by_check"] = {k: v["pass_share"] for k, v in suite["by_check"].items()}
    line["rules_pass_min"] = min(line["rules_pass_by_check"].values())
    line["meets_rules"] = rules.passes(suite)
    line["rules_s"] = round(time.perf_counter() - t0, 2)
    meta["history"].append(line)
    return line
