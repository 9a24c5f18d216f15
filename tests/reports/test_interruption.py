"""A hard-killed run leaves temporary files; the next run of the same job removes them.

``atomic_path`` writes every output as ``.<stem>.tmp<PID><suffix>`` beside it
and the mesh-convergence report builds each matrix from a scratch folder
``roughcontact-convergence-<host>-<pid>-<random>`` of the temporary folder;
``kill -9`` leaves both behind. These tests plant them as such a kill leaves
them (with the PID of a process that has exited) and run the library
functions that the workflow's jobs call.
"""

import os
import socket
import subprocess
import sys
import tempfile

import matplotlib
import nbformat
import pytest

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from roughcontact.elasticity.influence import BlockGeometry  # noqa: E402
from roughcontact.reports.convergence import (  # noqa: E402
    SCRATCH_PREFIX,
    influence_convergence,
    remove_stale_scratch,
)
from roughcontact.reports.execution import (  # noqa: E402
    execute_notebook,
    remove_stale_temporaries,
)
from roughcontact.reports.plotting import save_figure  # noqa: E402
from roughcontact.study.config import ConvergenceSettings  # noqa: E402


def exited_process() -> int:
    """The PID of a process that has exited (as a killed job's has)."""
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


@pytest.fixture(scope="module")
def dead_pid() -> int:
    """A killed job's PID (a figure job, which runs its notebook itself, or the
    convergence report)."""
    return exited_process()


@pytest.fixture
def live_pid():
    """The PID of a process that runs while the test does (another writer)."""
    proc = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(120)"])
    yield proc.pid
    proc.kill()
    proc.wait()


def plant(folder, name, text="half-written"):
    folder.mkdir(parents=True, exist_ok=True)
    (folder / name).write_text(text)
    return folder / name


def test_stale_temporaries_of_dead_writers_are_removed_only(tmp_path, dead_pid, live_pid):
    out = tmp_path / "fig04.ipynb"
    stale = plant(tmp_path, f".fig04.tmp{dead_pid}.ipynb")
    kept = [
        plant(tmp_path, f".fig04.tmp{live_pid}.ipynb"),  # another writer, still running
        plant(tmp_path, f".fig04.tmp{os.getpid()}.ipynb"),  # this process
        plant(tmp_path, f".fig040.tmp{dead_pid}.ipynb"),  # another figure
        plant(tmp_path, f".fig04.tmp{dead_pid}.png"),  # another output
        plant(tmp_path, ".fig04.tmpabc.ipynb"),  # not a PID
        plant(tmp_path, "fig04.ipynb", "finished"),
    ]
    assert remove_stale_temporaries(out) == [stale]
    assert not stale.exists()
    assert all(path.exists() for path in kept)
    assert remove_stale_temporaries(tmp_path / "missing" / "fig04.ipynb") == []


def test_save_figure_removes_the_images_a_killed_job_left(tmp_path, dead_pid):
    figures = tmp_path / "results" / "figures"
    stale = [plant(figures, f".fig04.tmp{dead_pid}.png"),
             plant(figures, f".fig04.tmp{dead_pid}.pdf")]
    fig, ax = plt.subplots()
    ax.plot([0, 1], [0, 1])
    save_figure(fig, figures / "fig04.png", figures / "fig04.pdf")
    plt.close(fig)
    assert not any(path.exists() for path in stale)
    assert sorted(p.name for p in figures.iterdir()) == ["fig04.pdf", "fig04.png"]


def test_rendering_a_figure_again_removes_what_a_killed_render_left(tmp_path, dead_pid):
    """The ``figure`` job's steps (``execute_notebook`` of a notebook that calls
    ``save_figure``), after a kill that left its notebook, PNG and PDF half-written."""
    figures = tmp_path / "results" / "figures"
    stale = [plant(figures, f".fig99.tmp{dead_pid}.ipynb", "{"),  # papermill's output
             plant(figures, f".fig99.tmp{dead_pid}.png"),  # the notebook's images
             plant(figures, f".fig99.tmp{dead_pid}.pdf")]
    notebook = nbformat.v4.new_notebook()
    parameters = nbformat.v4.new_code_cell('png = "x.png"\npdf = "x.pdf"')
    parameters.metadata["tags"] = ["parameters"]
    notebook.cells = [parameters, nbformat.v4.new_code_cell(
        "import matplotlib\nmatplotlib.use('Agg')\nimport matplotlib.pyplot as plt\n"
        "from roughcontact.reports.plotting import save_figure\n"
        "fig, ax = plt.subplots()\nax.plot([0, 1], [1, 0])\nsave_figure(fig, png, pdf)")]
    notebook.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3",
                                       "language": "python"}
    source = tmp_path / "fig99.ipynb"
    nbformat.write(notebook, source)
    cwd = os.getcwd()
    os.chdir(tmp_path)  # the workflow runs jobs in its working directory
    try:
        execute_notebook(source, "results/figures/fig99.ipynb",
                         {"png": "results/figures/fig99.png", "pdf": "results/figures/fig99.pdf"})
    finally:
        os.chdir(cwd)
    assert not any(path.exists() for path in stale)
    assert sorted(p.name for p in figures.iterdir()) == ["fig99.ipynb", "fig99.pdf", "fig99.png"]
    assert nbformat.read(figures / "fig99.ipynb", as_version=4).cells  # a finished notebook


def test_convergence_report_removes_the_scratch_a_killed_report_left(tmp_path, monkeypatch,
                                                                      dead_pid, live_pid):
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))  # the system's temporary folder
    host = socket.gethostname()
    stale = tmp_path / f"{SCRATCH_PREFIX}{host}-{dead_pid}-k1ll3d_"
    plant(stale, "task.pkl")
    kept = [
        tmp_path / f"{SCRATCH_PREFIX}{host}-{live_pid}-running",  # a report still running
        tmp_path / f"{SCRATCH_PREFIX}other-node.{host}-{dead_pid}-abc",  # another machine
        tmp_path / f"{SCRATCH_PREFIX}abcd1234",  # not named after a process
    ]
    for folder in kept:
        plant(folder, "task.pkl")
    block = BlockGeometry(size=(0.6e-3, 0.6e-3), thickness=1e-3, grid=(4, 4))
    table = influence_convergence(block, ConvergenceSettings(presets=("paper",), surfaces=0),
                                  halfspace=False)
    assert table["dofs"].iloc[0] > 0  # built in a fresh process, from a scratch folder
    assert not stale.exists()
    assert all((folder / "task.pkl").exists() for folder in kept)
    # the report's own scratch folders are gone when it ends
    assert sorted(tmp_path.iterdir()) == sorted(kept)
    assert remove_stale_scratch(tmp_path) == []
