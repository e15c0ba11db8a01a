"""Human-model parameters fitted to real pedestrians by gradient through the crowd step, with a
derivative-free search on the same loss as the check that the gradient finds what a search finds.

The loss (:func:`fd_loss`) is the fundamental diagram of the Jülich corridor runs of the
*training* split (:data:`TRAIN_RUNS`; the others, :data:`TEST_RUNS`, are never read here):
for each density bin the training runs cover, the model walks a periodic 1.8 m corridor at that
density and its mean speed along the corridor is compared with the data's, in units of the
data's standard deviation in the bin::

    loss(theta) = mean over bins of ((v_model(rho; theta) - v_data(rho)) / sd_data(rho))^2

The model's speed is measured over the last ``measured_steps`` of a run whose first
``warmup_steps`` are taken with the gradient stopped (the crowd arranges itself; a gradient
through hundreds of steps of a crowd is long, costly and chaotic): the gradient is that of the
speed the arranged crowd walks at, which for a first-order velocity model is most of it. The
parameters are fitted as logarithms (they must stay positive) with Adam (optax); Nelder-Mead
(scipy) minimises the same loss, with the warm-up included, from the same start.

The corridors are the validation's (:mod:`evaluation.humans.validation`: 1.8 m x 20 m, periodic,
the speed taken after 30 s): in a shorter one (10 m, 20 s) the velocity models, which do not
overtake a walker ahead, had not yet closed up behind the slowest, and a fit there walked 0.3 m/s
too slow at low density in the validation's. The density of a simulated corridor is its global
density (people over area); PedPy's Voronoi density of the validation is what scores the
result, on the held-out runs.

The corridors' people are drawn once (common random numbers across evaluations), placed for the
body radius of the model the fit starts from; a dense crowd starts on a lattice whose rows follow
from that radius (:func:`evaluation.humans.validation._starts`). A model whose people keep the
lanes they start in (the power law) is then fitted to that draw's arrangement as well as to its
law, and the validation, which draws for the fitted radius, may start it in other rows
(docs/humans.md, "The start of a dense corridor"). With ``start_draws`` (:func:`corridors_at`)
each bin is walked from that many more draws of its people as well, dense crowds in a disordered
packing (:func:`evaluation.humans.validation.packed_starts`: no rows to keep), and the loss is the
mean over bins and draws::

    loss(theta) = mean over bins b and draws d of ((v_model(rho_b; theta, d) - v_data(rho_b)) / sd_data(rho_b))^2

which is each draw's loss averaged: the mean of what the validation's check scores on one start,
over starts, so a fit that walks at the data's speed from one arrangement only is not rewarded for
it. The draws are simulated side by side (``vmap``): one program a bin whatever their number.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import optax

from socialnav.common.memory import USABLE_SHARE, shortfall
from socialnav.evaluation.humans import measures, minimise
from socialnav.evaluation.humans import validation as hv
from socialnav.jaxsim import humans, power_law, speed_model

TRAIN_RUNS, TEST_RUNS = hv.FD_TRAIN_RUNS, hv.FD_TEST_RUNS
# The fitted fields of each model's parameters (fitted as logarithms).
FITTED = {
    "collision_free_speed": ("time_gap_s", "neighbor_strength", "neighbor_range_m", "radius_m"),
    "anticipation": ("time_gap_s", "neighbor_strength", "neighbor_range_m", "radius_m", "anticipation_time_s"),
    "orca": ("time_horizon_s", "radius_m"),
    "steering_speed": ("time_gap_s", "neighbor_strength", "neighbor_range_m", "radius_m", "steering_max_rad"),
    "power_law": ("strength_m2ps2", "horizon_s", "relaxation_s", "radius_m"),
}
_FIELD = {"collision_free_speed": "speed", "anticipation": "anticipation", "orca": "orca", "steering_speed": "speed",
          "power_law": "power_law"}  # fmt: skip
# Models whose gradient through the crowd explodes over the measured steps: the power law's time to
# collision is not differentiable where two paths just touch, and a crowd always holds pairs near
# that, so its reverse-mode gradient grows by orders of magnitude a few steps and overflows within
# the measured steps (docs/humans.md). Their gradient is truncated to one step: each measured
# step's speed differentiated through that step alone, the state it starts from taken as given
# (truncated backpropagation through time, averaged over the measured steps).
TRUNCATED = ("power_law",)
# Models whose step holds a loop of unknown length (ORCA's fallback, :func:`jaxsim.orca._fallback`,
# a ``while_loop``): reverse mode cannot run through it, so their gradient is taken forward
# (one tangent per fitted parameter: as cheap for the few parameters fitted here).
FORWARD_MODE = ("orca",)


@dataclasses.dataclass(frozen=True)
class Corridors:
    """What the loss simulates: periodic corridors per density bin (people, desired speeds,
    their starts, fixed across evaluations: common random numbers) and the data's bins.

    ``starts``: one ``(xy0 (D, N, 2), direction (D, N), speed (D, N))`` a bin, D draws of its N
    people (the first placed as :func:`evaluation.humans.validation._starts` places them, the
    others in a disordered packing)."""

    densities: tuple[float, ...]
    speed_data: np.ndarray
    sd_data: np.ndarray
    starts: tuple
    width_m: float = 1.8
    length_m: float = 20.0
    warmup_steps: int = 300
    measured_steps: int = 50


def corridors_at(model: hv.HumanModel, densities, speed_data, sd_data, seed: int = 0, start_draws: int = 0,
                 **size) -> Corridors:  # fmt: skip
    """Corridors at ``densities`` (persons/m²) against ``speed_data`` +- ``sd_data``, people
    drawn once under ``seed``, and ``start_draws`` more times in a disordered packing
    (:func:`evaluation.humans.validation.packed_starts`; draw d from its own stream ``(seed, d)``,
    none of them the validation's) (``size``: ``width_m``, ``length_m``, ``warmup_steps``,
    ``measured_steps``)."""
    width, length = size.get("width_m", 1.8), size.get("length_m", 20.0)
    rng = np.random.default_rng(seed)
    draw_rngs = [np.random.default_rng([seed, d]) for d in range(1, start_draws + 1)]
    starts = []
    for rho in densities:
        n = people_in(rho, width, length)
        xy0 = [hv._starts(n, width, length, model.radius_m, rng)]
        speed = [hv.desired_speeds(model.crowd, n, rng)]
        for draw_rng in draw_rngs:
            xy0.append(hv.packed_starts(n, width, length, model.radius_m, draw_rng))
            speed.append(hv.desired_speeds(model.crowd, n, draw_rng))
        starts.append((jnp.asarray(np.stack(xy0), jnp.float32), jnp.ones((len(xy0), n), jnp.float32),
                       jnp.asarray(np.stack(speed), jnp.float32)))  # fmt: skip
    steps = {k: v for k, v in size.items() if k in ("warmup_steps", "measured_steps")}
    return Corridors(tuple(float(r) for r in densities), np.asarray(speed_data, float),
                     np.maximum(np.asarray(sd_data, float), 0.02), tuple(starts), width, length, **steps)  # fmt: skip


def people_in(density: float, width_m: float, length_m: float) -> int:
    """The people of a corridor at ``density`` persons/m² (at least two)."""
    return max(2, int(round(density * width_m * length_m)))


def training_bins(runs=TRAIN_RUNS):
    """The density bins the training ``runs`` cover with at least 100 frames: their densities,
    and the runs' mean speed and standard deviation there (a frame with ``density_bin``,
    ``speed_mean``, ``speed_sd``)."""
    bins = measures.binned(hv.data_fundamental_diagram(runs))
    return bins[bins["n"] >= measures.MIN_BIN_FRAMES]


def training_corridors(model: hv.HumanModel, seed: int = 0, runs=TRAIN_RUNS, start_draws: int = 0,
                       **size) -> Corridors:  # fmt: skip
    """The corridors of :func:`fd_loss` for the bins the training ``runs`` cover (with at least
    100 frames), against the runs' mean speed and standard deviation there (``start_draws``:
    :func:`corridors_at`'s)."""
    bins = training_bins(runs)
    return corridors_at(model, bins["density_bin"], bins["speed_mean"], bins["speed_sd"], seed, start_draws, **size)


