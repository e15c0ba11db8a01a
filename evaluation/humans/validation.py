"""Human models against real pedestrians: the protocols of ``socialnav humans validate``.

Each protocol runs a human model (the crowd step the arena and the warehouse use,
``--human-model``) where the data was recorded and measures both with the same code
(:mod:`evaluation.humans.measures`, PedPy's Voronoi method for densities and speeds):

* **Fundamental diagram** (:func:`data_fundamental_diagram`, :func:`model_fundamental_diagram`):
  the nine Jülich uni-directional runs in a 1.8 m corridor (their steady states) against the
  model in a periodic 1.8 m corridor at 0.5-3.5 persons/m², speed per density bin.
* **Counterflow** (:func:`data_counterflow`, :func:`model_counterflow`): the bi-directional
  run ``bi_corr_400_b_03`` in a 4.1 m corridor against the model there at the run's density:
  speed and lane order (:func:`evaluation.humans.measures.lane_order`).
* **Prediction on ETH/UCY** (:func:`eth_ucy_prediction`): the field's protocol (observe 8
  frames, 3.2 s; predict 12, 4.8 s; people present in all 20; each scene's test split), the
  model stepped from the last observed frame with every person present aimed along their last
  observed velocity at its speed (``aim="velocity"``) or at their true final position
  (``aim="destination"``, "social force with a destination"), beside constant velocity; and
  aimed along the velocity with the people who walked together over the observed frames walking
  on as groups (``"velocity_groups"``, :mod:`jaxsim.groups`; reported beside, the bar's check
  is the plain ``"velocity"``, as issue 61 defined it).
* **Bodies** (:func:`evaluation.humans.measures.overlaps`): how often and how deep two
  bodies overlap in the model's corridors.

A simulated corridor is periodic: each person has two ghosts a corridor length ahead and behind
(moved with them, felt by the others, never moved by the step), and a person who leaves one end
enters at the other under a new id, as a new pedestrian would (PedPy's speeds never straddle
the jump). People's desired speeds are the warehouse's workers' (normal, 1.34 ± 0.26 m/s,
clipped to 0.6 and the 1.5 m/s cap: ``data/warehouse/params.json``).
"""

from __future__ import annotations

import dataclasses
import functools
import time

import jax
import jax.numpy as jnp
import numpy as np
import pandas as pd
from flax import struct

from socialnav.common.progress import time_left
from socialnav.data import WAREHOUSE_DIR, recorded
from socialnav.evaluation.humans import datacache, measures
from socialnav.jaxsim import geometry, groups, humans, orca, power_law, speed_model
from socialnav.jaxsim.grid import Grid
from socialnav.jaxsim.params import SimParams
from socialnav.jaxsim.scenario.loader import load_scenario
from socialnav.jaxsim.walkers import Aims, RobotDisc, Walkers

HUMAN_MODELS = ("social_force", "orca", "collision_free_speed", "anticipation", "steering_speed", "power_law")
FAR_M = 1.0e4  # where the robot is: no robot in these protocols
# The ETH/UCY protocol counts samples: 8 observed, 12 predicted (3.2 s and 4.8 s at 2.5 Hz). A
# window's sample interval is its run's (PredictionWindows.frame_s): biwi_eth's samples are 0.67 s
# apart (data/pedestrians/README.md), so its windows span 5.3 s and 8 s, and a model is stepped
# for that long; constant velocity, which carries the last displacement on, is the same either way.
PREDICT_OBSERVED, PREDICT_FRAMES = 8, 12
COUNTERFLOW_RUN = "bi_corr_400_b_03"
UO_RUNS = tuple(f"uo-{a}" for a in ("050-180-180", "060-180-180", "070-180-180", "100-180-180", "145-180-180",
                                      "180-180-070", "180-180-095", "180-180-120", "180-180-180"))  # fmt: skip
# The uo runs split by run (issue 61): calibration reads the first alone, validation scores on
# the second. Each covers low and high densities; only uo-180-180-070 reaches 3.5 /m², so the test
# runs hold it and a fit extrapolates there.
FD_TRAIN_RUNS = ("uo-050-180-180", "uo-100-180-180", "uo-180-180-095", "uo-180-180-180")
FD_TEST_RUNS = ("uo-060-180-180", "uo-070-180-180", "uo-145-180-180", "uo-180-180-070", "uo-180-180-120")


@dataclasses.dataclass(frozen=True)
class HumanModel:
    """A human model and its parameters: ``name`` (:data:`HUMAN_MODELS`), the social force's
    :class:`~jaxsim.params.SimParams` (the warehouse's by default; its ``dt_s`` is the step)
    and ORCA's :class:`~jaxsim.orca.ORCAParams`, the velocity models', and the walking groups'
    :class:`~jaxsim.groups.GroupParams` (felt where a protocol has groups: ETH/UCY's), and the
    power law's :class:`~jaxsim.power_law.PowerLawParams`."""

    name: str = "social_force"
    crowd: SimParams | None = None
    orca: orca.ORCAParams = orca.ORCAParams()
    speed: speed_model.SpeedModelParams = speed_model.SpeedModelParams()
    anticipation: speed_model.AnticipationParams = speed_model.AnticipationParams()
    group: groups.GroupParams = groups.GroupParams()
    power_law: power_law.PowerLawParams = power_law.PowerLawParams()

    def __post_init__(self):
        if self.name not in HUMAN_MODELS:
            raise ValueError(f"human model must be one of {', '.join(HUMAN_MODELS)}, got {self.name!r}")
        if self.crowd is None:
            object.__setattr__(self, "crowd", load_scenario(WAREHOUSE_DIR).params)

    @property
    def dt_s(self) -> float:
        return float(self.crowd.dt_s)

    @property
    def radius_m(self) -> float:
        """The body radius its people are measured with (the model's own; the social force's
        is the workers')."""
        if self.name == "orca":
            return float(self.orca.radius_m)
        if speed_model.uses_speed_params(self.name):
            return float(self.speed.radius_m)
        if self.name == "anticipation":
            return float(self.anticipation.radius_m)
        if self.name == "power_law":
            return float(self.power_law.radius_m)
        return float(self.crowd.worker_radius_m)

    @property
    def params(self) -> humans.HumanParams:
        """The traced part (pass it through ``jit`` as an argument)."""
        return humans.HumanParams(self.crowd, self.orca, self.speed, self.anticipation, self.group, self.power_law)


