"""The queue scene in closed loop with a perfect queue map: does GSCL's mechanism join at the tail?

    python scripts/gscl_queue_oracle.py                   # 100 variants, both readings below
    python scripts/gscl_queue_oracle.py --variants 30 --held-out

Seed 002 Sec. 5.3.5 credits GSCL's queue behaviour (93 % social success) to the U its network
draws round a line whose goal is at its head. This script asks whether the arena's ``gscl`` stack
(the layer at 1 Hz, NavFn, pure pursuit, the scene's stop-and-go, the people left to the social
layer) joins the line at its tail when the map is the generator's own target, drawn from the
network's input map by a recogniser that knows the rule (:func:`oracle_costs`: the people's
pixels, the goal's; the head is the person nearest the goal, the tail the person farthest from
the head; a U when the goal is within 1.2 m ahead of the head, or near a line of one), so the
best a network could learn.

Two readings of that map (``--readings``):

* ``graded``: every cost graded, the U at the top of Nav2's graded range (252) like a person's
  own cell: the paper's single graded layer.
* ``layer``: the package's reading (:func:`planners.layers.gscl_layer.read_cost`): the U lethal and
  inflated with the walls by the actor, the graded shapes below it.

It prints the goal and social success (the scene's rule: join at the tail, never cut in, never
within 0.45 m) of each reading, and how often each part of the rule failed. The graded reading
patches :func:`planners.layers.gscl_layer.read_cost` for this process only.

Measured before the targets had a forbidden level (a graded U soft-edged at 0.7,
and hard-edged Us written into this script): graded 0 % social (held out 25 %), a hard U at 1
graded 0 % (32 %), the same U lethal 79 % (91 %), lethal and inflated 91 % (96 %).
"""

from __future__ import annotations

import argparse
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent))

import jax
import jax.numpy as jnp
import numpy as np

from socialnav.data import SCENES_DIR
from socialnav.evaluation.arena import episodes as arena
from socialnav.evaluation.arena import nav_metrics
from socialnav.jaxsim.scenes.spec import load_scene, mirror
from socialnav.jaxsim.scenes.variant import sample_variants
from socialnav.models import grid
from socialnav.models import social_costs as sc
from socialnav.planners.layers import costmap, gscl_layer
from socialnav.planners.stack import METHODS

MAX_PEOPLE = 24  # person pixels read from a map (the scene's line has at most 5)
HEAD_TO_GOAL_M = 1.2  # a goal this close to the person nearest it is "at the head"


def oracle_costs(image):
    """(40, 40) costs of one (40, 40) uint8 input map as the generator draws them
    (:mod:`models.families`): the people's proxemics (facing along the line), and, when the goal
    is at the head of the line, the U (:func:`models.social_costs.queue_u_cost` of the line from
    the tail's cell to the head's); 0 on walls."""
    flat = image.reshape(-1)
    idx = jnp.nonzero(flat == grid.PERSON, size=MAX_PEOPLE, fill_value=0)[0]
    valid = jnp.arange(MAX_PEOPLE) < jnp.sum(flat == grid.PERSON)
    cell_x, cell_y = jnp.asarray(grid.CELL_X_M).reshape(-1), jnp.asarray(grid.CELL_Y_M).reshape(-1)
    px, py = cell_x[idx], cell_y[idx]
    g = jnp.argmax(flat == grid.GOAL)
    has_goal = jnp.any(flat == grid.GOAL)
    gx, gy = cell_x[g], cell_y[g]
    to_goal = jnp.where(valid, jnp.hypot(px - gx, py - gy), jnp.inf)
    head = jnp.argmin(to_goal)
    hx, hy = px[head], py[head]
    tail = jnp.argmax(jnp.where(valid, jnp.hypot(px - hx, py - hy), -1.0))
    n = jnp.maximum(jnp.sum(valid), 1)
    mx, my = jnp.sum(jnp.where(valid, px, 0.0)) / n, jnp.sum(jnp.where(valid, py, 0.0)) / n
    # At the head: the goal near the head person, on the far side of the head from the line's middle.
    ahead = (gx - hx) * (hx - mx) + (gy - hy) * (hy - my) > 0
    one = jnp.sum(valid) == 1
    at_head = has_goal & (to_goal[head] <= HEAD_TO_GOAL_M) & (ahead | one)
    # A line of one faces its goal (the generator: its drawn heading, which here points the same way).
    phi = jnp.arctan2(gy - hy, gx - hx)
    line = sc.drawn_line(
        jnp.stack([hx, px[tail]]), jnp.stack([hy, py[tail]]), jnp.full(2, phi), jnp.stack([True, ~one])
    )
    people = sc.people_cost(px, py, jnp.full(MAX_PEOPLE, line[2]), valid)
    cost = jnp.where(at_head, jnp.maximum(people, sc.queue_u_cost(*line)), people)
    return jnp.where(image == grid.WALL, 0.0, cost)


def _graded_read_cost(value):
    return (costmap.MAX_GRADED * jnp.clip(value, 0.0, 1.0)).astype(jnp.float32)


READINGS = {"graded": _graded_read_cost, "layer": gscl_layer.read_cost}


def run(reading: str, n: int, held_out: bool) -> dict:
    """Goal and social success (%) of the oracle-map gscl stack on ``n`` variants of the queue
    scene, and how often each part of the rule failed."""
    gscl_layer.read_cost = READINGS[reading]
    spec = load_scene(SCENES_DIR / "gscl_queue.json")
    spec = mirror(spec) if held_out else spec
    setup = arena.setup_scene(spec)
    variants = jax.tree_util.tree_map(jnp.asarray, sample_variants(spec, 0, n, 0, held_out, setup.n_slots))
    predict = jax.vmap(oracle_costs)
    tr = arena.episode_function(setup, METHODS["gscl"], arena.crowd_params(), gscl_model=predict)(variants)

    def satisfied(rule):
        return np.asarray(jax.vmap(nav_metrics.rule_satisfied, in_axes=(None, 0, 0, 0, 0, 0, 0, 0))(
            rule, tr.robot_xy_m, tr.reached, tr.people_xy_m, variants.start_xy, variants.end_xy,
            tr.people_present, variants.group,
        ))  # fmt: skip

    reached = np.asarray(tr.reached[:, -1])
    parts = {r["type"]: satisfied(r) for r in spec.rule["rules"]}
    return {
        "goal": 100 * reached.mean(),
        "social": 100 * (reached & satisfied(spec.rule)).mean(),
        "cut in": 100 * (~parts["queue"]).mean(),
        "closer than 0.45 m": 100 * (~parts["min_distance"]).mean(),
    }


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--variants", type=int, default=100)
    parser.add_argument("--held-out", action="store_true", help="the mirrored, out-of-range variants")
    parser.add_argument("--readings", nargs="+", default=list(READINGS), choices=list(READINGS))
    args = parser.parse_args(argv)
    for reading in args.readings:
        rates = run(reading, args.variants, args.held_out)
        shown = ", ".join(f"{k} {v:5.1f} %" for k, v in rates.items())
        print(f"{reading:>9} ({args.variants} variants): {shown}", flush=True)


if __name__ == "__main__":
    main()
