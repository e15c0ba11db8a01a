"""The files of a policy training run, and the trained policy as an arena actor.

* ``config.json``: the :class:`~planners.learning.policy_training.PPOConfig` and the feature length (a
  resumed run must match it);
* ``checkpoints/<update>/``: orbax checkpoints of the whole :class:`TrainState` (``weights``
  apart, so the benchmark restores the network alone) and the metrics so far; orbax commits a
  checkpoint by renaming it, so a kill loses at most the updates since the last one;
* ``metrics.jsonl``: one line per update, rewritten atomically from the newest checkpoint (it
  never disagrees with it), each with the host it ran on (``host``,
  :func:`common.machine.compiler_host`); ``curve.png``: the training curve.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import pathlib

import jax
import numpy as np

from socialnav.common.atomic import write_text_atomic
from socialnav.common.machine import compiler_host
from socialnav.planners.learning import policy as policy_lib
from socialnav.planners.learning import policy_social
from socialnav.planners.learning.policy_training import PPOConfig, TrainState

CONFIG = "config.json"
CHECKPOINTS = "checkpoints"
METRICS = "metrics.jsonl"
CURVE = "curve.png"


class PolicyRunError(ValueError):
    """A folder that is not a usable policy run; the message names the file and why (one line)."""


def _host(tree):
    return jax.tree.map(np.asarray, tree)


def write_config(out: pathlib.Path, config: PPOConfig, n_features: int) -> None:
    write_text_atomic(out / CONFIG, json.dumps({"ppo": config.to_json(), "n_features": n_features}, indent=1) + "\n")


def read_config(out: pathlib.Path) -> tuple[PPOConfig, int]:
    """``(config, n_features)`` of a run; :class:`PolicyRunError` naming the file otherwise."""
    path = pathlib.Path(out) / CONFIG
    try:
        d = json.loads(path.read_text())
        return PPOConfig.from_json(d["ppo"]), int(d["n_features"])
    except FileNotFoundError:
        raise PolicyRunError(f"{path}: no such file (not a policy run: make one with socialnav policy train)") from None
    except (ValueError, KeyError, TypeError) as e:
        raise PolicyRunError(f"{path}: not a policy run's configuration ({type(e).__name__}: {e})") from None


def manager(out: pathlib.Path, read_only: bool = False, keep: int = 2):
    import orbax.checkpoint as ocp

    options = ocp.CheckpointManagerOptions(
        max_to_keep=keep, create=not read_only, enable_async_checkpointing=False, read_only=read_only
    )
    return ocp.CheckpointManager((pathlib.Path(out) / CHECKPOINTS).absolute(), options=options)


def save(mgr, state: TrainState, history: list[dict]) -> None:
    """A checkpoint at ``state.update`` (the weights, the rest of the state, the history)."""
    import orbax.checkpoint as ocp

    rest = (state.opt_state, state.runners, state.update)
    mgr.save(
        int(state.update),
        args=ocp.args.Composite(
            weights=ocp.args.StandardSave(_host(state.weights)),
            rest=ocp.args.StandardSave(_host(rest)),
            meta=ocp.args.JsonSave({"history": history}),
        ),
    )


def restore(mgr, template: TrainState, log=print) -> tuple[TrainState, list[dict]] | None:
    """The newest checkpoint that restores in ``template``'s shapes, with its history, or None
    without one. A damaged newer checkpoint is skipped with a warning (``log``) and removed, so
    the resumed run saves those updates again (:func:`models.checkpoints.drop_unreadable`).

    Raises:
      PolicyRunError: no checkpoint restores, naming each step and why, and the fix.
    """
    import orbax.checkpoint as ocp

    from socialnav.models.checkpoints import drop_unreadable, newest_restorable

    steps = mgr.all_steps()
    if not steps:
        return None
    rest_template = (template.opt_state, template.runners, template.update)

    def restore_one(step):
        return mgr.restore(
            step,
            args=ocp.args.Composite(
                weights=ocp.args.StandardRestore(_host(template.weights)),
                rest=ocp.args.StandardRestore(_host(rest_template)),
                meta=ocp.args.JsonRestore(),
            ),
        )

    step, got, failures = newest_restorable(steps, restore_one)
    if step is None:
        raise PolicyRunError(
            f"{mgr.directory}: no checkpoint restores ({'; '.join(failures)}): damaged files, or a run of an earlier "
            "version of the trainer (which still serves socialnav arena --policy-run); remove the damaged step "
            "folder(s) to resume from an older one, or start a new run in another --out"
        )
    if failures:
        log(f"warning: {mgr.directory}: skipped unreadable checkpoint(s) ({'; '.join(failures)}); using step {step}")
        drop_unreadable(mgr, step, log, mgr.directory)
    opt_state, runners, update = jax.tree.map(jax.numpy.asarray, got["rest"])
    weights = jax.tree.map(jax.numpy.asarray, got["weights"])
    return TrainState(weights, opt_state, runners, update), got["meta"]["history"]


def write_metrics(out: pathlib.Path, history: list[dict]) -> None:
    write_text_atomic(pathlib.Path(out) / METRICS, "".join(json.dumps(h) + "\n" for h in history))


def load_weights(out, log=None) -> tuple[PPOConfig, object, object, int]:
    """``(config, graphdef, weights, update)`` of a run's newest checkpoint whose weights restore
    (the network only; a damaged newer one is skipped with a warning on stderr, or ``log``)."""
    import sys

    import orbax.checkpoint as ocp

    from socialnav.models import policy_net
    from socialnav.models.checkpoints import newest_restorable

    log = log or (lambda message: print(message, file=sys.stderr))

    out = pathlib.Path(out)
    config, n_features = read_config(out)
    graphdef, template = policy_net.init_weights(n_features, config.policy.hidden, 0)
    if not (out / CHECKPOINTS).is_dir():
        raise PolicyRunError(f"{out / CHECKPOINTS}: no such folder (the run has no checkpoint yet)")
    with manager(out, read_only=True) as mgr:
        if not mgr.all_steps():
            raise PolicyRunError(f"{out / CHECKPOINTS}: no checkpoint yet")
        restore_one = lambda step: mgr.restore(
            step, args=ocp.args.Composite(weights=ocp.args.StandardRestore(_host(template)))
        )
        step, got, failures = newest_restorable(mgr.all_steps(), restore_one)
    if step is None:
        raise PolicyRunError(f"{out / CHECKPOINTS}: no checkpoint's weights restore ({'; '.join(failures)})")
    if failures:
        skipped = "; ".join(failures)
        log(f"warning: {out / CHECKPOINTS}: skipped unreadable checkpoint(s) ({skipped}); using step {step}")
    weights = jax.tree.map(jax.numpy.asarray, got["weights"])
    for path, a in jax.tree_util.tree_flatten_with_path(weights)[0]:
        if not np.all(np.isfinite(np.asarray(a))):
            raise PolicyRunError(f"{out / CHECKPOINTS}/{step}: {jax.tree_util.keystr(path)} is not finite")
    return config, graphdef, weights, step


def _gscl(config: PPOConfig, out):
    """The GSCL channel's model of a run (:func:`policy_social.load_gscl`; None without it)."""
    if config.policy.social_layer != "gscl":
        return None
    try:
        return policy_social.load_gscl(config.policy.gscl_run)
    except ValueError as e:
        raise PolicyRunError(f"{pathlib.Path(out) / CONFIG}: policy.gscl_run: {e}") from None


