"""socialnav.planners.learning: planners learned from experience or from people's paths.

The PPO policy (:mod:`~socialnav.planners.learning.policy`: what it observes and how its output
drives the base; :mod:`~socialnav.planners.learning.policy_training`: PPO in the vectorised arena;
:mod:`~socialnav.planners.learning.policy_run`: a training run's files and the trained policy as
an actor; :mod:`~socialnav.planners.learning.policy_social`: its optional cost-map input), and
costs learned from demonstrated paths (:mod:`~socialnav.planners.learning.irl`: maximum-entropy
IRL through the soft planner; :mod:`~socialnav.planners.learning.irl_fit`,
:mod:`~socialnav.planners.learning.tracks`: people's tracks as demonstrations, on the walls of a
ROS map, :mod:`~socialnav.planners.learning.ros_map`).

The GSCL network's own training (data to weights, no simulator) is :mod:`socialnav.models`.
"""

from socialnav.planners.learning.irl import Demonstrations
from socialnav.planners.learning.policy import PolicyConfig, PolicyParams, policy_actor
from socialnav.planners.learning.policy_training import PPOConfig
from socialnav.planners.learning.ros_map import read_ros_map
from socialnav.planners.learning.tracks import read_tracks, recorded_tracks

__all__ = [
    "Demonstrations",
    "PPOConfig",
    "PolicyConfig",
    "PolicyParams",
    "policy_actor",
    "read_ros_map",
    "read_tracks",
    "recorded_tracks",
]
