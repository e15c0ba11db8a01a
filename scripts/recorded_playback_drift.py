"""How far a reactive recorded crowd strays from its recording with no robot there, per human model.

    python scripts/recorded_playback_drift.py                     # every reactive scene, three models, 32 windows
    python scripts/recorded_playback_drift.py --variants 8 --models orca --scenes hotel_reactive

A reactive person walks by the human model towards where they are recorded 1 s ahead
(:mod:`jaxsim.scenes.people`); with the robot far away, what separates them from the recording is
the model itself (its pushing, its bodies, its deadlocks). Prints, per scene and model, the
distance between each present person and their recorded position over every step of the
windows: mean, median, 95th percentile, the share beyond 0.5 m, the largest. A replayed crowd's
is 0 by construction (tested).
"""

from __future__ import annotations

import argparse
import platform

import jax
import jax.numpy as jnp
import numpy as np

from socialnav.data import RECORDED_SCENES_DIR
from socialnav.evaluation.arena import episodes as arena
from socialnav.jaxsim.scenes.spec import load_scene
from socialnav.jaxsim.scenes.variant import sample_variants

MODELS = ("social_force", "collision_free_speed_calibrated", "orca")


def drift_m(scene_file, model: str, variants: int, seed: int = 0) -> np.ndarray:
    """Every present person's distance (m) from their recorded position, every step, ``variants`` windows."""
    spec = load_scene(scene_file)
    setup = arena.setup_scene(spec, arena.ArenaConfig.of(model))
    drawn = jax.tree_util.tree_map(jnp.asarray, sample_variants(spec, seed, variants, n_slots=setup.n_slots))
    without = jax.block_until_ready(arena.counterfactual_function(setup)(drawn))
    t = without.people_xy_m.shape[1]
    recorded_xy = np.asarray(drawn.track_xy)[:, :, 1 : t + 1].transpose(0, 2, 1, 3)
    present = np.asarray(without.people_present)
    return np.linalg.norm(np.asarray(without.people_xy_m) - recorded_xy, axis=-1)[present]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--variants", type=int, default=32)
    parser.add_argument("--models", default=",".join(MODELS))
    parser.add_argument("--scenes", default=None, help="reactive scene names (default: all)")
    args = parser.parse_args()
    files = (
        sorted(RECORDED_SCENES_DIR.glob("*_reactive.json"))
        if args.scenes is None
        else [RECORDED_SCENES_DIR / f"{name}.json" for name in args.scenes.split(",")]
    )
    print(f"# {platform.processor() or platform.machine()}, jax {jax.__version__}, {args.variants} windows per scene")
    print(f"{'scene':30s} {'model':32s} {'mean':>6s} {'median':>6s} {'p95':>6s} {'>0.5m':>6s} {'max':>6s}")
    for file in files:
        for model in args.models.split(","):
            d = drift_m(file, model, args.variants)
            print(
                f"{file.stem:30s} {model:32s} {d.mean():6.3f} {np.median(d):6.3f} {np.percentile(d, 95):6.3f} "
                f"{100 * (d > 0.5).mean():5.1f}% {d.max():6.2f}"
            )


if __name__ == "__main__":
    main()
