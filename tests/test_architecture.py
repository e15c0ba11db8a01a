"""The arrows between the parts run one way: a test that reads every import of every module.

The parts are folders at the top of the repository installed under one name: ``jaxsim/`` is
``socialnav.jaxsim``, ``models/`` is ``socialnav.models``, and ``socialnav/`` itself holds the
command line (the composition root). Allowed (DESIGN.md): ``socialnav`` may import everything
and nothing imports it; ``evaluation`` imports jaxsim, planners, models; ``planners`` may import
jaxsim (the plan format) and models (inference); ``jaxsim``, ``models`` and ``causal`` import none
of the other parts; ``causal`` and ``planners`` never import each other; ``common`` and ``data``
are leaves every part may use.
"""

from __future__ import annotations

import ast
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
PARTS = ("common", "data", "jaxsim", "models", "causal", "planners", "evaluation", "socialnav")
LEAVES = {"common", "data"}
ALLOWED = {
    "common": set(),
    "data": set(),
    "jaxsim": LEAVES,
    "models": LEAVES,
    "causal": LEAVES,
    "planners": LEAVES | {"jaxsim", "models"},
    "evaluation": LEAVES | {"jaxsim", "planners", "models"},
    "socialnav": set(PARTS) - {"socialnav"},
}


def part_of(module: str) -> str | None:
    """The part a module name belongs to: ``socialnav.models.config`` -> ``models``,
    ``socialnav.cli`` -> ``socialnav``; a bare part name (``models.config``: the layout before the
    namespace, which an installed package no longer has) -> ``bare models``; anything else None."""
    names = module.split(".")
    if names[0] == "socialnav":
        return names[1] if len(names) > 1 and names[1] in PARTS else "socialnav"
    return f"bare {names[0]}" if names[0] in PARTS else None


def imported_parts(file: pathlib.Path) -> dict[str, int]:
    """Project parts imported anywhere in ``file`` (also inside functions): part -> line."""
    found = {}
    for node in ast.walk(ast.parse(file.read_text(), str(file))):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names = [node.module]
        else:
            continue
        for name in names:
            part = part_of(name)
            if part is not None:
                found.setdefault(part, node.lineno)
    return found


def forbidden_arrows(root: pathlib.Path = ROOT) -> list[str]:
    """Every import of a part by a part that may not import it, as ``file:line imports part``."""
    bad = []
    for part in PARTS:
        for file in sorted((root / part).rglob("*.py")):
            for other, line in imported_parts(file).items():
                if other != part and other not in ALLOWED[part]:
                    bad.append(f"{file.relative_to(root)}:{line} imports {other}")
    return bad


def test_no_forbidden_arrow():
    assert forbidden_arrows() == []


def test_nothing_outside_the_root_imports_socialnav():
    users = [
        f
        for part in PARTS
        if part != "socialnav"
        for f in (ROOT / part).rglob("*.py")
        if "socialnav" in imported_parts(f)
    ]
    assert users == []


@pytest.mark.parametrize(
    "part,other",
    [
        ("jaxsim", "planners"),
        ("causal", "planners"),
        ("planners", "causal"),
        ("models", "jaxsim"),
        ("jaxsim", "socialnav"),
    ],
)
def test_the_check_catches_a_forbidden_import(tmp_path, part, other):
    """The checker itself: a module that imports a forbidden part, even inside a function, is reported."""
    for p in PARTS:
        (tmp_path / p).mkdir()
    module = "socialnav" if other == "socialnav" else f"socialnav.{other}"
    (tmp_path / part / "bad.py").write_text(f"import numpy\n\n\ndef f():\n    from {module} import something\n")
    (tmp_path / part / "good.py").write_text("from socialnav.common import pytree\n")
    assert forbidden_arrows(tmp_path) == [f"{part}/bad.py:5 imports {other}"]


def test_the_check_catches_a_bare_part_name(tmp_path):
    """``from models import x`` works only from the source tree, never in an installed package."""
    for p in PARTS:
        (tmp_path / p).mkdir()
    (tmp_path / "planners" / "old.py").write_text("from models.config import TrainConfig\n")
    (tmp_path / "socialnav" / "cli.py").write_text(
        "import socialnav.models.config as config\nfrom socialnav import cli\n"
    )
    assert forbidden_arrows(tmp_path) == ["planners/old.py:1 imports bare models"]


def test_only_the_backend_module_imports_ray():
    """Ray is an optional extra: the simulator, planners, models, causal code and evaluation never
    import it; in the composition root only ``socialnav/backend.py`` does."""
    users = []
    for part in PARTS:
        for file in sorted((ROOT / part).rglob("*.py")):
            for node in ast.walk(ast.parse(file.read_text(), str(file))):
                names = [a.name for a in node.names] if isinstance(node, ast.Import) else []
                if isinstance(node, ast.ImportFrom) and node.module:
                    names = [node.module]
                if any(n.split(".")[0] == "ray" for n in names):
                    users.append(str(file.relative_to(ROOT)))
    assert sorted(set(users)) == ["socialnav/backend.py"]


