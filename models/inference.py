"""Using a trained GSCL U-Net (seed 002 Sec. 4.3): input maps from a robot's world, cost maps out.

* :func:`input_map` builds the network's 40 x 40 input around the robot from an occupancy grid
  (cells above 0.6 become walls, 255), people (100, with a heading pixel 25) and the goal (200),
  as the paper's Sec. 4.3 does. Pure JAX: jit it, vmap it over robots or time steps.
* :class:`SocialCostModel` loads a training run's checkpoint and maps a batch of input maps to
  cost maps in [0, 1] with one jitted function (``model(maps)``), or hands out that function
  (``model.function``) for use inside a planner's own ``jit``.
* :func:`rotation_averaged` turns a prediction function into its average over the four 90-degree
  rotations of the input, which is exactly equivariant to them.
"""

from __future__ import annotations

import functools
import hashlib
import json
import math
import pathlib

import jax
import jax.numpy as jnp
import numpy as np
from flax import nnx

from socialnav.data import DATA_DIR
from socialnav.models import grid
from socialnav.models.social_costs import GRADED_TOP

OCCUPIED_ABOVE = 0.6  # the paper's threshold on occupancy values


def _check_finite(**arrays) -> None:
    """ValueError naming the first argument holding NaN or inf (arguments traced under ``jit``
    cannot be checked and are skipped: there a person at NaN is simply not drawn)."""
    for name, value in arrays.items():
        if isinstance(value, jax.core.Tracer):
            continue
        array = np.asarray(value, np.float64)
        if not np.isfinite(array).all():
            raise ValueError(f"{name} holds NaN or inf at {np.argwhere(~np.isfinite(array))[0].tolist()}")


def _check_input_shapes(
    occupancy, resolution_m, origin_xy_m, robot_xy_m, people_xy_m, people_heading_rad, goal_xy_m, people_valid
) -> None:
    """ValueError naming the argument of :func:`input_map` whose shape (static, so checked under
    ``jit`` too) or resolution is wrong: a resolution of 0 divided by zero, a negative one erased
    the walls, a heading count other than the people count was broadcast, a 3-D occupancy failed
    in a broadcast."""
    if not isinstance(resolution_m, jax.core.Tracer):
        try:
            value = float(resolution_m)
        except (TypeError, ValueError):
            raise ValueError(f"resolution_m must be a number of metres, got {resolution_m!r}") from None
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"resolution_m must be a positive number of metres, got {resolution_m!r}")
    shape = lambda a: tuple(np.shape(a))
    if len(shape(occupancy)) != 2:
        raise ValueError(f"occupancy must be a 2-D (H, W) grid, got shape {shape(occupancy)}")
    for name, value in (("origin_xy_m", origin_xy_m), ("robot_xy_m", robot_xy_m), ("goal_xy_m", goal_xy_m)):
        if shape(value) != (2,):
            raise ValueError(f"{name} must be (x, y), got shape {shape(value)}")
    people = shape(people_xy_m)
    if not ((len(people) == 2 and people[1] == 2) or people == (0,)):
        raise ValueError(f"people_xy_m must be (P, 2), got shape {people}")
    n = people[0] if len(people) == 2 else 0
    if shape(people_heading_rad) != (n,):
        raise ValueError(
            f"people_heading_rad must be ({n},), one per person in people_xy_m, got shape {shape(people_heading_rad)}"
        )
    if people_valid is not None and shape(people_valid) != (n,):
        raise ValueError(f"people_valid must be ({n},), one per person in people_xy_m, got shape {shape(people_valid)}")


