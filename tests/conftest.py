"""Shared fixtures: the built-in warehouse at reduced scale (short slots), built once."""

from __future__ import annotations

import os

import pytest


def _session_folder(variable: str, prefix: str) -> None:
    """``$variable`` set to a new folder of this test session's own, removed at its end, unless
    already set. Set once by the first process (pytest-xdist's controller loads this file before it
    starts its workers), so the workers and the processes the tests start share it."""
    if variable in os.environ:
        return
    import atexit
    import shutil
    import tempfile

    folder = tempfile.mkdtemp(prefix=prefix)
    os.environ[variable] = folder
    atexit.register(shutil.rmtree, folder, ignore_errors=True)


# JAX's compilation cache in a folder the test sessions keep on this processor (never the user's
# own: tests/xla_cache.py), unless SOCIALNAV_JAX_CACHE names another: a program one test (or
# worker, or command it runs) compiled is read back by the next that needs it, in this session and
# the next. SOCIALNAV_JAX_CACHE=off runs every test cold; an empty folder, as a new machine would.
if "SOCIALNAV_JAX_CACHE" not in os.environ:
    import xla_cache

    try:
        os.environ["SOCIALNAV_JAX_CACHE"] = str(xla_cache.made_folder())
    except OSError:  # no writable cache folder in the home: one of the session's own, removed at its end
        _session_folder("SOCIALNAV_JAX_CACHE", "socialnav-xla-")
# Every program, not only those that took a second to compile (JAX's default): a test session
# compiles thousands of small ones, each again in every command a test starts.
os.environ.setdefault("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", "0")
from socialnav import runtime  # noqa: E402  (before jax is imported)

runtime.request_compilation_cache()
# The C++ social force (jaxsim.native) is built afresh into a folder of this session's own, once
# (about 3 s; the processes the tests start inherit it): every run checks the build from source.
_session_folder("SOCIALNAV_NATIVE_CACHE", "socialnav-native-")
# The recorded runs' Voronoi measures (evaluation.humans.datacache: PedPy's cells, 42 s of one core
# on the 2-core AMD EPYC, the same in every session) kept like the compiled programs, beside them:
# never the user's own folder, and read back only while the data, the code that measures it and
# the libraries' versions are unchanged (the cache's key). Per processor, as NumPy's results may
# differ in their last bits from one instruction set to another; about half a megabyte a version
# of that code, pruned past HUMANS_CACHE_MAX_BYTES.
HUMANS_CACHE_MAX_BYTES = 64 * 1024**2
if "SOCIALNAV_HUMANS_CACHE" not in os.environ:
    import xla_cache

    try:
        os.environ["SOCIALNAV_HUMANS_CACHE"] = str(xla_cache.made_folder("-humans", HUMANS_CACHE_MAX_BYTES))
    except OSError:  # no writable cache folder in the home: one of the session's own, removed at its end
        _session_folder("SOCIALNAV_HUMANS_CACHE", "socialnav-humans-")

from plans import scipy_shortest_plan  # noqa: E402  (after the folders above are set)

from socialnav.jaxsim.route_follower import route_follower  # noqa: E402
from socialnav.jaxsim.scenario import load_scenario  # noqa: E402
from socialnav.jaxsim.world import build_world  # noqa: E402

# Share of the process's memory-map limit above which the compiled programs are dropped after a
# test module (below it, the next module reuses what this one compiled).
MAP_SHARE_BEFORE_RELEASE = 0.4


# Seconds this process spent making programs, summed from JAX's own monitoring events: tracing and
# lowering (paid again in every process, the compilation cache does not keep them) apart from
# XLA's compile or reading a compiled program back from the cache; and how many programs the
# compilation cache gave back.
_TRACE_EVENTS = ("/jax/core/compile/jaxpr_trace_duration", "/jax/core/compile/jaxpr_to_mlir_module_duration")
_XLA_EVENT = "/jax/core/compile/backend_compile_duration"
_HIT_EVENT = "/jax/compilation_cache/cache_hits"
_totals = {"trace_s": 0.0, "xla_s": 0.0, "xla_programs": 0, "cache_hits": 0}


def _count_compile_seconds(event: str, seconds: float, **_) -> None:
    if event in _TRACE_EVENTS:
        _totals["trace_s"] += seconds
    elif event == _XLA_EVENT:
        _totals["xla_s"] += seconds
        _totals["xla_programs"] += 1


def _count_cache_hits(event: str, **_) -> None:
    if event == _HIT_EVENT:
        _totals["cache_hits"] += 1


import jax.monitoring  # noqa: E402  (after the cache settings above)

jax.monitoring.register_event_duration_secs_listener(_count_compile_seconds)
jax.monitoring.register_event_listener(_count_cache_hits)


