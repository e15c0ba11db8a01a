"""Hostile but fair input against the command line and the model API, each case classified.

    python scripts/hostile_cases.py                     # every case, a table and the counts
    python scripts/hostile_cases.py --only params       # the cases whose name starts with it
    python scripts/hostile_cases.py --json cases.json   # also the outcomes as JSON

Each case builds its input in a scratch folder (a mutated copy of the warehouse scenario, a
truncated file, a bad option ...), runs one command in a subprocess and classifies what happened:

* ``clean error``: exit status not 0, no Python traceback, and the message names what the case
  expects (the file or option and the field);
* ``vague error``: exit status not 0 and no traceback, but the message does not name them;
* ``traceback``: a Python traceback reached the user;
* ``hang``: no answer within the case's time limit;
* ``accepted nonsense``: exit status 0 on input that is wrong;
* ``correct``: a case whose input is valid, run to the right result;
* ``wrong``: a valid input that failed or gave a wrong result;
* ``data lost``: a case about files whose check found a previous result damaged.

This is the measurement behind issue 17's table (before / after); the fuzz tests in
``tests/test_fuzz.py`` check the same properties in-process at random.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import pathlib
import re
import resource
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable

ROOT = pathlib.Path(__file__).resolve().parents[1]
WAREHOUSE = ROOT / "data" / "warehouse"
PY = sys.executable
SOCIALNAV = [PY, "-m", "socialnav"]
SHORT_DAY = ["--worlds", "1", "--slots", "1", "--slot-length-s", "60", "--no-progress"]


@dataclasses.dataclass
class Case:
    """One hostile input: ``make(tmp) -> argv``, the words a clean error names, or a check."""

    name: str
    make: Callable[[pathlib.Path], list[str]]
    expect_words: tuple[str, ...] = ()  # an error is expected; its message names these
    check: Callable[[pathlib.Path, subprocess.CompletedProcess], bool] | None = None  # valid input: the result
    api: bool = False  # a Python API call: its error is an exception (ValueError) naming the words
    fail_label: str = "wrong"  # what a failed check is called
    timeout_s: float = 120.0
    misleading: tuple[str, ...] = ()  # words that make an error vague even if it names the rest
    # A full disk, as a file-size limit (``ulimit -f``: a write past it fails with EFBIG, "File
    # too large", where ENOSPC needs a small file system mounted as root). The compilation cache
    # is off in such a case: JAX writes its entries in place and never replaces one, so an entry
    # cut short by the limit would stay in the user's cache.
    file_size_limit_bytes: int | None = None
    send_signal: tuple[int, float] | None = None  # (signal, seconds after the start): Ctrl-C, a scheduler's SIGTERM
    env: dict[str, str] = dataclasses.field(default_factory=dict)  # the user's environment ({tmp} as in make)


def scenario(tmp: pathlib.Path, file: str, mutate: Callable[[dict], object]) -> pathlib.Path:
    """A copy of the warehouse with ``mutate`` applied to the JSON of ``file``."""
    folder = tmp / "scenario"
    if not folder.exists():
        shutil.copytree(WAREHOUSE, folder)
    path = folder / file
    obj = json.loads(path.read_text())
    mutate(obj)
    path.write_text(json.dumps(obj))
    return folder


def simulate_with(file: str, mutate: Callable[[dict], object]) -> Callable[[pathlib.Path], list[str]]:
    return lambda tmp: [
        *SOCIALNAV,
        "simulate",
        "--scenario",
        str(scenario(tmp, file, mutate)),
        "--out",
        str(tmp / "out"),
        *SHORT_DAY,
    ]


def simulate_args(*extra: str) -> Callable[[pathlib.Path], list[str]]:
    def make(tmp):
        args = [*SOCIALNAV, "simulate", "--out", str(tmp / "out"), *SHORT_DAY]
        for e in extra:  # a later option of the same name wins in argparse
            args.append(e.replace("{tmp}", str(tmp)))
        return args

    return make


def setp(section: str, key: str, value) -> Callable[[dict], None]:
    def mutate(obj):
        obj[section][key] = value

    return mutate


def _move_waypoint(name: str, x: float, y: float) -> Callable[[dict], None]:
    def mutate(obj):
        (wp,) = [wp for wp in obj["waypoints"] if wp["id"] == name]
        wp["x_m"], wp["y_m"] = x, y

    return mutate


def _drop_edges_of(name: str) -> Callable[[dict], None]:
    def mutate(obj):
        obj["edges"] = [e for e in obj["edges"] if name not in e]

    return mutate


def _raw(file: str, text: bytes) -> Callable[[pathlib.Path], list[str]]:
    def make(tmp):
        folder = scenario(tmp, file, lambda obj: None)
        (folder / file).write_bytes(text)
        return [*SOCIALNAV, "simulate", "--scenario", str(folder), "--out", str(tmp / "out"), *SHORT_DAY]

    return make


# --- shared fixtures: a short run's logs and tables, made once -----------------------------------


FIXTURES = pathlib.Path(tempfile.mkdtemp(prefix="hostile-fixtures-"))


def base_run() -> pathlib.Path:
    """A 2-world day of 60 s slots with its causal tables (made once per harness run); the
    battery starts low so that the robot charges and the causal variables vary."""
    run = FIXTURES / "run"
    if not (run / "causal" / "engine_tables.npz").exists():
        low = scenario(FIXTURES, "params.json", setp("battery", "initial_pct", 21.0))
        for argv in (
            ["simulate", "--scenario", str(low), "--out", str(run), "--worlds", "2", "--slot-length-s", "60"],
            ["learn", "--logs", str(run)],
        ):
            done = subprocess.run([*SOCIALNAV, *argv, "--no-progress"], capture_output=True, text=True, cwd=ROOT)
            if done.returncode:
                raise RuntimeError(f"fixture {argv[0]} failed: {done.stderr.strip().splitlines()[-1:]}")
    return run


def logs_with(change: Callable[[object], object]) -> Callable[[pathlib.Path], list[str]]:
    """``socialnav learn`` on a copy of the base run's logs changed by ``change(frame)``."""

    def make(tmp):
        import pandas as pd

        run = tmp / "run"
        run.mkdir()
        shutil.copy(base_run() / "run.json", run / "run.json")
        frame = pd.read_parquet(base_run() / "logs.parquet")
        frame = change(frame)
        if frame is not None:
            frame.to_parquet(run / "logs.parquet")
        return [*SOCIALNAV, "learn", "--logs", str(run), "--no-progress"]

    return make


def tables_with(change: Callable[[dict], dict | bytes]) -> Callable[[pathlib.Path], list[str]]:
    """``socialnav evaluate`` on a copy of the base run's engine tables changed by ``change``."""

    def make(tmp):
        import numpy as np

        with np.load(base_run() / "causal" / "engine_tables.npz", allow_pickle=False) as f:
            tables = {k: f[k] for k in f.files}
        out = change(tables)
        path = tmp / "engine_tables.npz"
        if isinstance(out, bytes):
            path.write_bytes(out)
        else:
            np.savez(path, **out)
        return [*SOCIALNAV, "evaluate", "--tables", str(path), "--replicas", "1", "--slots", "S1", "--no-progress"]

    return make


