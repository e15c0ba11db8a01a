"""The arena's table in a run folder: scenes x methods x variants, computed in shards, joined per
scene, summarised.

What ``socialnav arena`` does between checking its arguments and printing its tables (the command,
:mod:`socialnav.cli.arena`, holds only the parsing, the checks and the printing). A run folder
holds:

- ``run.json``: the run's settings (:func:`settings`); a run with other settings is refused;
- ``shards/<scene>-<digest>/<first>.parquet``: a shard's episodes (and ``.trajectories.parquet``)
  while its scene is in flight (:func:`plan_shards`, :func:`compute_shard`, :func:`save_shard`);
- ``episodes/<scene>.parquet``: the scene's joined episodes, its digest in the file's metadata
  (present and matching: the scene is done; :func:`finish_scene`, :func:`finished`);
- ``trajectories/``, ``pictures/``: the kept variants' steps and their pictures;
- ``summary.csv``, ``stats.csv``, ``papers.csv``, ``directions.csv``,
  ``directions_held_out.csv``, ``directions_turned.csv``, ``papers_stats.csv``
  (:func:`write_tables`).

A rerun with the same settings computes only what is missing: the digest of a scene
(:func:`scene_digest`) covers its file's bytes and every setting that changes an episode.

From Python, with the shards run one after the other here::

    from socialnav.evaluation.arena import table
    from socialnav.jaxsim.scenes.spec import load_scene

    request = table.TableRequest(specs=(load_scene(FILE),), methods=("navfn", "casn"), variants=10)
    episodes, tables = table.run_table(out, request)
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
import pathlib
import shutil
from collections.abc import Callable, Sequence

from socialnav.common import runfolder
from socialnav.common.atomic import write_atomic
from socialnav.evaluation.arena import actor_spec
from socialnav.evaluation.arena.run import HELD_OUT, TURNED, row_name
from socialnav.jaxsim.scenes.spec import SceneSpec, mirror, turn

JOB = "socialnav arena"  # the job that owns a run folder's files (common.runfolder's manifest)
POLICY_METHOD = "ppo"  # the rows of a trained policy (``--policy-run``)
# What an arena run leaves at the top of its folder (run.json first, summary.csv last).
RESULTS = (
    "run.json",
    "summary.csv",
    "stats.csv",
    "papers.csv",
    "directions.csv",
    "directions_held_out.csv",
    "directions_turned.csv",
    "papers_stats.csv",
    "episodes",
    "trajectories",
    "pictures",
    "shards",
)
# The time printed before a run, as a range on this project's 2-core machine: start-up, then a
# compilation per program (one per scene file and method, and two per scene for the people
# without the robot and the metrics; a held-out mirror shares its scene's), then the simulated
# seconds of every episode. Measured here with no compilation cache
# (SOCIALNAV_JAX_CACHE=off): seed 001's four scenes x 11 methods in 75 s at 2 variants and 89 s
# at 50 (1.2 s a program; the 48 variants more, 84,000 simulated seconds, at 6,000 a second);
# the default table with --held-out x 100 variants took 9.3 min (docs/arena-results.md). The
# ends below widen those figures (a loaded machine, slower scenes); the estimate they replace,
# episodes / 55 per second, said 40 s for a run of minutes. An earlier run's programs in the
# compilation cache can beat the low end.
STARTUP_S = 10.0
COMPILE_S_PER_PROGRAM = (0.7, 2.0)
SIMULATED_S_PER_S = (6000.0, 2000.0)  # the fast end first: it gives the low estimate
# Bytes a finished episode's row costs in the joined tables: 146 measured in memory
# (``memory_usage(deep=True)``, 26 columns, 80 episodes of casn_head_on and casn_crossing), times
# about four for the copies the joins, the summary and the statistics make.
EPISODE_ROW_BYTES = 600


@dataclasses.dataclass(frozen=True)
class TableRequest:
    """What a table is made of: every input that changes an episode, and what is kept.

    Attributes:
      specs: the scenes (:func:`socialnav.jaxsim.scenes.spec.load_scene`), different names.
      methods: the rows: built-in methods, then the ``actor_specs``' names, then
        :data:`POLICY_METHOD` with ``policy_run``.
      variants: variants a scene; seed: their random seed.
      held_out: also every scene mirrored with its ranges exceeded (rows ``<scene>@held_out``).
      turned: also every scene turned a quarter turn, its own variants turned (rows
        ``<scene>@turned``; :func:`socialnav.jaxsim.scenes.spec.turn`).
      shard_variants: variants a shard (None: a scene's variants in one).
      keep_trajectories: variants a scene and method whose steps are kept.
      gscl_run: the GSCL model of method ``gscl`` (a resolved folder), or None.
      gscl_rotations: 1, or 4: the model's prediction averaged over the four quarter turns of its
        input (:func:`socialnav.models.inference.rotation_averaged`: a map that turns with the scene,
        at 4 times the inference).
      human_model: how the people move (:data:`socialnav.jaxsim.scenes.people.HUMAN_MODELS`).
      human_values: ``("<part>.<field>", value)`` pairs setting that model's constants (a
        calibration's fit, :func:`socialnav.evaluation.humans.fit_file.read_fit`; empty: the
        name's own); human_fit: where they came from (the fit file and method), for the record.
      params_file, params_text: the ``--params`` file and its text ("" for the seeds' values).
      actor_specs: users' actor factories, ``MODULE:FUNCTION`` with a file path made absolute.
      policy_run, policy_digest: a trained policy's run folder and its digest, or None.
      animate: ``(scene, method)`` pairs whose variant 0 is drawn as a GIF.
    """

    specs: tuple[SceneSpec, ...]
    methods: tuple[str, ...]
    variants: int = 100
    seed: int = 0
    held_out: bool = False
    turned: bool = False
    shard_variants: int | None = None
    keep_trajectories: int = 5
    gscl_run: pathlib.Path | None = None
    gscl_rotations: int = 1
    human_model: str = "social_force"
    human_values: tuple[tuple[str, float], ...] = ()
    human_fit: str | None = None
    params_file: pathlib.Path | None = None
    params_text: str = ""
    actor_specs: tuple[str, ...] = ()
    policy_run: pathlib.Path | None = None
    policy_digest: str | None = None
    animate: tuple[tuple[str, str], ...] = ()

    def __post_init__(self):
        """A method or a scene named twice would run twice and count twice under one row, its
        ``n`` doubled and its interval narrowed with no new episode: refused."""
        for what, names in (("methods", self.methods), ("scenes", [spec.name for spec in self.specs])):
            twice = sorted({name for name in names if list(names).count(name) > 1})
            if twice:
                raise ValueError(f"TableRequest.{what}: {', '.join(map(repr, twice))} named twice; name each once")

    @property
    def per_shard(self) -> int:
        return self.variants if self.shard_variants is None else self.shard_variants

    @functools.cached_property
    def runs(self) -> list[tuple[SceneSpec, bool]]:
        """``(spec, held_out)`` of every scene row: the scenes, their held-out mirrors, then the
        scenes turned (a turned row's spec is the turned scene, :func:`turn`)."""
        held_out = [(spec, True) for spec in self.specs] if self.held_out else []
        turned = [(turn(spec), False) for spec in self.specs] if self.turned else []
        return [(spec, False) for spec in self.specs] + held_out + turned

    @property
    def names(self) -> list[str]:
        """Every scene row's name (``<scene>``, ``<scene>@held_out``, ``<scene>@turned``), as
        :attr:`runs`."""
        return [row_name(spec.name, held_out, spec.turned_from is not None) for spec, held_out in self.runs]


def estimate_s(
    timeouts_s: Sequence[float], n_methods: int, variants: int, held_out: bool, turned: bool = False
) -> tuple[float, float]:
    """``(low, high)`` seconds a run of scenes with these ``timeouts_s`` x ``n_methods`` x
    ``variants`` takes here (see the constants above; a turned scene's grid has other shapes, so
    it compiles its own programs)."""
    programs = len(timeouts_s) * (n_methods + 2) * (2 if turned else 1)
    rows = 1 + int(held_out) + int(turned)
    simulated = sum(timeouts_s) * rows * variants * n_methods
    return tuple(
        STARTUP_S + programs * c + simulated / rate for c, rate in zip(COMPILE_S_PER_PROGRAM, SIMULATED_S_PER_S)
    )


def memory_bytes(request: TableRequest) -> float:
    """What a run holds at once: every episode's row in the joined tables, and one shard's
    variants in flight (their trajectories, T steps of the robot and every person slot, and the
    planner's grids, a few (H, W) float32 maps per variant)."""
    from socialnav.evaluation.arena.episodes import ArenaConfig

    config = ArenaConfig()
    rows = len(request.runs) * request.variants * len(request.methods) * EPISODE_ROW_BYTES
    flight = 0.0
    for spec in request.specs:
        steps = spec.timeout_s / config.env.dt_s
        xmin, xmax, ymin, ymax = spec.bounds_m
        cells = (xmax - xmin) * (ymax - ymin) / config.grid_resolution_m**2
        per_variant = steps * (48 + 24 * spec.n_people_slots) + 16 * cells * 4
        flight = max(flight, per_variant * min(request.per_shard, request.variants))
    return rows + flight


def settings(request: TableRequest) -> dict:
    """The run's settings as ``run.json`` records them, with every scene row's digest
    (``scene_digests``) and every scene file's (``scene_file_digests``)."""
    from socialnav.common import __version__
    from socialnav.evaluation.arena import nav_metrics
    from socialnav.models.inference import model_identity

    chosen = {
        "scenes": [s.name for s in request.specs],
        "scene_files": [str(s.file) for s in request.specs],
        "methods": list(request.methods),
        "variants": request.variants,
        "seed": request.seed,
        "keep_trajectories": request.keep_trajectories,
        "held_out": request.held_out,
        **({"turned": True} if request.turned else {}),  # absent without --turned: earlier runs resume
        "shard_variants": request.per_shard,
        "gscl_run": None if request.gscl_run is None else str(request.gscl_run),
        "gscl_model": None if request.gscl_run is None else model_identity(request.gscl_run),
        **({"gscl_rotations": request.gscl_rotations} if request.gscl_rotations != 1 else {}),
        "human_model": request.human_model,
        # absent without a fit: earlier runs' settings and digests stay the same
        **(
            {"human_fit": request.human_fit, "human_values": dict(request.human_values)} if request.human_values else {}
        ),
        "params_file": None if request.params_file is None else str(request.params_file),
        "params": request.params_text or None,  # None without a file: earlier runs' digests stay valid
        "actors": list(request.actor_specs),
        "actor_sources": [actor_spec.source_digest(spec) for spec in request.actor_specs],
        **(
            {}
            if request.policy_digest is None
            else {"policy_run": str(request.policy_run), "policy_model": request.policy_digest}
        ),
        "metrics_version": nav_metrics.VERSION,
        "socialnav_version": __version__,
    }
    chosen["scene_digests"] = {
        name: scene_digest(
            spec.file,
            held_out,
            chosen,
            turned=spec.turned_from is not None,
            recording_file=user_recording_file(spec.recording),
        )
        for (spec, held_out), name in zip(request.runs, request.names, strict=True)
    }
    chosen["scene_file_digests"] = {s.name: hashlib.sha256(s.file.read_bytes()).hexdigest()[:16] for s in request.specs}
    files = {s.name: user_recording_file(s.recording) for s in request.specs}
    if any(files.values()):  # absent without a user's recording: earlier runs' settings stay the same
        chosen["recording_file_digests"] = {name: file_sha256(f)[:16] for name, f in files.items() if f is not None}
    return chosen


def user_recording_file(recording: dict | None) -> pathlib.Path | None:
    """The user's recording a scene plays (its ``recording``'s ``file``), or None."""
    file = (recording or {}).get("file")
    return None if file is None else pathlib.Path(file)


def file_sha256(path: pathlib.Path) -> str:
    """The SHA-256 of the file at ``path``, read once while its size and modification time stay
    (a recording is digested for each of its scene's rows and for the run's settings)."""
    stat = pathlib.Path(path).stat()
    return _sha256_of(pathlib.Path(path).resolve(), stat.st_size, stat.st_mtime_ns)


@functools.lru_cache(maxsize=32)
def _sha256_of(path: pathlib.Path, size: int, mtime_ns: int) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def scene_digest(
    spec_file: pathlib.Path,
    held_out: bool,
    settings: dict,
    turned: bool = False,
    recording_file: pathlib.Path | None = None,
) -> str:
    """A scene's results are these when this digest matches: the scene file's bytes (and those of
    the user's recording it plays, ``recording_file``), the held-out
    and turned flags, and every setting that changes an episode (methods, variants, seed, shard layout, the
    GSCL model, the source files of the ``--actor`` factories, the human model and its fitted
    constants, the ``--params``
    file's text, the metrics' and the toolkit's versions)."""
    h = hashlib.sha256()
    h.update(pathlib.Path(spec_file).read_bytes())
    if recording_file is not None:  # only then: a shipped scene's digest as before
        h.update(file_sha256(recording_file).encode())
    keys = (
        "methods",
        "variants",
        "seed",
        "shard_variants",
        "keep_trajectories",
        "gscl_model",
        "actor_sources",
        "human_model",
        "params",
    )
    chosen = {k: settings.get(k) for k in keys}
    if settings.get("policy_model") is not None:  # absent without --policy-run: earlier digests stay valid
        chosen["policy_model"] = settings["policy_model"]
    if settings.get("human_values"):  # absent without --human-fit: earlier digests stay valid
        chosen["human_values"] = settings["human_values"]
    if settings.get("gscl_rotations", 1) != 1:  # absent at 1: earlier digests stay valid
        chosen["gscl_rotations"] = settings["gscl_rotations"]
    row = {"held_out": held_out, **({"turned": True} if turned else {})}  # an unturned row's digest as before
    h.update(json.dumps({**row, **chosen}, sort_keys=True).encode())
    h.update(json.dumps([settings["metrics_version"], settings["socialnav_version"]]).encode())
    return h.hexdigest()[:16]


def settings_conflict(out: pathlib.Path, chosen: dict) -> str | None:
    """What differs between ``chosen`` and the run already in ``out`` (its ``run.json``), in words,
    or None where there is none or it has the same settings (to be resumed)."""
    meta = out / "run.json"
    if not meta.exists():
        return None
    try:
        previous = json.loads(meta.read_text())
    except (OSError, json.JSONDecodeError):
        previous = None
    differs = [k for k in chosen if not isinstance(previous, dict) or previous.get(k) != chosen[k]]
    if not differs:
        return None
    files_before = previous.get("scene_file_digests") or {} if isinstance(previous, dict) else {}
    changed = [n for n, d in chosen["scene_file_digests"].items() if files_before.get(n) not in (None, d)]
    if changed:
        return f"scene file(s) changed since: {', '.join(changed)}"
    return f"other settings ({', '.join(differs)})"


def finished(out: pathlib.Path, name: str, digest: str) -> bool:
    """A scene's episodes file exists and was made with these settings (its ``scene_digest``)."""
    import pyarrow.parquet as pq

    path = out / "episodes" / f"{name}.parquet"
    if not path.is_file():
        return False
    try:
        metadata = pq.read_schema(path).metadata or {}
        attrs = json.loads(metadata.get(b"PANDAS_ATTRS", b"{}"))
    except (OSError, ValueError):
        return False
    return attrs.get("scene_digest") == digest


def shard_file(out: pathlib.Path, name: str, digest: str, first: int) -> pathlib.Path:
    """A shard's episodes file: under a folder named by its scene and the digest of what made it,
    so a shard of an edited scene or of other settings is never joined with these."""
    return out / "shards" / f"{name}-{digest}" / f"{first:06d}.parquet"


def plan_shards(out: pathlib.Path, request: TableRequest, digests: dict) -> list[tuple[str, pathlib.Path, tuple, int]]:
    """The shards still to compute: ``(name, output file, compute_shard's arguments, episodes)``
    each. A scene, its held-out mirror and its turned row come one after the other: the first two
    share their compiled programs, which the arena may drop between scenes
    (:func:`socialnav.evaluation.arena.episodes.release_programs_if_crowded`)."""
    runs, names = request.runs, request.names
    position = {spec.name: k for k, spec in enumerate(request.specs)}
    order = sorted(
        range(len(runs)), key=lambda i: (position[runs[i][0].name], runs[i][0].turned_from is not None, runs[i][1])
    )
    shards = []
    for (spec, held_out), name in ((runs[i], names[i]) for i in order):
        if finished(out, name, digests[name]):
            continue  # the whole scene is done, with these settings
        for first in range(0, request.variants, request.per_shard):
            n = min(request.per_shard, request.variants - first)
            args = (
                spec,
                held_out,
                first,
                n,
                tuple(request.methods),
                request.seed,
                request.keep_trajectories,
                request.gscl_run,
                tuple(request.actor_specs),
                request.human_model,
                request.params_text or "",
                None if request.policy_run is None else str(request.policy_run.resolve()),
                request.gscl_rotations,
                request.human_values,
            )
            output = runfolder.inside(out, shard_file(out, name, digests[name], first))
            shards.append((f"{name}[{first}:{first + n}]", output, args, n * len(request.methods)))
    return shards


@functools.lru_cache(maxsize=4)
def gscl_model(run: pathlib.Path | None):
    """The GSCL model in ``run`` (loaded once per process and run), or None."""
    if run is None:
        return None
    from socialnav.models.inference import SocialCostModel

    return SocialCostModel.load(run)


def _gscl_layer_model(run, rotations: int):
    """The GSCL method's model: the network, or its prediction averaged over ``rotations`` quarter
    turns (a function of the maps)."""
    model = gscl_model(run)
    if model is None or rotations == 1:
        return model
    from socialnav.models.inference import rotation_averaged

    return rotation_averaged(model.function, rotations)


def compute_shard(
    spec,
    held_out,
    first,
    n,
    methods,
    seed,
    keep_trajectories,
    gscl_run,
    actor_specs=(),
    human_model="social_force",
    params_text="",
    policy_run=None,
    gscl_rotations=1,
    human_values=(),
):
    """One shard: every method on variants ``first .. first + n - 1`` of a scene (a Ray task with
    ``--backend ray``): ``(episodes frame, trajectories frame or None)``. ``actor_specs``: the
    ``--actor`` factories, loaded here (in the worker); ``params_text``: the ``--params`` file's
    text (parsed here, so a worker needs no access to the file); ``policy_run``: a trained
    policy's run folder (``--policy-run``), restored here; ``human_values``: the people's
    constants as a calibration fitted them (pairs, :class:`TableRequest`). The GSCL weights enter the
    episode program traced: a second checkpoint of the same network compiles nothing new (with
    ``gscl_rotations`` 4 the rotation-averaged prediction closes over them instead)."""
    from socialnav.evaluation.arena import params as arena_params
    from socialnav.evaluation.arena import run as arena_run
    from socialnav.evaluation.arena.episodes import ArenaConfig

    keep = max(0, min(n, keep_trajectories - first))
    users = {actor_spec.name(text): actor_spec.load(text) for text in actor_specs}
    if policy_run is not None:
        from socialnav.planners.learning.policy_run import actor_factory

        users[POLICY_METHOD] = actor_factory(policy_run, POLICY_METHOD)
    return arena_run.run_scene(
        spec,
        list(methods),
        n,
        seed,
        first,
        keep,
        _gscl_layer_model(gscl_run, gscl_rotations),
        ArenaConfig.of(human_model),
        held_out=held_out,
        user_actors=users,
        params=arena_params.parse(params_text, "--params") if params_text else None,
        human_values=dict(human_values),
    )


def save_shard(shard, result) -> None:
    """Write :func:`compute_shard`'s ``result`` to ``shard.output`` (the episodes, last: its
    presence marks the shard done) and beside it the trajectories."""
    episodes, trajectories = result
    if trajectories is not None:
        write_atomic(shard.output.with_suffix(".trajectories.parquet"), trajectories.to_parquet)
    write_atomic(shard.output, episodes.to_parquet)  # last: its presence marks the shard done


def finish_scene(out, request: TableRequest, spec, held_out, name, digest) -> None:
    """Join a scene's shards into ``episodes/<name>.parquet`` and ``trajectories/``, draw its
    pictures, then remove the shards (the episodes file last: its presence, with the scene's
    digest in its metadata, marks the scene done)."""
    import pandas as pd

    from socialnav.evaluation.arena import plots as arena_plots

    methods = request.methods
    folder = runfolder.inside(out, out / "shards" / f"{name}-{digest}")
    parts = sorted(folder.glob("[0-9]*[0-9].parquet"))
    episodes = pd.concat([pd.read_parquet(f) for f in parts], ignore_index=True)
    kept = [pd.read_parquet(f) for f in sorted(folder.glob("*.trajectories.parquet"))]
    order = {m: k for k, m in enumerate(methods)}
    episodes = episodes.sort_values(["method", "variant"], key=lambda c: c.map(order) if c.name == "method" else c)
    episodes = episodes.reset_index(drop=True)
    episodes.attrs = {"scene_digest": digest}
    written = []
    if kept:
        trajectories = pd.concat(kept, ignore_index=True)
        drawn = mirror(spec) if held_out else spec
        write_atomic(runfolder.inside(out, out / "trajectories" / f"{name}.parquet"), trajectories.to_parquet)
        written.append(f"trajectories/{name}.parquet")
        pictures = out / "pictures"
        drawings = [
            (functools.partial(arena_plots.paths_figure, drawn), f"{name}_paths.png"),
            (arena_plots.distance_figure, f"{name}_distance.png"),
        ]
        if "snape_social_eband" in methods:  # the band's speed gain (seed 004 Fig. 13)
            band = functools.partial(arena_plots.speed_figure, method="snape_social_eband")
            drawings.append((band, f"{name}_speed.png"))
        for draw, file in drawings:
            draw(trajectories, path=runfolder.inside(out, pictures / file))
            written.append(f"pictures/{file}")
        for scene_name, method in request.animate:
            if scene_name == name:
                gif = runfolder.inside(out, pictures / f"{name}_{method}.gif")
                arena_plots.animation(drawn, trajectories, method, gif)
                written.append(f"pictures/{gif.name}")
    runfolder.record(out, JOB, [*written, f"episodes/{name}.parquet"])
    write_atomic(runfolder.inside(out, out / "episodes" / f"{name}.parquet"), episodes.to_parquet)
    shutil.rmtree(folder, ignore_errors=True)
    if out.joinpath("shards").is_dir() and not any(out.joinpath("shards").iterdir()):
        out.joinpath("shards").rmdir()


def join_scenes(out: pathlib.Path, request: TableRequest, digests: dict):
    """Every scene row's episodes as one frame, each scene's shards joined first where that scene
    is not yet finished."""
    import pandas as pd

    frames = []
    for (spec, held_out), name in zip(request.runs, request.names, strict=True):
        episodes_file = runfolder.inside(out, out / "episodes" / f"{name}.parquet")
        if not finished(out, name, digests[name]):
            finish_scene(out, request, spec, held_out, name, digests[name])
        frames.append(pd.read_parquet(episodes_file))
    return pd.concat(frames, ignore_index=True)


def write_tables(out: pathlib.Path, episodes) -> dict:
    """Write the run's tables from its joined ``episodes``: ``summary.csv`` (one row per scene and
    method, with intervals), ``stats.csv`` (the tests between methods), ``pictures/methods.png``
    and, where the run has the papers' scenes, ``papers.csv``, ``directions.csv`` (the claims on
    the evaluated variants), ``directions_held_out.csv`` and ``directions_turned.csv`` (the same
    claims on the held-out and the turned rows, where the run has them) and ``papers_stats.csv``.
    Returns the tables written, by file name, in that order."""
    from socialnav.evaluation.arena import papers
    from socialnav.evaluation.arena import report as arena_report
    from socialnav.evaluation.arena import stats as arena_stats

    summary = arena_report.summary(episodes)
    write_atomic(out / "summary.csv", lambda tmp: summary.to_csv(tmp, index=False))
    statistics = arena_stats.scene_statistics(episodes)
    write_atomic(out / "stats.csv", lambda tmp: statistics.to_csv(tmp, index=False))
    tables = {"summary.csv": summary, "stats.csv": statistics}
    written = ["summary.csv", "stats.csv"]
    if len(summary):
        from socialnav.evaluation.arena import plots as arena_plots

        arena_plots.methods_figure(summary, runfolder.inside(out, out / "pictures" / "methods.png"))
        written.append("pictures/methods.png")
    for name, table in (
        ("papers.csv", papers.comparison(summary).dropna(subset=["ours"])),
        ("directions.csv", papers.directions(episodes)),
        ("directions_held_out.csv", papers.directions(episodes, HELD_OUT)),
        ("directions_turned.csv", papers.directions(episodes, TURNED)),
        ("papers_stats.csv", papers.stats_comparison(episodes)),
    ):
        if not len(table):
            continue
        write_atomic(out / name, lambda tmp, table=table: table.to_csv(tmp, index=False))
        written.append(name)
        tables[name] = table
    runfolder.record(out, JOB, written)
    return tables


def _run_here(compute: Callable, save: Callable, shards: Sequence) -> None:
    for shard in shards:
        save(shard, compute(*shard.args))


@dataclasses.dataclass(frozen=True)
class _Shard:
    name: str
    output: pathlib.Path
    args: tuple
    work: float


class TableTooLarge(ValueError):
    """A table would hold more than the memory available (:func:`memory_bytes`): ``needed_bytes``
    at once where the machine has ``available_bytes``."""

    def __init__(self, variants: int, needed_bytes: float, available_bytes: float):
        self.needed_bytes, self.available_bytes = needed_bytes, available_bytes
        super().__init__(
            f"TableRequest.variants {variants:,}: about {needed_bytes / 1e9:.1f} GB at once, this machine has "
            f"{available_bytes / 1e9:.1f} GB available; fewer variants, or shard_variants for the shards"
        )


class SettingsConflict(ValueError):
    """The run folder holds a run with other settings (``conflict``, in words: :func:`settings_conflict`)."""

    def __init__(self, out: pathlib.Path, conflict: str):
        self.conflict = conflict
        super().__init__(f"{out} holds a run with {conflict} ({out / 'run.json'})")


@dataclasses.dataclass(frozen=True)
class TablePlan:
    """A table's run folder started and its work cut (:func:`plan_table`).

    Attributes:
      digests: every scene row's digest (``run.json``'s ``scene_digests``).
      shards: the shards still to compute (objects with ``name``, ``output``, ``args``, ``work``:
        ``compute_shard(*args)``, saved by :func:`save_shard`).
      needed_bytes: what the table holds at once (:func:`memory_bytes`).
    """

    digests: dict
    shards: list
    needed_bytes: float


def plan_table(out, request: TableRequest, recorded: dict | None = None) -> TablePlan:
    """Check a table, start its run folder ``out`` (made if missing; a run with the same settings
    is resumed) and cut its work into shards. ``recorded``: what ``run.json`` notes without
    comparing it on a resume (the backend, the command line). Raises, before anything is written:
    :class:`~jaxsim.scenario.errors.ScenarioError` where no method can finish a scene with the
    run's robot; :class:`TableTooLarge` where the table would hold more than 80 % of the memory
    available (:func:`memory_bytes`); :class:`socialnav.common.runfolder.NotOurs` where ``out``
    holds another job's files; :class:`SettingsConflict` where it holds a run with other settings."""
    from socialnav.common.memory import shortfall
    from socialnav.evaluation.arena import params as arena_params
    from socialnav.evaluation.arena.episodes import ArenaConfig
    from socialnav.jaxsim.scenes.reachable import refuse_unfinishable

    out = pathlib.Path(out)
    params = arena_params.parse(request.params_text, "--params") if request.params_text else arena_params.ArenaParams()
    for spec in request.specs:  # no method could finish it (or break its rule): refused before any work
        refuse_unfinishable(spec, params.robot, ArenaConfig().env.goal_tolerance_m)
    needed = memory_bytes(request)
    available = shortfall(needed)
    if available is not None:
        raise TableTooLarge(request.variants, needed, available)
    runfolder.claim(out, JOB, RESULTS)  # never writes over files no arena run wrote
    chosen = settings(request)
    conflict = settings_conflict(out, chosen)
    if conflict is not None:
        raise SettingsConflict(out, conflict)
    start(out, chosen, recorded)
    digests = chosen["scene_digests"]
    return TablePlan(digests, [_Shard(*s) for s in plan_shards(out, request, digests)], needed)


def finish_table(out, request: TableRequest, plan: TablePlan):
    """Once ``plan``'s shards are computed: every scene joined in ``out``
    (:func:`join_scenes`) and the tables written; ``(episodes frame, tables)``
    (:func:`write_tables`)."""
    out = pathlib.Path(out)
    episodes = join_scenes(out, request, plan.digests)
    return episodes, write_tables(out, episodes)


def run_table(out, request: TableRequest, run_shards: Callable | None = None, recorded: dict | None = None):
    """The whole table into the run folder ``out``: :func:`plan_table`, the shards computed, then
    :func:`finish_table`; returns ``(episodes frame, tables)``. ``socialnav arena`` is these three
    steps with the shards run by :func:`socialnav.backend.run_with_args` (a progress bar, Ray).

    ``run_shards(compute, save, shards)`` runs the shards; default: one after the other in this
    process. Raises what :func:`plan_table` raises, before anything is written. Unlike the command
    it takes no lock on ``out``: one run a folder.
    """
    plan = plan_table(out, request, recorded)
    (run_shards or _run_here)(compute_shard, save_shard, plan.shards)
    return finish_table(out, request, plan)


def start(out: pathlib.Path, chosen: dict, recorded: dict | None = None) -> None:
    """Make ``out`` and write its ``run.json`` (``chosen`` and ``recorded``: what is noted but not
    compared, such as the backend; and the source commit, :func:`socialnav.common.provenance.source`,
    and the host, :func:`socialnav.common.machine.compiler_host`, noted too: a run resumed at a
    later commit or on another machine records that one, and its digests say which episodes it
    could reuse)."""
    from socialnav.common import provenance
    from socialnav.common.atomic import write_text_atomic
    from socialnav.common.machine import compiler_host

    out.mkdir(parents=True, exist_ok=True)
    # The host: XLA compiles for the processor (its model, not only its instruction set) and a
    # learned layer's convolutions round as that code does, so the same command can give a GSCL
    # row other bits on another machine.
    noted = {**provenance.source(), "host": compiler_host(), **(recorded or {})}
    write_text_atomic(out / "run.json", json.dumps({**chosen, **noted}, indent=1) + "\n")
    runfolder.record(out, JOB, ["run.json", "shards/"])
