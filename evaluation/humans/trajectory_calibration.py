"""Human-model parameters fitted to ETH/UCY trajectories, leave one scene out, by gradient through
the crowd step and by Nelder-Mead as the check.

For each of the five scenes, the fit reads only that scene's *training* split (the other four
scenes' recordings, :func:`socialnav.data.recorded.eth_ucy_split`) and is scored on the scene's
test split, which it never reads. The loss is the prediction protocol's
(:func:`evaluation.humans.validation.eth_ucy_prediction`: 8 frames observed, 12 predicted, every
person aimed along their last observed velocity, walking groups detected over the observed
frames and walking on as groups)::

    loss(theta) = mean over scored people of the ADE (m) of the model's 12 predicted positions

``theta`` are the logarithms of the fitted fields (:data:`FITTED`: the velocity model's
interaction, its time gap, and Moussaïd's group terms' strengths; the body radius is left to the
Jülich fit). The loss is taken over one fixed sample of training windows (256 by default, drawn
once), minimised by Adam (optax, the gradient clipped to a global norm of 1) and by Nelder-Mead
(scipy) from the same start: one function for both, so their curves compare. The fields are
named ``"<part>.<field>"`` of :class:`evaluation.humans.validation.HumanModel` (``speed``,
``anticipation``, ``orca``, ``power_law``, ``group``).
"""

from __future__ import annotations

import dataclasses
import time

import jax
import jax.numpy as jnp
import numpy as np
import optax

from socialnav.common.memory import USABLE_SHARE, shortfall
from socialnav.data import recorded
from socialnav.evaluation.humans import measures, minimise
from socialnav.evaluation.humans import validation as hv
from socialnav.jaxsim import humans

_GROUP = ("group.gaze_per_rad", "group.attraction_mps2")
FITTED = {
    "collision_free_speed": ("speed.time_gap_s", "speed.neighbor_strength", "speed.neighbor_range_m", *_GROUP),
    "anticipation": (
        "anticipation.time_gap_s", "anticipation.neighbor_strength", "anticipation.neighbor_range_m",
        "anticipation.anticipation_time_s", *_GROUP,
    ),
    "orca": ("orca.time_horizon_s", *_GROUP),
    "steering_speed": ("speed.time_gap_s", "speed.neighbor_strength", "speed.neighbor_range_m",
                       "speed.steering_max_rad", *_GROUP),
    "power_law": ("power_law.strength_m2ps2", "power_law.horizon_s", "power_law.relaxation_s", *_GROUP),
}  # fmt: skip
# ORCA's fallback is a while_loop: its gradient is taken forward (evaluation.humans.minimise.value_and_grad).
FORWARD_MODE = ("orca",)


def with_values(model: hv.HumanModel, fields, values) -> hv.HumanModel:
    """``model`` with each ``"<part>.<field>"`` of ``fields`` set to the matching value."""
    parts = humans.by_part(dict(zip(fields, values, strict=True)))
    return dataclasses.replace(model, **{p: getattr(model, p).replace(**f) for p, f in parts.items()})


def values_of(model: hv.HumanModel, fields) -> dict:
    """``{"<part>.<field>": value}`` of ``model``'s ``fields``."""
    return {path: round(float(getattr(getattr(model, path.split(".")[0]), path.split(".")[1])), 4) for path in fields}


def ade_loss(model: hv.HumanModel, fields, theta, w: hv.PredictionWindows, key, groups: bool = True):
    """Mean ADE (m) over the scored people of windows ``w``, ``model`` with ``fields`` at
    ``exp(theta)``."""
    m = with_values(model, fields, jnp.exp(theta))
    predicted = hv.window_predictor(m.name, m.dt_s, "velocity", groups)(m.params, w, key)
    truth = jnp.asarray(w.future, jnp.float32)
    # (W, P); the epsilon keeps the gradient finite where a prediction is exact (a person standing)
    error = jnp.sqrt(jnp.sum((predicted - truth) ** 2, axis=-1) + 1e-12).mean(axis=-1)
    scored = jnp.asarray(w.complete, jnp.float32)
    return jnp.sum(error * scored) / jnp.maximum(jnp.sum(scored), 1.0)


