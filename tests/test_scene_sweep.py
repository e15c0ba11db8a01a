"""A scene's free parameter swept (scripts/scene_sweep.py) and the copies' shared variants
(the scene file's ``variants_of``)."""

import json

import jax
import numpy as np
import pandas as pd
import pytest
import script_loader

from socialnav.data import SCENES_DIR
from socialnav.jaxsim.scenario.errors import ScenarioError
from socialnav.jaxsim.scenes.spec import load_scene
from socialnav.jaxsim.scenes.variant import sample_variants

sweep = script_loader.load("scene_sweep")
ENTRANCE = SCENES_DIR / "gscl_crowded_entrance.json"


def _same(a, b) -> bool:
    return all(np.array_equal(x, y) for x, y in zip(jax.tree.leaves(a), jax.tree.leaves(b), strict=True))


def test_a_copy_that_changes_nothing_draws_the_scenes_own_variants(tmp_path):
    """The copies name the scene they copy (``variants_of``): a copy with the scene's own value
    draws its variants bit for bit; one with another start draws the same numbers but the
    starts; a copy under another name without ``variants_of`` draws other variants."""
    own = load_scene(ENTRANCE)
    same, later = sweep.sweep_copies(ENTRANCE, "people.start_s", [[2.0, 4.0], [4.0, 6.0]], tmp_path)
    assert load_scene(same).name == "gscl_crowded_entrance+sweep0"
    assert _same(sample_variants(own, 0, 8), sample_variants(load_scene(same), 0, 8))
    assert _same(sample_variants(own, 0, 8, held_out=True), sample_variants(load_scene(same), 0, 8, held_out=True))
    a, b = sample_variants(own, 0, 8), sample_variants(load_scene(later), 0, 8)
    assert np.array_equal(a.xy0, b.xy0) and np.array_equal(a.speed_mps, b.speed_mps)
    assert not np.array_equal(a.start_s, b.start_s)
    valid = np.asarray(b.valid) & (np.asarray(b.start_s) > 0)
    assert valid.any() and np.all((np.asarray(b.start_s)[valid] >= 4.0) & (np.asarray(b.start_s)[valid] <= 6.0))
    renamed = json.loads(same.read_text())
    del renamed["variants_of"]
    (tmp_path / "renamed.json").write_text(json.dumps(renamed))
    assert not _same(sample_variants(own, 0, 8), sample_variants(load_scene(tmp_path / "renamed.json"), 0, 8))


def test_a_variants_of_that_cannot_be_a_name_is_refused(tmp_path):
    scene = json.loads(ENTRANCE.read_text()) | {"variants_of": "../up"}
    (tmp_path / "bad.json").write_text(json.dumps(scene))
    with pytest.raises(ScenarioError, match="variants_of"):
        load_scene(tmp_path / "bad.json")


def test_a_field_is_set_through_lists_and_a_missing_one_is_named():
    scene = json.loads((SCENES_DIR / "gscl_l_hallway.json").read_text())
    assert sweep.set_field(scene, "rule.rules.min_share", 0.5) == 2  # both legs' keep-right, not the others
    assert [r.get("min_share") for r in scene["rule"]["rules"]] == [0.5, 0.5, None, None]
    assert sweep.set_field(scene, "timeout_s", 30.0) == 1 and scene["timeout_s"] == 30.0
    with pytest.raises(ValueError, match="rule.rules.nothing: no such field in scene 'gscl_l_hallway'"):
        sweep.set_field(scene, "rule.rules.nothing", 1.0)
    assert sweep.parse_value("0,0.5") == [0.0, 0.5] and sweep.parse_value("2") == 2.0
    assert sweep.parse_value("[-5,5,-7.25]") == [-5.0, 5.0, -7.25] and sweep.parse_value("[2]") == [2.0]
    with pytest.raises(ValueError, match="'a,b': a number"):
        sweep.parse_value("a,b")