def input_map(
    occupancy,
    resolution_m: float,
    origin_xy_m,
    robot_xy_m,
    people_xy_m,
    people_heading_rad,
    goal_xy_m,
    people_valid=None,
    robot_yaw_rad=0.0,
    occupied_above: float = OCCUPIED_ABOVE,
    supersample: int | None = None,
):
    """The U-Net's input map (40, 40) uint8 around the robot.

    Args:
      occupancy: (H, W) occupancy values in [0, 1] (unknown, e.g. ROS's -1, counts as free).
        ROS OccupancyGrid layout: cell (i, j) covers ``x in origin_x + [j, j + 1) * resolution``,
        ``y in origin_y + [i, i + 1) * resolution`` (row index grows with y).
      resolution_m: the occupancy grid's cell size; origin_xy_m: (2,) world position of cell
        (0, 0)'s corner.
      robot_xy_m: (2,) robot position; robot_yaw_rad: the map's orientation: 0 (default) keeps the
        world's axes (x right, y up), the robot's yaw turns the map into the robot's frame.
      people_xy_m: (P, 2) positions; people_heading_rad: (P,) headings; people_valid: (P,) bool
        (default all).
      goal_xy_m: (2,) goal. A goal outside the 16 m window is drawn where the line from the robot to
        it leaves the window (this project's choice; the paper does not say), so the direction to
        it survives.
      occupied_above: occupancy above which a cell is a wall (the paper: 0.6).
      supersample: each 0.4 m cell tests ``supersample**2`` points of the occupancy grid and is a
        wall if any is occupied; the default, ``ceil(0.4 / resolution_m)``, spaces the points one
        occupancy cell apart so that a wall one cell thick is not missed. ``resolution_m`` and
        ``supersample`` are static (Python numbers) under ``jit``.
    """
    _check_input_shapes(
        occupancy, resolution_m, origin_xy_m, robot_xy_m, people_xy_m, people_heading_rad, goal_xy_m, people_valid
    )
    if supersample is None:
        supersample = max(1, math.ceil(grid.CELL_M / resolution_m - 1e-9))
    _check_finite(
        people_xy_m=people_xy_m, people_heading_rad=people_heading_rad, robot_xy_m=robot_xy_m, goal_xy_m=goal_xy_m
    )
    occupancy = jnp.asarray(occupancy, jnp.float32)
    people_xy_m = jnp.asarray(people_xy_m, jnp.float32).reshape(-1, 2)
    people_heading_rad = jnp.asarray(people_heading_rad, jnp.float32).reshape(-1)
    valid = jnp.ones(people_xy_m.shape[0], bool) if people_valid is None else jnp.asarray(people_valid, bool)
    rx, ry = jnp.asarray(robot_xy_m, jnp.float32)
    c, s = jnp.cos(robot_yaw_rad), jnp.sin(robot_yaw_rad)

    # Walls: sample each cell at supersample x supersample points, in the world frame.
    offsets = (jnp.arange(supersample) + 0.5) / supersample * grid.CELL_M - grid.CELL_M / 2
    lx = grid.CELL_X_M[..., None, None] + offsets[None, None, None, :]
    ly = grid.CELL_Y_M[..., None, None] - offsets[None, None, :, None]
    wx, wy = rx + c * lx - s * ly, ry + s * lx + c * ly
    j = jnp.floor((wx - origin_xy_m[0]) / resolution_m).astype(jnp.int32)
    i = jnp.floor((wy - origin_xy_m[1]) / resolution_m).astype(jnp.int32)
    on_map = (i >= 0) & (i < occupancy.shape[0]) & (j >= 0) & (j < occupancy.shape[1])
    value = jnp.where(
        on_map, occupancy[jnp.clip(i, 0, occupancy.shape[0] - 1), jnp.clip(j, 0, occupancy.shape[1] - 1)], 0.0
    )
    walls = jnp.any(value > occupied_above, axis=(-2, -1))
    image = jnp.where(walls, jnp.uint8(grid.WALL), jnp.uint8(grid.FREE))

    def to_local(x, y):
        dx, dy = x - rx, y - ry
        return c * dx + s * dy, -s * dx + c * dy

    px, py = to_local(people_xy_m[:, 0], people_xy_m[:, 1])
    image = grid.draw_people(image, px, py, people_heading_rad - robot_yaw_rad, valid)
    gx, gy = to_local(*jnp.asarray(goal_xy_m, jnp.float32))
    reach = jnp.maximum(jnp.maximum(jnp.abs(gx), jnp.abs(gy)) / (grid.HALF_M - 1e-3), 1.0)
    return grid.draw_goal(image, gx / reach, gy / reach)


def check_maps(maps) -> jax.Array:
    """The input maps as an array, or ValueError saying what is wrong with them: a shape other
    than (B, 40, 40) or (40, 40), a bool or non-numeric dtype, NaN, or values outside the pixel
    encoding (0 free, 25 heading, 100 person, 200 goal, 255 wall; an occupancy grid in [0, 1]
    goes through :func:`input_map` first). Without the check such maps gave the empty room's
    costs."""
    array = np.asarray(maps)
    g = grid.GRID
    if array.ndim not in (2, 3) or array.shape[-2:] != (g, g):
        raise ValueError(f"input maps must be (B, {g}, {g}) or ({g}, {g}), got shape {array.shape}")
    if array.dtype == bool or not np.issubdtype(array.dtype, np.number):
        raise ValueError(f"input maps hold {array.dtype} values; expected the pixel codes {grid.INPUT_CODES} (uint8)")
    if np.issubdtype(array.dtype, np.floating) and np.isnan(array).any():
        raise ValueError(f"input maps hold NaN at {np.argwhere(np.isnan(array))[0].tolist()}")
    outside = ~np.isin(array, grid.INPUT_CODES)
    if outside.any():
        where = np.argwhere(outside)[0]
        values = np.unique(array[outside])
        raise ValueError(
            f"input maps hold values outside the pixel encoding {grid.INPUT_CODES}: {values[:5].tolist()} "
            f"(first at {where.tolist()}); an occupancy grid goes through models.inference.input_map first"
        )
    return jnp.asarray(array.astype(np.uint8))


