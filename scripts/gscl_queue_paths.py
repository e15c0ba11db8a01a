"""Where NavFn's cheapest path enters a queue whose goal is at its head, on the generator's own maps.

    python scripts/gscl_queue_paths.py                      # the generator's U as drawn (cost 0.7), and at 1.0
    python scripts/gscl_queue_paths.py --draws 100 --u 0.7 1.0 lethal

Seed 002 Sec. 5.3.5: with the goal at the head of a line, GSCL's U (high costs along both sides
and across the front, open at the tail) sends the robot to the tail. This script asks whether
the generator's target map (:func:`models.families.sample_queue`, the map the network learns to
draw, so the best a network can do) does that for the planner the arena runs: the target costs
(x 252, Nav2's graded range) over the walls inflated by the robot's radius, the people not
lethal (so a way through the line exists), NavFn from a start 2.5 m beside the line's middle to
the goal. It prints where each path first enters the line's corridor (within 0.6 m of its axis):
from the tail, from the side, or ahead of the head. ``--u``: the U's cost as drawn
(:data:`models.social_costs.QUEUE_U_COST`), a higher one up to 1, or ``lethal`` (the U's cells
impassable).
"""

from __future__ import annotations

import argparse
import collections
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent))

import jax
import jax.numpy as jnp
import numpy as np

from socialnav.jaxsim.params import TIAGO_RADIUS_M
from socialnav.models import families, grid
from socialnav.models import social_costs as sc
from socialnav.planners import costmap
from socialnav.planners.stack import METHODS, global_plan

CORRIDOR_M = 0.6  # the U's sides start this far from the line's axis
BESIDE_M = 2.5  # the start: this far to the side of the line's middle
WINDOW = costmap.GridSpec(grid.GRID, grid.GRID, grid.CELL_M, -grid.HALF_M, -grid.HALF_M)


def entry(draw: int, u: str) -> str:
    """'tail', 'side', 'front' (where the path first enters the corridor), 'no path' or 'skipped'
    (the start off the map or in a wall) for draw ``draw`` of the queue family."""
    key = jax.random.PRNGKey(draw)
    k_layout, k_goal, _ = jax.random.split(key, 3)  # as families._sample_queue splits it
    _, _, phi, valid, hx, hy, spacing = families.queue_layout(k_layout)
    image, target = families.sample_queue(key)
    ahead = jax.random.uniform(k_goal, (), minval=0.6, maxval=1.0)
    goal = jnp.stack([hx + ahead * jnp.cos(phi), hy + ahead * jnp.sin(phi)]).astype(jnp.float32)
    tail = jnp.max(jnp.where(valid, jnp.arange(valid.shape[0]), 0)) * spacing
    u_map = sc.queue_u_cost(hx, hy, phi, tail)
    if u == "lethal":
        social = jnp.where(u_map >= 0.5 * sc.QUEUE_U_COST, costmap.LETHAL, target * costmap.MAX_GRADED)
    else:  # the target is max(people's costs, U): a U raised to u is max(target, U x u / drawn)
        if not sc.QUEUE_U_COST <= float(u) <= 1.0:
            raise SystemExit(f"--u: a cost in [{sc.QUEUE_U_COST}, 1] or lethal, got {u}")
        social = jnp.maximum(target, u_map * (float(u) / sc.QUEUE_U_COST)) * costmap.MAX_GRADED
    # The image's row 0 is its top (y = +8 m); the planner's row 0 is its bottom.
    social = jnp.flipud(jnp.where(image == grid.WALL, 0.0, social))
    walls = jnp.flipud(image == grid.WALL).astype(jnp.float32)
    costs = costmap.combine_max(costmap.obstacle_layer(walls, WINDOW, TIAGO_RADIUS_M), social)
    c, s = float(jnp.cos(phi)), float(jnp.sin(phi))
    middle = np.array([float(hx) - 0.5 * float(tail) * c, float(hy) - 0.5 * float(tail) * s])
    start = middle + BESIDE_M * np.array([-s, c])
    row, col = int((start[1] + grid.HALF_M) / grid.CELL_M), int((start[0] + grid.HALF_M) / grid.CELL_M)
    if not (0 <= row < grid.GRID and 0 <= col < grid.GRID) or float(costs[row, col]) >= costmap.LETHAL:
        return "skipped"
    path, n, found = global_plan(METHODS["navfn"], costs, jnp.asarray(start, jnp.float32), goal, WINDOW, 400)
    if not bool(found):
        return "no path"
    offset = np.asarray(path)[: int(n)] - np.array([float(hx), float(hy)])
    along, across = offset @ np.array([c, s]), offset @ np.array([-s, c])
    inside = np.abs(across) < CORRIDOR_M
    if not inside.any():
        return "no path"
    first = int(np.argmax(inside))
    if along[first] < -float(tail) + 0.3:
        return "tail"
    return "front" if along[first] > 0.3 else "side"


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--draws", type=int, default=40, help="queue draws (seeds 0 .. N-1)")
    parser.add_argument("--u", nargs="+", default=[str(sc.QUEUE_U_COST), "1.0"], help="the U's cost(s), or lethal")
    args = parser.parse_args(argv)
    for u in args.u:
        counts = collections.Counter(entry(k, u) for k in range(args.draws))
        shown = ", ".join(f"{where} {counts[where]}" for where in ("tail", "side", "front", "no path", "skipped"))
        print(f"U = {u}: the path enters the line from: {shown} (of {args.draws} draws)")


if __name__ == "__main__":
    main()
