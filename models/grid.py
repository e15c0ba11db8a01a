"""The GSCL grid (seed 002 Sec. 4.1): 40 x 40 cells of 0.4 m around the robot, the input pixel
codes, and pure JAX rasterisers that the scene families and the input-map builder share.

Frame: the robot sits at the centre of the image; cell (row, col) has its centre at
``x = (col - 19.5) * 0.4``, ``y = (19.5 - row) * 0.4`` metres (x right, y up, row 0 at the top).
Everything here is a pure function of arrays, so a family's generator vmaps over keys.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

GRID = 40
CELL_M = 0.4
HALF_M = GRID * CELL_M / 2  # 8 m: the image spans [-8, 8] m on both axes

# Input pixel codes (seed 002 Sec. 4.1).
FREE, HEADING, PERSON, GOAL, WALL = 0, 25, 100, 200, 255
INPUT_CODES = (FREE, HEADING, PERSON, GOAL, WALL)

# Cell centres (GRID, GRID) in metres.
_COLS = (np.arange(GRID) - (GRID - 1) / 2) * CELL_M
CELL_X_M = np.broadcast_to(_COLS[None, :], (GRID, GRID)).astype(np.float32)
CELL_Y_M = np.broadcast_to(-_COLS[:, None], (GRID, GRID)).astype(np.float32)


def cell_of(x_m, y_m):
    """(row, col) int32 of the cell holding the point (x, y); may lie outside [0, GRID)."""
    col = jnp.floor(x_m / CELL_M + GRID / 2).astype(jnp.int32)
    row = jnp.floor(GRID / 2 - y_m / CELL_M).astype(jnp.int32)
    return row, col


def cell_of_point(x_m: float, y_m: float) -> tuple[int, int]:
    """:func:`cell_of` of one point given as Python (or numpy) floats, as Python ints: the same
    cell (tested), computed in numpy without JAX's dispatches (scene builders call it per person)."""
    col = np.floor(np.float32(x_m / CELL_M + GRID / 2))
    row = np.floor(np.float32(GRID / 2 - y_m / CELL_M))
    return int(row), int(col)


def inside(row, col):
    return (row >= 0) & (row < GRID) & (col >= 0) & (col < GRID)


def segment_distance_m(x0, y0, x1, y1):
    """(GRID, GRID) distance of every cell centre to the segment (x0, y0)-(x1, y1)."""
    dx, dy = x1 - x0, y1 - y0
    length2 = jnp.maximum(dx * dx + dy * dy, 1e-12)
    t = jnp.clip(((CELL_X_M - x0) * dx + (CELL_Y_M - y0) * dy) / length2, 0.0, 1.0)
    px, py = x0 + t * dx - CELL_X_M, y0 + t * dy - CELL_Y_M
    return jnp.sqrt(px * px + py * py)


def wall_mask(segments, valid, thickness_m: float = CELL_M):
    """(GRID, GRID) bool: cells within ``thickness_m / 2`` of any valid wall segment.

    Args:
      segments: (K, 4) x0, y0, x1, y1 in metres; valid: (K,) bool (padding segments are off).
    """
    d = jax.vmap(segment_distance_m)(*segments.T)  # (K, GRID, GRID)
    return jnp.any((d <= thickness_m / 2 + 1e-6) & valid[:, None, None], axis=0)


def _offgrid(row, col, on):
    """Indices that ``.at[...].set(mode="drop")`` drops when ``on`` is False (negative ones would wrap)."""
    return jnp.where(on, row, GRID), jnp.where(on, col, GRID)


def snap_to_cell(x_m, y_m):
    """The centre of the cell holding (x, y): where the input map shows a thing at (x, y)."""
    return (jnp.floor(x_m / CELL_M) + 0.5) * CELL_M, (jnp.floor(y_m / CELL_M) + 0.5) * CELL_M


def quantise_heading(heading_rad):
    """The heading the input map shows: the direction of the nearest of the 8 neighbours."""
    return jnp.round(heading_rad / (jnp.pi / 4)) * (jnp.pi / 4)


def snap_person(x_m: float, y_m: float, heading_rad: float) -> tuple[float, float, float]:
    """One person's drawn cell centre and heading (:func:`snap_to_cell`, :func:`quantise_heading`)
    as Python floats, in numpy's float32: the same bits as those functions on float32 scalars
    (tested), without three JAX dispatches a person (a scene builder placing thousands of people
    spent half its time in them)."""
    cell, octant = np.float32(CELL_M), np.float32(np.pi / 4)
    x, y, h = np.float32(x_m), np.float32(y_m), np.float32(heading_rad)
    snap = lambda v: (np.floor(v / cell) + np.float32(0.5)) * cell
    return float(snap(x)), float(snap(y)), float(np.round(h / octant) * octant)


def heading_offset(heading_rad):
    """(drow, dcol) of the 8-neighbour closest to the heading direction."""
    k = jnp.round(heading_rad / (jnp.pi / 4))
    a = k * (jnp.pi / 4)
    return (-jnp.round(jnp.sin(a))).astype(jnp.int32), jnp.round(jnp.cos(a)).astype(jnp.int32)


def draw_people(image, x_m, y_m, heading_rad, valid):
    """Write each valid person as a PERSON pixel and a HEADING pixel next to it, towards the heading.

    People off the grid are skipped; a heading pixel never overwrites a person (people are
    written last).
    """
    row, col = cell_of(x_m, y_m)
    drow, dcol = heading_offset(heading_rad)
    on = valid & inside(row, col)
    h_on = on & inside(row + drow, col + dcol)
    image = image.at[_offgrid(row + drow, col + dcol, h_on)].set(HEADING, mode="drop")
    return image.at[_offgrid(row, col, on)].set(PERSON, mode="drop")


def draw_goal(image, x_m, y_m):
    """Write the goal pixel (skipped when the goal is off the grid)."""
    row, col = cell_of(x_m, y_m)
    return image.at[_offgrid(row, col, inside(row, col))].set(GOAL, mode="drop")
