"""Figure notebooks run in the job's own process, through papermill.

``execute_notebook`` runs the cells with the in-process engine
(``roughcontact.reports.notebook_engine``): papermill still injects the
parameters and raises for a failing cell; the cells' prints, results,
displays and errors are the executed notebook's outputs, as a kernel's
would be; no kernel is started.
"""

import ast
import json
import os
import subprocess
import sys
from pathlib import Path

import nbformat
import papermill
import pytest
import yaml
from papermill.exceptions import PapermillExecutionError

from roughcontact.reports.execution import execute_figure, execute_notebook
from roughcontact.reports.notebook_engine import ENGINE_NAME

REPO = Path(__file__).resolve().parents[2]
NOTEBOOKS = sorted((REPO / "notebooks").glob("*.ipynb"))


def write_notebook(path, *sources, parameters='count = 1\nname = "default"'):
    """A notebook of a parameters cell, a Markdown cell and code cells of ``sources``."""
    cell = nbformat.v4.new_code_cell(parameters)
    cell.metadata["tags"] = ["parameters"]
    notebook = nbformat.v4.new_notebook()
    notebook.cells = [cell, nbformat.v4.new_markdown_cell("# A figure"),
                      *(nbformat.v4.new_code_cell(source) for source in sources)]
    notebook.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3",
                                       "language": "python"}
    nbformat.write(notebook, path)
    return path


def code_cells(path):
    return [c for c in nbformat.read(path, as_version=4).cells if c.cell_type == "code"]


def test_parameters_prints_results_and_displays_are_the_outputs(tmp_path):
    source = write_notebook(
        tmp_path / "fig.ipynb",
        'import os, sys, warnings\nprint("count is", count)\nprint("to stderr", file=sys.stderr)\n'
        'print("and on")\nwarnings.warn("a warning for the reader")',
        "count * 10",
        "name; # a trailing semicolon shows nothing",
        "os.getpid()",
        'display({"text/markdown": "**bold**", "text/plain": "bold"}, raw=True)\n__name__',
        "",  # an empty cell is not run and not numbered
        "None")
    out = tmp_path / "results" / "fig.ipynb"
    execute_notebook(source, out, {"count": 7, "name": "mine", "png": "fig.png"})

    cells = code_cells(out)
    injected = cells[1]
    assert "injected-parameters" in injected.metadata.tags
    assert "count = 7" in injected.source and 'name = "mine"' in injected.source
    assert "png" not in injected.source  # not declared, not passed
    assert [c.execution_count for c in cells] == [1, 2, 3, 4, 5, 6, 7, None, 8]
    assert [c.metadata.papermill.status for c in cells] == ["completed"] * 9

    printed = cells[2].outputs
    assert [(o.output_type, o.name) for o in printed] == [
        ("stream", "stdout"), ("stream", "stderr"), ("stream", "stdout"), ("stream", "stderr")]
    assert printed[0].text == "count is 7\n" and printed[2].text == "and on\n"
    assert printed[1].text == "to stderr\n"
    assert "UserWarning: a warning for the reader" in printed[3].text

    (result,) = cells[3].outputs
    assert result.output_type == "execute_result"
    assert result.data == {"text/plain": "70"} and result.execution_count == 4
    assert cells[4].outputs == []
    # the cells ran in this process, not in a kernel
    assert cells[5].outputs[0].data["text/plain"] == str(os.getpid())
    display, main = cells[6].outputs
    assert display.output_type == "display_data"
    assert display.data == {"text/markdown": "**bold**", "text/plain": "bold"}
    assert main.data["text/plain"] == "'__main__'"
    assert cells[7].outputs == [] and cells[8].outputs == []
    assert sorted(p.name for p in out.parent.iterdir()) == ["fig.ipynb"]


@pytest.mark.parametrize(("source", "ename", "evalue", "line"), [
    ('x = 41\nraise ValueError(f"bad value {x + 1}")', "ValueError", "bad value 42",
     'raise ValueError(f"bad value {x + 1}")'),
    ("def f():\n    return 1 / 0\n\nf()", "ZeroDivisionError", "division by zero",
     "return 1 / 0"),
    ("x = = 1", "SyntaxError", "invalid syntax", "x = = 1"),
])
def test_a_failing_cell_raises_and_leaves_no_notebook(tmp_path, source, ename, evalue, line):
    ran_on = tmp_path / "ran on"
    notebook = write_notebook(tmp_path / "fig.ipynb", 'print("before")', source,
                              f"open({str(ran_on)!r}, 'w').close()")
    out = tmp_path / "results" / "fig.ipynb"
    with pytest.raises(PapermillExecutionError) as raised:
        execute_notebook(notebook, out, {"count": 2})
    error = raised.value
    assert (error.ename, error.exec_count) == (ename, 4)
    assert evalue in error.evalue
    assert line in str(error)  # the cell's line in the traceback
    assert "notebook_engine" not in str(error)  # from the cell's frame on
    assert not ran_on.exists()  # no cell runs after the failing one
    assert not out.parent.exists() or list(out.parent.iterdir()) == []


