"""The docs' results tables against the runs they came from (scripts/results_tables.py)."""

import json
import re
import shutil

import pandas as pd
import pytest
import script_loader

from socialnav.evaluation.arena import markdown

tables = script_loader.load("results_tables")


def _summary_row(scene, method, goal, social):
    row = {"scene": scene, "method": method, "n": 100}
    for rate, pct in (("goal_no_collision", goal), ("social_no_collision", social), ("goal_success", 100.0)):
        row |= {f"{rate}_pct": pct, f"{rate}_lo": max(pct - 9, 0), f"{rate}_hi": min(pct + 9, 100)}
    return row


def test_every_generated_table_in_the_pages_says_what_its_committed_run_says():
    """The drift test: each ``<!-- results: ... -->`` block of README.md and docs/*.md is the
    table its snapshot under docs/results/ makes now; the README and the results page have such
    blocks (a page that lost them would pass vacuously)."""
    blocks = {}
    for page in tables.pages():
        _, problems = tables.stale_blocks(page)
        assert not problems, "\n".join(problems)
        blocks[page.name] = len(tables.BLOCK.findall(page.read_text()))
    assert blocks["README.md"] >= 1 and blocks["arena-results.md"] >= 5


def test_a_changed_number_in_a_run_is_caught_and_written_back(tmp_path):
    """One cell changed in a copy of the snapshot: the page's block is named with its line, and
    the rewritten text holds the new number."""
    page = tables.ROOT / "README.md"
    match = tables.BLOCK.search(page.read_text())
    name = match["spec"].split()[1]
    results = tmp_path / "results"
    shutil.copytree(tables.RESULTS / name, results / name)
    summary = pd.read_csv(results / name / "summary.csv")
    row = (summary["scene"] == "gscl_queue") & (summary["method"] == "gscl")
    summary.loc[row, ["social_no_collision_pct", "social_no_collision_lo", "social_no_collision_hi"]] = [7, 3, 11]
    summary.to_csv(results / name / "summary.csv", index=False)
    text, problems = tables.stale_blocks(page, results)
    line = page.read_text().count("\n", 0, match.start()) + 1
    assert problems == [f"{page}:{line}: '{match['spec']}' {tables.DIFFERS}"]
    assert "| queue | GSCL | 100 / 93 | " in text and "| 7 [3, 11] |" in text
    assert text.count("<!-- /results -->") == page.read_text().count("<!-- /results -->")


def test_the_success_table_puts_each_rows_goal_and_social_success_in_its_cell():
    summary = pd.DataFrame(
        [
            _summary_row("a", "navfn", 100.0, 62.0),
            _summary_row("a", "gscl", 98.0, 1.0),
            _summary_row("a@held_out", "navfn", 90.0, 15.0),
            _summary_row("a@turned", "navfn", 100.0, 60.0),
            _summary_row("b", "navfn", 50.0, 0.0),
        ]
    )
    own = markdown.success_table(summary)
    assert own.splitlines() == [
        "| scene | navfn | gscl |",
        "|---|---|---|",
        "| `a` | 100 / 62 | 98 / 1 |",
        "| `b` | 50 / 0 | - |",
    ]
    assert markdown.success_table(summary, rows="held_out").splitlines()[2:] == ["| `a@held_out` | 90 / 15 |"]
    assert markdown.success_table(summary, rows="turned").splitlines()[2:] == ["| `a@turned` | 100 / 60 |"]
    with pytest.raises(ValueError, match="no turned rows"):
        markdown.success_table(summary[~summary["scene"].str.contains("@")], rows="turned")


