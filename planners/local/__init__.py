"""socialnav.planners.local: a navigation stack's local planners, from a path to a velocity.

:mod:`~socialnav.planners.local.pure_pursuit`: a unicycle following a path (turning on the spot
first); :mod:`~socialnav.planners.local.elastic_band`: the classic elastic band and SNAPE's social
one, with SNAPE's speed gain. The reactive baselines (ORCA, the social force, DWA: a velocity rule
steering to a carrot on a path) are :mod:`socialnav.planners.reactive`.
"""

from socialnav.planners.local.elastic_band import BandParams, band_from_path, relax, speed_gain
from socialnav.planners.local.pure_pursuit import PursuitParams, lookahead_point, pursue

__all__ = ["BandParams", "PursuitParams", "band_from_path", "lookahead_point", "pursue", "relax", "speed_gain"]