def test_the_failing_cell_and_its_traceback_are_saved_in_the_executed_notebook(tmp_path):
    """Papermill's contract (execute_notebook writes atomically, so a failed
    notebook is not kept there): the executed notebook marks the cell."""
    notebook = write_notebook(tmp_path / "fig.ipynb", 'raise KeyError("sigma_um")', "1 + 1")
    out = tmp_path / "failed.ipynb"
    with pytest.raises(PapermillExecutionError):
        papermill.execute_notebook(str(notebook), str(out), engine_name=ENGINE_NAME,
                                   progress_bar=False)
    cells = [c for c in nbformat.read(out, as_version=4).cells if c.cell_type == "code"]
    (error,) = cells[1].outputs
    assert (error.output_type, error.ename, error.evalue) == ("error", "KeyError", "'sigma_um'")
    assert error.traceback[0] == "Traceback (most recent call last):"
    assert 'raise KeyError("sigma_um")' in "\n".join(error.traceback)
    assert cells[1].metadata.papermill.status == "failed"
    assert cells[2].execution_count is None and cells[2].outputs == []


def test_a_figure_notebook_starts_no_kernel(tmp_path):
    """Fig 1 of the quick study in a fresh interpreter, as its job runs it: no child
    Python process (a kernel is one), and neither ipykernel nor IPython imported."""
    settings = yaml.safe_load((REPO / "config" / "quick.yaml").read_text())["figures"]["fig01"]
    figures = tmp_path / "results" / "figures"
    parameters = {"figure": "fig01", "settings": settings, "png": str(figures / "fig01.png"),
                  "pdf": str(figures / "fig01.pdf")}
    code = f"""
import json, subprocess, sys
started = []
init = subprocess.Popen.__init__
def record(self, args, *rest, **options):
    started.append(args)
    init(self, args, *rest, **options)
subprocess.Popen.__init__ = record
from roughcontact.reports.execution import execute_figure, execute_notebook
execute_notebook({str(REPO / "notebooks" / "fig01.ipynb")!r}, {str(figures / "fig01.ipynb")!r},
                 json.loads({json.dumps(parameters)!r}))
kernel = [m for m in sys.modules if m.split(".")[0] in ("ipykernel", "IPython")]
print(json.dumps({{"started": [str(a) for a in started], "modules": kernel}}))
"""
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=tmp_path, env=dict(os.environ, OPENBLAS_NUM_THREADS="1"))
    assert proc.returncode == 0, proc.stderr[-3000:]
    report = json.loads(proc.stdout.splitlines()[-1])
    assert not [args for args in report["started"] if sys.executable in args], report
    assert report["modules"] == []
    assert sorted(p.name for p in figures.iterdir()) == ["fig01.ipynb", "fig01.pdf", "fig01.png"]
    (printed,) = code_cells(figures / "fig01.ipynb")[3].outputs
    assert printed.text.startswith("S3 = ")


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_figure_notebooks_are_plain_python_on_agg(path):
    """What the engine needs of a notebook: no IPython syntax (magics, shell escapes:
    the cells parse as Python), no IPython import, and matplotlib's Agg backend
    selected before pyplot is imported."""
    cells = [c.source for c in nbformat.read(path, as_version=4).cells if c.cell_type == "code"]
    source = "\n".join(cells)
    for cell in cells:
        ast.parse(cell)
    assert "IPython" not in source and "get_ipython" not in source
    if "matplotlib" in source:
        agg = source.index('matplotlib.use("Agg")')
        assert "pyplot" not in source[:agg]


def test_a_figure_leaves_its_answers_for_the_caption(tmp_path):
    """``execute_figure``: a notebook declaring ``answers`` writes the numbers there; one
    that does not gets an empty file; an earlier run's file never survives."""
    stating = write_notebook(tmp_path / "stating.ipynb",
                             'if answers:\n    open(answers, "w").write(f"Found {count}.\\n")',
                             parameters='count = 1\nanswers = ""')
    silent = write_notebook(tmp_path / "silent.ipynb", "count + 1")
    found = tmp_path / "found.rst"
    execute_figure(stating, tmp_path / "out1.ipynb", {"count": 7}, answers=found)
    assert found.read_text() == "Found 7.\n"
    execute_figure(silent, tmp_path / "out2.ipynb", {"count": 7}, answers=found)
    assert found.read_text() == ""  # the stale numbers removed, none written
