"""The route a scene takes through ``socialnav arena``, counted as the program runs.

    python scripts/scene_route.py                        # this checkout
    python scripts/scene_route.py --tree ../other-clone  # another checkout of the toolkit (before a change, say)

Runs ``socialnav arena --scenes casn_head_on --methods navfn --variants 2`` into a temporary folder
with a profile hook that notes every call of a toolkit function one of whose arguments carries
the scene: its file's path, its :class:`~jaxsim.scenes.spec.SceneSpec`, the arena's
:class:`~evaluation.arena.episodes.SceneSetup` or the :class:`~jaxsim.scenes.env.Env` made from it
(a list or tuple of them too). It prints the functions in the order first entered, then the
counts: functions (stops), modules, module entries (a module entered again after another counts
again), returns to a module already left, and climbs back up: calls into a module from another
module that the first one called, directly or not (a callback: the caller's module below the
callee's on the call stack), where a return is also a module's own function going on after a call
it made. Constructors count as the stops they are.

This counts what runs, not what the code's text could reach: a call through a variable, a
``jax.jit`` or a backend's shard is followed because it runs, and so is one in another thread (the
arena runs its methods' episodes in one thread per host device,
:func:`evaluation.arena.episodes.run_spread`: the episode programs' tracing, the env's ``reset``
and ``step`` among it, runs there). ``--tree`` imports the toolkit from
another checkout's folders (the layout of ``pyproject.toml``'s ``package-dir``), so two versions
are counted by the same script.
"""

from __future__ import annotations

import argparse
import importlib.machinery
import importlib.util
import pathlib
import sys
import tempfile
import threading

PARTS = ("causal", "common", "data", "evaluation", "jaxsim", "models", "planners")
SCENE = "casn_head_on"


def import_from(tree: pathlib.Path) -> None:
    """Import ``socialnav`` from ``tree``'s folders before the installed package."""
    mapping = {"socialnav": tree / "socialnav", **{f"socialnav.{p}": tree / p for p in PARTS}}

    class Finder:
        @classmethod
        def find_spec(cls, fullname, path=None, target=None):
            if fullname in mapping:
                return importlib.util.spec_from_file_location(fullname, mapping[fullname] / "__init__.py")
            parent = fullname.rpartition(".")[0]
            if parent in mapping:
                return importlib.machinery.PathFinder.find_spec(fullname, path=[str(mapping[parent])])
            return None

    sys.meta_path.insert(0, Finder)


def scene_types() -> tuple[type, ...]:
    from socialnav.jaxsim.scenes.env import Env
    from socialnav.jaxsim.scenes.spec import SceneSpec

    try:
        from socialnav.evaluation.arena.episodes import SceneSetup
    except ImportError:  # a checkout from before evaluation/arena/ was a package
        from socialnav.evaluation.arena import SceneSetup
    return SceneSpec, SceneSetup, Env


def route(out: pathlib.Path) -> tuple[list[tuple[str, str]], list[tuple[str, str]]]:
    """``(module, function)`` of each call that received the scene, consecutive repeats merged,
    and the calls among them that climb back up (:func:`main`'s docstring)."""
    from socialnav.cli import main

    types = scene_types()

    def carries_scene(value) -> bool:
        if isinstance(value, types):
            return True
        if isinstance(value, str | pathlib.Path) and str(value).endswith(f"{SCENE}.json"):
            return True
        if isinstance(value, list | tuple) and 0 < len(value) < 20:
            return any(carries_scene(v) for v in value)
        return False

    stops: list[tuple[str, str]] = []
    climbs: list[tuple[str, str]] = []

    def note(frame, event, arg):
        if event != "call":
            return
        module = frame.f_globals.get("__name__", "")
        if not module.startswith("socialnav."):
            return
        code = frame.f_code
        names = code.co_varnames[: code.co_argcount + code.co_kwonlyargcount]
        if any(carries_scene(frame.f_locals.get(n)) for n in names):
            stop = (module.removeprefix("socialnav."), code.co_name)
            if not stops or stops[-1] != stop:
                stops.append(stop)
            if climbs_back_up(module, toolkit_callers(frame)) and stop not in climbs:
                climbs.append(stop)

    import jax

    # A program traced earlier in this process (by another test, say) is not traced again, and
    # its calls would not run: every one is forgotten first, so the route is the same in any process.
    jax.clear_caches()
    argv = ["arena", "--scenes", SCENE, "--methods", "navfn", "--variants", "2", "--out", str(out), "--no-progress"]
    threading.setprofile(note)  # the threads the run starts (run_spread's, one per device)
    sys.setprofile(note)
    try:
        code = main(argv)
    finally:
        sys.setprofile(None)
        threading.setprofile(None)
    if code != 0:
        raise SystemExit(f"socialnav {' '.join(argv)} failed ({code})")
    return stops, climbs


def climbs_back_up(module: str, callers: list[str]) -> bool:
    """Whether a call into ``module`` from ``callers`` (the modules on the stack, innermost first)
    climbs back up: called from another module that ``module`` itself called, directly or not."""
    return bool(callers) and callers[0] != module and module in callers[1:]


def toolkit_callers(frame) -> list[str]:
    """The toolkit modules on ``frame``'s call stack, innermost caller first."""
    modules = []
    frame = frame.f_back
    while frame is not None:
        module = frame.f_globals.get("__name__", "")
        if module.startswith("socialnav."):
            modules.append(module)
        frame = frame.f_back
    return modules


def counts(stops: list[tuple[str, str]]) -> dict:
    modules, entries, returns = set(), [], 0
    for module, _ in stops:
        if entries and entries[-1] != module and module in modules:
            returns += 1
        if not entries or entries[-1] != module:
            entries.append(module)
        modules.add(module)
    return {
        "functions": len(dict.fromkeys(stops)),
        "modules": len(modules),
        "module entries": len(entries),
        "returns to a module left": returns,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--tree", type=pathlib.Path, default=None, help="another checkout to count (default: this)")
    args = parser.parse_args()
    if args.tree is not None:
        import_from(args.tree.resolve())
    with tempfile.TemporaryDirectory() as folder:
        stops, climbs = route(pathlib.Path(folder) / "arena")
    for module, function in dict.fromkeys(stops):
        climb = "  (climbs back up)" if (module, function) in climbs else ""
        print(f"  {module}:{function}{climb}")
    print(", ".join(f"{value} {name}" for name, value in {**counts(stops), "climbs back up": len(climbs)}.items()))


if __name__ == "__main__":
    main()