def run_digest(out) -> str:
    """The digest of what a run's actor computes with: its weights, and the GSCL channel's
    network's weights where it has one."""
    config, _, weights, _ = load_weights(out)
    gscl_model = _gscl(config, out)
    return weights_digest(weights if gscl_model is None else (weights, gscl_model.weights))


def weights_digest(weights) -> str:
    """sha256 of the weights' bytes (a changed network is a changed benchmark run)."""
    h = hashlib.sha256()
    for a in jax.tree.leaves(weights):
        h.update(np.ascontiguousarray(np.asarray(a)).tobytes())
    return h.hexdigest()[:16]


def actor_factory(out, name: str = "ppo"):
    """``factory(env) -> (actor, params)`` of a run's trained policy (the arena's ``user_actors``
    form), the network restored once."""
    config, graphdef, weights, _ = load_weights(out)
    _, n_features = read_config(out)
    gscl_model = _gscl(config, out)

    def factory(env):
        window = env.config.window_cells
        if config.policy.n_features(window) != n_features:
            raise PolicyRunError(f"{out}: the policy was trained with another observation window than {window} cells")
        grid = policy_lib.scene_grid(env)
        actor = policy_lib.policy_actor(config.policy, graphdef, grid, name, gscl_model)
        return actor, policy_lib.policy_params(env, weights, gscl_model)

    factory.__name__ = name
    return factory