def test_a_wall_is_moved_by_index_and_shift_and_the_moved_copy_draws_the_same_variants(tmp_path):
    """``walls.4.2`` picks one number of one wall; ``+`` sets several fields alike; ``--shift``
    adds to what is there. The L-hallway's dead end moved 2 m up: the end wall, the side walls'
    and the map's top edges move together, nothing else changes, and the copy's variants are the
    scene's own (the draws do not read the walls)."""
    hallway = SCENES_DIR / "gscl_l_hallway.json"
    scene = json.loads(hallway.read_text())
    top = "bounds_m.3+walls.1.3+walls.2.3+walls.3.3+walls.4.2+walls.4.3"
    assert sweep.set_field(scene, top, 2.0, shift=True) == 6
    before = json.loads(hallway.read_text())
    assert scene["walls"][4] == [-7, 3, 8.9, 9] and scene["bounds_m"] == [-7, 3, -2, 9]
    assert [w[3] for w in scene["walls"][1:4]] == [9, 9, 9] and scene["walls"][0] == before["walls"][0]
    assert {k: v for k, v in scene.items() if k not in ("walls", "bounds_m")} == {
        k: v for k, v in before.items() if k not in ("walls", "bounds_m")
    }
    assert sweep.set_field(scene, "robot.goal", 0.5, shift=True) == 1 and scene["robot"]["goal"] == [1.5, 6.5]
    assert sweep.set_field(scene, "walls.-1", [0, 1, 2, 3]) == 1 and scene["walls"][-1] == [0, 1, 2, 3]
    with pytest.raises(ValueError, match="walls.9.3: no such field"):
        sweep.set_field(scene, "walls.9.3", 1.0)
    with pytest.raises(ValueError, match='rule.type: "all" is not a number'):
        sweep.set_field(scene, "rule.type", 1.0, shift=True)
    (moved,) = sweep.sweep_copies(hallway, top, [2.0], tmp_path, shift=True)
    assert "moved by 2.0" in json.loads(moved.read_text())["source"]
    copy = load_scene(moved)
    assert _same(sample_variants(load_scene(hallway), 0, 8), sample_variants(copy, 0, 8))


def test_a_second_field_set_with_the_swept_one_takes_its_own_value_per_copy(tmp_path):
    """``--also``: the crossing walker's speed swept with its start, copy k taking value k of
    each; the speeds drawn are the scene's draws moved into each band; counts that differ are
    refused naming the field."""
    crossing = SCENES_DIR / "casn_crossing.json"
    slow, fast = sweep.sweep_copies(
        crossing,
        "people.speed_mps",
        [[0.3, 0.5], [0.85, 1.15]],
        tmp_path,
        also=(("people.start_s", [[1.5, 3.0], [5.55, 7.05]]),),
    )
    fast_scene = json.loads(fast.read_text())
    assert fast_scene["people"][0]["speed_mps"] == [0.85, 1.15] and fast_scene["people"][0]["start_s"] == [5.55, 7.05]
    assert "people.start_s = [5.55, 7.05]" in fast_scene["source"]
    own, a, b = (sample_variants(load_scene(f), 0, 16) for f in (crossing, slow, fast))
    assert _same(own, a)
    u = (np.asarray(own.speed_mps)[:, 0] - 0.3) / 0.2  # the scene's uniform draws, mapped into the fast band
    assert np.allclose(np.asarray(b.speed_mps)[:, 0], 0.85 + 0.3 * u, atol=1e-5)
    assert np.all((np.asarray(b.start_s)[:, 0] >= 5.55) & (np.asarray(b.start_s)[:, 0] <= 7.05))
    with pytest.raises(ValueError, match="--also people.start_s: 1 values for 2 swept values"):
        sweep.sweep_copies(crossing, "people.speed_mps", [0.4, 1.0], tmp_path, also=(("people.start_s", [2.0]),))


def test_the_sweep_table_puts_each_values_rate_in_its_row():
    rows = []
    for k, pct in enumerate((79.0, 28.0)):
        for method, p in (("navfn", 0.0), ("gscl", pct)):
            rows.append(
                {
                    "scene": f"s+sweep{k}",
                    "method": method,
                    "n": 100,
                    "social_no_collision_pct": p,
                    "social_no_collision_lo": max(p - 9, 0),
                    "social_no_collision_hi": min(p + 9, 100),
                }
            )
    said = sweep.sweep_table(pd.DataFrame(rows), {"scene": "s", "field": "people.start_s", "values": [[0, 0.5], 4]})
    named = {"scene": "s", "field": "a.b+c.d", "values": [0, 1], "label": "moved (m)"}
    assert sweep.sweep_table(pd.DataFrame(rows), named).splitlines()[0] == "| moved (m) | navfn | gscl |"
    assert said.splitlines()[:4] == [
        "| people.start_s | navfn | gscl |",
        "|---|---|---|",
        "| 0-0.5 | 0 [0, 9] | 79 [70, 88] |",
        "| 4 | 0 [0, 9] | 28 [19, 37] |",
    ]
    fig = sweep.sweep_figure(pd.DataFrame(rows), {"scene": "s", "field": "people.start_s", "values": [[0, 0.5], 4]})
    assert len(fig.axes[0].lines) >= 2
