"""``examples/quickstart.ipynb`` runs from top to bottom on a fresh kernel (nbclient), so the
walk-through never rots: every cell executes without error and leaves what it promises (result
files, the leaderboard, two GIFs of the trained robot)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")

NOTEBOOK = Path(__file__).resolve().parents[1] / "examples" / "quickstart.ipynb"


def test_the_quickstart_notebook_runs_and_leaves_what_it_promises(tmp_path, monkeypatch) -> None:
    notebook = nbformat.read(NOTEBOOK, as_version=4)
    assert all(not cell.get("outputs") for cell in notebook.cells if cell.cell_type == "code"), (
        "the notebook is shipped without outputs"
    )
    repository = str(NOTEBOOK.parents[1])
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(filter(None, [repository, os.environ.get("PYTHONPATH")])))
    monkeypatch.setenv("MPLBACKEND", "Agg")
    client = nbclient.NotebookClient(
        notebook, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}
    )
    client.execute()
    out = tmp_path / "notebook-results"
    assert len(list((out / "runs").glob("*.json"))) == 4
    assert len(list((out / "runs").glob("*.agent.pt"))) == 4
    assert (out / "LEADERBOARD.md").exists()
    assert (out / "empathic.gif").stat().st_size > 0 and (out / "still_cat.gif").stat().st_size > 0
    printed = "".join(
        output.get("text", "") for cell in notebook.cells if cell.cell_type == "code" for output in cell.get("outputs", [])
    )
    assert "'harms'" in printed and "empathic_dqn" in printed, printed
