"""The hand-written CPU social force (jaxsim.native) against the JAX one: batched, per-world
parameters, batch invariance, the edge sizes, and how a failed build reads."""

from __future__ import annotations

import dataclasses
import shutil

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from socialnav.jaxsim import native
from socialnav.jaxsim import social_force as sf

needs_compiler = pytest.mark.skipif(
    native.disabled() or shutil.which("c++") is None, reason="no C++ compiler, or SOCIALNAV_NATIVE=off"
)


def _crowd(key, worlds: int, agents: int):
    k = jax.random.split(key, 5)
    x, y = jax.random.uniform(k[0], (2, worlds, agents), minval=-8.0, maxval=8.0)
    vx, vy = jax.random.normal(k[2], (2, worlds, agents))
    weight = (jax.random.uniform(k[4], (worlds, agents)) > 0.2).astype(jnp.float32)
    return x, y, vx, vy, weight


@needs_compiler
def test_the_kernel_is_built_and_is_what_the_simulator_calls(warehouse):
    assert native.social_force_available()
    p = warehouse.params
    x = jnp.zeros((3, 51))
    text = jax.jit(jax.vmap(lambda *a: sf.social_force(p, *a))).lower(x, x, x, x, x).as_text()
    assert native.SOCIAL_FORCE_TARGET in text


@pytest.mark.slow
@needs_compiler
@pytest.mark.parametrize("worlds", [1, 5, 64, 130])  # under, at and over one block of 64 lanes
def test_kernel_equals_jax_over_a_batch_with_per_world_parameters(warehouse, worlds):
    base = warehouse.params
    x, y, vx, vy, weight = _crowd(jax.random.key(worlds), worlds, 51)
    # Each world its own interaction parameters (stacked params, as a sweep would vmap them).
    scale = jnp.linspace(0.7, 1.3, worlds)
    params = jax.vmap(
        lambda s: dataclasses.replace(
            base,
            worker_social_lambda=base.worker_social_lambda * s,
            worker_social_gamma=base.worker_social_gamma * s,
            worker_social_force_factor=base.worker_social_force_factor * s,
        )
    )(scale)
    got = jax.jit(jax.vmap(sf.social_force))(params, x, y, vx, vy, weight)
    want = jax.jit(jax.vmap(sf.social_force_xla))(params, x, y, vx, vy, weight)
    top = float(jnp.max(jnp.abs(jnp.stack(want)))) + 1.0
    np.testing.assert_allclose(np.stack(got), np.stack(want), atol=2e-6 * top)
    # The parameters really differ between worlds: the first world's alone give another answer.
    if worlds > 1:
        first = jax.tree.map(lambda a: a[0], params)
        other = jax.vmap(lambda *a: sf.social_force(first, *a))(x, y, vx, vy, weight)
        assert float(jnp.max(jnp.abs(other[0][-1] - got[0][-1]))) > 1e-3


@pytest.mark.slow
@needs_compiler
def test_a_world_gets_the_same_bits_alone_and_inside_any_batch(warehouse):
    """300 worlds: four blocks of 64, shared out over XLA's threads where there are several, then
    44 in narrower blocks; each world as it is alone and beside another."""
    p = warehouse.params
    crowd = _crowd(jax.random.key(7), 300, 51)
    batched = jax.jit(jax.vmap(lambda *a: sf.social_force(p, *a)))(*crowd)
    for row in (0, 63, 64, 191, 255, 256, 299):
        alone = sf.social_force(p, *(a[row] for a in crowd))
        assert np.array_equal(np.asarray(alone[0]), np.asarray(batched[0][row]))
        assert np.array_equal(np.asarray(alone[1]), np.asarray(batched[1][row]))
        # Two-world batch with the row last: other neighbours in the lanes, same answer.
        pair = jax.vmap(lambda *a: sf.social_force(p, *a))(*(a[jnp.array([5, row])] for a in crowd))
        assert np.array_equal(np.asarray(pair[0][1]), np.asarray(batched[0][row]))


@needs_compiler
@pytest.mark.parametrize("agents", [0, 1])
def test_no_pairs_no_force(warehouse, agents):
    p = warehouse.params
    crowd = _crowd(jax.random.key(1), 4, agents)
    ax, ay = jax.vmap(lambda *a: sf.social_force(p, *a))(*crowd)
    assert ax.shape == (4, agents) and not np.any(np.asarray(ax)) and not np.any(np.asarray(ay))


def test_a_source_that_does_not_compile_names_the_file_and_the_error(tmp_path, monkeypatch):
    if shutil.which("c++") is None:
        pytest.skip("no C++ compiler")
    bad = tmp_path / "broken.cc"
    bad.write_text("int main( { return 0; }\n")
    monkeypatch.setenv("SOCIALNAV_NATIVE_CACHE", str(tmp_path / "cache"))
    with pytest.raises(RuntimeError, match=r"compiling broken\.cc failed: .*error"):
        native.build(bad)
    assert not list((tmp_path / "cache").glob("*.so*"))  # nothing half written is left


