"""The files of a training run: ``config.json``, orbax checkpoints, ``metrics.jsonl``.

* ``config.json`` - the :class:`~models.config.TrainConfig` (a resumed run must match it);
* ``checkpoints/<step>/`` - orbax checkpoints (model, optimiser, accumulators, metrics so far);
  orbax commits a checkpoint by renaming it, so a kill loses at most the steps since the last;
* ``metrics.jsonl`` - one line per epoch, rewritten atomically from the checkpoint, so it never
  disagrees with it; ``baselines.json`` - the trivial predictors' test MSE.
"""

from __future__ import annotations

import json
import pathlib

import jax
import numpy as np

from socialnav.common.atomic import write_text_atomic
from socialnav.models.config import TrainConfig
from socialnav.models.steps import compiled, state_template


def write_metrics(out: pathlib.Path, meta: dict) -> None:
    """Rewrite ``metrics.jsonl`` from the history in a checkpoint's metadata."""
    if meta["history"]:
        write_text_atomic(out / "metrics.jsonl", "".join(json.dumps(h) + "\n" for h in meta["history"]))


def checkpoint_manager(out: pathlib.Path, config: TrainConfig, read_only: bool = False):
    import orbax.checkpoint as ocp

    options = ocp.CheckpointManagerOptions(
        max_to_keep=config.keep_checkpoints, create=not read_only, enable_async_checkpointing=False, read_only=read_only
    )
    return ocp.CheckpointManager((out / "checkpoints").absolute(), options=options)


def host(tree):
    """A pytree of device arrays as host numpy arrays (what orbax saves)."""
    return jax.tree.map(np.asarray, tree)


def load_config(out) -> TrainConfig:
    """The configuration stored in run folder ``out``."""
    path = pathlib.Path(out) / "config.json"
    if not path.exists():
        raise FileNotFoundError(f"{out} holds no training run (no config.json)")
    try:
        raw = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as e:
        raise ValueError(f"{path}: not valid JSON ({e})") from None
    return TrainConfig.from_json(raw, str(path))


def check_run_folder(out, config: TrainConfig) -> None:
    """Raise ValueError if ``out`` holds a run with another configuration."""
    path = pathlib.Path(out) / "config.json"
    if path.exists() and load_config(out) != config:
        raise ValueError(
            f"{out} holds a run with another configuration ({path}); "
            "resume it with the same settings or choose another output folder"
        )


def newest_restorable(steps, restore_one) -> tuple[int | None, object, list[str]]:
    """``(step, restored, failures)``: the newest of ``steps`` that ``restore_one(step)``
    restores (it returns the restored tree, or raises, or returns a string saying why the tree
    does not fit), with one line per newer step it fell back past; ``(None, None, failures)``
    when none restores. Orbax and tensorstore raise many types for a damaged or foreign file, so
    any exception counts as a failure."""
    failures = []
    for candidate in sorted(steps, reverse=True):
        try:
            restored = restore_one(candidate)
        except Exception as e:
            first = str(e).strip().splitlines()[0][:200] if str(e).strip() else type(e).__name__
            failures.append(f"step {candidate}: {first}")
            continue
        if isinstance(restored, str):
            failures.append(f"step {candidate}: {restored}")
            continue
        return candidate, restored, failures
    return None, None, failures


def drop_unreadable(manager, restored_step: int, log=print, where="") -> list[int]:
    """Delete the checkpoints newer than ``restored_step``, which :func:`newest_restorable` fell
    back past: a resumed run trains those steps again and saving them needs their places (left,
    orbax stopped every resume with "Checkpoint for step N already exists"). Returns the steps."""
    dropped = sorted(s for s in manager.all_steps() if s > restored_step)
    for step in dropped:
        manager.delete(step)
        log(f"warning: {where}: removed the unreadable checkpoint of step {step}; its steps are trained again")
    return dropped


class CheckpointError(ValueError):
    """No checkpoint of a run folder can be restored with its ``config.json``; the message says why."""


def restore_state(manager, template, out, config: TrainConfig, step: int | None = None, log=print):
    """``(step, state, meta)`` restored into ``template``'s shapes: the given step, or the newest
    checkpoint that restores, falling back past unreadable ones with a warning (``log``).

    Raises:
      CheckpointError: the run has no checkpoint, or none restores (a config.json whose widths
        differ from the weights' reads this way too); FileNotFoundError for a missing ``step``.
    """
    import orbax.checkpoint as ocp

    steps = sorted(manager.all_steps(), reverse=True)
    if step is not None:
        if step not in steps:
            raise FileNotFoundError(f"{out} has no checkpoint at step {step} (it has {sorted(steps)})")
        steps = [step]
    if not steps:
        raise FileNotFoundError(f"{out} has no checkpoint yet")

    def restore_one(candidate):
        restored = manager.restore(
            candidate,
            args=ocp.args.Composite(state=ocp.args.StandardRestore(host(template)), meta=ocp.args.JsonRestore()),
        )
        # orbax restores the saved shapes whatever the template's
        return _shape_mismatch(template, restored["state"]) or restored

    candidate, restored, failures = newest_restorable(steps, restore_one)
    if candidate is not None:
        if failures:
            log(f"warning: {out}: skipped unreadable checkpoint(s) ({'; '.join(failures)}); using step {candidate}")
        return candidate, restored["state"], restored["meta"]
    raise CheckpointError(
        f"{out}/checkpoints: no checkpoint restores with {out}/config.json (features "
        f"{list(config.features)}): {'; '.join(failures)}. "
        "A truncated or damaged checkpoint, or a config.json that does not describe these weights"
    )


def _shape_mismatch(template, restored) -> str:
    """'' if ``restored`` has ``template``'s tree and shapes, else where it first differs."""
    want = jax.tree_util.tree_flatten_with_path(template)[0]
    got = jax.tree_util.tree_flatten_with_path(restored)[0]
    if [p for p, _ in want] != [p for p, _ in got]:
        return "its arrays are not those of this configuration's model"
    for (path, a), (_, b) in zip(want, got, strict=True):
        if np.shape(a) != np.shape(b):
            return f"{jax.tree_util.keystr(path)} has shape {np.shape(b)}, this configuration's model {np.shape(a)}"
    return ""


def restore(out, step: int | None = None, log=print):
    """``(config, graphdef, state, meta)`` of a run's checkpoint (the newest good one by default)."""
    out = pathlib.Path(out)
    config = load_config(out)
    graphdef = compiled(config)[0]
    template = state_template(config)
    with checkpoint_manager(out, config, read_only=True) as manager:
        _, state, meta = restore_state(manager, template, out, config, step, log)
    return config, graphdef, state, meta
