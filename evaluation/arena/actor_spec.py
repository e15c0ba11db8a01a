"""``--actor SPEC``: a user's actor factory named on the command line.

``SPEC`` is ``package.module:function`` (importable: installed, or under the working directory)
or ``path/to/file.py:function``. The function is called with each scene's environment
(:class:`jaxsim.scenes.env.Env`) and returns an :class:`jaxsim.scenes.actor.Actor`, or
``(actor, params)``; its rows in the tables are named after the function.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import pathlib
import sys
from collections.abc import Callable

from socialnav.common.names import is_safe_name


class ActorSpecError(ValueError):
    """A ``--actor`` that cannot be loaded; the message names it and why (one line)."""


def split(spec: str) -> tuple[str, str]:
    """``(module or file, function)`` of ``spec``; refuses a malformed one."""
    where, sep, function = spec.rpartition(":")
    if not sep or not where or not function.isidentifier():
        raise ActorSpecError(f"--actor {spec}: expected module:function or file.py:function")
    return where, function


def name(spec: str) -> str:
    """The method name of ``spec`` in the tables: its function's name."""
    function = split(spec)[1]
    if not is_safe_name(function):
        raise ActorSpecError(f"--actor {spec}: {function!r} cannot name a method")
    return function


def _module(where: str, spec: str):
    if where.endswith(".py"):
        path = pathlib.Path(where).resolve()
        if not path.is_file():
            raise ActorSpecError(f"--actor {spec}: no file {where}")
        module_name = "socialnav_user_actor_" + hashlib.sha256(str(path).encode()).hexdigest()[:12]
        if module_name in sys.modules:
            return sys.modules[module_name]
        loader_spec = importlib.util.spec_from_file_location(module_name, path)
        module = importlib.util.module_from_spec(loader_spec)
        sys.modules[module_name] = module
        try:
            loader_spec.loader.exec_module(module)
        except Exception as e:
            del sys.modules[module_name]
            raise ActorSpecError(f"--actor {spec}: {path} failed to import: {type(e).__name__}: {e}") from e
        return module
    if str(pathlib.Path.cwd()) not in sys.path:
        sys.path.append(str(pathlib.Path.cwd()))  # a module of the user's, beside them
    try:
        return importlib.import_module(where)
    except ImportError as e:
        raise ActorSpecError(f"--actor {spec}: cannot import {where}: {e}") from e
    except Exception as e:
        raise ActorSpecError(f"--actor {spec}: {where} failed to import: {type(e).__name__}: {e}") from e


def load(spec: str) -> Callable:
    """The factory ``env -> Actor | (Actor, params)`` that ``spec`` names."""
    where, function = split(spec)
    module = _module(where, spec)
    factory = getattr(module, function, None)
    if not callable(factory):
        raise ActorSpecError(f"--actor {spec}: {where} has no function {function}")
    return factory


def source_digest(spec: str) -> str:
    """A digest of the file that defines ``spec``'s module (a changed actor is a changed run)."""
    where, _ = split(spec)
    module = _module(where, spec)
    path = getattr(module, "__file__", None)
    data = pathlib.Path(path).read_bytes() if path and pathlib.Path(path).is_file() else where.encode()
    return hashlib.sha256(data).hexdigest()[:16]
