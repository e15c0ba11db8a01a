"""socialnav.planners: planning alone.

Seed 000's waypoint planners: route tables (:mod:`~socialnav.planners.routes`: shortest path and
any arc costs), the causal costs, A* and the abort decision (:mod:`~socialnav.planners.waypoint`,
Eq. 8-10) and the typed reader of the causal engine's tables (:mod:`~socialnav.planners.tables`).
The social cost layers in one shape (:mod:`~socialnav.planners.layers`: SNL, CASN, SNAPE, GSCL),
the cost grid (:mod:`~socialnav.planners.costmap`), exact and differentiable grid planners
(:mod:`~socialnav.planners.grid_planner`, :mod:`~socialnav.planners.smooth_planner`), local
planners (elastic band, pure pursuit, ORCA, social force, DWA), the arena's actors
(:mod:`~socialnav.planners.actors`, :mod:`~socialnav.planners.baselines`), the learned policy, and
costs learned from demonstrated paths (:mod:`~socialnav.planners.irl`,
:mod:`~socialnav.planners.tracks`).

Re-exported here: what a script needs to go from a scene to a cost map to a plan.
"""

from socialnav.planners import layers
from socialnav.planners.casn import CASNParams, CASNState
from socialnav.planners.costmap import GridSpec, combine_max, obstacle_layer
from socialnav.planners.grid_planner import GridPlan, navfn_plans, path_xy_m, weighted_plans
from socialnav.planners.layers import CostLayer
from socialnav.planners.routes import plan_from_costs, shortest_path_plan
from socialnav.planners.scene import Scene, make_scene
from socialnav.planners.snape import SNAPEParams
from socialnav.planners.snl import SNLParams
from socialnav.planners.stack import LayerParams, StackConfig

__all__ = [
    "CASNParams",
    "CASNState",
    "CostLayer",
    "GridPlan",
    "GridSpec",
    "LayerParams",
    "SNAPEParams",
    "SNLParams",
    "Scene",
    "StackConfig",
    "combine_max",
    "layers",
    "make_scene",
    "navfn_plans",
    "obstacle_layer",
    "path_xy_m",
    "plan_from_costs",
    "shortest_path_plan",
    "weighted_plans",
]
