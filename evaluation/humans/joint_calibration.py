"""One parameter set for both kinds of data: a human model fitted at once to the Jülich corridors'
fundamental diagram and to ETH/UCY trajectories, the exchange rate between the two swept.

Issue 61's bar asks one model to walk the diagram's speeds *and* to predict ETH/UCY walkers better
than constant velocity. Fitted apart, the two pull a velocity model's parameters apart: the
diagram wants bodies and a repulsion (the steering model's Jülich fit: radius 0.18 m, strength
8.5), open-space prediction wants almost none (with both near zero the model is constant
velocity). The joint loss is::

    loss_w(theta) = fd_loss(theta) + w * 100 * (ADE(theta) / ADE_cv - 1)

- ``fd_loss``: :func:`evaluation.humans.calibration.fd_loss` on the Jülich *training* runs (mean
  over density bins of the squared speed error in the data's standard deviations);
- ``ADE``: the prediction protocol's (:func:`evaluation.humans.validation.eth_ucy_prediction`: 8
  frames observed, 12 predicted, every person aimed along their last observed velocity, no
  groups, as the bar's check) over the windows of :data:`TRAIN_RECORDINGS`, the two ETH/UCY
  recordings that no scene tests on (in every leave-one-scene-out fold's training split, in no
  test split), their frames before each file's validation cut; ``ADE_cv`` constant velocity's on
  the same windows, so the second term is the percent by which the model trails constant
  velocity there.

``w`` is an exchange rate (one percent of ADE against ``w`` units of the diagram's loss). No value
of it is privileged, so it is swept (:data:`WEIGHTS`, fixed before any result was seen, log-spaced
from "the diagram dominates" to "prediction dominates") and every fit is scored on held-out data
by the validation (the Jülich test runs, the bi-directional run, the five ETH/UCY test splits).

The fit is Nelder-Mead (scipy) from the model's own values: the steering model's choice of
heading is piecewise, and Adam through it stalled on the diagram alone (loss 2.85 against the
search's 1.17, :mod:`evaluation.humans.calibration`).
"""

from __future__ import annotations

import dataclasses
import time

import jax
import jax.numpy as jnp

from socialnav.data import recorded
from socialnav.evaluation.humans import calibration as hc
from socialnav.evaluation.humans import measures, minimise
from socialnav.evaluation.humans import validation as hv

# The ETH/UCY recordings no scene's test split holds (Trajectron++'s splits: univ tests on
# students001/003, zara2 on crowds_zara02).
TRAIN_RECORDINGS = tuple(r for r in recorded.run_names("eth_ucy") if recorded.run_info(r).get("test_of_scene") is None)
# The exchange rates swept: w units of the diagram's loss per percent of ADE behind constant velocity.
WEIGHTS = (0.03, 0.1, 0.3, 1.0)


@dataclasses.dataclass(frozen=True)
class JointData:
    """What the joint loss reads: the diagram's training corridors, the ETH/UCY training windows
    and constant velocity's ADE (m) on them."""

    corridors: hc.Corridors
    windows: hv.PredictionWindows
    constant_velocity_ade_m: float


def training_windows(recordings=TRAIN_RECORDINGS) -> hv.PredictionWindows:
    """The prediction windows of ``recordings``, each cut before its ``validation_from_frame``."""
    rows = recorded.trajectories(list(recordings))
    cut = rows["run"].map({r: recorded.run_info(r)["validation_from_frame"] for r in recordings})
    return hv.windows_of(rows[(rows["frame"] < cut).to_numpy()].reset_index(drop=True))


def joint_data(model: hv.HumanModel, seed: int = 0, recordings=TRAIN_RECORDINGS, **size) -> JointData:
    """The training data of :func:`joint_loss` for ``model`` (``size``: the corridors', as
    :func:`evaluation.humans.calibration.corridors_at`)."""
    windows = training_windows(recordings)
    ade, _ = measures.ade_fde(windows.constant_velocity[windows.complete], windows.future[windows.complete])
    return JointData(hc.training_corridors(model, seed, **size), windows, float(ade.mean()))


def prediction_ade(model: hv.HumanModel, windows: hv.PredictionWindows, key) -> jnp.ndarray:
    """Mean ADE (m) of ``model`` over the scored people of ``windows``, aimed along their velocity."""
    predicted = hv.window_predictor(model.name, model.dt_s, "velocity", False)(model.params, windows, key)
    error = jnp.linalg.norm(predicted - jnp.asarray(windows.future, jnp.float32), axis=-1).mean(axis=-1)
    scored = jnp.asarray(windows.complete, jnp.float32)
    return jnp.sum(error * scored) / jnp.maximum(jnp.sum(scored), 1.0)


def joint_terms(model: hv.HumanModel, data: JointData, theta, key) -> tuple[jnp.ndarray, jnp.ndarray]:
    """``(fd_loss, percent of ADE behind constant velocity)`` of ``model`` with its fitted fields
    (:data:`evaluation.humans.calibration.FITTED`) at ``exp(theta)``."""
    fd = hc.fd_loss(model, data.corridors, theta, key, stop_warmup=False)
    ade = prediction_ade(hc.with_theta(model, theta), data.windows, key)
    return fd, 100.0 * (ade / data.constant_velocity_ade_m - 1.0)


