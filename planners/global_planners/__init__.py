"""socialnav.planners.global_planners: paths across a cost grid.

:mod:`~socialnav.planners.global_planners.grid_planner`: the exact potential from the goal
(Dijkstra's distances; NavFn's) and the path down it, with a C++ Dijkstra on the CPU
(``grid_dijkstra.cc``); :mod:`~socialnav.planners.global_planners.smooth_planner`: its soft-min
relaxation, differentiable in the costs (what learning costs from paths needs).
"""

from socialnav.planners.global_planners.grid_planner import GridPlan, navfn_plans, path_xy_m, weighted_plans
from socialnav.planners.global_planners.smooth_planner import soft_path_cost, soft_potential

__all__ = ["GridPlan", "navfn_plans", "path_xy_m", "soft_path_cost", "soft_potential", "weighted_plans"]
