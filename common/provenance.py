"""Which source made a run: the git commit of the checkout the package runs from.

A results table names the commit it came from (docs/arena-results.md's generated tables), so a
run records it at its start: :func:`source` returns ``{"source_commit": <40 hex digits>,
"source_dirty": <bool>}`` when the package is imported from a git checkout (an editable install
or the source tree), where ``source_dirty`` says the checkout had uncommitted changes to tracked
files (then the commit alone does not name the code). An installed package (a wheel, no ``.git``
above it) or a machine without git records ``{"source_commit": None, "source_dirty": None}``:
never a guess.
"""

from __future__ import annotations

import pathlib
import subprocess

PACKAGE_ROOT = pathlib.Path(__file__).resolve().parent.parent  # the folder holding common/, jaxsim/, ...


def _git(root: pathlib.Path, *args: str) -> str | None:
    try:
        done = subprocess.run(["git", "-C", str(root), *args], capture_output=True, text=True, timeout=10, check=False)
    except (OSError, subprocess.SubprocessError):
        return None
    return done.stdout if done.returncode == 0 else None


def source(root: pathlib.Path = PACKAGE_ROOT) -> dict:
    """``{"source_commit": str | None, "source_dirty": bool | None}`` of the checkout at ``root``
    (default: the package's own folder); both None where ``root`` is not the top of a git
    checkout (an installed package inside some other repository is not that repository's code)."""
    top = _git(root, "rev-parse", "--show-toplevel")
    commit = _git(root, "rev-parse", "HEAD")
    if top is None or commit is None or pathlib.Path(top.strip()).resolve() != root.resolve():
        return {"source_commit": None, "source_dirty": None}
    status = _git(root, "status", "--porcelain", "--untracked-files=no")
    return {"source_commit": commit.strip(), "source_dirty": None if status is None else bool(status.strip())}
