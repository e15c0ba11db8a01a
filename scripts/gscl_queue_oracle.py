"""The queue scene in closed loop with a perfect queue map: would GSCL's mechanism join at the tail?

    python scripts/gscl_queue_oracle.py                   # 100 variants, the three readings below
    python scripts/gscl_queue_oracle.py --variants 30 --held-out

Seed 002 Sec. 5.3.5 credits GSCL's queue behaviour (93 % social success) to the U its network
draws round a line whose goal is at its head. Before training a network to draw a different U,
this script asks whether the arena's ``gscl`` stack (the layer at 1 Hz, NavFn, pure pursuit, the
scene's stop-and-go, the people left to the social layer) joins the line at its tail when the
map is the generator's own target, drawn from the network's input map by a recogniser that knows
the rule (:func:`oracle_costs`: the people's pixels, the goal's; the head is the person nearest
the goal; a U when the goal is within 1.2 m ahead of it), so the best a network could learn.

Three readings of the map (``--readings``):

* ``graded``: the generator's map as it is (people's peak 1, the U at
  :data:`models.social_costs.QUEUE_U_COST`), placed 252 x into Nav2's graded range, as the
  ``gscl`` layer does with every model.
* ``u_top``: a hard-edged U (:func:`hard_u`: its cells at exactly 1, 0.6-1.4 m either side of
  the line from 0.6 m behind the tail to 2.2 m ahead of the head, and across the front from 1.4
  to 2.2 m ahead), the people's costs scaled to at most 0.8, still graded. (The generator's U
  has soft edges: at the 0.4 m pixels' centres a U drawn at 1 reaches only about 0.8, the
  people's own peak, so no level could tell the two apart.)
* ``u_lethal``: as ``u_top``, and network costs of at least 0.9 read as lethal (254): the top of
  the network's range as Nav2's "do not enter", the people's costs below it graded.
* ``u_lethal_inflated``: as ``u_lethal`` with the U's sides reaching in to 0.6 m less the robot's
  radius, as Nav2's inflation layer would grow lethal cells a social layer wrote before it: the
  0.4 m gap between a person in line and the U's side, which the robot's centre fits through
  when nothing inflates the U, is closed.

It prints the goal and social success (the scene's rule: join at the tail, never cut in, never
within 0.45 m) of each reading, and how often each part of the rule failed. Nothing here
changes the package: the lethal reading patches :func:`planners.gscl_layer.read_window` for this
process only.
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
from socialnav.evaluation import arena, nav_metrics
from socialnav.jaxsim.params import TIAGO_RADIUS_M
from socialnav.jaxsim.scenes.spec import load_scene, mirror
from socialnav.jaxsim.scenes.variant import sample_variants
from socialnav.models import grid
from socialnav.models import social_costs as sc
from socialnav.planners import costmap, gscl_layer
from socialnav.planners.stack import METHODS

MAX_PEOPLE = 24  # person pixels read from a map (the scene's line has at most 5)
HEAD_TO_GOAL_M = 1.2  # a goal this close to the person nearest it is "at the head"
PEOPLE_PEAK = 0.8  # u_top / u_lethal: the people's costs scaled to this
LETHAL_FROM = 0.9  # u_lethal: network costs from here up are lethal


def hard_u(hx_m, hy_m, heading_rad, tail_m, inner_m: float = 0.6):
    """(GRID, GRID) 1 on a hard-edged U round a line (head at ``hx_m, hy_m``, facing
    ``heading_rad``, ``tail_m`` long), its sides ``inner_m`` to 1.4 m from the line, open behind
    the tail; 0 elsewhere."""
    c, s = jnp.cos(heading_rad), jnp.sin(heading_rad)
    dx, dy = jnp.asarray(grid.CELL_X_M) - hx_m, jnp.asarray(grid.CELL_Y_M) - hy_m
    lx, ly = dx * c + dy * s, jnp.abs(-dx * s + dy * c)
    sides = (lx >= -tail_m - 0.6) & (lx <= 2.2) & (ly >= inner_m) & (ly <= 1.4)
    front = (lx >= 1.4) & (lx <= 2.2) & (ly <= 1.4)
    return (sides | front).astype(jnp.float32)


def oracle_costs(image, u_level: float, people_peak: float, hard: bool = False, inner_m: float = 0.6):
    """(40, 40) costs in [0, 1] of one (40, 40) uint8 input map: the people's proxemics (facing
    along the line, at the generator's speed) times ``people_peak``, and, when the goal is at the
    head of the line, a U at ``u_level`` (the generator's, or :func:`hard_u` if ``hard``); 0 on
    walls."""
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
    n = jnp.maximum(jnp.sum(valid), 1)
    mx, my = jnp.sum(jnp.where(valid, px, 0.0)) / n, jnp.sum(jnp.where(valid, py, 0.0)) / n
    phi = jnp.arctan2(gy - hy, gx - hx)  # the line faces its goal
    tail = jnp.max(jnp.where(valid, jnp.hypot(px - hx, py - hy), 0.0))
    # At the head: the goal near the head person, on the far side of the head from the line's middle.
    ahead = (gx - hx) * (hx - mx) + (gy - hy) * (hy - my) > 0
    at_head = has_goal & (to_goal[head] <= HEAD_TO_GOAL_M) & (ahead | (jnp.sum(valid) == 1))
    people = sc.people_cost(px, py, jnp.full(MAX_PEOPLE, phi), valid) * people_peak
    if hard:
        u = hard_u(hx, hy, phi, tail, inner_m) * u_level
    else:
        u = sc.queue_u_cost(hx, hy, phi, tail) * (u_level / sc.QUEUE_U_COST)
    cost = jnp.where(at_head, jnp.maximum(people, u), people)
    return jnp.where(image == grid.WALL, 0.0, cost)


def _lethal_read_window(window_costs, dx_m, dy_m):
    row, col = grid.cell_of(dx_m, dy_m)
    on = grid.inside(row, col)
    value = window_costs[jnp.clip(row, 0, grid.GRID - 1), jnp.clip(col, 0, grid.GRID - 1)]
    graded = jnp.where(value >= LETHAL_FROM, costmap.LETHAL, costmap.MAX_GRADED * jnp.clip(value, 0.0, 1.0))
    return jnp.where(on, graded, 0.0).astype(jnp.float32)


INFLATED_INNER_M = 0.6 - TIAGO_RADIUS_M  # the U's sides inflated inwards by the robot's radius

READINGS = {  # the U's level, the people's peak, costs >= LETHAL_FROM lethal, the hard U, its inner edge
    "graded": (sc.QUEUE_U_COST, 1.0, False, False, 0.6),
    "u_top": (1.0, PEOPLE_PEAK, False, True, 0.6),
    "u_lethal": (1.0, PEOPLE_PEAK, True, True, 0.6),
    "u_lethal_inflated": (1.0, PEOPLE_PEAK, True, True, INFLATED_INNER_M),
}


def run(reading: str, n: int, held_out: bool) -> dict:
    """Goal and social success (%) of the oracle-map gscl stack on ``n`` variants of the queue
    scene, and how often each part of the rule failed."""
    u_level, peak, lethal, hard, inner = READINGS[reading]
    gscl_layer.read_window = _lethal_read_window if lethal else ORIGINAL_READ_WINDOW
    spec = load_scene(SCENES_DIR / "gscl_queue.json")
    spec = mirror(spec) if held_out else spec
    setup = arena.setup_scene(spec)
    variants = jax.tree_util.tree_map(jnp.asarray, sample_variants(spec, 0, n, 0, held_out, setup.n_slots))
    predict = jax.vmap(lambda m: oracle_costs(m, u_level, peak, hard, inner))
    tr = arena.episode_function(setup, METHODS["gscl"], arena.crowd_params(), gscl_predict=predict)(variants)

    def satisfied(rule):
        return np.asarray(jax.vmap(nav_metrics.rule_satisfied, in_axes=(None, 0, 0, 0, 0, 0, 0, 0))(
            rule, tr.robot_xy, tr.reached, tr.people_xy, variants.start_xy, variants.end_xy,
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


ORIGINAL_READ_WINDOW = gscl_layer.read_window


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
