"""Social costs learned from demonstrated paths: maximum-entropy IRL through the soft planner.

A cost map ``c`` (H, W) in [0, 1] (a GSCL network's output, or a free grid) prices a move on the
network's 0.4 m grid at NavFn's cell cost, as the GSCL layer's planner does
(:func:`traversal_per_m`: ``50 + 0.8 * 252 c`` per metre, walls impassable; with the "layer"
reading, as the GSCL layer reads a network's costs, the queue's U lethal). The soft-min
planner (:func:`planners.global_planners.smooth_planner.soft_potential_implicit`) at temperature ``tau`` defines a
stochastic policy ``pi(a | s) = exp(-(w(s, a) + phi(s')) / tau) / exp(-phi(s) / tau)``: maximum
entropy IRL's soft value iteration (Ziebart et al., AAAI 2008). The log-likelihood of a path
``s_0 .. s_T`` ending at the goal telescopes, because ``phi(goal) = 0``:

    -log P(path) = (C(path) - phi(s_0)) / tau

the path's cost minus the soft cost-to-go of its start, in units of the temperature; it is >= 0
(the soft-min lies below every path's cost) and 0 only when the path is the policy's certain
choice. Its gradient in the move weights is the demonstrated moves minus the soft policy's
expected moves (the implicit gradient of ``phi`` is the expected visitation, computed by the
adjoint recursion in bounded memory). Everything here is batched with ``vmap``.

A demonstration is a fixed-shape pytree (:class:`Demonstrations`): the number of times each move
is taken from each cell (K, H, W), the number of paths starting in each cell (H, W), and the
goal (one per demonstration; several paths may share it and then share one potential).

Where they come from:

* :func:`planned_demonstrations`: exact plans (:mod:`planners.global_planners.grid_planner`) on known cost maps
  (the GSCL generator's targets): the map that made them is known, so the learned one can be
  checked against it. A map with a goal pixel is planned to that goal, from the robot's cell and
  from ``paths_per_map - 1`` random free cells; a map without (the generator's families with no
  goal) gets a random free goal.
* :func:`planners.learning.tracks.track_demonstrations`: people's tracks, from a user's file or the
  arena's walkers (:func:`planners.learning.tracks.simulated_tracks`).

:class:`PathObjective` is the "paths" objective of a GSCL training run (``TrainConfig.objective``):
:func:`models.train.train` calls it with each batch, so ``models`` needs no planner import.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

from socialnav.models import grid
from socialnav.models.config import PATH_TEMPERATURE, READINGS
from socialnav.models.social_costs import FORBIDDEN_FROM, GRADED_TOP
from socialnav.planners.global_planners import grid_planner, smooth_planner
from socialnav.planners.layers.costmap import LETHAL, MAX_GRADED, NAVFN_FACTOR, NAVFN_NEUTRAL
from socialnav.planners.layers.gscl_layer import read_cost

CONNECTIVITY = 8
K = CONNECTIVITY
TEMPERATURE = PATH_TEMPERATURE  # cost units (its reason: models.config.PATH_TEMPERATURE)
ITERATIONS = 2 * (grid.GRID + grid.GRID)  # Jacobi steps of the soft recursion and of its adjoint
CEILING = smooth_planner.BLOCKED * grid.CELL_M * 2 * grid.GRID  # the potential of an unreachable cell
_MOVE_INDEX = {m: k for k, m in enumerate(grid_planner.moves(CONNECTIVITY))}
# (di + 1) * 3 + (dj + 1) -> move index (-1: no move)
_MOVE_LOOKUP = np.array([_MOVE_INDEX.get((di, dj), -1) for di in (-1, 0, 1) for dj in (-1, 0, 1)], np.int32)
# The soft planner's price per metre of a cell the "layer" reading makes lethal, on top of the
# graded top: one 0.4 m cell costs 2,000 more, the price of 40 m of free space, so that wherever
# crossing it saves less than 20 m of free space the soft policy's odds of crossing are below
# e^-500 at the default temperature; finite, so that the ramp in traversal_per_m has a gradient.
LETHAL_PER_M = 5000.0
LETHAL_RAMP = 0.05  # network cost units above FORBIDDEN_FROM over which the soft price reaches it


@struct.dataclass
class Demonstrations:
    """Demonstrated paths on one map (leading batch axes allowed on every field).

    Attributes:
      moves: (K, H, W) float32, how many times the move ``k`` (:func:`planners.global_planners.grid_planner.moves`
        order) is taken out of each cell.
      starts: (H, W) float32, how many paths start in each cell.
      goal_ij: (2,) int32, the goal cell every path ends in.
      n_paths: () float32, the number of paths (0: nothing demonstrated; the loss ignores it).
    """

    moves: jnp.ndarray
    starts: jnp.ndarray
    goal_ij: jnp.ndarray
    n_paths: jnp.ndarray


def traversal_per_m(maps, costs, impassable: float = smooth_planner.BLOCKED, reading: str = "graded"):
    """(..., H, W) cost per metre of entering a cell, ``impassable`` on the input map's walls
    (:data:`planners.global_planners.smooth_planner.BLOCKED` for the soft planner, ``inf`` for the exact one).

    ``reading`` (:data:`READINGS`) says how a cost ``c`` in [0, 1] is priced: ``"graded"``,
    NavFn's ``50 + 0.8 * 252 c``; ``"layer"``, ``50 + 0.8 x`` with ``x`` the GSCL layer's Nav2
    cost (:func:`planners.layers.gscl_layer.read_cost`: ``252 c / GRADED_TOP`` clipped, lethal from
    ``FORBIDDEN_FROM``). Lethal is ``impassable`` for the exact planner (``impassable`` inf).

    The soft planner needs a gradient all the way up, so for it the graded slope goes on past
    ``GRADED_TOP`` to ``FORBIDDEN_FROM`` (at most 17 % above the graded top, where the layer reads
    the top), and :data:`LETHAL_PER_M` is added by a linear ramp over the :data:`LETHAL_RAMP`
    above ``FORBIDDEN_FROM``. A cost the likelihood pushes past the graded top climbs at the
    graded slope, and is priced prohibitively only once the layer reads it lethal: a ramp below
    the threshold would stop it where the soft planner already avoids it but the layer reads
    the graded top (``scripts/irl_rule_oracle.py --reading layer``: with a ramp from
    ``GRADED_TOP`` to ``FORBIDDEN_FROM`` no queue case passed).
    """
    costs, walls = jnp.asarray(costs), jnp.asarray(maps) == grid.WALL
    if reading == "graded":
        return jnp.where(walls, impassable, NAVFN_NEUTRAL + NAVFN_FACTOR * MAX_GRADED * costs)
    if reading != "layer":
        raise ValueError(f"reading must be one of {READINGS}, got {reading!r}")
    if np.isinf(impassable):
        nav2 = read_cost(costs)
        return jnp.where(walls | (nav2 >= LETHAL), impassable, NAVFN_NEUTRAL + NAVFN_FACTOR * nav2)
    rising = NAVFN_NEUTRAL + NAVFN_FACTOR * MAX_GRADED * jnp.clip(costs, 0.0, FORBIDDEN_FROM) / GRADED_TOP
    lethal = LETHAL_PER_M * jnp.clip((costs - FORBIDDEN_FROM) / LETHAL_RAMP, 0.0, 1.0)
    return jnp.where(walls, impassable, rising + lethal)


def path_moves(path_ij, shape=(grid.GRID, grid.GRID)):
    """(K, H, W) move counts of one path of cells (L, 2), consecutive cells 8-neighbours or equal
    (repeats, e.g. after the goal, count nothing)."""
    path_ij = jnp.asarray(path_ij, jnp.int32)
    step = path_ij[1:] - path_ij[:-1]
    k = jnp.asarray(_MOVE_LOOKUP)[(step[:, 0] + 1) * 3 + (step[:, 1] + 1)]
    moved = k >= 0
    counts = jnp.zeros((K, *shape), jnp.float32)
    return counts.at[jnp.maximum(k, 0), path_ij[:-1, 0], path_ij[:-1, 1]].add(moved.astype(jnp.float32))


def path_nll(
    costs,
    maps,
    demo: Demonstrations,
    temperature: float = TEMPERATURE,
    iterations: int = ITERATIONS,
    reading: str = "graded",
):
    """Mean negative log-likelihood per path of one map's demonstrations under the soft policy of
    ``costs`` (H, W) in [0, 1] on input map ``maps`` (H, W), priced by ``reading``
    (:func:`traversal_per_m`): ``(sum of the paths' costs - sum of phi at their starts) / (tau
    n_paths)``; 0 when ``n_paths`` is 0."""
    weights = smooth_planner.soft_weights(traversal_per_m(maps, costs, reading=reading), grid.CELL_M, CONNECTIVITY)
    phi = smooth_planner.soft_potential_implicit(weights, demo.goal_ij, temperature, iterations, CEILING, CONNECTIVITY)
    nll = (jnp.sum(demo.moves * weights) - jnp.sum(demo.starts * phi)) / temperature
    return jnp.where(demo.n_paths > 0, nll / jnp.maximum(demo.n_paths, 1.0), 0.0)


def batch_nll(
    costs,
    maps,
    demos: Demonstrations,
    temperature: float = TEMPERATURE,
    iterations: int = ITERATIONS,
    reading: str = "graded",
):
    """(B,) :func:`path_nll` of a batch: costs and maps (B, H, W), demonstrations with axis B."""
    return jax.vmap(lambda c, m, d: path_nll(c, m, d, temperature, iterations, reading))(costs, maps, demos)


def _goal_cell(maps):
    """(row, col) of the map's goal pixel and whether it has one."""
    flat = (maps == grid.GOAL).reshape(-1)
    index = jnp.argmax(flat)
    return jnp.stack([index // grid.GRID, index % grid.GRID]).astype(jnp.int32), flat[index]


def _random_cell(key, allowed):
    """A cell drawn uniformly from the True cells of ``allowed`` (H, W) (cell (0, 0) if none)."""
    logits = jnp.where(allowed.reshape(-1), 0.0, -jnp.inf)
    index = jax.random.categorical(key, jnp.where(jnp.any(allowed), logits, 0.0))
    return jnp.stack([index // allowed.shape[1], index % allowed.shape[1]]).astype(jnp.int32)


def _exact_potential(goal_key, maps, target_costs, reading: str = "graded"):
    """What both demonstrations plan on one map: ``(reach, goal, has_goal, exact, phi)``, the cells
    a demonstration may start in (H, W: free, reaching the goal, not the goal), the goal (the
    map's goal pixel, else a free cell drawn with ``goal_key``) and whether the map has one, the
    exact traversal costs (the targets priced by ``reading``) and their potential."""
    maps = jnp.asarray(maps)
    free = (maps != grid.WALL) & (maps != grid.PERSON) & (maps != grid.HEADING)
    goal_pixel, has_goal = _goal_cell(maps)
    goal = jnp.where(has_goal, goal_pixel, _random_cell(goal_key, free))
    exact = traversal_per_m(maps, target_costs, jnp.inf, reading)
    phi = grid_planner.potential(exact, goal, grid.CELL_M, CONNECTIVITY)
    rows, cols = jnp.arange(grid.GRID)[:, None], jnp.arange(grid.GRID)[None, :]
    reach = jnp.isfinite(phi) & free & ~((rows == goal[0]) & (cols == goal[1]))
    return reach, goal, has_goal, exact, phi


def planned_demonstration(key, maps, target_costs, paths_per_map: int = 4, reading: str = "graded") -> Demonstrations:
    """Exact plans on one known cost map priced by ``reading`` (:func:`traversal_per_m`):
    ``paths_per_map`` paths to the map's goal pixel (the first from the robot's cell, the others
    from random free cells that reach the goal), or, on a map without a goal pixel, to a random
    free cell. Jit and vmap it."""
    k_goal, k_starts = jax.random.split(key)
    reach, goal, has_goal, exact, phi = _exact_potential(k_goal, maps, target_costs, reading)
    robot = jnp.stack(grid.cell_of(0.0, 0.0)).astype(jnp.int32)
    others = jax.vmap(lambda k: _random_cell(k, reach))(jax.random.split(k_starts, paths_per_map))
    starts = others.at[0].set(jnp.where(has_goal & reach[robot[0], robot[1]], robot, others[0]))
    paths, _, reached = jax.vmap(lambda s: grid_planner.descend(phi, exact, s, goal, grid.CELL_M, CONNECTIVITY))(starts)
    ok = reached & reach[starts[:, 0], starts[:, 1]]
    moves = jnp.sum(jax.vmap(path_moves)(paths) * ok[:, None, None, None], axis=0)
    start_counts = jnp.zeros((grid.GRID, grid.GRID), jnp.float32).at[starts[:, 0], starts[:, 1]].add(ok)
    return Demonstrations(moves, start_counts, goal, jnp.sum(ok).astype(jnp.float32))


def policy_demonstration(key, maps, target_costs, reading: str = "graded") -> Demonstrations:
    """The exact planner's move out of **every** free cell that reaches the goal, each counted once:
    the demonstrations of :func:`planned_demonstration` from every start, each step once.

    The goal is chosen as there (the map's goal pixel, or a random free cell). The negative
    log-likelihood of one step ``s -> s'`` is ``(w(s, s') + phi(s') - phi(s)) / tau``, so the
    steps go into :class:`Demonstrations` as move counts and as ``starts`` of +1 at ``s`` and -1 at
    ``s'`` (the sum telescopes as a path's does); ``n_paths`` counts the steps, so
    :func:`path_nll` is the mean NLL per step. A path constrains the costs only along itself and
    where the soft policy might leave it; every cell's move constrains them where no plan goes,
    e.g. how a robot on the wrong side of a hallway gets back to the right one. The targets are
    priced by ``reading`` (:func:`traversal_per_m`; with ``"layer"`` no move enters the queue's U,
    as the GSCL layer's planner never does). Jit and vmap it.
    """
    reach, goal, _, exact, phi = _exact_potential(key, maps, target_costs, reading)
    offsets = grid_planner.moves(CONNECTIVITY)
    weights = grid_planner.move_costs(exact, grid.CELL_M, CONNECTIVITY)
    value = jnp.stack([weights[m] + grid_planner._shift(phi, *m, jnp.inf) for m in offsets])  # (K, H, W)
    n = grid.GRID
    k = jnp.argmin(value, axis=0)  # (H, W) the exact planner's move (its first on a tie, as descend takes)
    rows, cols = jnp.arange(n)[:, None], jnp.arange(n)[None, :]
    ok = reach & jnp.isfinite(jnp.min(value, axis=0))
    moves = (jax.nn.one_hot(k, K, axis=0) * ok).astype(jnp.float32)
    step = jnp.asarray(offsets, jnp.int32)[k]  # (H, W, 2)
    ni, nj = jnp.clip(rows + step[..., 0], 0, n - 1), jnp.clip(cols + step[..., 1], 0, n - 1)
    okf = ok.astype(jnp.float32)
    starts = okf - jnp.zeros((n, n), jnp.float32).at[ni, nj].add(okf)
    return Demonstrations(moves, starts, goal, jnp.sum(okf))


def planned_demonstrations(key, maps, target_costs, paths_per_map: int = 4, reading: str = "graded") -> Demonstrations:
    """:func:`planned_demonstration` of a batch: maps and targets (B, H, W), one key per map."""
    keys = jax.random.split(key, len(maps))
    one = lambda k, m, c: planned_demonstration(k, m, c, paths_per_map, reading)
    return jax.vmap(one)(keys, maps, target_costs)


def exact_path_cost(true_costs, maps, plan_costs, start_ij, goal_ij):
    """The cost under ``true_costs`` of the exact plan on ``plan_costs`` from ``start_ij`` to
    ``goal_ij`` (one map, (H, W) each), and the optimum under ``true_costs``: ``(cost, optimum)``
    (``inf`` when the plan does not reach the goal)."""
    true_t = traversal_per_m(maps, true_costs, jnp.inf)
    plan_t = traversal_per_m(maps, plan_costs, jnp.inf)
    planned = grid_planner.plan(plan_t, start_ij, goal_ij, grid.CELL_M, CONNECTIVITY)
    weights = jnp.stack(list(grid_planner.move_costs(true_t, grid.CELL_M, CONNECTIVITY).values()))
    moves = path_moves(planned.path_ij, plan_t.shape)
    cost = jnp.where(planned.reached, jnp.sum(moves * jnp.where(moves > 0, weights, 0.0)), jnp.inf)
    optimum = grid_planner.plan(true_t, start_ij, goal_ij, grid.CELL_M, CONNECTIVITY).cost
    return cost, optimum


@dataclasses.dataclass(frozen=True)
class PathObjective:
    """The "paths" training objective of the GSCL U-Net (``TrainConfig.objective == "paths"``).

    :meth:`prepare` plans the demonstrations of a batch on its target maps (outside the
    gradient); :meth:`loss` is the per-sample negative log-likelihood of a batch's predicted
    costs. Both jit; :func:`models.train.train` takes an instance.
    """

    temperature: float = TEMPERATURE
    paths_per_map: int = 4
    iterations: int = ITERATIONS
    demonstrations: str = "paths"  # or "cells" (models.config.DEMONSTRATIONS)
    reading: str = "graded"  # or "layer" (models.config.READINGS; traversal_per_m)

    @classmethod
    def of(cls, config) -> PathObjective:
        """The objective of a :class:`models.config.TrainConfig`."""
        return cls(
            float(config.temperature), int(config.paths_per_map), ITERATIONS, config.demonstrations, config.reading
        )

    def prepare(self, key, maps, target_costs) -> Demonstrations:
        """(B,) demonstrations planned on a batch's target maps (B, H, W): :func:`planned_demonstrations`,
        or with ``demonstrations == "cells"`` :func:`policy_demonstration` of each map."""
        if self.demonstrations == "cells":
            one = lambda k, m, c: policy_demonstration(k, m, c, self.reading)
            return jax.vmap(one)(jax.random.split(key, len(maps)), maps, target_costs)
        return planned_demonstrations(key, maps, target_costs, self.paths_per_map, self.reading)

    def loss(self, costs, maps, demos: Demonstrations):
        """(B,) mean negative log-likelihood per path of each map's demonstrations."""
        return batch_nll(costs, maps, demos, self.temperature, self.iterations, self.reading)
