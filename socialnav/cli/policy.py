"""``socialnav policy``: a navigation policy trained by PPO in the vectorised arena.

socialnav policy train --out runs/ppo                       # every built-in scene; run again to resume
socialnav policy train --out runs/ppo-hallway --scenes gscl_l_hallway --updates 50
socialnav arena --out runs/arena --policy-run runs/ppo       # its rows beside the other methods

The run folder holds ``config.json``, orbax ``checkpoints/``, ``metrics.jsonl`` (one line per
update) and ``curve.png`` (:mod:`planners.learning.policy_run`). Training uses the scenes' training
variants (a random stream the benchmark never draws from).
"""

from __future__ import annotations

import dataclasses
import fnmatch
import pathlib
import sys
import time

from socialnav.cli.argtypes import comma_names, output_folder, positive_int, seed_int
from socialnav.common import runfolder
from socialnav.common.runfolder import RunFolderError
from socialnav.jaxsim.scenes.people import HUMAN_MODELS
from socialnav.locking import locks_folder
from socialnav.planners.learning.policy_social import SOCIAL_LAYERS

TRAIN_JOB = "socialnav policy train"
TRAIN_RESULTS = ("config.json", "checkpoints", "metrics.jsonl", "curve.png")


def add_parser(top) -> None:
    parser = top.add_parser(
        "policy",
        help="train a navigation policy by reinforcement learning (PPO) in the arena's scenes",
        description="A learned policy (PPO) trained in the vectorised arena; benchmark it with "
        "socialnav arena --policy-run RUN.",
    )
    sub = parser.add_subparsers(dest="policy_command", required=True)
    tr = sub.add_parser("train", help="train (or resume) a PPO policy in --out")
    tr.add_argument("--out", type=output_folder, required=True, help="the run folder (resumed if it holds one)")
    tr.add_argument(
        "--scenes",
        type=comma_names,
        default=None,
        help="comma-separated scenes to train on, each a name (a seed scene or a recorded-crowd "
        "scene, which trains on its own training windows), 'seed' or 'recorded' for all of either, a "
        "pattern such as '*_reactive', or a scene file of your own (.json: socialnav arena-scene makes them of "
        "your recording) (default: seed)",
    )
    tr.add_argument(
        "--human-model",
        choices=HUMAN_MODELS,
        default=None,
        help="how the people trained among move (default social_force, the arena's default; a recorded scene's "
        "reactive people follow their recording through it)",
    )
    tr.add_argument(
        "--human-fit",
        default=None,
        metavar="FIT_JSON[:METHOD]",
        help="the people as a calibration fitted them, in place of --human-model: socialnav humans calibrate's "
        "fit.json (Jülich or --data tracks), its model with the fitted constants; METHOD gradient or nelder_mead "
        "(default: the one of lower training loss)",
    )
    tr.add_argument("--updates", type=positive_int, default=None, help="PPO updates in all (default 300)")
    tr.add_argument(
        "--envs-per-scene", type=positive_int, default=None, help="episodes stepped at once per scene (default 64)"
    )
    tr.add_argument("--rollout-steps", type=positive_int, default=None, help="steps per update (default 64)")
    tr.add_argument("--seed", type=seed_int, default=None, help="random seed of the run (default 0)")
    tr.add_argument(
        "--social-layer",
        choices=SOCIAL_LAYERS,
        default=None,
        help="also give the policy a social cost layer around the robot as an input (default none; gscl runs "
        "the model shipped with the package unless --gscl-run names another)",
    )
    tr.add_argument(
        "--gscl-run",
        type=pathlib.Path,
        default=None,
        help="the GSCL model of --social-layer gscl: a socialnav gscl train run or a socialnav gscl export folder "
        "(default: the model shipped with the package)",
    )
    tr.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    tr.set_defaults(handler=_train)


def _config(args, scene_names: tuple[str, ...]):
    from socialnav.planners.learning.policy import PolicyConfig
    from socialnav.planners.learning.policy_run import read_config
    from socialnav.planners.learning.policy_training import PPOConfig

    given = {
        "updates": args.updates,
        "envs_per_scene": args.envs_per_scene,
        "rollout_steps": args.rollout_steps,
        "seed": args.seed,
        "human_model": args.human_model,
    }
    given = {k: v for k, v in given.items() if v is not None}
    if args.human_fit is not None:
        from socialnav.evaluation.humans import fit_file

        people = fit_file.for_command(args.human_fit, args.human_model)
        print(f"socialnav policy train: {fit_file.describe(people)}")
        given.update(human_model=people.model, human_values=tuple(sorted(people.values.items())))
    if args.gscl_run is not None and args.social_layer != "gscl":
        raise ValueError("--gscl-run goes with --social-layer gscl")
    if args.social_layer == "gscl" and args.gscl_run is None:
        from socialnav.models.inference import DEFAULT_MODEL

        args.gscl_run = DEFAULT_MODEL
    if args.gscl_run is not None:
        from socialnav.models.inference import model_problem

        problem = model_problem(args.gscl_run)
        if problem:
            raise ValueError(f"--gscl-run {problem}")
    if args.social_layer is not None:
        gscl_run = "" if args.gscl_run is None else str(args.gscl_run.resolve())
        given["policy"] = PolicyConfig(social_layer=args.social_layer, gscl_run=gscl_run)
    if (args.out / "config.json").exists():
        # A resume keeps the recorded settings; an option given replaces its recorded value
        # (the trainer accepts a new --updates and refuses any other change, naming it).
        stored, _ = read_config(args.out)
        if args.scenes is not None:
            given["scenes"] = scene_names
        config = dataclasses.replace(stored, **given)
        for key in given:
            if getattr(config, key) != getattr(stored, key):
                print(
                    f"socialnav policy train: {args.out}: {key} {_shown(getattr(config, key))} given, "
                    f"the run recorded {_shown(getattr(stored, key))}"
                )
        return config
    return PPOConfig(scenes=scene_names, **given)


