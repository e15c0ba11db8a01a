"""The documentation's examples as a reader copies them: every Python block of the README and of
``docs/*.md`` compiles and imports only names the package has, and every ``socialnav`` command
line in their shell blocks parses (fast); the Python blocks no other test runs are run as
written, each in a fresh interpreter outside the source tree (slow)."""

from __future__ import annotations

import ast
import contextlib
import importlib
import io
import pathlib
import re
import shlex
import subprocess
import sys

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def python_blocks(page: pathlib.Path) -> list[str]:
    """The page's ```python blocks, in order."""
    return re.findall(r"```python\n(.*?)```", page.read_text(), re.S)


BLOCKS = {f"{page.relative_to(ROOT)}[{i}]": code for page in PAGES for i, code in enumerate(python_blocks(page))}

# Blocks this file does not run, and why: another test runs them, or the same calls, as written.
RUN_ELSEWHERE = {
    "README.md[0]": "tests/test_quickstart.py runs the README's blocks from outside the tree",
    "README.md[1]": "tests/test_quickstart.py",
    "README.md[2]": "tests/test_quickstart.py",
    "docs/arena.md[0]": "tests/test_arena_command.py makes the same run_table call (about 70 s as written)",
    "docs/arena.md[1]": "the README's actor quickstart, the same text (tests/test_quickstart.py checks that)",
    "docs/humans.md[0]": "tests/test_humans.py runs the quick validation as `humans validate --quick` (2-3 min)",
    "docs/simulator.md[1]": "tests/test_warehouse_actors.py runs the warehouse actor quickstart",
}
RUN_HERE = sorted(set(BLOCKS) - set(RUN_ELSEWHERE))


def test_the_examples_left_to_other_tests_still_exist():
    assert set(RUN_ELSEWHERE) <= set(BLOCKS), set(RUN_ELSEWHERE) - set(BLOCKS)
    assert len(RUN_HERE) >= 8  # the pages' own examples: a block lost from a page shows here


def _missing_names(code: str) -> list[str]:
    """Every ``socialnav`` module or name ``code`` imports that the package does not have."""
    missing = []
    for node in ast.walk(ast.parse(code)):
        if isinstance(node, ast.Import):
            modules = [(alias.name, None) for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module:
            modules = [(node.module, alias.name) for alias in node.names]
        else:
            continue
        for module, name in modules:
            if not module.startswith("socialnav"):
                continue
            try:
                imported = importlib.import_module(module)
            except ImportError:
                missing.append(module)
                continue
            if name is not None and not hasattr(imported, name):
                try:
                    importlib.import_module(f"{module}.{name}")
                except ImportError:
                    missing.append(f"{module}.{name}")
    return missing


@pytest.mark.parametrize("block", sorted(BLOCKS))
def test_every_example_compiles_and_imports_what_the_package_has(block):
    code = BLOCKS[block]
    compile(code, block, "exec")
    assert _missing_names(code) == []


def _run(code: str, cwd: pathlib.Path) -> str:
    """``code`` in a new interpreter in ``cwd`` (outside the tree: the installed package only);
    its standard output, or a failure with its standard error."""
    script = cwd / "example.py"
    script.write_text(code)
    done = subprocess.run([sys.executable, str(script)], cwd=cwd, capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr[-3000:]
    return done.stdout


@pytest.mark.slow
@pytest.mark.parametrize("block", RUN_HERE)
def test_the_example_runs_as_written(block, tmp_path, request):
    code = BLOCKS[block]
    if block.startswith("docs/warehouse-planners.md"):  # reads the tables `socialnav learn` wrote
        learned = request.getfixturevalue("learned_run")
        assert '"runs/warehouse/' in code
        code = code.replace('"runs/warehouse/', f'"{learned}/')
    out = _run(code, tmp_path)
    if "humans.step_humans(" in code:  # the page's claim: the pair 1 m abreast, 1.25 m on; the third 1.3 m on
        xy = np.array(re.findall(r"[-\d.]+", out), float).reshape(3, 2)
        assert abs(xy[1, 1] - xy[0, 1] - 0.99) < 0.02 and abs(xy[0, 0] - 2.25) < 0.02
        assert abs(xy[2, 0] - 4.3) < 0.02


def test_the_import_check_names_what_is_missing():
    code = "from socialnav.jaxsim import rollout, no_such_name\nimport socialnav.no_such_module\nimport numpy"
    assert _missing_names(code) == ["socialnav.jaxsim.no_such_name", "socialnav.no_such_module"]


def socialnav_commands(page: pathlib.Path) -> list[str]:
    """The ``socialnav ...`` command lines of the page's shell blocks (a line's ``&&``/``;``/``|``
    parts apart, continuation lines joined), without the program's name."""
    commands = []
    for block in re.findall(r"```(?:bash|console|sh)\n(.*?)```", page.read_text(), re.S):
        for line in block.replace("\\\n", " ").splitlines():
            for part in re.split(r"&&|;|\|", line):
                found = re.match(r"^(?:\S*/)?socialnav\s+(.*)$", part.strip())
                if found:
                    commands.append(found.group(1))
    return commands


COMMANDS = sorted({(str(page.relative_to(ROOT)), c) for page in PAGES for c in socialnav_commands(page)})


def test_the_pages_show_the_commands():
    assert len(COMMANDS) >= 50 and any(c.startswith("arena ") for _, c in COMMANDS)


@pytest.mark.parametrize(("page", "command"), COMMANDS)
def test_every_command_line_of_the_pages_parses(page, command):
    """Options and subcommands as the command line has them (parsed, not run)."""
    from socialnav.cli import _command, build_parser

    argv = shlex.split(command, comments=True)
    said = io.StringIO()
    try:
        with contextlib.redirect_stderr(said), contextlib.redirect_stdout(io.StringIO()):
            build_parser(_command(argv)).parse_args(argv)
    except SystemExit as e:
        assert e.code in (0, None), f"{page}: socialnav {command}: {said.getvalue().strip()}"
