"""Figure output: atomic saving and papermill execution of figure notebooks."""

from __future__ import annotations

import logging
import os
import sys
import time
from pathlib import Path

from .provenance import atomic_path

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

    The notebook must have a cell tagged ``parameters``; ``parameters`` are
    injected after it. The executed notebook is kept so a reader sees the code
    beside the figure. A failing cell raises with the notebook's traceback.
    """
    import papermill

    start = time.perf_counter()
    log.info("executing %s with parameters %s", notebook, sorted(parameters))
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
