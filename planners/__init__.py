"""socialnav.planners: planning alone, one folder a kind of part.

- :mod:`~socialnav.planners.layers`: the social cost layers in one shape (SNL, CASN, SNAPE,
  GSCL), the cost grid, what a layer sees;
- :mod:`~socialnav.planners.global_planners`: exact and differentiable grid planners (NavFn's
  potential, its soft-min relaxation);
- :mod:`~socialnav.planners.local`: a stack's local planners (pure pursuit, the elastic bands);
- :mod:`~socialnav.planners.reactive`: the reactive baselines (ORCA, the social force, DWA), a
  velocity rule steering to a carrot on the ``navfn`` stack's path;
- :mod:`~socialnav.planners.learning`: the PPO policy and costs learned from demonstrated paths
  (IRL);
- :mod:`~socialnav.planners.warehouse`: seed 000's waypoint planners: route tables, causal costs,
  A*, the causal planner's actor.

Beside them, :mod:`~socialnav.planners.stack` composes a layer, a global planner and a local one
into a navigation stack (the seeds' methods as named configurations), and
:mod:`~socialnav.planners.actors` turns a stack into the arena's actor;
:mod:`~socialnav.planners.plots` draws every layer and its planner's path side by side.

Re-exported here: what a script needs to go from a scene to a cost map to a plan.
"""

from socialnav.planners import layers
from socialnav.planners.global_planners.grid_planner import GridPlan, navfn_plans, path_xy_m, weighted_plans
from socialnav.planners.layers import CostLayer
from socialnav.planners.layers.casn_layer import CASNParams, CASNState
from socialnav.planners.layers.costmap import GridSpec, combine_max, obstacle_layer
from socialnav.planners.layers.scene import Scene, make_scene
from socialnav.planners.layers.snape_layer import SNAPEParams
from socialnav.planners.layers.snl_layer import SNLParams
from socialnav.planners.stack import LayerParams, StackConfig
from socialnav.planners.warehouse.routes import plan_from_costs, shortest_path_plan

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
