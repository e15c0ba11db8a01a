"""What maximum-entropy IRL can learn of GSCL's rules at best: a free cost grid fitted to each rule-suite map.

    python scripts/irl_rule_oracle.py                                  # tau 2 4 8 x 4 paths / every cell
    python scripts/irl_rule_oracle.py --temperature 8 --demos cells --scenes 20
    python scripts/irl_rule_oracle.py --crossing --scenes 20          # do the exact plans cross the queue's U?
    python scripts/irl_rule_oracle.py --demos cells --temperature 2 --reading graded layer   # the U read as lethal

Issue 36 trains the U-Net from exact plans on the generator's maps and finds the held-out rule
suite (``socialnav gscl rules``) far below the maps-trained model. Is that the network, the
training, or the likelihood itself? This script takes the network out: for each map of the suite's
cases (``--scenes`` scenes of each kind from the suite's own seed), demonstrations are planned
exactly on the case's **expected** map (the rule's own costs: the best a generator could draw), and
a free cost grid (the sigmoid of one parameter per cell, starting at the U-Net's initial 0.05) is
fitted to them alone by Adam through the soft planner (planners.learning.irl), as the paths objective
does. The fitted maps are then scored by the suite's own test (models.rules.score): a case passes
when the fitted map keeps half of what the rule adds.

Demonstrations (``--demos``):

* ``paths``: ``--paths-per-map`` exact plans to the map's goal (the first from the robot's cell),
  what ``socialnav gscl train --objective paths`` plans on each map;
* ``cells``: the exact planner's move out of every free cell (planners.learning.irl.policy_demonstration).

Readings (``--reading``, planners.learning.irl.traversal_per_m), how both the expected maps (for the exact
demonstrations) and the fitted grids (in the soft planner) are priced: ``graded``, every cost on
NavFn's graded scale, the queue's U at 1 five times a free cell; ``layer``, as the GSCL layer
reads a network's costs, the U lethal (no demonstration enters it) and the fitted grid able to
learn a lethal level, scored as the layer reads it (:func:`as_read`).

The printed table is the pass share per (scene, rule) for each setting: an upper bound of what
the likelihood identifies on one scene with unlimited capacity (a network shares its capacity
across scenes, which can help where a rule is seen in other scenes and hurt everywhere else).
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent))

import jax
import jax.numpy as jnp
import numpy as np
import optax

from socialnav.cli.argtypes import positive_int
from socialnav.models import grid, rules
from socialnav.models.config import MAX_PATH_TEMPERATURE, READINGS
from socialnav.models.social_costs import FORBIDDEN, FORBIDDEN_FROM, GRADED_TOP
from socialnav.planners.global_planners import grid_planner
from socialnav.planners.learning import irl

INITIAL_LOGIT = -3.0  # the U-Net's output bias at the start (models.unet: sigmoid(-3) = 0.05)


def fit(maps, demos, temperature: float, steps: int, learning_rate: float = 0.1, reading: str = "graded"):
    """Free cost grids (M, 40, 40) fitted to demonstrations on maps (M, 40, 40) by Adam, priced by
    ``reading`` (planners.learning.irl.traversal_per_m): the grids and the final mean NLL."""

    def loss(theta):
        return jnp.mean(irl.batch_nll(jax.nn.sigmoid(theta), maps, demos, temperature, reading=reading))

    opt = optax.adam(learning_rate)

    @jax.jit
    def run(theta):
        def step(carry, _):
            theta, state = carry
            value, grad = jax.value_and_grad(loss)(theta)
            updates, state = opt.update(grad, state)
            return (optax.apply_updates(theta, updates), state), value

        (theta, _), values = jax.lax.scan(step, (theta, opt.init(theta)), None, length=steps)
        return jax.nn.sigmoid(theta), values[-1]

    return run(jnp.full(maps.shape, INITIAL_LOGIT, jnp.float32))


def demonstrations(kind: str, key, maps, expected, paths_per_map: int, reading: str = "graded"):
    keys = jax.random.split(key, len(maps))
    if kind == "cells":
        return jax.jit(jax.vmap(lambda k, m, c: irl.policy_demonstration(k, m, c, reading)))(keys, maps, expected)
    one = lambda k, m, c: irl.planned_demonstration(k, m, c, paths_per_map, reading)
    return jax.jit(jax.vmap(one))(keys, maps, expected)


def as_read(fitted, reading: str):
    """Fitted grids as the suite should score them: as they are for the ``graded`` reading (priced
    like the targets), and for ``layer`` as the GSCL layer reads them (graded up to GRADED_TOP,
    FORBIDDEN from FORBIDDEN_FROM), so that a lethal U scores as the targets' U does."""
    if reading == "graded":
        return fitted
    return np.where(fitted >= FORBIDDEN_FROM, FORBIDDEN, np.minimum(fitted, GRADED_TOP))


