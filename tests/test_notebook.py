"""The evaluation notebook runs top to bottom (at a reduced size) on a learnt engine."""

from __future__ import annotations

import pathlib

import nbformat
import pytest
from nbclient import NotebookClient

NOTEBOOKS = pathlib.Path(__file__).resolve().parent.parent / "notebooks"


@pytest.mark.slow
def test_evaluation_notebook_executes(learned_run, tmp_path, monkeypatch):
    monkeypatch.setenv("SOCIALNAV_TABLES", str(learned_run / "causal" / "engine_tables.npz"))
    monkeypatch.setenv("SOCIALNAV_REPLICAS", "2")
    monkeypatch.setenv("SOCIALNAV_SLOTS", "S1,S11")
    monkeypatch.setenv("SOCIALNAV_OUT", str(tmp_path / "out"))
    nb = nbformat.read(NOTEBOOKS / "evaluation.ipynb", as_version=4)
    NotebookClient(
        nb, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(NOTEBOOKS)}}
    ).execute()  # raises if a cell fails
    outputs = "".join(o.get("text", "") for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", []))
    assert "checks passed" in outputs
    for name in (
        "tasks.parquet",
        "summary.json",
        "per_slot.csv",
        "fig9_efficiency.png",
        "fig10_safety.png",
        "fig11_routes.png",
    ):
        assert (tmp_path / "out" / name).stat().st_size > 0


@pytest.mark.slow
def test_benchmark_notebook_executes(tmp_path, monkeypatch):
    monkeypatch.setenv("SOCIALNAV_VARIANTS", "2")
    monkeypatch.setenv("SOCIALNAV_SCENES", "casn_static_person,snape_walking")
    monkeypatch.setenv("SOCIALNAV_METHODS", "navfn,casn")
    monkeypatch.setenv("SOCIALNAV_OUT", str(tmp_path / "out"))
    nb = nbformat.read(NOTEBOOKS / "benchmark.ipynb", as_version=4)
    NotebookClient(
        nb, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(NOTEBOOKS)}}
    ).execute()  # raises if a cell fails
    outputs = "".join(o.get("text", "") for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", []))
    assert "checks passed" in outputs
    assert (tmp_path / "out" / "casn_static_person_paths.png").stat().st_size > 0
