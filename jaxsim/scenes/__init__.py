"""socialnav.jaxsim.scenes: the social-navigation scenes (seeds 001, 002, 004).

The file format and its validation (:mod:`~socialnav.jaxsim.scenes.spec`), variants
(:mod:`~socialnav.jaxsim.scenes.variant`), the walls (:mod:`~socialnav.jaxsim.scenes.world`),
people (:mod:`~socialnav.jaxsim.scenes.people`; recorded crowds,
:mod:`~socialnav.jaxsim.scenes.recording`), perception
(:mod:`~socialnav.jaxsim.scenes.perception`), the robot base (:mod:`~socialnav.jaxsim.scenes.robot`),
the environment (:mod:`~socialnav.jaxsim.scenes.env`) and the rollout of an actor in it
(:mod:`~socialnav.jaxsim.scenes.actor`), the typed specs of its observation and action
(:mod:`~socialnav.jaxsim.scenes.specs`), its wrappers (:mod:`~socialnav.jaxsim.scenes.wrappers`: a
pool of variants, reward shaping, the rule monitor, episode statistics). The Gymnasium adapters
(:mod:`~socialnav.jaxsim.scenes.gym_env`) need the ``gym`` extra and are not imported here.
"""

from socialnav.jaxsim.scenes.actor import Actor, StepRecord, replanning, rollout
from socialnav.jaxsim.scenes.env import Env, EnvConfig, Observation, RewardParams, TimeStep, make_env
from socialnav.jaxsim.scenes.robot import RobotParams
from socialnav.jaxsim.scenes.spec import SceneSpec, load_scene, mirror
from socialnav.jaxsim.scenes.variant import Variant, sample_variant, sample_variants

__all__ = [
    "Actor",
    "Env",
    "EnvConfig",
    "Observation",
    "RewardParams",
    "RobotParams",
    "SceneSpec",
    "StepRecord",
    "TimeStep",
    "Variant",
    "load_scene",
    "make_env",
    "mirror",
    "replanning",
    "rollout",
    "sample_variant",
    "sample_variants",
]
