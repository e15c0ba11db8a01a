"""From simulator logs to the per-waypoint datasets J-PCMCI+ expects.

The logs are read through their written contract (:mod:`common.logschema`: file and column
names), not through the simulator, which this package never imports.

For every world and every kept waypoint ``w`` one dataset (T, 7) holds, sample by sample,
``V`` (robot speed), ``L`` (battery change since the previous kept sample), ``D`` (Eq. 3
density at ``w``), ``W`` (= w, constant), ``S`` (slot), ``C`` (charging) and ``O`` (obstacle),
in the order of :data:`causal.variables.VARIABLES`.

Subsampling follows the paper's Nyquist rule (:func:`nyquist_step`): the highest significant
frequency over the series sets the rate, and nothing coarsens it. J-PCMCI+'s time grows with
its samples, so a sample budget chooses *which datasets* discovery sees
(:func:`discovery_subset`), never the rate: a coarser step would alias the dynamics the rule
keeps (people crossing a waypoint's disc make D broadband, so on the warehouse the rule keeps
every logged second). Waypoints where nobody ever stands carry a constant ``D`` and are dropped
(reported); asking for one by name is an error.
"""

from __future__ import annotations

import dataclasses
import json
import pathlib

import numpy as np
import pandas as pd

from socialnav.causal.variables import VARIABLES
from socialnav.common import logschema
from socialnav.common.logschema import density_column

# The log columns the causal variables come from (all in the schema: the contract test checks it).
LOG_COLUMNS = ("world", "time_s", "slot", "robot_speed_mps", "battery_pct", "charging", "obstacle")
# Share of a series' spectral energy (DC excluded) below its "highest significant frequency".
SIGNIFICANT_ENERGY = 0.95


class LogError(ValueError):
    """The logs cannot give the causal variables; the message names the problem."""


@dataclasses.dataclass(frozen=True)
class Datasets:
    """Per-(world, waypoint) datasets ready for J-PCMCI+.

    Attributes:
      data: {dataset index: (T, 7) float array} in the order of :data:`VARIABLES`.
      waypoints: waypoint name of each dataset, same keys.
      worlds: world id of each dataset.
      step: subsampling step (in logged samples); ``sample_interval_s * step`` is the period.
      nyquist_step: the step the paper's rule asks for (``step`` differs only when given).
      sample_interval_s: the logs' sampling interval.
      dropped_waypoints: waypoints left out because their density never changes.
      frequencies_hz: highest significant frequency found per variable.
    """

    data: dict[int, np.ndarray]
    waypoints: dict[int, str]
    worlds: dict[int, int]
    step: int
    nyquist_step: int
    sample_interval_s: float
    dropped_waypoints: tuple[str, ...]
    frequencies_hz: dict[str, float]

    @property
    def period_s(self) -> float:
        return self.step * self.sample_interval_s


def check_logs(df: pd.DataFrame, waypoints: list[str]) -> None:
    """Raise :class:`LogError` naming the first missing column or unusable series."""
    if df.empty:
        raise LogError("the logs have no rows")
    missing = [c for c in LOG_COLUMNS if c not in df.columns]
    missing += [density_column(w) for w in waypoints if density_column(w) not in df.columns]
    if missing:
        raise LogError(
            f"the logs lack column(s) {', '.join(missing[:5])}"
            f"{' ...' if len(missing) > 5 else ''}: were they written by 'socialnav simulate'?"
        )
    for col, name in [("robot_speed_mps", "V (robot_speed_mps)"), ("battery_pct", "L (from battery_pct)")]:
        if df[col].nunique() < 2:
            raise LogError(f"{name} is constant over the whole log: nothing to learn from it")
    for col, name in [("charging", "C (charging)"), ("obstacle", "O (obstacle)")]:
        if df[col].nunique() < 2:
            raise LogError(
                f"context {name} is constant over the whole log (the robot never "
                f"{'charged' if col == 'charging' else 'met an obstacle'}): simulate longer or "
                f"drop the variable"
            )


def highest_frequency_hz(x: np.ndarray, dt_s: float, energy: float = SIGNIFICANT_ENERGY) -> float:
    """Smallest frequency below which ``energy`` of the series' (non-DC) spectral energy lies."""
    x = np.asarray(x, np.float64)
    x = x - x.mean()
    power = np.abs(np.fft.rfft(x)) ** 2
    power[0] = 0.0
    total = power.sum()
    if total <= 0:
        return 0.0
    freqs = np.fft.rfftfreq(len(x), dt_s)
    k = int(np.searchsorted(np.cumsum(power) / total, energy))
    return float(freqs[min(k, len(freqs) - 1)])


