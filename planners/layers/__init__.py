"""socialnav.planners.layers: the social cost layers and the grid they are drawn on.

One file a layer, and the shape they share:

- :mod:`~socialnav.planners.layers.cost_layer`: :class:`CostLayer`, every layer in one shape
  (``none``, ``snl``, ``casn``, ``snape``, ``gscl``);
- :mod:`~socialnav.planners.layers.costmap`: the cost grid (:class:`GridSpec`), Nav2's cost
  scale, obstacles, inflation, combination;
- :mod:`~socialnav.planners.layers.scene`: what a layer sees (:class:`Scene`: people, objects,
  robot, goal);
- :mod:`~socialnav.planners.layers.snl_layer`: ROS social_navigation_layers' proxemic and
  passing layers (seeds 001-002's baseline);
- :mod:`~socialnav.planners.layers.casn_layer`: CASN's context-aware costs (seed 001);
- :mod:`~socialnav.planners.layers.snape_layer`: SNAPE's person Gaussians and interaction
  spaces (seed 004);
- :mod:`~socialnav.planners.layers.gscl_layer`: the trained U-Net's costs placed into a
  planner's grid (seed 002);
- :mod:`~socialnav.planners.plots`: every layer side by side on one scene.

``layers.casn()``, ``layers.gscl(model)``: a layer object, its function and its parameters
together (:mod:`~socialnav.planners.layers.cost_layer`).
"""

from socialnav.planners.layers.cost_layer import BY_NAME, CostLayer, casn, gscl, none, snape, snl

__all__ = ["BY_NAME", "CostLayer", "casn", "gscl", "none", "snape", "snl"]
