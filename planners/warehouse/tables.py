"""The causal engine's tables as the planners read them: ``engine_tables.npz``, typed and checked.

The causal pipeline writes the file (``causal.learn``); the planners own this reader, so neither
imports the other: the file is the contract. Keys (arrays):

* ``density_ppm2`` (S, W): E[D | do(S = s), W = w], people / m^2; NaN where the engine has no
  data (a waypoint never learned, a slot never sampled there);
* ``battery_pct_per_s`` (V, 2): E[L | do(V = v), C = c] per second, for each speed bin and
  charging state; NaN where unseen;
* ``speed_edges_mps`` (V + 1,): the speed bins' edges, increasing;
* optional ``speed_mps`` (V,): mean speed per bin; ``waypoints`` (W,) and ``slots`` (S,): the
  names the rows and columns belong to, checked against the scenario when given.
"""

from __future__ import annotations

import dataclasses
import pathlib
import zipfile

import numpy as np

TABLES_FILE = "engine_tables.npz"
REQUIRED_KEYS = ("density_ppm2", "battery_pct_per_s", "speed_edges_mps")


class TablesError(ValueError):
    """A tables file is missing, unreadable or inconsistent; the message names the file."""


@dataclasses.dataclass(frozen=True)
class CausalTables:
    """The engine's answers, validated on construction (see the module docstring for shapes).

    Attributes:
      density_ppm2: (S, W) float64.
      battery_pct_per_s: (V, 2) float64.
      speed_edges_mps: (V + 1,) float64, strictly increasing.
      speed_mps: (V,) float64 or None.
      waypoints: (W,) names or None; slots: (S,) names or None.
      source: the file read (for messages), or None.
    """

    density_ppm2: np.ndarray
    battery_pct_per_s: np.ndarray
    speed_edges_mps: np.ndarray
    speed_mps: np.ndarray | None = None
    waypoints: tuple[str, ...] | None = None
    slots: tuple[str, ...] | None = None
    source: str | None = None

    def __post_init__(self) -> None:
        self.validate()

    def _fail(self, message: str) -> TablesError:
        return TablesError(f"{self.source or 'engine tables'}: {message}")

    def validate(self) -> None:
        """Check shapes and values; raise :class:`TablesError` naming the source and key."""
        d, b, e = self.density_ppm2, self.battery_pct_per_s, self.speed_edges_mps
        if d.ndim != 2:
            raise self._fail(f"'density_ppm2' must be (slots, waypoints), got shape {d.shape}")
        if b.ndim != 2 or b.shape[1] != 2:
            raise self._fail(f"'battery_pct_per_s' must be (speed bins, 2), got shape {b.shape}")
        if e.ndim != 1 or len(e) != b.shape[0] + 1:
            raise self._fail(
                f"'speed_edges_mps' must have {b.shape[0] + 1} edges for {b.shape[0]} speed bins, got shape {e.shape}"
            )
        if not np.isfinite(e).all() or (np.diff(e) <= 0).any():
            raise self._fail("'speed_edges_mps' must be finite and strictly increasing")
        if (np.isinf(d)).any() or (d[np.isfinite(d)] < 0).any():
            raise self._fail("'density_ppm2' must be >= 0 (NaN where unknown)")
        if np.isinf(b).any():
            raise self._fail("'battery_pct_per_s' must be finite (NaN where unknown)")
        if self.speed_mps is not None and self.speed_mps.shape != (b.shape[0],):
            raise self._fail(f"'speed_mps' must have shape ({b.shape[0]},), got {self.speed_mps.shape}")
        if self.waypoints is not None and len(self.waypoints) != d.shape[1]:
            raise self._fail(f"'waypoints' names {len(self.waypoints)} waypoints, 'density_ppm2' has {d.shape[1]}")
        if self.slots is not None and len(self.slots) != d.shape[0]:
            raise self._fail(f"'slots' names {len(self.slots)} slots, 'density_ppm2' has {d.shape[0]}")

    def check_against(self, waypoint_ids, slot_names) -> None:
        """Raise :class:`TablesError` unless the tables are for these waypoints and slots, in order."""
        n_s, n_w = self.density_ppm2.shape
        if (n_s, n_w) != (len(slot_names), len(waypoint_ids)):
            raise self._fail(
                f"'density_ppm2' has shape {(n_s, n_w)}, the scenario has {len(slot_names)} slots "
                f"and {len(waypoint_ids)} waypoints"
            )
        if self.waypoints is not None and tuple(self.waypoints) != tuple(waypoint_ids):
            first = next(i for i, (a, b) in enumerate(zip(self.waypoints, waypoint_ids, strict=True)) if a != b)
            raise self._fail(
                f"'waypoints' differ from the scenario's at index {first}: "
                f"{self.waypoints[first]!r} vs {waypoint_ids[first]!r}"
            )
        if self.slots is not None and tuple(self.slots) != tuple(slot_names):
            raise self._fail(f"'slots' {list(self.slots)} differ from the scenario's {list(slot_names)}")

    @classmethod
    def from_arrays(cls, arrays: dict, source: str | None = None) -> CausalTables:
        """From a dict of arrays (the file's contents); raises :class:`TablesError`."""
        missing = [k for k in REQUIRED_KEYS if k not in arrays]
        if missing:
            raise TablesError(f"{source or 'engine tables'}: missing key(s) {missing}; expected {list(REQUIRED_KEYS)}")

        def floats(key):
            try:
                return np.asarray(arrays[key], np.float64)
            except (TypeError, ValueError):
                raise TablesError(f"{source or 'engine tables'}: '{key}' is not numeric") from None

        names = lambda key: tuple(str(v) for v in np.asarray(arrays[key]).tolist()) if key in arrays else None
        return cls(
            density_ppm2=floats("density_ppm2"),
            battery_pct_per_s=floats("battery_pct_per_s"),
            speed_edges_mps=floats("speed_edges_mps"),
            speed_mps=floats("speed_mps") if "speed_mps" in arrays else None,
            waypoints=names("waypoints"),
            slots=names("slots"),
            source=source,
        )

    @classmethod
    def load(cls, path: str | pathlib.Path) -> CausalTables:
        """Read ``engine_tables.npz``; raises :class:`TablesError` naming the file on any problem."""
        path = pathlib.Path(path)
        if path.is_dir():
            raise TablesError(f"{path}: is a folder; expected the engine_tables.npz file in its causal/ folder")
        if not path.is_file():
            raise TablesError(f"{path}: not found (the causal pipeline, 'socialnav learn', writes it)")
        with open(path, "rb") as head:
            if head.read(4) != b"PK\x03\x04":  # numpy reads anything else as a pickle, and says so
                raise TablesError(f"{path}: not an .npz archive (engine_tables.npz is a zip of arrays)")
        try:
            with np.load(path, allow_pickle=False) as f:
                arrays = {k: f[k] for k in f.files}
        except (OSError, ValueError, zipfile.BadZipFile, EOFError) as e:
            raise TablesError(f"{path}: not a readable .npz file ({e})") from None
        return cls.from_arrays(arrays, source=str(path))
