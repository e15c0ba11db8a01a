"""Where a batch job's shards run: here, one after another (``local``), or as Ray tasks (``ray``).

A batch job (``simulate``, ``evaluate``, ``gscl generate``, ``arena``) cuts its work into
:class:`Shard` s, each a pure function call ``compute(*shard.args)`` whose result the driver
saves with ``save(shard, result)``: one file per shard, written atomically, whose presence marks
the shard done. The backend decides only where ``compute`` runs:

* ``local``: in this process, in order; no Ray needed.
* ``ray``: one Ray task per shard (``ray.remote(max_retries=...)``: a task whose worker dies is
  run again), on the cluster at ``address`` (else ``$RAY_ADDRESS``, else a Ray instance started
  here). A task ships its arguments (a few numbers, a scene, a file name) and returns its result
  (a Parquet file's bytes, a frame, arrays) to the driver, which alone writes the output folder:
  the cluster's nodes need the package, not a shared file system.

The shard layout is the job's and the same for both backends, so the results are the same bit
for bit (same shards, same batch shapes, same XLA host devices: the driver's ``XLA_FLAGS`` are
passed to every worker). A killed driver leaves the finished shards' files; a rerun computes only
the missing ones. Ray is imported here only, and only when ``ray`` is asked for: nothing below
the composition root knows it.
"""

from __future__ import annotations

import dataclasses
import os
import pathlib
import re
import sys
from collections.abc import Callable, Sequence

from socialnav.common.progress import bar

BACKENDS = ("local", "ray")


class BackendError(RuntimeError):
    """A backend cannot run the job (Ray missing, the cluster unreachable or lacking the
    package); the message is one line for the user."""


@dataclasses.dataclass(frozen=True)
class Shard:
    """One piece of a job.

    Attributes:
      name: what the progress bar and errors call it.
      output: the file ``save`` writes; present = done.
      args: ``compute``'s arguments (picklable: Ray ships them).
      work: units of work for the progress bar (worlds, episodes, samples).
    """

    name: str
    output: pathlib.Path
    args: tuple
    work: float = 1.0


def add_backend_options(parser) -> None:
    """``--backend``, ``--ray-address``, ``--ray-cpus-per-task`` on a subcommand's parser."""
    group = parser.add_argument_group("where the shards run")
    group.add_argument(
        "--backend",
        choices=BACKENDS,
        default="local",
        help="local: this process (default); ray: one Ray task per shard (pip install 'socialnav-jax[ray]')",
    )
    group.add_argument(
        "--ray-address",
        default=None,
        help="the Ray cluster (default: $RAY_ADDRESS, else a Ray instance started on this machine)",
    )
    from socialnav.cli.argtypes import positive_float

    group.add_argument(
        "--ray-cpus-per-task",
        type=positive_float,
        default=None,
        help="CPUs Ray reserves per task (default: a whole node's, so a shard keeps its machine's cores busy)",
    )


def describe(args) -> dict:
    """The backend settings a run records in its metadata."""
    return {
        "backend": getattr(args, "backend", "local"),
        "ray_address": getattr(args, "ray_address", None) or os.environ.get("RAY_ADDRESS"),
    }


def _worker_env() -> dict[str, str]:
    """Environment every Ray worker gets: the driver's XLA host-device count (the one JAX runs
    with here, whatever ``XLA_FLAGS`` says now) and JAX settings, so a shard computes what it
    would compute here (the C++ social force's switch and build settings included: a worker on the
    JAX force would sum in another order than a driver on the kernel)."""
    keys = (
        "XLA_FLAGS",
        "JAX_COMPILATION_CACHE_DIR",
        "SOCIALNAV_JAX_CACHE",
        "JAX_ENABLE_X64",
        "JAX_PLATFORMS",
        "SOCIALNAV_NATIVE",
        "SOCIALNAV_NATIVE_CACHE",
        "CXX",
    )
    env = {k: os.environ[k] for k in keys if k in os.environ}
    jax = sys.modules.get("jax")
    if jax is not None and jax.default_backend() == "cpu":
        flags = re.sub(r"--xla_force_host_platform_device_count=\d+", "", env.get("XLA_FLAGS", "")).strip()
        env["XLA_FLAGS"] = f"{flags} --xla_force_host_platform_device_count={jax.local_device_count()}".strip()
    return env


def _check_reachable(address: str, timeout_s: float = 10.0) -> None:
    """A ``host:port`` (or ``ray://host:port``) address must accept a TCP connection within
    ``timeout_s``: Ray itself retries an unreachable cluster for minutes without a word."""
    import socket

    host, sep, port = address.removeprefix("ray://").rpartition(":")
    if not sep or not port.isdigit():
        return  # "auto", "local" or a form Ray resolves itself
    try:
        socket.create_connection((host, int(port)), timeout=timeout_s).close()
    except OSError as e:
        raise BackendError(f"cannot reach the Ray cluster at {address}: {e.strerror or e}") from e


def _connect(address: str | None):
    try:
        import ray
    except ImportError as e:
        raise BackendError("--backend ray needs Ray: pip install 'socialnav-jax[ray]'") from e
    if ray.is_initialized():
        return ray
    address = address or os.environ.get("RAY_ADDRESS") or None
    if address:
        _check_reachable(address)
    try:
        ray.init(
            address=address,
            runtime_env={"env_vars": _worker_env()},
            log_to_driver=False,
            include_dashboard=False,
            configure_logging=False,
        )
    except (ConnectionError, TimeoutError, RuntimeError, ValueError) as e:
        where = address or "a new local instance"
        raise BackendError(f"cannot reach the Ray cluster at {where}: {str(e).splitlines()[0]}") from e
    return ray