def test_the_models_table_sets_one_methods_cells_of_several_runs_side_by_side(tmp_path):
    """Two runs of the same scenes with different GSCL models: each column is one run's gscl row,
    other methods ignored, a scene the second run lacks shown as '-', each run named by its line."""
    results = tmp_path / "results"
    for name, rows in {
        "first": [
            _summary_row("a", "gscl", 100.0, 49.0),
            _summary_row("a", "navfn", 100.0, 0.0),
            _summary_row("a@held_out", "gscl", 87.0, 0.0),
        ],
        "second": [_summary_row("a", "gscl", 100.0, 98.0)],
    }.items():
        (results / name).mkdir(parents=True)
        (results / name / "run.json").write_text(json.dumps({"gscl_model": name}))
        pd.DataFrame(rows).to_csv(results / name / "summary.csv", index=False)
    text = tables.render('models first other=second labels="open|closed"', results)
    assert "And from `" in text and "GSCL model second" in text
    assert text.strip().splitlines()[-4:] == [
        "| scene (gscl) | open | closed |",
        "|---|---|---|",
        "| `a` | 100 / 49 | 100 / 98 |",
        "| `a@held_out` | 87 / 0 | - |",
    ]
    with pytest.raises(ValueError, match="1 labels for 2 runs"):
        tables.render("models first other=second labels=open", results)
    with pytest.raises(ValueError, match="second: no row of method navfn"):
        tables.render("models first other=second method=navfn", results)
    with pytest.raises(ValueError, match="third: no snapshot"):
        tables.render("models first other=third", results)


def _claim(source, scene, diff, verdict):
    return {"source": source, "scene": scene, "metric": "social_no_collision_pct", "proposed": "gscl",
            "baseline": "navfn", "paper_diff": 60.0, "ours_diff": diff, "ours_diff_lo": diff - 5,
            "ours_diff_hi": diff + 5, "n_pairs": 100, "verdict": verdict}  # fmt: skip


def test_the_claims_table_keeps_one_papers_claims_and_reads_turned_rows(tmp_path):
    """``source=`` keeps the claims whose source starts so (a second run of one seed's scenes and
    methods, the rest not run); ``rows=turned`` reads the turned rows' directions."""
    results = tmp_path / "results"
    whole = [_claim("seed 001 Table 1", "x", 10.0, "reproduced"), _claim("seed 002 Table 1", "q", 89.0, "reproduced")]
    runs = {"whole": whole, "candidate": [_claim("seed 002 Table 1", "q", 3.0, "not reproduced")]}
    for name, claims in runs.items():
        (results / name).mkdir(parents=True)
        (results / name / "run.json").write_text(json.dumps({"gscl_model": name}))
        pd.DataFrame(claims).to_csv(results / name / "directions.csv", index=False)
        turned = [claim | {"verdict": "no difference here"} for claim in claims]  # the turned rows' own verdicts
        pd.DataFrame(turned).to_csv(results / name / "directions_turned.csv", index=False)
    text = tables.render('claims whole other=candidate labels="a|b" source="seed 002"', results)
    assert "seed 001" not in text and "| seed 002 Table 1 | `q` |" in text
    assert "1 claims in both runs; the verdict differs in 1:" in text
    assert "- q social_no_collision_pct (gscl - navfn): reproduced -> not reproduced" in text
    everything = tables.render("claims whole other=candidate rows=turned", results)
    assert "| seed 001 Table 1 | `x` |" in everything and "- | not run" in everything
    assert "2 claims" not in everything and "1 claims in both runs; the verdict differs in 0." in everything
    with pytest.raises(ValueError, match="source='seed 003': no claim"):
        tables.render('claims whole other=candidate source="seed 003"', results)


