"""Probe (not a fit): the joint calibration's two training terms for the shipped speed-model fit
with a share b of the leader's speed away from the person added to the headway speed, the time gap
divided by 1 - b (the corridor's equilibrium unchanged).

    python scripts/probe_leader_speed.py collision_free_speed_calibrated
"""

import dataclasses
import sys

import jax

from socialnav.evaluation import human_calibration as hc
from socialnav.evaluation import joint_calibration as jc

for name in sys.argv[1].split(","):
    base = hc.named_model(name)
    data = jc.joint_data(base)
    T = float(base.speed.time_gap_s)
    for beta in (0.0, 0.3, 0.6, 0.9):
        m = dataclasses.replace(base, speed=base.speed.replace(leader_share=beta, time_gap_s=T / (1 - beta)))
        fd, behind = jc.joint_terms(m, data, hc.theta_of(m), jax.random.key(0))
        gap = f"time gap {T / (1 - beta):.2f} s"
        print(f"{name} b {beta:.1f} ({gap}): diagram {float(fd):.3f}, ADE behind CV {float(behind):+.2f} %", flush=True)