def _truncated_tables(tables):
    import io

    import numpy as np

    buf = io.BytesIO()
    np.savez(buf, **tables)
    return buf.getvalue()[: len(buf.getvalue()) // 2]


def _reversed_names(tables):
    tables["waypoints"] = tables["waypoints"][::-1].copy()
    return tables


def _drop_key(tables):
    tables.pop(sorted(tables)[0])
    return tables


def python_case(code: str) -> Callable[[pathlib.Path], list[str]]:
    return lambda tmp: [PY, "-c", code]


GSCL_INPUT = (
    "import numpy as np; from models.inference import {fn}; import jax.numpy as jnp\n"
    "occ = np.zeros((100, 100), np.float32)\n"
)


def _gscl_predict(values: str) -> Callable[[pathlib.Path], list[str]]:
    """``SocialCostModel`` of a tiny training run applied to ``values`` (a Python expression)."""

    def make(tmp):
        run = tiny_gscl_run()
        code = (
            "import numpy as np\n"
            "from socialnav.models.inference import SocialCostModel\n"
            f"model = SocialCostModel.load({str(run)!r})\n"
            f"print(np.asarray(model({values})).mean())\n"
        )
        return [PY, "-c", code]

    return make


def tiny_gscl_run() -> pathlib.Path:
    run = FIXTURES / "gscl"
    if not (run / "config.json").exists():
        code = (
            "from socialnav.models.config import TrainConfig; from models.train import train\n"
            "train(TrainConfig(features=(4, 4, 8, 8), epochs=1, batch_size=16, train_fraction=0.01, "
            f"test_fraction=0.004, warmup_steps=2), {str(run)!r}, progress=False)\n"
        )
        subprocess.run([PY, "-c", code], check=True, capture_output=True, cwd=ROOT)
    return run


def _copy_gscl(mutate: Callable[[pathlib.Path], None]) -> Callable[[pathlib.Path], list[str]]:
    def make(tmp):
        run = tmp / "gscl"
        shutil.copytree(tiny_gscl_run(), run)
        mutate(run)
        return [*SOCIALNAV, "gscl", "evaluate", "--run", str(run), "--examples", "1"]

    return make


def _truncate_checkpoint(run: pathlib.Path) -> None:
    files = sorted(p for p in (run / "checkpoints").rglob("*") if p.is_file() and p.stat().st_size > 1000)
    biggest = max(files, key=lambda p: p.stat().st_size)
    biggest.write_bytes(biggest.read_bytes()[: biggest.stat().st_size // 3])


def _other_width(run: pathlib.Path) -> None:
    cfg = json.loads((run / "config.json").read_text())
    cfg["features"] = [8, 8, 8, 8]
    (run / "config.json").write_text(json.dumps(cfg))


def arena_scene(
    mutate: Callable[[dict], object], scene: str = "casn_static_person"
) -> Callable[[pathlib.Path], list[str]]:
    """``socialnav arena`` on a mutated copy of a built-in scene (seed 001's static person)."""

    def make(tmp):
        obj = json.loads((ROOT / "data" / "scenes" / f"{scene}.json").read_text())
        mutate(obj)
        path = tmp / "scene.json"
        path.write_text(json.dumps(obj))
        options = ["--scenes", str(path), "--methods", "navfn", "--variants", "2", "--no-progress"]
        return [*SOCIALNAV, "arena", "--out", str(tmp / "a"), *options]

    return make


def _arena_fast_robot(tmp: pathlib.Path) -> list[str]:
    """``socialnav arena`` with a 3 m/s robot (``--params``): 0.3 m a 0.1 s step, more than its
    0.275 m radius, so the base could end a step past a thin wall."""
    (tmp / "fast.toml").write_text("[robot]\nmax_speed_mps = 3.0\nmax_accel_mps2 = 30.0\n")
    options = ["--scenes", "casn_static_person", "--methods", "navfn", "--variants", "2", "--no-progress"]
    return [*SOCIALNAV, "arena", "--out", str(tmp / "a"), "--params", str(tmp / "fast.toml"), *options]


ENV_LONG_STEP = (
    "from socialnav.data import SCENES_DIR\n"
    "from socialnav.jaxsim.scenes import env as env_lib\n"
    "from socialnav.jaxsim.scenes.gym_env import SocialNavEnv\n"
    "from socialnav.jaxsim.scenes.spec import load_scene\n"
    "env = SocialNavEnv(load_scene(SCENES_DIR / 'gscl_l_hallway.json'), pool=4, config=env_lib.EnvConfig(dt_s=1.0))\n"
    "env.reset(seed=0)\n"
    "print('made and reset: 0.5 m a step for a 0.275 m body')\n"
)


TABLE_TWICE = (
    "import tempfile\n"
    "from socialnav.data import SCENES_DIR\n"
    "from socialnav.evaluation.arena import table\n"
    "from socialnav.jaxsim.scenes.spec import load_scene\n"
    "request = table.TableRequest(specs=(load_scene(SCENES_DIR / 'casn_head_on.json'),), methods=('navfn', 'navfn'),"
    " variants=2)\n"
    "episodes, _ = table.run_table(tempfile.mkdtemp(), request)\n"
    "print('n for navfn:', int((episodes['method'] == 'navfn').sum()))\n"
)


def _track_file(rows: Callable[[int, int], str], header: str = "frame,id,x,y") -> Callable[[pathlib.Path], list[str]]:
    """``gscl fit-tracks`` on a 30 m empty map and a track file of six walkers, 20 frames each:
    ``header``, then ``rows(frame, person)`` (one CSV line each, walking along x at y = 10-15 m)."""
    fit = _tracks_at(lambda f: 1.0 + 0.5 * f)

    def make(tmp):
        argv = fit(tmp)
        lines = [header] + [rows(f, p) for p in range(6) for f in range(20)]
        (tmp / "t.csv").write_text("\n".join(lines) + "\n")
        return argv

    return make


# Reads a ROS map with whichever module has the reader (planners.learning.ros_map now; before,
# planners.learning.tracks) and prints the walls of each image column, top row first.
ROS_MAP_WALLS = (
    "import numpy as np, pathlib\n"
    "from PIL import Image\n"
    "try:\n"
    "    from socialnav.planners.learning.ros_map import read_ros_map\n"
    "except ImportError:\n"
    "    from socialnav.planners.learning.tracks import read_ros_map\n"
    "pixels, extra = {pixels}, {extra!r}\n"
    "path = pathlib.Path({image!r})\n"
    "if path.suffix == '.pgm':\n"
    "    path.write_bytes(b'P5\\n%d 1\\n65535\\n' % pixels.shape[1] + pixels.astype('>u2').tobytes())\n"
    "else:\n"
    "    Image.fromarray(pixels).save(path)\n"
    "pathlib.Path('m.yaml').write_text(f'image: {{path}}\\nresolution: 0.1\\norigin: [0, 0, 0]\\n' + extra)\n"
    "print('WALLS', read_ros_map('m.yaml')[0][0].astype(int).tolist())\n"
)


def _walls_are(expected: list[int]) -> Callable[[pathlib.Path, subprocess.CompletedProcess], bool]:
    return lambda tmp, proc: proc.returncode == 0 and f"WALLS {expected}" in proc.stdout


# The same six walkers and a wall, at zero and in a UTM-like frame (x + 5e5 m, y + 5e6 m), their
# windows compared.
TRACKS_FAR_FROM_ZERO = (
    "import numpy as np\n"
    "from socialnav.planners.learning import tracks\n"
    "occ = np.zeros((300, 300), np.float32); occ[160:166, 120:180] = 1\n"
    "near = {p: np.stack([np.arange(20), 12 + 0.3 * np.arange(20), 10 + 1.1 * p + 0.05 * np.arange(20)], 1)"
    " for p in range(6)}\n"
    "far = {p: t + [0, 5e5, 5e6] for p, t in near.items()}\n"
    "a = tracks.track_demonstrations(near, occ, 0.1, (0.0, 0.0))[0]\n"
    "b = tracks.track_demonstrations(far, occ, 0.1, (5e5, 5e6))[0]\n"
    "print('SAME WINDOWS' if np.array_equal(a, b) else f'{int((a != b).sum())} of {a.size} window cells moved')\n"
)


SIMULATE_ENTRY_1E8 = (
    "from socialnav.jaxsim import logs\n"
    "from socialnav.jaxsim.route_follower import route_follower\n"
    "from socialnav.jaxsim.scenario import load_scenario\n"
    "from socialnav.jaxsim.world import build_world\n"
    "from socialnav.planners.warehouse.routes import shortest_path_plan\n"
    "s = load_scenario(slot_length_s=20.0, n_workers=5)\n"
    "driver = route_follower(shortest_path_plan(s), build_world(s))\n"
    "logs.simulate_to_parquet(s, 'o', driver, n_worlds=10**8, duration_s=20.0, progress=False)\n"
    "print('simulated 10^8 worlds')\n"
)


def _scene_key_twice(tmp: pathlib.Path) -> list[str]:
    """``socialnav arena`` on seed 001's static person with a second ``timeout_s`` above the first
    (``json.loads`` keeps the last one)."""
    text = (ROOT / "data" / "scenes" / "casn_static_person.json").read_text()
    first = text.index('"timeout_s"')
    (tmp / "scene.json").write_text(text[:first] + '"timeout_s": 5,\n' + text[first:])
    options = ["--scenes", str(tmp / "scene.json"), "--methods", "navfn", "--variants", "2", "--no-progress"]
    return [*SOCIALNAV, "arena", "--out", str(tmp / "a"), *options]


def command(*argv: str) -> Callable[[pathlib.Path], list[str]]:
    """A command line; ``{tmp}`` is the case's scratch folder, ``{tables}`` the fixture's tables."""

    def make(tmp):
        out = []
        for a in argv:
            if "{tables}" in a:
                a = a.replace("{tables}", str(base_run() / "causal" / "engine_tables.npz"))
            if "{run}" in a:
                a = a.replace("{run}", str(base_run()))
            out.append(a.replace("{tmp}", str(tmp)))
        return [*SOCIALNAV, *out]

    return make


# --- file-safety cases ---------------------------------------------------------------------------


def _second_simulate(tmp):
    out = tmp / "out"
    subprocess.run([*SOCIALNAV, "simulate", "--out", str(out), *SHORT_DAY], check=True, capture_output=True, cwd=ROOT)
    (tmp / "first.sha").write_bytes((out / "logs.parquet").read_bytes())
    return [*SOCIALNAV, "simulate", "--out", str(out), *SHORT_DAY, "--seed", "5"]


def _first_run_kept(tmp, proc):
    out = tmp / "out"
    return proc.returncode != 0 and (out / "logs.parquet").read_bytes() == (tmp / "first.sha").read_bytes()


def _overwrite(tmp):
    out = tmp / "out"
    subprocess.run([*SOCIALNAV, "simulate", "--out", str(out), *SHORT_DAY], check=True, capture_output=True, cwd=ROOT)
    (out / "causal").mkdir()
    (out / "causal" / "stale.txt").write_text("from the old run")
    sys.path.insert(0, str(ROOT))
    from socialnav.common import runfolder

    runfolder.record(out / "causal", "socialnav learn", ["stale.txt"])  # a later job's run inside it
    return [*SOCIALNAV, "simulate", "--out", str(out), *SHORT_DAY, "--seed", "5", "--overwrite"]


def _overwritten_whole(tmp, proc):
    out = tmp / "out"
    return proc.returncode == 0 and not (out / "causal").exists() and json.loads((out / "run.json").read_text())


def _stale_temporary(tmp):
    out = tmp / "out"
    out.mkdir()
    (out / ".socialnav-tmp-99999-logs.parquet").write_bytes(b"half a file from a killed run")
    return [*SOCIALNAV, "simulate", "--out", str(out), *SHORT_DAY]


def _no_stale_left(tmp, proc):
    out = tmp / "out"
    return proc.returncode == 0 and not list(out.glob(".socialnav-tmp-*")) and (out / "logs.parquet").exists()


def _same_day(tmp, proc):
    return proc.returncode == 0


# --- round two (issue 30): files outside --out, --overwrite, resumption, estimates, noise ----------

INJECT_REMOVE_FAILURE = (
    "import os, shutil, sys\n"
    "FAIL = os.environ['FAIL_ON']\n"
    "def failing(fn):\n"
    "    def wrapper(p, *a, **k):\n"
    "        if os.path.basename(str(p)) == FAIL or str(p).endswith(os.sep + FAIL):\n"
    "            raise PermissionError(1, 'Operation not permitted', str(p))\n"
    "        return fn(p, *a, **k)\n"
    "    return wrapper\n"
    "os.unlink = failing(os.unlink); os.remove = failing(os.remove); os.rmdir = failing(os.rmdir)\n"
    "shutil.rmtree = failing(shutil.rmtree)\n"
    "_replace = os.replace\n"
    "def replace(src, dst, *a, **k):\n"
    "    if os.path.basename(str(src)) == FAIL and '.socialnav-staging-' not in str(src):\n"
    "        raise PermissionError(1, 'Operation not permitted', str(src))\n"
    "    return _replace(src, dst, *a, **k)\n"
    "os.replace = replace\n"
    "from socialnav.cli import main\n"
    "sys.exit(main(sys.argv[1:]))\n"
)


def _user_files(folder: pathlib.Path) -> dict[str, bytes]:
    """A folder of a user's own files (notes, data), made and returned as name -> content."""
    files = {"notes.txt": b"my notes", "data/measurements.csv": b"t,x\n0,1\n", "logs.txt": b"not a run"}
    for name, content in files.items():
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        (folder / name).write_bytes(content)
    return files


def _untouched(folder: pathlib.Path, files: dict[str, bytes]) -> bool:
    return all((folder / n).is_file() and (folder / n).read_bytes() == c for n, c in files.items())


def _overwrite_user_folder(*job: str) -> Callable[[pathlib.Path], list[str]]:
    """``job`` with ``--out {tmp}/mine --overwrite`` on a folder of the user's files."""

    def make(tmp):
        mine = tmp / "mine"
        mine.mkdir()
        (tmp / "expected.json").write_text(json.dumps({k: v.decode() for k, v in _user_files(mine).items()}))
        return command(*job, "--out", "{tmp}/mine", "--overwrite")(tmp)

    return make


# A user's hidden files named as the toolkit's scratch files were before round fifteen gave them
# its prefix: its lock (opened, truncated and removed by every job) and a killed job's
# temporary, staging and aside folders (removed by the next job's clean-up as its own).
LOOK_ALIKES = {
    ".lock": b"a user's lock",
    ".tmp-1-draft.txt": b"a draft",
    ".old-2024/thesis.tex": b"last year's thesis",
    ".staging-1/plan.txt": b"a plan",
}


def _look_alikes_in_out(*job: str) -> Callable[[pathlib.Path], list[str]]:
    """``job`` with ``--out {tmp}/mine``, a folder holding a user's :data:`LOOK_ALIKES`."""

    def make(tmp):
        mine = tmp / "mine"
        for name, content in LOOK_ALIKES.items():
            (mine / name).parent.mkdir(parents=True, exist_ok=True)
            (mine / name).write_bytes(content)
        (tmp / "expected.json").write_text(json.dumps({k: v.decode() for k, v in LOOK_ALIKES.items()}))
        return command(*job, "--out", "{tmp}/mine")(tmp)

    return make


def _look_alikes_kept(tmp, proc):
    return proc.returncode == 0 and _user_files_kept(tmp, proc)


def _copy_kept_inside(copy: Callable[[pathlib.Path], tuple[pathlib.Path, pathlib.Path]]):
    """``simulate --overwrite`` on a copy of the base run (its ``causal/`` inside) where the user
    kept a copy, ``copy(out) -> (source, kept)``, inside the run's folder."""

    def make(tmp):
        out = tmp / "out"
        shutil.copytree(base_run(), out)
        source, kept = copy(out)
        shutil.copytree(source, tmp / "copy", ignore=shutil.ignore_patterns("causal") if source == out else None)
        (tmp / "copy").rename(kept)
        files = {p.relative_to(tmp).as_posix(): p.read_bytes().hex() for p in kept.rglob("*") if p.is_file()}
        (tmp / "expected.json").write_text(json.dumps(files))
        return [*SOCIALNAV, "simulate", "--out", str(out), "--overwrite", *SHORT_DAY]

    return make


def _copy_untouched(tmp, proc):
    files = json.loads((tmp / "expected.json").read_text())
    same = all((tmp / rel).is_file() and (tmp / rel).read_bytes().hex() == h for rel, h in files.items())
    return proc.returncode == 0 and same and not (tmp / "out" / "causal" / "engine_tables.npz").exists()


def _user_files_kept(tmp, proc):
    files = {k: v.encode() for k, v in json.loads((tmp / "expected.json").read_text()).items()}
    return _untouched(tmp / "mine", files)


def _learn_into_its_logs(tmp):
    run = tmp / "run"
    shutil.copytree(base_run(), run, ignore=shutil.ignore_patterns("causal"))
    (run / "my-notes.txt").write_text("notes")
    (tmp / "logs.sha").write_bytes((run / "logs.parquet").read_bytes())
    return [*SOCIALNAV, "learn", "--logs", str(run), "--out", str(run), "--overwrite", "--no-progress"]


def _logs_kept(tmp, proc):
    run = tmp / "run"
    ok = (run / "logs.parquet").is_file() and (run / "logs.parquet").read_bytes() == (tmp / "logs.sha").read_bytes()
    return ok and (run / "run.json").is_file() and (run / "my-notes.txt").is_file()


def _scene_named(name: str, *, file: str = "scene.json") -> Callable[[pathlib.Path], pathlib.Path]:
    def write(tmp):
        obj = json.loads((ROOT / "data" / "scenes" / "casn_static_person.json").read_text())
        obj["name"] = name
        path = tmp / file
        path.write_text(json.dumps(obj))
        return path

    return write


def _arena_escape(tmp):
    """A scene named ``../../victim`` beside a folder of the user's called victim."""
    victim = tmp / "victim"
    victim.mkdir()
    (victim / "thesis.tex").write_text("three years of work")
    scene = _scene_named("../../victim")(tmp)
    return [*SOCIALNAV, "arena", "--out", str(tmp / "a"), "--scenes", str(scene), "--methods", "navfn"] + [
        "--variants",
        "2",
        "--no-progress",
    ]


def _nothing_outside(tmp, proc):
    inside = {p for p in tmp.rglob("*") if p.is_file() and (p.is_relative_to(tmp / "a") or p.name == "scene.json")}
    others = {p for p in tmp.rglob("*") if p.is_file()} - inside
    return (tmp / "victim" / "thesis.tex").is_file() and others == {tmp / "victim" / "thesis.tex"}


def _arena_edited_scene(tmp):
    """A run, then the scene file edited (the person moved 0.8 m), then a rerun into the same --out."""
    scene = _scene_named("mine")(tmp)
    argv = [*SOCIALNAV, "arena", "--out", str(tmp / "a"), "--scenes", str(scene), "--methods", "navfn"]
    argv += ["--variants", "2", "--no-progress"]
    subprocess.run(argv, check=True, capture_output=True, cwd=ROOT)
    (tmp / "before.csv").write_bytes((tmp / "a" / "summary.csv").read_bytes())
    obj = json.loads(scene.read_text())
    obj["robot"]["goal"] = [obj["robot"]["goal"][0], obj["robot"]["goal"][1] + 0.8]
    scene.write_text(json.dumps(obj))
    return argv


def _edit_seen(tmp, proc):
    """Refused with a line naming the scene, or recomputed (the summary changed)."""
    if proc.returncode != 0:
        return "mine" in proc.stderr and "Traceback" not in proc.stderr
    return (tmp / "a" / "summary.csv").read_bytes() != (tmp / "before.csv").read_bytes()


def _two_scenes_one_name(tmp):
    first = _scene_named("twin", file="one.json")(tmp)
    second = _scene_named("twin", file="two.json")(tmp)
    return [*SOCIALNAV, "arena", "--out", str(tmp / "a"), "--scenes", f"{first},{second}", "--methods", "navfn"] + [
        "--variants",
        "2",
        "--no-progress",
    ]


def _commit_cannot_remove(tmp):
    """A previous run one of whose files cannot be removed, replaced with --overwrite."""
    out = tmp / "out"
    subprocess.run([*SOCIALNAV, "simulate", "--out", str(out), *SHORT_DAY], check=True, capture_output=True, cwd=ROOT)
    (tmp / "old.parquet").write_bytes((out / "logs.parquet").read_bytes())
    (tmp / "old.json").write_bytes((out / "run.json").read_bytes())
    os.environ["FAIL_ON"] = "snapshot.png"
    return [PY, "-c", INJECT_REMOVE_FAILURE, "simulate", "--out", str(out), *SHORT_DAY, "--seed", "5", "--overwrite"]


def _one_whole_run(tmp, proc):
    """Either the old run whole (and the error names the file) or the new one whole."""
    out = tmp / "out"
    if not (out / "run.json").is_file() or not (out / "logs.parquet").is_file():
        return False
    old = (out / "run.json").read_bytes() == (tmp / "old.json").read_bytes()
    if old:
        same_logs = (out / "logs.parquet").read_bytes() == (tmp / "old.parquet").read_bytes()
        return same_logs and proc.returncode != 0 and "snapshot.png" in proc.stderr
    return json.loads((out / "run.json").read_text())["seed"] == 5


def _damaged_newest_checkpoint(tmp):
    run = tmp / "gscl"
    shutil.copytree(tiny_gscl_run(), run)
    steps = sorted((run / "checkpoints").iterdir(), key=lambda p: int(p.name) if p.name.isdigit() else -1)
    (tmp / "steps").write_text(str(len([s for s in steps if s.name.isdigit()])))
    newest = [s for s in steps if s.name.isdigit()][-1]
    for f in newest.rglob("*"):
        if f.is_file() and f.stat().st_size > 100:
            f.write_bytes(f.read_bytes()[: f.stat().st_size // 3])
    return [*SOCIALNAV, "gscl", "evaluate", "--run", str(run), "--examples", "1"]


def _quiet_fallback(tmp, proc):
    """One warning naming the skipped step, not hundreds of lines of third-party noise."""
    text = proc.stderr + proc.stdout
    if int((tmp / "steps").read_text()) < 2:
        return proc.returncode != 0 and len(text.strip().splitlines()) <= 3
    return proc.returncode == 0 and "Event loop is closed" not in text and len(proc.stderr.splitlines()) <= 5


def _layers_with(mutate: Callable[[pathlib.Path], None]) -> Callable[[pathlib.Path], list[str]]:
    def make(tmp):
        run = tmp / "gscl"
        shutil.copytree(tiny_gscl_run(), run)
        mutate(run)
        return [*SOCIALNAV, "layers", "--out", str(tmp / "img"), "--gscl-run", str(run)]

    return make


def _empty_checkpoints(run: pathlib.Path) -> None:
    shutil.rmtree(run / "checkpoints")
    (run / "checkpoints").mkdir()


def _bad_config(run: pathlib.Path) -> None:
    (run / "config.json").write_text('{"features": "wide"')


def _text_as_tables(tmp):
    path = tmp / "engine_tables.npz"
    path.write_text("these are not tables\n")
    return [*SOCIALNAV, "evaluate", "--tables", str(path), "--replicas", "1", "--slots", "S1", "--no-progress"]


def _generate_read_only(tmp):
    return [*SOCIALNAV, "gscl", "generate", "--out", "/proc/socialnav-data.npz", "--count", "group=8"]


def _evaluate_out_a_file(tmp):
    (tmp / "f").write_text("a file of mine")
    return [*SOCIALNAV, "gscl", "evaluate", "--run", str(tiny_gscl_run()), "--out", str(tmp / "f")]


def _scene_people(mutate: Callable[[dict], object]) -> Callable[[pathlib.Path], list[str]]:
    """``socialnav arena`` on a copy of seed 001's group scene changed by ``mutate``."""

    def make(tmp):
        obj = json.loads((ROOT / "data" / "scenes" / "casn_static_person.json").read_text())
        mutate(obj)
        path = tmp / "scene.json"
        path.write_text(json.dumps(obj))
        return [*SOCIALNAV, "arena", "--out", str(tmp / "a"), "--scenes", str(path), "--methods", "navfn"] + [
            "--variants",
            "2",
            "--no-progress",
        ]

    return make


def _second_person_at_first(obj):
    first = obj["people"][0]
    obj["people"].append(dict(first))


def _person_on_start(obj):
    obj["people"].append({"behaviour": "standing", "position": obj["robot"]["start"], "heading_deg": 0})


def _goal_at_start(obj):
    obj["robot"]["goal"] = list(obj["robot"]["start"])


def _waypoint_on_wall_face(obj):
    """Move ``toilet-1`` onto the face of the first wall box (x exactly at its xmin)."""
    (wp,) = [wp for wp in obj["waypoints"] if wp["id"] == "toilet-1"]
    wp["x_m"], wp["y_m"] = 9.925, 0.0


# --- round three (issue 60): actions, scene geometry, track files, resumes, small things ---------

ENV_STEP = (
    "import jax, jax.numpy as jnp, numpy as np\n"
    "from socialnav.data import SCENES_DIR\n"
    "from socialnav.evaluation.arena import episodes as arena\n"
    "from socialnav.jaxsim.scenes.spec import load_scene\n"
    "from socialnav.jaxsim.scenes.variant import sample_variant\n"
    "setup = arena.setup_scene(load_scene(SCENES_DIR / 'snape_walking.json'))\n"
    "v = jax.tree.map(jnp.asarray, sample_variant(setup.spec, 0, 0, n_slots=setup.n_slots))\n"
    "state, ts = setup.env.reset(jax.random.key(0), v)\n"
    "step = jax.jit(setup.env.step)\n"
    "for _ in range(30):\n"
    "    state, ts = step(state, {action})\n"
    "leaves = jax.tree.leaves((state.robot.xy, state.people.xy, ts.reward))\n"
    "finite = all(bool(jnp.all(jnp.isfinite(a))) for a in leaves)\n"
    "marked = bool(getattr(ts.info, 'invalid_action', False))\n"
    "print('FINITE' if finite else 'NOT FINITE', 'MARKED' if marked else 'NOT MARKED')\n"
)


def _env_nan_stays_finite(tmp, proc):
    return proc.returncode == 0 and "FINITE MARKED" in proc.stdout and "NOT" not in proc.stdout


ENV_STEP_0 = (
    "import jax\n"
    "import numpy as np\n"
    "from socialnav.data import SCENES_DIR\n"
    "from socialnav.jaxsim.scenes import env as env_lib\n"
    "from socialnav.jaxsim.scenes.gym_env import SocialNavEnv\n"
    "from socialnav.jaxsim.scenes.spec import load_scene\n"
    "env = SocialNavEnv(load_scene(SCENES_DIR / 'snape_walking.json'), pool=4, config=env_lib.EnvConfig(dt_s=0.0))\n"
    "obs, _ = env.reset(seed=0)\n"
    "after, *_ = env.step(np.array([0.5, 0.0], np.float32))\n"
    "same = all(np.array_equal(a, b) for a, b in zip(jax.tree.leaves(obs), jax.tree.leaves(after)))\n"
    "print('nothing moved' if same else 'it moved')\n"
)

GYM_WALLED_OFF = (
    "import json, pathlib\n"
    "from socialnav.data import SCENES_DIR\n"
    "from socialnav.jaxsim.scenes.gym_env import SocialNavEnv\n"
    "from socialnav.jaxsim.scenes.spec import load_scene\n"
    "obj = json.loads((SCENES_DIR / 'casn_static_person.json').read_text())\n"
    "obj['walls'].append([2.0, 2.2, -3.0, 3.0])\n"
    "path = pathlib.Path(SCENE_PATH)\n"
    "path.write_text(json.dumps(obj))\n"
    "env = SocialNavEnv(load_scene(path), pool=4)\n"
    "env.reset(seed=0)\n"
    "print('made and reset: every episode would run to its timeout')\n"
)

GYM_NAN = (
    "import numpy as np\n"
    "from socialnav.data import SCENES_DIR\n"
    "from socialnav.jaxsim.scenes.gym_env import SocialNavEnv\n"
    "from socialnav.jaxsim.scenes.spec import load_scene\n"
    "env = SocialNavEnv(load_scene(SCENES_DIR / 'snape_walking.json'), pool=4)\n"
    "env.reset(seed=0)\n"
    "for _ in range(5):\n"
    "    obs, *_ = env.step(np.array([np.nan, np.nan], np.float32))\n"
    "print('INSIDE' if env.observation_space.contains(obs) else 'OUTSIDE its space')\n"
)


def _gym_inside(tmp, proc):
    return proc.returncode == 0 and "INSIDE" in proc.stdout


ODD_ACTORS = """
import jax.numpy as jnp
from socialnav.jaxsim.scenes import Actor


def nan_after_a_second(env):
    def act(robot, state, obs, key):
        return jnp.where(obs.time_s > 1.0, jnp.nan, 1.0) * jnp.array([robot.max_speed_mps, 0.0]), state

    return Actor(init=lambda key, obs: (), act=act, name="nan_after_a_second")


def one_number(env):
    return Actor(init=lambda key, obs: (), act=lambda p, s, o, k: (jnp.array([0.5]), s), name="one_number")


def a_scalar(env):
    return Actor(init=lambda key, obs: (), act=lambda p, s, o, k: (jnp.float32(0.5), s), name="a_scalar")
"""


def _arena_actor(function: str) -> Callable[[pathlib.Path], list[str]]:
    def make(tmp):
        (tmp / "odd_actors.py").write_text(ODD_ACTORS)
        argv = ["arena", "--out", str(tmp / "a"), "--scenes", "snape_walking", "--methods", "navfn", "--variants", "2"]
        return [*SOCIALNAV, *argv, "--actor", f"{tmp / 'odd_actors.py'}:{function}", "--no-progress"]

    return make


def _nan_actor_marked(tmp, proc):
    import pandas as pd

    if proc.returncode != 0 or not (tmp / "a" / "summary.csv").is_file():
        return False
    summary = pd.read_csv(tmp / "a" / "summary.csv").set_index("method")
    marked = "invalid_action_pct" in summary and summary.loc["nan_after_a_second", "invalid_action_pct"] > 0
    return marked and "NaN or infinite action" in proc.stderr


def _fit_tracks(
    map_yaml: str, image: str, pixels: Callable, x_of_frame: Callable[[int], float], y_of_person: Callable[[int], float]
) -> Callable[[pathlib.Path], list[str]]:
    """``gscl fit-tracks`` on six walkers (20 frames at ``x_of_frame(f)``, ``y_of_person(p)``) and a
    ROS map: ``map.yaml`` of ``map_yaml``, its image file ``image`` of ``pixels(numpy)``."""

    def make(tmp):
        import numpy as np
        from PIL import Image

        Image.fromarray(pixels(np)).save(tmp / image)
        (tmp / "map.yaml").write_text(map_yaml)
        rows = ["frame,id,x,y"] + [f"{f},{p},{x_of_frame(f)},{y_of_person(p)}" for p in range(6) for f in range(20)]
        (tmp / "t.csv").write_text("\n".join(rows) + "\n")
        argv = ["gscl", "fit-tracks", "--tracks", str(tmp / "t.csv"), "--map", str(tmp / "map.yaml")]
        return [*SOCIALNAV, *argv, "--out", str(tmp / "m"), "--steps", "2", "--no-progress"]

    return make


def _tracks_at(x_of_frame: Callable[[int], float]) -> Callable[[pathlib.Path], list[str]]:
    """``gscl fit-tracks`` on six walkers at ``x_of_frame`` over a 30 m empty ROS map at the origin."""
    map_yaml = "image: map.pgm\nresolution: 0.1\norigin: [0.0, 0.0, 0.0]\n"
    return _fit_tracks(map_yaml, "map.pgm", lambda np: np.full((300, 300), 254, np.uint8), x_of_frame, lambda p: 10 + p)


def _ros_map_with(map_yaml: str) -> Callable[[pathlib.Path], list[str]]:
    """``gscl fit-tracks`` on six walkers and a 3 m empty ROS map of ``map_yaml`` (its image
    ``map.png``): a bad field is refused before any work."""
    return _fit_tracks(
        map_yaml, "map.png", lambda np: np.full((30, 30), 254, np.uint8), lambda f: 1 + 0.05 * f, lambda p: 1 + 0.2 * p
    )


GSCL_RESUME = (
    "import pathlib, sys\n"
    "from socialnav.models.config import TrainConfig\n"
    "from socialnav.models.train import train\n"
    "out = pathlib.Path('run')\n"
    "cfg = TrainConfig(features=(4, 4, 8, 8), epochs=2, batch_size=16, train_fraction=0.01, test_fraction=0.004, "
    "warmup_steps=2, checkpoint_every_steps=3)\n"
    "train(cfg, out, progress=False, max_steps=6, log=lambda *a: None)\n"
    "for f in (out / 'checkpoints' / '6').rglob('*'):\n"
    "    if f.is_file() and f.stat().st_size > 100:\n"
    "        f.write_bytes(f.read_bytes()[: f.stat().st_size // 3])\n"
    "for attempt in range(2):\n"
    "    try:\n"
    "        train(cfg, out, progress=False, max_steps=6 + attempt, log=lambda *a: None)\n"
    "    except Exception as e:\n"
    "        sys.exit(f'resume {attempt + 1}: {type(e).__name__}: {e}')\n"
    "print('RESUMED TWICE')\n"
)

POLICY_RESUME = (
    "import dataclasses, pathlib, sys\n"
    "from socialnav.data import SCENES_DIR\n"
    "from socialnav.jaxsim.scenes.spec import load_scene\n"
    "from socialnav.planners.learning import policy_run\n"
    "from socialnav.planners.learning.policy_training import PPOConfig\n"
    "spec = load_scene(SCENES_DIR / 'casn_static_person.json')\n"
    "cfg = PPOConfig(scenes=('casn_static_person',), envs_per_scene=4, rollout_steps=8, updates=4, minibatches=2, "
    "pool_per_scene=8, checkpoint_every=2)\n"
    "run = pathlib.Path('ppo')\n"
    "policy_run.train([spec], cfg, run, progress=False)\n"
    "for f in (run / 'checkpoints' / '4').rglob('*'):\n"
    "    if f.is_file() and f.stat().st_size > 100:\n"
    "        f.write_bytes(f.read_bytes()[: f.stat().st_size // 3])\n"
    "try:\n"
    "    history = policy_run.train([spec], cfg, run, progress=False, log=lambda *a: None)\n"
    "except Exception as e:\n"
    "    sys.exit(f'{type(e).__name__}: {e}')\n"
    "print('RESUMED at', [h['update'] for h in history])\n"
)


def _resumed(word: str):
    return lambda tmp, proc: proc.returncode == 0 and word in proc.stdout


def _policy_updates(tmp):
    base = ["policy", "train", "--out", str(tmp / "ppo"), "--scenes", "casn_static_person", "--envs-per-scene", "4"]
    base += ["--rollout-steps", "8", "--no-progress"]
    subprocess.run([*SOCIALNAV, *base, "--updates", "3"], check=True, capture_output=True, cwd=tmp)
    return [*SOCIALNAV, *base]  # resumed with the same options but no --updates


def _kept_its_updates(tmp, proc):
    recorded = json.loads((tmp / "ppo" / "config.json").read_text())["ppo"]["updates"]
    return proc.returncode == 0 and recorded == 3


def _second_export(tmp):
    first = [*SOCIALNAV, "gscl", "export", "--run", str(tiny_gscl_run()), "--out", str(tmp / "m"), "--scenes", "1"]
    subprocess.run(first, check=True, capture_output=True, cwd=tmp)
    (tmp / "card.json").write_bytes((tmp / "m" / "model.json").read_bytes())
    return first


def _first_export_kept(tmp, proc):
    kept = (tmp / "m" / "model.json").read_bytes() == (tmp / "card.json").read_bytes()
    return proc.returncode != 0 and "--overwrite" in proc.stderr and kept


def _symlinked_manifest(tmp):
    """A run folder holding ``link -> ../victim`` and a hand-edited manifest entry through it."""
    out = tmp / "out"
    subprocess.run([*SOCIALNAV, "simulate", "--out", str(out), *SHORT_DAY], check=True, capture_output=True, cwd=tmp)
    victim = tmp / "victim"
    victim.mkdir()
    (victim / "precious.txt").write_text("the user's")
    (out / "link").symlink_to(victim, target_is_directory=True)
    manifest = json.loads((out / ".socialnav-run.json").read_text())
    manifest["files"].append("link/precious.txt")
    (out / ".socialnav-run.json").write_text(json.dumps(manifest))
    return [*SOCIALNAV, "simulate", "--out", str(out), *SHORT_DAY, "--seed", "5", "--overwrite"]


def _symlinked_lock(tmp):
    """A run folder whose lock file (``.socialnav-lock``; ``.lock`` before round fifteen) is a
    symbolic link to a user's file beside it."""
    out = tmp / "out"
    out.mkdir()
    (tmp / "precious.txt").write_text("the user's")
    (out / ".socialnav-lock").symlink_to(tmp / "precious.txt")
    return [*SOCIALNAV, "simulate", "--out", str(out), *SHORT_DAY]


def _lock_target_kept(tmp, proc):
    return (tmp / "precious.txt").read_text() == "the user's" and proc.returncode != 0 and "-lock" in proc.stderr


def _victim_kept(tmp, proc):
    return (tmp / "victim" / "precious.txt").is_file() and proc.returncode != 0 and "link/precious.txt" in proc.stderr


def _unicode_waypoint(obj):
    for wp in obj["waypoints"]:
        if wp["id"] == "toilet-1":
            wp["id"] = "Toilette-ü1"


def _unicode_simulate(tmp):
    folder = scenario(tmp, "waypoints.json", lambda o: None)
    for file in folder.glob("*.json"):
        file.write_text(file.read_text(encoding="utf-8").replace('"toilet-1"', '"Toilette-ü1"'), encoding="utf-8")
    return [*SOCIALNAV, "simulate", "--scenario", str(folder), "--out", str(tmp / "out"), *SHORT_DAY]


def _own_scene_names_only_its_files(tmp, proc):
    wrote = [line for line in proc.stdout.splitlines() if line.startswith("wrote ")]
    said = wrote[-1] if wrote else ""
    listed = [name for name in ("papers.csv", "directions.csv") if name in said]
    return proc.returncode == 0 and bool(said) and all((tmp / "a" / name).exists() for name in listed)


def _estimate_holds(tmp, proc):
    """The printed estimate within a factor of two of the run's own time (its process's wall
    time, measured by the harness), or a range that holds it."""
    import re

    line = next((x for x in proc.stdout.splitlines() if x.startswith("arena:")), "")
    took = getattr(proc, "took_s", math.nan)
    numbers = [
        float(v) * (60.0 if unit.startswith("min") else 1.0)
        for v, unit in re.findall(r"(\d+(?:\.\d+)?) ?(s|min)\b", line.split("about")[-1].split("(")[0])
    ]
    if proc.returncode != 0 or not numbers:
        return False
    lo, hi = min(numbers[:2]), max(numbers[:2])
    return lo / 2 <= took <= 2 * hi


def _timed_arena(tmp):
    argv = [*SOCIALNAV, "arena", "--out", str(tmp / "a"), "--scenes", "casn_head_on,gscl_group", "--methods"]
    return argv + ["navfn,snl_small,orca", "--variants", "6", "--no-progress"]


# --- round eight: the machine's faults (a full disk, Ctrl-C, a scheduler's SIGTERM) ---------------

FULL_DISK_BYTES = 20_000  # short of the largest file of every job below (a layer's picture is 17-29 kB)
WHOLE_DAY = ["--worlds", "2", "--no-progress"]  # long enough (tens of seconds) to be stopped midway


def full_disk(name: str, make, expect_words: tuple[str, ...] = (), **fields) -> Case:
    """A case run under :data:`FULL_DISK_BYTES`'s file-size limit (300 s unless ``timeout_s``)."""
    return Case(name, make, expect_words, file_size_limit_bytes=FULL_DISK_BYTES, **{"timeout_s": 300, **fields})


def _last_line(proc: subprocess.CompletedProcess) -> str:
    return next((line for line in reversed((proc.stderr or "").splitlines()) if line.strip()), "")


def _one_line(proc: subprocess.CompletedProcess, *words: str) -> bool:
    """No traceback, and the last line of stderr holds ``words`` (case-insensitive)."""
    last = _last_line(proc)
    return "Traceback" not in (proc.stderr or "") and bool(last) and all(w.lower() in last.lower() for w in words)


def _nothing_left(folder: pathlib.Path) -> bool:
    """``folder`` absent, or holding nothing (no staging folder, no lock file)."""
    return not folder.exists() or not any(folder.iterdir())


def _stopped_cleanly(code: int, words: str) -> Callable[[pathlib.Path, subprocess.CompletedProcess], bool]:
    def check(tmp, proc):
        return proc.returncode == code and _one_line(proc, words) and _nothing_left(tmp / "out")

    return check


NAMES_A_FILE = re.compile(r"cannot write /\S+: ")


def _names_a_file(proc: subprocess.CompletedProcess) -> bool:
    """Exit status 2 and one line (no traceback) naming the file the command could not write."""
    return proc.returncode == 2 and _one_line(proc, "socialnav") and NAMES_A_FILE.search(_last_line(proc)) is not None


def _full_disk_nothing_left(tmp, proc):
    return _names_a_file(proc) and _nothing_left(tmp / "out")


def _previous_engine(tmp):
    """A finished ``learn`` run in ``tmp/out`` (the fixture's), then ``learn --overwrite`` into it."""
    shutil.copytree(base_run() / "causal", tmp / "out")
    (tmp / "before").mkdir()
    for f in (tmp / "out").iterdir():
        if f.is_file():
            shutil.copy(f, tmp / "before" / f.name)
    return [*SOCIALNAV, "learn", "--logs", str(base_run()), "--out", str(tmp / "out"), "--overwrite", "--no-progress"]


def _previous_engine_kept(tmp, proc):
    kept = all((tmp / "out" / f.name).read_bytes() == f.read_bytes() for f in (tmp / "before").iterdir())
    return _names_a_file(proc) and kept and not list((tmp / "out").glob(".socialnav-staging-*"))


# --- round nine: the environment a user brings ---------------------------------------------------

SMALL_ARENA = [
    "arena",
    "--scenes",
    "casn_head_on,gscl_group",
    "--methods",
    "navfn,gscl",
    "--variants",
    "2",
    "--no-progress",
]


def _x64_case(name: str, argv: list[str], files: tuple[str, ...], **fields) -> Case:
    """``argv`` (``{tmp}/out`` its run folder) under ``JAX_ENABLE_X64=1``, checked against the same
    command run again without it: ``files`` byte for byte."""
    make = command(*argv)

    def check(tmp, proc):
        if proc.returncode != 0:
            return False
        out, plain = tmp / "out", tmp / "plain"
        again = [a.replace(str(out), str(plain)) for a in make(tmp)]
        env = dict(os.environ, PYTHONPATH=str(ROOT), JAX_ENABLE_X64="0")
        subprocess.run(again, capture_output=True, cwd=tmp, env=env, timeout=600)
        return all((plain / f).is_file() and (out / f).read_bytes() == (plain / f).read_bytes() for f in files)

    return Case(name, make, check=check, env={"JAX_ENABLE_X64": "1"}, **fields)


ARENA_UNDER_X64 = (
    "import jax\n"
    "jax.config.update('jax_enable_x64', True)  # a notebook's set-up, for its own float64 work\n"
    "from socialnav.data import SCENES_DIR\n"
    "from socialnav.evaluation import arena\n"
    "from socialnav.jaxsim.scenes import load_scene\n"
    "episodes, _ = arena.run_scene(load_scene(SCENES_DIR / 'casn_head_on.json'), ['navfn'], 2)\n"
)


def _killed_then_again(tmp):
    """``simulate`` killed by SIGKILL (no handler runs: the out-of-memory killer, ``kill -9``) 15 s
    in, its lock and staging folder left; then the same command again, shorter."""
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    argv = [*SOCIALNAV, "simulate", "--out", str(tmp / "out"), *WHOLE_DAY]
    with subprocess.Popen(argv, cwd=tmp, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env) as child:
        time.sleep(15)
        child.kill()
    (tmp / "left.txt").write_text(" ".join(sorted(p.name for p in (tmp / "out").iterdir())))
    return [*SOCIALNAV, "simulate", "--out", str(tmp / "out"), *SHORT_DAY]


def _second_run_whole(tmp, proc):
    names = sorted(p.name for p in (tmp / "out").iterdir())
    killed_left = (tmp / "left.txt").read_text().split()
    leftovers = [n for n in names if n == ".socialnav-lock" or n.startswith(".socialnav-staging")]
    return proc.returncode == 0 and ".socialnav-lock" in killed_left and "logs.parquet" in names and not leftovers


def _arena_under_hash_seed_one(tmp):
    """The small arena run under ``PYTHONHASHSEED=1`` into ``tmp/h1``; the case runs it under 2."""
    argv = [*SOCIALNAV, *SMALL_ARENA, "--out"]
    env = dict(os.environ, PYTHONPATH=str(ROOT), PYTHONHASHSEED="1")
    subprocess.run([*argv, str(tmp / "h1")], capture_output=True, cwd=tmp, env=env, timeout=600)
    return [*argv, str(tmp / "h2")]


def _same_tables(tmp, proc):
    names = ("summary.csv", "stats.csv")
    return proc.returncode == 0 and all(
        (tmp / "h1" / n).is_file() and (tmp / "h1" / n).read_bytes() == (tmp / "h2" / n).read_bytes() for n in names
    )


def _beside_a_file(make: Callable[[pathlib.Path], list[str]]) -> Callable[[pathlib.Path], list[str]]:
    """``make``, with a file ``{tmp}/a-file`` made first (for a variable naming it as a folder)."""

    def made(tmp):
        (tmp / "a-file").write_text("not a folder")
        return make(tmp)

    return made


def _ran_and_named(variable: str):
    """A check: the run succeeded and its stderr names ``variable`` (what it could not use)."""
    return lambda tmp, proc: proc.returncode == 0 and variable in (proc.stderr or "")


# --- round ten: a user's own recording in the arena ----------------------------------------------


def _tracks(
    tmp: pathlib.Path, edit: Callable[[object], object] = lambda rows: rows, run: str = "crowds_zara01"
) -> pathlib.Path:
    """A shipped recording (ETH/UCY's zara01 unless ``run`` names another) written as a user's
    tracks file (``frame, id, x, y``; frames of a 25 fps video), ``edit`` applied to its rows (a
    pandas DataFrame)."""
    import pandas as pd

    from socialnav.data import recorded

    shipped = recorded.trajectories(run)
    rows = pd.DataFrame({"frame": shipped["frame"], "id": shipped["person"], "x": shipped["x_m"], "y": shipped["y_m"]})
    path = tmp / "tracks.csv"
    edit(rows).to_csv(path, index=False)
    return path


def _arena_scene_of(edit: Callable[[object], object] = lambda rows: rows, fps: str = "25", run: str = "crowds_zara01"):
    """``socialnav arena-scene`` on the edited tracks file, into ``{tmp}/scenes``."""
    return lambda tmp: [
        *SOCIALNAV,
        "arena-scene",
        str(_tracks(tmp, edit, run)),
        "--frames-per-s",
        fps,
        "--out",
        str(tmp / "scenes"),
    ]


def _predict_on(edit: Callable[[object], object]):
    """``socialnav humans predict`` on zara01's tracks, ``edit`` applied to them."""
    return lambda tmp: [*SOCIALNAV, "humans", "predict", "--tracks", str(_tracks(tmp, edit)), "--frames-per-s", "25",
                        "--out", str(tmp / "out"), "--no-progress"]  # fmt: skip


def _first_fifteen(rows):
    """Each person's first 15 frames: tracks too short for 8 observed and 12 predicted."""
    return rows[rows.groupby("id").cumcount() < 15]


def _arena_scene_with_map_at(origin_m: float):
    """``socialnav arena-scene`` on zara01's tracks with a free 25 x 22 m ROS map whose origin is
    ``(origin_m, origin_m)``."""

    def make(tmp):
        from PIL import Image

        Image.new("L", (250, 220), 254).save(tmp / "map.pgm")
        (tmp / "map.yaml").write_text(f"image: map.pgm\nresolution: 0.1\norigin: [{origin_m}, {origin_m}, 0.0]\n")
        return [*_arena_scene_of()(tmp), "--map", str(tmp / "map.yaml")]

    return make


def _seven_copies(rows):
    """The recording seven times over, each copy 1 cm aside under other ids (147 people at once)."""
    import pandas as pd

    return pd.concat([rows.assign(id=rows["id"] + 1000 * k, x=rows["x"] + 0.01 * k) for k in range(7)])


def _arena_on_scene(edit_scene: Callable[[dict], object], variants: str = "2"):
    """The arena (NavFn) on the tracks file's replayed scene, ``edit_scene`` applied to its JSON."""

    def make(tmp):
        made = subprocess.run(_arena_scene_of()(tmp), capture_output=True, text=True, timeout=120)
        if made.returncode:
            raise RuntimeError(made.stderr)
        path = tmp / "scenes" / "tracks_replayed.json"
        scene = json.loads(path.read_text())
        edit_scene(scene)
        path.write_text(json.dumps(scene))
        return [
            *SOCIALNAV,
            "arena",
            "--scenes",
            str(path),
            "--methods",
            "navfn",
            "--variants",
            variants,
            "--out",
            str(tmp / "out"),
            "--no-progress",
        ]

    return make


def _edited_recording_then_resumed(tmp):
    """An arena run on the tracks file's scenes; one person's position edited in the file; the
    same command again (a resume)."""
    argv = _arena_on_scene(lambda scene: None)(tmp)
    first = subprocess.run(argv, capture_output=True, text=True, timeout=300)
    if first.returncode:
        raise RuntimeError(first.stderr)
    tracks = tmp / "tracks.csv"
    lines = tracks.read_text().splitlines()
    frame, pid, x, y = lines[5].split(",")
    lines[5] = ",".join([frame, pid, str(float(x) + 0.5), y])
    tracks.write_text("\n".join(lines) + "\n")
    return argv


# --- round eleven: a calibration's fit as the people of a run (--human-fit) -----------------------

_FIT_FIELDS = ["speed.time_gap_s", "speed.neighbor_strength", "speed.neighbor_range_m", "group.gaze_per_rad",
               "group.attraction_mps2"]  # fmt: skip


def _tracks_fit() -> dict:
    """A ``humans calibrate --data tracks`` record, as the command writes it (its fields)."""
    row = {"scene": "mine.csv", "gradient_values": dict(zip(_FIT_FIELDS, [0.17, 4.7, 0.027, 0.41, 2.5], strict=True)),
           "nelder_mead_values": dict(zip(_FIT_FIELDS, [0.03, 11.2, 0.005, 0.2, 518.0], strict=True)),
           "sample_loss": {"start": 0.53, "gradient": 0.448, "nelder_mead": 0.449}}  # fmt: skip
    return {"model": "collision_free_speed_calibrated", "data": "tracks", "fields": list(_FIT_FIELDS),
            "scenes": [row], "complete": True}  # fmt: skip


def _with_fit(mutate: Callable[[dict], object] = lambda fit: None, option: str = "{fit}", job: str = ""):
    """A small arena run (or ``job``) with ``--human-fit`` of ``_tracks_fit()`` written to
    ``{tmp}/calibration/fit.json`` after ``mutate``; ``option`` the option's text."""

    def make(tmp):
        fit = _tracks_fit()
        mutate(fit)
        (tmp / "calibration").mkdir()
        (tmp / "calibration" / "fit.json").write_text(json.dumps(fit))  # NaN written as NaN, as Python does
        given = option.replace("{fit}", str(tmp / "calibration" / "fit.json")).replace("{tmp}", str(tmp))
        small = ["arena", "--scenes", "gscl_group", "--methods", "navfn", "--variants", "2", "--out", str(tmp / "out"),
                 "--no-progress"]  # fmt: skip
        argv = job.replace("{tmp}", str(tmp)).split() or small
        return [*SOCIALNAV, *argv, "--human-fit", given]

    return make


def _both_values(field: str, value) -> Callable[[dict], None]:
    def mutate(fit):
        row = fit["scenes"][0]
        if field not in fit["fields"]:
            fit["fields"].append(field)
        for method in ("gradient", "nelder_mead"):
            row[f"{method}_values"][field] = value

    return mutate


def _stopped_after_the_gradient(fit):
    fit["complete"] = False
    del fit["scenes"][0]["nelder_mead_values"]


def _arena_then_another_fit(tmp):
    """An arena run with the fit's gradient point, then the same command with its search's."""
    argv = _with_fit(option="{fit}:gradient")(tmp)
    first = subprocess.run(argv, capture_output=True, text=True, timeout=300)
    if first.returncode:
        raise RuntimeError(first.stderr)
    return [*argv[:-1], str(tmp / "calibration" / "fit.json") + ":nelder_mead"]


def _ran_with_fit(tmp, proc):
    """The run holds the fit's gradient values under its model's name."""
    run = tmp / "out" / "run.json"
    if proc.returncode or not run.is_file():
        return False
    meta = json.loads(run.read_text())
    return (meta.get("human_model") == "collision_free_speed_calibrated"
            and meta.get("human_values") == _tracks_fit()["scenes"][0]["gradient_values"])  # fmt: skip


def _walker_into_a_room(left_wall: list[list[float]], end_xy: tuple[float, float] = (2.5, 2.0)):
    """``socialnav arena`` on seed 001's static person with a side room in the upper right (x in
    [1.6, 3.4], y in [1.1, 2.85]; its left wall ``left_wall``) and a walker from (-3, 0.5) to
    ``end_xy`` in the room: the straight line crosses the room's left wall."""
    room = [[1.5, 3.5, 1.0, 1.1], [3.4, 3.5, 1.0, 2.85], *left_wall]
    walker = {"behaviour": "walk", "from": [-3, 0.5], "to": list(end_xy), "speed_mps": 1.0, "start_s": 0}

    def mutate(obj):
        obj["walls"] += room
        obj["people"].append(walker)
        obj["timeout_s"] = 40

    def make(tmp):
        argv = arena_scene(mutate)(tmp)
        return [*argv, "--keep-trajectories", "2"]

    return make


def _standing_in(scene: str, xy: tuple[float, float]) -> Callable[[pathlib.Path], list[str]]:
    """``socialnav arena`` on a built-in scene with a person standing at ``xy`` added."""
    person = {"behaviour": "standing", "position": list(xy), "heading_deg": 0}
    return arena_scene(lambda o: o["people"].append(person), scene=scene)


def _pass_behind_a_routed_walker(tmp: pathlib.Path) -> list[str]:
    """``socialnav arena`` on :func:`_walker_into_a_room`'s scene with a 1 m door (the walker routed
    round its post), its rule ``pass_behind`` that walker: the rule reads the straight line."""
    room = [[1.5, 3.5, 1.0, 1.1], [3.4, 3.5, 1.0, 2.85], [1.5, 1.6, 1.0, 1.85]]
    walker = {"behaviour": "walk", "from": [-3, 0.5], "to": [2.5, 1.4], "speed_mps": 1.0, "start_s": 0}

    def mutate(obj):
        obj["walls"] += room
        obj["people"].append(walker)
        obj["rule"] = {"type": "pass_behind", "person": 1}
        obj["timeout_s"] = 40

    return arena_scene(mutate)(tmp)


def _walker_got_in(end_xy: tuple[float, float]):
    """The run finished and in both variants the walker (slot 1) ends within the arena's arrival
    distance (0.3 m) of ``end_xy``."""

    def check(tmp, proc):
        import pandas as pd

        files = list((tmp / "a" / "trajectories").glob("*.parquet"))
        if proc.returncode or not files:
            return False
        rows = pd.read_parquet(files[0])
        last = rows.sort_values("t_s").groupby("variant").tail(1)
        gap = ((last["p1_x"] - end_xy[0]) ** 2 + (last["p1_y"] - end_xy[1]) ** 2) ** 0.5
        return len(last) == 2 and bool((gap < 0.3).all())

    return check


def _queue_into_a_room(left_wall: list[list[float]]):
    """``socialnav arena`` on seed 001's static person with the side room of
    :func:`_walker_into_a_room` (its left wall ``left_wall``) and a queue of three whose head is at
    (0.5, 2) facing the room and whose exit is in it at (2.5, 1.4): the served leave across the
    room's left wall."""
    queue = {"behaviour": "queue", "head": [0.5, 2.0], "towards_deg": 0, "length": 3, "spacing_m": 0.7,
             "advance_every_s": 5, "exit": [2.5, 1.4]}  # fmt: skip

    def mutate(obj):
        obj["walls"] += [[1.5, 3.5, 1.0, 1.1], [3.4, 3.5, 1.0, 2.85], *left_wall]
        obj["people"].append(queue)
        obj["timeout_s"] = 40

    def make(tmp):
        return [*arena_scene(mutate)(tmp), "--keep-trajectories", "2"]

    return make


def _queue_left(tmp, proc):
    """The run finished and in both variants every queue member (slots 1-3) has left by the end."""
    import pandas as pd

    files = list((tmp / "a" / "trajectories").glob("*.parquet"))
    if proc.returncode or not files:
        return False
    last = pd.read_parquet(files[0]).sort_values("t_s").groupby("variant").tail(1)
    return len(last) == 2 and not last[["p1_present", "p2_present", "p3_present"]].to_numpy().any()


def _arena_ran(tmp, proc):
    """The run's summary holds the scene's NavFn row over its 2 variants."""
    import pandas as pd

    summary = tmp / "out" / "summary.csv"
    if proc.returncode or not summary.is_file():
        return False
    rows = pd.read_csv(summary)
    return list(rows["scene"]) == ["tracks_replayed"] and list(rows["n"]) == [2]


CASES: list[Case] = [
    # params.json: ranges and types
    Case(
        "params: robot accel 0", simulate_with("params.json", setp("robot", "accel_mps2", 0)), ("params.json", "accel")
    ),
    Case(
        "params: robot accel negative",
        simulate_with("params.json", setp("robot", "accel_mps2", -1)),
        ("params.json", "accel"),
    ),
    Case(
        "params: battery initial -10 %",
        simulate_with("params.json", setp("battery", "initial_pct", -10)),
        ("params.json", "initial_pct"),
    ),
    Case(
        "params: battery initial 150 %",
        simulate_with("params.json", setp("battery", "initial_pct", 150)),
        ("params.json", "initial_pct"),
    ),
    Case(
        "params: negative static drain",
        simulate_with("params.json", setp("battery", "static_pct_per_s", -0.1)),
        ("params.json", "static_pct_per_s"),
    ),
    Case(
        "params: negative activity time",
        simulate_with("params.json", setp("workers", "activity_min_s", -5)),
        ("params.json", "activity_min_s"),
    ),
    Case(
        "params: negative stuck time",
        simulate_with("params.json", setp("workers", "stuck_time_s", -1)),
        ("params.json", "stuck_time_s"),
    ),
    Case(
        "params: toilet min above max",
        simulate_with("params.json", setp("workers", "toilet_activity_min_s", 9)),
        ("params.json", "toilet_activity"),
    ),
    Case(
        "params: n_workers 2.7",
        simulate_with("params.json", setp("sim", "n_workers", 2.7)),
        ("params.json", "n_workers"),
    ),
    Case(
        "params: n_workers 40,000",
        simulate_with("params.json", setp("sim", "n_workers", 40_000)),
        ("params.json", "n_workers"),
        timeout_s=90,
    ),
    Case(
        "params: n_workers 10^6",
        simulate_with("params.json", setp("sim", "n_workers", 10**6)),
        ("params.json", "n_workers"),
        timeout_s=90,
    ),
    Case(
        "params: n_workers '50'",
        simulate_with("params.json", setp("sim", "n_workers", "50")),
        ("params.json", "n_workers"),
    ),
    Case("params: dt 0", simulate_with("params.json", setp("sim", "dt_s", 0)), ("params.json", "dt_s")),
    Case(
        "params: negative radius",
        simulate_with("params.json", setp("workers", "radius_m", -0.2)),
        ("params.json", "radius"),
    ),
    Case(
        "params: random force std negative",
        simulate_with("params.json", setp("workers", "random_force_std_mps2", -1)),
        ("params.json", "random_force"),
    ),
    Case(
        "params: desired speed min above max speed",
        simulate_with("params.json", setp("workers", "desired_speed_min_mps", 3.0)),
        ("params.json", "desired_speed"),
    ),
    Case(
        "params: obstacle probability 1.5",
        simulate_with("params.json", setp("robot", "obstacle_probability", 1.5)),
        ("params.json", "obstacle_probability"),
    ),
    Case(
        "params: missing section", simulate_with("params.json", lambda o: o.pop("battery")), ("params.json", "battery")
    ),
    Case(
        "params: unknown key",
        simulate_with("params.json", setp("robot", "max_sped_mps", 1.0)),
        ("params.json", "max_sped"),
    ),
    Case("params: not UTF-8", _raw("params.json", b"\xff\xfe{ \x00"), ("params.json",)),
    Case("params: a JSON list", _raw("params.json", b"[1, 2]"), ("params.json", "object")),
    Case("params: empty file", _raw("params.json", b""), ("params.json",)),
    # geometry and graph
    Case(
        "waypoints: one moved to (500, -700)",
        simulate_with("waypoints.json", _move_waypoint("toilet-1", 500.0, -700.0)),
        ("waypoints.json", "toilet-1"),
        timeout_s=90,
    ),
    Case(
        "waypoints: NaN radius",
        _raw(
            "waypoints.json",
            b'{"waypoints": [{"id": "parking", "x_m": 0, "y_m": 0, "radius_m": NaN, "kind": "p", '
            b'"human_destination": false}]}',
        ),
        ("waypoints.json", "radius_m"),
    ),
    Case("graph: no edges", simulate_with("graph.json", lambda o: o.update(edges=[])), ("graph.json",)),
    Case(
        "graph: a destination cut off",
        simulate_with("graph.json", _drop_edges_of("toilet-1")),
        ("graph.json", "toilet-1"),
    ),
    Case(
        "graph: the charger cut off",
        simulate_with("graph.json", _drop_edges_of("charging-station")),
        ("graph.json", "charging-station"),
    ),
    Case(
        "walls: an empty box",
        simulate_with("walls.json", lambda o: o["boxes"][0].update(xmax_m=o["boxes"][0]["xmin_m"])),
        ("walls.json", "boxes[0]"),
    ),
    Case(
        "schedule: probabilities sum to 0.5",
        simulate_with("schedule.json", lambda o: o["slots"][0].update(destinations={"toilet-1": 0.5})),
        ("schedule.json", "destinations"),
    ),
    Case(
        "tasks: a goal that does not exist",
        simulate_with("tasks.json", lambda o: o["slots"][0].update(goals=["nowhere"])),
        ("tasks.json", "goals"),
    ),
    # command-line values
    Case("cli: --slots 15 of 11", simulate_args("--slots", "15"), ("--slots", "11")),
    Case("cli: --slots 0", simulate_args("--slots", "0"), ("--slots",)),
    Case("cli: --hours inf", simulate_args("--hours", "inf"), ("--hours",)),
    Case("cli: --hours nan", simulate_args("--hours", "nan"), ("--hours",)),
    Case("cli: --slot-length-s nan", simulate_args("--slot-length-s", "nan"), ("--slot-length-s",)),
    Case("cli: --slot-length-s -60", simulate_args("--slot-length-s", "-60"), ("--slot-length-s",)),
    Case("cli: --sample-interval-s inf", simulate_args("--sample-interval-s", "inf"), ("--sample-interval-s",)),
    Case("cli: --sample-interval-s 0.15", simulate_args("--sample-interval-s", "0.15"), ("--sample-interval-s", "0.1")),
    Case("cli: --snapshot-time-s nan", simulate_args("--snapshot-time-s", "nan"), ("--snapshot-time-s",)),
    Case("cli: --snapshot-time-s 1e9", simulate_args("--snapshot-time-s", "1e9"), ("--snapshot-time-s",)),
    Case("cli: --worlds 0", simulate_args("--worlds", "0"), ("--worlds",)),
    Case("cli: --worlds 10^8", simulate_args("--worlds", "100000000"), ("--worlds", "GB"), timeout_s=90),
    Case("cli: --obstacle-probability 2", simulate_args("--obstacle-probability", "2"), ("--obstacle-probability",)),
    Case("cli: --out ''", simulate_args("--out", ""), ("--out",)),
    Case(
        "cli: --out a file",
        lambda tmp: (tmp.joinpath("f").write_text("x"), simulate_args("--out", "{tmp}/f")(tmp))[1],
        ("--out",),
    ),
    Case("cli: --out cannot be created", simulate_args("--out", "/proc/socialnav-run"), ("--out", "/proc")),
    Case("cli: --seed -1 (32-bit seeds: it would repeat 2^32 - 1)", simulate_args("--seed", "-1"), ("--seed",)),
    Case("cli: --seed 4294967295 (valid)", simulate_args("--seed", "4294967295"), check=_same_day),
    Case(
        "cli: evaluate --slots S99",
        lambda tmp: [
            *SOCIALNAV,
            "evaluate",
            "--tables",
            str(base_run() / "causal" / "engine_tables.npz"),
            "--slots",
            "S99",
        ],
        ("--slots", "S99"),
    ),
    Case(
        "cli: evaluate --replicas 0",
        lambda tmp: [
            *SOCIALNAV,
            "evaluate",
            "--tables",
            str(base_run() / "causal" / "engine_tables.npz"),
            "--replicas",
            "0",
        ],
        ("--replicas",),
    ),
    Case(
        "cli: learn --alpha 2",
        lambda tmp: [*SOCIALNAV, "learn", "--logs", str(base_run()), "--alpha", "2"],
        ("--alpha",),
    ),
    Case(
        "cli: gscl train --learning-rate inf",
        lambda tmp: [*SOCIALNAV, "gscl", "train", "--out", str(tmp / "g"), "--learning-rate", "inf"],
        ("--learning-rate",),
    ),
    Case(
        "cli: gscl train --learning-rate nan",
        lambda tmp: [*SOCIALNAV, "gscl", "train", "--out", str(tmp / "g"), "--learning-rate", "nan"],
        ("--learning-rate",),
    ),
    Case(
        "cli: gscl generate --scale 1e-9",
        lambda tmp: [*SOCIALNAV, "gscl", "generate", "--out", str(tmp / "d.npz"), "--scale", "1e-9"],
        ("--scale",),
    ),
    Case(
        "cli: gscl generate --count nothing=5",
        lambda tmp: [*SOCIALNAV, "gscl", "generate", "--out", str(tmp / "d.npz"), "--count", "nothing=5"],
        ("nothing",),
    ),
    Case(
        "cli: arena --scenes nowhere",
        lambda tmp: [*SOCIALNAV, "arena", "--out", str(tmp / "a"), "--scenes", "nowhere"],
        ("nowhere",),
    ),
    # logs
    Case("logs: folder without logs", lambda tmp: [*SOCIALNAV, "learn", "--logs", str(tmp)], ("logs.parquet",)),
    Case(
        "logs: truncated parquet",
        lambda tmp: (
            (tmp / "run").mkdir(),
            (tmp / "run" / "logs.parquet").write_bytes((base_run() / "logs.parquet").read_bytes()[:5000]),
            shutil.copy(base_run() / "run.json", tmp / "run" / "run.json"),
            [*SOCIALNAV, "learn", "--logs", str(tmp / "run")],
        )[3],
        ("logs.parquet",),
    ),
    Case(
        "logs: a column dropped", logs_with(lambda f: f.drop(columns=["battery_pct"])), ("logs.parquet", "battery_pct")
    ),
    Case(
        "logs: NaN in a column",
        logs_with(lambda f: f.assign(robot_speed_mps=float("nan"))),
        ("logs.parquet", "robot_speed_mps"),
    ),
    Case(
        "logs: duplicated rows",
        logs_with(lambda f: __import__("pandas").concat([f, f.iloc[:100]])),
        ("logs.parquet", "time"),
    ),
    Case("logs: time not increasing", logs_with(lambda f: f.iloc[::-1]), ("logs.parquet", "time")),
    Case("logs: wrong dtype", logs_with(lambda f: f.assign(slot=f["slot"].astype(str))), ("logs.parquet", "slot")),
    # engine tables
    Case("tables: truncated", tables_with(_truncated_tables), ("engine_tables.npz",)),
    Case("tables: random bytes", tables_with(lambda t: os.urandom(4000)), ("engine_tables.npz",)),
    Case("tables: a key missing", tables_with(_drop_key), ("engine_tables.npz",)),
    Case("tables: waypoint order differs", tables_with(_reversed_names), ("engine_tables.npz", "waypoint")),
    # checkpoints and model inputs
    Case("checkpoint: truncated", _copy_gscl(_truncate_checkpoint), ("checkpoint",)),
    Case("checkpoint: config names another width", _copy_gscl(_other_width), ("config.json", "features")),
    Case("model input: 0/1 occupancy", _gscl_predict("np.ones((1, 40, 40), np.float32)"), ("0", "255"), api=True),
    Case("model input: walls coded 254", _gscl_predict("np.full((1, 40, 40), 254, np.uint8)"), ("254",), api=True),
    Case("model input: NaN", _gscl_predict("np.full((1, 40, 40), np.nan, np.float32)"), ("NaN",), api=True),
    Case("model input: bool", _gscl_predict("np.zeros((1, 40, 40), bool)"), ("bool",), api=True),
    Case("model input: wrong shape", _gscl_predict("np.zeros((1, 30, 40), np.uint8)"), ("40",), api=True),
    Case(
        "model input: person at NaN",
        python_case(
            GSCL_INPUT.format(fn="input_map")
            + "input_map(occ, 0.1, (0.0, 0.0), (5.0, 5.0), [[np.nan, 5.0]], [0.0], (8.0, 5.0))\n"
        ),
        ("people_xy_m", "NaN"),
        api=True,
    ),
    # more commands and files
    Case(
        "more: arena scene with NaN goal",
        arena_scene(lambda o: o["robot"].update(goal=[float("nan"), 0.0])),
        ("scene.json", "goal"),
    ),
    Case("more: arena scene without robot", arena_scene(lambda o: o.pop("robot")), ("scene.json", "robot")),
    Case("more: arena scene timeout -1", arena_scene(lambda o: o.update(timeout_s=-1)), ("scene.json", "timeout_s")),
    Case(
        "more: arena goal inside a wall",
        arena_scene(lambda o: o["robot"].update(goal=[4.9, 0.0])),
        ("scene.json", "goal"),
    ),
    Case("more: arena --variants 0", command("arena", "--out", "{tmp}/a", "--variants", "0"), ("--variants",)),
    Case("more: arena --methods nothing", command("arena", "--out", "{tmp}/a", "--methods", "nothing"), ("nothing",)),
    Case(
        "more: evaluate --collision-radius-m nan",
        command("evaluate", "--tables", "{tables}", "--collision-radius-m", "nan"),
        ("--collision-radius-m",),
    ),
    Case(
        "more: evaluate --collision-radius-m -1",
        command("evaluate", "--tables", "{tables}", "--collision-radius-m", "-1"),
        ("--collision-radius-m",),
    ),
    Case(
        "more: evaluate --tables a folder", command("evaluate", "--tables", "{tmp}", "--replicas", "1"), ("--tables",)
    ),
    Case("more: learn --step 0", command("learn", "--logs", "{run}", "--out", "{tmp}/c", "--step", "0"), ("--step",)),
    Case("more: learn --worlds 99", command("learn", "--logs", "{run}", "--out", "{tmp}/c", "--worlds", "99"), ("99",)),
    Case(
        "more: learn --waypoints nowhere",
        command("learn", "--logs", "{run}", "--out", "{tmp}/c", "--waypoints", "nowhere"),
        ("nowhere",),
    ),
    Case(
        "more: gscl train --batch-size 0",
        command("gscl", "train", "--out", "{tmp}/g", "--batch-size", "0"),
        ("--batch-size",),
    ),
    Case(
        "more: gscl train --features 1,2",
        command("gscl", "train", "--out", "{tmp}/g", "--features", "1,2"),
        ("--features",),
    ),
    Case("more: gscl evaluate --run nowhere", command("gscl", "evaluate", "--run", "{tmp}/nowhere"), ("nowhere",)),
    Case(
        "more: simulate --scenario a file",
        command("simulate", "--scenario", "{tmp}/x.json", "--out", "{tmp}/o"),
        ("x.json",),
    ),
    Case(
        "more: ablation --probabilities 0,2",
        command("ablation", "--out", "{tmp}/a", "--probabilities", "0,2"),
        ("--probabilities",),
    ),
    Case("more: ablation --seeds 0", command("ablation", "--out", "{tmp}/a", "--seeds", "0"), ("--seeds",)),
    # run folders
    Case("folder: a second run into the same --out", _second_simulate, check=_first_run_kept, fail_label="data lost"),
    Case("folder: --overwrite replaces the run whole", _overwrite, check=_overwritten_whole),
    Case("folder: a killed run's temporary", _stale_temporary, check=_no_stale_left),
    # round two (issue 30): files outside --out, --overwrite, resumption
    Case("r2 lost: arena scene named ../../victim", _arena_escape, check=_nothing_outside, fail_label="data lost"),
    Case(
        "r2 lost: simulate --overwrite on a folder of user files",
        _overwrite_user_folder("simulate", *SHORT_DAY),
        check=_user_files_kept,
        fail_label="data lost",
    ),
    Case(
        "r2 lost: ablation --overwrite on a folder of user files",
        _overwrite_user_folder("ablation", "--seeds", "1", "--probabilities", "0.3", "--no-progress"),
        check=_user_files_kept,
        fail_label="data lost",
        timeout_s=300,
    ),
    Case(
        "r2 lost: evaluate --overwrite on a folder of user files",
        _overwrite_user_folder("evaluate", "--tables", "{tables}", "--replicas", "1", "--slots", "S1", "--no-progress"),
        check=_user_files_kept,
        fail_label="data lost",
        timeout_s=300,
    ),
    Case(
        "r2 lost: learn --overwrite on a folder of user files",
        _overwrite_user_folder("learn", "--logs", "{run}", "--no-progress"),
        check=_user_files_kept,
        fail_label="data lost",
        timeout_s=300,
    ),
    Case(
        "r2 lost: learn --out its own --logs --overwrite",
        _learn_into_its_logs,
        check=_logs_kept,
        fail_label="data lost",
    ),
    Case(
        "r2 lost: a commit that cannot remove an old file",
        _commit_cannot_remove,
        check=_one_whole_run,
        fail_label="data lost",
    ),
    Case("r2 stale: arena rerun after the scene file was edited", _arena_edited_scene, check=_edit_seen),
    Case("r2 stale: two scene files with one name", _two_scenes_one_name, ("twin", "one.json")),
    Case(
        "r2 hang: arena --variants 10^9",
        command("arena", "--out", "{tmp}/a", "--scenes", "casn_head_on", "--variants", "1000000000", "--no-progress"),
        ("--variants", "GB"),
        timeout_s=60,
    ),
    Case(
        "r2 hang: gscl generate --scale 10^6",
        command("gscl", "generate", "--out", "{tmp}/d.npz", "--scale", "1000000"),
        ("--scale", "GB"),
        timeout_s=60,
    ),
    Case(
        "r2 hang: evaluate --replicas 10^7",
        command("evaluate", "--tables", "{tables}", "--out", "{tmp}/e", "--replicas", "10000000", "--no-progress"),
        ("--replicas", "GB"),
        timeout_s=60,
    ),
    # round two: tracebacks
    Case("r2 traceback: simulate --seed 2^70", simulate_args("--seed", str(2**70)), ("--seed",)),
    Case(
        "r2 traceback: arena --seed 2^70",
        command("arena", "--out", "{tmp}/a", "--scenes", "casn_head_on", "--seed", str(2**70)),
        ("--seed",),
    ),
    Case("r2 traceback: gscl generate onto a read-only file system", _generate_read_only, ("/proc",)),
    Case("r2 traceback: gscl evaluate --out a file", _evaluate_out_a_file, ("--out",)),
    Case("r2 traceback: layers with an empty checkpoints folder", _layers_with(_empty_checkpoints), ("checkpoint",)),
    Case("r2 traceback: layers with a bad config.json", _layers_with(_bad_config), ("config.json",)),
    Case("r2 noise: a damaged newest checkpoint", _damaged_newest_checkpoint, check=_quiet_fallback),
    # round two: accepted without a word
    Case(
        "r2 silent: waypoint radius 1e6 m",
        simulate_with("waypoints.json", lambda o: o["waypoints"][1].update(radius_m=1e6)),
        ("waypoints.json", "radius_m"),
    ),
    Case(
        "r2 silent: worker radius 5 m",
        simulate_with("params.json", setp("workers", "radius_m", 5.0)),
        ("params.json", "radius_m"),
    ),
    Case(
        "r2 silent: a waypoint on a wall face",
        simulate_with("waypoints.json", _waypoint_on_wall_face),
        ("waypoints.json", "toilet-1"),
    ),
    Case(
        "r2 silent: an empty waypoint name",
        simulate_with("waypoints.json", lambda o: o["waypoints"][1].update(id="")),
        ("waypoints.json", "id"),
    ),
    Case("r2 silent: two people at one point", _scene_people(_second_person_at_first), ("scene.json", "people[1]")),
    Case("r2 silent: a person on the robot's start", _scene_people(_person_on_start), ("scene.json", "start")),
    Case("r2 silent: the robot's goal at its start", _scene_people(_goal_at_start), ("scene.json", "goal")),
    # round two: unclear messages
    Case(
        "r2 unclear: an empty wall list",
        simulate_with("walls.json", lambda o: o.update(boxes=[])),
        ("walls.json", "boxes"),
        misleading=("argmin",),
    ),
    Case(
        "r2 unclear: learn --step 100000",
        command("learn", "--logs", "{run}", "--out", "{tmp}/c", "--step", "100000", "--no-progress"),
        ("--step",),
        misleading=("No valid reference point",),
    ),
    Case(
        "r2 unclear: a text file given as tables",
        _text_as_tables,
        ("engine_tables.npz",),
        misleading=("allow_pickle",),
        timeout_s=120,
    ),
    # round three (issue 60)
    Case(
        "r3 lost: a manifest entry through a symbolic link out of --out",
        _symlinked_manifest,
        check=_victim_kept,
        fail_label="data lost",
    ),
    Case(
        "r3 silent: env NaN action",
        python_case(ENV_STEP.format(action="jnp.array([jnp.nan, 0.3])")),
        check=_env_nan_stays_finite,
        fail_label="accepted nonsense",
    ),
    Case(
        "r3 silent: env inf action",
        python_case(ENV_STEP.format(action="jnp.array([jnp.inf, 0.0])")),
        check=_env_nan_stays_finite,
        fail_label="accepted nonsense",
    ),
    Case(
        "r3 silent: env action of shape (1,)",
        python_case(ENV_STEP.format(action="jnp.array([0.5])")),
        ("shape (2,)",),
        api=True,
    ),
    Case(
        "r3 silent: env action of shape (3,)",
        python_case(ENV_STEP.format(action="jnp.array([0.5, 0.1, 3.0])")),
        ("shape (2,)",),
        api=True,
    ),
    Case(
        "r3 traceback: env scalar action",
        python_case(ENV_STEP.format(action="jnp.float32(0.5)")),
        ("shape (2,)",),
        api=True,
    ),
    Case(
        "r3 silent: gymnasium step([nan, nan])", python_case(GYM_NAN), check=_gym_inside, fail_label="accepted nonsense"
    ),
    Case(
        "r3 traceback: arena --actor returning NaN",
        _arena_actor("nan_after_a_second"),
        check=_nan_actor_marked,
        fail_label="accepted nonsense",
        timeout_s=300,
    ),
    Case(
        "r3 silent: arena --actor of shape (1,)",
        _arena_actor("one_number"),
        ("one_number", "shape (2,)"),
        timeout_s=300,
    ),
    Case("r3 traceback: arena --actor scalar", _arena_actor("a_scalar"), ("a_scalar", "shape (2,)"), timeout_s=300),
    Case(
        "r3 silent: a queue of 20 at 3 m in a 12 m room",
        arena_scene(lambda o: o["people"][0].update(length=20, spacing_m=3.0), "gscl_queue"),
        ("scene.json", "people[0].length"),
    ),
    Case(
        "r3 silent: a queue rule whose head is at (300, 0)",
        arena_scene(lambda o: o["rule"]["rules"][0].update(head=[300, 0]), "gscl_queue"),
        ("scene.json", "rule.rules[0].head", "outside"),
    ),
    Case(
        "r3 silent: fit-tracks 100 m from the map",
        _tracks_at(lambda f: 101.0 + 0.5 * f),
        ("t.csv", "map.yaml", "on the map"),
        timeout_s=300,
    ),
    Case(
        "r3 unclear: fit-tracks at 1e12 m",
        _tracks_at(lambda f: 1e12 + f),
        ("t.csv", "map.yaml", "on the map"),
        timeout_s=300,
    ),
    Case(
        "r3 loop: gscl resume past a damaged newest checkpoint",
        python_case(GSCL_RESUME),
        check=_resumed("RESUMED TWICE"),
        timeout_s=400,
    ),
    Case(
        "r3 unclear: policy resume past a damaged newest checkpoint",
        python_case(POLICY_RESUME),
        check=_resumed("RESUMED at [1, 2, 3, 4]"),
        timeout_s=400,
    ),
    Case("r3 wrong: policy resumed without --updates", _policy_updates, check=_kept_its_updates, timeout_s=400),
    Case(
        "r3 lost: gscl export twice into one --out",
        _second_export,
        check=_first_export_kept,
        fail_label="data lost",
        timeout_s=400,
    ),
    Case(
        "r3 traceback: input_map resolution 0",
        python_case(
            GSCL_INPUT.format(fn="input_map")
            + "input_map(occ, 0, (0.0, 0.0), (5.0, 5.0), [[4.0, 5.0]], [0.0], (8.0, 5.0))\n"
        ),
        ("resolution_m",),
        api=True,
    ),
    Case(
        "r3 silent: input_map resolution -0.05",
        python_case(
            GSCL_INPUT.format(fn="input_map")
            + "input_map(occ, -0.05, (0.0, 0.0), (5.0, 5.0), [[4.0, 5.0]], [0.0], (8.0, 5.0))\n"
        ),
        ("resolution_m",),
        api=True,
    ),
    Case(
        "r3 silent: input_map one heading for two people",
        python_case(
            GSCL_INPUT.format(fn="input_map")
            + "input_map(occ, 0.1, (0.0, 0.0), (5.0, 5.0), [[4.0, 5.0], [6.0, 5.0]], [0.0], (8.0, 5.0))\n"
        ),
        ("people_heading_rad",),
        api=True,
    ),
    Case(
        "r3 traceback: input_map 3-D occupancy",
        python_case(
            GSCL_INPUT.format(fn="input_map")
            + "input_map(occ[None], 0.1, (0.0, 0.0), (5.0, 5.0), [[4.0, 5.0]], [0.0], (8.0, 5.0))\n"
        ),
        ("occupancy",),
        api=True,
    ),
    Case(
        "r3 unclear: a waypoint entry given as a string",
        simulate_with("waypoints.json", lambda o: o["waypoints"].__setitem__(3, "toilet")),
        ("waypoints.json", "waypoints[3]", "object"),
    ),
    Case(
        "r3 unclear: a task slot given as a string",
        simulate_with("tasks.json", lambda o: o["slots"].__setitem__(0, "S1")),
        ("tasks.json", "slots[0]", "object"),
    ),
    Case(
        "r3 wrong: referee --do-worlds 0 (documented: skip)",
        command("referee", "--out", "{tmp}/r", "--do-worlds", "0", "--seeds", "x"),
        check=lambda tmp, proc: "argument --do-worlds" not in proc.stderr and "argument --seeds" in proc.stderr,
    ),
    Case(
        "r3 wrong: arena on a user's scene names only its files",
        arena_scene(lambda o: o.update(name="mine")),
        check=_own_scene_names_only_its_files,
    ),
    Case("r3 wrong: Unicode waypoint ids (accepted before)", _unicode_simulate, check=_same_day),
    Case("r3 wrong: the arena's time estimate", _timed_arena, check=_estimate_holds, timeout_s=600),
    # Round four: a field nothing reads (misspelt, or meaningless where it stands) ran with the
    # default in its place and said nothing.
    Case(
        "r4 silent: a scene's misspelt optional field",
        arena_scene(lambda o: o["people"][1].update(start_S=[2.0, 3.0]), "gscl_group"),
        ("scene.json", "people[1].start_S", "start_s"),
    ),
    Case(
        "r4 silent: a scene's walker field on a group",
        arena_scene(lambda o: o["people"][0].update(walks_with=1), "gscl_group"),
        ("scene.json", "people[0].walks_with", "unknown"),
    ),
    Case(
        "r4 silent: a scene's rule field of another rule",
        arena_scene(lambda o: o["rule"].update(distance_m=2.0), "gscl_group"),
        ("scene.json", "rule.distance_m", "unknown"),
    ),
    Case(
        "r4 silent: a recorded scene's made-up field",
        arena_scene(lambda o: o["recording"].update(speed=2.0), "recorded/hotel_reactive"),
        ("scene.json", "recording.speed", "unknown"),
    ),
    Case("r4 silent: a scene's key given twice", _scene_key_twice, ("scene.json", "timeout_s", "twice")),
    Case(
        "r4 impossible: a scene's goal walled off",
        arena_scene(lambda o: o["walls"].append([2.0, 2.2, -3.0, 3.0])),
        ("scene.json", "robot.goal", "cannot be reached"),
    ),
    Case(
        "r4 impossible: a way 0.4 m wide for a 0.55 m robot",
        arena_scene(lambda o: o["walls"].append([2.0, 2.2, -3.0, 2.45])),
        ("scene.json", "robot.goal", "0.275 m"),
    ),
    Case(
        "r4 impossible: 8 m to go in a 4 s timeout at 0.5 m/s",
        arena_scene(lambda o: o.update(timeout_s=4)),
        ("scene.json", "timeout_s", "top speed"),
    ),
    Case(
        "r4 impossible: a visit box inside a wall",
        arena_scene(lambda o: o.update(rule={"type": "visit", "box": [0.0, 1.0, -3.0, -2.9]})),
        ("scene.json", "rule.box", "reach"),
    ),
    Case("r4 silent: an env with a step of 0 s", python_case(ENV_STEP_0), ("dt_s", "> 0"), api=True),
    Case(
        "r5 impossible: a walled-off scene in the Gymnasium adapter",
        lambda tmp: [PY, "-c", GYM_WALLED_OFF.replace("SCENE_PATH", repr(str(tmp / "scene.json")))],
        ("scene.json", "robot.goal", "cannot be reached"),
        api=True,
    ),
    Case(
        "r5 physics: a robot whose step is longer than its body",
        _arena_fast_robot,
        ("fast.toml", "max_speed_mps", "through a wall"),
    ),
    Case(
        "r5 lost: a run folder's lock file linked to a file outside",
        _symlinked_lock,
        check=_lock_target_kept,
        fail_label="data lost",
    ),
    Case(
        "r5 physics: people of 3 m radius",
        python_case(ENV_LONG_STEP.replace("dt_s=1.0", "person_radius_m=3.0")),
        ("person_radius_m", "body radius"),
        api=True,
    ),
    Case(
        "r5 physics: a warehouse step of 0.25 s (workers end steps in walls)",
        simulate_with("params.json", lambda o: o["sim"].update(dt_s=0.25)),
        ("params.json", "sim.dt_s", "walls"),
    ),
    Case("r5 physics: an env step of 1 s", python_case(ENV_LONG_STEP), ("dt_s", "through a wall"), api=True),
    # round six: a list option naming one thing twice (ran and counted it twice)
    Case(
        "r6 silent: arena --methods navfn,navfn (n doubled)",
        command(
            "arena",
            "--out",
            "{tmp}/a",
            "--scenes",
            "casn_head_on",
            "--methods",
            "navfn,navfn",
            "--variants",
            "2",
            "--no-progress",
        ),  # fmt: skip
        ("--methods", "'navfn' is given twice"),
    ),
    Case(
        "r6 silent: referee --seeds 0,0",
        command("referee", "--out", "{tmp}/r", "--seeds", "0,0", "--worlds", "1"),
        ("--seeds", "0 is given twice"),
    ),
    Case(
        "r6 silent: humans validate --models social_force,social_force",
        command("humans", "validate", "--out", "{tmp}/h", "--models", "social_force,social_force", "--quick"),
        ("--models", "'social_force' is given twice"),
    ),
    # round six: sizes no machine holds (were: killed for memory, or a traceback)
    Case(
        "r6 crash: ablation --seeds 10^6",
        command("ablation", "--out", "{tmp}/ab", "--seeds", "1000000", "--no-progress"),
        ("--seeds", "GB at once", "seeds fit"),
    ),
    Case(
        "r6 crash: policy train --envs-per-scene 10^6",
        command("policy", "train", "--out", "{tmp}/p", "--envs-per-scene", "1000000", "--updates", "1"),
        ("--envs-per-scene", "GB at once"),
    ),
    Case(
        "r6 traceback: policy train --rollout-steps 10^7",
        command("policy", "train", "--out", "{tmp}/p", "--rollout-steps", "10000000", "--updates", "1"),
        ("--rollout-steps", "2^31"),
    ),
    Case(
        "r6 traceback: humans calibrate --data eth_ucy --sample 10^8",
        command(
            "humans",
            "calibrate",
            "--data",
            "eth_ucy",
            "--scenes",
            "hotel",
            "--sample",
            "100000000",
            "--steps",
            "1",
            "--evaluations",
            "0",
            "--out",
            "{tmp}/c",
        ),  # fmt: skip
        ("--sample", "hotel", "windows fit"),
    ),
    Case(
        "r6 silent: a TableRequest naming a method twice",
        python_case(TABLE_TWICE),
        ("TableRequest.methods", "'navfn' named twice"),
        api=True,
    ),
    # round seven: a ROS map read as Nav2 reads it (fields taken for what they are not, walls lost)
    Case(
        "r7 silent: a ROS map's resolution: true (read as 1 m a pixel)",
        _ros_map_with("image: map.png\nresolution: true\norigin: [0.0, 0.0, 0.0]\n"),
        ("map.yaml", "field 'resolution'"),
        timeout_s=300,
    ),
    Case(
        "r7 silent: a ROS map's origin [.nan, 0, 0]",
        _ros_map_with("image: map.png\nresolution: 0.1\norigin: [.nan, 0.0, 0.0]\n"),
        ("map.yaml", "field 'origin[0]'", "finite"),
        timeout_s=300,
    ),
    Case(
        "r7 silent: a ROS map's negate: '0' (quoted: read as negated)",
        python_case(
            ROS_MAP_WALLS.format(pixels="np.array([[0, 254]], np.uint8)", extra="negate: '0'\n", image="m.png")
        ),
        check=_walls_are([1, 0]),
    ),
    Case(
        "r7 silent: a ROS map's free_thresh above occupied_thresh",
        _ros_map_with("image: map.png\nresolution: 0.1\norigin: [0.0, 0.0, 0.0]\nfree_thresh: 0.9\n"),
        ("map.yaml", "free_thresh", "occupied_thresh"),
        timeout_s=300,
    ),
    Case(
        "r7 silent: a ROS map's mode: grey (ignored)",
        _ros_map_with("image: map.png\nresolution: 0.1\norigin: [0.0, 0.0, 0.0]\nmode: grey\n"),
        ("map.yaml", "field 'mode'", "trinary"),
        timeout_s=300,
    ),
    Case(
        "r7 silent: a ROS map in raw mode (its walls, value 100, read as free)",
        python_case(
            ROS_MAP_WALLS.format(pixels="np.array([[99, 100, 101, 0]], np.uint8)", extra="mode: raw\n", image="m.png")
        ),
        check=_walls_are([0, 1, 0, 0]),
    ),
    Case(
        "r7 silent: a 16-bit PGM map (mid-grey walls read as white)",
        python_case(ROS_MAP_WALLS.format(pixels="np.array([[0, 20000, 40000, 65535]])", extra="", image="m.pgm")),
        check=_walls_are([1, 1, 0, 0]),
    ),
    Case(
        "r7 silent: a colour map's green wall (luma, not Nav2's channel mean)",
        python_case(
            ROS_MAP_WALLS.format(pixels="np.array([[[0, 255, 0], [255, 255, 255]]], np.uint8)", extra="", image="m.png")
        ),
        check=_walls_are([1, 0]),
    ),
    Case(
        "r7 silent: tracks and map in a UTM frame (float32 windows off by cells)",
        python_case(TRACKS_FAR_FROM_ZERO),
        check=lambda tmp, proc: proc.returncode == 0 and "SAME WINDOWS" in proc.stdout,
    ),
    Case(
        "r7 silent: a track file's empty ids (their rows dropped)",
        _track_file(lambda f, p: f"{f},{'' if p == 5 else p},{1.0 + 0.5 * f},{10.0 + p}"),
        ("t.csv", "column 'id'", "empty"),
        timeout_s=300,
    ),
    Case(
        "r7 silent: a track file's frame 10^20 (wrapped to -9.2e18)",
        _track_file(lambda f, p: f"{10**20 if f == 0 else f},{p},{1.0 + 0.5 * f},{10.0 + p}"),
        ("t.csv", "column 'frame'", "2^53"),
        timeout_s=300,
    ),
    Case(
        "r7 silent: a track file with two x columns (the first read)",
        _track_file(lambda f, p: f"{f},{p},{1.0 + 0.5 * f},{10.0 + p},{20.0 - 0.5 * f}", header="frame,id,x,y,x"),
        ("t.csv", "column 'x'", "2 times"),
        timeout_s=300,
    ),
    Case(
        "r7 hang: gscl rules --scenes 10^8",
        command(
            "gscl",
            "rules",
            "--run",
            str(ROOT / "data" / "gscl" / "default"),
            "--scenes",
            "100000000",
            "--out",
            "{tmp}/r",
        ),  # fmt: skip
        ("--scenes", "GB at once", "scenes of each kind fit"),
    ),
    Case(
        "r7 crash: simulate_to_parquet of 10^8 worlds (Python)",
        python_case(SIMULATE_ENTRY_1E8),
        ("n_worlds=100000000", "GB at once"),
        api=True,
    ),
    full_disk(
        "r8 traceback: layers on a full disk",
        command("layers", "--out", "{tmp}/img"),
        ("socialnav layers: cannot write", ".png", "file too large"),
    ),
    full_disk(
        "r8 traceback: learn on a full disk",
        command(*"learn --logs {run} --out {tmp}/out --no-progress".split()),
        check=_full_disk_nothing_left,
    ),
    full_disk(
        "r8 traceback: learn --overwrite on a full disk (the old engine kept)",
        _previous_engine,
        check=_previous_engine_kept,
        fail_label="data lost",
    ),
    full_disk(
        "r8 traceback: evaluate on a full disk",
        command(*"evaluate --tables {tables} --replicas 1 --slots S1 --out {tmp}/out --no-progress".split()),
        check=_full_disk_nothing_left,
    ),
    full_disk(
        "r8 traceback: gscl rules on a full disk",
        command(
            "gscl",
            "rules",
            "--run",
            str(ROOT / "data" / "gscl" / "default"),
            *"--scenes 2 --out {tmp}/r --no-progress".split(),
        ),  # fmt: skip
        ("socialnav gscl rules: cannot write", "rules", "file too large"),
    ),
    full_disk(
        "r8 traceback: humans validate --quick on a full disk (an empty folder left)",
        command(*"humans validate --quick --out {tmp}/out --no-progress".split()),
        check=_full_disk_nothing_left,
        timeout_s=600,
    ),
    full_disk(
        "r8 vague: arena on a full disk (no file named)",
        command(*"arena --scenes casn_head_on --methods navfn --variants 2 --out {tmp}/a --no-progress".split()),
        ("socialnav arena: cannot write", "/a/", "file too large"),
    ),
    Case(
        "r8 traceback: simulate stopped by Ctrl-C",
        command("simulate", "--out", "{tmp}/out", *WHOLE_DAY),
        check=_stopped_cleanly(130, "socialnav simulate: interrupted"),
        send_signal=(signal.SIGINT, 20.0),
    ),
    Case(
        "r8 leftovers: simulate stopped by SIGTERM (a scheduler's time limit)",
        command("simulate", "--out", "{tmp}/out", *WHOLE_DAY),
        check=_stopped_cleanly(143, "socialnav simulate: terminated (SIGTERM)"),
        send_signal=(signal.SIGTERM, 20.0),
    ),
    _x64_case(
        "r9 wrong: simulate under JAX_ENABLE_X64=1 (other numbers from the same seed)",
        ["simulate", "--out", "{tmp}/out", *SHORT_DAY],
        ("logs.parquet",),
    ),
    _x64_case(
        "r9 traceback: arena under JAX_ENABLE_X64=1",
        [*SMALL_ARENA, "--out", "{tmp}/out"],
        ("summary.csv", "stats.csv"),
        timeout_s=600,
    ),
    Case(
        "r9 traceback: humans validate --quick under JAX_ENABLE_X64=1",
        command(*"humans validate --quick --out {tmp}/out --no-progress".split()),
        check=lambda tmp, proc: proc.returncode == 0 and (tmp / "out" / "summary.json").is_file(),
        env={"JAX_ENABLE_X64": "1"},
        timeout_s=600,
    ),
    Case(
        "r9 traceback: the arena in Python under jax_enable_x64",
        python_case(ARENA_UNDER_X64),
        ("jax_enable_x64", "jax.enable_x64(False)"),
        api=True,
    ),
    Case(
        "r9 traceback: JAX_PLATFORMS=cuda where JAX has no GPU",
        command("simulate", "--out", "{tmp}/out", *SHORT_DAY),
        ("socialnav simulate", "JAX_PLATFORMS=cuda", "unset JAX_PLATFORMS"),
        env={"JAX_PLATFORMS": "cuda"},
    ),
    Case(
        "r9 traceback: JAX_PLATFORMS=tpu without a TPU",
        command("simulate", "--out", "{tmp}/out", *SHORT_DAY),
        ("socialnav simulate", "JAX_PLATFORMS=tpu", "libtpu"),
        env={"JAX_PLATFORMS": "tpu"},
    ),
    Case(
        "r9: XLA_FLAGS naming a flag XLA does not know",
        command("simulate", "--out", "{tmp}/out", *SHORT_DAY),
        ("XLA_FLAGS", "--xla_bogus_flag"),
        env={"XLA_FLAGS": "--xla_bogus_flag=1"},
    ),
    Case(
        "r9 hang: humans calibrate --model steering_speed --start-draws 10^4",
        command(*"humans calibrate --model steering_speed --start-draws 10000 --out {tmp}/out".split()),
        ("--start-draws 10000", "GB at once", "start draws fit"),
        timeout_s=300,
    ),
    Case(
        "r9 hang: humans calibrate --data joint --start-draws 10^5",
        command(*"humans calibrate --data joint --model steering_speed --start-draws 100000 --out {tmp}/o".split()),
        ("--start-draws 100000", "GB at once", "start draws fit"),
        timeout_s=300,
    ),
    Case(
        "r9 traceback: SOCIALNAV_GRID_SOLVER=dijstra (a typo)",
        command(*SMALL_ARENA, "--out", "{tmp}/out"),
        ("SOCIALNAV_GRID_SOLVER=dijstra", "sweeps"),
        env={"SOCIALNAV_GRID_SOLVER": "dijstra"},
        timeout_s=300,
    ),
    Case(
        "r9 vague: SOCIALNAV_NATIVE_CACHE naming a file",
        _beside_a_file(command("simulate", "--out", "{tmp}/out", *SHORT_DAY)),
        check=_ran_and_named("SOCIALNAV_NATIVE_CACHE"),
        env={"SOCIALNAV_NATIVE_CACHE": "{tmp}/a-file"},
        fail_label="vague error",
    ),
    Case(
        "r9 silent: SOCIALNAV_HUMANS_CACHE naming a file",
        _beside_a_file(command(*"humans validate --quick --out {tmp}/out --no-progress".split())),
        check=_ran_and_named("SOCIALNAV_HUMANS_CACHE"),
        env={"SOCIALNAV_HUMANS_CACHE": "{tmp}/a-file"},
        fail_label="wrong",
        timeout_s=600,
    ),
    Case("r9: simulate killed by SIGKILL, then run again", _killed_then_again, check=_second_run_whole, timeout_s=300),
    Case(
        "r9: the arena's tables under two hash seeds (PYTHONHASHSEED)",
        _arena_under_hash_seed_one,
        check=_same_tables,
        env={"PYTHONHASHSEED": "2"},
        timeout_s=600,
    ),
    Case(
        "r10: a tracks file in millimetres",
        _arena_scene_of(lambda r: r.assign(x=r["x"] * 1000, y=r["y"] * 1000)),
        ("tracks.csv", "person", "m/s between frames", "metres"),
    ),
    Case(
        "r10: --frames-per-s ten times the file's",
        _arena_scene_of(fps="250"),
        ("tracks.csv", "250 frames a second", "rate of the frame numbers"),
    ),
    Case(
        "r10: frame numbers of milliseconds at --frames-per-s 25",
        _arena_scene_of(lambda r: r.assign(frame=r["frame"] * 40)),
        ("tracks.csv", "--frames-per-s 25", "nobody walks faster"),
    ),
    Case(
        "r10: a recording with 147 people at once",
        _arena_scene_of(_seven_copies),
        ("tracks.csv", "128 allowed"),
    ),
    Case(
        "r10: a recording shorter than a window",
        _arena_scene_of(lambda r: r[r["frame"] < r["frame"].min() + 500]),
        ("window_within_s", "shorter than one window"),
    ),
    Case(
        "r10: a crowd that never leaves the robot's start (the Jülich bottleneck)",
        _arena_scene_of(run="bottleneck_040_c_56"),
        ("tracks.csv", "robot.start", "no start clear of the recorded people"),
    ),
    Case(
        "r10: arena-scene --map of another place (another frame)",
        _arena_scene_with_map_at(100.0),
        ("tracks.csv", "map.yaml", "% of the positions lie on the map"),
    ),
    Case(
        "r10: a scene whose recording file is gone",
        _arena_on_scene(lambda s: s["recording"].update(file="gone.csv")),
        ("tracks_replayed.json", "recording.file", "no such file"),
        timeout_s=300,
    ),
    Case(
        "r10: a scene's bounds narrower than its recorded people",
        _arena_on_scene(lambda s: s.update(bounds_m=[0, 10, 0, 10])),
        ("tracks_replayed.json", "recording.file", "outside bounds_m"),
        timeout_s=300,
    ),
    Case(
        "r10: a recording edited between a run and its resume",
        _edited_recording_then_resumed,
        ("out", "other settings", "recording_file_digests", "--overwrite"),
        timeout_s=600,
    ),
    Case(
        "r10: a user's recording through arena-scene and the arena",
        _arena_on_scene(lambda s: None),
        check=_arena_ran,
        timeout_s=300,
    ),
    Case(
        "r10: humans predict on tracks shorter than the protocol's 20 samples",
        _predict_on(_first_fifteen),
        ("tracks.csv", "nobody is seen in 20 samples", "longest track has 15"),
    ),
    Case(
        "r10: humans predict on a tracks file in centimetres",
        _predict_on(lambda r: r.assign(x=r["x"] * 100, y=r["y"] * 100)),
        ("tracks.csv", "m/s between frames", "metres"),
    ),
    Case(
        "r11: --human-fit of an ETH/UCY fit (one fit a held-out scene)",
        _with_fit(lambda fit: fit.update(data="eth_ucy")),
        ("fit.json", "data", "one fit a scene"),
    ),
    Case(
        "r11: --human-fit with a NaN time gap",
        _with_fit(_both_values("speed.time_gap_s", float("nan"))),
        ("fit.json", "speed.time_gap_s", "not a positive number"),
    ),
    Case(
        "r11: --human-fit with a body 3 m wide",
        _with_fit(_both_values("speed.radius_m", 3.0)),
        ("fit.json", "speed.radius_m", "wider than a person's body"),
    ),
    Case(
        "r11: --human-fit of ORCA holding a speed model's time gap",
        _with_fit(lambda fit: fit.update(model="orca")),
        ("fit.json", "speed.time_gap_s", "orca reads orca and group"),
    ),
    Case(
        "r11: --human-fit :nelder_mead of a fit stopped before the search",
        _with_fit(_stopped_after_the_gradient, "{fit}:nelder_mead"),
        ("fit.json", "no point yet of nelder_mead"),
    ),
    Case(
        "r11: --human-fit with a training loss that is text",
        _with_fit(lambda fit: fit["scenes"][0]["sample_loss"].update(gradient="low")),
        ("fit.json", "gradient", "training loss 'low'"),
    ),
    Case(
        "r11: --human-fit and --human-model both",
        lambda tmp: [*_with_fit()(tmp), "--human-model", "orca"],
        ("--human-fit", "leave out --human-model"),
    ),
    Case(
        "r11: --human-fit inside the run's --out (an --overwrite could remove it)",
        _with_fit(job="arena --scenes gscl_group --methods navfn --variants 2 --out {tmp}/calibration --no-progress"),
        ("calibration", "contains the job's input"),
    ),
    Case(
        "r11: simulate --human-fit naming a folder without a fit",
        _with_fit(option="{tmp}", job="simulate --hours 0.01 --out {tmp}/wh --no-progress"),
        ("--human-fit", "a folder without a fit.json"),
    ),
    Case(
        "r11: an arena run resumed with another fit's people",
        _arena_then_another_fit,
        ("out", "human_values", "--overwrite"),
        timeout_s=600,
    ),
    Case(
        "r11: --human-fit of the calibration's folder, through the arena",
        _with_fit(option="{tmp}/calibration:gradient"),
        check=_ran_with_fit,
        timeout_s=300,
    ),
    Case(
        "r12: a walker into a closed room",
        _walker_into_a_room([[1.5, 1.6, 1.0, 2.85]]),
        ("scene.json", "people[1].to", "no way from (-3, 0.5) to (2.5, 2)"),
    ),
    Case(
        "r12: a walker into a room by a door 0.4 m wide",
        _walker_into_a_room([[1.5, 1.6, 1.0, 2.0], [1.5, 1.6, 2.4, 2.85]]),
        ("scene.json", "people[1].to", "a way 0.5 m wide"),
    ),
    Case(
        "r12: a walker into a room by a door 1 m wide, round its post",
        _walker_into_a_room([[1.5, 1.6, 1.0, 1.85]], end_xy=(2.5, 1.4)),
        check=_walker_got_in((2.5, 1.4)),
        timeout_s=300,
    ),
    Case(
        "r13: a queue whose exit is in a closed room",
        _queue_into_a_room([[1.5, 1.6, 1.0, 2.85]]),
        ("scene.json", "people[1].exit", "no way from (0.5, 2) to (2.5, 1.4)"),
    ),
    Case(
        "r13: a queue whose exit is in a room by a door 1 m wide, round its post",
        _queue_into_a_room([[1.5, 1.6, 1.0, 1.85]]),
        check=_queue_left,
        timeout_s=300,
    ),
    Case(
        "r14: a queue whose line runs through a thin wall",
        arena_scene(lambda o: o["walls"].append([2.65, 2.7, -1.0, 1.0]), scene="gscl_queue"),
        ("scene.json", "people[0].length", "walls[5] stands between"),
    ),
    Case(
        "r14: a group of six on a circle of 0.3 m",
        arena_scene(lambda o: o["people"][0].update(size=[6, 6], radius_m=[0.3, 0.3]), scene="gscl_group"),
        ("scene.json", "people[0].radius_m", "closer than two bodies", "at least 0.50 m"),
    ),
    Case(
        "r14: a person standing on a group's circle",
        _standing_in("gscl_group", (2.75, 0.0)),
        ("scene.json", "people[2].position", "of the circle of people[0]"),
    ),
    Case(
        "r14: two groups on one spot",
        arena_scene(lambda o: o["people"].append(dict(o["people"][0])), scene="gscl_group"),
        ("scene.json", "people[2].centre", "the circle of people[2] can pass within 0.5 m"),
    ),
    Case(
        "r14: a person standing in a queue's line",
        _standing_in("gscl_queue", (1.6, 0.0)),
        ("scene.json", "people[1].position", "of people[0]: two people in one place"),
    ),
    Case(
        "r14: pass_behind a walker routed round a wall",
        _pass_behind_a_routed_walker,
        ("scene.json", "rule.person", "crosses a wall"),
    ),
    Case(
        "r15 lost: simulate --out a folder holding a user's .lock, .old-2024/, .staging-1/, .tmp-1-draft.txt",
        _look_alikes_in_out("simulate", *SHORT_DAY),
        check=_look_alikes_kept,
        fail_label="data lost",
    ),
    Case(
        "r15 lost: learn --out a folder holding the same",
        _look_alikes_in_out("learn", "--logs", "{run}", "--no-progress"),
        check=_look_alikes_kept,
        fail_label="data lost",
        timeout_s=300,
    ),
    Case(
        "r15 lost: arena --out a folder holding the same",
        _look_alikes_in_out(*"arena --scenes casn_head_on --methods navfn --variants 2 --no-progress".split()),
        check=_look_alikes_kept,
        fail_label="data lost",
        timeout_s=300,
    ),
    Case(
        "r15 lost: evaluate --out a folder holding the same",
        _look_alikes_in_out("evaluate", "--tables", "{tables}", "--replicas", "1", "--slots", "S1", "--no-progress"),
        check=_look_alikes_kept,
        fail_label="data lost",
        timeout_s=300,
    ),
    Case(
        "r15 lost: simulate --overwrite, the previous run copied by the user into its folder's backup-monday/",
        _copy_kept_inside(lambda out: (out, out / "backup-monday")),
        check=_copy_untouched,
        fail_label="data lost",
    ),
    Case(
        "r15 lost: simulate --overwrite, the run's causal/ copied by the user to causal-monday/",
        _copy_kept_inside(lambda out: (out / "causal", out / "causal-monday")),
        check=_copy_untouched,
        fail_label="data lost",
    ),
    Case(
        "r4 silent: a waypoint's made-up speed",
        simulate_with("waypoints.json", lambda o: o["waypoints"][2].update(speed_mps=0.5)),
        ("waypoints.json", "waypoints[2].speed_mps", "unknown"),
    ),
    Case(
        "r4 silent: params.json's misspelt section",
        simulate_with("params.json", lambda o: o.update(batery={"initial_pct": 50})),
        ("params.json", "batery", "battery"),
    ),
    Case(
        "r4 silent: graph.json's misspelt exclusion",
        simulate_with("graph.json", lambda o: o.update(robots_exclude=[])),
        ("graph.json", "robots_exclude", "robot_exclude"),
    ),
]


API_ERROR = re.compile(r"^(ValueError|RuntimeError|socialnav\.jaxsim\.scenario\.errors\.ScenarioError): ")


def _run(case: Case, argv: list[str], tmp: pathlib.Path) -> subprocess.CompletedProcess:
    """Run ``argv`` as the case says: under its file-size limit, sent its signal."""
    env = dict(os.environ, PYTHONPATH=str(ROOT), **{k: v.replace("{tmp}", str(tmp)) for k, v in case.env.items()})
    limit = case.file_size_limit_bytes

    def start() -> None:
        signal.signal(signal.SIGINT, signal.SIG_DFL)  # a harness started with & ignores Ctrl-C; its cases do not
        if limit is not None:
            resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    if limit is not None:
        env.pop("JAX_COMPILATION_CACHE_DIR", None)
        env["SOCIALNAV_JAX_CACHE"] = "off"
    with subprocess.Popen(
        argv, cwd=tmp, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env, preexec_fn=start
    ) as child:
        try:
            if case.send_signal is not None:
                sig, after_s = case.send_signal
                try:
                    child.wait(timeout=after_s)  # finished first: the case did not test what it says
                except subprocess.TimeoutExpired:
                    child.send_signal(sig)
            out, err = child.communicate(timeout=case.timeout_s)
        except subprocess.TimeoutExpired:
            child.kill()
            child.communicate()
            raise
    return subprocess.CompletedProcess(argv, child.returncode, out, err)


def classify(case: Case, tmp: pathlib.Path) -> tuple[str, str]:
    """(outcome, the message's last line)."""
    try:
        argv = case.make(tmp)
    except Exception as e:  # the harness's own set-up failed: report it, never hide it
        return "harness error", f"{type(e).__name__}: {e}"
    t0 = time.perf_counter()
    try:
        proc = _run(case, argv, tmp)
    except subprocess.TimeoutExpired:
        return "hang", f"no answer in {case.timeout_s:.0f} s"
    proc.took_s = time.perf_counter() - t0  # for the checks of a run's own time estimate
    text = (proc.stderr or "") + (proc.stdout or "")
    last = next((line for line in reversed(text.strip().splitlines()) if line.strip()), "")
    if case.check is not None:
        ok = case.check(tmp, proc)
        if "Traceback" in text:
            return "traceback", last
        if ok:
            return "correct", last
        return case.fail_label, last
    # The API's documented exception, naming what is wrong (JAX appends a note on its filtered
    # frames after an exception raised while tracing: the ValueError line is the one read; a
    # file's fault is a ScenarioError, a ValueError naming the file and field).
    raised = next((line for line in reversed(text.splitlines()) if API_ERROR.match(line)), "")
    if case.api and raised and all(w.lower() in raised.lower() for w in case.expect_words):
        return "clean error", raised
    if "Traceback" in text:
        return "traceback", last
    if proc.returncode == 0:
        return "accepted nonsense", last or f"exit 0 in {time.perf_counter() - t0:.0f} s"
    if all(w.lower() in text.lower() for w in case.expect_words) and not any(
        w.lower() in text.lower() for w in case.misleading
    ):
        return "clean error", last
    return "vague error", last


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--only", default="", help="run the cases whose name starts with this")
    ap.add_argument("--json", type=pathlib.Path, default=None, help="write the outcomes here")
    args = ap.parse_args()
    results = []
    for case in CASES:
        if not case.name.startswith(args.only):
            continue
        with tempfile.TemporaryDirectory() as tmp:
            outcome, message = classify(case, pathlib.Path(tmp))
        results.append({"case": case.name, "outcome": outcome, "message": message[:160]})
        print(f"| {case.name} | {outcome} | {message[:110]} |", flush=True)
    counts: dict[str, int] = {}
    for r in results:
        counts[r["outcome"]] = counts.get(r["outcome"], 0) + 1
    print(
        "\n" + ", ".join(f"{k}: {v}" for k, v in sorted(counts.items(), key=lambda kv: -kv[1])),
        f"({len(results)} cases)",
    )
    if args.json:
        args.json.write_text(json.dumps(results, indent=1))
    shutil.rmtree(FIXTURES, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
