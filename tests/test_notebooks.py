"""The four notebooks (``notebooks/*.py``, jupytext's percent format) run to their end in a kernel,
each in under a minute, draw figures, ask each question in a markdown cell before its call and
say what to see after each figure, and print every number with its unit.

The docs build (``make docs``, which ``make test`` runs first) executes them once, into myst-nb's
cache (``docs/_build/.jupyter_cache``); a cached execution of the notebook's present code,
newer than every source file of the packages, is checked here as it is, so that CI runs each
notebook once. Without one (no docs build, a notebook or the code changed since), the test
executes the notebook itself: a notebook that breaks fails here either way."""

import calendar
import re
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.py"))
CACHE = ROOT / "docs" / "_build" / ".jupyter_cache"
#: A printed block names at least one of these units (or says "dimensionless").
UNITS = re.compile(r"\b(deg|deg/s|uT|uT/V|Hz|1/s|V|m/s2?|dimensionless)\b|\(1/\(V s\)\)")

pytestmark = pytest.mark.slow
sys.path.insert(0, str(ROOT / "docs" / "_ext"))
from quadcosim_docs import newest_source  # noqa: E402  (the docs build's own rule of a stale execution)


def _executed(path: Path, monkeypatch):
    """The notebook executed (from the docs build's cache when that ran this code after the
    sources last changed) and its execution time (s)."""
    jupytext = pytest.importorskip("jupytext")
    notebook = jupytext.read(path)
    if CACHE.is_dir():
        from jupyter_cache import get_cache

        cache = get_cache(CACHE)
        try:
            record = cache.match_cache_notebook(notebook)
        except KeyError:
            record = None
        if record is not None and calendar.timegm(record.created.utctimetuple()) > newest_source(ROOT):
            _, merged = cache.merge_match_into_notebook(notebook)  # the outputs, into the whole notebook
            return merged, record.data["execution_seconds"]
    nbclient = pytest.importorskip("nbclient")
    monkeypatch.setenv("MPLBACKEND", "module://matplotlib_inline.backend_inline")  # figures, as in Jupyter
    monkeypatch.delenv("QUADCOSIM_RECORDING", raising=False)
    started = time.perf_counter()
    client = nbclient.NotebookClient(notebook, timeout=600, kernel_name="python3",
                                     resources={"metadata": {"path": str(path.parent)}})
    client.execute()  # raises CellExecutionError, with the cell and its traceback, on an error
    return notebook, time.perf_counter() - started


def test_the_four_notebooks_are_there():
    assert [p.stem for p in NOTEBOOKS] == ["attitude_lab", "estimators_on_a_recording", "infrared_ekf",
                                           "magnetometer_calibration"]


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_a_notebook_runs_in_a_minute_draws_and_says_what_to_see(path, monkeypatch):
    notebook, seconds = _executed(path, monkeypatch)
    assert seconds < 60.0, f"{path.name} ran {seconds:.0f} s: a notebook runs in under a minute"
    cells = notebook.cells
    outputs = [o for cell in cells if cell.cell_type == "code" for o in cell.get("outputs", [])]
    assert not [o for o in outputs if o.get("output_type") == "error"]
    figures = [i for i, cell in enumerate(cells) if cell.cell_type == "code"
               and any("image/png" in o.get("data", {}) for o in cell.get("outputs", []))]
    assert len(figures) >= 2, f"{path.name} draws {len(figures)} figures"
    for i, cell in enumerate(cells):
        if cell.cell_type == "code":  # a question (or what a cell does) said first
            assert i > 0 and cells[i - 1].cell_type == "markdown", f"{path.name}: code cell {i} has no text before it"
    for i in figures:  # and what to see in the figure, after it
        assert i + 1 < len(cells) and cells[i + 1].cell_type == "markdown", \
            f"{path.name}: the figure of cell {i} is not followed by what to see in it"
    printed = [o["text"] for o in outputs if o.get("output_type") == "stream" and o.get("name") == "stdout"]
    assert printed
    for text in printed:
        if re.search(r"\d", text):
            assert UNITS.search(text), f"{path.name} prints numbers without a unit:\n{text}"