def theta_of(model: hv.HumanModel, fields) -> jnp.ndarray:
    """The logarithms of ``model``'s ``fields``."""
    return jnp.log(jnp.asarray([getattr(getattr(model, p.split(".")[0]), p.split(".")[1]) for p in fields],
                               jnp.float32))  # fmt: skip


FitTooLarge = minimise.FitTooLarge  # a fit's sample of windows needs more memory than is available


def refuse_past_memory(compiled, sample: hv.PredictionWindows, share: float = USABLE_SHARE) -> None:
    """Raise :class:`FitTooLarge` where the compiled loss and gradient over ``sample`` need more
    than ``share`` of the memory available (XLA's own count of its buffers; nothing is checked where
    the available memory is not known)."""
    needed = minimise.held_bytes(compiled)
    available = None if needed is None else shortfall(needed, share)
    if available is not None:
        windows, people = sample.start.shape[:2]
        fits = int(windows * share * available / needed)
        raise FitTooLarge(
            f"a fit over {windows:,} windows of up to {people} people holds about {needed / 1e9:.1f} GB at once, "
            f"this machine has {available / 1e9:.1f} GB available: about {fits:,} windows fit"
        )


def fit_gradient(model, fields, sample: hv.PredictionWindows, steps: int = 60, learning_rate: float = 0.2,
                 groups: bool = True, log=print):  # fmt: skip
    """Adam on :func:`ade_loss` over the fixed training windows ``sample`` (the loss Nelder-Mead
    minimises, so the two are compared on one function): ``(fitted model, history)``, the model at
    the lowest loss seen, ``history`` a list of ``(step, loss, seconds)``."""
    loss_and_grad = minimise.value_and_grad(
        lambda th, w: ade_loss(model, fields, th, w, jax.random.key(0), groups), forward=model.name in FORWARD_MODE
    )
    # compiled here to ask XLA what it holds at once: a rollout of every window's people, kept for
    # the gradient, is 22 MB a window of 75 people (5.7 GB at the default 256 windows)
    loss_and_grad = loss_and_grad.lower(theta_of(model, fields), sample).compile()
    refuse_past_memory(loss_and_grad, sample)
    # the rollout's gradient spikes where a neighbour enters or leaves a lane (the speed model's
    # min and lane test are piecewise): clipped to a global norm of 1 before Adam
    optimizer = optax.chain(optax.clip_by_global_norm(1.0), optax.adam(learning_rate))
    best, history = minimise.adam(loss_and_grad, theta_of(model, fields), steps, optimizer, (sample,), log,
                                  "ADE {:.3f} m")  # fmt: skip
    return with_values(model, fields, jnp.exp(best)), history


def fit_nelder_mead(model, fields, sample: hv.PredictionWindows, max_evaluations: int = 60, groups: bool = True,
                    log=print):  # fmt: skip
    """Nelder-Mead (scipy) on :func:`ade_loss` over the fixed windows ``sample``: ``(fitted
    model, history)`` as :func:`fit_gradient`."""
    loss = jax.jit(lambda th, w: ade_loss(model, fields, th, w, jax.random.key(0), groups))
    x, history = minimise.nelder_mead(loss, theta_of(model, fields), max_evaluations, 1e-4, (sample,), log,
                                      "ADE {:.3f} m")  # fmt: skip
    return with_values(model, fields, np.exp(x)), history


def errors(model: hv.HumanModel | None, w: hv.PredictionWindows, groups: bool = True, seed: int = 0) -> tuple:
    """``(ade, fde, window)``: (N,) each scored person's ADE and FDE (m) on windows ``w`` under
    ``model`` (None: constant velocity) and (N,) the window they were scored in."""
    if model is None:
        predicted = w.constant_velocity
    else:
        predict = hv.window_predictor(model.name, model.dt_s, "velocity", groups)
        predicted = np.asarray(predict(model.params, w, jax.random.key(seed)))
    ade, fde = measures.ade_fde(predicted[w.complete], w.future[w.complete])
    return ade, fde, np.nonzero(w.complete)[0]


