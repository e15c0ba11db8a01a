"""The package as installed: every folder with an ``__init__.py`` listed under its ``socialnav.``
name in pyproject.toml, and each part's public names (``__all__``) importable, none of them
hiding a submodule of the same name (``from socialnav.jaxsim import rollout`` must stay the
module the code imports)."""

from __future__ import annotations

import importlib
import pathlib
import pkgutil
import tomllib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
SETUPTOOLS = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]


def packages_on_disk() -> set[str]:
    """Every package the mapping (package-dir) makes of the folders holding an ``__init__.py``."""
    found = set()
    for name, folder in SETUPTOOLS["package-dir"].items():
        for init in (ROOT / folder).rglob("__init__.py"):
            relative = init.parent.relative_to(ROOT / folder)
            found.add(".".join((name, *relative.parts)))
    return found


def test_pyproject_lists_every_package_under_the_socialnav_name():
    assert set(SETUPTOOLS["packages"]) == packages_on_disk()
    assert all(p == "socialnav" or p.startswith("socialnav.") for p in SETUPTOOLS["packages"])


@pytest.mark.parametrize("package", sorted(packages_on_disk()))
def test_public_names_resolve_and_hide_no_submodule(package):
    module = importlib.import_module(package)
    public = getattr(module, "__all__", [])
    submodules = {m.name for m in pkgutil.iter_modules(module.__path__)}
    for name in public:
        value = getattr(module, name)  # AttributeError: __all__ names something missing
        if name in submodules:
            assert value is importlib.import_module(f"{package}.{name}"), f"{package}.{name} hides its submodule"
    if package != "socialnav" and package != "socialnav.jaxsim.native":
        assert public, f"{package} re-exports nothing"