def joint_loss(model: hv.HumanModel, data: JointData, theta, key, weight: float) -> jnp.ndarray:
    """The loss of the module's docstring at exchange rate ``weight``."""
    fd, behind_pct = joint_terms(model, data, theta, key)
    return fd + weight * behind_pct


def compiled_loss(model: hv.HumanModel, data: JointData):
    """``loss(theta, key, weight)``: :func:`joint_loss` jitted once, the weight traced, so a sweep
    compiles one program for all its weights."""
    return jax.jit(lambda th, key, weight: joint_loss(model, data, th, key, weight))


def fit(model: hv.HumanModel, data: JointData, weight: float, evaluations: int = 150, seed: int = 0, log=print,
        loss=None):  # fmt: skip
    """Nelder-Mead on :func:`joint_loss` at ``weight`` from ``model``'s values: ``(fitted model,
    history)``, ``history`` a list of ``(evaluation, loss, seconds)``. ``loss``: a
    :func:`compiled_loss` of the same model and data to reuse (default: one made here)."""
    loss = compiled_loss(model, data) if loss is None else loss
    args = (jax.random.key(seed), jnp.float32(weight))
    x, history = minimise.nelder_mead(loss, hc.theta_of(model), evaluations, 1e-3, args, log)
    return hc.with_theta(model, jnp.asarray(x, jnp.float32)), history


def sweep(model: hv.HumanModel, data: JointData, weights=WEIGHTS, evaluations: int = 150, seed: int = 0,
          log=print) -> list[dict]:  # fmt: skip
    """One fit a weight: a row each with the weight, the fitted values, both training terms at the
    start and at the fit, the seconds and the fitted model (``"model"``)."""
    terms = jax.jit(lambda th, key: joint_terms(model, data, th, key))
    loss = compiled_loss(model, data)
    key = jax.random.key(seed)
    start = [float(t) for t in terms(hc.theta_of(model), key)]
    rows = []
    for weight in weights:
        log(f"weight {weight:g}: Nelder-Mead on the diagram's loss + {weight:g} x the percent behind constant velocity")
        fitted, history = fit(model, data, weight, evaluations, seed, log, loss)
        fd, behind = (float(t) for t in terms(hc.theta_of(fitted), key))
        rows.append({"weight": weight, "values": hc.fitted_values(fitted), "start_fd_loss": start[0],
                     "start_behind_pct": start[1], "fd_loss": fd, "behind_pct": behind,
                     "evaluations": len(history), "seconds": history[-1][2], "model": fitted})  # fmt: skip
        log(f"  weight {weight:g}: training diagram loss {start[0]:.2f} -> {fd:.2f}, ADE behind constant velocity "
            f"{start[1]:+.1f} -> {behind:+.1f} %")  # fmt: skip
    return rows


def calibrate(model: hv.HumanModel, weights=WEIGHTS, evaluations: int = 150, seed: int = 0, start_draws: int = 0,
              log=print, name: str | None = None) -> tuple[dict, dict, dict]:  # fmt: skip
    """:func:`sweep` of ``model`` over ``weights`` on its :func:`joint_data`, every fit scored by the
    validation (:func:`evaluation.humans.validation.validate`) on held-out data.

    Returns:
      ``(fit, reference, results)``: ``fit`` the record ``socialnav humans calibrate --data joint``
      writes as ``fit.json`` (the model, ``name``, default its kind; the training data; a row a
      weight with its held-out checks as ``"held_out"``; the seed, the start draws, the seconds),
      ``reference`` the validation's measures of the recorded data and ``results`` ``"w=<weight>"``
      -> the validation's result (:func:`evaluation.humans.report.write_validation` writes both).
    """
    t0 = time.perf_counter()
    data = joint_data(model, seed, start_draws=start_draws)
    log(f"{name or model.name}: fitting {', '.join(hc.FITTED[model.name])} to the runs {', '.join(hc.TRAIN_RUNS)} "
        f"and {len(data.windows.start)} ETH/UCY windows of {', '.join(TRAIN_RECORDINGS)} (constant velocity's ADE "
        f"{data.constant_velocity_ade_m:.3f} m), weights {', '.join(f'{w:g}' for w in weights)}")  # fmt: skip
    rows = sweep(model, data, weights, evaluations, seed, log)
    reference = hv.reference(log)
    results = {f"w={r['weight']:g}": hv.validate(r.pop("model"), reference, seed=seed, progress=log,
                                                 label=f"w={r['weight']:g}") for r in rows}  # fmt: skip
    for row, result in zip(rows, results.values(), strict=True):
        row["held_out"] = result["checks"]
    fit = {"model": name or model.name, "data": "joint", "fields": list(hc.FITTED[model.name]),
           "train_runs": list(hc.TRAIN_RUNS), "train_recordings": list(TRAIN_RECORDINGS),
           "train_windows": len(data.windows.start), "constant_velocity_ade_m": data.constant_velocity_ade_m,
           "start": hc.fitted_values(model), "weights": rows, "seed": seed, "start_draws": start_draws,
           "seconds": round(time.perf_counter() - t0, 1)}  # fmt: skip
    return fit, reference, results


__all__ = ["TRAIN_RECORDINGS", "WEIGHTS", "JointData", "calibrate", "compiled_loss", "fit", "joint_data",
           "joint_loss", "joint_terms", "prediction_ade", "sweep", "training_windows"]  # fmt: skip