def fit_bytes(model: hv.HumanModel, densities, start_draws: int = 0, gradient: bool = True, fields=None,
              **size) -> int | None:  # fmt: skip
    """What a fit's program holds at once (XLA's count of its buffers) over corridors at
    ``densities``, each walked from ``1 + start_draws`` draws of its people: with ``gradient``, the
    loss and gradient of :func:`fit_gradient` (reverse mode keeps every measured step of every draw
    for the gradient), without it the loss alone, as :func:`fit_nelder_mead` evaluates it. Compiled
    for the shapes alone, so nothing is drawn or run (``size`` as :func:`corridors_at`'s). Measured
    on the training runs' six bins: the gradient holds 1.24 GB a draw for the steering model and
    0.68 GB for the collision-free speed model, the loss alone about 0.01 GB; compiling it takes
    10-20 s here."""
    width, length = size.get("width_m", 1.8), size.get("length_m", 20.0)
    steps = {k: v for k, v in size.items() if k in ("warmup_steps", "measured_steps")}
    draws = 1 + start_draws
    shapes = tuple(
        (jax.ShapeDtypeStruct((draws, n, 2), jnp.float32),) + (jax.ShapeDtypeStruct((draws, n), jnp.float32),) * 2
        for n in (people_in(rho, width, length) for rho in densities)
    )
    ones = np.ones(len(densities))
    template = Corridors(tuple(float(r) for r in densities), ones, ones, (), width, length, **steps)

    def loss(theta, key, starts):
        corridors = dataclasses.replace(template, starts=starts)
        return fd_loss(model, corridors, theta, key, stop_warmup=gradient, fields=fields)

    program = minimise.value_and_grad(loss, forward=model.name in FORWARD_MODE) if gradient else jax.jit(loss)
    return minimise.held_bytes(program.lower(theta_of(model, fields), jax.random.key(0), shapes).compile())


