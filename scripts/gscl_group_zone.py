"""Where a GSCL model misses the group's interaction zone, and whether the input could tell it.

    python scripts/gscl_group_zone.py --run runs/gscl                 # 4,000 generator groups
    python scripts/gscl_group_zone.py --run runs/gscl --samples 1000 --posterior 0

On the generator's own group family (:func:`models.families.sample_group` and its facing-out
twin from the same keys, so the same circle), it scores the rule suite's ``group_zone`` contrast
(:mod:`models.rules`: the circle's middle facing in minus facing out; a pass keeps half of what
the zone adds over the people's own cost) by circle radius, with the model's and the target's
mean cost in the middle.

``--posterior K`` also builds, for up to K groups per radius band, the **input-optimal** map: the
average of the targets of every circle that draws exactly the same people cells and headings
(importance sampling: centres within 0.5 m and radii within 0.6 m of the true ones, each person's
angle marginalised over +-0.7 rad on a grid of 141, each locally uniform, as the generator's
priors are), and scores it like the model. If that map passes where the model fails, the input
fixes the zone and the miss is the network's; if it fails too, no model trained on these targets
could pass. Only groups whose middle keeps 3 free cells and where the zone adds at least 0.1 are
scored (the suite's own conditions).
"""

from __future__ import annotations

import argparse
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent))

import jax
import jax.numpy as jnp
import numpy as np

from socialnav.models import families, grid, rules
from socialnav.models import social_costs as sc
from socialnav.models.inference import SocialCostModel

BANDS_M = ((0.8, 0.9), (0.9, 1.0), (1.0, 1.2), (1.2, 1.5), (1.5, 1.8))


def _cells(v):
    return np.floor(np.asarray(v, np.float64) / grid.CELL_M).astype(int)


def _octant(a):
    return np.round(np.asarray(a, np.float64) / (np.pi / 4)).astype(int) % 8


