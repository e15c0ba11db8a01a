"""The source commit a run records (common/provenance.py)."""

import shutil
import subprocess

import pytest

from socialnav.common import provenance

pytestmark = pytest.mark.skipif(shutil.which("git") is None, reason="needs git")


def _git(root, *args):
    subprocess.run(["git", "-C", str(root), *args], check=True, capture_output=True)


def test_a_checkout_names_its_commit_and_whether_tracked_files_changed(tmp_path):
    _git(tmp_path, "init", "-q")
    (tmp_path / "a.py").write_text("x = 1\n")
    _git(tmp_path, "add", "a.py")
    _git(tmp_path, "-c", "user.name=t", "-c", "user.email=t@t", "commit", "-q", "-m", "one")
    head = subprocess.run(["git", "-C", str(tmp_path), "rev-parse", "HEAD"], capture_output=True, text=True).stdout
    assert provenance.source(tmp_path) == {"source_commit": head.strip(), "source_dirty": False}
    (tmp_path / "new.py").write_text("")  # untracked: the commit still names the code that runs
    assert provenance.source(tmp_path)["source_dirty"] is False
    (tmp_path / "a.py").write_text("x = 2\n")
    assert provenance.source(tmp_path) == {"source_commit": head.strip(), "source_dirty": True}


def test_a_folder_that_is_not_the_top_of_a_checkout_names_nothing(tmp_path):
    assert provenance.source(tmp_path) == {"source_commit": None, "source_dirty": None}
    _git(tmp_path, "init", "-q")
    inner = tmp_path / "site-packages" / "socialnav"
    inner.mkdir(parents=True)
    assert provenance.source(inner) == {"source_commit": None, "source_dirty": None}