def model_step(name: str, params, field: Grid, people: Walkers, aims: Aims, uniforms, group_id=None) -> Walkers:
    """One step of N people by human model ``name`` (:func:`jaxsim.humans.step_humans`, the one
    crowd function) with ``params`` (:class:`~jaxsim.humans.HumanParams`), no robot: the people
    after it. ``uniforms``: two (N,) draws in (0, 1]; ``group_id`` (N,) the walking groups (None:
    none)."""
    robot = RobotDisc(jnp.float32(FAR_M), jnp.float32(FAR_M), jnp.float32(0.0), jnp.float32(0.0), 0.0)
    return humans.step_humans(name, params, field, people, aims, robot, uniforms, group_id)


def desired_speeds(params: SimParams, n: int, rng: np.random.Generator) -> np.ndarray:
    """(n,) the warehouse workers' desired speeds: normal, clipped to their minimum and cap."""
    v = rng.normal(float(params.worker_desired_speed_mean_mps), float(params.worker_desired_speed_std_mps), n)
    return np.clip(v, float(params.worker_desired_speed_min_mps), float(params.worker_max_speed_mps))


# ------------------------------------------------------------------ corridors


def corridor_field(width_m: float, length_m: float) -> Grid:
    """The wall field of a corridor along x, ``y`` from 0 to ``width_m``, long enough for the
    ghosts a corridor length either side."""
    walls = np.array(
        [[-length_m - 2, 2 * length_m + 2, -1.0, 0.0], [-length_m - 2, 2 * length_m + 2, width_m, width_m + 1.0]],
        np.float32,
    )
    return walls_field(walls, (-length_m - 2, 2 * length_m + 2, -1.5, width_m + 1.5), 0.05)


