"""Social-navigation scenes (seeds 001, 002, 004): the file format and its validation
(:mod:`~jaxsim.scenes.spec`), variants (:mod:`~jaxsim.scenes.variant`), the walls
(:mod:`~jaxsim.scenes.world`), people (:mod:`~jaxsim.scenes.people`), perception
(:mod:`~jaxsim.scenes.perception`) and the robot base (:mod:`~jaxsim.scenes.robot`)."""