def refuse_past_memory(model: hv.HumanModel, densities, start_draws: int, gradient: bool = True,
                       share: float = USABLE_SHARE, **size) -> None:  # fmt: skip
    """Raise :class:`~evaluation.humans.minimise.FitTooLarge` where a fit over ``1 + start_draws``
    draws of each corridor would hold more than ``share`` of the memory available
    (:func:`fit_bytes`; nothing is checked where the available memory is not known), naming how
    many draws fit, before any is drawn."""
    needed = fit_bytes(model, densities, start_draws, gradient, **size)
    available = None if needed is None else shortfall(needed, share)
    if available is not None:
        fits = max(0, int((1 + start_draws) * share * available / needed) - 1)
        what = "gradient fit" if gradient else "fit"
        raise minimise.FitTooLarge(
            f"a {what} of {model.name} over {1 + start_draws:,} draws of each of {len(densities)} corridors "
            f"holds about {needed / 1e9:.1f} GB at once, this machine has {available / 1e9:.1f} GB available: "
            f"about {fits:,} start draws fit"
        )


def with_theta(model: hv.HumanModel, theta, fields=None) -> hv.HumanModel:
    """``model`` with its fitted ``fields`` (default :data:`FITTED`'s) set to ``exp(theta)``."""
    fields = FITTED[model.name] if fields is None else fields
    return with_fitted(model, dict(zip(fields, jnp.exp(theta), strict=True)))


def theta_of(model: hv.HumanModel, fields=None) -> jnp.ndarray:
    """The logarithms of ``model``'s fitted ``fields`` (default :data:`FITTED`'s)."""
    params = getattr(model, _FIELD[model.name])
    fields = FITTED[model.name] if fields is None else fields
    return jnp.log(jnp.asarray([float(getattr(params, f)) for f in fields], jnp.float32))


def draw_speeds(model: hv.HumanModel, corridors: Corridors, theta, key, stop_warmup: bool = True, fields=None):
    """(bins, D) the model's mean speed along each corridor of each draw over its measured steps
    (with ``stop_warmup``, a model in :data:`TRUNCATED` differentiated one step at a time). Draw 0
    walks on the keys of ``fold_in(key, bin)``, draw d > 0 on those of ``fold_in(fold_in(key,
    bin), d)``; a single draw is walked outside ``vmap``."""
    field = hv.corridor_field(corridors.width_m, corridors.length_m)
    m = with_theta(model, theta, fields)
    truncate = stop_warmup and model.name in TRUNCATED
    n_steps = corridors.warmup_steps + corridors.measured_steps

    def walk(xy0, direction, speed, keys):
        step = hv.periodic_step(m.name, m.params, field, direction, speed, corridors.length_m)
        carry, _ = jax.lax.scan(lambda c, q: (step(c, q), None), hv.periodic_start(direction, speed, xy0),
                                keys[: corridors.warmup_steps])  # fmt: skip
        if stop_warmup:
            carry = jax.lax.stop_gradient(carry)

        def measured(c, q):
            new = step(jax.lax.stop_gradient(c) if truncate else c, q)
            return new, new[1][:, 0]

        _, vx = jax.lax.scan(measured, carry, keys[corridors.warmup_steps :])
        return jnp.mean(vx)

    speeds = []
    for k, (xy0, direction, speed) in enumerate(corridors.starts):
        base = jax.random.fold_in(key, k)
        draw_keys = [base] + [jax.random.fold_in(base, d) for d in range(1, xy0.shape[0])]
        keys = jnp.stack([jax.random.split(q, n_steps) for q in draw_keys])
        # One draw walked as itself: a batch of one is another program, whose last bits a chaotic
        # crowd (the power law's) carries into another loss.
        walked = walk(xy0[0], direction[0], speed[0], keys[0])[None] if len(draw_keys) == 1 else jax.vmap(walk)(
            xy0, direction, speed, keys)  # fmt: skip
        speeds.append(walked)
    return jnp.stack(speeds)