def test_no_compiler_is_a_clear_error(tmp_path, monkeypatch):
    monkeypatch.setenv("CXX", str(tmp_path / "no-such-compiler"))
    monkeypatch.setenv("SOCIALNAV_NATIVE_CACHE", str(tmp_path / "cache"))
    with pytest.raises(RuntimeError, match="no C\\+\\+ compiler"):
        native.build()


@pytest.mark.skipif(shutil.which("c++") is None, reason="no C++ compiler here")
def test_a_cache_that_cannot_hold_the_kernel_is_named_with_its_variable(tmp_path, monkeypatch):
    """``SOCIALNAV_NATIVE_CACHE`` naming a file: the error (the warning's reason, the simulator
    going on in XLA's code) names the folder, why, and the variable; it was ``[Errno 17] File exists``."""
    (tmp_path / "a file").write_text("")
    monkeypatch.setenv("SOCIALNAV_NATIVE_CACHE", str(tmp_path / "a file"))
    with pytest.raises(RuntimeError, match=r"its cache .*a file: a file, not a folder; SOCIALNAV_NATIVE_CACHE names"):
        native.build()


@pytest.mark.parametrize(("value", "off"), [("off", True), ("0", True), ("FALSE", True), ("", False), ("1", False)])
def test_the_switch(monkeypatch, value, off):
    monkeypatch.setenv("SOCIALNAV_NATIVE", value)
    assert native.disabled() is off


def test_the_target_processor_is_a_setting_and_part_of_the_build_key(monkeypatch):
    monkeypatch.delenv("SOCIALNAV_NATIVE_MARCH", raising=False)
    assert native.flags()[-1] == "-march=native"
    monkeypatch.setenv("SOCIALNAV_NATIVE_MARCH", " x86-64-v3 ")
    assert native.flags()[-1] == "-march=x86-64-v3" and "-fno-trapping-math" in native.flags()


def test_the_scheduling_flags_go_to_gcc_only():
    """GCC's scheduling flags go to GCC alone (another compiler may reject them, and a failed build
    falls back to the JAX force), and to the social force alone (the Dijkstra is slower with them)."""
    gcc = "c++ (Debian 12.2.0-14+deb12u1) 12.2.0\nCopyright (C) 2022 Free Software Foundation, Inc.\n"
    clang = "Debian clang version 14.0.6\nTarget: x86_64-pc-linux-gnu\n"
    assert set(native.GCC_FLAGS) <= set(native.flags(gcc))
    assert not set(native.GCC_FLAGS) & set(native.flags(clang))
    assert native.flags(clang)[-1] == native.flags(gcc)[-1]
    other = native.SOURCE.with_name("other.cc")  # the planners' Dijkstra, say: not for it
    assert not set(native.GCC_FLAGS) & set(native.flags(gcc, other))


def _has_avx2() -> bool:
    try:
        with open("/proc/cpuinfo", encoding="ascii", errors="replace") as f:
            return " avx2" in f.read()
    except OSError:
        return False


@needs_compiler
@pytest.mark.slow
@pytest.mark.skipif(not _has_avx2(), reason="the processor has no AVX2")
def test_the_avx2_build_passes_the_same_checks(tmp_path):
    """The AVX2 build (8-lane narrow blocks, no AVX-512) under XLA capped at AVX2, as a processor
    without AVX-512 runs it: this module's kernel checks again, in a process of its own."""
    import os
    import pathlib
    import subprocess
    import sys

    env = dict(
        os.environ,
        SOCIALNAV_NATIVE_MARCH="x86-64-v3",
        SOCIALNAV_NATIVE_CACHE=str(tmp_path),
        XLA_FLAGS=(os.environ.get("XLA_FLAGS", "") + " --xla_cpu_max_isa=AVX2").strip(),
    )
    here = pathlib.Path(__file__)
    done = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-n", "0", "-m", "slow or not slow"]
        + [str(here), "-k", "equals or same_bits"],
        env=env,
        cwd=here.parent.parent,
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-2000:]
    assert "5 passed" in done.stdout  # 4 batch sizes against JAX, and the batch-invariance check
    (library,) = tmp_path.glob("social_force-*.so")  # built there, for x86-64-v3
    assert library.stat().st_size > 0


def test_the_path_description_names_the_kernel_its_target_and_xla_cap(monkeypatch):
    monkeypatch.setenv("XLA_FLAGS", "--xla_force_host_platform_device_count=2 --xla_cpu_max_isa=AVX2")
    monkeypatch.setenv("SOCIALNAV_NATIVE_MARCH", "x86-64-v3")
    text = native.describe()
    assert text.endswith("; XLA capped at AVX2") and f"processor {native.cpu_isa()}" in text
    if native.social_force_available():
        assert text.startswith("C++ kernel (jaxsim.native, -march=x86-64-v3)")
    monkeypatch.setenv("XLA_FLAGS", "")
    assert "capped" not in native.describe()