ROTATIONS = (1, 4)


def rotation_averaged(predict, rotations: int = 4):
    """``predict`` ((B, 40, 40) maps -> (B, 40, 40) costs) averaged over ``rotations`` quarter turns.

    A quarter turn about the image centre is an exact symmetry of the encoding (cells go to cells,
    the 8 heading directions to heading directions, the robot stays at the centre) and of every
    rule (each is about where things are relative to each other and to the robot), so the average
    of ``rot90^-k(predict(rot90^k(maps)))`` over k = 0..3 is a prediction that turns with the map.
    Mirrors are not symmetries (keep right becomes keep left). 1 returns ``predict`` itself.
    Measured (README, "The held-out rule suite"): the MSE against the rule suite's expected maps
    down a fifth, the rules' pass shares up by 0-2.5 points, at 4 times the inference cost.
    """
    if rotations not in ROTATIONS:
        raise ValueError(f"rotations must be one of {ROTATIONS}, got {rotations}")
    if rotations == 1:
        return predict

    def averaged(maps):
        turned = [jnp.rot90(predict(jnp.rot90(maps, k, axes=(1, 2))), -k, axes=(1, 2)) for k in range(rotations)]
        return sum(turned) / rotations

    return averaged


@functools.lru_cache(maxsize=8)
def _apply_for(graphdef, scale: float = 1.0):
    """``(weights, maps) -> scale x costs`` over :func:`models.steps.make_predict`, one per
    structure and scale."""
    from socialnav.models.steps import make_predict

    predict = make_predict(graphdef)
    if scale == 1.0:
        return lambda weights, maps: predict(*weights, maps)
    return lambda weights, maps: scale * predict(*weights, maps)


def output_scale(config) -> float:
    """1, or :data:`models.social_costs.GRADED_TOP` for a model that learnt graded costs only
    (:attr:`models.config.TrainConfig.reads_lethal` false), so that its peak is read as the
    top of the graded range and never as forbidden."""
    return 1.0 if config is None or config.reads_lethal else GRADED_TOP


WEIGHTS_FILE = "weights.msgpack"
CARD_FILE = "model.json"


def read_card(folder) -> dict:
    """An exported model's card (:data:`CARD_FILE`: how it was made and what it reached; ``{}``
    for a folder without one).

    Raises:
      ValueError: the card is not a JSON object (the file named).
    """
    path = pathlib.Path(folder) / CARD_FILE
    if not path.is_file():
        return {}
    try:
        card = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as e:
        raise ValueError(f"{path}: not valid JSON ({e})") from None
    if not isinstance(card, dict):
        raise ValueError(f"{path}: not a JSON object")
    return card


# The model shipped with the package (made by the recipe in its model.json; socialnav gscl export).
DEFAULT_MODEL = DATA_DIR / "gscl" / "default"


def _leaves(*trees):
    return jax.tree_util.tree_flatten_with_path(trees)[0]


def model_problem(path) -> str | None:
    """None when ``path`` holds a GSCL model :meth:`SocialCostModel.load` can read (a training
    run's folder with ``checkpoints/``, or an exported model with ``weights.msgpack``), else
    what is wrong, naming the folder."""
    path = pathlib.Path(path)
    if (path / "checkpoints").is_dir() or (path / WEIGHTS_FILE).is_file():
        if not (path / "config.json").is_file():
            return f"{path}: no config.json beside the weights"
        return None
    return (
        f"{path}: neither a GSCL training run (checkpoints/, made by socialnav gscl train) nor an "
        f"exported model ({WEIGHTS_FILE}, made by socialnav gscl export)"
    )


def model_identity(path=None) -> str:
    """What makes a model this one (16 hex digits): an exported model's configuration and
    weights, or a run's configuration and its checkpoints' steps."""
    path = DEFAULT_MODEL if path is None else pathlib.Path(path)
    h = hashlib.sha256((path / "config.json").read_bytes() if (path / "config.json").is_file() else b"")
    if (path / WEIGHTS_FILE).is_file():
        h.update((path / WEIGHTS_FILE).read_bytes())
    else:
        h.update(",".join(sorted(p.name for p in (path / "checkpoints").iterdir() if p.name.isdigit())).encode())
    return h.hexdigest()[:16]


