"""MkDocs hook (mkdocs.yml ``hooks:``): the installed package's layout for mkdocstrings.

The parts are folders at the top of the repository that install as ``socialnav.<part>``
(pyproject's package-dir mapping); griffe reads source statically and cannot follow that mapping,
and importing the package to inspect it would run ``socialnav/__main__.py``. So before the build
this writes ``.docs-src/socialnav/``: a copy of the Python files of ``socialnav/`` and of each
part's folder, the tree ``pip install .`` would produce (griffe does not follow links to
folders), which mkdocs.yml gives griffe as its path.
"""

from __future__ import annotations

import pathlib
import shutil
import tomllib

from mkdocs.plugins import event_priority


@event_priority(100)  # before mkdocstrings reads its paths (it drops one that does not exist yet)
def on_config(config, **kwargs):
    root = pathlib.Path(config.config_file_path).resolve().parent
    mapping = tomllib.loads((root / "pyproject.toml").read_text())["tool"]["setuptools"]["package-dir"]
    tree = root / ".docs-src"
    shutil.rmtree(tree, ignore_errors=True)
    for name, folder in mapping.items():
        target = tree.joinpath(*name.split("."))
        for source in (root / folder).rglob("*.py"):
            relative = source.relative_to(root / folder)
            (target / relative).parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(source, target / relative)
    return config