@pytest.hookimpl(trylast=True)
def pytest_collection_modifyitems(config, items):
    """The test files in :func:`suite_order.file_order`'s order (longest first by
    ``tests/file_seconds.json``, which ``scripts/test_files.py JUNIT --write tests/file_seconds.json``
    writes from a full run's report; the files marked ``runs_jobs_elsewhere`` later), each file's
    tests in their own order.

    A file runs whole on one worker (``--dist loadfile``, and ``--no-loadscope-reorder`` so that
    pytest-xdist keeps this order instead of putting the files with the most tests first), so
    starting the longest first leaves the short ones to even out the workers' ends: a file of one
    two-minute test started last would otherwise run alone on one core while the other idles."""
    import json
    import pathlib

    from suite_order import file_order

    seconds_file = pathlib.Path(__file__).with_name("file_seconds.json")
    seconds = json.loads(seconds_file.read_text()) if seconds_file.is_file() else {}
    files = list(dict.fromkeys(item.nodeid.split("::")[0] for item in items))
    late = {item.nodeid.split("::")[0] for item in items if item.get_closest_marker("runs_jobs_elsewhere")}
    position = {name: k for k, name in enumerate(file_order(files, seconds, late))}
    items.sort(key=lambda item: position[item.nodeid.split("::")[0]])


@pytest.fixture(autouse=True)
def _record_compile_seconds(record_property):
    """Each test's seconds spent making programs, as JUnit properties (CI sums them per file beside
    the test time: what a faster test would have to cut): ``compile_s`` in all, of which
    ``trace_s`` tracing and lowering and ``xla_s`` XLA's compiling or reading from the cache;
    ``xla_programs`` programs given to XLA, ``cache_hits`` of them read back from the cache."""
    start = dict(_totals)
    yield
    done = {k: _totals[k] - start[k] for k in _totals}
    record_property("compile_s", round(done["trace_s"] + done["xla_s"], 3))
    for key in ("trace_s", "xla_s"):
        record_property(key, round(done[key], 3))
    for key in ("xla_programs", "cache_hits"):
        record_property(key, done[key])


@pytest.fixture(autouse=True, scope="module")
def _free_compiled_programs_when_crowded():
    """After a test module, drop JAX's compiled programs (and the arena's caches of them) if the
    process holds more than :data:`MAP_SHARE_BEFORE_RELEASE` of Linux's memory-map limit. Each
    episode program holds several hundred memory maps of JIT code (measured: 9,449 maps after 16
    arena tests); kept for the whole suite they reached the default limit of 65,530 maps per
    process, and the suite died inside native code without a Python traceback at a test that
    passes alone. Dropping them after every module kept the suite alive but made each module
    trace and compile again what the one before had compiled; dropping them only when the maps
    run high does both (the arena does the same between scenes,
    :func:`evaluation.arena.episodes.release_programs_if_crowded`)."""
    yield
    import gc

    from socialnav.evaluation.arena import episodes as arena

    if arena.release_programs_if_crowded(MAP_SHARE_BEFORE_RELEASE):
        gc.collect()


@pytest.fixture(scope="session")
def warehouse():
    return load_scenario()


@pytest.fixture(scope="session")
def short_day():
    """The warehouse with 60 s slots (a whole day is 6600 steps), its world and a route follower."""
    scenario = load_scenario(slot_length_s=60.0)
    world = build_world(scenario)
    return scenario, world, route_follower(scipy_shortest_plan(scenario), world)


@pytest.fixture(scope="session")
def learned_run(tmp_path_factory):
    """A short simulated day (60 s slots, 2 worlds) and the causal engine learnt from it.

    The robot starts at 21 % battery so that it charges and C varies. Returns the run folder;
    the engine's tables are in ``causal/engine_tables.npz``. Made once per test session: under
    pytest-xdist the first worker to ask makes it in the session's shared temporary folder while
    the others wait on a lock, then read it (every test only reads it: the commands that would
    write there are the ones the tests show refused).
    """
    if os.environ.get("PYTEST_XDIST_WORKER") is None:
        return _learn_a_short_day(tmp_path_factory.mktemp("learned_run"))
    import fcntl

    shared = tmp_path_factory.getbasetemp().parent  # pytest-N/, the parent of every worker's own
    with open(shared / "learned_run.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes, also if making it fails
        run, done = shared / "learned_run", shared / "learned_run.done"
        if not done.exists():
            if run.exists():  # a worker that failed half way
                import shutil

                shutil.rmtree(run)
            run.mkdir()
            _learn_a_short_day(run)
            done.touch()
    return run


def _learn_a_short_day(run):
    """:func:`learned_run`'s folder made in ``run`` (an empty folder)."""
    from socialnav.causal.learn import learn
    from socialnav.jaxsim.logs import simulate_to_parquet
    from socialnav.planners.warehouse.routes import shortest_path_plan

    scenario = load_scenario(slot_length_s=60.0, battery_initial_pct=21.0)
    simulate_to_parquet(
        scenario,
        run,
        route_follower(shortest_path_plan(scenario), build_world(scenario)),
        n_worlds=2,
        duration_s=scenario.n_slots * 60.0,
        progress=False,
    )
    learn(run, run / "causal", max_samples=60_000, progress=False)
    # Written from Python, not by the commands: give the folders the manifests the commands write,
    # so that the commands treat them as their runs.
    from socialnav.common import runfolder

    for folder, job, marker in (
        (run, "socialnav simulate", "run.json"),
        (run / "causal", "socialnav learn", "report.json"),
    ):
        files = [p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file()]
        runfolder.record(folder, job, [f for f in files if not f.startswith("causal/")], marker=marker)
    return run