def mean_speeds(model: hv.HumanModel, corridors: Corridors, theta, key, stop_warmup: bool = True, fields=None):
    """(bins,) the model's mean speed along each corridor, averaged over the draws
    (:func:`draw_speeds`)."""
    return jnp.mean(draw_speeds(model, corridors, theta, key, stop_warmup, fields), axis=1)


def fd_loss(model: hv.HumanModel, corridors: Corridors, theta, key, stop_warmup: bool = True, fields=None):
    """The loss of the module's docstring (``theta``: the logarithms of ``fields``): each draw's
    loss, averaged over the draws."""
    v = draw_speeds(model, corridors, theta, key, stop_warmup, fields)
    return jnp.mean(((v - corridors.speed_data[:, None]) / corridors.sd_data[:, None]) ** 2)


def fit_gradient(
    model: hv.HumanModel,
    corridors: Corridors,
    steps: int = 80,
    learning_rate: float = 0.02,
    seed: int = 0,
    log=print,
    fields=None,
    on_best=None,
):
    """Adam on :func:`fd_loss` from ``model``'s parameters (``fields``, default :data:`FITTED`'s):
    ``(fitted model, history)``, the model at the lowest loss seen, ``history`` a list of
    ``(step, loss, seconds)``; ``on_best`` as :func:`evaluation.humans.minimise.adam`'s."""
    loss_and_grad = minimise.value_and_grad(
        lambda th, key: fd_loss(model, corridors, th, key, fields=fields), forward=model.name in FORWARD_MODE
    )
    best, history = minimise.adam(loss_and_grad, theta_of(model, fields), steps, optax.adam(learning_rate),
                                  (jax.random.key(seed),), log, on_best=on_best)  # fmt: skip
    return with_theta(model, best, fields), history


def fit_nelder_mead(
    model: hv.HumanModel,
    corridors: Corridors,
    max_evaluations: int = 250,
    seed: int = 0,
    log=print,
    fields=None,
    on_best=None,
):
    """Nelder-Mead (scipy) on :func:`fd_loss` with the warm-up's gradient not stopped (no
    gradient is taken): ``(fitted model, history)`` as :func:`fit_gradient`."""
    loss = jax.jit(lambda th, key: fd_loss(model, corridors, th, key, stop_warmup=False, fields=fields))
    x, history = minimise.nelder_mead(loss, theta_of(model, fields), max_evaluations, 1e-3,
                                      (jax.random.key(seed),), log, on_best=on_best)  # fmt: skip
    return with_theta(model, jnp.asarray(x, jnp.float32), fields), history


