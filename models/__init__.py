"""socialnav.models: GSCL (seed 002), the learned social cost map, and the policy's network.

The procedural dataset (:mod:`~socialnav.models.families`, :mod:`~socialnav.models.dataset`, on
:mod:`~socialnav.models.grid` and :mod:`~socialnav.models.social_costs`), the U-Net
(:mod:`~socialnav.models.unet`), training (:mod:`~socialnav.models.config`,
:mod:`~socialnav.models.streams`, :mod:`~socialnav.models.steps`, :mod:`~socialnav.models.quality`,
:mod:`~socialnav.models.checkpoints`, :mod:`~socialnav.models.train`), evaluation
(:mod:`~socialnav.models.evaluation`; the held-out rule suite, :mod:`~socialnav.models.rules`) and
inference (:mod:`~socialnav.models.inference`). Imports none of the toolkit's other parts.

Re-exported here: a trained model and its input maps (train with ``socialnav.models.train.train``
or ``socialnav gscl train``).
"""

from socialnav.models.config import TrainConfig
from socialnav.models.inference import DEFAULT_MODEL, SocialCostModel, input_map, rotation_averaged

__all__ = ["DEFAULT_MODEL", "SocialCostModel", "TrainConfig", "input_map", "rotation_averaged"]
