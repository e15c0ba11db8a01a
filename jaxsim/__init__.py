"""socialnav.jaxsim: the simulator alone. The PeopleFlow warehouse as a batched, pure-JAX simulation,
and the social-navigation scenes (:mod:`socialnav.jaxsim.scenes`).

:mod:`~socialnav.jaxsim.scenario` (the scenario files, loaded and validated),
:mod:`~socialnav.jaxsim.world` (its static arrays), :mod:`~socialnav.jaxsim.grid` (the one grid
type of every map: walls, waypoints, occupancy, costs), :mod:`~socialnav.jaxsim.step` (the crowd
step, the day's transition under the robot's command, the measurement), :mod:`~socialnav.jaxsim.control`
(the control loop both worlds run: the actor acts, the world steps), :mod:`~socialnav.jaxsim.robot`
(the robot's body and day), :mod:`~socialnav.jaxsim.rollout` (scan, vmap, sharding) and
:mod:`~socialnav.jaxsim.logs` (Parquet logs). Imports none of the toolkit's other parts.

Re-exported here: what a script needs to simulate worlds and read their logs (the functions
``rollout.rollout`` and ``route_follower.route_follower`` keep their modules' names, so import
them from their modules).
"""

from socialnav.jaxsim.actor import Actor, Driver, replanning
from socialnav.jaxsim.control import control_loop
from socialnav.jaxsim.logs import record_table, simulate_to_parquet
from socialnav.jaxsim.params import SimParams
from socialnav.jaxsim.rollout import to_numpy
from socialnav.jaxsim.scenario import Scenario, ScenarioError, load_scenario
from socialnav.jaxsim.world import World, build_world

__all__ = [
    "Actor",
    "Driver",
    "Scenario",
    "ScenarioError",
    "SimParams",
    "World",
    "build_world",
    "control_loop",
    "load_scenario",
    "record_table",
    "replanning",
    "simulate_to_parquet",
    "to_numpy",
]
