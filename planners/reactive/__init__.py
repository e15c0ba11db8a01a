"""socialnav.planners.reactive: the reactive baselines, a velocity rule steering to a carrot.

:mod:`~socialnav.planners.reactive.actor`: the actor (the ``navfn`` stack's path, its lookahead
point, a rule between the path and the wheels) and the rules' shared inputs
(:class:`~socialnav.planners.reactive.actor.ReactiveParams`); the rules:
:mod:`~socialnav.planners.reactive.orca_robot` (ORCA), :mod:`~socialnav.planners.reactive.social_force_robot`
(the people's social force) and :mod:`~socialnav.planners.reactive.dwa` (the dynamic window);
:mod:`~socialnav.planners.reactive.baselines`: the three by name with their default parameters.
"""

from socialnav.planners.reactive.actor import ReactiveParams, reactive_actor
from socialnav.planners.reactive.baselines import BASELINES, Baseline, baseline_actor, baseline_params
from socialnav.planners.reactive.dwa import DWAParams
from socialnav.planners.reactive.orca_robot import ORCARobotParams
from socialnav.planners.reactive.social_force_robot import SocialForceRobotParams

__all__ = [
    "BASELINES",
    "Baseline",
    "DWAParams",
    "ORCARobotParams",
    "ReactiveParams",
    "SocialForceRobotParams",
    "baseline_actor",
    "baseline_params",
    "reactive_actor",
]