# Inside planners/: the folders of parts and what each may import. The base parts (layers, the
# global and local planners, the warehouse's planners) never import the compositions at the top
# of planners/ (stack, actors, plots) nor the folders built on them (reactive, learning).
PLANNER_FOLDERS = {
    "layers": set(),
    "global_planners": {"layers"},
    "local": {"layers"},
    "warehouse": set(),
    "reactive": {"layers", "local", "global_planners", "top"},
    "learning": {"layers", "local", "global_planners", "top"},
}


def planner_folder_arrows(root: pathlib.Path = ROOT) -> list[str]:
    """Every import inside ``planners/`` that :data:`PLANNER_FOLDERS` does not allow, as
    ``file:line imports folder`` (``top`` for a module at the top of planners/)."""
    planners = root / "planners"
    bad = []
    for folder, allowed in PLANNER_FOLDERS.items():
        for file in sorted((planners / folder).rglob("*.py")):
            for node in ast.walk(ast.parse(file.read_text(), str(file))):
                if not (isinstance(node, ast.ImportFrom) and node.module or isinstance(node, ast.Import)):
                    continue
                modules = [node.module] if isinstance(node, ast.ImportFrom) else [a.name for a in node.names]
                for module in modules:
                    names = module.split(".")
                    if names[:2] != ["socialnav", "planners"]:
                        continue
                    if len(names) > 2:
                        targets = [names[2]]
                    else:  # from socialnav.planners import x, y
                        targets = [a.name for a in node.names]
                    for target in targets:
                        other = target if (planners / target).is_dir() else "top"
                        if other != folder and other not in allowed:
                            bad.append(f"{file.relative_to(root)}:{node.lineno} imports {other}")
    return bad


def test_planner_folders_import_one_way():
    assert planner_folder_arrows() == []


def test_the_planner_folder_check_catches_a_climb(tmp_path):
    """A cost layer that imports a stack (a composition above it) or a reactive rule is reported."""
    for folder in PLANNER_FOLDERS:
        (tmp_path / "planners" / folder).mkdir(parents=True)
    (tmp_path / "planners" / "layers" / "bad.py").write_text(
        "from socialnav.planners import stack\nfrom socialnav.planners.reactive import dwa\n"
    )
    (tmp_path / "planners" / "local" / "good.py").write_text("from socialnav.planners.layers import costmap\n")
    assert planner_folder_arrows(tmp_path) == [
        "planners/layers/bad.py:1 imports top",
        "planners/layers/bad.py:2 imports reactive",
    ]


def test_the_scene_route_is_counted_as_it_runs():
    """scripts/scene_route.py: the counts of a hand-made route (a return to a module left counted
    once per return, consecutive calls in one module one entry)."""
    import script_loader

    script = script_loader.load("scene_route")
    made = [("a", "f"), ("b", "g"), ("b", "h"), ("a", "f"), ("c", "k"), ("a", "m")]
    assert script.counts(made) == {
        "functions": 5,
        "modules": 3,
        "module entries": 5,
        "returns to a module left": 2,
    }
    # a callback (c calls b, b calls back into c) climbs back up; c going on after b returned does not
    assert script.climbs_back_up("c", ["b", "c", "a"])
    assert not script.climbs_back_up("c", ["c", "b", "a"])
    assert not script.climbs_back_up("c", ["b", "a"])


@pytest.mark.slow
def test_the_scene_route_of_an_arena_run_reaches_the_scenes_table(tmp_path):
    """The route of a real ``socialnav arena`` run: the scene file read, then the episodes built
    from it (the environment, the method's episode function, the variants, the episodes themselves,
    which run in the arena's device threads), then the scene's episodes joined in the run folder, in
    that order, and no climb back up."""
    import script_loader

    stops, climbs = script_loader.load("scene_route").route(tmp_path / "arena")
    assert climbs == []  # no call climbs back up into a module that called down (issue 64)
    order = [f"{module}:{function}" for module, function in stops]
    wanted = ["jaxsim.scenes.spec:load_scene", "jaxsim.scenes.env:make_env",
              "evaluation.arena.episodes:episode_function", "jaxsim.scenes.variant:sample_variants",
              "jaxsim.scenes.actor:rollout", "evaluation.arena.table:finish_scene"]  # fmt: skip
    where = [order.index(w) for w in wanted]  # ValueError names a stop the route missed
    assert where == sorted(where)
