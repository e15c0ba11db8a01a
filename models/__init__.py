"""models: GSCL (seed 002), the learned social cost map.

The procedural dataset (:mod:`models.families`, :mod:`models.dataset`, on :mod:`models.grid` and
:mod:`models.social_costs`), the U-Net (:mod:`models.unet`), training (:mod:`models.config`,
:mod:`models.streams`, :mod:`models.steps`, :mod:`models.quality`, :mod:`models.checkpoints`,
:mod:`models.train`), evaluation (:mod:`models.evaluation`; the held-out rule suite,
:mod:`models.rules`) and inference. Imports none of the toolkit's other parts.
"""
