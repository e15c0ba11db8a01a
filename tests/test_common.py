"""The shared leaf: atomic writes leave the old file or the new one, never a half one or a
temporary; pytree helpers; the progress bar that shows nothing when disabled."""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
import pytest

from socialnav.common import atomic, progress, pytree


def test_atomic_write_replaces_whole_or_not_at_all(tmp_path):
    target = tmp_path / "sub" / "table.csv"
    atomic.write_text_atomic(target, "old\n")
    assert target.read_text() == "old\n"

    def fail(tmp):
        tmp.write_text("half")
        raise KeyboardInterrupt("killed mid-write")

    with pytest.raises(KeyboardInterrupt):
        atomic.write_atomic(target, fail)
    assert target.read_text() == "old\n"
    assert sorted(p.name for p in target.parent.iterdir()) == ["table.csv"]  # no temporary left
    atomic.write_bytes_atomic(tmp_path / "a.npz", lambda h: np.savez(h, x=np.arange(3)))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.npz", "sub"]  # savez added no second suffix
    np.testing.assert_array_equal(np.load(tmp_path / "a.npz")["x"], [0, 1, 2])
    assert atomic.temporary_path(target).suffix == ".csv"  # writers that pick a format from it still can


def test_pytree_helpers():
    a = {"x": jnp.arange(4), "y": jnp.zeros(4)}
    b = {"x": -jnp.arange(4), "y": jnp.ones(4)}
    chosen = pytree.select(jnp.array([True, False, True, False]), a, b)
    np.testing.assert_array_equal(chosen["x"], [0, -1, 2, -3])
    host = pytree.to_numpy(a)
    host["x"][0] = 7  # a writable copy
    pytree.put(host, np.array([1, 2]), pytree.take(pytree.to_numpy(b), np.array([1, 2])))
    np.testing.assert_array_equal(host["x"], [7, -1, -2, 3])
    stacked = pytree.stack([a, b])
    assert stacked["x"].shape == (2, 4)
    rows = pytree.select_rows(jnp.array([False, True]), {"m": jnp.zeros((2, 3, 2))}, {"m": jnp.ones((2, 3, 2))})
    np.testing.assert_array_equal(rows["m"][:, 0, 0], [1.0, 0.0])  # a row's every entry follows its mask


def test_a_disabled_bar_does_nothing(capsys):
    with progress.bar("quiet", enabled=False) as bar:
        bar.update(5, 10)
        bar.set_postfix(loss=1.0)
    assert capsys.readouterr().err == ""
    assert list(progress.iterate(range(3), "quiet", enabled=False)) == [0, 1, 2]