def average_vs_cv(model: hv.HumanModel, rows: list[dict], method: str = "nelder_mead", fields=None,
                  groups: bool = True, seed: int = 0) -> dict:  # fmt: skip
    """How far ``method``'s fits (``"gradient"`` or ``"nelder_mead"``) in ``rows`` (of
    :func:`leave_one_scene_out`) lie from constant velocity on the average over the rows' scenes:
    ``{"ade_m": [d, low, high], "fde_m": [...], "scenes": [...], "by_scene": {scene: {"ade_m": [d,
    low, high], "fde_m": [...]}}}``, the average of the scenes' differences (m; below 0: ahead) and
    its 95 % interval (:func:`evaluation.humans.measures.mean_paired_difference`), and each
    scene's (:func:`evaluation.humans.measures.paired_difference`). Each scene's fit is predicted
    again on its test split as the row scored it, from the row's values, which are rounded to four
    figures: the average may differ from the rows' by a few tenths of a millimetre."""
    fields = FITTED[model.name] if fields is None else fields
    paired = {"ade": [], "fde": []}
    for row in rows:
        w = hv.prediction_windows(row["scene"], "test")
        values = row[f"{method}_values"]
        ade, fde, window = errors(with_values(model, fields, [values[f] for f in fields]), w, groups, seed)
        ade_cv, fde_cv, _ = errors(None, w)
        paired["ade"].append((ade, ade_cv, window))
        paired["fde"].append((fde, fde_cv, window))
    rounded = lambda interval: [round(x, 4) for x in interval]
    average = {f"{e}_m": rounded(measures.mean_paired_difference(paired[e], seed=seed)) for e in ("ade", "fde")}
    by_scene = {row["scene"]: {f"{e}_m": rounded(measures.paired_difference(*paired[e][k], seed=seed))
                               for e in ("ade", "fde")} for k, row in enumerate(rows)}  # fmt: skip
    return {**average, "scenes": [row["scene"] for row in rows], "by_scene": by_scene}


def leave_one_scene_out(model: hv.HumanModel, fields=None, scenes=recorded.ETH_UCY_SCENES, steps: int = 60,
                        learning_rate: float = 0.2, evaluations: int = 60, sample: int = 256, seed: int = 0,
                        log=print, on_scene=None) -> list[dict]:  # fmt: skip
    """One fit a scene on ``sample`` windows drawn from its training split (by gradient; by
    Nelder-Mead too when ``evaluations`` > 0), scored on its test split: a row a scene with the
    test ADE/FDE of constant velocity, of ``model`` as given and as fitted, the fitted values,
    the loss curves on the training sample. ``on_scene(rows so far)`` is called as each scene's
    row is done."""
    fields = FITTED[model.name] if fields is None else fields
    rows = []
    for scene in scenes:
        log(f"{scene}: fitting on the other scenes (its training split)")
        try:
            train, test = hv.prediction_windows(scene, "train"), hv.prediction_windows(scene, "test")
            row = fit_and_score(model, fields, train, test, steps, learning_rate, evaluations, sample, seed, log)
        except FitTooLarge as e:
            raise FitTooLarge(f"{scene}: {e}") from None
        rows.append({"scene": scene, **row})
        log(f"  {scene} test ADE/FDE: {row_line(row)}")
        if on_scene is not None:
            on_scene(list(rows))
    return rows