def test_a_snapshot_keeps_what_the_tables_read_and_names_the_command(tmp_path):
    run = tmp_path / "run"
    run.mkdir()
    (run / "run.json").write_text(json.dumps({"variants": 100, "seed": 0, "source_commit": "ab" * 20}))
    summary = pd.DataFrame([_summary_row("a", "navfn", 100.0, 62.0)]).assign(jerk_mean_mps3=1.0)
    summary.to_csv(run / "summary.csv", index=False)
    folder = tables.snapshot(run, "mine", tmp_path / "results", command="socialnav arena --scenes a")
    assert sorted(p.name for p in folder.iterdir()) == ["run.json", "summary.csv"]
    (folder / "notes.txt").write_text("mine")  # a user's file in the snapshot survives a new snapshot
    (folder / "turned.csv").write_text("stale")  # an earlier snapshot's file the run no longer has does not
    folder = tables.snapshot(run, "mine", tmp_path / "results", command="socialnav arena --scenes a")
    assert sorted(p.name for p in folder.iterdir()) == ["notes.txt", "run.json", "summary.csv"]
    assert "jerk_mean_mps3" not in pd.read_csv(folder / "summary.csv").columns
    said = tables.render("success mine", tmp_path / "results")
    assert said.startswith("From `") and "(`socialnav arena --scenes a`): commit abababababab," in said
    assert "| `a` | 100 / 62 |" in said
    (run / "run.json").write_text(json.dumps({"command": "socialnav arena"}))
    with pytest.raises(SystemExit, match="made by 'socialnav arena', not"):
        tables.snapshot(run, "mine", tmp_path / "results", command="socialnav arena --scenes a")
    with pytest.raises(SystemExit, match="cannot name a file"):
        tables.snapshot(run, "../up", tmp_path / "results")
    with pytest.raises(SystemExit, match="summary.csv: no such file"):
        (run / "summary.csv").unlink()
        tables.snapshot(run, "mine", tmp_path / "results")


def _episodes(scene, method, d_min, intruded):
    return pd.DataFrame(
        {"scene": scene, "method": method, "variant": range(len(d_min)), "d_min_m": d_min, "intruded": intruded}
    )


def test_two_methods_paired_by_variant_are_kept_by_the_snapshot_and_shown_per_scene(tmp_path):
    """Hand-made episodes: in scene ``x`` method a passes 0.5 m further than b in every variant
    and intrudes in one of four where b intrudes in all; the snapshot's pairs and the table say
    so, pairing by variant (b's rows shuffled), with a zero-width interval where every pair
    differs alike. A method the run lacks and a pair not written A:B are named."""
    run = tmp_path / "run"
    (run / "episodes").mkdir(parents=True)
    (run / "run.json").write_text(json.dumps({"command": "socialnav arena --scenes x"}))
    pd.DataFrame([_summary_row("x", "a", 100.0, 50.0)]).to_csv(run / "summary.csv", index=False)
    b = _episodes("x", "b", [0.2, 0.4, 0.1, 0.3], [1, 1, 1, 1]).iloc[[2, 0, 3, 1]]
    episodes = pd.concat([_episodes("x", "a", [0.7, 0.9, 0.6, 0.8], [0, 1, 0, 0]), b])
    episodes.to_parquet(run / "episodes" / "x.parquet")
    folder = tables.snapshot(run, "mine", tmp_path / "results", pairs=("a:b",))
    pairs = pd.read_csv(folder / markdown.PAIRS_FILE)
    assert set(pairs["metric"]) == {"d_min_m", "intruded"}
    d = pairs.set_index("metric").loc["d_min_m"]
    assert d["a - b"] == pytest.approx(0.5) and d["lo"] == pytest.approx(0.5) and d["hi"] == pytest.approx(0.5)
    said = tables.render("pairs mine metrics=d_min_m,intruded", tmp_path / "results")
    assert "| `x` | a - b | +0.50 [+0.50, +0.50] (0.75, 0.25) | -75 [" in said and "] (25, 100) |" in said
    sweep = {"scene": "s", "field": "people.speed_mps", "values": [[0.3, 0.5]], "label": "speed"}
    (folder / markdown.SWEEP_FILE).write_text(json.dumps(sweep))  # a sweep's copy is shown by its value
    pairs.assign(scene="s+sweep0").to_csv(folder / markdown.PAIRS_FILE, index=False)
    assert "| `s`, speed: 0.3-0.5 | a - b | +0.50 [" in tables.render(
        "pairs mine metrics=d_min_m", tmp_path / "results"
    )
    with pytest.raises(ValueError, match="metrics=collisions: not in the pairs"):
        tables.render("pairs mine metrics=collisions", tmp_path / "results")
    with pytest.raises(SystemExit, match="no method 'c' in the episodes"):
        tables.snapshot(run, "mine", tmp_path / "results", pairs=("a:c",))
    with pytest.raises(SystemExit, match="--pairs ab: two methods as A:B"):
        tables.snapshot(run, "mine", tmp_path / "results", pairs=("ab",))


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("success", "expected KIND RUN"),
        ("table mine", "'table': not a kind of table"),
        ("success nowhere", "no snapshot"),
        ("success mine rows", "options are OPTION=VALUE"),
        ("papers mine cells=all", "papers takes no option cells"),
        ("success mine rows=sideways", "'sideways'"),
        ("papers mine", "papers.csv: no such file"),
        ("claims mine", "claims needs other=NAME"),
        ("claims mine other=theirs", "theirs: no snapshot"),
        ("claims mine other=mine labels=one", "two names"),
        ("claims mine other=mine rows=sideways", "rows='sideways': own, held_out or turned"),
        ("claims mine other=mine", "directions.csv: no such file"),
        ("pairs mine", "pairs.csv: no such file"),
    ],
)
def test_a_block_that_cannot_be_made_is_named_in_one_line(tmp_path, spec, message):
    results = tmp_path / "results"
    (results / "mine").mkdir(parents=True)
    (results / "mine" / "run.json").write_text("{}")
    pd.DataFrame([_summary_row("a", "navfn", 100.0, 62.0)]).to_csv(results / "mine" / "summary.csv", index=False)
    with pytest.raises(ValueError, match=message):
        tables.render(spec, results)
    page = tmp_path / "page.md"
    page.write_text(f"text\n\n<!-- results: {spec} -->\nold\n<!-- /results -->\n")
    text, problems = tables.stale_blocks(page, results)
    assert text == page.read_text() and len(problems) == 1 and problems[0].startswith(f"{page}:3: ")


