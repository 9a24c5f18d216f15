"""Figure output: atomic saving and papermill execution of figure notebooks."""

from __future__ import annotations

import logging
import os
import sys
import time
from pathlib import Path

from roughcontact.study.provenance import atomic_path

log = logging.getLogger(__name__)


def save_figure(fig, *paths, dpi: int = 150) -> None:
    """Save a matplotlib figure to each path (format from the suffix), atomically."""
    for path in paths:
        path = Path(path)
        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=dpi, bbox_inches="tight", format=path.suffix.lstrip("."))


def _kernel_name() -> str:
    """A Jupyter kernel that runs this interpreter (so it sees this package)."""
    from jupyter_client.kernelspec import KernelSpecManager, NoSuchKernel

    manager = KernelSpecManager()
    try:
        spec = manager.get_kernel_spec("python3")
        exe = spec.argv[0]
        if exe in ("python", "python3", "{python}") or os.path.realpath(exe) == os.path.realpath(
            sys.executable
        ):
            return "python3"
    except NoSuchKernel:
        pass
    raise RuntimeError(
        f"the Jupyter kernel 'python3' does not run {sys.executable}; "
        "install ipykernel into this environment (make does this)"
    )


def execute_notebook(notebook, output, parameters: dict, log_path=None) -> None:
    """Execute ``notebook`` with papermill into ``output`` (atomically).

    The notebook must have a cell tagged ``parameters``; the entries of
    ``parameters`` that it declares there are injected after it (the workflow
    passes one set to every figure; the others are logged, not passed). The
    executed notebook is kept so a reader sees the code beside the figure. A
    failing cell raises with the notebook's traceback.
    """
    import papermill

    start = time.perf_counter()
    declared = papermill.inspect_notebook(str(notebook))
    unused = sorted(set(parameters) - set(declared))
    parameters = {k: v for k, v in parameters.items() if k in declared}
    log.info("executing %s with parameters %s%s", notebook, sorted(parameters),
             f" (not declared there, not passed: {unused})" if unused else "")
    with atomic_path(output) as tmp:
        papermill.execute_notebook(
            str(notebook),
            str(tmp),
            parameters=parameters,
            kernel_name=_kernel_name(),
            cwd=os.getcwd(),
            progress_bar=False,
        )
    log.info("executed %s in %.1f s -> %s", notebook, time.perf_counter() - start, output)


def load_aggregates(paths) -> tuple:
    """The aggregate table, per-surface moduli and sidecar of a study (``aggregate_files``)."""
    import json

    import pandas as pd

    table_path, moduli_path, meta_path = paths
    return (pd.read_csv(table_path), pd.read_csv(moduli_path),
            json.loads(Path(meta_path).read_text()))


def plot_band(ax, frame, quantity: str, *, y_scale: float = 1.0, label=None, color=None,
              linestyle="-"):
    """Mean curve of ``quantity`` against nominal pressure [MPa] with its confidence band.

    ``frame`` holds one cell's rows of an aggregate table. Levels that rest on
    no surface are left out; a level resting on fewer surfaces than the cell
    has is drawn with a hollow marker, so a thin band there is not mistaken
    for a tight one. Returns the line.
    """
    import numpy as np

    count = frame[f"{quantity}_count"].to_numpy()
    ok = count > 0
    x = frame["nominal_pressure"].to_numpy()[ok] / 1e6
    y = frame[f"{quantity}_mean"].to_numpy()[ok] * y_scale
    hw = np.nan_to_num(frame[f"{quantity}_half_width"].to_numpy()[ok] * y_scale)
    (line,) = ax.plot(x, y, label=label, color=color, linestyle=linestyle)
    ax.fill_between(x, y - hw, y + hw, color=line.get_color(), alpha=0.2, linewidth=0)
    partial = count[ok] < frame["surfaces"].to_numpy()[ok]
    if partial.any():
        ax.plot(x[partial], y[partial], "o", mfc="none", color=line.get_color(), ms=4)
    return line


def study_note(table) -> str:
    """One line for a caption: surfaces per cell, confidence, unconverged solves."""
    cells = table.drop_duplicates("cell")
    bad = int(cells["unconverged_steps"].sum())
    return (f"{int(cells['surfaces'].min())}-{int(cells['surfaces'].max())} surfaces per "
            f"curve; bands: 95 % confidence interval of the mean; unconverged solves "
            f"excluded: {bad}")
