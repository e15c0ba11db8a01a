"""jaxsim: the simulator alone. The PeopleFlow warehouse as a batched, pure-JAX simulation.

Import what you need from the submodules: :mod:`jaxsim.scenario` (the scenario files, loaded
and validated), :mod:`jaxsim.world` (its static arrays), :mod:`jaxsim.step` (the crowd step, the
day step with the robot's controller passed in, the measurement), :mod:`jaxsim.robot` (the
day's controller), :mod:`jaxsim.rollout` (scan, vmap, sharding, batch compaction) and
:mod:`jaxsim.logs` (Parquet logs). This package imports none of the toolkit's other parts.
"""