COMMAND = re.compile(r"socialnav (arena|gscl|humans|policy|run|simulate|layers)\b|python scripts/|benchmarks/")


@pytest.mark.parametrize("page", ["arena-results.md", "arena-history.md"])
def test_every_other_table_on_the_results_pages_follows_the_command_that_made_it(page):
    """docs/arena-results.md and its history: a table not made by the script (a measurement of its
    time: an earlier model, scene or definition) has the command that made it earlier in its
    section."""
    lines = (tables.ROOT / "docs" / page).read_text().splitlines()
    generated, section_start, missing, previous = False, 0, [], ""
    for number, line in enumerate(lines, 1):
        if line.startswith("<!-- results:"):
            generated = True
        elif line.startswith("<!-- /results -->"):
            generated = False
        elif line.startswith("#"):
            section_start = number
        elif line.lstrip().startswith("|") and not previous.lstrip().startswith("|") and not generated:
            if not any(COMMAND.search(text) for text in lines[section_start : number - 1]):
                missing.append(f"docs/{page}:{number}: {line.strip()[:60]}")
        previous = line
    assert not missing, "tables without the command that made them:\n" + "\n".join(missing)


def test_a_source_line_names_the_hosts_instruction_set_where_the_run_recorded_it():
    info = {"source_commit": "ab" * 20, "socialnav_version": "1", "metrics_version": "m", "gscl_model": None}
    info |= {"human_model": "social_force", "variants": 4, "seed": 0}
    assert markdown.source_line(info, "x").endswith(", 4 variants, seed 0.")  # a run from before hosts were noted
    said = markdown.source_line({**info, "host": {"isa": "AVX2", "cpu": "a"}}, "x")
    assert said.endswith(", 4 variants, seed 0, AVX2.")
