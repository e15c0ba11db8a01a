"""Pictures of the cost layers: one figure per scene type, every layer side by side on the same
people and walls with the path its planner finds (as seed 001 Fig. 2-5 (c)(d) and seed 002
Fig. 4-5 show them).

The scenes here are small fixed examples of the seeds' situations (a static person, a pair, a
group facing in and the same people facing out, a walker head-on, a person crossing, an
L-shaped hallway with a person round the corner, a queue at a desk); the arena's randomised
scenes are data files of their own.
"""

from __future__ import annotations

import dataclasses
import pathlib

import jax
import numpy as np

from socialnav.common import figures
from socialnav.jaxsim.params import TIAGO_RADIUS_M
from socialnav.planners import layers
from socialnav.planners.global_planners import grid_planner
from socialnav.planners.layers import costmap
from socialnav.planners.layers import snl_layer as snl
from socialnav.planners.layers.scene import Scene, make_scene

SPEC = costmap.GridSpec(height=80, width=120, resolution_m=0.1, origin_x_m=-6.0, origin_y_m=-4.0)
ROBOT_RADIUS_M = TIAGO_RADIUS_M  # the inscribed radius of the obstacle layer


@dataclasses.dataclass(frozen=True)
class DemoScene:
    """A picture's scene: the room's occupancy (H, W) in [0, 1] and what the layers see (the
    robot's start is ``scene.robot_xy_m``, its goal ``scene.goal_xy_m``)."""

    occupancy: np.ndarray
    scene: Scene


def _box(occupancy: np.ndarray, x0: float, x1: float, y0: float, y1: float, value: float) -> None:
    """Set the cells whose centres lie in [x0, x1] x [y0, y1] (metres)."""
    x, y = SPEC.cell_centres()
    occupancy[(x >= x0) & (x <= x1) & (y >= y0) & (y <= y1)] = value


def _room() -> np.ndarray:
    """(H, W) occupancy of a 12 m x 8 m room: walls on its border."""
    occupancy = np.zeros(SPEC.shape, np.float32)
    occupancy[[0, -1], :] = 1.0
    occupancy[:, [0, -1]] = 1.0
    return occupancy


def _l_hallway() -> np.ndarray:
    """A 2 m wide hallway along x that turns left (up) at its end."""
    occupancy = np.ones(SPEC.shape, np.float32)
    _box(occupancy, -6.0, 3.0, -3.0, -1.0, 0.0)
    _box(occupancy, 1.0, 3.0, -3.0, 4.0, 0.0)
    occupancy[-1, :] = 1.0
    return occupancy


def _desk_room() -> np.ndarray:
    """The room with a desk (1 m x 1.6 m) near its right wall."""
    occupancy = _room()
    _box(occupancy, 4.5, 5.5, -0.8, 0.8, 1.0)
    return occupancy


def _circle(n: int, radius: float, inward: bool, centre=(0.0, 0.0)):
    angles = np.linspace(0, 2 * np.pi, n, endpoint=False) + np.pi / n
    xy = np.stack([centre[0] + radius * np.cos(angles), centre[1] + radius * np.sin(angles)], axis=1)
    return xy, angles + (np.pi if inward else 0.0)


def demo_scenes() -> dict[str, DemoScene]:
    """Name -> :class:`DemoScene` (at most 4 people): seed 001's four situations, seed 002's group
    and non-group, its L-shaped hallway (a person just round the corner) and its queue at a desk."""
    across = dict(robot_xy_m=(-5.0, 0.0), robot_yaw_rad=0.0, goal_xy_m=(5.0, 0.0), max_people=4)
    group_in = _circle(4, 1.2, inward=True)
    group_out = _circle(4, 1.2, inward=False)
    queue_x = np.array([3.3, 2.5, 1.7, 0.9])
    room = _room()
    return {
        "static_person": DemoScene(room, make_scene([[0.0, 0.0]], [np.pi], **across)),
        "static_pair": DemoScene(room, make_scene([[0.0, 1.0], [0.0, -1.0]], [-np.pi / 2, np.pi / 2], **across)),
        "group_facing_in": DemoScene(room, make_scene(*group_in, **across)),
        "group_facing_out": DemoScene(room, make_scene(*group_out, **across)),
        "head_on": DemoScene(room, make_scene([[1.5, 0.0]], people_velocity_mps=[[-1.0, 0.0]], **across)),
        "crossing": DemoScene(room, make_scene([[-1.0, 2.0]], people_velocity_mps=[[0.0, -0.4]], **across)),
        "l_hallway": DemoScene(
            _l_hallway(),
            make_scene([[2.4, 0.2]], [-np.pi / 2], robot_xy_m=(-5.0, -2.0), goal_xy_m=(2.0, 3.3), max_people=4),
        ),
        "queue": DemoScene(
            _desk_room(),
            make_scene(
                np.stack([queue_x, np.zeros(4)], axis=1),
                np.zeros(4),
                robot_xy_m=(-5.0, -2.5),
                goal_xy_m=(4.1, 0.0),
                max_people=4,
            ),
        ),
    }


