"""The two minimisers the human-model calibrations share (:mod:`evaluation.humans.calibration`,
:mod:`evaluation.humans.trajectory_calibration`): Adam (optax) through a loss's gradient, and
Nelder-Mead (scipy) on its value as the check that the gradient finds what a search finds.

Both take a loss of the log-parameters ``theta`` and return the best ``theta`` seen with a
history of ``(step, loss, seconds)``, so the two curves compare.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import jax
import jax.numpy as jnp
import numpy as np
import optax

from socialnav.common.progress import time_left


class FitTooLarge(ValueError):
    """A fit needs more memory at once than the machine has available."""


def held_bytes(compiled) -> int | None:
    """XLA's count of the buffers the compiled program ``compiled`` holds at once (its arguments,
    outputs and temporaries); None where XLA gives none."""
    stats = compiled.memory_analysis()
    if stats is None:
        return None
    return stats.temp_size_in_bytes + stats.argument_size_in_bytes + stats.output_size_in_bytes


def value_and_grad(loss: Callable, forward: bool = False) -> Callable:
    """``jit``-ed ``(theta, *args) -> (loss, d loss / d theta)``. ``forward``: by forward mode
    (one tangent a parameter), for a loss whose rollout holds a loop of unknown length that
    reverse mode cannot run through (ORCA's fallback); one rollout gives the value and tangents."""
    if not forward:
        return jax.jit(jax.value_and_grad(loss))
    tangents = jax.jacfwd(lambda theta, *args: (loss(theta, *args),) * 2, has_aux=True)
    return jax.jit(lambda theta, *args: tangents(theta, *args)[::-1])


def adam(loss_and_grad: Callable, theta, steps: int, optimizer: optax.GradientTransformation, args=(),
         log=print, what: str = "loss {:.3f}", on_best: Callable | None = None):  # fmt: skip
    """``steps`` updates of ``optimizer`` from ``theta`` on ``loss_and_grad(theta, *args)``:
    ``(best theta, history)``; ``what`` formats the loss in the progress lines. A gradient that is
    not finite (NaN or infinite: a rollout whose derivative breaks, as the power law's can) stops
    the descent there, said in the log; the best ``theta`` so far is returned. ``on_best(theta,
    loss, steps done, seconds)`` is called at each new best (to save it as the fit goes)."""
    state = optimizer.init(theta)
    history, t0 = [], time.perf_counter()
    best = (np.inf, theta)
    for k in range(steps):
        value, grad = loss_and_grad(theta, *args)
        value = float(value)
        history.append((k, value, time.perf_counter() - t0))
        if value < best[0]:
            best = (value, theta)
            if on_best is not None:
                on_best(theta, value, k + 1, history[-1][2])
        if k % 10 == 0 or k == steps - 1:
            left = time_left(history, steps)
            log(f"  gradient step {k}: {what.format(value)} ({time.perf_counter() - t0:.0f} s{left})")
        if not all(bool(jnp.all(jnp.isfinite(g))) for g in jax.tree.leaves(grad)):
            log(f"  gradient step {k}: the gradient is not finite; the descent stops here")
            break
        updates, state = optimizer.update(grad, state)
        theta = optax.apply_updates(theta, updates)
    return best[1], history


def nelder_mead(loss: Callable, theta, max_evaluations: int, fatol: float, args=(), log=print,
                what: str = "loss {:.3f}", on_best: Callable | None = None):  # fmt: skip
    """Nelder-Mead on ``loss(theta, *args)`` from ``theta``: ``(theta found, history)``. The first
    simplex lies 30 % away in each log-parameter (scipy's default step is 5 % of a value, and
    0.00025 of a zero: a log-parameter of 1 would start on a point). ``on_best`` as
    :func:`adam`'s, with the evaluations done."""
    from scipy.optimize import minimize

    history, t0 = [], time.perf_counter()
    best = [np.inf]  # the lowest loss so far

    def f(x):
        theta = jnp.asarray(x, jnp.float32)
        value = float(loss(theta, *args))
        history.append((len(history), value, time.perf_counter() - t0))
        if value < best[0]:
            best[0] = value
            if on_best is not None:
                on_best(theta, value, len(history), history[-1][2])
        if len(history) % 20 == 0:
            left = time_left(history, max_evaluations, "at most ")  # the search may stop before its last
            log(f"  Nelder-Mead evaluation {len(history)}: {what.format(best[0])} ({history[-1][2]:.0f} s{left})")
        return value

    x0 = np.asarray(theta, float)
    simplex = np.vstack([x0, x0 + 0.3 * np.eye(len(x0))])
    options = {"maxfev": max_evaluations, "xatol": 1e-3, "fatol": fatol, "initial_simplex": simplex}
    return minimize(f, x0, method="Nelder-Mead", options=options).x, history