class SocialCostModel:
    """A trained U-Net in evaluation mode: ``model(maps)`` (B, 40, 40) codes -> (B, 40, 40) costs.

    Build it with :meth:`load` from a training run's folder (``socialnav gscl train --out``).
    """

    def __init__(self, graphdef, params, batch_stats, config=None):
        from socialnav.models.steps import make_predict

        self._predict = make_predict(graphdef)  # jitted, batch norm in eval mode
        self._scale = output_scale(config)
        self._graphdef = graphdef
        self._params, self._batch_stats = params, batch_stats
        self.config = config

    @classmethod
    def load(cls, path=None, step: int | None = None) -> SocialCostModel:
        """The model of a training run's latest checkpoint (or of ``step``), or of an exported
        model folder (:meth:`export`); ``path=None`` loads the model shipped with the package
        (:data:`DEFAULT_MODEL`).

        Raises:
          ValueError: ``path`` is neither (:func:`model_problem` says why).
        """
        from socialnav.models.checkpoints import load_config, restore
        from socialnav.models.steps import compiled, weight_shapes

        path = DEFAULT_MODEL if path is None else pathlib.Path(path)
        problem = model_problem(path)
        if problem:
            raise ValueError(problem)
        if (path / WEIGHTS_FILE).is_file():
            from flax import serialization

            config = load_config(path)
            params, batch_stats = weight_shapes(config)
            want = [(jax.tree_util.keystr(k), np.shape(a)) for k, a in _leaves(params, batch_stats)]
            try:
                pure = serialization.msgpack_restore((path / WEIGHTS_FILE).read_bytes())
                nnx.replace_by_pure_dict(params, pure["params"])
                nnx.replace_by_pure_dict(batch_stats, pure["batch_stats"])
            except Exception as e:  # msgpack's, flax's and a wrong tree's errors have no common base
                raise ValueError(f"{path / WEIGHTS_FILE}: not the weights of {path / 'config.json'} ({e})") from None
            missing = [
                jax.tree_util.keystr(k) for k, a in _leaves(params, batch_stats) if isinstance(a, jax.ShapeDtypeStruct)
            ]
            if missing:  # the template holds shapes only: a leaf not in the file would stay one
                raise ValueError(f"{path / WEIGHTS_FILE}: has no {missing[0]}, which {path / 'config.json'} needs")
            got = [(jax.tree_util.keystr(k), np.shape(a)) for k, a in _leaves(params, batch_stats)]
            if got != want:
                wrong = next(g for g, w in zip(got, want, strict=False) if g != w)
                raise ValueError(f"{path / WEIGHTS_FILE}: {wrong[0]} is not shaped as {path / 'config.json'} says")
            return cls(compiled(config)[0], params, batch_stats, config)
        config, graphdef, state, _ = restore(path, step)
        return cls(graphdef, state["params"], state["batch_stats"], config)

    def export(self, folder, card: dict | None = None) -> pathlib.Path:
        """Write the model alone (no optimiser state): ``config.json``, ``weights.msgpack`` (the
        weights and batch statistics, flax's msgpack) and ``model.json`` (``card``: how it was
        made and what it reached), each atomically; :meth:`load` reads the folder back."""
        from flax import serialization

        from socialnav.common.atomic import write_bytes_atomic, write_text_atomic

        folder = pathlib.Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        pure = {
            "params": jax.tree.map(np.asarray, nnx.to_pure_dict(self._params)),
            "batch_stats": jax.tree.map(np.asarray, nnx.to_pure_dict(self._batch_stats)),
        }
        write_text_atomic(folder / "config.json", json.dumps(self.config.to_json(), indent=1))
        write_bytes_atomic(folder / WEIGHTS_FILE, lambda h: h.write(serialization.msgpack_serialize(pure)))
        write_text_atomic(folder / CARD_FILE, json.dumps(card or {}, indent=1))
        return folder

    def function(self, maps):
        """The prediction as a function of the maps alone (closes over the weights): use it inside
        your own jit. Scaled by :func:`output_scale`."""
        costs = self._predict(self._params, self._batch_stats, maps)
        return costs if self._scale == 1.0 else self._scale * costs

    @property
    def weights(self):
        """The network's weights and batch statistics, the pytree :attr:`apply` takes."""
        return (self._params, self._batch_stats)

    @property
    def apply(self):
        """``(weights, maps (B, 40, 40)) -> costs (B, 40, 40)``: the prediction with the weights an
        argument, so that under a caller's ``jit`` they are traced and another checkpoint of the
        same network reuses the compiled program. One function per network structure (equal
        structures give the same function, so callers that cache on it hit)."""
        return _apply_for(self._graphdef, self._scale)

    def __call__(self, maps) -> jax.Array:
        """Costs (B, 40, 40) in [0, 1] of input maps (B, 40, 40) or (40, 40), checked first
        (:func:`check_maps`)."""
        maps = check_maps(maps)
        if maps.ndim == 2:
            return self.function(maps[None])[0]
        return self.function(maps)

    def cost_layer(self, maps) -> np.ndarray:
        """Costs as the paper's 0-255 uint8 images."""
        return np.asarray(jnp.round(self(maps) * 255)).astype(np.uint8)