def input_optimal_zone(px, py, angle, cx, cy, radius, rng, draws: int = 40_000, keep: int = 300):
    """(keep, 40, 40) zone plateaus of circles drawn from the posterior given the drawn people.

    Args: the true people's positions (m) and angles from the centre (rad), (n,) each; the true
    centre and radius (m). Returns None when fewer than 20 draws reproduce the input."""
    ocol, orow, ohead = _cells(px), _cells(py), _octant(angle + np.pi)
    ccx = cx + rng.uniform(-0.5, 0.5, draws)
    ccy = cy + rng.uniform(-0.5, 0.5, draws)
    rr = rng.uniform(families.GROUP_RADIUS_M[0], min(families.GROUP_RADIUS_M[1], radius + 0.6), draws)
    offsets = np.linspace(-0.7, 0.7, 141)
    weight = np.ones(draws)
    for p in range(len(px)):
        th = angle[p] + offsets[None]
        x, y = ccx[:, None] + rr[:, None] * np.cos(th), ccy[:, None] + rr[:, None] * np.sin(th)
        same = (_cells(x) == ocol[p]) & (_cells(y) == orow[p]) & (_octant(th + np.pi) == ohead[p])
        weight *= same.mean(axis=1)
    if (weight > 0).sum() < 20:
        return None
    pick = rng.choice(draws, keep, p=weight / weight.sum())
    return np.asarray(sc.disc_plateau(ccx[pick, None, None], ccy[pick, None, None], rr[pick, None, None]))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--run", required=True, help="a training run's folder (socialnav gscl train --out)")
    ap.add_argument("--samples", type=int, default=4000, help="generator groups scored (default 4000)")
    ap.add_argument("--posterior", type=int, default=40, help="groups per radius band for the input-optimal map")
    ap.add_argument("--seed", type=int, default=123)
    args = ap.parse_args(argv)
    model = SocialCostModel.load(args.run)
    keys = jax.random.split(jax.random.PRNGKey(args.seed), args.samples)
    img_in, t_in = (np.asarray(v) for v in jax.vmap(families.sample_group)(keys))
    img_out, t_out = (np.asarray(v) for v in jax.vmap(families.sample_non_group)(keys))
    x, y, angle, valid, cx, cy, radius = (np.asarray(v) for v in jax.vmap(families.group_layout)(keys))

    def predict(images):
        chunks = [model.function(jnp.asarray(images[i : i + 500])) for i in range(0, len(images), 500)]
        return np.concatenate([np.asarray(c) for c in chunks])

    p_in, p_out = predict(img_in), predict(img_out)
    d = np.hypot(grid.CELL_X_M[None] - cx[:, None, None], grid.CELL_Y_M[None] - cy[:, None, None])
    zone = (d < np.maximum(0.55 * radius, 0.5)[:, None, None]) & (img_in == grid.FREE) & (img_out == grid.FREE)
    # The facing-in map without the zone: the people's own cost, as the suite's rule-blind map.
    people = jax.vmap(lambda *a: sc.people_cost(*families._as_drawn(*a[:3]), a[3]))(x, y, angle + np.pi, valid)
    blind_in = np.where(img_in == grid.WALL, 0.0, np.asarray(people))

    def middle(maps, region=zone):
        return (maps * region).sum((1, 2)) / np.maximum(region.sum((1, 2)), 1)

    def contrast(facing_in, facing_out=t_out):
        """The suite's contrast (the zone facing in minus facing out); NaN for an empty zone, which
        ``usable`` leaves out."""
        with np.errstate(invalid="ignore"):
            return rules.contrasts(np.stack([facing_in, facing_out], 1), zone, zone)

    expected_c, blind_c = contrast(t_in), contrast(blind_in)
    usable = (zone.sum((1, 2)) >= rules.MIN_REGION_CELLS) & (expected_c - blind_c >= rules.MIN_EXPECTED_CONTRAST)
    bar = blind_c + rules.PASS_FRACTION * (expected_c - blind_c)
    passed = contrast(p_in, p_out) >= bar
    m_p_in, m_t_in, m_p_out, m_t_out = (middle(m) for m in (p_in, t_in, p_out, t_out))
    print(f"{args.run}: {usable.sum()} of {args.samples} generator groups scored; pass {passed[usable].mean():.3f}")
    print("radius m | groups | model passes | middle facing in: model / target | facing out: model / target", end="")
    if args.posterior:
        print(" | input-optimal map passes (groups) | model passes on those | its middle - target: mean / rms")
    else:
        print()
    rng = np.random.default_rng(0)
    for lo, hi in BANDS_M:
        band = usable & (radius >= lo) & (radius < hi)
        line = (
            f"{lo:.1f}-{hi:.1f} | {band.sum()} | {passed[band].mean():.2f} | {m_p_in[band].mean():.3f} / "
            f"{m_t_in[band].mean():.3f} | {m_p_out[band].mean():.3f} / {m_t_out[band].mean():.3f}"
        )
        if args.posterior:
            optimal, model_on_same, optimal_in = [], [], []
            for k in np.flatnonzero(band)[: args.posterior]:
                v = valid[k]
                plateaus = input_optimal_zone(x[k][v], y[k][v], angle[k][v], cx[k], cy[k], radius[k], rng)
                if plateaus is None:
                    continue
                mean_in = np.where(img_in[k] == grid.WALL, 0.0, np.maximum(blind_in[k][None], plateaus).mean(0))
                mean_middle = middle(mean_in[None], zone[k : k + 1])[0]
                optimal.append(mean_middle - m_t_out[k] >= bar[k])
                optimal_in.append(mean_middle - m_t_in[k])
                model_on_same.append(passed[k])
            if optimal:
                line += f" | {np.mean(optimal):.2f} ({len(optimal)}) | {np.mean(model_on_same):.2f}"
                line += f" | {np.mean(optimal_in):+.3f} / {np.sqrt(np.mean(np.square(optimal_in))):.3f}"
        print(line)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
