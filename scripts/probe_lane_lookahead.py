"""Probe (not a fit): the joint calibration's two training terms (the Jülich diagram's loss, ADE
behind constant velocity on the ETH/UCY training windows) for shipped speed-model fits with the
lane lookahead (``SpeedModelParams.lane_lookahead_s``) at 0, 0.5, 1, 2 and 4 s.

    python scripts/probe_lane_lookahead.py steering_speed_calibrated,collision_free_speed_calibrated
"""

import dataclasses
import sys
import time

import jax

from socialnav.evaluation import human_calibration as hc
from socialnav.evaluation import joint_calibration as jc

for name in sys.argv[1].split(","):
    base = hc.named_model(name)
    data = jc.joint_data(base)
    print(name, "CV ADE", round(data.constant_velocity_ade_m, 4), "scored people", int(data.windows.complete.sum()))
    for look in (0.0, 0.5, 1.0, 2.0, 4.0):
        model = dataclasses.replace(base, speed=base.speed.replace(lane_lookahead_s=look))
        t = time.perf_counter()
        fd, behind = jc.joint_terms(model, data, hc.theta_of(model), jax.random.key(0))
        print(
            f"  lookahead {look:3.1f} s: diagram loss {float(fd):.3f}, ADE behind CV {float(behind):+.2f} % "
            f"({time.perf_counter() - t:.0f} s)",
            flush=True,
        )
