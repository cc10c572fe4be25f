"""The teachers' notebook (docs/demo.ipynb): the demo's own text, and it runs.

Needs the ``notebook`` extra (nbclient, nbformat, ipykernel, rerun-notebook); skipped without it.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

NOTEBOOK = Path(__file__).resolve().parents[3] / "docs" / "demo.ipynb"
QUICK_T_END = 0.2  # s per step: the cells run as a teacher's would, on a short horizon


def test_the_notebook_is_the_demo_s_text():
    """The committed notebook is what validation.studies.demo_notebook builds from the demo's text (run
    ``python -m validation.studies.demo_notebook docs/demo.ipynb`` after changing a step)."""
    from validation.studies.demo import STEPS
    from validation.studies.demo_notebook import notebook_text

    assert NOTEBOOK.read_text(encoding="utf-8") == notebook_text()
    cells = json.loads(notebook_text())["cells"]
    text = "\n".join(c["source"] for c in cells if c["cell_type"] == "markdown")
    for step in STEPS:
        assert f"## {step.title.split('. ', 1)[0]}." in text
        assert all(look in text for look in step.look_at)


@pytest.mark.slow
def test_the_notebook_runs_and_shows_each_step(tmp_path):
    """Executed headless as Jupyter would, every cell runs; each step's cell shows the Rerun
    viewer widget and the step's figure."""
    nbclient = pytest.importorskip("nbclient")
    nbformat = pytest.importorskip("nbformat")
    pytest.importorskip("ipykernel")
    pytest.importorskip("rerun_notebook")
    from validation.studies.demo import STEPS

    nb = nbformat.reads(NOTEBOOK.read_text(encoding="utf-8"), as_version=4)
    params = next(c for c in nb.cells if "parameters" in c.metadata.get("tags", []))
    assert "T_END = 10.0" in params.source
    params.source = params.source.replace("T_END = 10.0", f"T_END = {QUICK_T_END}")
    nbclient.NotebookClient(
        nb, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}
    ).execute()
    shown = [c for c in nb.cells if c.cell_type == "code" and "show_step(" in c.source]
    assert len(shown) == len(STEPS)
    for cell in shown:
        kinds = {k for out in cell.outputs for k in out.get("data", {})}
        assert "application/vnd.jupyter.widget-view+json" in kinds, cell.source
        assert "image/png" in kinds, cell.source
        assert not [o for o in cell.outputs if o.output_type == "error"]