def _cpus_per_task(ray, requested: float | None) -> float:
    if requested is not None:
        if requested <= 0:
            raise BackendError(f"--ray-cpus-per-task must be > 0, got {requested}")
        return requested
    cpus = [n["Resources"].get("CPU", 0) for n in ray.nodes() if n.get("Alive")]
    return max(1.0, min(c for c in cpus if c > 0)) if any(c > 0 for c in cpus) else 1.0


def run_shards(
    compute: Callable,
    save: Callable[[Shard, object], None],
    shards: Sequence[Shard],
    *,
    backend: str = "local",
    address: str | None = None,
    cpus_per_task: float | None = None,
    max_retries: int = 3,
    progress: bool = True,
    desc: str = "shards",
    unit: str = "shards",
) -> int:
    """Compute every shard whose output is missing and save it; returns how many were computed.

    Args:
      compute: a module-level function (Ray pickles it by reference): ``compute(*shard.args)``.
      save: ``save(shard, result)`` on the driver; must write ``shard.output`` atomically, last.
      backend: ``local`` or ``ray``.
      address, cpus_per_task: the Ray cluster and the CPUs each task reserves.
      max_retries: Ray's retries of a task whose worker died.

    Raises:
      BackendError: Ray missing, the cluster unreachable, or its workers lacking the package.
    """
    if backend not in BACKENDS:
        raise BackendError(f"--backend must be one of {', '.join(BACKENDS)}, got {backend!r}")
    total = sum(s.work for s in shards)
    todo = [s for s in shards if not s.output.exists()]
    done = total - sum(s.work for s in todo)
    ray = _connect(address) if backend == "ray" else None  # before the bar: errors come first
    with bar(desc, unit=unit, enabled=progress) as progress_bar:
        progress_bar.update(done, total)
        if ray is None:
            for shard in todo:
                save(shard, compute(*shard.args))
                done += shard.work
                progress_bar.update(done, total)
            return len(todo)
        if not todo:
            return 0
        remote = ray.remote(compute).options(num_cpus=_cpus_per_task(ray, cpus_per_task), max_retries=max_retries)
        pending = {remote.remote(*s.args): s for s in todo}
        while pending:
            ready, _ = ray.wait(list(pending), num_returns=1)
            shard = pending.pop(ready[0])
            try:
                result = ray.get(ready[0])
            except ray.exceptions.RayError as e:
                for ref in pending:
                    ray.cancel(ref)
                cause = getattr(e, "cause", None)
                if isinstance(cause, ModuleNotFoundError) or "No module named" in str(e):
                    raise BackendError(
                        f"the Ray workers cannot import the toolkit ({str(cause or e).splitlines()[0]}): "
                        "install socialnav-jax on every node"
                    ) from e
                raise
            save(shard, result)
            done += shard.work
            progress_bar.update(done, total)
    return len(todo)


def run_with_args(
    compute: Callable, save: Callable[[Shard, object], None], shards: Sequence[Shard], args, **bar
) -> int:
    """:func:`run_shards` with the backend options of a parsed command line (``--backend``,
    ``--ray-address``, ``--ray-cpus-per-task``, ``--no-progress``); ``bar``: ``desc``, ``unit``."""
    return run_shards(
        compute,
        save,
        shards,
        backend=getattr(args, "backend", "local"),
        address=getattr(args, "ray_address", None),
        cpus_per_task=getattr(args, "ray_cpus_per_task", None),
        progress=not getattr(args, "no_progress", False),
        **bar,
    )


STAGING_SIGNATURE = "socialnav-shards/1"


def _is_staging(folder: pathlib.Path) -> dict | None:
    """The layout recorded in a shard staging folder this toolkit made, else None."""
    import json

    try:
        raw = json.loads((folder / "settings.json").read_text())
    except (OSError, ValueError):
        return None
    if isinstance(raw, dict) and raw.get("format") == STAGING_SIGNATURE:
        return raw.get("layout")
    return None


def staging_folder(folder: pathlib.Path, layout: dict) -> pathlib.Path:
    """The folder where a job keeps its finished shards until it commits its output: reused when
    it holds shards of the same ``layout`` (settings and shard sizes), emptied when it holds
    another run's, created if missing; ``layout`` is recorded in ``settings.json`` there.

    Raises:
      common.runfolder.NotOurs: ``folder`` exists and is not a staging folder of this toolkit
        (nothing in it is removed).
    """
    import json
    import shutil

    from socialnav.common.atomic import write_text_atomic
    from socialnav.common.runfolder import NotOurs

    if folder.exists() or folder.is_symlink():
        recorded = _is_staging(folder) if folder.is_dir() and not folder.is_symlink() else None
        if recorded is None and (not folder.is_dir() or folder.is_symlink() or any(folder.iterdir())):
            raise NotOurs(f"{folder} exists and is not a shard folder socialnav made: move it away")
        if recorded is not None and recorded != json.loads(json.dumps(layout)):
            shutil.rmtree(folder)
    folder.mkdir(parents=True, exist_ok=True)
    write_text_atomic(folder / "settings.json", json.dumps({"format": STAGING_SIGNATURE, "layout": layout}))
    return folder


def remove_staging(folder: pathlib.Path) -> None:
    """Remove a shard staging folder once its job has committed, if it is one this toolkit made."""
    import shutil

    if folder.is_dir() and not folder.is_symlink() and _is_staging(folder) is not None:
        shutil.rmtree(folder)
