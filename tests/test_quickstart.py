"""The README's Python quickstart, run as a user runs it: each block in a fresh interpreter whose
working folder is outside the source tree, so that only the installed ``socialnav`` package can
be imported (CI also runs them from a non-editable install: ``.ci/run``)."""

from __future__ import annotations

import pathlib
import re
import subprocess
import sys

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
MARK = "<!-- quickstart -->"


def quickstart_blocks(text: str) -> list[str]:
    """The python blocks that follow a ``<!-- quickstart -->`` line, in order."""
    return re.findall(re.escape(MARK) + r"\s*```python\n(.*?)```", text, re.S)


def run_block(code: str, cwd: pathlib.Path) -> str:
    """Run ``code`` in a new interpreter in ``cwd``; its standard output (fails with its stderr)."""
    script = cwd / "quickstart.py"
    script.write_text(code)
    done = subprocess.run([sys.executable, str(script)], cwd=cwd, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    return done.stdout


def test_the_readme_has_three_quickstart_blocks_and_the_arena_page_the_same_actor():
    blocks = quickstart_blocks(README.read_text())
    assert len(blocks) == 3 == README.read_text().count(MARK)
    arena_page = (ROOT / "docs" / "arena.md").read_text()
    match = re.search(r"<!-- actor-quickstart -->\s*```python\n(.*?)```", arena_page, re.S)
    assert match and match.group(1) == blocks[1], "docs/arena.md's actor quickstart differs from the README's"


def test_no_generic_top_level_package_is_importable_outside_the_tree(tmp_path):
    names = ("data", "models", "common", "planners", "jaxsim", "causal", "evaluation")
    out = run_block(
        "import importlib.util\n"
        f"print(sorted(n for n in {names!r} if importlib.util.find_spec(n) is not None))\n"
        "import socialnav.planners, socialnav.data\n"
        "print(socialnav.data.SCENES_DIR.is_dir())\n",
        tmp_path,
    )
    assert out.split() == ["[]", "True"]


@pytest.mark.slow
def test_quickstart_scene_to_cost_map_to_plan(tmp_path):
    out = run_block(quickstart_blocks(README.read_text())[0], tmp_path)
    found = re.search(r"(\d+) people; plan of cost (\d+), (\d+) cells", out)
    ends = re.search(r"ends at \[([-\d.e]+)\s+([-\d.e]+)\] the goal is \[([-\d.e]+)\s+([-\d.e]+)\]", out)
    assert found and ends, out
    end, goal = np.array(ends.groups()[:2], float), np.array(ends.groups()[2:], float)
    # The plan ends in the goal's cell (0.2 m): its centre is within half a cell's diagonal.
    assert np.linalg.norm(end - goal) <= 0.2 * np.sqrt(2) / 2 + 1e-6
    assert int(found.group(1)) >= 1 and int(found.group(2)) > 0 and int(found.group(3)) >= 2


@pytest.mark.slow
def test_quickstart_own_actor_in_the_arena(tmp_path):
    out = run_block(quickstart_blocks(README.read_text())[1], tmp_path)
    rows = [line.split() for line in out.strip().splitlines()[1:]]
    assert sorted(r[1] for r in rows) == ["keep_right", "navfn"] and all(r[2] == "4" for r in rows)


@pytest.mark.slow
def test_quickstart_warehouse_worlds_to_a_dataframe(tmp_path):
    out = run_block(quickstart_blocks(README.read_text())[2], tmp_path)
    rows = out.strip().splitlines()[2:]
    assert [int(r.split()[0]) for r in rows] == list(range(8))
    battery = [float(r.split()[2]) for r in rows]
    assert all(50.0 < b < 100.0 for b in battery)  # ten minutes drain a little, never all of it