# Samples a world's series keeps after subsampling, at least: J-PCMCI+ at tau_max 1 regresses on
# the previous sample and the contexts, and its partial correlations need some dozens of points.
MIN_SERIES_SAMPLES = 20


def nyquist_step(
    series: dict[str, np.ndarray], dt_s: float, energy: float = SIGNIFICANT_ENERGY
) -> tuple[int, dict[str, float]]:
    """Subsampling step by the paper's rule: sample at ``>= 2 x`` the highest significant frequency.

    Returns:
      (step in samples, highest significant frequency per series).
    """
    freqs = {k: highest_frequency_hz(v, dt_s, energy) for k, v in series.items()}
    f_max = max(freqs.values())
    if f_max <= 0:
        return 1, freqs
    step = int(np.floor(1.0 / (2.0 * f_max * dt_s)))
    return max(step, 1), freqs


def build_datasets(
    df: pd.DataFrame,
    waypoint_names: list[str],
    *,
    waypoints: list[str] | None = None,
    step: int | None = None,
    worlds: list[int] | None = None,
    energy: float = SIGNIFICANT_ENERGY,
) -> Datasets:
    """Per-(world, waypoint) datasets from a log table.

    Args:
      df: the log (``pandas.read_parquet(logs.parquet)``).
      waypoint_names: all waypoint names of the scenario (index = W's value).
      waypoints: waypoints to keep (default: every waypoint whose density ever changes).
      step: subsampling step in samples (default: :func:`nyquist_step` over V, L, D, C, O of
        the first world). A larger one decimates without a low-pass filter.
      worlds: world ids to use (default: all).
    """
    if worlds is not None:
        missing = sorted(set(worlds) - set(df.world.unique()))
        if missing:
            raise LogError(f"world(s) {missing} are not in the logs")
        df = df[df.world.isin(worlds)]
    wanted = list(waypoint_names) if waypoints is None else list(waypoints)
    unknown = [w for w in wanted if w not in waypoint_names]
    if unknown:
        raise LogError(f"unknown waypoint(s) {unknown}")
    check_logs(df, wanted)
    df = df.sort_values(["world", "time_s"], kind="stable")
    dropped = [w for w in wanted if df[density_column(w)].nunique() < 2]
    if waypoints is not None and dropped:
        raise LogError(f"waypoint(s) {dropped} are empty: their density D never changes in the logs")
    kept = [w for w in wanted if w not in dropped]
    if not kept:
        raise LogError("no waypoint has a changing density D: were there workers in the simulation?")
    times = df.loc[df.world == df.world.iloc[0], "time_s"].to_numpy()
    dt = float(np.median(np.diff(times))) if len(times) > 1 else 1.0

    first = df[df.world == df.world.iloc[0]]
    robot_l = np.diff(first.battery_pct.to_numpy(np.float64), prepend=first.battery_pct.iloc[0])
    probe = {
        "V": first.robot_speed_mps.to_numpy(),
        "L": robot_l,
        "C": first.charging.to_numpy(float),
        "O": first.obstacle.to_numpy(float),
    }
    densest = max(kept, key=lambda w: first[density_column(w)].var())
    probe["D"] = first[density_column(densest)].to_numpy()
    auto_step, freqs = nyquist_step(probe, dt, energy)
    step = int(auto_step if step is None else step)
    if step < 1:
        raise LogError(f"step must be >= 1, got {step}")
    shortest = int(df.groupby("world", sort=False).size().min())
    if shortest // step < MIN_SERIES_SAMPLES:
        raise LogError(
            f"subsampling step {step} (--step) leaves {shortest // step} sample(s) of the shortest world's "
            f"{shortest}: discovery needs at least {MIN_SERIES_SAMPLES} per world, so a step of at most "
            f"{max(1, shortest // MIN_SERIES_SAMPLES)}"
        )

    data, names, world_of = {}, {}, {}
    index = {w: i for i, w in enumerate(waypoint_names)}
    for world, g in df.groupby("world", sort=True):
        g = g.iloc[::step]
        battery = g.battery_pct.to_numpy(np.float64)
        l_pct = np.diff(battery)  # L_t = B_t - B_{t-1}: the change over the period ending at t
        base = {
            "V": g.robot_speed_mps.to_numpy(np.float64)[1:],
            "L": l_pct,
            "S": g.slot.to_numpy(np.float64)[1:],
            "C": g.charging.to_numpy(np.float64)[1:],
            "O": g.obstacle.to_numpy(np.float64)[1:],
        }
        for w in kept:
            cols = dict(base, D=g[density_column(w)].to_numpy(np.float64)[1:], W=np.full(len(l_pct), float(index[w])))
            k = len(data)
            data[k] = np.stack([cols[v] for v in VARIABLES], axis=1)
            names[k] = w
            world_of[k] = int(world)
    return Datasets(data, names, world_of, step, auto_step, dt, tuple(dropped), freqs)