def fit_and_score(model: hv.HumanModel, fields, train: hv.PredictionWindows, test: hv.PredictionWindows,
                  steps: int = 60, learning_rate: float = 0.2, evaluations: int = 60, sample: int = 256,
                  seed: int = 0, log=print, intervals: bool = False) -> dict:  # fmt: skip
    """One fit on ``sample`` windows drawn from ``train`` (by gradient; by Nelder-Mead too when
    ``evaluations`` > 0), scored on ``test``: the test ADE/FDE of constant velocity, of ``model``
    as given and as fitted, the fitted values, the loss curves on the training sample (a row of
    :func:`leave_one_scene_out`, without its scene). With ``intervals``, also ``"vs_cv"``: each of
    ``start``, ``gradient`` and ``nelder_mead``'s test ADE and FDE minus constant velocity's with a
    95 % interval (:func:`evaluation.humans.measures.paired_difference`), from the same predictions."""
    pick = np.random.default_rng(seed).choice(len(train.start), size=min(sample, len(train.start)), replace=False)
    log(f"  fitting on {len(pick)} training windows of {len(train.start)}")
    fixed = train.take(np.sort(pick))
    fitted, history = fit_gradient(model, fields, fixed, steps, learning_rate, log=log)
    # each predictor's per-person errors on the test windows, taken once: their means are the row's
    # figures, and (with ``intervals``) their paired differences from constant velocity's
    predicted = {
        "constant_velocity": errors(None, test),
        "start": errors(model, test),
        "gradient": errors(fitted, test),
    }
    mean = lambda key: (float(predicted[key][0].mean()), float(predicted[key][1].mean()))
    row = {
        "train_windows": len(train.start),
        "sample_windows": len(fixed.start),
        "constant_velocity": mean("constant_velocity"),
        "start": mean("start"),
        "gradient": mean("gradient"),
        "gradient_values": values_of(fitted, fields),
        "gradient_history": history,
        "sample_loss": {"start": history[0][1], "gradient": min(h[1] for h in history)},
    }
    if evaluations:
        by_search, search_history = fit_nelder_mead(model, fields, fixed, evaluations, log=log)
        predicted["nelder_mead"] = errors(by_search, test)
        row.update(nelder_mead=mean("nelder_mead"), nelder_mead_values=values_of(by_search, fields),
                   nelder_mead_history=search_history)  # fmt: skip
        row["sample_loss"]["nelder_mead"] = min(h[1] for h in search_history)
    if intervals:
        ade_cv, fde_cv, window = predicted.pop("constant_velocity")
        row["vs_cv"] = {
            key: {f"{e}_m": [round(x, 4) for x in measures.paired_difference(err, cv, window, seed=seed)]
                  for e, err, cv in (("ade", ade, ade_cv), ("fde", fde, fde_cv))}
            for key, (ade, fde, _) in predicted.items()
        }  # fmt: skip
    return row


def row_line(row: dict) -> str:
    """A fit's test figures in one line: constant velocity's, as given, by each method."""
    return (
        f"constant velocity {row['constant_velocity'][0]:.3f}/{row['constant_velocity'][1]:.3f}, as given "
        f"{row['start'][0]:.3f}/{row['start'][1]:.3f}, by gradient {row['gradient'][0]:.3f}/{row['gradient'][1]:.3f}"
        + (f", by Nelder-Mead {row['nelder_mead'][0]:.3f}/{row['nelder_mead'][1]:.3f}" if "nelder_mead" in row else "")
    )


def calibrate(model: hv.HumanModel, scenes=recorded.ETH_UCY_SCENES, steps: int = 60, learning_rate: float = 0.2,
              evaluations: int = 60, sample: int = 256, seed: int = 0, log=print, name: str | None = None,
              progress=None) -> dict:  # fmt: skip
    """:func:`leave_one_scene_out` of ``model``'s :data:`FITTED` fields, with each method's fits
    against constant velocity on the average over the held-out scenes (:func:`average_vs_cv`).

    Returns the record ``socialnav humans calibrate --data eth_ucy`` writes as ``fit.json``: the
    model (``name``, default the model's kind: a preset's name says which values it started
    from), the fields, their values at the start, a row a scene (``"scenes"``), ``"average_vs_cv"``
    (a method -> its average and by-scene intervals), the seed and the seconds taken,
    ``"complete": true``. ``progress``: called with the record so far (the scenes done,
    ``"complete": false``) as each scene's fit ends, so a run stopped before its end keeps them.
    """
    t0 = time.perf_counter()
    fields = FITTED[model.name]
    head = {"model": name or model.name, "data": "eth_ucy", "fields": list(fields), "start": values_of(model, fields)}

    def scenes_done(rows):
        progress({**head, "scenes": rows, "seed": seed, "complete": False})

    rows = leave_one_scene_out(model, fields, scenes, steps, learning_rate, evaluations, sample, seed=seed, log=log,
                               on_scene=None if progress is None else scenes_done)  # fmt: skip
    average = {m: average_vs_cv(model, rows, m, fields) for m in ("gradient", "nelder_mead") if m in rows[0]}
    return {**head, "scenes": rows, "average_vs_cv": average, "seed": seed,
            "seconds": round(time.perf_counter() - t0, 1), "complete": True}  # fmt: skip
