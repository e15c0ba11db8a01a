"""socialnav.evaluation.humans: the human models measured against real pedestrians, and fitted.

- :mod:`~socialnav.evaluation.humans.validation`: each test (the Jülich fundamental diagram,
  counterflow and lanes, ETH/UCY prediction, body overlaps) for a human model, and the report;
- :mod:`~socialnav.evaluation.humans.measures`: what is measured on data and model alike
  (PedPy's Voronoi density and speed, Weidmann's curve, the diagram's band check, lane order,
  overlaps, ADE/FDE and a model's difference from a baseline with its interval, groups);
- :mod:`~socialnav.evaluation.humans.calibration`: the fundamental diagram's fit, by gradient
  through the crowd step and by Nelder-Mead;
- :mod:`~socialnav.evaluation.humans.trajectory_calibration`: the fit to ETH/UCY trajectories,
  leave one scene out;
- :mod:`~socialnav.evaluation.humans.joint_calibration`: both at once, and the trade-off;
- :mod:`~socialnav.evaluation.humans.datacache`: the recorded runs' measures kept on disk between processes;
- :mod:`~socialnav.evaluation.humans.minimise`: Adam and Nelder-Mead on a scalar loss;
- :mod:`~socialnav.evaluation.humans.plots`: the pictures.

In code the modules are imported under the names they had before they were a folder
(``validation as hv``, ``calibration as hc``, ``measures``).
"""

from socialnav.evaluation.humans.measures import ade_fde, lane_order, overlaps, voronoi_density_speed, weidmann_speed
from socialnav.evaluation.humans.validation import HumanModel, validate

__all__ = ["HumanModel", "ade_fde", "lane_order", "overlaps", "validate", "voronoi_density_speed", "weidmann_speed"]
