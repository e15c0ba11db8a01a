"""jaxsim: the PeopleFlow warehouse as a batched, pure-JAX simulator.

Import what you need from the submodules (``jaxsim.scenario``, ``jaxsim.world``,
``jaxsim.rollout``, ``jaxsim.logs``); this package file imports nothing, so that
``jaxsim.devices.request_host_devices()`` can run before JAX is loaded.
"""

__version__ = "0.1.0"
