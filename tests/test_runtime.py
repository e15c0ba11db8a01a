"""The process set-up of the ``socialnav`` command: XLA's host devices and vector width."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from socialnav import runtime
from socialnav.common.machine import compiler_host, cpu_isa, hosts_of, usable_cores

ROOT = os.path.join(os.path.dirname(__file__), "..")
ZEN5 = "processor\t: 0\nflags\t\t: fpu sse2 avx2 fma avx512f avx512dq avx512_bf16\n"
ZEN3 = "processor\t: 0\nflags\t\t: fpu sse2 avx2 fma\n"
FP16_ONLY = "flags\t\t: fpu avx2 avx512fp16\n"  # a name that starts like avx512f but is not it


@pytest.mark.skipif(not hasattr(os, "sched_setaffinity"), reason="no CPU affinity on this platform")
def test_host_devices_are_the_cores_the_process_may_run_on_not_the_machines():
    """A process pinned to one core (as ``taskset -c 0`` pins it) asks for one host device, where
    ``os.cpu_count()`` would still say every core of the machine; a count given, or one already in
    ``XLA_FLAGS``, is kept."""
    code = (
        "import os; os.sched_setaffinity(0, {min(os.sched_getaffinity(0))}); "
        "from socialnav import runtime; runtime.request_host_devices(); print(os.environ['XLA_FLAGS'])"
    )
    env = {k: v for k, v in os.environ.items() if k != "XLA_FLAGS"}
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "--xla_force_host_platform_device_count=1"
    assert usable_cores() == len(os.sched_getaffinity(0))


def test_a_device_count_given_or_already_set_is_kept(monkeypatch):
    # setenv, not delenv(raising=False): that records nothing when the variable is absent, so the
    # count set below outlived the test, and a later test's JAX started with 3 host devices.
    monkeypatch.setenv("XLA_FLAGS", "")
    runtime.request_host_devices(3)
    assert os.environ["XLA_FLAGS"] == "--xla_force_host_platform_device_count=3"
    runtime.request_host_devices()  # already set: nothing added
    assert os.environ["XLA_FLAGS"] == "--xla_force_host_platform_device_count=3"


def test_avx512f_is_read_from_the_flags_line():
    assert runtime.cpu_has_avx512(ZEN5)
    assert not runtime.cpu_has_avx512(ZEN3)
    assert not runtime.cpu_has_avx512(FP16_ONLY)
    assert not runtime.cpu_has_avx512("")


def test_wide_vectors_are_asked_for_only_where_the_cpu_has_them(monkeypatch):
    monkeypatch.setenv("XLA_FLAGS", "--xla_force_host_platform_device_count=2")
    runtime.request_wide_vectors(ZEN3)
    assert os.environ["XLA_FLAGS"] == "--xla_force_host_platform_device_count=2"
    runtime.request_wide_vectors(ZEN5)
    assert os.environ["XLA_FLAGS"] == "--xla_force_host_platform_device_count=2 --xla_cpu_prefer_vector_width=512"
    runtime.request_wide_vectors(ZEN5)  # asking twice adds nothing
    assert os.environ["XLA_FLAGS"].count("prefer_vector_width") == 1


def test_a_width_the_user_set_is_kept(monkeypatch):
    monkeypatch.setenv("XLA_FLAGS", "--xla_cpu_prefer_vector_width=256")
    runtime.request_wide_vectors(ZEN5)
    assert os.environ["XLA_FLAGS"] == "--xla_cpu_prefer_vector_width=256"


@pytest.mark.slow
def test_a_day_is_bitwise_reproducible_with_either_width():
    """Two processes with the same vector width give the same day bit for bit (either width)."""
    code = "import sys; sys.path.insert(0, 'tests'); from test_determinism import day_digest; print(day_digest(2))"
    digests = {}
    for width in (256, 512, 512, 256):
        env = dict(os.environ, XLA_FLAGS=f"--xla_cpu_prefer_vector_width={width}")
        run = [sys.executable, "-c", code]
        out = subprocess.run(run, cwd=ROOT, env=env, capture_output=True, text=True, check=True)
        digests.setdefault(width, set()).add(out.stdout.strip())
    assert len(digests[256]) == 1 and len(digests[512]) == 1


def test_the_compiler_host_names_what_a_results_rounding_depends_on():
    """``compiler_host``: the versions, the processor and its widest vector instructions (as the
    process set-up reads them) and XLA's flags; a simulated run's ``run.json`` records the same."""
    import jax

    from socialnav.jaxsim import logs, native

    host = compiler_host()
    assert list(host) == ["jax", "jaxlib", "cpu", "isa", "machine", "xla_flags"]
    assert host["jax"] == jax.__version__ and host["xla_flags"] == os.environ.get("XLA_FLAGS", "")
    assert host["isa"] == cpu_isa() == native.cpu_isa() and (host["isa"] == "AVX-512") == runtime.cpu_has_avx512()
    assert logs.reproducibility().items() >= host.items()


def test_a_trainings_hosts_are_its_lines_each_once_in_order():
    """``hosts_of``: the hosts of a training's lines (a GSCL card's ``trained_on``; a resumed run
    may span machines), each once in the order first met; lines written before hosts were
    recorded add none."""
    here, there = {"cpu": "a", "isa": "AVX2"}, {"cpu": "b", "isa": "AVX-512"}
    history = [{"epoch": 1}, {"epoch": 2, "host": here}, {"epoch": 3, "host": there}, {"epoch": 4, "host": here}]
    assert hosts_of(history) == [here, there]
    assert hosts_of([{"epoch": 1}]) == [] and hosts_of([]) == []


CACHED_PROGRAM = """
import sys, jax, jax.numpy as jnp
from socialnav import runtime
jax.config.update("jax_compilation_cache_dir", sys.argv[1])
jax.config.update("jax_persistent_cache_min_compile_time_secs", 0)
jax.config.update("jax_persistent_cache_min_entry_size_bytes", 0)
if sys.argv[2] == "repair":
    runtime.repair_compilation_cache()