def _shown(value) -> str:
    return ",".join(value) if isinstance(value, tuple) and all(isinstance(v, str) for v in value) else str(value)


@locks_folder(lambda args: args.out, "policy train")
def _train(args) -> int:
    from socialnav.data import RECORDED_SCENES_DIR, SCENES_DIR
    from socialnav.jaxsim.scenario import ScenarioError
    from socialnav.jaxsim.scenes.spec import load_scene
    from socialnav.planners.learning import policy_run

    try:
        runfolder.claim(args.out, TRAIN_JOB, TRAIN_RESULTS)
    except RunFolderError as err:
        print(f"socialnav policy train: {err}", file=sys.stderr)
        return 2
    seed_scenes = {p.stem: p for p in sorted(SCENES_DIR.glob("*.json"))}
    recorded_scenes = {p.stem: p for p in sorted(RECORDED_SCENES_DIR.glob("*.json"))}
    available = {**seed_scenes, **recorded_scenes}
    groups = {"seed": list(seed_scenes), "recorded": list(recorded_scenes)}
    asked = None
    if args.scenes:
        # a group's name, a shell pattern (fnmatch) over the scenes' names, or a name
        # (a scene file of one's own by its absolute path: a resume from another folder finds it)
        expand = lambda name: (
            [str(pathlib.Path(name).resolve())]
            if name.endswith(".json")
            else groups.get(name) or fnmatch.filter(available, name) or [name]
        )
        asked = tuple(dict.fromkeys(n for name in args.scenes for n in expand(name)))
    try:
        config = _config(args, asked or ())
    except (ValueError, policy_run.PolicyRunError) as err:
        print(f"socialnav policy train: {err}", file=sys.stderr)
        return 2
    names = list(config.scenes) or list(seed_scenes)
    available.update({n: pathlib.Path(n) for n in names if n.endswith(".json")})  # a file of one's own
    unknown = [n for n in names if n not in available]
    if unknown:
        print(
            f"socialnav policy train: --scenes: unknown {', '.join(unknown)} (known: {', '.join(available)}, recorded)",
            file=sys.stderr,
        )
        return 2
    try:
        specs = [load_scene(available[n]) for n in names]
    except ScenarioError as err:
        print(f"socialnav policy train: {err}", file=sys.stderr)
        return 2
    from socialnav.common.memory import available_bytes
    from socialnav.planners.learning.policy_training import size_problem, transitions_per_update

    problem = size_problem(len(specs), config, available_bytes())  # before the folder is claimed
    if problem:
        print(f"socialnav policy train: {problem}", file=sys.stderr)
        return 2
    runfolder.record(args.out, TRAIN_JOB, ["config.json", "checkpoints/", "metrics.jsonl", "curve.png"])
    per_update = transitions_per_update(len(specs), config)
    print(
        f"PPO on {len(specs)} scene(s): {config.updates} updates of {per_update:,} env-steps "
        f"({config.envs_per_scene} episodes x {config.rollout_steps} steps per scene), people moved by "
        f"{config.human_model} -> {args.out}"
    )
    t0 = time.perf_counter()
    try:
        history = policy_run.train(specs, config, args.out, progress=not args.no_progress)
    except policy_run.PolicyRunError as err:
        print(f"socialnav policy train: {err}", file=sys.stderr)
        return 2
    if history:
        last = history[-1]
        steps = last["env_steps"]
        ended = (
            f"return {last['return']:.3f}, goal {100 * last['goal_rate']:.0f} %, "
            f"social success {100 * last.get('social_rate', float('nan')):.0f} %, "
            f"touched a person {100 * last['contact_rate']:.0f} % of the episodes that ended in it"
            if last["episodes"]
            else "no episode ended in it"
        )
        print(
            f"update {last['update']}: {ended}; "
            f"{steps:,} env-steps in {last['wall_s']:.0f} s of training ({steps / max(last['wall_s'], 1e-9):,.0f}/s); "
            f"{time.perf_counter() - t0:.0f} s in this call"
        )
    print(f"curve: {pathlib.Path(args.out) / 'curve.png'}")
    return 0