def layer_functions(gscl_model=None) -> dict[str, tuple[layers.CostLayer, str]]:
    """Panel name -> (the social layer, :class:`planners.layers.CostLayer`; planner: ``navfn`` or
    ``weighted``). ``gscl_model``: the GSCL panel's network (:func:`planners.layers.gscl`)."""
    out = {
        "no social layer": (layers.none(), "navfn"),
        "SNL sigma1 (cov 0.25)": (layers.snl(snl.SIGMA_SMALL), "navfn"),
        "SNL sigma2 (cov 0.5)": (layers.snl(snl.SIGMA_LARGE), "navfn"),
        "CASN": (layers.casn(), "navfn"),
        "SNAPE map (Dijkstra)": (layers.snape(), "weighted"),
    }
    if gscl_model is not None:
        out["GSCL"] = (layers.gscl(gscl_model), "navfn")
    return out


def plan_panels(demo: DemoScene, panel_layers: dict) -> list[tuple[str, np.ndarray, np.ndarray, bool]]:
    """For each layer: (name, combined costs (H, W), path (L, 2) in metres, reached)."""
    obstacles = costmap.obstacle_layer(demo.occupancy, SPEC, ROBOT_RADIUS_M)
    start, goal = demo.scene.robot_xy_m[None], demo.scene.goal_xy_m[None]
    panels = []
    for name, (layer, planner) in panel_layers.items():
        social, _ = layer(demo.scene, SPEC, occupancy=demo.occupancy)
        costs = costmap.combine_max(obstacles, social)
        plan_fn = grid_planner.navfn_plans if planner == "navfn" else grid_planner.weighted_plans
        plan = jax.tree_util.tree_map(lambda a: a[0], plan_fn(costs[None], start, goal, SPEC))
        path = np.asarray(grid_planner.path_xy_m(plan, SPEC))[: int(plan.path_length)]
        panels.append((name, np.asarray(costs), path, bool(plan.reached)))
    return panels


def scene_figure(name: str, demo: DemoScene, panel_layers: dict, path: str | pathlib.Path) -> pathlib.Path:
    """Write one scene's figure: a panel per layer, costs in grey, the path in blue, people red."""
    panels = plan_panels(demo, panel_layers)
    scene = demo.scene
    fig = figures.figure(figsize=(2.6 * len(panels), 2.2))
    axes = fig.subplots(1, len(panels), squeeze=False)[0]
    extent = (
        SPEC.origin_x_m,
        SPEC.origin_x_m + SPEC.width * SPEC.resolution_m,
        SPEC.origin_y_m,
        SPEC.origin_y_m + SPEC.height * SPEC.resolution_m,
    )
    valid = np.asarray(scene.people_valid)
    xy = np.asarray(scene.people_xy_m)[valid]
    heading = np.asarray(scene.people_heading_rad)[valid]
    velocity = np.asarray(scene.people_velocity_mps)[valid]
    for ax, (title, costs, route, reached) in zip(axes, panels, strict=True):
        ax.imshow(np.minimum(costs, 254), origin="lower", extent=extent, cmap="Greys", vmin=0, vmax=254)
        ax.plot(route[:, 0], route[:, 1], color="tab:blue", lw=1.5)
        ax.plot(*np.asarray(scene.robot_xy_m), "o", color="tab:blue", ms=4)
        ax.plot(*np.asarray(scene.goal_xy_m), "*", color="tab:green", ms=7)
        ax.plot(xy[:, 0], xy[:, 1], "o", color="tab:red", ms=4)
        ax.quiver(xy[:, 0], xy[:, 1], np.cos(heading), np.sin(heading), color="tab:red", scale=12, width=0.012)
        moving = np.linalg.norm(velocity, axis=1) > 0.05
        if moving.any():
            ax.quiver(*xy[moving].T, *velocity[moving].T, color="tab:orange", scale=4, width=0.012)
        ax.set_title(title + ("" if reached else " (no path)"), fontsize=8)
        ax.set_xticks([])
        ax.set_yticks([])
    fig.suptitle(name.replace("_", " "), fontsize=9)
    return figures.save(fig, path, dpi=80)


def write_all(out_dir: str | pathlib.Path, gscl_model=None) -> list[pathlib.Path]:
    """One ``layers_<scene>.png`` per demo scene in ``out_dir``."""
    out_dir = pathlib.Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    panel_layers = layer_functions(gscl_model)
    return [
        scene_figure(name, demo, panel_layers, out_dir / f"layers_{name}.png") for name, demo in demo_scenes().items()
    ]