print(float(jax.jit(lambda x: jnp.sin(x) * 3)(1.0)))
"""


@pytest.mark.slow  # three processes compiling: 13 s
def test_a_cache_entry_cut_short_is_stored_again_once_not_read_for_good(tmp_path):
    """An entry cut short (as a full disk leaves it): JAX alone warns about it in every process
    and keeps it; with the repair, the first process that meets it removes it and stores the
    program again, and the next reads it without a word. Programs that read are left alone."""
    cache = tmp_path / "cache"

    def run(mode: str) -> str:
        done = subprocess.run(
            [sys.executable, "-c", CACHED_PROGRAM, str(cache), mode], cwd=ROOT, capture_output=True, text=True
        )
        assert done.returncode == 0, done.stderr
        assert float(done.stdout) == pytest.approx(3 * 0.8414709848)
        return done.stderr

    assert "Error reading" not in run("repair")
    (entry,) = cache.glob("jit__lambda-*-cache")
    whole = entry.read_bytes()
    (cache / "jit__other-0-cache").write_bytes(b"not ours to judge by name")  # another program's entry
    entry.write_bytes(whole[: len(whole) // 2])
    for _ in range(2):  # without the repair: the same warning every time, the entry kept cut short
        assert "Error reading persistent compilation cache entry for 'jit__lambda'" in run("plain")
        assert len(entry.read_bytes()) == len(whole) // 2
    assert f"removed {entry.name}" in run("repair")
    assert entry.exists() and runtime.remove_unreadable_entries("jit__lambda", str(cache)) == []  # stored again, whole
    assert "Error reading" not in run("repair")
    assert (cache / "jit__other-0-cache").exists()


def test_a_cache_folder_that_cannot_hold_the_cache_is_named_and_left_off(tmp_path, monkeypatch, capsys):
    """SOCIALNAV_JAX_CACHE naming a file (or a folder under one): a one-line warning naming it,
    and no cache asked of JAX (which would run without one, saying nothing); a folder that can
    hold it is made and asked for."""
    monkeypatch.delenv("JAX_COMPILATION_CACHE_DIR", raising=False)
    (tmp_path / "a-file").write_text("not a folder")
    for folder, why in ((tmp_path / "a-file", "a file, not a folder"), (tmp_path / "a-file" / "xla", "cannot be made")):
        monkeypatch.setenv("SOCIALNAV_JAX_CACHE", str(folder))
        runtime.request_compilation_cache()
        assert "JAX_COMPILATION_CACHE_DIR" not in os.environ
        err = capsys.readouterr().err.strip()
        assert err.startswith(f"socialnav: warning: the compilation cache {folder}: {why}") and "\n" not in err
    assert runtime.cache_folder_problem(str(tmp_path / "new" / "xla")) is None
    assert (tmp_path / "new" / "xla").is_dir()


@pytest.mark.parametrize("value", ["1", "True", "maybe"])
def test_x64_asked_for_is_turned_off_with_a_note(value, monkeypatch, capsys):
    """``JAX_ENABLE_X64`` set true (or to what JAX cannot read): off for this process and its
    children, and one line naming the value; set false or unset: untouched, nothing said."""
    monkeypatch.setenv("JAX_ENABLE_X64", value)
    runtime.request_float32()
    assert os.environ["JAX_ENABLE_X64"] == "0"
    err = capsys.readouterr().err.strip()
    note = "ignored: the toolkit runs in float32, as its seeds and tables are defined"
    assert err == f"socialnav: note: JAX_ENABLE_X64={value} {note}"
    for value in ("off", "0"):
        monkeypatch.setenv("JAX_ENABLE_X64", value)
        runtime.request_float32()
        assert os.environ["JAX_ENABLE_X64"] == value
    monkeypatch.delenv("JAX_ENABLE_X64")
    runtime.request_float32()
    assert "JAX_ENABLE_X64" not in os.environ and capsys.readouterr().err == ""


def test_platforms_unset_are_no_problem(monkeypatch):
    monkeypatch.delenv("JAX_PLATFORMS", raising=False)
    assert runtime.jax_platforms_problem() is None


def _socialnav(argv: list[str], **env: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "socialnav", *argv],
        capture_output=True,
        text=True,
        env={**os.environ, "PYTHONPATH": ROOT, **env},
        timeout=300,
    )


def test_a_platform_jax_cannot_start_ends_the_command_in_one_line(tmp_path):
    """``JAX_PLATFORMS`` naming a platform JAX has no backend for: exit status 2, one line naming
    the variable and what to do, no run folder made (JAX's own error: a traceback, or for a
    platform no plugin provides, a bare AssertionError)."""
    out = tmp_path / "out"
    proc = _socialnav(
        ["simulate", "--hours", "0.01", "--out", str(out), "--no-progress"], JAX_PLATFORMS="nosuchplatform"
    )
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    line = proc.stderr.strip()
    assert "\n" not in line and line.startswith("socialnav simulate: JAX_PLATFORMS=nosuchplatform: JAX cannot start it")
    assert "unset JAX_PLATFORMS" in line and not out.exists()


@pytest.mark.slow  # two short days: 20 s
def test_a_day_under_jax_enable_x64_is_the_float32_day(tmp_path):
    """``JAX_ENABLE_X64=1`` in the user's environment: the command notes it and writes the logs it
    writes without it, bit for bit (before, the same seed gave other numbers)."""
    day = ["simulate", "--worlds", "1", "--slots", "1", "--slot-length-s", "60", "--no-progress", "--out"]
    x64 = _socialnav([*day, str(tmp_path / "x64")], JAX_ENABLE_X64="1")
    plain = _socialnav([*day, str(tmp_path / "plain")], JAX_ENABLE_X64="0")
    assert x64.returncode == 0 and plain.returncode == 0, x64.stderr + plain.stderr
    assert "JAX_ENABLE_X64=1 ignored" in x64.stderr and "JAX_ENABLE_X64" not in plain.stderr
    assert (tmp_path / "x64" / "logs.parquet").read_bytes() == (tmp_path / "plain" / "logs.parquet").read_bytes()


WARNINGS_PROGRAM = """
import warnings
from socialnav import runtime
runtime.one_line_warnings()
runtime.one_line_warnings()  # a second command in one process installs it once
warnings.warn("socialnav.jaxsim.native: XLA's slower code (no compiler)")
warnings.warn("a library's own warning")
"""


def test_the_toolkits_own_warnings_are_one_line_and_others_keep_pythons_format(tmp_path):
    env = {k: v for k, v in os.environ.items() if k != "SOCIALNAV_VERBOSE"}
    done = subprocess.run([sys.executable, "-c", WARNINGS_PROGRAM], capture_output=True, text=True, env=env)
    err = done.stderr.splitlines()
    assert err[0] == "socialnav: warning: socialnav.jaxsim.native: XLA's slower code (no compiler)"
    assert "UserWarning: a library's own warning" in err[1] and "<string>" in err[1]  # Python's format
    verbose = subprocess.run(
        [sys.executable, "-c", WARNINGS_PROGRAM], capture_output=True, text=True, env={**env, "SOCIALNAV_VERBOSE": "1"}
    )
    assert "UserWarning: socialnav.jaxsim.native" in verbose.stderr and "socialnav: warning" not in verbose.stderr