def discovery_subset(datasets: Datasets, max_samples: int | None) -> list[int]:
    """The datasets discovery runs on: all of them within ``max_samples`` samples, else as many
    as the budget holds (at least 2, so that W varies), evenly spaced over the (world, waypoint)
    order, so over the warehouse and the worlds.

    The graph is one for every dataset (J-PCMCI+'s premise), so a subset at the full rate loses
    no dynamics; the engine's parameters still learn from every dataset.
    """
    keys = sorted(datasets.data)
    total = sum(len(datasets.data[k]) for k in keys)
    if not max_samples or total <= max_samples:
        return keys
    per_dataset = total / len(keys)
    n = min(len(keys), max(2, int(max_samples // per_dataset)))
    return [keys[i] for i in np.unique(np.linspace(0, len(keys) - 1, n).round().astype(int))]


def read_run(logs_dir: str | pathlib.Path, waypoints: list[str] | None = None) -> tuple[pd.DataFrame, dict]:
    """The columns the causal variables need from a run folder, and its metadata.

    Args:
      logs_dir: a folder written by ``socialnav simulate`` (:data:`common.logschema.LOG_FILE` and
        :data:`~common.logschema.META_FILE`).
      waypoints: the waypoints whose density is read (default: every waypoint of the run).

    Raises:
      LogError: a file or a needed column or metadata key is missing, naming it.
    """
    logs_dir = pathlib.Path(logs_dir)
    log_file, meta_file = logs_dir / logschema.LOG_FILE, logs_dir / logschema.META_FILE
    for f in (log_file, meta_file):
        if not f.exists():  # logs.parquet is a folder of parts when the run was sharded
            raise LogError(f"{f} is missing: point --logs at a folder written by 'socialnav simulate'")
    try:
        meta = json.loads(meta_file.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as e:
        raise LogError(f"{meta_file}: not valid JSON ({e})") from None
    if not isinstance(meta, dict) or not meta.get("waypoints") or not meta.get("slots"):
        raise LogError(f"{meta_file} lacks the waypoint or slot names")
    columns = list(LOG_COLUMNS) + [density_column(w) for w in (waypoints or meta["waypoints"])]
    import pyarrow.parquet as pq

    try:
        present = set(pq.read_schema(log_file).names)
    except Exception as e:  # pyarrow's errors for an unreadable file have no common base
        raise LogError(f"{log_file}: not a readable Parquet file ({e})") from None
    missing = [c for c in columns if c not in present]
    if missing:
        raise LogError(f"{log_file} lacks column(s) {missing[:5]}{' ...' if len(missing) > 5 else ''}")
    try:
        frame = pd.read_parquet(log_file, columns=columns)
    except Exception as e:  # a truncated or corrupt data page: pyarrow's errors have no common base
        raise LogError(f"{log_file}: not a readable Parquet file ({type(e).__name__}: {e})") from None
    check_values(frame, log_file)
    return frame, meta


def check_values(frame: pd.DataFrame, log_file: pathlib.Path) -> None:
    """Raise :class:`LogError` naming the column at fault: a non-numeric column, NaN or infinite
    values, or a world whose ``time_s`` is not strictly increasing (duplicated or reordered rows)."""
    for column in frame.columns:
        values = frame[column].to_numpy()
        if values.dtype == bool:
            continue
        if not np.issubdtype(values.dtype, np.number):
            raise LogError(f"{log_file}: column {column!r} holds {values.dtype} values, expected numbers")
        bad = ~np.isfinite(values)
        if bad.any():
            row = int(np.argmax(bad))
            raise LogError(
                f"{log_file}: column {column!r} has {int(bad.sum())} NaN or infinite value(s), "
                f"the first at row {row} (world {frame['world'].iloc[row]}, time_s {frame['time_s'].iloc[row]})"
            )
    step = frame.groupby("world", sort=False)["time_s"].diff()
    back = (step <= 0).to_numpy()
    if back.any():
        row = int(np.argmax(back))
        raise LogError(
            f"{log_file}: column 'time_s' is not strictly increasing in world {frame['world'].iloc[row]} "
            f"(time_s {frame['time_s'].iloc[row]} at row {row} after {frame['time_s'].iloc[row] - step.iloc[row]}): "
            "duplicated or reordered rows"
        )