def plot_curve(history: list[dict], path: pathlib.Path) -> pathlib.Path:
    """The training curve: the mean return and the goal, social success and person-contact rates
    of the episodes that ended in each update, against environment steps (a history from before
    social success was recorded draws no social line)."""
    from socialnav.common import figures

    fig = figures.figure(figsize=(9, 3.4))
    steps = np.array([h["env_steps"] for h in history], float) / 1e6
    ax1, ax2 = fig.subplots(1, 2)
    ax1.plot(steps, [h["return"] for h in history], color="tab:blue")
    ax1.set(xlabel="environment steps (M)", ylabel="mean episode return", title="return (training reward)")
    ax2.plot(steps, [100 * h["goal_rate"] for h in history], label="goal reached", color="tab:green")
    ax2.plot(steps, [100 * h.get("social_rate", np.nan) for h in history], label="social success", color="tab:purple")
    ax2.plot(steps, [100 * h["contact_rate"] for h in history], label="touched a person", color="tab:red")
    ax2.set(xlabel="environment steps (M)", ylabel="% of ended episodes", ylim=(-2, 102), title="episodes")
    ax2.legend(loc="center right")
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3)
    fig.tight_layout()
    return figures.save(fig, path)


def train(
    specs,
    config: PPOConfig,
    out,
    progress: bool = True,
    stop_after_updates: int | None = None,
    log=print,
) -> list[dict]:
    """Train (or resume) the run in ``out`` up to ``config.updates``; returns the history. A
    run may be resumed with more (or fewer) updates than it was started with, nothing else changed.

    A checkpoint every ``config.checkpoint_every`` updates and at the end; ``metrics.jsonl`` and
    ``curve.png`` follow each checkpoint. ``stop_after_updates`` stops early after that many
    updates of this call (tests: an interrupted run), checkpointing first.
    """
    import time

    from socialnav.common import progress as progress_lib
    from socialnav.common.memory import available_bytes
    from socialnav.planners.learning.policy_training import Trainer, size_problem

    problem = size_problem(len(specs), config, available_bytes())
    if problem:
        raise PolicyRunError(problem)
    out = pathlib.Path(out)
    out.mkdir(parents=True, exist_ok=True)
    try:
        trainer = Trainer(specs, config)
    except ValueError as e:  # the GSCL channel's run is not one
        raise PolicyRunError(str(e)) from None
    stored = read_config(out) if (out / CONFIG).exists() else None
    if stored is not None and (
        dataclasses.replace(stored[0], updates=config.updates) != config or stored[1] != trainer.n_features
    ):
        differ = [
            f.name
            for f in dataclasses.fields(config)
            if f.name != "updates" and getattr(stored[0], f.name) != getattr(config, f.name)
        ]
        raise PolicyRunError(
            f"{out / CONFIG} holds a run with other settings ({', '.join(differ) or 'the feature length'}): resume it "
            "with the same ones (only --updates may change) or choose another --out"
        )
    if stored is None or stored[0].updates != config.updates:  # a new run, or one trained on for longer
        write_config(out, config, trainer.n_features)
    state = trainer.initial_state()
    history: list[dict] = []
    with manager(out) as mgr:
        restored = restore(mgr, state, log)
        if restored is not None:
            state, history = restored
            log(f"resuming {out} at update {int(state.update)} of {config.updates}")
        done_here = 0
        wall0 = history[-1]["wall_s"] if history else 0.0
        # Where the updates ran: another processor rounds differently, so the same settings and
        # seed train other weights there (a resumed run may span machines: hosts_of lists them).
        host = compiler_host()
        t0 = time.perf_counter()
        with progress_lib.bar("policy train", unit="update", enabled=progress) as bar:
            while int(state.update) < config.updates:
                state, metrics = trainer.step(state)
                metrics["wall_s"] = wall0 + time.perf_counter() - t0
                metrics["host"] = host
                history.append(metrics)
                done_here += 1
                bar.update(int(state.update), config.updates)
                if metrics["episodes"]:  # the episodes that ended in this update
                    bar.set_postfix(
                        ret=f"{metrics['return']:.2f}",
                        goal=f"{100 * metrics['goal_rate']:.0f}%",
                        social=f"{100 * metrics['social_rate']:.0f}%",
                        contact=f"{100 * metrics['contact_rate']:.0f}%",
                    )
                last = int(state.update) >= config.updates
                stop = stop_after_updates is not None and done_here >= stop_after_updates
                if last or stop or int(state.update) % config.checkpoint_every == 0:
                    save(mgr, state, history)
                    write_metrics(out, history)
                    plot_curve(history, out / CURVE)
                if stop:
                    break
    return history