def calibrate(
    model: hv.HumanModel,
    corridors: Corridors,
    steps: int = 80,
    learning_rate: float = 0.02,
    evaluations: int = 250,
    seed: int = 0,
    log=print,
    fields=None,
    progress=None,
) -> tuple[dict, dict]:
    """Both fits of ``model`` to ``corridors`` (:func:`training_corridors`): Adam through the crowd
    step (:func:`fit_gradient`) and Nelder-Mead on the same loss (:func:`fit_nelder_mead`), from
    the model's own parameters (``fields``: those fitted, default :data:`FITTED`'s; the record
    holds every field of :data:`FITTED`, those not fitted as given).

    Args:
      progress: called with the record so far (``"complete": false``, each method that has a
        point with its best point yet, its loss, the steps or evaluations done and the seconds)
        at each new best, so a fit stopped before its end keeps what it found
        (``socialnav humans calibrate`` writes it as ``progress.json``; :func:`fitted_models`
        reads it as it reads a finished fit).

    Returns:
      ``(fit, histories)``: ``fit`` the record ``socialnav humans calibrate`` writes as ``fit.json``
      (the model, the runs, the densities, the loss and values at the start and of each method,
      the seed and the number of start draws, ``"complete": true``; :func:`fitted_models` reads it
      back), ``histories`` each method's ``[(step, loss, seconds), ...]`` (``"gradient"``,
      ``"nelder_mead"``).
    """
    start = float(fd_loss(model, corridors, theta_of(model, fields), jax.random.key(seed), fields=fields))
    head = {
        "model": model.name,
        "train_runs": list(TRAIN_RUNS),
        "test_runs": list(TEST_RUNS),
        "densities": list(corridors.densities),
        "start": {"values": fitted_values(model), "loss": start},
    }
    tail = {"seed": seed, "start_draws": int(corridors.starts[0][0].shape[0]) - 1}
    found = {}  # method -> its best point so far

    def saver(method: str, count: str):
        def on_best(theta, loss, done, seconds):
            values = fitted_values(with_theta(model, theta, fields))
            found[method] = {"values": values, "loss": float(loss), count: done, "seconds": seconds}
            progress({**head, **found, **tail, "complete": False})

        return None if progress is None else on_best

    by_gradient, gradient_history = fit_gradient(
        model, corridors, steps, learning_rate, seed, log, fields, saver("gradient", "steps")
    )
    by_search, search_history = fit_nelder_mead(
        model, corridors, evaluations, seed, log, fields, saver("nelder_mead", "evaluations")
    )
    fit = {
        **head,
        "gradient": {"values": fitted_values(by_gradient), "loss": min(h[1] for h in gradient_history),
                     "steps": steps, "seconds": gradient_history[-1][2]},
        "nelder_mead": {"values": fitted_values(by_search), "loss": min(h[1] for h in search_history),
                        "evaluations": len(search_history), "seconds": search_history[-1][2]},
        **tail,
        "complete": True,
    }  # fmt: skip
    return fit, {"gradient": gradient_history, "nelder_mead": search_history}


def fitted_values(model: hv.HumanModel) -> dict:
    params = getattr(model, _FIELD[model.name])
    return {f: round(float(getattr(params, f)), 4) for f in FITTED[model.name]}


FIT_METHODS = ("gradient", "nelder_mead")


def fitted_models(path, methods=FIT_METHODS) -> dict[str, hv.HumanModel]:
    """The models a fit file (``socialnav humans calibrate``'s ``fit.json`` at ``path``, a Jülich
    fit or one of a user's recording) found, one a method of ``methods``, labelled
    ``<folder>:<method>``: its model with the fitted values. An unfinished fit (its
    ``progress.json``, ``"complete": false``) gives the best point of each method that has one.
    Raises ``ValueError`` naming the file and the field where the file is not such a fit
    (:func:`evaluation.humans.fit_file.read_points`)."""
    from socialnav.evaluation.humans import fit_file
    from socialnav.evaluation.humans import trajectory_calibration as tc

    return {
        p.label: tc.with_values(named_model(p.model), list(p.values), list(p.values.values()))
        for p in fit_file.read_points(path, tuple(methods)).values()
    }


def with_fitted(model: hv.HumanModel, values: dict) -> hv.HumanModel:
    """``model`` with the fitted fields in ``values`` (field -> value) set."""
    field = _FIELD[model.name]
    return dataclasses.replace(model, **{field: getattr(model, field).replace(**values)})


def named_model(name: str) -> hv.HumanModel:
    """A human model by name, the calibrated ones (:data:`jaxsim.speed_model.CALIBRATED`,
    :data:`jaxsim.power_law.CALIBRATED`) included."""
    kind = humans.kind_of(name)
    if kind in speed_model.VELOCITY_MODELS:
        return hv.HumanModel(kind, **{_FIELD[kind]: speed_model.params_of(name)})
    if kind == "power_law":
        return hv.HumanModel(kind, power_law=power_law.params_of(name))
    return hv.HumanModel(name)


__all__ = ["FITTED", "FIT_METHODS", "TEST_RUNS", "TRAIN_RUNS", "calibrate", "fd_loss", "fit_gradient",
           "fit_nelder_mead", "fitted_models", "named_model", "speed_model", "training_corridors",
           "with_fitted"]  # fmt: skip