def _starts(n: int, width_m: float, length_m: float, radius_m: float, rng: np.random.Generator,
            lattice: bool = True) -> np.ndarray | None:  # fmt: skip
    """(n, 2) starts spread over the corridor: uniform at random, no two bodies closer than
    ``2 radius + 5 cm`` (periodic along x); where random placement cannot fit everyone (dense
    crowds: random discs jam at about 55 % of the area), a lattice with as much jitter as the
    cells leave (None without ``lattice``). A lattice alone puts a thin crowd in single file, which
    a model without lateral motion then never leaves; its number of rows follows from the radius,
    and a model whose people keep their lanes keeps them (:func:`packed_starts` has none)."""
    gap = 2 * radius_m + 0.05
    lo, hi = radius_m + 0.05, width_m - radius_m - 0.05
    placed = np.zeros((0, 2))
    for _ in range(50 * n):
        if len(placed) == n:
            return placed
        p = np.array([rng.uniform(0, length_m), rng.uniform(lo, hi)])
        d = placed - p
        d[:, 0] = (d[:, 0] + length_m / 2) % length_m - length_m / 2
        if not len(placed) or np.min(np.hypot(d[:, 0], d[:, 1])) >= gap:
            placed = np.vstack([placed, p])
    if not lattice:
        return None
    rows = max(1, int(np.floor((hi - lo) / gap)) + 1)
    cols = -(-n // rows)
    gx = (np.arange(cols) + 0.5) * length_m / cols
    gy = lo + (np.arange(rows) + 0.5) * (hi - lo) / rows
    xy = np.stack(np.meshgrid(gx, gy), -1).reshape(-1, 2)[rng.permutation(rows * cols)[:n]]
    room = np.array([max(0.0, length_m / cols - gap), max(0.0, (hi - lo) / rows - gap)]) / 2
    return xy + rng.uniform(-1, 1, xy.shape) * room


def packed_starts(n: int, width_m: float, length_m: float, radius_m: float, rng: np.random.Generator,
                  iterations: int = 3000) -> np.ndarray:  # fmt: skip
    """(n, 2) starts spread over the corridor as :func:`_starts`'s, with a disordered packing where
    random placement cannot fit everyone: everyone placed uniformly at random, then every pair
    closer than ``2 radius + 5 cm`` pushed apart (periodic along x, the walls' margins kept) until
    none is (the relaxation of a soft-disc packing). Unlike a lattice its people are in no rows, so
    another ``rng`` draws another arrangement; where even this cannot fit everyone in ``iterations``
    (past random close packing) it is :func:`_starts`'s lattice."""
    gap = 2 * radius_m + 0.05
    lo, hi = radius_m + 0.05, width_m - radius_m - 0.05
    spread = _starts(n, width_m, length_m, radius_m, rng, lattice=False)
    if spread is not None:
        return spread
    xy = np.stack([rng.uniform(0, length_m, n), rng.uniform(lo, hi, n)], -1)
    for _ in range(iterations):
        d = xy[:, None, :] - xy[None, :, :]
        d[..., 0] = (d[..., 0] + length_m / 2) % length_m - length_m / 2
        dist = np.hypot(d[..., 0], d[..., 1])
        np.fill_diagonal(dist, np.inf)
        deficit = np.maximum(gap - dist, 0.0)
        if deficit.max() < 1e-4:
            return xy
        # Each of a pair moves half the deficit, a little further so that a packing near its limit
        # does not creep; a pair at one point is parted along y.
        push = np.where(dist[..., None] > 1e-9, d / np.maximum(dist, 1e-9)[..., None], np.array([0.0, 1.0]))
        xy = xy + 0.55 * (deficit[..., None] * push).sum(axis=1)
        xy[:, 0] %= length_m
        xy[:, 1] = np.clip(xy[:, 1], lo, hi)
    return _starts(n, width_m, length_m, radius_m, rng)


def periodic_step(name: str, params, field, direction, speed, length_m: float, group_id=None):
    """``step((xy, v, laps), key) -> (xy, v, laps)``: one step of N people (``xy``, ``v`` (N, 2))
    in a periodic corridor along x, their ghosts a length either side; ``laps`` (N,) counts wraps;
    ``group_id`` (N,) who walks together (their ghosts walk alone), None: nobody."""
    n = direction.shape[0]
    moving = jnp.arange(3 * n) < n
    present = jnp.ones(3 * n, bool)
    shift = jnp.array([length_m, 0.0], jnp.float32)
    groups_all = None if group_id is None else jnp.concatenate([group_id, jnp.full(2 * n, groups.ALONE, jnp.int32)])

    def step(carry, key):
        xy, v, laps = carry
        all_xy = jnp.concatenate([xy, xy - shift, xy + shift])
        all_v = jnp.concatenate([v, v, v])
        aim = jnp.tile(direction, 3) * 10.0
        u = jax.random.uniform(key, (2, 3 * n), minval=1e-6, maxval=1.0)
        everyone = Walkers.of(all_xy, all_v, present, moving)
        speeds = jnp.tile(speed, 3)
        aims = Aims(aim, jnp.zeros(3 * n), speeds, speeds)  # the social force's cap: the desired speed
        after = model_step(name, params, field, everyone, aims, (u[0], u[1]), groups_all)
        x, y, vx, vy = after.x_m[:n], after.y_m[:n], after.vx_mps[:n], after.vy_mps[:n]
        wrap = jnp.floor(x / length_m)
        laps = laps + jnp.abs(wrap).astype(jnp.int32)
        return (jnp.stack([x - wrap * length_m, y], -1), jnp.stack([vx, vy], -1), laps)

    return step


def periodic_start(direction, speed, xy0):
    """The carry of :func:`periodic_step` at the start: everyone at their desired speed."""
    v0 = direction[:, None] * jnp.stack([speed, jnp.zeros_like(speed)], -1)
    return (xy0, v0, jnp.zeros(xy0.shape[0], jnp.int32))


@functools.partial(jax.jit, static_argnames=("name", "n_steps", "length_m"))
def _run_periodic(name: str, params, field, xy0, direction, speed, key, n_steps: int, length_m: float):
    """(T, N, 2) positions and (T, N) laps of N people in a periodic corridor along x."""
    step = periodic_step(name, params, field, direction, speed, length_m)

    def scan_step(carry, key):
        new = step(carry, key)
        return new, (new[0], new[2])

    _, (xy, laps) = jax.lax.scan(scan_step, periodic_start(direction, speed, xy0), jax.random.split(key, n_steps))
    return xy, laps


def corridor_run(
    model: HumanModel,
    density_per_m2: float,
    width_m: float = 1.8,
    length_m: float = 20.0,
    seconds: float = 60.0,
    counterflow: bool = False,
    seed: int = 0,
    packed: bool = False,
):
    """A periodic corridor at ``density_per_m2``: ``(rows, direction_of)``, ``rows`` the
    ``person, frame, x_m, y_m`` of every step (a person's id renewed when they wrap round),
    ``direction_of`` id -> +1 or -1. ``counterflow``: every other person walks the other way.
    ``packed``: a dense crowd starts in :func:`packed_starts`'s disordered packing, not in
    :func:`_starts`'s lattice."""
    rng = np.random.default_rng(seed)
    n = max(2, int(round(density_per_m2 * width_m * length_m)))
    xy0 = (packed_starts if packed else _starts)(n, width_m, length_m, model.radius_m, rng)
    direction = np.where(rng.permutation(n) % 2 == 1, -1.0, 1.0) if counterflow else np.ones(n)
    speed = desired_speeds(model.crowd, n, rng)
    n_steps = int(round(seconds / model.dt_s))
    xy, laps = _run_periodic(model.name, model.params, corridor_field(width_m, length_m), jnp.asarray(xy0, jnp.float32),
                             jnp.asarray(direction, jnp.float32), jnp.asarray(speed, jnp.float32),
                             jax.random.key(seed), n_steps, float(length_m))  # fmt: skip
    xy, laps = np.asarray(xy), np.asarray(laps)
    person = (np.arange(n)[None, :] + n * laps).reshape(-1)
    rows = pd.DataFrame(
        {
            "person": person,
            "frame": np.repeat(np.arange(1, n_steps + 1), n),
            "x_m": xy[..., 0].reshape(-1).astype(float),
            "y_m": xy[..., 1].reshape(-1).astype(float),
        }
    )
    direction_of = dict(zip(person, np.tile(direction, n_steps), strict=True))
    return rows, direction_of


def data_fundamental_diagram(runs=UO_RUNS) -> pd.DataFrame:
    """``run, frame, density, speed`` of the Jülich uni-directional runs' steady states."""
    return pd.concat([_run_fundamental_diagram(run) for run in runs], ignore_index=True)


@functools.lru_cache(maxsize=len(UO_RUNS))
@datacache.kept
def _run_fundamental_diagram(run: str) -> pd.DataFrame:
    """One run's steady-state points (PedPy's Voronoi method, a few seconds a run). Cached: the
    data never changes within a process, and a validation, a calibration and a notebook each ask
    for the same runs; callers get a new frame from :func:`data_fundamental_diagram`'s concat.
    Kept on disk between processes too (:mod:`evaluation.humans.datacache`)."""
    info = recorded.run_info(run)
    g = info["geometry"]
    points = measures.voronoi_density_speed(
        recorded.trajectories(run), info["frames_per_s"], g["walkable_polygon_m"], g["measurement_area_m"],
        g["walking_direction"], frames=tuple(info["steady_state_frames"]),
    )  # fmt: skip
    return points.assign(run=run)


def _corridor_measure(rows, width_m, length_m, frames_per_s, warmup_s, direction=(1.0, 0.0)):
    """Density and speed in 2 m at the middle of a simulated corridor, after ``warmup_s``."""
    middle = length_m / 2
    return measures.voronoi_density_speed(
        rows, frames_per_s, [[0, 0], [length_m, 0], [length_m, width_m], [0, width_m]],
        [[middle - 1, 0], [middle + 1, 0], [middle + 1, width_m], [middle - 1, width_m]], direction,
        frames=(int(round(warmup_s * frames_per_s)), int(rows["frame"].max())),
    )  # fmt: skip


def model_fundamental_diagram(
    model: HumanModel,
    densities=measures.DENSITY_BINS,
    width_m: float = 1.8,
    length_m: float = 20.0,
    seconds: float = 60.0,
    warmup_s: float = 20.0,
    seed: int = 0,
    packed: bool = False,
):
    """``(points, overlaps)``: ``density_target, frame, density, speed`` of the model in the
    periodic corridor at each density, and its bodies' overlaps there (one row a density).
    ``packed``: dense crowds start disordered (:func:`corridor_run`)."""
    points, bodies = [], []
    for k, rho in enumerate(densities):
        rows, _ = corridor_run(model, rho, width_m, length_m, seconds, seed=seed + k, packed=packed)
        measured = _corridor_measure(rows, width_m, length_m, 1.0 / model.dt_s, warmup_s)
        points.append(measured.assign(density_target=rho))
        late = rows[rows["frame"] >= warmup_s / model.dt_s]
        bodies.append({"density_target": rho, **measures.overlaps(late[late["frame"] % 10 == 0], model.radius_m)})
    return pd.concat(points, ignore_index=True), pd.DataFrame(bodies)


# ------------------------------------------------------------------ counterflow


@datacache.kept
def data_counterflow(run: str = COUNTERFLOW_RUN) -> dict:
    """The bi-directional run's ``density`` (persons/m²), ``speed_mps`` (mean speed along each
    person's own direction) in its measurement area and ``lane_order``, over the frames where the
    area's density is within 20 % of its median (the steady part). Kept on disk between processes
    (:mod:`evaluation.humans.datacache`: every frame's Voronoi cells, half a minute)."""
    info = recorded.run_info(run)
    g = info["geometry"]
    rows = recorded.trajectories(run)
    direction_of = _directions(rows)
    flipped = rows.assign(x_m=rows["x_m"] * rows["person"].map(direction_of))
    area = np.array(g["measurement_area_m"], float)
    box = (area[:, 0].min(), area[:, 0].max(), area[:, 1].min(), area[:, 1].max())
    dens = measures.voronoi_density_speed(
        rows, info["frames_per_s"], g["walkable_polygon_m"], g["measurement_area_m"], None, g["obstacles_m"]
    )
    steady = dens[np.abs(dens["density"] - dens["density"].median()) < 0.2 * dens["density"].median()]
    frames = set(steady["frame"])
    return {
        "density": float(steady["density"].mean()),
        "speed_mps": _own_direction_speed(flipped, box, info["frames_per_s"], frames),
        "lane_order": measures.lane_order(rows[rows["frame"].isin(frames)], direction_of, box),
    }


def model_counterflow(
    model: HumanModel, density_per_m2: float, width_m: float = 4.1, length_m: float = 20.0,
    seconds: float = 60.0, warmup_s: float = 20.0, seed: int = 0,
) -> dict:  # fmt: skip
    """The model's counterflow in a periodic corridor: ``density``, ``speed_mps``,
    ``lane_order`` (measured as :func:`data_counterflow` measures the run)."""
    rows, direction_of = corridor_run(model, density_per_m2, width_m, length_m, seconds, counterflow=True, seed=seed)
    late = rows[rows["frame"] >= warmup_s / model.dt_s]
    late = late[late["frame"] % 2 == 0]
    middle = length_m / 2
    box = (middle - 1.0, middle + 1.0, 0.0, width_m)
    flipped = late.assign(x_m=late["x_m"] * late["person"].map(direction_of))
    frames = set(late["frame"])
    return {
        "density": density_per_m2,
        "speed_mps": _own_direction_speed(flipped, box, 1.0 / model.dt_s, frames, length_m),
        "lane_order": measures.lane_order(late, direction_of, box),
        **measures.overlaps(late[late["frame"] % 10 == 0], model.radius_m),
    }


def _directions(rows: pd.DataFrame) -> dict:
    """person -> +1 or -1: the sign of their net displacement along x."""
    ends = rows.groupby("person")["x_m"].agg(["first", "last"])
    return dict(zip(ends.index, np.where(ends["last"] >= ends["first"], 1.0, -1.0), strict=True))


def _own_direction_speed(flipped, box, frames_per_s, frames, period_m: float | None = None) -> float:
    """Mean speed along each person's own direction (``flipped``: x multiplied by it) over the
    positions inside ``box`` in ``frames``, from positions 0.3 s apart."""
    step = max(1, round(0.3 * frames_per_s))
    speeds = []
    for _, g in flipped.groupby("person", sort=False):
        g = g.sort_values("frame")
        x, f = g["x_m"].to_numpy(), g["frame"].to_numpy()
        if len(x) <= step:
            continue
        dx = x[step:] - x[:-step]
        if period_m is not None:
            dx = (dx + period_m / 2) % period_m - period_m / 2
        dt = (f[step:] - f[:-step]) / frames_per_s
        ok = dt > 0
        speeds.append((dx / np.where(ok, dt, 1.0))[ok])
    del box, frames  # the corridor is uniform along x: every position counts
    return float(np.concatenate(speeds).mean()) if speeds else float("nan")


# ------------------------------------------------------------------ ETH/UCY prediction


def eth_ucy_windows(rows: pd.DataFrame):
    """The prediction samples of one split: for every file and every frame at which someone is
    present for 20 consecutive frames, ``(observed (W, P, 8, 2), future (W, P, 12, 2),
    complete (W, P) bool, present (W, P) bool)``: the P people present at the last observed frame
    and the one before it (the others in the crowd), of whom ``complete`` are present in all 20
    frames (the ones scored), and ``frame_s`` (W,) the seconds between two samples (the run's).
    Positions of frames a person is absent are NaN."""
    observed, future, complete, present, frame_s = [], [], [], [], []
    for _, g in rows.groupby("run", sort=False):
        step = int(np.median(np.diff(np.unique(g["frame"].to_numpy()))))
        seconds = float(np.median(np.diff(np.unique(g["t_s"].to_numpy()))))
        index = ((g["frame"] - g["frame"].min()) // step).to_numpy()
        people = {p: k for k, p in enumerate(np.unique(g["person"]))}
        grid = np.full((index.max() + 1, len(people), 2), np.nan)
        grid[index, g["person"].map(people).to_numpy()] = g[["x_m", "y_m"]].to_numpy()
        span = PREDICT_OBSERVED + PREDICT_FRAMES
        for start in range(grid.shape[0] - span + 1):
            window = grid[start : start + span]
            seen = ~np.isnan(window[..., 0])
            here = seen[PREDICT_OBSERVED - 1] & seen[PREDICT_OBSERVED - 2]
            scored = seen.all(axis=0)
            if not scored.any():
                continue
            observed.append(window[:PREDICT_OBSERVED, here].transpose(1, 0, 2))
            future.append(window[PREDICT_OBSERVED:, here].transpose(1, 0, 2))
            complete.append(scored[here])
            present.append(np.ones(here.sum(), bool))
            frame_s.append(seconds)
    p = max(len(c) for c in complete)
    pad = lambda a, fill: np.stack([np.concatenate([x, np.full((p - len(x), *x.shape[1:]), fill)]) for x in a])
    return pad(observed, np.nan), pad(future, np.nan), pad(complete, False), pad(present, False), np.array(frame_s)


def _sample_steps(frame_s: float, dt_s: float) -> tuple[int, np.ndarray, np.ndarray]:
    """How to read 12 samples ``frame_s`` apart off a path stepped every ``dt_s``: ``(steps, lo,
    frac)``, the sample ``k`` at ``path[lo[k]] * (1 - frac[k]) + path[lo[k] + 1] * frac[k]``
    (``path[i]`` is at ``(i + 1) * dt_s``). Where ``frame_s`` is a multiple of ``dt_s`` every
    ``frac`` is 0 and the samples are steps of the path."""
    at = np.arange(1, PREDICT_FRAMES + 1) * frame_s / dt_s - 1.0
    lo = np.floor(at + 1e-6).astype(int)
    frac = np.where(at - lo < 1e-6, 0.0, at - lo)
    return int(lo[-1] + (frac[-1] > 0) + 1), lo, frac.astype(np.float32)


def _predict(name: str, params, field, xy, v, aim, speed, present, key, frame_s: float, dt_s: float, group_id=None):
    """(P, 12, 2) positions of one window's people stepped by the model from ``xy``, ``v``
    (``aim(xy) -> (P, 2)``: where each is heading; ``group_id`` (P,) who walks together), read
    every ``frame_s`` seconds off the path stepped every ``dt_s`` (:func:`_sample_steps`)."""

    def step(carry, k):
        xy, v = carry
        u = jax.random.uniform(k, (2, xy.shape[0]), minval=1e-6, maxval=1.0)
        to = aim(xy)
        people = Walkers.of(xy, v, present, present & (speed > 0.0))
        after = model_step(name, params, field, people, Aims(to[:, 0], to[:, 1], speed, speed), (u[0], u[1]), group_id)
        return (after.xy_m, after.velocity_mps), after.xy_m

    steps, lo, frac = _sample_steps(frame_s, dt_s)
    _, path = jax.lax.scan(step, (xy, v), jax.random.split(key, steps))
    if not frac.any():
        return path[lo].transpose(1, 0, 2)
    w = frac[:, None, None]
    return (path[lo] * (1.0 - w) + path[np.minimum(lo + 1, steps - 1)] * w).transpose(1, 0, 2)


def _open_field() -> Grid:
    """A field with no wall near (ETH/UCY ships no walls): every person far from every wall."""
    values = np.zeros((2, 2, 3), np.float32)
    values[..., 0] = FAR_M
    values[..., 1] = 1.0
    return Grid.of_samples(jnp.asarray(values), -FAR_M, -FAR_M, 2 * FAR_M)


@struct.dataclass
class PredictionWindows:
    """The samples of one ETH/UCY split, ready to step (:func:`prediction_windows`); (W, P, ...)
    arrays, P padded: ``start`` the last observed position (absent people far away),
    ``velocity`` the last observed one (m/s), ``speed`` its norm, ``present``, ``goal`` the true
    final position of a scored person (else the constant-velocity one), ``group_id`` who walked
    together over the observed frames, ``future`` (W, P, 12, 2) the truth (0 where a person is
    absent: only the ``complete`` count), ``complete`` who is scored, ``constant_velocity``
    (W, P, 12, 2) the baseline's prediction, ``frame_s`` (W floats) the seconds between two
    samples; ``walls`` the recording's wall field (a :class:`~jaxsim.grid.Grid` of signed distance
    and normal, :func:`walls_field`), or None: open ground, as ETH/UCY ships no walls."""

    start: np.ndarray
    velocity: np.ndarray
    speed: np.ndarray
    present: np.ndarray
    goal: np.ndarray
    group_id: np.ndarray
    future: np.ndarray
    complete: np.ndarray
    constant_velocity: np.ndarray
    # static (a tuple of floats): a calibration passes the windows through jit, and the steps a
    # window's horizon takes are part of the program
    frame_s: tuple = struct.field(pytree_node=False, default=())
    walls: Grid | None = None

    def take(self, index, bucket: int = 16) -> PredictionWindows:
        """The windows at ``index`` (an index array or slice), their people cut to the most any
        of them has, rounded up to a multiple of ``bucket`` (the people are padded at the end;
        the rounding bounds the shapes a jit compiles for)."""
        people = int(np.asarray(self.present)[index].sum(axis=1).max(initial=1))
        keep = min(self.start.shape[1], -(-people // bucket) * bucket)
        arrays = (getattr(self, f.name)[index][:, :keep] for f in dataclasses.fields(self) if f.name not in _WHOLE)
        return PredictionWindows(*arrays, tuple(np.asarray(self.frame_s)[index].tolist()), self.walls)


_WHOLE = ("frame_s", "walls")  # PredictionWindows' fields that are not (W, P, ...) arrays


def walls_field(boxes_m, bounds_m, resolution_m: float = 0.05) -> Grid | None:
    """The wall field of wall boxes ``boxes_m`` ((K, 4) xmin, xmax, ymin, ymax) over ``bounds_m``
    (xmin, xmax, ymin, ymax), as the corridors' (:func:`corridor_field`); None without a box."""
    if not len(boxes_m):
        return None
    field = geometry.build_distance_field(np.asarray(boxes_m, np.float32), tuple(bounds_m), resolution_m)
    values = np.stack([field.sdf_m, field.normal_x, field.normal_y], axis=-1)
    return Grid.of_samples(jnp.asarray(values), float(field.origin_m[0]), float(field.origin_m[1]), resolution_m)


@functools.lru_cache(maxsize=16)
def prediction_windows(scene: str, split: str = "test", reach_m: float = 1.0) -> PredictionWindows:
    """:class:`PredictionWindows` of ``scene``'s ``split`` (:func:`eth_ucy_windows`); walking
    groups detected within ``reach_m`` (:func:`evaluation.humans.measures.walking_groups`).
    Cached: a validation scores every model three ways on each test split (read-only arrays)."""
    return windows_of(recorded.eth_ucy_split(scene, split), reach_m)


def windows_of(rows, reach_m: float = 1.0) -> PredictionWindows:
    """:class:`PredictionWindows` of trajectory ``rows`` (:func:`socialnav.data.recorded.trajectories`'
    table, any recordings), read-only."""
    observed, future, complete, present, frame_s = eth_ucy_windows(rows)
    last, before = observed[:, :, -1], observed[:, :, -2]
    velocity = np.nan_to_num((last - before) / frame_s[:, None, None])
    horizon = frame_s[:, None] * np.arange(1, PREDICT_FRAMES + 1)  # (W, 12) s
    cv = last[:, :, None, :] + velocity[:, :, None, :] * horizon[:, None, :, None]
    start = np.nan_to_num(last, nan=FAR_M)
    goal = np.where(complete[..., None], np.nan_to_num(future[:, :, -1]), start + velocity * horizon[:, -1, None, None])
    windows = PredictionWindows(start.astype(np.float32), velocity.astype(np.float32),
                                np.linalg.norm(velocity, axis=-1).astype(np.float32), present,
                                goal.astype(np.float32), measures.walking_groups(observed, reach_m),
                                np.nan_to_num(future), complete, cv, tuple(frame_s.tolist()))  # fmt: skip
    for f in dataclasses.fields(windows):
        if f.name not in _WHOLE:
            getattr(windows, f.name).setflags(write=False)  # shared by the cache
    return windows


def window_predictor(name: str, dt_s: float, aim: str = "velocity", groups: bool = False):
    """``predict(params, windows, key) -> (W, P, 12, 2)``: human model ``name`` stepped
    from each window's last observed frame (``aim``: along the last velocity, or at the true
    ``"destination"``), walking groups felt if ``groups``; pure and jit-able, so a loss over it
    differentiates with respect to ``params`` (:class:`~jaxsim.humans.HumanParams`). Windows
    of one sample interval are stepped together, each interval for its own 12 samples (a batch of
    ETH/UCY's 0.4 s windows does not pay for biwi_eth's 8 s horizon)."""
    open_ground = _open_field()

    def one(params, field, xy, v, s, here, g, gid, key, frame_s):
        along = lambda p: v * 10.0 / jnp.maximum(jnp.linalg.norm(v, axis=-1, keepdims=True), 1e-6)
        towards = lambda p: g - p
        return _predict(name, params, field, xy, v, along if aim == "velocity" else towards, s, here, key, frame_s,
                        dt_s, gid if groups else None)  # fmt: skip

    @functools.partial(jax.jit, static_argnames="frame_s")
    def batched(params, field, start, velocity, speed, present, goal, group_id, key, frame_s):
        keys = jax.random.split(key, start.shape[0])
        return jax.vmap(functools.partial(one, frame_s=frame_s), in_axes=(None, None, 0, 0, 0, 0, 0, 0, 0))(
            params, field, start, velocity, speed, present, goal, group_id, keys)  # fmt: skip

    def predict(params, w: PredictionWindows, key):
        field = open_ground if w.walls is None else w.walls
        intervals = np.unique(np.asarray(w.frame_s))
        if len(intervals) == 1:
            return batched(params, field, w.start, w.velocity, w.speed, w.present, w.goal, w.group_id, key,
                           frame_s=float(intervals[0]))  # fmt: skip
        parts, order = [], []
        for k, interval in enumerate(intervals):
            index = np.flatnonzero(np.asarray(w.frame_s) == interval)  # static; the arrays may be traced
            part = (w.start[index], w.velocity[index], w.speed[index], w.present[index], w.goal[index],
                    w.group_id[index])  # fmt: skip
            parts.append(batched(params, field, *part, jax.random.fold_in(key, k), frame_s=float(interval)))
            order.append(index)
        return jnp.concatenate(parts)[np.argsort(np.concatenate(order))]

    return predict


def eth_ucy_prediction(
    model: HumanModel | None, scene: str, aim: str = "velocity", seed: int = 0, groups: bool = False,
    reach_m: float = 1.0, split: str = "test", per_person: bool = False,
) -> dict:  # fmt: skip
    """ADE and FDE (m) of one scene's ``split`` (the test split unless asked): ``model`` None is
    constant velocity (the last observed displacement carried on); else the model from the last
    observed frame, every person aimed along their last observed velocity (``aim="velocity"``) or
    at their true final position (``aim="destination"``), at their last observed speed; with
    ``groups``, the people who walked together over the observed frames
    (:func:`evaluation.humans.measures.walking_groups` within ``reach_m``) walk on as groups
    (:mod:`jaxsim.groups`). Returns ``ade_m``, ``fde_m``, ``samples``, ``grouped`` (the share of
    scored people in a group); for a model also ``ade_vs_cv_m`` and ``fde_vs_cv_m``, its error
    minus constant velocity's on the same people, with a 95 % interval ``..._low_m``,
    ``..._high_m`` (:func:`evaluation.humans.measures.paired_difference`); with ``per_person``
    also ``per_person``: ``{"ade": (model's, constant velocity's, window), "fde": ...}``, each
    scored person's errors and window, what the interval is drawn from."""
    return prediction_scores(model, prediction_windows(scene, split, reach_m), aim, seed, groups, per_person)


def prediction_scores(
    model: HumanModel | None, w: PredictionWindows, aim: str = "velocity", seed: int = 0, groups: bool = False,
    per_person: bool = False,
) -> dict:  # fmt: skip
    """:func:`eth_ucy_prediction`'s figures for any windows ``w`` (:func:`windows_of`: a shipped
    split, or a user's recording)."""
    if model is None:
        predicted = w.constant_velocity
    else:
        predict = window_predictor(model.name, model.dt_s, aim, groups)
        predicted = np.asarray(predict(model.params, w, jax.random.key(seed)))
    ade, fde = measures.ade_fde(predicted[w.complete], w.future[w.complete])
    out = {"ade_m": float(ade.mean()), "fde_m": float(fde.mean()), "samples": int(w.complete.sum()),
           "grouped": float((w.group_id[w.complete] >= 0).mean())}  # fmt: skip
    if model is not None:
        ade_cv, fde_cv = measures.ade_fde(w.constant_velocity[w.complete], w.future[w.complete])
        window = np.nonzero(w.complete)[0]  # the window of each scored person, in the order above
        for name, error, baseline in (("ade", ade, ade_cv), ("fde", fde, fde_cv)):
            d, low, high = measures.paired_difference(error, baseline, window, seed=seed)
            out.update({f"{name}_vs_cv_m": d, f"{name}_vs_cv_low_m": low, f"{name}_vs_cv_high_m": high})
        if per_person:
            out["per_person"] = {"ade": (ade, ade_cv, window), "fde": (fde, fde_cv, window)}
    return out


# ------------------------------------------------------------------ the report


# The bar a human model passes (issue 61): speed inside the data's mean +- 1 s.d. in every
# density bin, no overlap deeper than 0.1 m, ahead of constant velocity on ETH/UCY (average, and
# in at least four of five scenes), with its destination ADE <= 0.30 m, and counterflow speed
# within 15 % of the run's and lane order >= 0.9.
MAX_OVERLAP_M = 0.1
DESTINATION_ADE_M = 0.30
COUNTERFLOW_SPEED_TOLERANCE = 0.15
LANE_ORDER_MIN = 0.9


def data_agreement(points: pd.DataFrame, train_runs=FD_TRAIN_RUNS, test_runs=FD_TEST_RUNS,
                   min_frames: int = measures.MIN_BIN_FRAMES) -> dict:  # fmt: skip
    """How well the Jülich runs pass the diagram's check themselves: the ceiling a model's score
    is read against.

    ``points``: ``run, density, speed`` of at least ``train_runs`` and ``test_runs``. Two readings,
    each bin of a run counted where it holds ``min_frames`` frames (the calibration's rule):

    * ``training_runs``: the training runs' pooled bins scored as a model is, against the test
      runs' band (what a model that walked exactly as the training runs walk would score);
    * ``each_run``: every run's bins against the band of the other runs pooled.

    Each: ``inside`` and ``of`` (bins), ``z2_mean`` (mean squared distance in standard
    deviations); ``each_run`` also ``runs`` (run -> ``"k of n"``)."""

    def band(runs):  # the runs' pooled bins, as the check's band
        return measures.binned(points[points["run"].isin(list(runs))])

    def bins_of(runs):  # the runs' pooled bins with enough frames, as a model's
        b = band(runs)
        return b[b["n"] >= min_frames]

    training = measures.against_band(bins_of(train_runs), band(test_runs))
    runs = list(train_runs) + list(test_runs)
    each = {r: measures.against_band(bins_of([r]), band([o for o in runs if o != r])) for r in runs}
    every = pd.concat(each.values(), ignore_index=True)
    return {
        "training_runs": measures.band_score(training),
        "each_run": {
            **measures.band_score(every),
            "runs": {r: f"{int(b['inside'].sum())} of {len(b)}" for r, b in each.items()},
        },
    }


def reference(progress=lambda what: None, fd_runs=FD_TEST_RUNS) -> dict:
    """The data's side of every test (the same for every model): ``fd_points``, ``fd_bins``
    (the Jülich ``fd_runs``: by default the test runs, which no calibration reads),
    ``fd_agreement`` (:func:`data_agreement` of all nine runs: how well the data passes the
    diagram's check itself), ``counterflow`` (the bi-directional run), ``constant_velocity`` (a
    frame of scene, ade_m, fde_m, samples)."""
    progress("the Jülich corridors (PedPy's Voronoi method)")
    points = data_fundamental_diagram(fd_runs)
    agreement = data_agreement(data_fundamental_diagram(FD_TRAIN_RUNS + FD_TEST_RUNS))
    progress("the bi-directional run")
    counter = data_counterflow()
    progress("constant velocity on ETH/UCY")
    cv = pd.DataFrame([{"scene": s, **eth_ucy_prediction(None, s)} for s in recorded.ETH_UCY_SCENES])
    return {"fd_points": points, "fd_bins": measures.binned(points), "fd_agreement": agreement, "counterflow": counter,
            "constant_velocity": cv}  # fmt: skip


def validate(
    model: HumanModel,
    data: dict,
    quick: bool = False,
    seed: int = 0,
    progress=lambda what: None,
    label: str = "",
    start_draws: int = 0,
) -> dict:
    """One model against ``data`` (:func:`reference`): its tables and the headline checks.

    ``quick``: shorter corridors (10 m, 30 s after 10 s) for a first look; the report says so.
    ``start_draws``: the diagram measured that many times more, each from another draw of the
    corridors' people with dense crowds in a disordered packing (:func:`packed_starts`), to show
    how much the check's verdict owes to the start (a model whose people keep the lanes they start
    in walks as fast as its lattice's rows let it). The checks stay those of the first diagram.
    Returns ``fd_points``, ``fd_bins``, ``bodies``, ``prediction`` (scene, aim, ade_m, fde_m; aim
    ``velocity``, ``velocity_groups`` or ``destination``), ``counterflow``, ``checks`` (a dict of
    the bar's numbers and whether each passes; ``eth_ucy_average_vs_cv``: the five-scene
    average's difference from constant velocity with its 95 % interval, ADE and FDE in m
    (:func:`evaluation.humans.measures.mean_paired_difference`), ``eth_ucy_average_clearly_ahead``
    whether both intervals lie below 0; with ``start_draws``, ``fd_start_draws``: each draw's bins
    inside, mean z² and deepest overlap) and ``fd_draws`` (the draws' bins, a ``draw`` column;
    empty without)."""
    size = dict(length_m=10.0, seconds=30.0, warmup_s=10.0) if quick else {}
    label = label or model.name
    progress(f"{label}: the fundamental diagram")
    points, bodies = model_fundamental_diagram(model, seed=seed, **size)
    progress(f"{label}: counterflow")
    counter = model_counterflow(model, data["counterflow"]["density"], seed=seed, **size)
    progress(f"{label}: ETH/UCY prediction")
    rows, along = [], []
    for aim, grouped in (("velocity", False), ("velocity", True), ("destination", False)):
        for scene in recorded.ETH_UCY_SCENES:
            aim_label = f"{aim}_groups" if grouped else aim
            result = eth_ucy_prediction(model, scene, aim, seed, grouped, per_person=True)
            if aim_label == "velocity":
                along.append(result["per_person"])
            rows.append({"scene": scene, "aim": aim_label, **{k: v for k, v in result.items() if k != "per_person"}})
    prediction = pd.DataFrame(rows)
    fd = measures.binned(points)
    verdicts = checks(fd, bodies, prediction, counter, data)
    # the five-scene average's difference from constant velocity, with a 95 % interval
    average = {f"{e}_m": [round(x, 4) for x in measures.mean_paired_difference([a[e] for a in along], seed=seed)]
               for e in ("ade", "fde")}  # fmt: skip
    verdicts["eth_ucy_average_vs_cv"] = average
    verdicts["eth_ucy_average_clearly_ahead"] = bool(measures.clearly_ahead(average["ade_m"][2], average["fde_m"][2]))
    draws, scores, walked = [], [], []  # walked: (draw, 0, seconds since the first began) as each ends
    began = time.perf_counter()
    for draw in range(1, start_draws + 1):
        left = time_left(walked, start_draws)
        progress(f"{label}: the fundamental diagram from disordered start {draw} of {start_draws}{left}")
        drawn, drawn_bodies = model_fundamental_diagram(model, seed=seed + 100 * draw, packed=True, **size)
        walked.append((draw, 0.0, time.perf_counter() - began))
        bins = measures.binned(drawn)
        score = measures.band_score(measures.against_band(bins, data["fd_bins"]))
        draws.append(bins.assign(draw=draw))
        scores.append((score["inside"], score["z2_mean"], float(drawn_bodies["max_depth_m"].max())))
    if start_draws:
        inside, z2, depth = zip(*scores, strict=True)
        verdicts["fd_start_draws"] = {"bins_inside": list(inside), "z2_mean": list(z2), "overlap_max_m": list(depth)}
    return {
        "fd_points": points,
        "fd_bins": fd,
        "fd_draws": pd.concat(draws, ignore_index=True) if draws else pd.DataFrame(columns=[*fd.columns, "draw"]),
        "bodies": bodies,
        "prediction": prediction,
        "counterflow": counter,
        "checks": verdicts,
        "quick": quick,
    }


def checks(fd: pd.DataFrame, bodies: pd.DataFrame, prediction: pd.DataFrame, counter: dict, data: dict) -> dict:
    """The bar's numbers and verdicts (see the constants above)."""
    both = measures.against_band(fd, data["fd_bins"])
    inside = both["inside"]
    cv = data["constant_velocity"].set_index("scene")
    along = prediction[prediction["aim"] == "velocity"].set_index("scene")
    towards = prediction[prediction["aim"] == "destination"].set_index("scene")
    grouped = prediction[prediction["aim"] == "velocity_groups"]
    ahead = (along["ade_m"] < cv["ade_m"]) & (along["fde_m"] < cv["fde_m"])
    # a scene where both intervals of the difference from constant velocity lie below 0 (above 0)
    clearly_ahead = measures.clearly_ahead(along["ade_vs_cv_high_m"], along["fde_vs_cv_high_m"])
    clearly_behind = (along["ade_vs_cv_low_m"] > 0) | (along["fde_vs_cv_low_m"] > 0)
    speed_ratio = counter["speed_mps"] / data["counterflow"]["speed_mps"]
    return {
        "fd_bins_inside_1sd": f"{int(inside.sum())} of {len(both)}",
        "fd_speed_ratio_by_bin": {
            f"{b:g}": round(r, 2)
            for b, r in zip(both["density_bin"], both["speed_mean"] / both["speed_mean_data"], strict=True)
        },
        "fd_z2_mean": measures.band_score(both)["z2_mean"],
        "fd_pass": bool(inside.all() and len(both) == len(measures.DENSITY_BINS)),
        "overlap_max_m": float(bodies["max_depth_m"].max()),
        "overlap_pass": bool(bodies["max_depth_m"].max() <= MAX_OVERLAP_M),
        "eth_ucy_ade_fde": [float(along["ade_m"].mean()), float(along["fde_m"].mean())],
        "constant_velocity_ade_fde": [float(cv["ade_m"].mean()), float(cv["fde_m"].mean())],
        "eth_ucy_groups_ade_fde": [float(grouped["ade_m"].mean()), float(grouped["fde_m"].mean())],
        "eth_ucy_scenes_ahead": int(ahead.sum()),
        "eth_ucy_scenes_clearly_ahead": int(clearly_ahead.sum()),
        "eth_ucy_scenes_clearly_behind": int(clearly_behind.sum()),
        "eth_ucy_vs_cv_by_scene": {
            scene: {
                f"{e}_m": [round(float(row[f"{e}_vs_cv{part}_m"]), 4) for part in ("", "_low", "_high")]
                for e in ("ade", "fde")
            }
            for scene, row in along.iterrows()
        },  # each: the model's error minus constant velocity's, and its 95 % interval
        "eth_ucy_pass": bool(
            along["ade_m"].mean() < cv["ade_m"].mean()
            and along["fde_m"].mean() < cv["fde_m"].mean()
            and ahead.sum() >= 4
        ),
        "destination_ade_m": float(towards["ade_m"].mean()),
        "destination_pass": bool(towards["ade_m"].mean() <= DESTINATION_ADE_M),
        "counterflow_speed_ratio": float(speed_ratio),
        "counterflow_lane_order": float(counter["lane_order"]),
        "counterflow_pass": bool(
            abs(speed_ratio - 1) <= COUNTERFLOW_SPEED_TOLERANCE and counter["lane_order"] >= LANE_ORDER_MIN
        ),
    }