def crossed_share(cases, demos) -> np.ndarray:
    """(N,) the share of each case's region A (map 0) that some demonstrated move enters, with
    ``demos`` planned on the cases' maps 0."""
    moves = np.asarray(demos.moves)  # (N, K, H, W): out of each cell
    entered = np.zeros((len(cases), 40, 40))
    for k, (di, dj) in enumerate(grid_planner.moves(irl.CONNECTIVITY)):
        entered += np.roll(moves[:, k], (di, dj), axis=(1, 2))  # into the cell it lands in
    return np.array([(entered[i][c.region_a] > 0).mean() for i, c in enumerate(cases)])


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--temperature", type=float, nargs="+", default=[2.0, 4.0, 8.0])
    ap.add_argument("--demos", choices=("paths", "cells"), nargs="+", default=["paths", "cells"])
    ap.add_argument("--reading", choices=READINGS, nargs="+", default=["graded"])
    ap.add_argument("--paths-per-map", type=positive_int, default=4)
    ap.add_argument("--scenes", type=positive_int, default=10, help="scenes of each kind from the suite's seed")
    ap.add_argument("--steps", type=positive_int, default=300, help="Adam steps of the fit")
    ap.add_argument(
        "--crossing",
        action="store_true",
        help="only the queue's U (the queue_u cases' region beside the queue, goal at its head): how much of it "
        "the exact planner's moves out of every cell enter, and the fit of those moves with the U priced and "
        "with it planned as a wall (at the first --temperature), and stop",
    )
    args = ap.parse_args(argv)
    for t in args.temperature:
        if not 0 < t < MAX_PATH_TEMPERATURE:
            ap.error(f"--temperature: {t} is not in (0, {MAX_PATH_TEMPERATURE:.2f}) (the soft-min diverges)")

    cases = rules.build_suite(args.scenes)
    if args.crossing:
        queue = [c for c in cases if c.rule == "queue_u"]
        images = np.stack([c.images for c in queue]).reshape(-1, 40, 40)  # each case's maps 0 and 1
        expected = np.stack([c.expected for c in queue]).reshape(-1, 40, 40)
        priced = demonstrations("cells", jax.random.key(0), jnp.asarray(images), jnp.asarray(expected), 1)
        share = crossed_share(queue, jax.tree.map(lambda a: a[::2], priced))
        level = np.mean([c.expected[0][c.region_a].mean() for c in queue])
        print(
            f"{len(queue)} queue_u cases, the U costing {level:.2f} there: exact moves enter {share.mean():.2f} of "
            f"its cells on average; none in {int((share == 0).sum())} cases"
        )
        # Would demonstrations that never cross it teach the U? Plan them with the U as a wall (as
        # the GSCL layer reads a forbidden cost), fit on the maps as the network sees them.
        # Or read as the layer reads it, lethal in the demonstrations and learnable as lethal.
        lethal = np.where(expected >= FORBIDDEN_FROM, grid.WALL, images).astype(np.uint8)
        walled = demonstrations("cells", jax.random.key(0), jnp.asarray(lethal), jnp.asarray(expected), 1)
        layer = demonstrations("cells", jax.random.key(0), jnp.asarray(images), jnp.asarray(expected), 1, "layer")
        for name, demos, reading in (
            ("priced as the soft planner prices it", priced, "graded"),
            ("a wall", walled, "graded"),
            ("lethal as the layer reads it, and learnt so", layer, "layer"),
        ):
            fitted, _ = fit(jnp.asarray(images), demos, args.temperature[0], args.steps, reading=reading)
            fitted = as_read(np.asarray(fitted), reading)
            report = rules.score(fitted.reshape(len(queue), 2, 40, 40), queue)
            checks = ", ".join(
                f"{k} {100 * v['pass_share']:.0f} % (contrast {v['contrast']:.2f} of {v['expected_contrast']:.2f})"
                for k, v in report["by_check"].items()
            )
            print(f"every cell's move, the U {name}, tau {args.temperature[0]:g}: {checks}")
        return
    images = np.stack([c.images for c in cases]).reshape(-1, 40, 40)
    expected = np.stack([c.expected for c in cases]).reshape(-1, 40, 40)
    maps, targets = jnp.asarray(images), jnp.asarray(expected)
    print(f"{len(cases)} cases ({len(maps)} maps), {args.steps} Adam steps per fit, {jax.devices()[0].platform}")

    results = {"initial": rules.score(np.full((len(cases), 2, 40, 40), 0.05, np.float32), cases)}
    for kind in args.demos:
        for reading in args.reading:
            demos = demonstrations(kind, jax.random.key(0), maps, targets, args.paths_per_map, reading)
            for t in args.temperature:
                t0 = time.perf_counter()
                fitted, nll = fit(maps, demos, t, args.steps, reading=reading)
                fitted = as_read(np.asarray(fitted), reading).reshape(len(cases), 2, 40, 40)
                name = f"{kind} tau {t:g}" + (f" {reading}" if len(args.reading) > 1 else "")
                results[name] = rules.score(fitted, cases)
                print(
                    f"{name}: NLL {float(nll):.3f} per {'step' if kind == 'cells' else 'path'}, "
                    f"{time.perf_counter() - t0:.0f} s, MSE against the expected maps {results[name]['mse']:.4f}"
                )

    names = list(results)
    print("\n| check | " + " | ".join(names) + " |")
    print("|---|" + "---|" * len(names))
    for check in results["initial"]["by_check"]:
        row = [f"{100 * results[n]['by_check'][check]['pass_share']:.0f}" for n in names]
        print(f"| {check} | " + " | ".join(row) + " |")
    passing = [sum(v["pass_share"] >= rules.RULES_BAR for v in results[n]["by_check"].values()) for n in names]
    print("| checks at the bar | " + " | ".join(str(p) for p in passing) + " |")


if __name__ == "__main__":
    main()
